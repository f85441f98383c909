#!/usr/bin/env bash
# Instructions per transaction of the sans-IO master core (busspec-link-core), from callgrind:
# runs the `icount_link` binary for two pass counts and divides the difference in instructions
# by the difference in transactions, so set-up (the simulated replies) cancels out. A
# transaction here is the core's rules plus encoding the request and decoding the reply, fed
# in memory (no driver, no I/O). Prints Markdown table rows. Needs valgrind.
# Usage: bash benches/icount-link.sh [ub2|sd ...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release --locked -q -p busspec-benches --bin icount_link
bin=target/release/icount_link

# count PROTO PASSES -> "instructions units_per_pass"
count() {
  local out ir units
  out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$@" 2>&1)
  ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' <<<"$out")
  units=$(sed -n 's/^units per pass: \([0-9]*\).*/\1/p' <<<"$out")
  if [[ -z $ir || -z $units ]]; then
    echo "icount_link $* failed:" >&2
    echo "$out" >&2
    exit 1
  fi
  echo "$ir $units"
}

protos=("$@")
[[ ${#protos[@]} -gt 0 ]] || protos=(ub2 sd)
echo "| protocol | instructions / transaction (core + codec) |"
echo "|---|---|"
for proto in "${protos[@]}"; do
  read -r a units < <(count "$proto" 100)
  read -r b _ < <(count "$proto" 1100)
  awk -v a="$a" -v b="$b" -v n="$((1000 * units))" -v p="$proto" \
    'BEGIN { printf "| %s | %.1f |\n", p, (b - a) / n }'
done
