"""`busspec talk modbus` against a real pymodbus RTU serial server, over pseudo-terminals.

Two pseudo-terminal pairs and a relay thread that copies bytes between their master sides make
one serial line with a device path at each end: pymodbus's `ModbusSerialServer` (RTU framer,
device id 1, broadcasts enabled) opens one, each `busspec talk --port ... modbus` call the
other. The server's datastore holds known coils, discrete inputs, holding and input registers
at addresses 0..SIZE-1; anything beyond is not there, and pymodbus answers it with exception 2.

For every function code the spec has, the reply's JSON must carry what the datastore holds (a
read) or what was written (a write), and after every write the datastore, read back in Python
from the server's own store, must hold the new values. Requests outside the datastore must be
answered with the exception reply, printed, with `modbus refused ...` on stderr, and must
change nothing. Writes to broadcast address 0 must change the datastore and get no reply (the
relay sees no byte come back). The relay also counts busspec's bytes: each call must put exactly
one request on the line (no retry after a late reply).

Every `talk` call has a timeout and so has the whole script (nothing can hang CI). Prints
`talk modbus against pymodbus: N transactions, 0 mismatches`; exits 1 on any mismatch.
Run by tests/reference/check.sh (which makes the virtual environment, pyserial included).
"""

import asyncio
import json
import os
import random
import select
import signal
import subprocess
import sys
import termios
import threading
import time
import tty

from pymodbus.framer import FramerType
from pymodbus.server import ModbusSerialServer
from pymodbus.simulator import DataType, SimData, SimDevice

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
TALK_TIMEOUT_S = 20  # one `busspec talk` process, however slow the machine
SCRIPT_TIMEOUT_S = 300  # the whole check
REPLY_TIMEOUT_MS = "3000"  # busspec's response timeout (the spec's 1 s is for a real line; CI is busy)
SIZE = 48  # addresses 0..SIZE-1 of each table exist (pymodbus keeps bits 16 to a register)
DEVICE = 1

# Function code -> table, for the server's store (SimCore.async_getValues takes a function code).
FC = {"coils": 1, "inputs": 2, "holding": 3, "input_registers": 4}

rng = random.Random(24)
transactions = 0
mismatches = []


def mismatch(what):
    mismatches.append(what)
    print(f"mismatch: {what}", file=sys.stderr)


# ---------------------------------------------------------------- the line: two ptys and a relay


def raw_pty():
    master, slave = os.openpty()
    tty.setraw(slave)
    return master, slave, os.ttyname(slave)


class Line:
    """Bytes from busspec's side go to the server's side and back, as they come."""

    def __init__(self):
        self.server_master, self.server_slave, self.server_path = raw_pty()
        self.talk_master, self.talk_slave, self.talk_path = raw_pty()
        self.from_server = 0  # bytes the server sent
        self.from_talk = 0  # bytes busspec sent
        self.lock = threading.Lock()
        self.stop = False
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        peer = {self.server_master: self.talk_master, self.talk_master: self.server_master}
        while not self.stop:
            ready, _, _ = select.select(list(peer), [], [], 0.05)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:  # EIO while no process holds the slave side open
                    continue
                with self.lock:
                    if fd == self.server_master:
                        self.from_server += len(data)
                    else:
                        self.from_talk += len(data)
                os.write(peer[fd], data)

    def counts(self):
        with self.lock:
            return self.from_talk, self.from_server

    def flush(self):
        """Drops whatever is waiting on busspec's side (a late reply must not meet the next call)."""
        termios.tcflush(self.talk_slave, termios.TCIFLUSH)


# ---------------------------------------------------------------- the pymodbus server

COILS = [rng.random() < 0.5 for _ in range(SIZE)]
INPUTS = [rng.random() < 0.5 for _ in range(SIZE)]
HOLDING = [rng.randrange(0x10000) for _ in range(SIZE)]
INPUT_REGISTERS = [rng.randrange(0x10000) for _ in range(SIZE)]


