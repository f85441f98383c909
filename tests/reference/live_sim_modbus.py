"""pymodbus's serial client against `busspec sim modbus`, over a pseudo-terminal.

`busspec sim modbus --pty --address 1 --address 2` serves two devices simulated from the spec's
`device:` section and prints the pseudo-terminal's path; pymodbus's `ModbusSerialClient` (RTU,
19200 baud; no parity, which a pseudo-terminal cannot set) opens it. The script keeps its own
model of both devices (the spec's tables: 10,000 coils, discrete inputs, holding and input
registers, the inputs' start values from the spec) and runs a seeded random mix over every
function code the spec has:

- reads (0x01-0x04) must return what the model holds;
- writes (0x05, 0x06, 0x0F, 0x10) must be answered as pymodbus expects, and change what later
  reads return, on the device written only;
- a request past the end of a table must get exception 2 (illegal data address), and one whose
  quantity the spec forbids exception 3 (illegal data value), changing nothing;
- writes to broadcast address 0 must get no reply, and change both devices.

Prints `pymodbus client against busspec sim modbus: N transactions, 0 mismatches`; exits 1 on
any mismatch. Every request has pymodbus's timeout, the whole script one of its own. Run by
tests/reference/check.sh.
"""

import os
import random
import signal
import subprocess
import sys
import time

from pymodbus.client import ModbusSerialClient
from pymodbus.exceptions import ModbusException

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SCRIPT_TIMEOUT_S = 300
ROUNDS = 400
SIZE = 10000
DEVICES = (1, 2)
# The spec's start values of the read-only tables (spec/modbus.yaml, device.spaces).
INPUTS = [1, 0, 1, 1, 0, 0, 1, 0]
INPUT_REGISTERS = [1000, 2000, 0x1234, 0xFFFF]

rng = random.Random(24)
transactions = 0
mismatches = []


def mismatch(what):
    mismatches.append(what)
    print(f"mismatch: {what}", file=sys.stderr)


def fresh():
    discrete = [0] * SIZE
    discrete[: len(INPUTS)] = INPUTS
    inregs = [0] * SIZE
    inregs[: len(INPUT_REGISTERS)] = INPUT_REGISTERS
    return {"coils": [0] * SIZE, "discrete": discrete, "holding": [0] * SIZE, "input": inregs}


model = {d: fresh() for d in DEVICES}


def span(limit):
    """A start address and count within the table, counts up to `limit`."""
    count = rng.randint(1, limit)
    start = rng.randint(0, SIZE - count)
    # Now and then at the very start or end of the table.
    if rng.random() < 0.1:
        start = rng.choice([0, SIZE - count])
    return start, count


def expect_ok(what, rr):
    global transactions
    transactions += 1
    if rr.isError():
        mismatch(f"{what}: got an error reply {rr}")
        return False
    return True


def expect_exception(what, rr, code):
    global transactions
    transactions += 1
    if not rr.isError():
        mismatch(f"{what}: expected exception {code}, got {rr}")
    elif rr.exception_code != code:
        mismatch(f"{what}: expected exception {code}, got exception {rr.exception_code}")


def crc16(data):
    """Modbus RTU's CRC, low byte first."""
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc.to_bytes(2, "little")


def raw(c, frame, want):
    """Writes `frame` on the client's port and reads up to `want` bytes back (its timeout)."""
    port = c.ctx.socket if hasattr(c, "ctx") and hasattr(c.ctx, "socket") else c.socket
    port.reset_input_buffer()
    port.write(frame)
    port.flush()
    return port.read(want)


