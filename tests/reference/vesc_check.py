"""VESC held both ways to pyvesc 1.0.5, an independent implementation, through the fixture
model/tests/fixtures/valid/vesc.yaml (the interpreter: `busspec decode/encode --spec`):

- pyvesc encodes random SetDutyCycle, SetCurrent, SetCurrentBrake, SetRPM and SetPosition
  messages; busspec decodes each to the values pyvesc was given;
- pyvesc frames random COMM_WRITE_NEW_APP_DATA payloads (0 to 512 data bytes, so short and long
  frames: pyvesc takes the long form from 256 payload bytes on) and GetValues replies (packed
  with struct: pyvesc 1.0.5 cannot pack its own GetValues, whose last field has no scalar);
  busspec decodes each to its values, and busspec's encode of those values is pyvesc's frame
  byte for byte (the same form chosen);
- busspec encodes random setters, GetValues replies and WRITE_NEW_APP_DATA chunks; pyvesc reads
  each to the same values (its `decode`, or `packet.codec.unframe` for the payload);
- a long form of a length the short field holds (which pyvesc's unframe accepts) is refused by
  busspec at the length field: busspec's strict rule, pyvesc's leniency.

pyvesc 1.0.5 requires a distribution named PyCRC for its `from PyCRC.CRCCCITT import CRCCCITT`;
that name now installs pycrc 0.12.0, whose module is `pycrc`, so `import pyvesc` fails. PythonCRC
1.21 provides the `PyCRC` module it imports (CRC-16/XMODEM: check 0x31C3), so check.sh pins it.

Run after `cargo build`:
    python3 -m venv /tmp/vescenv && /tmp/vescenv/bin/pip install pyvesc==1.0.5 PythonCRC==1.21
    /tmp/vescenv/bin/python tests/reference/vesc_check.py [N]
"""

import json
import os
import random
import struct
import subprocess
import sys
from decimal import Decimal

import pyvesc  # noqa: E402
from pyvesc.packet.codec import frame as pyvesc_frame, unframe as pyvesc_unframe  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SPEC = os.path.join(ROOT, "model", "tests", "fixtures", "valid", "vesc.yaml")

# busspec's setter, its field and scale (raw × scale = the JSON value), pyvesc's class and the
# number pyvesc is given for a raw value.
SETTERS = [
    ("set_duty", "duty", Decimal("0.00001"), pyvesc.SetDutyCycle, lambda raw: raw),
    ("set_current", "current", Decimal("0.001"), pyvesc.SetCurrent, lambda raw: raw),
    ("set_current_brake", "current", Decimal("0.001"), pyvesc.SetCurrentBrake, lambda raw: raw),
    ("set_rpm", "rpm", Decimal(1), pyvesc.SetRPM, lambda raw: raw),
    # pyvesc packs int(pos × 1e6): a multiple of 1/64 degree is exact as a float.
    ("set_pos", "pos", Decimal("0.000001"), pyvesc.SetPosition, lambda raw: raw / 1000000),
]

# GetValues: busspec's field (pyvesc's name), struct format, pyvesc's scalar, busspec's scale.
VALUES = [(n, f, s) for n, f, s in [
    ("temp_mos1", "h", 10), ("temp_mos2", "h", 10), ("temp_mos3", "h", 10),
    ("temp_mos4", "h", 10), ("temp_mos5", "h", 10), ("temp_mos6", "h", 10),
    ("temp_pcb", "h", 10), ("current_motor", "i", 100), ("current_in", "i", 100),
    ("duty_now", "h", 1000), ("rpm", "i", 1), ("v_in", "h", 10), ("amp_hours", "i", 10000),
    ("amp_hours_charged", "i", 10000), ("watt_hours", "i", 10000),
    ("watt_hours_charged", "i", 10000), ("tachometer", "i", 1), ("tachometer_abs", "i", 1),
    ("mc_fault_code", "B", 1),
]]


def fail(what):
    print(f"vesc reference check FAILED: {what}", file=sys.stderr)
    sys.exit(1)


