"""MAVLink v1 held both ways to pymavlink, an independent implementation, through the fixture
model/tests/fixtures/valid/mavlink_v1.yaml (the interpreter: `busspec decode/encode --spec`):

- pymavlink packs random HEARTBEAT, SYS_STATUS, PING, ATTITUDE and REQUEST_DATA_STREAM messages
  with random sequence numbers, system and component IDs; busspec decodes each frame to the
  values and header fields pymavlink was given;
- busspec encodes random values and header fields; pymavlink parses each frame (its CRC with
  CRC_EXTRA included) to the same values and header.

Run after `cargo build` with pymavlink installed (2.4.50 here):
    python3 -m venv /tmp/mav && /tmp/mav/bin/pip install pymavlink
    /tmp/mav/bin/python tests/reference/mavlink_v1_check.py [N]
"""

import json
import os
import random
import struct
import subprocess
import sys

os.environ.pop("MAVLINK20", None)
from pymavlink.dialects.v10 import common as mav  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SPEC = os.path.join(ROOT, "model", "tests", "fixtures", "valid", "mavlink_v1.yaml")

# busspec's message and direction, pymavlink's class, and each field as (busspec name,
# pymavlink name, kind): kinds are struct formats.
MESSAGES = [
    ("heartbeat", "response", mav.MAVLink_heartbeat_message, [
        ("custom_mode", "custom_mode", "I"), ("vehicle_type", "type", "B"),
        ("autopilot", "autopilot", "B"), ("base_mode", "base_mode", "B"),
        ("system_status", "system_status", "B"), ("mavlink_version", "mavlink_version", "B")]),
    ("sys_status", "response", mav.MAVLink_sys_status_message, [
        ("onboard_control_sensors_present", "onboard_control_sensors_present", "I"),
        ("onboard_control_sensors_enabled", "onboard_control_sensors_enabled", "I"),
        ("onboard_control_sensors_health", "onboard_control_sensors_health", "I"),
        ("load", "load", "H"), ("voltage_battery", "voltage_battery", "H"),
        ("current_battery", "current_battery", "h"), ("drop_rate_comm", "drop_rate_comm", "H"),
        ("errors_comm", "errors_comm", "H"), ("errors_count1", "errors_count1", "H"),
        ("errors_count2", "errors_count2", "H"), ("errors_count3", "errors_count3", "H"),
        ("errors_count4", "errors_count4", "H"), ("battery_remaining", "battery_remaining", "b")]),
    ("ping", "request", mav.MAVLink_ping_message, [
        ("time_usec", "time_usec", "Q"), ("seq", "seq", "I"),
        ("target_system", "target_system", "B"), ("target_component", "target_component", "B")]),
    ("attitude", "response", mav.MAVLink_attitude_message, [
        ("time_boot_ms", "time_boot_ms", "I"), ("roll", "roll", "f"), ("pitch", "pitch", "f"),
        ("yaw", "yaw", "f"), ("rollspeed", "rollspeed", "f"), ("pitchspeed", "pitchspeed", "f"),
        ("yawspeed", "yawspeed", "f")]),
    ("request_data_stream", "request", mav.MAVLink_request_data_stream_message, [
        ("req_message_rate", "req_message_rate", "H"), ("target_system", "target_system", "B"),
        ("target_component", "target_component", "B"), ("req_stream_id", "req_stream_id", "B"),
        ("start_stop", "start_stop", "B")]),
]


def fail(what):
    print(f"mavlink_v1 reference check FAILED: {what}", file=sys.stderr)
    sys.exit(1)


