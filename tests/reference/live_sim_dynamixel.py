"""ROBOTIS dynamixel-sdk (protocol 1.0) against `busspec sim dynamixel`, over a pseudo-terminal.

`busspec sim dynamixel --pty --address 1 --address 2` serves two devices simulated from the
spec's `device:` section (an MX control table of 74 bytes, model number 29); the SDK's
`PortHandler` opens the printed path and its `PacketHandler(1.0)` runs a seeded random mix:

- ping: the SDK reads the model number after the status packet (29 at start; the simulated
  table is writable throughout, so what the script's model holds);
- read (1, 2 and n bytes) must return what the script's model of the table holds;
- write (1, 2 and n bytes) must be acknowledged without error, and change later reads of that
  device only;
- reg_write then action (broadcast, unanswered): the table must change only at the action, and
  a second reg_write replaces the first;
- sync_write (GroupSyncWrite, broadcast, unanswered): each device must take its own data;
- a read or write past the table's end must get the status packet with the range error bit.

Prints `dynamixel-sdk against busspec sim dynamixel: N transactions, 0 mismatches`; exits 1 on
any mismatch. Run by tests/reference/check.sh.
"""

import os
import random
import signal
import subprocess
import sys
import time

import dynamixel_sdk as dxl

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
SCRIPT_TIMEOUT_S = 300
ROUNDS = 300
SIZE = 74
DEVICES = (1, 2)
RANGE_ERROR = 1 << 3
# The spec's start values (spec/dynamixel.yaml, device.spaces): model 29, firmware 36, ID 1,
# return delay 250.
START = {0: 29, 1: 0, 2: 36, 3: 1, 5: 250}
# After a broadcast nobody answers: give the simulator its frame gap before the next packet.
QUIET_S = 0.02

rng = random.Random(10)
transactions = 0
mismatches = []


def mismatch(what):
    mismatches.append(what)
    print(f"mismatch: {what}", file=sys.stderr)


def fresh():
    t = [0] * SIZE
    for a, v in START.items():
        t[a] = v
    return t


model = {d: fresh() for d in DEVICES}


def ok(what, result, error, ph):
    global transactions
    transactions += 1
    if result != dxl.COMM_SUCCESS:
        mismatch(f"{what}: {ph.getTxRxResult(result)}")
        return False
    if error != 0:
        mismatch(f"{what}: status error {error:#04x}")
        return False
    return True


