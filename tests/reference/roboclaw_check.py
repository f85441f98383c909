"""RoboClaw's packet serial held both ways to Basicmicro's Python library (as tcr-roboclaw
0.1.5 packages it), an independent implementation, through the fixture
model/tests/fixtures/valid/roboclaw.yaml (the interpreter: `busspec decode/encode --spec`).
The library talks to a port object; here it is one that keeps what the library writes and
hands it the bytes busspec made:

- the library sends random writes (drive forward and backwards, signed duty and speed, reset)
  and every read of the fixture; busspec decodes each frame to the command and values the
  library was given (a read travels as address and command alone, without a CRC), and
  busspec's encode of them is the library's frame byte for byte;
- busspec encodes random replies to each read over the read's bytes (`--request`); the
  library reads each back to the values busspec was given, its CRC over the read's bytes and
  the data accepted, and busspec decodes the frame back to them;
- the firmware version (command 21) is text up to a NUL, then the CRC, with no length field:
  busspec's replies of 0 to 47 characters are read back by the library's ReadVersion;
- a reply with one bit changed, or whose CRC leaves out the read's bytes, is refused by both;
- the write acknowledgement FF is a frame to both.

Run after `cargo build`:
    python3 -m venv /tmp/rcenv && /tmp/rcenv/bin/pip install tcr-roboclaw==0.1.5
    /tmp/rcenv/bin/python tests/reference/roboclaw_check.py [N]
"""

import json
import os
import random
import subprocess
import sys
from decimal import Decimal

from tcr_roboclaw.roboclaw import Roboclaw

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SPEC = os.path.join(ROOT, "model", "tests", "fixtures", "valid", "roboclaw.yaml")

ENCODER_STATUS = {0: "underflow", 1: "backward", 2: "overflow"}
STATUS = {
    0: "e_stop", 1: "temperature_error", 2: "temperature_2_error", 3: "main_voltage_high",
    4: "logic_voltage_high", 5: "logic_voltage_low", 6: "m1_driver_fault",
    7: "m2_driver_fault", 8: "m1_speed_error", 9: "m2_speed_error", 10: "m1_position_error",
    11: "m2_position_error", 12: "m1_current_error", 13: "m2_current_error",
    16: "m1_over_current", 17: "m2_over_current", 18: "main_voltage_high_warning",
    19: "main_voltage_low_warning", 20: "temperature_warning", 21: "temperature_2_warning",
    22: "s4_triggered", 23: "s5_triggered", 24: "speed_error_limit",
    25: "position_error_limit",
}


def fail(what):
    print(f"roboclaw reference check FAILED: {what}", file=sys.stderr)
    sys.exit(1)


def busspec(args, stdin=None, ok=True):
    r = subprocess.run([BUSSPEC, *args], input=stdin, capture_output=True, text=True)
    if ok and r.returncode != 0:
        fail(f"busspec {' '.join(args)[:160]}: {r.stderr.strip()}")
    return r


class Port:
    """What the library writes is kept; what it reads comes from `rx`."""

    def __init__(self, rx=b""):
        self.out = bytearray()
        self.rx = bytearray(rx)

    def write(self, b):
        self.out += b

    def read(self, n):
        d = bytes(self.rx[:n])
        del self.rx[:n]
        return d

    def flushInput(self):
        pass


def library(rx=b""):
    rc = Roboclaw("busspec", 38400, 0x80, retries=1)
    rc._port = Port(rx)
    return rc


def flags(raw, names):
    out = [names[b] if b in names else 1 << b for b in range(32) if raw >> b & 1]
    return out


def signed(raw, bits):
    return raw - (1 << bits) if raw >> (bits - 1) else raw


def crc16(data):
    crc = 0
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


# Writes: the library's method, busspec's command, its field and a random raw value.
WRITES = [
    ("ForwardM1", "drive_forward_m1", "speed", lambda r: r.randint(0, 127)),
    ("BackwardM1", "drive_backward_m1", "speed", lambda r: r.randint(0, 127)),
    ("DutyM1", "duty_m1", "duty", lambda r: r.randint(-32767, 32767)),
    ("SpeedM1", "speed_m1", "speed", lambda r: r.randint(-(1 << 31), (1 << 31) - 1)),
    ("ResetEncoders", "reset_encoders", None, None),
]

# Reads: the library's method, busspec's command and reply, and for a random reply the
# fields busspec encodes and what the library returns after its acknowledgement.
def reads(r):
    count, speed = r.randint(-(1 << 31), (1 << 31) - 1), r.randint(-(1 << 31), (1 << 31) - 1)
    est, direction = r.randint(0, 7), r.randint(0, 1)
    v1, v2, t = r.randint(0, 65535), r.randint(0, 65535), r.randint(0, 65535)
    m1, m2 = r.randint(-32768, 32767), r.randint(-32768, 32767)
    st = r.getrandbits(26) & ~(0b11 << 14)
    # Up to 47 characters and the NUL: the library reads at most 48 bytes before the CRC.
    name = "RoboClaw " + "".join(chr(r.randint(0x20, 0x7E)) for _ in range(r.randint(0, 36)))
    version = (name + "\n")[: r.randint(9, 47)]
    return [
        ("ReadVersion", "read_firmware_version", "firmware_version", {"version": version},
         (version,)),
        ("ReadEncM1", "read_encoder_m1", "encoder_m1",
         {"count": count, "status": flags(est, ENCODER_STATUS)}, (count, est)),
        ("ReadSpeedM1", "read_speed_m1", "encoder_speed_m1",
         {"speed": speed, "direction": ["forward", "backward"][direction]}, (speed, direction)),
        ("ReadMainBatteryVoltage", "read_main_battery", "main_battery",
         {"voltage": str(Decimal(v1) / 10)}, (v1,)),
        ("ReadLogicBatteryVoltage", "read_logic_battery", "logic_battery",
         {"voltage": str(Decimal(v2) / 10)}, (v2,)),
        ("ReadCurrents", "read_currents", "currents",
         {"m1": str(Decimal(m1) / 100), "m2": str(Decimal(m2) / 100)}, (m1, m2)),
        ("ReadTemp", "read_temperature", "temperature",
         {"temperature": str(Decimal(t) / 10)}, (t,)),
        ("ReadError", "read_status", "status", {"status": flags(st, STATUS)}, (st,)),
    ]


