#!/usr/bin/env bash
# Instructions per pass of the generator over both built-in specs, from callgrind: runs the
# `icount_gen` binary for two pass counts and divides the difference in instructions by the
# difference in passes, so the process's start-up cancels out. Rows: load and validate, emit,
# and both (the `generator` bench's `both`). Prints Markdown table rows. Needs valgrind.
# Usage: bash benches/icount-gen.sh [load|emit|both ...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release --locked -q -p busspec-benches --bin icount_gen
bin=target/release/icount_gen

# count WHAT PASSES -> instructions
count() {
  local out ir
  out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$@" 2>&1)
  ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' <<<"$out")
  if [[ -z $ir ]]; then
    echo "icount_gen $* failed:" >&2
    echo "$out" >&2
    exit 1
  fi
  echo "$ir"
}

whats=("$@")
[[ ${#whats[@]} -gt 0 ]] || whats=(load emit both)
echo "| generator, ub2 + sd | million instructions / pass |"
echo "|---|---|"
for what in "${whats[@]}"; do
  a=$(count "$what" 1)
  b=$(count "$what" 3)
  awk -v a="$a" -v b="$b" -v w="$what" 'BEGIN { printf "| %s | %.1f |\n", w, (b - a) / 2e6 }'
done