class Server:
    def __init__(self, port):
        self.connected = threading.Event()
        self.loop = asyncio.new_event_loop()
        device = SimDevice(
            id=DEVICE,
            simdata=(
                [SimData(0, values=list(COILS), datatype=DataType.BITS)],
                [SimData(0, values=list(INPUTS), datatype=DataType.BITS)],
                [SimData(0, values=list(HOLDING), datatype=DataType.REGISTERS)],
                [SimData(0, values=list(INPUT_REGISTERS), datatype=DataType.REGISTERS)],
            ),
        )
        self.port = port
        self.device = device
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        asyncio.set_event_loop(self.loop)

        async def serve():
            self.server = ModbusSerialServer(
                self.device,
                framer=FramerType.RTU,
                port=self.port,
                baudrate=19200,
                # spec/modbus.yaml says even parity; a pseudo-terminal has no parity bit, and
                # pyserial's request for one was refused (EINVAL, Linux 6.18): ask for none.
                parity="N",
                broadcast_enable=True,
                trace_connect=lambda up: up and self.connected.set(),
            )
            await self.server.serve_forever()

        self.loop.run_until_complete(serve())

    def values(self, table, address, count):
        """What the server's store holds, read in its own event loop."""
        got = asyncio.run_coroutine_threadsafe(
            self.server.context.async_getValues(DEVICE, FC[table], address, count), self.loop
        ).result(10)
        if not isinstance(got, list):
            raise RuntimeError(f"pymodbus store refused {table} {address}+{count}: {got}")
        return [int(v) for v in got]


# ---------------------------------------------------------------- busspec talk