def main():
    signal.alarm(SCRIPT_TIMEOUT_S)
    sim = subprocess.Popen(
        [BUSSPEC, "sim", "modbus", "--pty", "--address", "1", "--address", "2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        path = sim.stdout.readline().strip()
        if not path.startswith("/dev/"):
            print(f"error: busspec sim printed {path!r}: {sim.stderr.read()}", file=sys.stderr)
            return 1
        # spec/modbus.yaml says even parity; a pseudo-terminal has no parity bit, and Linux
        # refuses to set one on it (EINVAL), so the client opens it without.
        client = ModbusSerialClient(path, baudrate=19200, parity="N", timeout=2, retries=0)
        if not client.connect():
            print(f"error: pymodbus cannot open {path}", file=sys.stderr)
            return 1
        run(client)
        client.close()
    finally:
        sim.kill()
        sim.wait()
    print(
        f"pymodbus client against busspec sim modbus: {transactions} transactions, "
        f"{len(mismatches)} mismatches"
    )
    return 1 if mismatches else 0


def run(c):
    ops = [
        "read_coils", "read_discrete", "read_holding", "read_input", "write_coil",
        "write_register", "write_coils", "write_registers", "outside", "invalid", "broadcast",
    ]
    for _ in range(ROUNDS):
        op = rng.choice(ops)
        dev = rng.choice(DEVICES)
        m = model[dev]
        try:
            step(c, op, dev, m)
        except ModbusException as e:
            mismatch(f"{op} to {dev}: pymodbus raised {e}")
    # Every op at least once more, in order, so none is left to chance.
    for op in ops:
        dev = DEVICES[0]
        step(c, op, dev, model[dev])


def step(c, op, dev, m):
    global transactions
    if op == "read_coils":
        start, n = span(2000)
        rr = c.read_coils(start, count=n, device_id=dev)
        if expect_ok(f"read_coils {start}+{n}", rr) and [int(b) for b in rr.bits[:n]] != m["coils"][start : start + n]:
            mismatch(f"read_coils {start}+{n} on {dev}: {rr.bits[:n]}")
    elif op == "read_discrete":
        start, n = span(2000)
        if rng.random() < 0.5:
            start = 0
        rr = c.read_discrete_inputs(start, count=n, device_id=dev)
        if expect_ok(f"read_discrete_inputs {start}+{n}", rr) and [int(b) for b in rr.bits[:n]] != m["discrete"][start : start + n]:
            mismatch(f"read_discrete_inputs {start}+{n} on {dev}: {rr.bits[:n]}")
    elif op == "read_holding":
        start, n = span(125)
        rr = c.read_holding_registers(start, count=n, device_id=dev)
        if expect_ok(f"read_holding_registers {start}+{n}", rr) and rr.registers != m["holding"][start : start + n]:
            mismatch(f"read_holding_registers {start}+{n} on {dev}: {rr.registers}")
    elif op == "read_input":
        start, n = span(125)
        if rng.random() < 0.5:
            start = 0
        rr = c.read_input_registers(start, count=n, device_id=dev)
        if expect_ok(f"read_input_registers {start}+{n}", rr) and rr.registers != m["input"][start : start + n]:
            mismatch(f"read_input_registers {start}+{n} on {dev}: {rr.registers}")
    elif op == "write_coil":
        start, _ = span(1)
        v = rng.random() < 0.5
        if expect_ok(f"write_coil {start}", c.write_coil(start, v, device_id=dev)):
            m["coils"][start] = int(v)
    elif op == "write_register":
        start, _ = span(1)
        v = rng.randrange(0x10000)
        if expect_ok(f"write_register {start}", c.write_register(start, v, device_id=dev)):
            m["holding"][start] = v
    elif op == "write_coils":
        start, n = span(1968)
        vs = [rng.random() < 0.5 for _ in range(n)]
        if expect_ok(f"write_coils {start}+{n}", c.write_coils(start, vs, device_id=dev)):
            m["coils"][start : start + n] = [int(v) for v in vs]
    elif op == "write_registers":
        start, n = span(123)
        vs = [rng.randrange(0x10000) for _ in range(n)]
        if expect_ok(f"write_registers {start}+{n}", c.write_registers(start, vs, device_id=dev)):
            m["holding"][start : start + n] = vs
    elif op == "outside":
        n = rng.randint(2, 100)
        start = SIZE - n + rng.randint(1, n - 1)
        which = rng.choice(["holding", "coils", "write_registers"])
        if which == "holding":
            rr = c.read_holding_registers(start, count=n, device_id=dev)
        elif which == "coils":
            rr = c.read_coils(start, count=n, device_id=dev)
        else:
            rr = c.write_registers(start, [1] * n, device_id=dev)
        expect_exception(f"{which} {start}+{n} past the end", rr, 2)
        # Nothing changed: the last registers still hold what the model says.
        rr = c.read_holding_registers(SIZE - 2, count=2, device_id=dev)
        if expect_ok("read_holding_registers after a refusal", rr) and rr.registers != m["holding"][SIZE - 2 :]:
            mismatch(f"a refused write changed registers {SIZE - 2}..: {rr.registers}")
    elif op == "invalid":
        # The spec's ranges: 1 to 125 holding registers, 1 to 2000 coils a read. pymodbus will
        # not build such a request, so it goes on the line by hand, through pymodbus's port.
        fc, count = rng.choice([(0x03, 0), (0x03, 126), (0x03, 0x7FFF), (0x01, 2001), (0x01, 0)])
        body = bytes([dev, fc, 0, 0]) + count.to_bytes(2, "big")
        got = raw(c, body + crc16(body), 5)
        want = bytes([dev, fc | 0x80, 3])
        transactions += 1
        if got != want + crc16(want):
            mismatch(f"function {fc:#04x} quantity {count}: expected exception 3, got {got.hex()}")
    elif op == "broadcast":
        start, _ = span(1)
        v = rng.randrange(0x10000)
        c.write_register(start, v, device_id=0, no_response_expected=True)
        # The master waits the turnaround delay after a broadcast (serial 2.4.1; the spec's
        # transactions.turnaround_ms, 100 ms) before its next request: pymodbus leaves it to us.
        time.sleep(0.1)
        for d in DEVICES:
            model[d]["holding"][start] = v
        # Both devices changed: read each back (the broadcast counts as the transaction).
        transactions += 1
        for d in DEVICES:
            rr = c.read_holding_registers(start, count=1, device_id=d)
            if expect_ok("read after broadcast", rr) and rr.registers != [v]:
                mismatch(f"broadcast write_register {start}={v}: device {d} holds {rr.registers}")


if __name__ == "__main__":
    sys.exit(main())
