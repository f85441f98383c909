#!/usr/bin/env bash
# Whole-process throughput of the CLI, in MB/s (10^6 bytes of input per second): builds the
# release binary, writes the benches' seeded 1 MiB capture of each protocol (every example frame
# over and over, 1 % noise; `benches/src/bin/capture.rs`) and the same frames as hex lines, then
# times `busspec decode P --stream FILE > /dev/null` and `busspec decode P - < HEX > /dev/null`
# RUNS times each (default 5) and prints the best run per row as a Markdown table.
#
#   bash benches/cli.sh [--spec] [ub2|sd ...]
#
# --spec decodes with the interpreter (`--spec spec/P.yaml`) instead of the generated code.
# BUSSPEC=/path/to/busspec times that binary instead of building one (a "before" figure).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
runs=${RUNS:-5}
interp=()
if [[ ${1:-} == --spec ]]; then
  interp=(--spec)
  shift
fi
protos=("$@")
[[ ${#protos[@]} -gt 0 ]] || protos=(ub2 sd)
size=$((1 << 20))

cargo build --release --locked -q -p busspec-benches --bin capture
if [[ -z ${BUSSPEC:-} ]]; then
  cargo build --release --locked -q -p busspec --bin busspec
fi
bin=${BUSSPEC:-target/release/busspec}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# best FILE ARGS... -> the shortest wall time of $runs runs, in nanoseconds; FILE is stdin.
best() {
  local input=$1 min='' t0 t1 status
  shift
  for ((i = 0; i < runs; i++)); do
    t0=$(date +%s%N)
    status=0
    "$bin" "$@" <"$input" >/dev/null 2>"$dir/stderr" || status=$?
    t1=$(date +%s%N)
    if [[ $status -ne 0 ]]; then
      echo "$bin $* failed ($status):" >&2
      head -5 "$dir/stderr" >&2
      exit 1
    fi
    if [[ -z $min || $((t1 - t0)) -lt $min ]]; then
      min=$((t1 - t0))
    fi
  done
  echo "$min"
}

row() {
  local proto=$1 form=$2 file=$3 ns=$4
  awk -v p="$proto" -v f="$form" -v b="$(stat -c %s "$file")" -v ns="$ns" -v e="${interp[*]:+interpreter}" \
    'BEGIN { printf "| %s | %s | %s | %d | %.1f ms | %.1f MB/s |\n", p, (e ? e : "generated"), f, b, ns / 1e6, b * 1e3 / ns }'
}

echo "| protocol | engine | input | bytes | best of $runs | throughput |"
echo "|---|---|---|---|---|---|"
for proto in "${protos[@]}"; do
  target/release/capture "$proto" raw "$size" >"$dir/$proto.bin"
  target/release/capture "$proto" hex "$size" >"$dir/$proto.hex"
  spec=()
  [[ ${#interp[@]} -eq 0 ]] || spec=(--spec "spec/$proto.yaml")
  ns=$(best /dev/null decode "$proto" "${spec[@]}" --stream "$dir/$proto.bin")
  row "$proto" "--stream FILE (raw capture)" "$dir/$proto.bin" "$ns"
  if "$bin" decode --help | grep -q 'one per line from stdin'; then
    ns=$(best "$dir/$proto.hex" decode "$proto" "${spec[@]}" -)
    row "$proto" "- (hex lines on stdin)" "$dir/$proto.hex" "$ns"
  fi
done
