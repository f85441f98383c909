#!/usr/bin/env bash
# Whether two busspec binaries print the same: stdout, stderr and exit status of `busspec
# decode` for ub2, sd, modbus and dynamixel, each with the generated code and with the
# interpreter (`--spec spec/P.yaml`), on
#   - the benches' 1 MiB capture (`capture P raw 1048576`, 1 % noise) with `--stream`,
#   - a 256 KiB capture with 10 % noise (`capture P raw 262144 100`) with `--stream`,
#   - the same noisy capture with `--direction response` and with `--direction request`,
#   - the capture's frames as hex lines on stdin (`capture P hex 1048576`), plain and
#     `--lenient`:
# 48 runs, compared by SHA-256; prints a line per run and exits 1 on any difference. A
# speed change to the decoders or the printer must leave every output byte for byte as it was.
#
#   bash benches/same-output.sh BEFORE [AFTER]
#
# BEFORE and AFTER are busspec binaries (AFTER defaults to target/release/busspec, built
# here); run from anywhere, the specs are this checkout's.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if [[ $# -lt 1 || $# -gt 2 ]]; then
  echo "usage: bash benches/same-output.sh BEFORE [AFTER]" >&2
  exit 2
fi
before=$1
after=${2:-target/release/busspec}
cargo build --release --locked -q -p busspec-benches --bin capture
[[ $# -eq 2 ]] || cargo build --release --locked -q -p busspec --bin busspec
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# digest BIN STDIN ARGS...: the SHA-256 of the run's stdout, stderr and exit status.
digest() {
  local bin=$1 input=$2 status=0
  shift 2
  "$bin" "$@" <"$input" >"$dir/stdout" 2>"$dir/stderr" || status=$?
  {
    sha256sum <"$dir/stdout"
    sha256sum <"$dir/stderr"
    echo "$status"
  } | sha256sum | cut -c1-16
}

runs=0 differ=0
for proto in ub2 sd modbus dynamixel; do
  target/release/capture "$proto" raw 1048576 >"$dir/$proto.bin" 2>/dev/null ||
    target/release/capture "spec/$proto.yaml" raw 1048576 >"$dir/$proto.bin"
  target/release/capture "spec/$proto.yaml" raw 262144 100 >"$dir/$proto.noisy"
  target/release/capture "spec/$proto.yaml" hex 1048576 >"$dir/$proto.hex"
  for engine in generated spec; do
    spec=()
    [[ $engine == generated ]] || spec=(--spec "spec/$proto.yaml")
    while IFS='|' read -r input args; do
      read -ra words <<<"$args"
      a=$(digest "$before" "$input" decode "$proto" "${spec[@]}" "${words[@]}")
      b=$(digest "$after" "$input" decode "$proto" "${spec[@]}" "${words[@]}")
      runs=$((runs + 1))
      if [[ $a == "$b" ]]; then
        echo "same   $a  $proto $engine ${args//$dir\//}"
      else
        differ=$((differ + 1))
        echo "DIFFER $a $b  $proto $engine ${args//$dir\//}"
      fi
    done <<EOF
/dev/null|--stream $dir/$proto.bin
/dev/null|--stream $dir/$proto.noisy
/dev/null|--direction response --stream $dir/$proto.noisy
/dev/null|--direction request --stream $dir/$proto.noisy
$dir/$proto.hex|-
$dir/$proto.hex|--lenient -
EOF
  done
done
echo "$runs runs, $differ differ"
[[ $differ -eq 0 ]]
