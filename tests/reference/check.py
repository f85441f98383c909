"""busspec's Modbus RTU, Dynamixel 1.0 and 2.0, Pelco D and CRSF specs against the reference implementations.

Each way, for every function code / instruction:
- peer -> busspec: the peer's own encoder builds a frame; `busspec decode --spec` must decode it
  to the message and the values it was built from (replies also with `--request`, which checks
  them against their request: byte count = 2 x quantity, code | 0x80, ...);
- busspec -> peer: `busspec encode --spec` builds a frame from JSON values; the peer's decoder
  must accept it and read the same values (Dynamixel requests, which the SDK only sends, must be
  byte for byte what the SDK sends for the same values).

Every busspec call runs twice, with the built-in protocol (its generated code) and with
`--spec` (the interpreter), and the two must answer alike.

Run by tests/reference/check.sh, which makes the virtual environment. Prints the number of
frames checked each way per peer; exits 1 on the first disagreement, naming the frame.
"""

import json
import os
import random
import subprocess
import sys

import dynamixel_sdk as dxl
from pymodbus.framer import FramerRTU
from pymodbus.pdu import ExceptionResponse
from pymodbus.pdu.bit_message import (
    ReadCoilsRequest,
    ReadCoilsResponse,
    ReadDiscreteInputsRequest,
    ReadDiscreteInputsResponse,
    WriteMultipleCoilsRequest,
    WriteMultipleCoilsResponse,
    WriteSingleCoilRequest,
    WriteSingleCoilResponse,
)
from pymodbus.pdu.decoders import DecodePDU
from pymodbus.pdu.register_message import (
    ReadHoldingRegistersRequest,
    ReadHoldingRegistersResponse,
    ReadInputRegistersRequest,
    ReadInputRegistersResponse,
    WriteMultipleRegistersRequest,
    WriteMultipleRegistersResponse,
    WriteSingleRegisterRequest,
    WriteSingleRegisterResponse,
)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUSSPEC = os.environ.get("BUSSPEC", os.path.join(ROOT, "target", "debug", "busspec"))
MODBUS = os.path.join(ROOT, "spec", "modbus.yaml")
DYNAMIXEL = os.path.join(ROOT, "spec", "dynamixel.yaml")
rng = random.Random(14)
counts = {}


def count(peer, way):
    counts[(peer, way)] = counts.get((peer, way), 0) + 1


def fail(what):
    print(f"reference check FAILED: {what}", file=sys.stderr)
    sys.exit(1)


