"""MAVLink v2 held both ways to pymavlink, an independent implementation, through the fixture
model/tests/fixtures/valid/mavlink_v2.yaml (the interpreter: `busspec decode/encode --spec`):

- pymavlink packs random HEARTBEAT, SYS_STATUS (with its extension fields), PING, ATTITUDE,
  ATTITUDE_QUATERNION (its extension field repr_offset_q a float[4], a list of a fixed count),
  REQUEST_DATA_STREAM and RAW_RPM (id 339, a 3-byte id above 255) messages with random
  sequence numbers, system and component IDs and compatibility flags, about half of their
  fields zero so that pymavlink strips the payload's trailing zeros (it truncates every v2
  payload); busspec decodes each frame to the values and header fields pymavlink was given;
- busspec encodes random values and header fields (as many zeros), stripping trailing zeros
  as a v2 sender does; pymavlink parses each frame (its CRC with CRC_EXTRA over the bytes as
  they travel) to the same values and header, and each frame is byte for byte the one
  pymavlink packs from those values.

Run after `cargo build` with pymavlink installed (2.4.50 here), e.g. in the venv
tests/reference/check.sh makes:
    target/reference-venv/bin/python tests/reference/mavlink_v2_check.py [N]
"""

import json
import os
import random
import struct
import subprocess
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import common as mav  # noqa: E402
from pymavlink.generator import mavcrc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SPEC = os.path.join(ROOT, "model", "tests", "fixtures", "valid", "mavlink_v2.yaml")

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
        ("errors_count4", "errors_count4", "H"), ("battery_remaining", "battery_remaining", "b"),
        ("onboard_control_sensors_present_extended", "onboard_control_sensors_present_extended", "I"),
        ("onboard_control_sensors_enabled_extended", "onboard_control_sensors_enabled_extended", "I"),
        ("onboard_control_sensors_health_extended", "onboard_control_sensors_health_extended", "I")]),
    ("ping", "request", mav.MAVLink_ping_message, [
        ("time_usec", "time_usec", "Q"), ("seq", "seq", "I"),
        ("target_system", "target_system", "B"), ("target_component", "target_component", "B")]),
    ("attitude", "response", mav.MAVLink_attitude_message, [
        ("time_boot_ms", "time_boot_ms", "I"), ("roll", "roll", "f"), ("pitch", "pitch", "f"),
        ("yaw", "yaw", "f"), ("rollspeed", "rollspeed", "f"), ("pitchspeed", "pitchspeed", "f"),
        ("yawspeed", "yawspeed", "f")]),
    ("attitude_quaternion", "response", mav.MAVLink_attitude_quaternion_message, [
        ("time_boot_ms", "time_boot_ms", "I"), ("q1", "q1", "f"), ("q2", "q2", "f"),
        ("q3", "q3", "f"), ("q4", "q4", "f"), ("rollspeed", "rollspeed", "f"),
        ("pitchspeed", "pitchspeed", "f"), ("yawspeed", "yawspeed", "f"),
        ("repr_offset_q", "repr_offset_q", "4f")]),
    ("request_data_stream", "request", mav.MAVLink_request_data_stream_message, [
        ("req_message_rate", "req_message_rate", "H"), ("target_system", "target_system", "B"),
        ("target_component", "target_component", "B"), ("req_stream_id", "req_stream_id", "B"),
        ("start_stop", "start_stop", "B")]),
    ("raw_rpm", "response", mav.MAVLink_raw_rpm_message, [
        ("frequency", "frequency", "f"), ("index", "index", "B")]),
]


def fail(what):
    print(f"mavlink_v2 reference check FAILED: {what}", file=sys.stderr)
    sys.exit(1)