def value(rng, kind, name):
    if name == "start_stop":
        return rng.randint(0, 1)
    if kind == "f":
        # A float32 exactly, so both sides hold the same number.
        return struct.unpack("<f", struct.pack("<f", rng.uniform(-4, 4)))[0]
    size = struct.calcsize("<" + kind)
    if kind.islower():
        return rng.randint(-(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1)
    return rng.randint(0, (1 << (8 * size)) - 1)


def same(kind, a, b):
    if kind == "f":
        return struct.pack("<f", a) == struct.pack("<f", b)
    return a == b


def busspec(args, stdin):
    r = subprocess.run([BUSSPEC, *args], input=stdin, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"busspec {' '.join(args)[:120]}: {r.stderr.strip()}")
    return r.stdout.splitlines()


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    rng = random.Random(23)
    link = mav.MAVLink(None)
    # pymavlink → busspec.
    frames, wants = [], []
    for _ in range(n):
        name, direction, cls, fields = rng.choice(MESSAGES)
        vals = {b: value(rng, k, b) for b, _, k in fields}
        link.seq = rng.randint(0, 255)
        link.srcSystem = rng.randint(0, 255)
        link.srcComponent = rng.randint(0, 255)
        header = {"sequence": link.seq, "sysid": link.srcSystem, "compid": link.srcComponent}
        msg = cls(**{p: vals[b] for b, p, _ in fields})
        frames.append(bytes(msg.pack(link)))
        wants.append((name, direction, fields, vals, header))
    by_dir = {"request": [], "response": []}
    for f, w in zip(frames, wants):
        by_dir[w[1]].append((f, w))
    decoded = 0
    for d, items in by_dir.items():
        if not items:
            continue
        lines = busspec(["decode", "--spec", SPEC, "--direction", d, "mavlink_v1",
                         *[f.hex() for f, _ in items]], None)
        if len(lines) != len(items):
            fail(f"{len(lines)} lines for {len(items)} frames")
        for line, (f, (name, _, fields, vals, header)) in zip(lines, items):
            got = json.loads(line)
            if got["message"] != name:
                fail(f"{f.hex()}: {got['message']}, pymavlink packed {name}")
            for k, v in header.items():
                if got["fields"][k] != v:
                    fail(f"{f.hex()}: header {k} {got['fields'][k]}, pymavlink put {v}")
            for b, _, kind in fields:
                if not same(kind, got["fields"][b], vals[b]):
                    fail(f"{f.hex()}: {b} {got['fields'][b]}, pymavlink packed {vals[b]}")
            decoded += 1
    # busspec → pymavlink.
    objs, wants = [], []
    for _ in range(n):
        name, direction, cls, fields = rng.choice(MESSAGES)
        vals = {b: value(rng, k, b) for b, _, k in fields}
        header = {"sequence": rng.randint(0, 255), "sysid": rng.randint(0, 255),
                  "compid": rng.randint(0, 255)}
        objs.append({"message": name, "direction": direction, "address": 0,
                     "fields": {**header, **vals}})
        wants.append((name, fields, vals, header))
    lines = busspec(["encode", "--spec", SPEC, "mavlink_v1"],
                    "\n".join(json.dumps(o) for o in objs) + "\n")
    parsed = 0
    for line, (name, fields, vals, header) in zip(lines, wants):
        frame = bytes.fromhex(line)
        try:
            msg = link.decode(bytearray(frame))
        except Exception as e:  # pymavlink names a bad CRC or length here
            fail(f"pymavlink refused busspec's {name} {line}: {e}")
        h = msg.get_header()
        if (h.seq, h.srcSystem, h.srcComponent) != (header["sequence"], header["sysid"], header["compid"]):
            fail(f"{line}: pymavlink reads header {(h.seq, h.srcSystem, h.srcComponent)}, busspec encoded {header}")
        for b, p, kind in fields:
            if not same(kind, getattr(msg, p), vals[b]):
                fail(f"{line}: pymavlink reads {p} {getattr(msg, p)}, busspec encoded {vals[b]}")
        parsed += 1
    print(f"mavlink_v1 against pymavlink: {decoded} pymavlink frames decoded by busspec, "
          f"{parsed} busspec frames parsed by pymavlink, every value and header field alike")


main()