def busspec(args, stdin=None):
    r = subprocess.run([BUSSPEC] + args, input=stdin, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def both_engines(command, spec, proto, rest, stdin=None):
    """Runs `busspec COMMAND PROTO REST` with the built-in protocol (generated code) and with
    `--spec SPEC` (the interpreter); they must answer alike, status and stderr included."""
    built_in = busspec([command, proto, *rest], stdin)
    interpreted = busspec([command, "--spec", spec, proto, *rest], stdin)
    if built_in != interpreted:
        fail(
            f"busspec {command} {proto} {' '.join(rest)[:200]}: the generated code answers "
            f"{built_in}, the interpreter {interpreted}"
        )
    return built_in


def decode(spec, proto, frames, extra=()):
    """Decodes frames (bytes) in one call; returns one JSON object per frame."""
    if not frames:
        return []
    rc, out, err = both_engines(
        "decode", spec, proto, [*extra] + [f.hex() for f in frames]
    )
    lines = out.splitlines()
    if rc != 0 or len(lines) != len(frames):
        fail(f"busspec decode {' '.join(extra)} refused a peer frame: {err.strip()}")
    return [json.loads(l) for l in lines]


def encode(spec, proto, objs):
    rc, out, err = both_engines(
        "encode", spec, proto, [], "\n".join(json.dumps(o) for o in objs) + "\n"
    )
    lines = out.splitlines()
    if rc != 0 or len(lines) != len(objs):
        fail(f"busspec encode refused values: {err.strip()}")
    return [bytes.fromhex(l) for l in lines]


def expect(frame, got, want, peer):
    for k, v in want.items():
        if k not in ("message",) and got["fields"].get(k) != v:
            fail(
                f"{peer} frame {frame.hex()}: busspec reads {k} = {got['fields'].get(k)}, the peer built {v}"
            )
    if got["message"] != want["message"]:
        fail(f"{peer} frame {frame.hex()}: busspec reads {got['message']}, the peer built {want['message']}")


# ---------------------------------------------------------------- Modbus RTU (pymodbus)

client = FramerRTU(DecodePDU(is_server=False))  # decodes responses
server = FramerRTU(DecodePDU(is_server=True))  # decodes requests
EXCEPTIONS = {
    1: "illegal_function",
    2: "illegal_data_address",
    3: "illegal_data_value",
    4: "server_device_failure",
    5: "acknowledge",
    6: "server_device_busy",
    8: "memory_parity_error",
    10: "gateway_path_unavailable",
    11: "gateway_target_device_failed_to_respond",
}
CODES = {
    1: "read_coils",
    2: "read_discrete_inputs",
    3: "read_holding_registers",
    4: "read_input_registers",
    5: "write_single_coil",
    6: "write_single_register",
    15: "write_multiple_coils",
    16: "write_multiple_registers",
}


def bits(n):
    return [rng.random() < 0.5 for _ in range(n)]


def regs(n):
    return [rng.choice([0, 1, 0x7FFF, 0x8000, 0xFFFF, rng.randrange(0x10000)]) for _ in range(n)]


def as01(bs):
    return [1 if b else 0 for b in bs]


def padded(bs):
    return as01(bs) + [0] * (-len(bs) % 8)


def modbus_cases():
    """(request pdu, request values, reply pdu, reply values), the values as busspec prints them."""
    cases = []
    devices = [1, 2, 17, 100, 247]
    starts = [0, 1, 0x6B, 0x1234, 0xFFFF]
    for dev in devices:
        for start in starts:
            for fc, req_cls, rsp_cls, name, top in (
                (1, ReadCoilsRequest, ReadCoilsResponse, "coils", 2000),
                (2, ReadDiscreteInputsRequest, ReadDiscreteInputsResponse, "inputs", 2000),
            ):
                for q in (1, 7, 8, 9, 16, 100, top):
                    b = bits(q)
                    cases.append((
                        req_cls(address=start, count=q, dev_id=dev),
                        {"message": CODES[fc], "starting_address": start, "quantity": q},
                        rsp_cls(bits=b, dev_id=dev),
                        {"message": CODES[fc] + "_reply", "byte_count": (q + 7) // 8, name: padded(b)},
                    ))
            for fc, req_cls, rsp_cls in (
                (3, ReadHoldingRegistersRequest, ReadHoldingRegistersResponse),
                (4, ReadInputRegistersRequest, ReadInputRegistersResponse),
            ):
                for q in (1, 2, 3, 64, 125):
                    r = regs(q)
                    cases.append((
                        req_cls(address=start, count=q, dev_id=dev),
                        {"message": CODES[fc], "starting_address": start, "quantity": q},
                        rsp_cls(registers=r, dev_id=dev),
                        {"message": CODES[fc] + "_reply", "byte_count": 2 * q, "registers": r},
                    ))
            for on in (True, False):
                v = {"output_address": start, "output_value": "on" if on else "off"}
                cases.append((
                    WriteSingleCoilRequest(address=start, bits=[on], dev_id=dev),
                    {"message": "write_single_coil", **v},
                    WriteSingleCoilResponse(address=start, bits=[on], dev_id=dev),
                    {"message": "write_single_coil_reply", **v},
                ))
            for value in (0, 3, 0x1234, 0xFFFF):
                v = {"register_address": start, "register_value": value}
                cases.append((
                    WriteSingleRegisterRequest(address=start, registers=[value], dev_id=dev),
                    {"message": "write_single_register", **v},
                    WriteSingleRegisterResponse(address=start, registers=[value], dev_id=dev),
                    {"message": "write_single_register_reply", **v},
                ))
            for q in (1, 8, 10, 17, 1968):
                b = bits(q)
                cases.append((
                    WriteMultipleCoilsRequest(address=start, bits=b, dev_id=dev),
                    {"message": "write_multiple_coils", "starting_address": start, "quantity": q,
                     "byte_count": (q + 7) // 8, "outputs": padded(b)},
                    WriteMultipleCoilsResponse(address=start, count=q, dev_id=dev),
                    {"message": "write_multiple_coils_reply", "starting_address": start, "quantity": q},
                ))
            for q in (1, 2, 50, 123):
                r = regs(q)
                cases.append((
                    WriteMultipleRegistersRequest(address=start, registers=r, dev_id=dev),
                    {"message": "write_multiple_registers", "starting_address": start, "quantity": q,
                     "byte_count": 2 * q, "values": r},
                    WriteMultipleRegistersResponse(address=start, count=q, dev_id=dev),
                    {"message": "write_multiple_registers_reply", "starting_address": start, "quantity": q},
                ))
    # Exception replies to every function code, with every exception code.
    for fc in CODES:
        for code, name in EXCEPTIONS.items():
            dev = rng.choice(devices)
            req, req_v = {
                1: (ReadCoilsRequest(address=0x04A1, count=1, dev_id=dev), {"starting_address": 0x04A1, "quantity": 1}),
                2: (ReadDiscreteInputsRequest(address=5, count=3, dev_id=dev), {"starting_address": 5, "quantity": 3}),
                3: (ReadHoldingRegistersRequest(address=9, count=2, dev_id=dev), {"starting_address": 9, "quantity": 2}),
                4: (ReadInputRegistersRequest(address=9, count=2, dev_id=dev), {"starting_address": 9, "quantity": 2}),
                5: (WriteSingleCoilRequest(address=7, bits=[True], dev_id=dev), {"output_address": 7, "output_value": "on"}),
                6: (WriteSingleRegisterRequest(address=7, registers=[9], dev_id=dev), {"register_address": 7, "register_value": 9}),
                15: (WriteMultipleCoilsRequest(address=7, bits=[True, False, True], dev_id=dev),
                     {"starting_address": 7, "quantity": 3, "byte_count": 1, "outputs": [1, 0, 1, 0, 0, 0, 0, 0]}),
                16: (WriteMultipleRegistersRequest(address=7, registers=[1, 2], dev_id=dev),
                     {"starting_address": 7, "quantity": 2, "byte_count": 4, "values": [1, 2]}),
            }[fc]
            cases.append((
                req, {"message": CODES[fc], **req_v},
                ExceptionResponse(fc, code, device_id=dev),
                {"message": CODES[fc] + "_exception", "exception_code": name},
            ))
    return cases


def pymodbus_read(framer, frame):
    used, pdu = framer.handleFrame(frame, 0, 0)
    if pdu is None or used != len(frame):
        fail(f"pymodbus refused busspec's frame {frame.hex()}")
    return pdu


def pymodbus_values(pdu, want):
    """The values of a pymodbus pdu in busspec's terms (only the keys `want` names)."""
    fc = pdu.function_code
    got = {}
    if fc & 0x80:
        got["message"] = CODES[fc & 0x7F] + "_exception"
        got["exception_code"] = EXCEPTIONS.get(pdu.exception_code, pdu.exception_code)
        return got
    name = want["message"]
    got["message"] = name
    if name in ("read_coils", "read_discrete_inputs", "read_holding_registers", "read_input_registers"):
        got.update(starting_address=pdu.address, quantity=pdu.count)
    elif name in ("read_coils_reply", "read_discrete_inputs_reply"):
        key = "coils" if name == "read_coils_reply" else "inputs"
        got[key] = as01(pdu.bits)
        got["byte_count"] = len(pdu.bits) // 8
    elif name in ("read_holding_registers_reply", "read_input_registers_reply"):
        got.update(registers=list(pdu.registers), byte_count=2 * len(pdu.registers))
    elif name.startswith("write_single_coil"):
        got.update(output_address=pdu.address, output_value="on" if pdu.bits[0] else "off")
    elif name.startswith("write_single_register"):
        got.update(register_address=pdu.address, register_value=pdu.registers[0])
    elif name == "write_multiple_coils":
        got.update(starting_address=pdu.address, quantity=pdu.count, byte_count=pdu.byte_count,
                   outputs=padded(pdu.bits))
    elif name == "write_multiple_registers":
        got.update(starting_address=pdu.address, quantity=pdu.count, byte_count=pdu.byte_count,
                   values=list(pdu.registers))
    else:
        got.update(starting_address=pdu.address, quantity=pdu.count)
    return got


def check_modbus():
    cases = modbus_cases()
    # peer -> busspec: requests, then each reply with its request.
    frames = [client.buildFrame(req) for req, _, _, _ in cases]
    for f, got, (_, want, _, _) in zip(frames, decode(MODBUS, "modbus", frames, ["--direction", "request"]), cases):
        expect(f, got, want, "pymodbus")
        count("pymodbus", "peer -> busspec")
    for f, (_, _, rsp, want) in zip(frames, cases):
        frame = server.buildFrame(rsp)
        (got,) = decode(MODBUS, "modbus", [frame], ["--request", f.hex()])
        expect(frame, got, want, "pymodbus")
        count("pymodbus", "peer -> busspec")
    # busspec -> peer: busspec encodes the same values; pymodbus must read them alike.
    objs = []
    for req, req_v, rsp, rsp_v in cases:
        for v, pdu in ((req_v, req), (rsp_v, rsp)):
            fields = {k: x for k, x in v.items() if k != "message"}
            objs.append({"message": v["message"], "address": pdu.dev_id, "fields": fields})
    encoded = encode(MODBUS, "modbus", objs)
    for i, (frame, obj) in enumerate(zip(encoded, objs)):
        framer = server if i % 2 == 0 else client
        pdu = pymodbus_read(framer, frame)
        want = {"message": obj["message"], **obj["fields"]}
        got = pymodbus_values(pdu, want)
        if pdu.dev_id != obj["address"]:
            fail(f"pymodbus reads device {pdu.dev_id} from {frame.hex()}, busspec wrote {obj['address']}")
        for k, v in want.items():
            if got.get(k) != v:
                fail(f"busspec frame {frame.hex()}: pymodbus reads {k} = {got.get(k)}, busspec wrote {v}")
        count("pymodbus", "busspec -> peer")
    # Where pymodbus and the document disagree (reported, busspec follows the document):
    # pymodbus writes up to 2000 coils in one request (a 259-byte frame); the document allows
    # 1968 (0x7B0), which keeps the frame within the 256 bytes of an RTU frame.
    for q, reason in ((2000, "frame too long: 259 bytes, the longest frame has 255"),
                      (1969, "frame too long: 256 bytes, the longest frame has 255")):
        over = client.buildFrame(WriteMultipleCoilsRequest(address=0, bits=bits(q), dev_id=1))
        rc, _, err = both_engines("decode", MODBUS, "modbus", ["--direction", "request", over.hex()])
        if rc == 0 or reason not in err:
            fail(f"busspec accepted pymodbus's {q}-coil write: {err}")
        count("pymodbus", "peer -> busspec (refused: outside the document)")
    # modbus-e02: a Write Single Coil value other than FF 00 / 00 00 is illegal; busspec reads
    # it as its number, pymodbus as ON.
    (odd,) = encode(MODBUS, "modbus", [{"message": "write_single_coil", "address": 1,
                                        "fields": {"output_address": 5, "output_value": 0x1234}}])
    (got,) = decode(MODBUS, "modbus", [odd], ["--direction", "request"])
    if got["fields"]["output_value"] != 0x1234 or pymodbus_read(server, odd).bits != [True]:
        fail(f"erratum modbus-e02 is out of date: busspec {got}, pymodbus {pymodbus_read(server, odd).bits}")
    count("pymodbus", "busspec -> peer (read differently: erratum modbus-e02)")


# ------------------------------------------------------- Dynamixel 1.0 (dynamixel-sdk)


class Port:
    """A port for the SDK's packet handler: keeps what it writes, reads what it is given."""

    def __init__(self):
        self.is_using = False
        self.written = b""
        self.incoming = b""

    def clearPort(self):
        pass

    def writePort(self, packet):
        self.written = bytes(packet)
        return len(packet)

    def readPort(self, length):
        data, self.incoming = self.incoming[:length], self.incoming[length:]
        return list(data)

    def setPacketTimeout(self, _length):
        pass

    def isPacketTimeout(self):
        return True

    def getBytesAvailable(self):
        return len(self.incoming)


def dxl_cases():
    """(sdk call sending a request, busspec values of that request, reply values or None)."""
    ph = dxl.PacketHandler(1.0)
    cases = []
    for dev in (0, 1, 7, 100, 253):
        cases.append((lambda p, d=dev: ph.factoryReset(p, d), {"message": "reset"}, dev))
        cases.append((lambda p, d=dev: ph.action(p, d), {"message": "action"}, dev))
        for addr in (0, 3, 0x1E, 0x2B, 0xFF):
            for n in (1, 2, 4, 16, 64):
                data = [rng.randrange(256) for _ in range(n)]
                cases.append((lambda p, d=dev, a=addr, n=n: ph.readTx(p, d, a, n),
                              {"message": "read", "address": addr, "length": n}, dev))
                cases.append((lambda p, d=dev, a=addr, n=n, x=data: ph.writeTxOnly(p, d, a, n, x),
                              {"message": "write", "address": addr, "data": data}, dev))
                cases.append((lambda p, d=dev, a=addr, n=n, x=data: ph.regWriteTxOnly(p, d, a, n, x),
                              {"message": "reg_write", "address": addr, "data": data}, dev))
    # Ping is a transaction in the SDK (it reads the model number after); its request goes
    # out through the same txPacket as every other, here built as the SDK's ping builds it.
    for dev in (0, 1, 253):
        cases.append((lambda p, d=dev: ph.txPacket(p, [0, 0, d, 2, dxl.INST_PING, 0]), {"message": "ping"}, dev))
    for addr, n, ids in ((30, 4, [0, 1, 2, 3]), (24, 1, [5]), (32, 2, list(range(0, 40)))):
        blocks = []
        for i in ids:
            blocks += [i] + [rng.randrange(256) for _ in range(n)]
        cases.append((lambda p, a=addr, n=n, b=blocks: ph.syncWriteTxOnly(p, a, n, b, len(b)),
                      {"message": "sync_write", "address": addr, "data_length": n, "blocks": blocks}, 0xFE))
    return ph, cases


def check_dynamixel():
    ph, cases = dxl_cases()
    sent = []
    for call, want, dev in cases:
        port = Port()
        call(port)
        if not port.written:
            fail(f"the SDK sent nothing for {want}")
        sent.append((port.written, want, dev))
    got = decode(DYNAMIXEL, "dynamixel", [s for s, _, _ in sent], ["--direction", "request"])
    for (frame, want, dev), g in zip(sent, got):
        expect(frame, g, want, "dynamixel-sdk")
        if g["address"] != dev:
            fail(f"dynamixel-sdk frame {frame.hex()}: busspec reads ID {g['address']}, the SDK sent {dev}")
        count("dynamixel-sdk", "peer -> busspec")
    # busspec -> SDK, requests: what busspec encodes from the same values is what the SDK sends.
    objs = [{"message": w["message"], "address": dev,
             "fields": {k: v for k, v in w.items() if k != "message"}} for _, w, dev in sent]
    for frame, (sdk, want, _) in zip(encode(DYNAMIXEL, "dynamixel", objs), sent):
        if frame != sdk:
            fail(f"{want['message']}: busspec encodes {frame.hex()}, the SDK sends {sdk.hex()}")
        count("dynamixel-sdk", "busspec -> peer")
    # Status packets: the SDK's own status packet parser (rxPacket) reads what busspec encodes.
    statuses = []
    names = ["input_voltage", "angle_limit", "overheating", "range", "checksum", "overload", "instruction"]
    for dev in (0, 1, 7, 253):
        for error in (0, 1, 0x24, 0x40, 0x7F):
            flags = [n for b, n in enumerate(names) if error >> b & 1]
            statuses.append({"message": "status", "address": dev, "fields": {"error": flags}, "raw_error": error})
            for n in (1, 2, 4, 32, 200):
                data = [rng.randrange(256) for _ in range(n)]
                statuses.append({"message": "read_status", "address": dev,
                                 "fields": {"error": flags, "data": data}, "raw_error": error})
    frames = encode(DYNAMIXEL, "dynamixel", [{k: v for k, v in s.items() if k != "raw_error"} for s in statuses])
    for frame, s in zip(frames, statuses):
        port = Port()
        port.incoming = frame
        rx, result = ph.rxPacket(port)
        if result != dxl.COMM_SUCCESS:
            fail(f"the SDK refuses busspec's status packet {frame.hex()}: {ph.getTxRxResult(result)}")
        data = rx[5:-1]
        want = s["fields"].get("data", [])
        if rx[2] != s["address"] or rx[4] != s["raw_error"] or data != want:
            fail(f"the SDK reads {frame.hex()} as ID {rx[2]}, error {rx[4]}, data {data}; busspec wrote {s}")
        count("dynamixel-sdk", "busspec -> peer")
        # And back: busspec decodes the status the SDK accepted as the answer to a READ of
        # that many bytes (or, without data, to a PING).
        if s["message"] == "read_status":
            req = bytes(encode(DYNAMIXEL, "dynamixel", [{"message": "read", "address": s["address"] if s["address"] < 254 else 1,
                                                          "fields": {"address": 0, "length": len(want)}}])[0])
            (g,) = decode(DYNAMIXEL, "dynamixel", [frame], ["--request", req.hex()])
            if g["fields"]["data"] != want:
                fail(f"busspec reads {frame.hex()} as {g}")


def check_dynamixel_erratum():
    """dxl-e01: bit 7 of the error byte, and ID 254 in a status packet: busspec decodes them,
    the SDK refuses them."""
    ph = dxl.PacketHandler(1.0)
    for obj in ({"message": "status", "address": 1, "fields": {"error": [128]}},
                {"message": "status", "address": 254, "fields": {"error": []}}):
        (frame,) = encode(DYNAMIXEL, "dynamixel", [obj])
        decode(DYNAMIXEL, "dynamixel", [frame], ["--direction", "response"])
        port = Port()
        port.incoming = frame
        _, result = ph.rxPacket(port)
        if result == dxl.COMM_SUCCESS:
            fail(f"the SDK now accepts {frame.hex()}: erratum dxl-e01 is out of date")
        count("dynamixel-sdk", "busspec -> peer (refused by the peer: erratum dxl-e01)")


# ------------------------------------------------------- Dynamixel 2.0 (dynamixel-sdk)
#
# The SDK's protocol 2.0 packet handler writes each instruction packet to the port (byte
# stuffing and CRC-16 applied by its txPacket) and parses status packets with its rxPacket
# (CRC checked, stuffing removed); the port is the Port above.

DYNAMIXEL2 = os.path.join(ROOT, "spec", "dynamixel2.yaml")


def stuffable(n):
    """n random bytes, now and then holding the FF FF FD that byte stuffing escapes."""
    data = [rng.randrange(256) for _ in range(n)]
    if n >= 3 and rng.random() < 0.4:
        at = rng.randrange(n - 2)
        data[at:at + 3] = [0xFF, 0xFF, 0xFD]
    return data


def unstuffed(frame):
    """Whether an instruction packet holds FF FF FD after its header without the stuffed FD."""
    body = frame[7:-2]
    for i in range(len(body)):
        ctx = frame[i + 5:i + 8]
        if body[i] == 0xFD and ctx[:2] == b"\xff\xff" and (i + 1 >= len(body) or body[i + 1] != 0xFD):
            return True
    return False


def sdk_stuffed(ph, frame):
    """`frame` as the SDK's addStuffing stuffs it, its CRC computed again over the result."""
    p = ph.addStuffing(list(frame))
    crc = ph.updateCRC(0, p, len(p) - 2)
    p[-2], p[-1] = crc & 0xFF, crc >> 8
    return bytes(p)


def dxl2_cases():
    """(sdk call sending a request, busspec values of that request, the ID it goes to)."""
    ph = dxl.PacketHandler(2.0)
    cases = []

    def ping(p, d):
        tx = [0] * 10
        tx[4], tx[5], tx[7] = d, 3, dxl.INST_PING
        ph.txPacket(p, tx)

    for dev in (0, 1, 7, 100, 252, 0xFE):
        cases.append((lambda p, d=dev: ping(p, d), {"message": "ping"}, dev))
        cases.append((lambda p, d=dev: ph.action(p, d), {"message": "action"}, dev))
        cases.append((lambda p, d=dev: ph.reboot(p, d), {"message": "reboot"}, dev))
        cases.append((lambda p, d=dev: ph.clearMultiTurn(p, d), {"message": "clear"}, dev))
        for option, name in ((0xFF, "reset_all"), (0x01, "except_id"), (0x02, "except_id_and_baud")):
            cases.append((lambda p, d=dev, o=option: ph.factoryReset(p, d, o),
                          {"message": "factory_reset", "option": name}, dev))
        for addr in (0, 64, 116, 0x1FF, 0xFFFD):
            for n in (1, 2, 4, 16, 64, 200):
                data = stuffable(n)
                if dev != 0xFE:
                    cases.append((lambda p, d=dev, a=addr, n=n: ph.readTx(p, d, a, n),
                                  {"message": "read", "address": addr, "length": n}, dev))
                cases.append((lambda p, d=dev, a=addr, n=n, x=data: ph.writeTxOnly(p, d, a, n, x),
                              {"message": "write", "address": addr, "data": data}, dev))
                cases.append((lambda p, d=dev, a=addr, n=n, x=data: ph.regWriteTxOnly(p, d, a, n, x),
                              {"message": "reg_write", "address": addr, "data": data}, dev))
    for addr in (0, 116, 0x1FD):
        for n in (1, 2, 3, 4):
            for ids in ([1], [1, 2], list(range(0, 40)), [0xFF, 0xFF, 0xFD][:0] or [252, 0, 17]):
                cases.append((lambda p, a=addr, n=n, i=ids: ph.syncReadTx(p, a, n, i, len(i), False),
                              {"message": "sync_read", "address": addr, "length": n, "ids": ids}, 0xFE))
                blocks, param = [], []
                for i in ids[:50]:
                    data = stuffable(n)
                    blocks.append({"id": i, "data": int.from_bytes(bytes(data), "little")})
                    param += [i] + data
                cases.append((lambda p, a=addr, n=n, x=param: ph.syncWriteTxOnly(p, a, n, x, len(x)),
                              {"message": "sync_write", "address": addr, "data_length": n, "blocks": blocks}, 0xFE))
    for k in (1, 2, 5, 30):
        blocks, param, wparam = [], [], []
        for j in range(k):
            i, a, n = rng.randrange(253), rng.randrange(0x10000), rng.randrange(1, 40)
            blocks.append({"id": i, "address": a, "length": n})
            param += [i, a & 0xFF, a >> 8, n & 0xFF, n >> 8]
            if len(wparam) < 200:
                data = stuffable(n)
                wparam += [i, a & 0xFF, a >> 8, n & 0xFF, n >> 8] + data
        cases.append((lambda p, x=param: ph.bulkReadTx(p, x, len(x), False),
                      {"message": "bulk_read", "blocks": blocks}, 0xFE))
        if len(wparam) <= 255:
            cases.append((lambda p, x=wparam: ph.bulkWriteTxOnly(p, x, len(x)),
                          {"message": "bulk_write", "blocks": wparam}, 0xFE))
    return ph, cases


def check_dynamixel2():
    peer = "dynamixel-sdk (protocol 2.0)"
    ph, cases = dxl2_cases()
    sent = []
    for call, want, dev in cases:
        port = Port()
        call(port)
        if not port.written:
            fail(f"the SDK sent nothing for {want}")
        sent.append((port.written, want, dev))
    # The SDK's txPacket drops what addStuffing returns: a packet whose parameters hold
    # FF FF FD goes out unstuffed (erratum dxl2-e05). busspec refuses those, as the e-Manual's
    # receiver would; the others decode to the values they were built from.
    plain = [s for s in sent if not unstuffed(s[0])]
    got = decode(DYNAMIXEL2, "dynamixel2", [s for s, _, _ in plain], ["--direction", "request"])
    for (frame, want, dev), g in zip(plain, got):
        expect(frame, g, want, peer)
        if g["address"] != dev:
            fail(f"{peer} frame {frame.hex()}: busspec reads ID {g['address']}, the SDK sent {dev}")
        count(peer, "peer -> busspec")
    for frame, want, _ in sent:
        if unstuffed(frame):
            rc, _, err = both_engines("decode", DYNAMIXEL2, "dynamixel2", ["--direction", "request", frame.hex()])
            if rc == 0 or "bad escape" not in err:
                fail(f"{peer} frame {frame.hex()} ({want['message']}, unstuffed): busspec answers {rc} {err.strip()}")
            count(peer, "peer -> busspec (unstuffed, refused by busspec: erratum dxl2-e05)")
    # busspec -> SDK, requests: what busspec encodes from the same values is what the SDK sends
    # (stuffed as its own addStuffing stuffs, CRC over the stuffed packet).
    objs = [{"message": w["message"], "address": dev,
             "fields": {k: v for k, v in w.items() if k != "message"}} for _, w, dev in sent]
    for frame, (sdk, want, _) in zip(encode(DYNAMIXEL2, "dynamixel2", objs), sent):
        if frame != sdk_stuffed(ph, sdk):
            fail(f"{want['message']}: busspec encodes {frame.hex()}, the SDK sends {sdk.hex()}")
        count(peer, "busspec -> peer")
    # Status packets: the SDK's rxPacket reads what busspec encodes (ID, error byte,
    # parameters), and busspec decodes them back as the reply to the request they answer.
    statuses = []
    for dev in (0, 1, 7, 252):
        for error in (0, 1, 2, 7, 0x80, 0x85):
            alert, number = error >> 7, error & 0x7F
            statuses.append(({"message": "status", "address": dev,
                              "fields": {"alert": alert, "error_number": number}}, error, [], "write", None))
            model, fw = rng.randrange(0x10000), rng.randrange(256)
            statuses.append(({"message": "ping_status", "address": dev,
                              "fields": {"ping_alert": alert, "ping_error_number": number,
                                         "model_number": model, "firmware_version": fw}},
                             error, [model & 0xFF, model >> 8, fw], "ping", None))
            for n in (1, 2, 3, 4, 32, 200):
                data = stuffable(n)
                statuses.append(({"message": "read_status", "address": dev,
                                  "fields": {"read_alert": alert, "read_error_number": number, "data": data}},
                                 error, data, "read", {"address": 0, "length": n}))
                statuses.append(({"message": "bulk_read_status", "address": dev,
                                  "fields": {"bulk_alert": alert, "bulk_error_number": number, "data": data}},
                                 error, data, "bulk_read", None))
    frames = encode(DYNAMIXEL2, "dynamixel2", [s[0] for s in statuses])
    for frame, (obj, error, params, cmd, req) in zip(frames, statuses):
        port = Port()
        port.incoming = frame
        rx, result = ph.rxPacket(port, False)
        if result != dxl.COMM_SUCCESS:
            fail(f"the SDK refuses busspec's status packet {frame.hex()}: {ph.getTxRxResult(result)}")
        length = rx[5] | rx[6] << 8
        got = rx[9:9 + length - 4]
        if rx[4] != obj["address"] or rx[8] != error or got != params:
            fail(f"the SDK reads {frame.hex()} as ID {rx[4]}, error {rx[8]}, parameters {got}; busspec wrote {obj}")
        count(peer, "busspec -> peer")
        # And back, as the reply to its command (READ: to a request of that many bytes).
        extra = ["--reply-to", cmd]
        if req is not None:
            (q,) = encode(DYNAMIXEL2, "dynamixel2", [{"message": cmd, "address": obj["address"], "fields": req}])
            extra = ["--request", q.hex()]
        (g,) = decode(DYNAMIXEL2, "dynamixel2", [frame], extra)
        expect(frame, g, {"message": obj["message"], **obj["fields"]}, peer)
        count(peer, "peer -> busspec (status packets the SDK accepted)")


def check_dynamixel2_errata():
    """dxl2-e01: a Sync Write of more than four bytes a device the SDK builds, busspec refuses."""
    ph = dxl.PacketHandler(2.0)
    port = Port()
    ph.syncWriteTxOnly(port, 116, 8, [1] + list(range(8)), 9)
    rc, _, err = both_engines("decode", DYNAMIXEL2, "dynamixel2", ["--direction", "request", port.written.hex()])
    if rc == 0 or "data_length" not in err:
        fail(f"busspec now decodes {port.written.hex()} (8 bytes a device): erratum dxl2-e01 is out of date")
    count("dynamixel-sdk (protocol 2.0)", "peer -> busspec (refused by busspec: erratum dxl2-e01)")


# --------------------------------------------------------------- Pelco D (pyptzcontroller)
#
# pyptzcontroller 0.1.2's PtzControl writes its frames to a serial port and reads a position
# query's 7-byte answer from it; here the port is an object that keeps what is written and
# hands back what busspec encoded. Its public methods (stop, move, set_preset, go_to_preset,
# move_to_pan_tilt, get_position) and, for the commands it has no method for (clear_preset,
# aux_on, aux_off, reboot, the queries, move_to_zoom), its frame builder `_create_command`.
# (libpelco 1.1, the other Pelco D package there, is Python 2 only: it does not import.)

PELCO_D = os.path.join(ROOT, "spec", "pelco_d.yaml")
BITS = ["sense", "auto_manual_scan", "camera_on_off", "iris_close", "iris_open", "focus_near",
        "focus_far", "zoom_wide", "zoom_tele", "tilt_down", "tilt_up", "pan_left", "pan_right"]
SPECIAL_PRESETS = {0x21: "flip", 0x22: "zero_pan"}


class PeerPort:
    """What PtzControl takes for a serial port: keeps the frames written, answers reads."""

    def __init__(self):
        self.is_open = True
        self.written = []
        self.answers = []

    def reset_input_buffer(self):
        pass

    def write(self, frame):
        self.written.append(bytes(frame))

    def read(self, n):
        return self.answers.pop(0)[:n] if self.answers else b""


def pelco_peer(address):
    import contextlib
    import io

    from ptz_control_lib import PtzControl

    with contextlib.redirect_stdout(io.StringIO()):  # it reports every step on stdout
        ptz = PtzControl(port="unused", address=address)
    ptz.serial_port = PeerPort()
    return ptz


def peer_call(ptz, method, *args, **kwargs):
    """Calls the peer, returns the frames it wrote and what the method returned."""
    import contextlib
    import io

    ptz.serial_port.written = []
    with contextlib.redirect_stdout(io.StringIO()):
        result = getattr(ptz, method)(*args, **kwargs)
    return ptz.serial_port.written, result


def standard(**set_bits):
    fields = {b: 0 for b in BITS}
    fields.update({"pan_speed": 0, "tilt_speed": 0})
    fields.update(set_bits)
    return fields


def pelco_cases():
    """(address, peer method, args, kwargs, [(busspec message, fields)] it should write)."""
    cases = []
    for address in (1, 2, 0x7F, 0xFE, 0xFF):
        cases.append((address, "stop", (), {}, [("standard", standard())]))
        speeds = range(64) if address == 1 else rng.sample(range(64), 8)
        for speed in speeds:
            cases.append((address, "move", ("up", speed), {}, [("standard", standard(tilt_up=1, tilt_speed=speed))]))
            cases.append((address, "move", ("down", speed), {}, [("standard", standard(tilt_down=1, tilt_speed=speed))]))
            cases.append((address, "move", ("left", speed), {}, [("standard", standard(pan_left=1, pan_speed=speed))]))
            cases.append((address, "move", ("right", speed), {}, [("standard", standard(pan_right=1, pan_speed=speed))]))
        presets = range(1, 256) if address == 1 else rng.sample(range(1, 256), 8) + [0x21, 0x22]
        for preset in presets:
            value = SPECIAL_PRESETS.get(preset, preset)
            cases.append((address, "set_preset", (preset,), {}, [("set_preset", {"preset": preset})]))
            cases.append((address, "go_to_preset", (preset,), {}, [("go_to_preset", {"preset": value})]))
            cases.append((address, "_create_command", ("clear_preset",), {"preset_id": preset},
                          [("clear_preset", {"preset": preset})]))
        for aux in range(1, 9):
            cases.append((address, "_create_command", ("aux_on",), {"switch_id": aux}, [("set_auxiliary", {"auxiliary": aux})]))
            cases.append((address, "_create_command", ("aux_off",), {"switch_id": aux}, [("clear_auxiliary", {"auxiliary": aux})]))
        cases.append((address, "_create_command", ("reboot",), {}, [("remote_reset", {})]))
        for q in ("pan", "tilt", "zoom"):
            cases.append((address, "_create_command", (f"query_{q}",), {}, [(f"query_{q}_position", {})]))
        for zoom in [0, 1, 0x1234, 0xFFFF] + rng.sample(range(0x10000), 4):
            cases.append((address, "_create_command", ("move_to_zoom",), {"d1": zoom >> 8, "d2": zoom & 0xFF},
                          [("set_zoom_position", {"position": zoom})]))
        for _ in range(16 if address == 1 else 4):
            pan = rng.randrange(36000) / 100
            tilt = rng.randrange(-8500, 2001) / 100
            pan_raw = int(pan * 100)
            tilt_raw = int(36000 - tilt * 100) if tilt >= 0 else int(abs(tilt * 100))
            cases.append((address, "move_to_pan_tilt", (pan, tilt), {},
                          [("set_pan_position", {"position": pan_raw}), ("set_tilt_position", {"position": tilt_raw})]))
    return cases


# Fields busspec gives in degrees (the `centidegrees` unit, raw hundredths): compared as the raw
# numbers the peer wrote.
SCALED = {("set_pan_position", "position"): 100, ("set_tilt_position", "position"): 100,
          ("pan_position_response", "position"): 100, ("tilt_position_response", "position"): 100}


def raw_fields(message, fields):
    out = {}
    for k, v in fields.items():
        scale = SCALED.get((message, k))
        if scale is not None:
            out[k] = round(v * scale)
        else:
            out[k] = v
    return out


def json_fields(message, fields):
    """The raw numbers as `busspec encode` takes them (physical units)."""
    out = {}
    for k, v in fields.items():
        scale = SCALED.get((message, k))
        if scale is not None:
            out[k] = v / scale
        else:
            out[k] = v
    return out


def check_pelco_d():
    peer = "pyptzcontroller (Pelco D)"
    peers = {}
    cases = pelco_cases()
    frames, wants = [], []
    for address, method, args, kwargs, want in cases:
        ptz = peers.setdefault(address, pelco_peer(address))
        if method == "_create_command":
            # The frame builder returns the frame rather than writing it.
            _, frame = peer_call(ptz, method, *args, **kwargs)
            written = [frame]
        else:
            written, _ = peer_call(ptz, method, *args, **kwargs)
        if len(written) != len(want):
            fail(f"{peer} {method}{args}: wrote {len(written)} frames, expected {len(want)}")
        for frame, (message, fields) in zip(written, want):
            frames.append(frame)
            wants.append((address, message, fields))
    # peer -> busspec: every frame decodes to what the peer built it from.
    for frame, got, (address, message, fields) in zip(frames, decode(PELCO_D, "pelco_d", frames), wants):
        if got["address"] != address:
            fail(f"{peer} frame {frame.hex()}: busspec reads address {got['address']}, the peer wrote {address}")
        expect(frame, {"message": got["message"], "fields": raw_fields(got["message"], got["fields"])},
               {"message": message, **fields}, peer)
        count(peer, "peer -> busspec")
    # busspec -> peer: busspec encodes the same values to the peer's bytes.
    objs = [{"message": m, "address": a, "fields": json_fields(m, f)} for a, m, f in wants]
    for frame, ours, obj in zip(frames, encode(PELCO_D, "pelco_d", objs), objs):
        if ours != frame:
            fail(f"busspec encodes {obj} as {ours.hex()}, the peer as {frame.hex()}")
        count(peer, "busspec -> peer")
    # Position replies: busspec encodes them, the peer's get_position reads them (its queries
    # decode in busspec, above and here).
    for address in (1, 0x7F, 0xFF):
        ptz = peers[address]
        for _ in range(40):
            pan_raw = rng.randrange(36000)
            tilt_raw = rng.choice([rng.randrange(0, 8501), rng.randrange(34000, 36001)])
            replies = encode(PELCO_D, "pelco_d", [
                {"message": "pan_position_response", "address": address, "fields": {"position": pan_raw / 100}},
                {"message": "tilt_position_response", "address": address, "fields": {"position": tilt_raw / 100}},
            ])
            ptz.serial_port.answers = list(replies)
            written, (pan, tilt) = peer_call(ptz, "get_position")
            want_tilt = (36000 - tilt_raw) / 100 if tilt_raw > 18000 else -tilt_raw / 100
            if pan != pan_raw / 100 or tilt != want_tilt:
                fail(f"the peer reads {[r.hex() for r in replies]} as pan {pan}, tilt {tilt}; busspec wrote {pan_raw}, {tilt_raw}")
            count(peer, "busspec -> peer")
            count(peer, "busspec -> peer")
            queries = decode(PELCO_D, "pelco_d", written)
            if [q["message"] for q in queries] != ["query_pan_position", "query_tilt_position"]:
                fail(f"the peer's get_position wrote {[w.hex() for w in written]}, busspec reads {queries}")
            for reply, query in zip(replies, written):
                (g,) = decode(PELCO_D, "pelco_d", [reply], ["--request", query.hex()])
                if g["message"] not in ("pan_position_response", "tilt_position_response"):
                    fail(f"busspec reads {reply.hex()} as the reply to {query.hex()}: {g}")
            count(peer, "peer -> busspec")
            count(peer, "peer -> busspec")


# ----------------------------------------------------------------------- CRSF (crsf-parser)
#
# crsf-parser 0.3.2 builds (crsf_build_frame) and parses (crsf_frame, CRSFParser.parse_stream)
# frames that start with the sync byte 0xC8, with payload structures for RC channels, battery,
# link statistics and heartbeat; it lists GPS and attitude sizes and parses extended headers
# (destination, origin for types above 0x27) but builds and parses neither whole (erratum
# crsf-e07): those frames are held to its CRC, its sizes and its header structure.

from crsf_parser import CRSFParser, PacketValidationStatus
from crsf_parser.frames import crsf_header
from crsf_parser.handling import crsf_build_frame, crsf_crc, crsf_frame_crc
from crsf_parser.payloads import PAYLOADS_SIZE, PacketsTypes

CRSF = os.path.join(ROOT, "spec", "crsf.yaml")
CRSF_PEER = "crsf-parser"
RF_PROFILE = ["fps_4", "fps_50", "fps_150"]
RF_POWER = ["mw_0", "mw_10", "mw_25", "mw_100", "mw_500", "mw_1000", "mw_2000"]
ANTENNA = ["ANTENNA_1", "ANTENNA_2"]
PEER_RF_MODE = ["RF_4_FPS", "RF_50_FPS", "RF_150_FPS"]
PEER_TX_POWER = ["TX_POWER_0_MW", "TX_POWER_10_MW", "TX_POWER_25_MW", "TX_POWER_100_MW",
                 "TX_POWER_500_MW", "TX_POWER_1000_MW", "TX_POWER_2000_MW"]


def tenths(x):
    return round(x * 10)


def peer_stream(frames):
    """What crsf-parser's stream parser reports for these frames in one buffer: (status,
    container) per frame, and its statistics."""
    got = []
    parser = CRSFParser(lambda content, status: got.append((status, content)))
    parser.parse_stream(bytearray(b"".join(frames)))
    return got, parser.get_stats()


def crsf_cases():
    """(message, raw values as the peer names and builds them) for the four payloads it
    builds."""
    cases = []
    for _ in range(150):
        cases.append(("rc_channels_packed", {"channels": [rng.randrange(2048) for _ in range(16)]}))
    for ch in ([0] * 16, [2047] * 16, [172, 992, 1811, 191] * 4):
        cases.append(("rc_channels_packed", {"channels": ch}))
    for _ in range(60):
        cases.append(("battery_sensor", {
            "voltage": rng.randrange(65536), "current": rng.randrange(65536),
            "capacity": rng.choice([0, 0xFFFFFF, rng.randrange(1 << 24)]), "remaining": rng.randrange(101),
        }))
    for _ in range(60):
        cases.append(("link_statistics", {
            "uplink_rssi_ant_1": rng.randrange(256), "uplink_rssi_ant_2": rng.randrange(256),
            "uplink_link_quality": rng.randrange(101), "uplink_snr": rng.randrange(-128, 128),
            "diversity_active_antenna": rng.randrange(2), "rf_mode": rng.randrange(3),
            "uplink_tx_power": rng.randrange(7), "downlink_rssi": rng.randrange(256),
            "downlink_link_quality": rng.randrange(101), "downlink_snr": rng.randrange(-128, 128),
        }))
    return cases


def crsf_peer_build(message, raw):
    if message == "rc_channels_packed":
        # The peer's list starts with channel 16 (erratum crsf-e01).
        return crsf_build_frame(PacketsTypes.RC_CHANNELS_PACKED, {"channels": raw["channels"][::-1]})
    if message == "battery_sensor":
        return crsf_build_frame(PacketsTypes.BATTERY_SENSOR, raw)
    peer = dict(raw)
    peer["diversity_active_antenna"] = ANTENNA[raw["diversity_active_antenna"]]
    peer["rf_mode"] = PEER_RF_MODE[raw["rf_mode"]]
    peer["uplink_tx_power"] = PEER_TX_POWER[raw["uplink_tx_power"]]
    return crsf_build_frame(PacketsTypes.LINK_STATISTICS, peer)


def crsf_json(message, raw):
    """busspec's JSON fields for the peer's raw values."""
    if message == "rc_channels_packed":
        return {"channels": raw["channels"]}
    if message == "battery_sensor":
        return {"voltage": raw["voltage"] / 10, "current": raw["current"] / 10,
                "capacity_used": raw["capacity"], "remaining": raw["remaining"]}
    return {
        "up_rssi_ant1": raw["uplink_rssi_ant_1"], "up_rssi_ant2": raw["uplink_rssi_ant_2"],
        "up_link_quality": raw["uplink_link_quality"], "up_snr": raw["uplink_snr"],
        "active_antenna": raw["diversity_active_antenna"], "rf_profile": RF_PROFILE[raw["rf_mode"]],
        "up_rf_power": RF_POWER[raw["uplink_tx_power"]], "down_rssi": raw["downlink_rssi"],
        "down_link_quality": raw["downlink_link_quality"], "down_snr": raw["downlink_snr"],
    }


def crsf_peer_values(message, content):
    """The raw values the peer parsed, named as it builds them."""
    p = content.payload
    if message == "rc_channels_packed":
        return {"channels": list(p.channels)[::-1]}
    if message == "battery_sensor":
        return {k: p[k] for k in ("voltage", "current", "capacity", "remaining")}
    out = {k: p[k] for k in ("uplink_rssi_ant_1", "uplink_rssi_ant_2", "uplink_link_quality",
                              "uplink_snr", "downlink_rssi", "downlink_link_quality", "downlink_snr")}
    out["diversity_active_antenna"] = ANTENNA.index(str(p.diversity_active_antenna))
    out["rf_mode"] = PEER_RF_MODE.index(str(p.rf_mode))
    out["uplink_tx_power"] = PEER_TX_POWER.index(str(p.uplink_tx_power))
    return out


def check_crsf():
    peer = f"{CRSF_PEER} (CRSF)"
    cases = crsf_cases()
    frames = [bytes(crsf_peer_build(m, raw)) for m, raw in cases]
    # peer -> busspec: each frame decodes to the message and values the peer built it from.
    for frame, got, (message, raw) in zip(frames, decode(CRSF, "crsf", frames), cases):
        if got["address"] != 0xC8:
            fail(f"{peer} frame {frame.hex()}: busspec reads address {got['address']}")
        expect(frame, got, {"message": message, **crsf_json(message, raw)}, peer)
        count(peer, "peer -> busspec")
    # The same frames as one capture: busspec's stream finds each, in order, with no noise.
    # (The built-in protocol and `--spec`, alike.)
    streams = [subprocess.run([BUSSPEC, "decode", *spec, "crsf", "--stream", "-"], input=b"".join(frames),
                              capture_output=True) for spec in ([], ["--spec", CRSF])]
    if streams[0].stdout != streams[1].stdout:
        fail("busspec's stream of the peer's frames: the generated code and the interpreter differ")
    lines = [json.loads(l) for l in streams[0].stdout.decode().splitlines()]
    if streams[0].returncode != 0 or [l.get("message") for l in lines] != [m for m, _ in cases]:
        fail(f"busspec's stream of the peer's {len(frames)} frames: {streams[0].stderr.decode()[:300]} / {[l.get('message') for l in lines][:10]}")
    for _ in lines:
        count(peer, "peer -> busspec (as one stream)")
    # busspec -> peer: busspec encodes the same values to the peer's bytes, and the peer's stream
    # parser reads them back, every frame valid, to the same values.
    objs = [{"message": m, "address": 0xC8, "fields": crsf_json(m, raw)} for m, raw in cases]
    ours = encode(CRSF, "crsf", objs)
    for frame, mine, obj in zip(frames, ours, objs):
        if mine != frame:
            fail(f"busspec encodes {obj} as {mine.hex()}, the peer as {frame.hex()}")
    parsed, stats = peer_stream(ours)
    if len(parsed) != len(ours) or stats.valid_frames != len(ours) or stats.crc_errors or stats.framing_errors:
        fail(f"the peer's stream parser read {len(parsed)} of busspec's {len(ours)} frames: {stats}")
    for (status, content), (message, raw), mine in zip(parsed, cases, ours):
        if status != PacketValidationStatus.VALID or crsf_peer_values(message, content) != raw:
            fail(f"the peer reads busspec's {mine.hex()} as {status} {crsf_peer_values(message, content)}, busspec wrote {raw}")
        count(peer, "busspec -> peer")

    # GPS and attitude: busspec encodes random values; the peer's CRC and payload sizes agree.
    # The other way, frames of the peer's size sealed with its CRC decode and encode back.
    def sealed(kind, payload, address=0xC8):
        body = bytes([kind]) + payload
        frame = bytes([address, len(body) + 1]) + body
        return frame + bytes([crsf_crc(frame[2:])])

    telemetry = []
    for _ in range(40):
        telemetry.append({"message": "gps", "address": 0xC8, "fields": {
            "latitude": rng.randrange(-900000000, 900000001) / 1e7,
            "longitude": rng.randrange(-1800000000, 1800000001) / 1e7,
            "groundspeed": rng.randrange(65536) / 10, "heading": rng.randrange(36000) / 100,
            "altitude": rng.randrange(65536) - 1000, "satellites": rng.randrange(256)}})
        telemetry.append({"message": "attitude", "address": 0xC8, "fields": {
            k: rng.randrange(-31416, 31417) / 10000 for k in ("pitch", "roll", "yaw")}})
    kinds = {"gps": PacketsTypes.GPS, "attitude": PacketsTypes.ATTITUDE}
    for obj, frame in zip(telemetry, encode(CRSF, "crsf", telemetry)):
        kind = kinds[obj["message"]]
        if frame[2] != kind or frame[1] - 2 != PAYLOADS_SIZE[kind] or crsf_frame_crc(frame) != frame[-1]:
            fail(f"busspec's {obj['message']} {frame.hex()}: the peer's size {PAYLOADS_SIZE[kind]} or CRC {crsf_frame_crc(frame):#04x} differ")
        count(peer, "busspec -> peer (CRC and size only: erratum crsf-e07)")
    sealed_frames = []
    for _ in range(40):
        lat = rng.randrange(-900000000, 900000001).to_bytes(4, "big", signed=True)
        lon = rng.randrange(-1800000000, 1800000001).to_bytes(4, "big", signed=True)
        sealed_frames.append(sealed(PacketsTypes.GPS, lat + lon + bytes(rng.randrange(256) for _ in range(7))))
        sealed_frames.append(sealed(PacketsTypes.ATTITUDE, b"".join(
            rng.randrange(-31416, 31417).to_bytes(2, "big", signed=True) for _ in range(3))))
    decoded = decode(CRSF, "crsf", sealed_frames)
    back = encode(CRSF, "crsf", [{"message": d["message"], "address": d["address"], "fields": d["fields"]} for d in decoded])
    for frame, d, b in zip(sealed_frames, decoded, back):
        if d["message"] not in kinds or b != frame:
            fail(f"a frame sealed with the peer's CRC, {frame.hex()}, reads {d} and encodes back as {b.hex()}")
        count(peer, "peer -> busspec (CRC and size only: erratum crsf-e07)")

    # Extended frames: the peer's header structure (destination, origin after the type) both ways.
    addresses = [0x00, 0xC8, 0xEA, 0xEC, 0xEE, 0x10]
    names = {0x00: "broadcast", 0xC8: "flight_controller", 0xEA: "remote_control", 0xEC: "receiver",
             0xEE: "transmitter_module", 0x10: "usb"}
    extended = []
    for _ in range(20):
        d, o = rng.choice(addresses), rng.choice(addresses)
        extended.append(("device_ping", 0x28, d, o, b"", {}))
        n, c = rng.randrange(256), rng.randrange(256)
        extended.append(("parameter_read", 0x2C, d, o, bytes([n, c]), {"parameter_number": n, "chunk_number": c}))
        i, off = rng.randrange(1 << 32), rng.randrange(-(1 << 31), 1 << 31)
        extended.append(("timing_correction", 0x3A, d, o,
                         bytes([0x10]) + i.to_bytes(4, "big") + off.to_bytes(4, "big", signed=True),
                         {"update_interval": i / 10, "offset": off / 10}))
        # Device information: the name up to its NUL (0 to 43 printable characters), then
        # the serial number, hardware and firmware IDs and the parameters (erratum crsf-e06).
        name = "".join(chr(rng.randrange(0x20, 0x7F)) for _ in range(rng.randrange(44)))
        serial, hw, fw = (rng.randrange(1 << 32) for _ in range(3))
        total, version = rng.randrange(256), rng.randrange(256)
        extended.append(("device_information", 0x29, d, o,
                         name.encode() + b"\0" + b"".join(x.to_bytes(4, "big") for x in (serial, hw, fw))
                         + bytes([total, version]),
                         {"device_name": name, "serial_number": serial, "hardware_id": hw, "firmware_id": fw,
                          "parameters_total": total, "parameter_version": version}))
    peer_frames = []
    for message, kind, d, o, payload, _ in extended:
        head = crsf_header.build({"frame_length": 4 + len(payload), "type": kind,
                                  "destination_address": d, "origin_address": o})
        frame = head + payload
        peer_frames.append(frame + bytes([crsf_crc(frame[2:])]))
    for frame, got, (message, kind, d, o, _, fields) in zip(peer_frames, decode(CRSF, "crsf", peer_frames), extended):
        want = {"message": message, "destination": names[d], "origin": names[o], **fields}
        expect(frame, got, want, peer)
        count(peer, "peer -> busspec (extended header: erratum crsf-e07)")
    objs = [{"message": m, "address": 0xC8,
             "fields": {"destination": names[d], "origin": names[o], **f}} for m, _, d, o, _, f in extended]
    for frame, mine in zip(peer_frames, encode(CRSF, "crsf", objs)):
        h = crsf_header.parse(mine)
        if mine != frame or (h.type, h.destination_address, h.origin_address) != (frame[2], frame[3], frame[4]) \
                or crsf_frame_crc(mine) != mine[-1]:
            fail(f"busspec's extended frame {mine.hex()}: the peer's header reads {h}, built {frame.hex()}")
        count(peer, "busspec -> peer (extended header: erratum crsf-e07)")

    # Heartbeat (erratum crsf-e04): the peer's is one byte, the document's two; each refuses the other's.
    hb = bytes(crsf_build_frame(PacketsTypes.HEARTBEAT, {"origin_device_address": 0xC8}))
    rc, out, err = both_engines("decode", CRSF, "crsf", [hb.hex()])
    if rc != 1 or out:
        fail(f"busspec decodes the peer's one-byte heartbeat {hb.hex()}: {out}")
    count(peer, "peer -> busspec refused (one-byte heartbeat: erratum crsf-e04)")
    (ours_hb,) = encode(CRSF, "crsf", [{"message": "heartbeat", "address": 0xC8, "fields": {"origin_address": "flight_controller"}}])
    parsed, stats = peer_stream([ours_hb])
    if parsed or stats.invalid_frames != 1:
        fail(f"the peer's stream parser takes busspec's two-byte heartbeat {ours_hb.hex()}: {parsed} {stats}")
    count(peer, "busspec -> peer refused (two-byte heartbeat: erratum crsf-e04)")


check_modbus()
check_dynamixel()
check_dynamixel_erratum()
check_dynamixel2()
check_dynamixel2_errata()
check_pelco_d()
check_crsf()
for (peer, way), n in sorted(counts.items()):
    print(f"{peer}: {n} frames {way}")
print("reference check: ok")