def busspec(args, stdin):
    r = subprocess.run([BUSSPEC, *args], input=stdin, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"busspec {' '.join(args)[:120]}: {r.stderr.strip()}")
    return r.stdout.splitlines()


def raw(rng, kind):
    if pyvesc_signed(kind):
        bits = 8 * struct.calcsize(">" + kind)
        return rng.randint(-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    return rng.randint(0, (1 << (8 * struct.calcsize(">" + kind))) - 1)


def pyvesc_signed(kind):
    return kind.islower()


def physical(raw_value, scale):
    """The JSON number text of a raw value: exact."""
    v = Decimal(raw_value) * scale
    return format(v.normalize(), "f") if v != 0 else "0"


def decode(frames, direction):
    lines = busspec(["decode", "--spec", SPEC, "--direction", direction, "vesc",
                     *[f.hex() for f in frames]], None)
    if len(lines) != len(frames):
        fail(f"{len(lines)} lines for {len(frames)} frames")
    return [json.loads(line, parse_float=Decimal) for line in lines]


def encode(lines):
    out = busspec(["encode", "--spec", SPEC, "vesc"], "\n".join(lines) + "\n")
    if len(out) != len(lines):
        fail(f"{len(out)} frames for {len(lines)} lines")
    return [bytes.fromhex(x) for x in out]


def setter_line(name, field, scale, r):
    return ('{"protocol":"vesc","direction":"request","code":"%s","message":"%s","fields":{"%s":%s}}'
            % ({"set_duty": "0x05", "set_current": "0x06", "set_current_brake": "0x07",
                "set_rpm": "0x08", "set_pos": "0x09"}[name], name, field, physical(r, scale)))


def write_line(offset, data):
    return json.dumps({"protocol": "vesc", "direction": "request", "code": "0x03",
                       "message": "write_new_app_data",
                       "fields": {"offset": offset, "data": list(data)}}, separators=(",", ":"))


def values_line(raws):
    fields = ",".join('"%s":%s' % (n, physical(r, Decimal(1) / Decimal(s)))
                      for (n, _, s), r in zip(VALUES, raws))
    return ('{"protocol":"vesc","direction":"response","code":"0x04","message":"get_values_reply",'
            '"fields":{%s}}' % fields)


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    rng = random.Random(29)
    counts = {"setters": 0, "short": 0, "long": 0, "values": 0}

    # pyvesc → busspec: setters.
    sent = []
    for _ in range(n):
        name, field, scale, cls, given = rng.choice(SETTERS)
        r = rng.randint(-(1 << 31), (1 << 31) - 1)
        if name == "set_pos":
            r = rng.randint(-137438, 137437) * 15625
        msg = cls(given(r))
        sent.append((pyvesc.encode(msg), name, field, scale, r))
    for (f, name, field, scale, r), got in zip(sent, decode([s[0] for s in sent], "request")):
        if got["message"] != name or got["fields"][field] != Decimal(r) * scale:
            fail(f"{f.hex()}: busspec reads {got}, pyvesc packed {name} {field} raw {r}")
        counts["setters"] += 1
    back = encode([setter_line(name, field, scale, r) for _, name, field, scale, r in sent])
    for (f, *_), b in zip(sent, back):
        if f != b:
            fail(f"busspec encodes {b.hex()}, pyvesc {f.hex()}")

    # pyvesc → busspec: WRITE_NEW_APP_DATA, short and long (pyvesc's frame of the payload).
    chunks = []
    for i in range(n):
        k = rng.choice([0, 1, 250, 251, 252, 255, 256, 300, 511, 512, rng.randint(0, 512)])
        offset = rng.randint(0, (1 << 32) - 1)
        data = bytes(rng.randint(0, 255) for _ in range(k))
        chunks.append((pyvesc_frame(bytes([3]) + struct.pack(">I", offset) + data), offset, data))
    for (f, offset, data), got in zip(chunks, decode([c[0] for c in chunks], "request")):
        if (got["message"], got["fields"]["offset"], bytes(got["fields"]["data"])) != (
                "write_new_app_data", offset, data):
            fail(f"{f.hex()[:40]}…: busspec reads {str(got)[:200]}")
        counts["long" if f[0] == 3 else "short"] += 1
    back = encode([write_line(offset, data) for _, offset, data in chunks])
    for (f, offset, data), b in zip(chunks, back):
        if f != b:
            fail(f"busspec encodes {len(data)} data bytes as {b.hex()[:40]}…, pyvesc {f.hex()[:40]}…")
        payload, consumed = pyvesc_unframe(b)
        if consumed != len(b) or payload != bytes([3]) + struct.pack(">I", offset) + data:
            fail(f"pyvesc unframes busspec's {b.hex()[:40]}… to {payload!r}")

    # pyvesc → busspec and back: GetValues replies, packed with struct, framed by pyvesc.
    replies = []
    for _ in range(n):
        raws = [raw(rng, f) for _, f, _ in VALUES]
        payload = struct.pack(">B" + "".join(f for _, f, _ in VALUES), 4, *raws)
        replies.append((pyvesc_frame(payload), raws))
    for (f, raws), got in zip(replies, decode([r[0] for r in replies], "response")):
        for (name, _, s), r in zip(VALUES, raws):
            if got["fields"][name] != Decimal(r) / Decimal(s):
                fail(f"{f.hex()}: busspec reads {name} {got['fields'][name]}, packed raw {r}")
        msg, consumed = pyvesc.decode(f)
        if consumed != len(f):
            fail(f"pyvesc does not read its own {f.hex()}")
        counts["values"] += 1
    back = encode([values_line(raws) for _, raws in replies])
    for (f, raws), b in zip(replies, back):
        if f != b:
            fail(f"busspec encodes {b.hex()}, pyvesc frames {f.hex()}")
        msg, consumed = pyvesc.decode(b)
        for (name, _, s), r in zip(VALUES, raws):
            v = getattr(msg, name)
            got = v[0] if isinstance(v, bytes) else v * s
            if round(got) != r:
                fail(f"pyvesc reads busspec's {name} as {v}, busspec encoded raw {r}")

    # busspec → pyvesc: setters busspec encodes from random values, read by pyvesc's decode.
    mine = []
    for _ in range(n):
        name, field, scale, cls, _ = rng.choice(SETTERS)
        mine.append((name, field, scale, cls, rng.randint(-(1 << 31), (1 << 31) - 1)))
    for (name, field, scale, cls, r), b in zip(mine, encode([setter_line(*m[:3], m[4]) for m in mine])):
        msg, consumed = pyvesc.decode(b)
        if consumed != len(b) or type(msg) is not cls:
            fail(f"pyvesc reads busspec's {name} {b.hex()} as {msg!r}")
        v = getattr(msg, cls._field_names[0])
        if round(v * 1000000) != r if name == "set_pos" else v != r:
            fail(f"pyvesc reads busspec's {name} {b.hex()} as {v}, busspec encoded raw {r}")

    # A long form of a length the short field holds: pyvesc reads it, busspec refuses it.
    needless = bytes([0x03, 0x00]) + pyvesc.encode(pyvesc.SetRPM(1000))[1:]
    payload, consumed = pyvesc_unframe(needless)
    if consumed != len(needless) or payload is None:
        fail(f"pyvesc no longer reads the needless long form {needless.hex()}")
    r = subprocess.run([BUSSPEC, "decode", "--spec", SPEC, "vesc", needless.hex()],
                       capture_output=True, text=True)
    if r.returncode != 1 or "long length field at offset 1 says 5" not in r.stderr:
        fail(f"busspec does not refuse the needless long form {needless.hex()}: {r.stderr}")

    print(f"vesc against pyvesc 1.0.5: {counts['setters']} pyvesc setters, {counts['short']} short and "
          f"{counts['long']} long WRITE_NEW_APP_DATA frames and {counts['values']} GetValues replies "
          f"decoded by busspec and encoded back byte for byte; {n} busspec setters, {n} replies and "
          f"{n} chunks read by pyvesc alike; a needless long form refused by busspec, read by pyvesc")


main()
