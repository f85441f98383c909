#!/usr/bin/env bash
# The clean release build of a minimal consumer of busspec-protocols: a binary crate depending
# on it by path and decoding one frame, built in a fresh target directory. Prints the machine
# load before and after (other builds on the machine slow it down), cargo's wall time and the
# CPU time of the build (user + sys, cargo and every process it starts), which other builds on
# the machine change much less than the wall time. With --cpu, also each rustc's CPU time
# (through a RUSTC_WRAPPER; needs /usr/bin/time). Other arguments go to cargo.
# Usage: bash benches/build-cost.sh [--cpu] [--timings]
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [[ ${1:-} == --cpu ]]; then
  shift
  cat >"$tmp/rustc-cpu" <<'SH'
#!/usr/bin/env bash
# Runs rustc, appending "crate user sys" to $BUILD_COST_CPU_LOG.
name=?
prev=
for a in "$@"; do
  [[ $prev == --crate-name ]] && name=$a
  prev=$a
done
[[ $name == "?" ]] && exec "$@"
out=$(mktemp)
rc=0
/usr/bin/time -f "%U %S" -o "$out" "$@" || rc=$?
echo "$name $(cat "$out")" >>"$BUILD_COST_CPU_LOG"
rm -f "$out"
exit "$rc"
SH
  chmod +x "$tmp/rustc-cpu"
  export RUSTC_WRAPPER="$tmp/rustc-cpu" BUILD_COST_CPU_LOG="$tmp/cpu.log"
fi
mkdir -p "$tmp/consumer/src"
cat >"$tmp/consumer/Cargo.toml" <<TOML
[package]
name = "consumer"
version = "0.1.0"
edition = "2021"
publish = false

[dependencies]
busspec-protocols = { path = "$repo/generated" }

[workspace]
TOML
cat >"$tmp/consumer/src/main.rs" <<'RS'
use busspec_protocols::sd;

fn main() {
    let frame = [0x69u8, 0x01, 0x00, 0x00, 0x00, 0x00];
    println!("{:?}", sd::Request::decode(&frame));
}
RS
# The workspace's lock file, so the consumer builds the same dependency versions.
cp "$repo/Cargo.lock" "$tmp/consumer/Cargo.lock"
cd "$tmp/consumer"
echo "load before: $(uptime)"
start=$(date +%s.%N)
TIMEFORMAT="cpu: user %U s, sys %S s"
time cargo build --release --target-dir "$tmp/target" "$@"
end=$(date +%s.%N)
echo "load after: $(uptime)"
awk -v s="$start" -v e="$end" 'BEGIN { printf "clean release build: %.1f s\n", e - s }'
if [[ -f $tmp/cpu.log ]]; then
  echo "rustc CPU (user + sys) by crate, the ten largest:"
  awk '{ cpu[$1] += $2 + $3 } END { for (c in cpu) printf "%s %.2f s\n", c, cpu[c] }' "$tmp/cpu.log" |
    sort -k2 -rn | head -10
fi
# With --timings, the slowest units and the build script's run (the report itself goes with the
# temporary directory).
for html in "$tmp"/target/cargo-timings/cargo-timing.html; do
  [[ -f $html ]] || continue
  python3 - "$html" <<'PY'
import json, re, sys
units = json.loads(re.search(r"const UNIT_DATA = (\[.*?\]);", open(sys.argv[1]).read(), re.S).group(1))
def show(u):
    print(f"{u['name']} {u['version']}{u.get('target', '')}: {u['duration']:.1f} s (from {u['start']:.1f} s)")
top = sorted(units, key=lambda u: -u["duration"])[:10]
for u in top:
    show(u)
for u in units:
    if u not in top and u["name"] == "busspec-protocols":
        show(u)
PY
done