def main():
    signal.alarm(SCRIPT_TIMEOUT_S)
    sim = subprocess.Popen(
        [BUSSPEC, "sim", "dynamixel", "--pty", "--address", "1", "--address", "2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        path = sim.stdout.readline().strip()
        if not path.startswith("/dev/"):
            print(f"error: busspec sim printed {path!r}: {sim.stderr.read()}", file=sys.stderr)
            return 1
        port = dxl.PortHandler(path)
        if not port.openPort():
            print(f"error: dynamixel-sdk cannot open {path}", file=sys.stderr)
            return 1
        port.setBaudRate(1000000)
        ph = dxl.PacketHandler(1.0)
        run(port, ph)
        port.closePort()
    finally:
        sim.kill()
        sim.wait()
    print(
        f"dynamixel-sdk against busspec sim dynamixel: {transactions} transactions, "
        f"{len(mismatches)} mismatches"
    )
    return 1 if mismatches else 0


def run(port, ph):
    ops = ["ping", "read", "write", "reg_write", "sync_write", "outside"]
    for _ in range(ROUNDS):
        step(port, ph, rng.choice(ops), rng.choice(DEVICES))
    for op in ops:
        step(port, ph, op, DEVICES[0])


def step(port, ph, op, dev):
    global transactions
    t = model[dev]
    if op == "ping":
        number, result, error = ph.ping(port, dev)
        # 29 at start; the simulated table is writable throughout, so the script's model says.
        want = t[0] | t[1] << 8
        if ok(f"ping {dev}", result, error, ph) and number != want:
            mismatch(f"ping {dev}: model number {number}, want {want}")
    elif op == "read":
        n = rng.choice([1, 2, rng.randint(1, 12)])
        a = rng.randint(0, SIZE - n)
        if n == 1:
            v, result, error = ph.read1ByteTxRx(port, dev, a)
            want = t[a]
        elif n == 2:
            v, result, error = ph.read2ByteTxRx(port, dev, a)
            want = t[a] | t[a + 1] << 8
        else:
            v, result, error = ph.readTxRx(port, dev, a, n)
            want = t[a : a + n]
        if ok(f"read {dev} {a}+{n}", result, error, ph) and v != want:
            mismatch(f"read {dev} {a}+{n}: {v}, want {want}")
    elif op == "write":
        n = rng.choice([1, 2, rng.randint(1, 8)])
        # Not the ID byte's neighbours alone: anywhere in the table.
        a = rng.randint(0, SIZE - n)
        data = [rng.randrange(256) for _ in range(n)]
        if n == 1:
            result, error = ph.write1ByteTxRx(port, dev, a, data[0])
        elif n == 2:
            result, error = ph.write2ByteTxRx(port, dev, a, data[0] | data[1] << 8)
        else:
            result, error = ph.writeTxRx(port, dev, a, n, data)
        if ok(f"write {dev} {a}+{n}", result, error, ph):
            t[a : a + n] = data
    elif op == "reg_write":
        first = (rng.randint(6, SIZE - 2), [rng.randrange(256) for _ in range(2)])
        second = (rng.randint(6, SIZE - 2), [rng.randrange(256) for _ in range(2)])
        for a, data in (first, second):
            result, error = ph.regWriteTxRx(port, dev, a, 2, data)
            ok(f"reg_write {dev} {a}", result, error, ph)
        # Nothing changed yet.
        a, data = second
        v, result, error = ph.readTxRx(port, dev, a, 2)
        if ok("read before action", result, error, ph) and v != t[a : a + 2]:
            mismatch(f"reg_write {dev} {a}: applied before the action ({v})")
        ph.action(port, dxl.BROADCAST_ID)
        time.sleep(QUIET_S)
        transactions += 1
        t[a : a + 2] = data  # the second replaced the first
        fa, _ = first
        v, result, error = ph.readTxRx(port, dev, min(fa, a), abs(fa - a) + 2)
        lo = min(fa, a)
        if ok("read after action", result, error, ph) and v != t[lo : lo + abs(fa - a) + 2]:
            mismatch(f"action on {dev}: table {v}, want {t[lo : lo + abs(fa - a) + 2]}")
    elif op == "sync_write":
        a = rng.randint(6, SIZE - 4)
        group = dxl.GroupSyncWrite(port, ph, a, 4)
        for d in DEVICES:
            data = [rng.randrange(256) for _ in range(4)]
            group.addParam(d, data)
            model[d][a : a + 4] = data
        result = group.txPacket()
        time.sleep(QUIET_S)
        transactions += 1
        if result != dxl.COMM_SUCCESS:
            mismatch(f"sync_write: {ph.getTxRxResult(result)}")
        for d in DEVICES:
            v, result, error = ph.readTxRx(port, d, a, 4)
            if ok(f"read after sync_write {d}", result, error, ph) and v != model[d][a : a + 4]:
                mismatch(f"sync_write at {a}: device {d} holds {v}, want {model[d][a : a + 4]}")
    elif op == "outside":
        n = rng.randint(2, 10)
        a = SIZE - n + rng.randint(1, n - 1)
        if rng.random() < 0.5:
            _, result, error = ph.readTxRx(port, dev, a, n)
            what = "read"
        else:
            result, error = ph.writeTxRx(port, dev, a, n, [1] * n)
            what = "write"
        transactions += 1
        if result != dxl.COMM_SUCCESS or error != RANGE_ERROR:
            mismatch(
                f"{what} {dev} {a}+{n} past the end: {ph.getTxRxResult(result)}, error {error:#04x}"
            )
        # Nothing changed.
        v, result, error = ph.readTxRx(port, dev, SIZE - 4, 4)
        if ok("read after a refusal", result, error, ph) and v != t[SIZE - 4 :]:
            mismatch(f"a refused write changed the table's end: {v}")


if __name__ == "__main__":
    sys.exit(main())