def talk(line, address, command, **fields):
    global transactions
    transactions += 1
    args = [BUSSPEC, "talk", "--port", line.talk_path, "modbus", "--address", str(address)]
    args += ["--timeout", REPLY_TIMEOUT_MS, command]
    # A list's byte count: given as byte_count (talk checks it against the list) or as _bytes
    # (talk computes it, as encode does; only the line's length check here uses it).
    data_bytes = fields.pop("_bytes", fields.get("byte_count"))
    for name, value in fields.items():
        if isinstance(value, list):
            value = "[" + ",".join(str(v) for v in value) + "]"
        args.append(f"{name}={value}")
    line.flush()
    sent_before, replied_before = line.counts()
    try:
        r = subprocess.run(args, capture_output=True, text=True, timeout=TALK_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return None, "", f"timed out after {TALK_TIMEOUT_S} s", 0, args
    # One request on the line, no retry: address, code, 4 bytes, [count, data], CRC.
    one = 8 if data_bytes is None else 9 + data_bytes
    # busspec may exit before the relay has carried its last bytes (a broadcast waits for no
    # reply): wait for them, then, after a broadcast, give the server time to answer wrongly.
    deadline = time.monotonic() + 2
    while line.counts()[0] - sent_before < one and time.monotonic() < deadline:
        time.sleep(0.01)
    if address == 0:
        time.sleep(0.2)
    sent, replied = line.counts()
    sent, replied = sent - sent_before, replied - replied_before
    if sent != one:
        mismatch(f"{' '.join(args[3:])}: {sent} bytes on the line from busspec, one request is {one}")
    return r.returncode, r.stdout, r.stderr, replied, args


def reply(result, message):
    """The one JSON line of a transaction that must succeed with MESSAGE; None on a mismatch."""
    rc, out, err, _, args = result
    what = " ".join(args[3:])
    if rc != 0:
        mismatch(f"{what}: exit {rc}: {err.strip()}")
        return None
    lines = out.splitlines()
    if len(lines) != 1:
        mismatch(f"{what}: {len(lines)} lines: {out!r}")
        return None
    got = json.loads(lines[0])
    if got.get("message") != message or got.get("direction") != "response":
        mismatch(f"{what}: reply {got}, want message {message}")
        return None
    if got.get("address") != DEVICE:
        mismatch(f"{what}: reply from address {got.get('address')}")
    return got["fields"]


def check(what, got, want):
    if got != want:
        mismatch(f"{what}: {got}, want {want}")


READS = [
    ("read_coils", "coils", "coils"),
    ("read_discrete_inputs", "inputs", "inputs"),
    ("read_holding_registers", "holding", "registers"),
    ("read_input_registers", "input_registers", "registers"),
]


def read_all(line, server):
    """Every read function code over a few spans, each reply against the store."""
    for command, table, field in READS:
        spans = [(0, 1), (0, SIZE), (SIZE - 1, 1), (3, 9 if table in ("coils", "inputs") else 5)]
        spans += [(a, rng.randint(1, SIZE - a)) for a in (rng.randrange(SIZE) for _ in range(2))]
        for start, n in spans:
            fields = reply(talk(line, DEVICE, command, starting_address=start, quantity=n),
                           f"{command}_reply")
            if fields is not None:
                want = server.values(table, start, n)
                if table in ("coils", "inputs"):
                    want += [0] * (-n % 8)  # the last byte's unused bits travel as zeros
                check(f"{command} {start}+{n}", fields.get(field), want)


def write_all(line, server, address):
    """Every write function code to ADDRESS (DEVICE, or broadcast 0); the store must change."""
    broadcast = address == 0

    def sent(result, message, want):
        if broadcast:
            rc, out, err, replied, args = result
            what = " ".join(args[3:])
            if rc != 0 or out != "" or "it is not answered" not in err:
                mismatch(f"{what}: exit {rc}, stdout {out!r}, stderr {err.strip()!r}")
            if replied:
                mismatch(f"{what}: the server answered a broadcast ({replied} bytes)")
            return
        fields = reply(result, message)
        if fields is not None:
            check(message, fields, want)

    def store(table, start, want, what):
        # A broadcast has no reply to wait for: give the server a moment to apply it.
        deadline = time.monotonic() + (3 if broadcast else 0)
        while True:
            got = server.values(table, start, len(want))
            if got == want or time.monotonic() >= deadline:
                break
            time.sleep(0.02)
        check(f"{what}: the store after the write", got, want)

    for _ in range(3):
        a = rng.randrange(SIZE)
        state = "off" if server.values("coils", a, 1)[0] else "on"
        sent(talk(line, address, "write_single_coil", output_address=a, output_value=state),
             "write_single_coil_reply", {"output_address": a, "output_value": state})
        store("coils", a, [1 if state == "on" else 0], f"write_single_coil {a}")

        a, v = rng.randrange(SIZE), rng.randrange(0x10000)
        sent(talk(line, address, "write_single_register", register_address=a, register_value=v),
             "write_single_register_reply", {"register_address": a, "register_value": v})
        store("holding", a, [v], f"write_single_register {a}")

        a = rng.randrange(SIZE)
        n = rng.randint(1, SIZE - a)
        bits = [rng.randint(0, 1) for _ in range(n)]
        sent(talk(line, address, "write_multiple_coils", starting_address=a, quantity=n,
                  _bytes=(n + 7) // 8, outputs=bits),
             "write_multiple_coils_reply", {"starting_address": a, "quantity": n})
        store("coils", a, bits, f"write_multiple_coils {a}+{n}")

        a = rng.randrange(SIZE)
        n = rng.randint(1, SIZE - a)
        regs = [rng.randrange(0x10000) for _ in range(n)]
        sent(talk(line, address, "write_multiple_registers", starting_address=a, quantity=n,
                  _bytes=2 * n, values=regs),
             "write_multiple_registers_reply", {"starting_address": a, "quantity": n})
        store("holding", a, regs, f"write_multiple_registers {a}+{n}")


def refusals(line, server):
    """Every function code beyond the datastore: exception 2, said on stderr, nothing changed."""
    coils, holding = server.values("coils", 0, SIZE), server.values("holding", 0, SIZE)
    cases = [(c, {"starting_address": SIZE, "quantity": 2}) for c, _, _ in READS]
    cases += [(c, {"starting_address": SIZE - 1, "quantity": 2}) for c, _, _ in READS]
    cases += [
        ("write_single_coil", {"output_address": SIZE, "output_value": "on"}),
        ("write_single_register", {"register_address": SIZE + 5, "register_value": 7}),
        ("write_multiple_coils", {"starting_address": SIZE - 1, "quantity": 3, "byte_count": 1,
                                  "outputs": [1, 0, 1]}),
        ("write_multiple_registers", {"starting_address": SIZE, "quantity": 2, "byte_count": 4,
                                      "values": [1, 2]}),
    ]
    for command, fields in cases:
        result = talk(line, DEVICE, command, **fields)
        got = reply(result, f"{command}_exception")
        if got is not None:
            check(f"{command} {fields}: exception code", got.get("exception_code"),
                  "illegal_data_address")
            want = f"modbus refused {command} ({command}_exception)\n"
            check(f"{command} {fields}: stderr", result[2], want)
    check("the coils after refused writes", server.values("coils", 0, SIZE), coils)
    check("the holding registers after refused writes", server.values("holding", 0, SIZE), holding)


def main():
    signal.signal(signal.SIGALRM, lambda *_: (print(
        f"talk modbus against pymodbus: timed out after {SCRIPT_TIMEOUT_S} s", file=sys.stderr),
        os._exit(2)))
    signal.alarm(SCRIPT_TIMEOUT_S)
    line = Line()
    server = Server(line.server_path)
    if not server.connected.wait(20):
        print("talk modbus against pymodbus: the server did not open its port", file=sys.stderr)
        sys.exit(2)
    check("the store as built", server.values("coils", 0, SIZE), [int(c) for c in COILS])
    check("the store as built", server.values("input_registers", 0, SIZE), INPUT_REGISTERS)
    read_all(line, server)
    write_all(line, server, DEVICE)
    read_all(line, server)
    refusals(line, server)
    write_all(line, server, 0)
    read_all(line, server)
    print(f"talk modbus against pymodbus: {transactions} transactions, {len(mismatches)} mismatches")
    # The server thread is a daemon; leaving without shutting it down is what ends it.
    sys.stdout.flush()
    os._exit(1 if mismatches else 0)


if __name__ == "__main__":
    main()