def value(rng, kind, name):
    if kind == "4f":
        # A float[4] (a list of a fixed count): all 0 now and then (an extension field
        # stripped whole), else each element as a float field is drawn.
        if rng.random() < 0.3:
            return [0.0] * 4
        return [value(rng, "f", name) for _ in range(4)]
    # Half the fields zero, so that payloads end in zeros of every length.
    if rng.random() < 0.5:
        return 0.0 if kind == "f" else 0
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
    if kind == "4f":
        return len(a) == len(b) == 4 and all(same("f", x, y) for x, y in zip(a, b))
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
    stripped, lengths = [0, 0], set()
    for _ in range(n):
        name, direction, cls, fields = rng.choice(MESSAGES)
        vals = {b: value(rng, k, b) for b, _, k in fields}
        link.seq = rng.randint(0, 255)
        link.srcSystem = rng.randint(0, 255)
        link.srcComponent = rng.randint(0, 255)
        compat = rng.choice([0, 0, 1, rng.randint(0, 255)])
        header = {"incompat_flags": 0, "compat_flags": compat, "sequence": link.seq,
                  "sysid": link.srcSystem, "compid": link.srcComponent}
        msg = cls(**{p: vals[b] for b, p, _ in fields})
        frame = bytes(msg.pack(link, force_mavlink1=False))
        if compat:
            # pymavlink always sends compat_flags 0: set it and seal the CRC again as
            # pymavlink computes it (x25crc over the bytes after FD, then CRC_EXTRA).
            body = bytearray(frame[1:-2])
            body[2] = compat
            crc = mavcrc.x25crc(bytes(body))
            crc.accumulate_str(struct.pack("B", cls.crc_extra))
            frame = b"\xfd" + bytes(body) + struct.pack("<H", crc.crc)
        payload = frame[1]
        stripped[0] += payload < msg.unpacker.size
        stripped[1] += 1
        lengths.add((name, payload))
        frames.append(frame)
        wants.append((name, direction, fields, vals, header))
    by_dir = {"request": [], "response": []}
    for f, w in zip(frames, wants):
        by_dir[w[1]].append((f, w))
    decoded, per, per_encoded = 0, {}, {}
    for d, items in by_dir.items():
        if not items:
            continue
        lines = busspec(["decode", "--spec", SPEC, "--direction", d, "mavlink_v2",
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
            per[name] = per.get(name, 0) + 1
    # busspec → pymavlink.
    objs, wants = [], []
    for _ in range(n):
        name, direction, cls, fields = rng.choice(MESSAGES)
        vals = {b: value(rng, k, b) for b, _, k in fields}
        header = {"incompat_flags": 0, "compat_flags": 0, "sequence": rng.randint(0, 255),
                  "sysid": rng.randint(0, 255), "compid": rng.randint(0, 255)}
        objs.append({"message": name, "direction": direction, "address": 0,
                     "fields": {**header, **vals}})
        wants.append((name, fields, vals, header))
    lines = busspec(["encode", "--spec", SPEC, "mavlink_v2"],
                    "\n".join(json.dumps(o) for o in objs) + "\n")
    parsed, encoded_stripped = 0, 0
    for line, (name, fields, vals, header) in zip(lines, wants):
        frame = bytes.fromhex(line)
        try:
            msg = link.decode(bytearray(frame))
        except Exception as e:  # pymavlink names a bad CRC or length here
            fail(f"pymavlink refused busspec's {name} {line}: {e}")
        h = msg.get_header()
        if (h.incompat_flags, h.compat_flags) != (0, 0):
            fail(f"{line}: pymavlink reads flags {(h.incompat_flags, h.compat_flags)}")
        if (h.seq, h.srcSystem, h.srcComponent) != (header["sequence"], header["sysid"], header["compid"]):
            fail(f"{line}: pymavlink reads header {(h.seq, h.srcSystem, h.srcComponent)}, busspec encoded {header}")
        for b, p, kind in fields:
            if not same(kind, getattr(msg, p), vals[b]):
                fail(f"{line}: pymavlink reads {p} {getattr(msg, p)}, busspec encoded {vals[b]}")
        # pymavlink packs the same values into the same bytes.
        cls = next(c for n, _, c, _ in MESSAGES if n == name)
        link.seq, link.srcSystem, link.srcComponent = (header["sequence"], header["sysid"],
                                                       header["compid"])
        ours = bytes(cls(**{p: vals[b] for b, p, _ in fields}).pack(link, force_mavlink1=False))
        if ours != frame:
            fail(f"busspec encoded {line}, pymavlink packs {ours.hex().upper()}")
        encoded_stripped += len(frame) - 12 < cls.unpacker.size
        parsed += 1
        per_encoded[name] = per_encoded.get(name, 0) + 1
    if len(lines) != n:
        fail(f"{len(lines)} frames encoded for {n} lines")
    # A signed frame (incompat_flags bit 0, 13 signature bytes after the CRC) is refused, not
    # misread: the signature is not expressible yet. One frame decoded alone is refused (its
    # last two bytes are no CRC of it); its first 12 + len bytes (the CRC covering the flag)
    # are refused at the flag, and a stream reports them out of spec for it, the signature as
    # skipped bytes.
    signer = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    signer.signing.secret_key = bytes(range(32))
    signer.signing.link_id = 1
    signer.signing.timestamp = 1
    signer.signing.sign_outgoing = True
    signed = bytes(mav.MAVLink_heartbeat_message(2, 3, 0x51, 0, 4, 3).pack(signer))
    if signed[2] != 1 or len(signed) != 12 + signed[1] + 13:
        fail(f"pymavlink's signed frame {signed.hex()} is not what this check expects")
    for wire, why in ((signed, "checksum mismatch"), (signed[:-13], "incompat_flags")):
        r = subprocess.run([BUSSPEC, "decode", "--spec", SPEC, "mavlink_v2", wire.hex()],
                           capture_output=True, text=True)
        if r.returncode == 0 or why not in r.stderr:
            fail(f"a signed frame {wire.hex()}: {r.stdout.strip()} {r.stderr.strip()}")
    r = subprocess.run([BUSSPEC, "decode", "--spec", SPEC, "mavlink_v2", "--stream", "-"],
                       input=signed, capture_output=True)
    events = [json.loads(x) for x in r.stdout.decode().splitlines()]
    if (r.returncode != 0 or len(events) != 2 or "incompat_flags" not in events[0].get("out_of_spec", "")
            or events[1].get("skipped") != 13):
        fail(f"a signed frame in a stream: {r.stdout.decode().strip()} {r.stderr.decode().strip()}")
    print(f"mavlink_v2 against pymavlink: {decoded} pymavlink frames decoded by busspec "
          f"({stripped[0]} of {stripped[1]} truncated, {len(lengths)} distinct message and "
          f"payload lengths), {parsed} busspec frames parsed by pymavlink and packed alike by it "
          f"({encoded_stripped} truncated), every value and header field alike; "
          f"ATTITUDE_QUATERNION (float[4]): {per.get('attitude_quaternion', 0)} decoded, "
          f"{per_encoded.get('attitude_quaternion', 0)} encoded")


main()
