#!/usr/bin/env bash
# Instructions per frame (decode, encode) and per byte (stream), from callgrind: runs the
# `icount` binary for two pass counts and divides the difference in instructions by the
# difference in frames or bytes, so set-up (loading the spec, building the inputs) cancels out.
# Stream rows: the 1 MiB capture with 1 % noise (`generated`) and without (`generated-clean`),
# per byte and per frame of the capture (the yardstick's frames: bytes per frame as in the clean
# capture), and their ratio to the yardstick: the clean capture's frames decoded one by one,
# their boundaries known (`stream decode`). Also per frame the stream reports as a request or
# response, which leaves out the frames it reports as ambiguous (a Modbus echo, a Dynamixel
# instruction that also reads as a status packet) though it decoded them.
# Prints Markdown table rows. Needs valgrind.
# Usage: bash benches/icount.sh [ub2|sd|modbus|dynamixel ...] (default: all four)
# Builds into and runs from $CARGO_TARGET_DIR when set (a worktree with its own target).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release --locked -q -p busspec-benches --bin icount
bin=${CARGO_TARGET_DIR:-target}/release/icount

# count ARGS... -> "instructions units_per_pass"
count() {
  local out
  out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$@" 2>&1)
  local ir units
  ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' <<<"$out")
  units=$(sed -n 's/^units per pass: \([0-9]*\).*/\1/p' <<<"$out")
  if [[ -z $ir || -z $units ]]; then
    echo "icount $* failed:" >&2
    echo "$out" >&2
    exit 1
  fi
  # Stream runs also say how many frames a pass decodes.
  local frames
  frames=$(sed -n 's/^frames per pass: \([0-9]*\).*/\1/p' <<<"$out")
  echo "$ir $units ${frames:-0}"
}

# Instructions per frame of `stream decode` and its bytes per frame, set by the first stream
# row of a protocol.
yardstick=0
bytes_per_frame=0

# per PROTO WHO OP LO HI UNIT -> one table row
per() {
  local proto=$1 who=$2 op=$3 lo=$4 hi=$5 unit=$6
  read -r a units frames < <(count "$proto" "$who" "$op" "$lo")
  read -r b _ _ < <(count "$proto" "$who" "$op" "$hi")
  # `icount PROTO stream CONTENDER` names the operation first.
  if [[ $who == stream ]]; then
    who=$op op=stream
  fi
  # For the stream decoders, also per frame decoded (the yardstick is decode's per frame).
  if [[ $op == stream && $who == decode ]]; then
    yardstick=$(awk -v a="$a" -v b="$b" -v f="$(((hi - lo) * frames))" 'BEGIN { print (b - a) / f }')
    bytes_per_frame=$(awk -v u="$units" -v f="$frames" 'BEGIN { print u / f }')
  fi
  awk -v a="$a" -v b="$b" -v n="$(((hi - lo) * units))" -v f="$(((hi - lo) * frames))" \
    -v p="$proto" -v w="$who" -v o="$op" -v u="$unit" -v y="$yardstick" -v bpf="$bytes_per_frame" \
    'BEGIN { per = (f > 0) ? (b - a) / f : 0
             byte = (b - a) / n
             stream = (o == "stream" && w != "decode" && w != "plain-sum" && y > 0)
             capture = byte * bpf
             ratio = stream ? sprintf(", %.2f× decode; %.1f per frame it decodes", capture / y, per) : ""
             first = stream ? capture : per
             extra = (u == "byte" && f > 0) ? sprintf(" (%.1f per frame%s)", first, ratio) : ""
             printf "| %s | %s | %s | %.1f per %s%s |\n", p, o, w, byte, u, extra }'
}

protos=("$@")
[[ ${#protos[@]} -gt 0 ]] || protos=(ub2 sd modbus dynamixel)
echo "| protocol | operation | contender | instructions |"
echo "|---|---|---|---|"
for proto in "${protos[@]}"; do
  # The contenders beside the generated code: UB2 and SD have hand-written and deku
  # baselines, Modbus its peer modbus-core, Dynamixel none.
  case $proto in
    ub2 | sd) peers=(hand-written deku) ;;
    modbus) peers=(modbus-core) ;;
    *) peers=() ;;
  esac
  for op in decode encode; do
    for who in generated "${peers[@]}"; do
      per "$proto" "$who" "$op" 10 110 frame
    done
    # Modbus and Dynamixel decode through the generated borrowed views too.
    if [[ $op == decode && ($proto == modbus || $proto == dynamixel) ]]; then
      per "$proto" view "$op" 10 110 frame
    fi
    per "$proto" interpreter "$op" 2 12 frame
  done
  per "$proto" stream decode 1 3 byte
  per "$proto" stream generated 1 3 byte
  per "$proto" stream generated-clean 1 3 byte
  per "$proto" stream plain-sum 1 3 byte
done
