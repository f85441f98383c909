#!/usr/bin/env bash
# Checks spec/modbus.yaml and spec/dynamixel.yaml against the reference implementations:
# pymodbus and the ROBOTIS dynamixel-sdk, installed from PyPI into a virtual environment under
# target/ that this script makes (rebuilt when missing). Frames each peer's encoders build must
# decode through `busspec decode` to the values they were built from, and frames
# `busspec encode` builds must be read identically by the peers (tests/reference/check.py);
# every call runs with the built-in generated code and with `--spec` (the interpreter), alike.
# Versions are pinned so a new release cannot change the result silently.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
venv=target/reference-venv
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import pymodbus, dynamixel_sdk' 2>/dev/null; then
  rm -rf "$venv"
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check 'pymodbus==3.16.1' 'dynamixel-sdk==4.1.0'
fi
"$venv/bin/python" -c 'import importlib.metadata as m; print("pymodbus", m.version("pymodbus"), "/ dynamixel-sdk", m.version("dynamixel-sdk"))'
cargo build --locked --quiet --bin busspec
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/check.py
