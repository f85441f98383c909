"""ROBOTIS dynamixel-sdk against `busspec sim dynamixel` (protocol 1.0) or `busspec sim
dynamixel2` (protocol 2.0, with the argument `2.0`), over a pseudo-terminal.

`busspec sim dynamixel --pty --address 1 --address 2` serves two devices simulated from the
spec's `device:` section (1.0: an MX control table of 74 bytes, model number 29; 2.0: an
X-series table of 662 bytes, model number 1030, firmware 38); the SDK's `PortHandler` opens the
printed path and its `PacketHandler` of that version runs a seeded random mix:

- ping: the model number (1.0: the SDK reads it after the status packet; 2.0: the status
  packet carries it), as the script's model of the table holds it (the simulated table is
  writable throughout);
- read (1, 2 and n bytes) must return what the script's model of the table holds;
- write (1, 2 and n bytes) must be acknowledged without error, and change later reads of that
  device only;
- reg_write then action (broadcast, unanswered): the table must change only at the action, and
  a second reg_write replaces the first;
- sync_write (GroupSyncWrite, broadcast, unanswered): each device must take its own data;
- 2.0: sync_read (GroupSyncRead, broadcast, each listed device answers in turn) must give each
  device's bytes; a sync read that lists one device is answered by that one alone;
- a read or write past the table's end must get the status packet with the range error bit
  (1.0) or Access Error, error number 7 (2.0).

The SDK's protocol 2.0 handler sends parameters holding FF FF FD unstuffed (erratum
dxl2-e05), which the simulator rightly refuses: the mix draws no such packet.

Prints `dynamixel-sdk against busspec sim dynamixel: N transactions, 0 mismatches`; exits 1 on
any mismatch. Run by tests/reference/check.sh, once for each version.
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
DEVICES = (1, 2)
VERSION = sys.argv[1] if len(sys.argv) > 1 else "1.0"
if VERSION == "2.0":
    SIM = "dynamixel2"
    SIZE = 662
    # The error byte of a refusal past the table's end: Access Error, error number 7.
    OUTSIDE_ERROR = 7
    # spec/dynamixel2.yaml's start values: model 1030 at 0-1, firmware 38 at 6, ID 1 at 7, baud
    # rate 1 at 8, return delay 250 at 9.
    START = {0: 0x06, 1: 0x04, 6: 38, 7: 1, 8: 1, 9: 250}
    FIRST_FREE = 10
    OPS = ["ping", "read", "write", "reg_write", "sync_write", "sync_read", "outside"]
else:
    SIM = "dynamixel"
    SIZE = 74
    OUTSIDE_ERROR = 1 << 3  # the Range error bit
    # spec/dynamixel.yaml's start values: model 29, firmware 36, ID 1, return delay 250.
    START = {0: 29, 1: 0, 2: 36, 3: 1, 5: 250}
    FIRST_FREE = 6
    OPS = ["ping", "read", "write", "reg_write", "sync_write", "outside"]
# After a broadcast nobody answers: give the simulator its frame gap before the next packet.
QUIET_S = 0.02
# The SDK waits for a status packet twice its USB adapter's latency timer (16 ms) plus 2 ms:
# a pseudo-terminal and a simulator process on a loaded two-core machine answered later than
# that once in 671 transactions ("There is no status packet!" after an action). The script
# checks what the simulator answers, not how fast: it gives the SDK a 100 ms latency timer.
dxl.port_handler.LATENCY_TIMER = 100

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
        [BUSSPEC, "sim", SIM, "--pty", "--address", "1", "--address", "2"],
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
        ph = dxl.PacketHandler(float(VERSION))
        run(port, ph)
        port.closePort()
    finally:
        sim.kill()
        sim.wait()
    print(
        f"dynamixel-sdk {VERSION} against busspec sim {SIM}: {transactions} transactions, "
        f"{len(mismatches)} mismatches"
    )
    return 1 if mismatches else 0


def run(port, ph):
    for _ in range(ROUNDS):
        step(port, ph, rng.choice(OPS), rng.choice(DEVICES))
    for op in OPS:
        step(port, ph, op, DEVICES[0])


def bytes_of(n, head):
    """`n` random bytes for a packet whose parameters are `head` then them: under 2.0 none
    that make the parameters hold FF FF FD, which the SDK's handler would send unstuffed
    (erratum dxl2-e05)."""
    while True:
        data = [rng.randrange(256) for _ in range(n)]
        if VERSION != "2.0" or b"\xff\xff\xfd" not in bytes(head + data):
            return data


def le(address):
    """A control table address as the packet carries it."""
    return [address & 0xFF, address >> 8] if VERSION == "2.0" else [address]


def step(port, ph, op, dev):
    global transactions
    t = model[dev]
    if op == "ping":
        number, result, error = ph.ping(port, dev)
        # The start value at first; the simulated table is writable throughout, so the
        # script's model says.
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
        data = bytes_of(n, le(a))
        if n == 1:
            result, error = ph.write1ByteTxRx(port, dev, a, data[0])
        elif n == 2:
            result, error = ph.write2ByteTxRx(port, dev, a, data[0] | data[1] << 8)
        else:
            result, error = ph.writeTxRx(port, dev, a, n, data)
        if ok(f"write {dev} {a}+{n}", result, error, ph):
            t[a : a + n] = data
    elif op == "reg_write":
        # Near each other: the read after the action spans both (2.0: at most 254 bytes).
        fa = rng.randint(FIRST_FREE, SIZE - 2)
        sa = min(max(fa + rng.randint(-60, 60), FIRST_FREE), SIZE - 2)
        first = (fa, bytes_of(2, le(fa)))
        second = (sa, bytes_of(2, le(sa)))
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
        a = rng.randint(FIRST_FREE, SIZE - 4)
        group = dxl.GroupSyncWrite(port, ph, a, 4)
        params = le(a) + le(4)
        for d in DEVICES:
            data = bytes_of(4, params + [d])
            params += [d] + data
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
    elif op == "sync_read":
        n = rng.choice([1, 2, 4])
        a = rng.randint(0, SIZE - n)
        listed = DEVICES if rng.random() < 0.7 else (dev,)
        group = dxl.GroupSyncRead(port, ph, a, n)
        for d in listed:
            group.addParam(d)
        result = group.txRxPacket()
        transactions += 1
        if result != dxl.COMM_SUCCESS:
            mismatch(f"sync_read {listed} {a}+{n}: {ph.getTxRxResult(result)}")
            return
        for d in listed:
            want = int.from_bytes(bytes(model[d][a : a + n]), "little")
            if not group.isAvailable(d, a, n):
                mismatch(f"sync_read {listed} {a}+{n}: nothing from device {d}")
            elif group.getData(d, a, n) != want:
                mismatch(f"sync_read {a}+{n}: device {d} gave {group.getData(d, a, n)}, want {want}")
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
        if result != dxl.COMM_SUCCESS or error != OUTSIDE_ERROR:
            mismatch(
                f"{what} {dev} {a}+{n} past the end: {ph.getTxRxResult(result)}, error {error:#04x}"
            )
        # Nothing changed.
        v, result, error = ph.readTxRx(port, dev, SIZE - 4, 4)
        if ok("read after a refusal", result, error, ph) and v != t[SIZE - 4 :]:
            mismatch(f"a refused write changed the table's end: {v}")


if __name__ == "__main__":
    sys.exit(main())