def same(decoded, expected):
    """Decoded JSON fields against expected ones (numbers compared exactly)."""
    for k, v in expected.items():
        got = decoded.get(k)
        if isinstance(v, str) and v.lstrip("-").replace(".", "").isdigit():
            if got is None or Decimal(str(got)) != Decimal(v):
                return False
        elif got != v:
            return False
    return True


def numbers(fields):
    """Fields as JSON for `busspec encode`: decimal strings as numbers."""
    return {
        k: (json.loads(v) if isinstance(v, str) and v.lstrip("-").replace(".", "").isdigit() else v)
        for k, v in fields.items()
    }


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    r = random.Random(0x80)
    requests = replies = refused = versions = 0
    for _ in range(n):
        # A write: the library's frame, decoded and encoded by busspec; FF acknowledges it.
        method, command, field, value = r.choice(WRITES)
        lib = library(b"\xff")
        args = [] if value is None else [value(r)]
        if getattr(lib, method)(*args) is not True:
            fail(f"{method}{args}: the library took FF as no acknowledgement")
        frame = bytes(lib._port.out).hex().upper()
        got = json.loads(busspec(["decode", "--spec", SPEC, "--direction", "request",
                                  "roboclaw", frame]).stdout)
        want = {} if field is None else {field: args[0]}
        if got["message"] != command or got["address"] != 0x80 or got["fields"] != want:
            fail(f"{method}{args} sent {frame}: busspec decodes {got}")
        back = busspec(["encode", "--spec", SPEC, "roboclaw"], json.dumps(got) + "\n")
        if back.stdout.strip() != frame:
            fail(f"{method}{args}: busspec encodes {back.stdout.strip()}, the library sent {frame}")
        ack = json.loads(busspec(["decode", "--spec", SPEC, "--reply-to", command,
                                  "roboclaw", "FF"]).stdout)
        if ack["message"] != "ack":
            fail(f"FF after {command}: {ack}")
        requests += 1
        # A read and its reply.
        method, command, reply, fields, returned = r.choice(reads(r))
        lib = library()
        getattr(lib, method)()
        read = bytes(lib._port.out)
        got = json.loads(busspec(["decode", "--spec", SPEC, "--direction", "request",
                                  "roboclaw", read.hex()]).stdout)
        if got["message"] != command or got["fields"] != {} or len(read) != 2:
            fail(f"{method} sent {read.hex()}: busspec decodes {got}")
        line = json.dumps({"message": reply, "address": 0, "fields": numbers(fields)})
        frame = bytes.fromhex(busspec(["encode", "--spec", SPEC, "--request", read.hex(),
                                       "roboclaw"], line + "\n").stdout.strip())
        lib = library(frame)
        answer = getattr(lib, method)()
        if answer[0] != 1 or tuple(answer[1:]) != returned:
            fail(f"{method}: busspec's {frame.hex()} read as {answer}, expected {returned}")
        back = json.loads(busspec(["decode", "--spec", SPEC, "--request", read.hex(),
                                   "roboclaw", frame.hex()]).stdout)
        if back["message"] != reply or not same(back["fields"], fields):
            fail(f"{reply} {frame.hex()}: busspec decodes {back}, expected {fields}")
        replies += 1
        versions += reply == "firmware_version"
        # Damaged: one bit changed, or the CRC over the reply's own bytes alone.
        bad = bytearray(frame)
        bad[r.randrange(len(bad))] ^= 1 << r.randrange(8)
        own = frame[:-2] + crc16(frame[:-2]).to_bytes(2, "big")
        for wrong in (bytes(bad), own):
            if wrong == frame:
                continue
            lib = library(wrong)
            if getattr(lib, method)()[0] != 0:
                fail(f"{method}: the library took {wrong.hex()}")
            d = busspec(["decode", "--spec", SPEC, "--request", read.hex(), "roboclaw",
                         wrong.hex()], ok=False)
            # Text up to a NUL: a bit that makes or unmakes the NUL moves where the text
            # ends, which decode refuses before it checks the CRC.
            moved = reply == "firmware_version" and ("terminator" in d.stderr
                                                      or "by the frame's length" in d.stderr)
            if d.returncode == 0 or ("checksum mismatch" not in d.stderr and not moved):
                fail(f"{reply}: busspec took {wrong.hex()}: {d.stdout}{d.stderr}")
            refused += 1
    print(f"roboclaw (tcr-roboclaw 0.1.5): {requests} library frames decoded and encoded back, "
          f"{replies} busspec replies read by the library ({versions} firmware versions), "
          f"{refused} damaged replies refused by both")


if __name__ == "__main__":
    main()
