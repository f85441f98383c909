#!/usr/bin/env bash
# Flash size of busspec codecs on a Cortex-M4F: builds this crate as a staticlib for
# thumbv7em-none-eabihf at opt-level "s" (LTO, panic = abort) once per feature and prints the
# .text and .rodata of its object (the codec and what it pulls in from the runtime, crc and
# core; compiler_builtins is a separate object and left out). Needs the target
# (rustup target add thumbv7em-none-eabihf) and llvm-size/llvm-ar (or rust-size/rust-ar).
# Usage: bash benches/flash/size.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
target=thumbv7em-none-eabihf
out=../../target/flash
# llvm-size and llvm-ar from the toolchain's llvm-tools component, or else from PATH.
tools="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
size=$(command -v "$tools/llvm-size" || command -v llvm-size)
ar=$(command -v "$tools/llvm-ar" || command -v llvm-ar)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| build | .text | .rodata |"
echo "|---|---|---|"
for feature in generated hand subset; do
  cargo build --release --locked --target "$target" --features "$feature" --target-dir "$out" -q
  lib="$out/$target/release/libbusspec_flash.a"
  obj=$("$ar" t "$lib" | grep '^busspec_flash')
  (cd "$tmp" && rm -f ./*.o && "$ar" x "$OLDPWD/$lib" "$obj")
  "$size" -A "$tmp/$obj" | awk -v f="$feature" \
    '$1 ~ /^\.text/ { t += $2 } $1 ~ /^\.rodata/ { r += $2 } END { printf "| %s | %d | %d |\n", f, t, r }'
done
