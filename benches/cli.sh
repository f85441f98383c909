#!/usr/bin/env bash
# Whole-process throughput of the CLI, in MB/s (10^6 bytes of input per second): builds the
# release binary, writes the benches' seeded 1 MiB capture of each protocol (every example frame
# over and over, 1 % noise; `benches/src/bin/capture.rs`) and the same frames as hex lines, then
# times `busspec decode P --stream FILE > /dev/null` and `busspec decode P - < HEX > /dev/null`
# RUNS times each (default 5) and prints the best run per row as a Markdown table: wall time,
# and CPU time (user + system) of the process. MB/s is bytes of input per microsecond.
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

# best FILE ARGS... -> "WALL CPU": the shortest wall time and the shortest CPU time (user +
# system) of $runs runs, in milliseconds; FILE is stdin. CPU time is what the process itself
# spent, so it moves less than wall time when other work shares the machine.
best() {
  local input=$1 wall='' cpu='' t status
  shift
  for ((i = 0; i < runs; i++)); do
    status=0
    t=$({
      TIMEFORMAT='%3R %3U %3S'
      time "$bin" "$@" <"$input" >/dev/null 2>"$dir/stderr"
    } 2>&1) || status=$?
    if [[ $status -ne 0 ]]; then
      echo "$bin $* failed ($status):" >&2
      head -5 "$dir/stderr" >&2
      exit 1
    fi
    read -r w u s <<<"$t"
    wall=$(awk -v a="$w" -v b="$wall" 'BEGIN { print (b == "" || a * 1000 < b) ? a * 1000 : b }')
    cpu=$(awk -v u="$u" -v s="$s" -v b="$cpu" 'BEGIN { c = (u + s) * 1000; print (b == "" || c < b) ? c : b }')
  done
  echo "$wall $cpu"
}

row() {
  local proto=$1 form=$2 file=$3 wall=$4 cpu=$5
  awk -v p="$proto" -v f="$form" -v b="$(stat -c %s "$file")" -v w="$wall" -v c="$cpu" -v e="${interp[*]:+interpreter}" \
    'BEGIN { printf "| %s | %s | %s | %d | %.0f ms | %.1f MB/s | %.0f ms | %.1f MB/s |\n", p, (e ? e : "generated"), f, b, w, b / w / 1e3, c, (c > 0 ? b / c / 1e3 : 0) }'
}

echo "| protocol | engine | input | bytes | wall, best of $runs | MB/s | CPU, best of $runs | MB/s |"
echo "|---|---|---|---|---|---|---|---|"
for proto in "${protos[@]}"; do
  target/release/capture "$proto" raw "$size" >"$dir/$proto.bin"
  target/release/capture "$proto" hex "$size" >"$dir/$proto.hex"
  spec=()
  [[ ${#interp[@]} -eq 0 ]] || spec=(--spec "spec/$proto.yaml")
  read -r wall cpu < <(best /dev/null decode "$proto" "${spec[@]}" --stream "$dir/$proto.bin")
  row "$proto" "--stream FILE (raw capture)" "$dir/$proto.bin" "$wall" "$cpu"
  if "$bin" decode --help | grep -q 'one per line from stdin'; then
    read -r wall cpu < <(best "$dir/$proto.hex" decode "$proto" "${spec[@]}" -)
    row "$proto" "- (hex lines on stdin)" "$dir/$proto.hex" "$wall" "$cpu"
  fi
done
