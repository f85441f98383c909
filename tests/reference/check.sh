#!/usr/bin/env bash
# Checks spec/modbus.yaml, spec/dynamixel.yaml, spec/dynamixel2.yaml, spec/pelco_d.yaml and
# spec/crsf.yaml against the reference implementations: pymodbus, the ROBOTIS dynamixel-sdk
# (its protocol 1.0 and 2.0 packet handlers), pyptzcontroller (a Pelco D camera
# controller), crsf-parser (CRSF, with construct, which it parses with) and pymavlink (MAVLink v1
# through the fixture model/tests/fixtures/valid/mavlink_v1.yaml: tests/reference/mavlink_v1_check.py,
# and MAVLink v2 with payload truncation through model/tests/fixtures/valid/mavlink_v2.yaml:
# tests/reference/mavlink_v2_check.py, with the interpreter only, as no MAVLink is built in) and pyvesc (VESC, short and long frames,
# through the fixture model/tests/fixtures/valid/vesc.yaml: tests/reference/vesc_check.py; pyvesc
# imports `PyCRC`, which PythonCRC provides, not the distribution now named PyCRC), installed from PyPI
# into a virtual environment under
# target/ that this script makes (rebuilt when missing). Frames each peer's encoders build must
# decode through `busspec decode` to the values they were built from, and frames
# `busspec encode` builds must be read identically by the peers (tests/reference/check.py);
# every call runs with the built-in generated code and with `--spec` (the interpreter), alike.
# Then live, over pseudo-terminals, both ways: `busspec talk modbus` against pymodbus's RTU serial
# server (tests/reference/live_modbus.py; pyserial is what the server opens its port with),
# pymodbus's serial client against `busspec sim modbus` (live_sim_modbus.py), and dynamixel-sdk's
# protocol 1.0 and 2.0 packet handlers against `busspec sim dynamixel` and `busspec sim dynamixel2`
# (live_sim_dynamixel.py).
# Versions are pinned so a new release cannot change the result silently.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
venv=target/reference-venv
pins=(pymodbus==3.16.1 dynamixel-sdk==4.1.0 pyserial==3.5 pyptzcontroller==0.1.2 crsf-parser==0.3.2 construct==2.10.68 construct-typing==0.5.6 pymavlink==2.4.50 fastcrc==0.5.0 lxml==6.1.3 pyvesc==1.0.5 PythonCRC==1.21 tcr-roboclaw==0.1.5)
# Rebuilt unless exactly the pinned versions are there (dynamixel-sdk alone pulls any pyserial).
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c '
import importlib.metadata as m, sys
sys.exit(any(m.version(p) != v for p, v in (a.split("==") for a in sys.argv[1:])))
' "${pins[@]}" 2>/dev/null; then
  rm -rf "$venv"
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "${pins[@]}"
fi
"$venv/bin/python" -c 'import importlib.metadata as m; print("pymodbus", m.version("pymodbus"), "/ dynamixel-sdk", m.version("dynamixel-sdk"), "/ pyserial", m.version("pyserial"), "/ pyptzcontroller", m.version("pyptzcontroller"), "/ crsf-parser", m.version("crsf-parser"), "/ construct", m.version("construct"), "/ pymavlink", m.version("pymavlink"), "/ pyvesc", m.version("pyvesc"), "/ PythonCRC", m.version("PythonCRC"), "/ tcr-roboclaw", m.version("tcr-roboclaw"))'
cargo build --locked --quiet --bin busspec
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/check.py
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/mavlink_v1_check.py
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/mavlink_v2_check.py
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/vesc_check.py
BUSSPEC=target/debug/busspec "$venv/bin/python" tests/reference/roboclaw_check.py 100
# Bounded twice: each talk call and the script time out on their own; this is the last resort.
BUSSPEC=target/debug/busspec timeout 600 "$venv/bin/python" tests/reference/live_modbus.py
BUSSPEC=target/debug/busspec timeout 600 "$venv/bin/python" tests/reference/live_sim_modbus.py
BUSSPEC=target/debug/busspec timeout 600 "$venv/bin/python" tests/reference/live_sim_dynamixel.py 1.0
BUSSPEC=target/debug/busspec timeout 600 "$venv/bin/python" tests/reference/live_sim_dynamixel.py 2.0
