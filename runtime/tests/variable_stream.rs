//! The stream decoder's variable-length framing ([`Framing::variable_candidates`](crate::Framing::variable_candidates)), through a
//! protocol written by hand: `toy`, whose frames carry a length byte. Held to the interpreter's
//! stream decoder (`busspec_model::stream`, whose `lens_of` is the reference for a variable
//! message's lengths) on captures with noise, lying length bytes, truncated frames and
//! out-of-spec frames, cut into chunks at random.
//!
//! The toy protocol: `7E addr len code payload sum8`, `len` counting code, payload and checksum
//! (so a frame is `len + 3` bytes), addresses 1..=16, the sum over every byte before it.
//! Requests: `read` (0x01, `reg` 0..=0x7F: 6 bytes) and `write` (0x02, 1..=6 values
//! 0x10..=0xFF to the end: 6..=11 bytes). Responses: `data` (0x81, 1..=6 values to the end:
//! 6..=11 bytes) and `ack` (0x02, `status` 0..=3: 6 bytes). A `write` of one value and an `ack`
//! share code and length, so that length is tried once with both directions; their ranges keep
//! a frame from decoding as both (the runtime reports a frame that decodes in both directions as
//! ambiguous, where the interpreter lets the request before it settle it: not compared here).

use busspec_model::interp::format_hex;
use busspec_model::stream as interp_stream;
use busspec_runtime::codec::{LengthField, VarLen, VarLens};
use busspec_runtime::stream::{Candidates, Event, StreamDecoder};
use busspec_runtime::{
    Broadcast, Bus, Command, CommandKind, DecodeError, Decoded, EncodeError, FieldDesc, FieldError,
    FieldValue, Framing, Message, MessageDesc, Protocol, Repeated, Reply, RequestMessage,
    ResponseMessage, Source, Transactions,
};

const SPEC: &str = r#"
protocol: toy
title: "A toy protocol with a length byte"
document: {title: "Toy document", revision: "1", date: "2024-01-01"}
byte_order: big
printed_byte_order: big
serial: {baud: 9600, data_bits: 8, parity: none, stop_bits: 1}
framing:
  layout: [start, address, length, code, payload, checksum]
  start: 0x7E
  length: {width: 1, counts: [code, payload, checksum]}
  address: {devices: {min: 1, max: 16}}
  request:  {code_lengths: [1], payload: {min: 0, max: 6}}
  response: {code_lengths: [1], payload: {min: 0, max: 6}}
  checksum: {algorithm: sum8, width: 8, check: 0xDD}
units:
  - {name: count, symbol: "", scale: "1"}
commands:
  - name: read
    title: "Read"
    section: "1"
    kind: getter
    code: "0x01"
    fields:
      - {name: reg, type: u8, unit: count, range: {min: 0, max: 0x7F}}
    responses: [data]
  - name: write
    title: "Write"
    section: "2"
    kind: setter
    code: "0x02"
    fields:
      - {name: values, type: u8, unit: count, range: {min: 0x10, max: 0xFF}, repeat: {count: end, min: 1, max: 6}}
    responses: [ack]
responses:
  - name: data
    title: "Data"
    section: "1"
    kind: data
    code: "0x81"
    fields:
      - {name: values, type: u8, unit: count, repeat: {count: end, min: 1, max: 6}}
  - name: ack
    title: "Ack"
    section: "2"
    kind: ack
    code: "0x02"
    fields:
      - {name: status, type: u8, unit: count, range: {min: 0, max: 3}}
examples:
  - section: "1"
    message: read
    derived: "7E 01 03 01 05 88"
    values: {reg: 5}
  - section: "2"
    message: write
    derived: "7E 02 05 02 1A 1B 1C D8"
    values: {values: [0x1A, 0x1B, 0x1C]}
errata: []
"#;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Toy;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Req {
    Read { reg: u8 },
    Write { values: Repeated<u8, 6> },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Resp {
    Data { values: Repeated<u8, 6> },
    Ack { status: u8 },
}

/// The frame of `code` with `payload` to `address`.
fn frame(address: u8, code: u8, payload: &[u8], buf: &mut [u8]) -> Result<usize, EncodeError> {
    let len = payload.len() + 5;
    let available = buf.len();
    let out = buf.get_mut(..len).ok_or(EncodeError::BufferTooSmall {
        needed: len,
        available,
    })?;
    out[..4].copy_from_slice(&[0x7E, address, payload.len() as u8 + 2, code]);
    out[4..len - 1].copy_from_slice(payload);
    out[len - 1] = busspec_runtime::sum8(&out[..len - 1]);
    Ok(len)
}

impl Message for Req {
    fn name(&self) -> &'static str {
        match self {
            Req::Read { .. } => "read",
            Req::Write { .. } => "write",
        }
    }
    fn code(&self) -> &'static [u8] {
        match self {
            Req::Read { .. } => &[0x01],
            Req::Write { .. } => &[0x02],
        }
    }
    fn frame_len(&self) -> usize {
        match self {
            Req::Read { .. } => 6,
            Req::Write { values } => 5 + values.len(),
        }
    }
    fn visit<F: FnMut(&'static str, FieldValue<'_>)>(&self, mut f: F) {
        match self {
            Req::Read { reg } => f("reg", FieldValue::Int(i64::from(*reg))),
            Req::Write { values } => f("values", FieldValue::List(values.elements())),
        }
    }
    fn encode(&self, address: u8, buf: &mut [u8]) -> Result<usize, EncodeError> {
        match self {
            Req::Read { reg } => frame(address, 0x01, &[*reg], buf),
            Req::Write { values } => frame(address, 0x02, values, buf),
        }
    }
    fn from_fields<'v, F: FnMut(&'static str) -> Option<FieldValue<'v>>>(
        _name: &str,
        _field: F,
    ) -> Result<Self, FieldError> {
        Err(FieldError::UnknownMessage)
    }
}

impl Message for Resp {
    fn name(&self) -> &'static str {
        match self {
            Resp::Data { .. } => "data",
            Resp::Ack { .. } => "ack",
        }
    }
    fn code(&self) -> &'static [u8] {
        match self {
            Resp::Data { .. } => &[0x81],
            Resp::Ack { .. } => &[0x02],
        }
    }
    fn frame_len(&self) -> usize {
        match self {
            Resp::Data { values } => 5 + values.len(),
            Resp::Ack { .. } => 6,
        }
    }
    fn visit<F: FnMut(&'static str, FieldValue<'_>)>(&self, mut f: F) {
        match self {
            Resp::Data { values } => f("values", FieldValue::List(values.elements())),
            Resp::Ack { status } => f("status", FieldValue::Int(i64::from(*status))),
        }
    }
    fn encode(&self, address: u8, buf: &mut [u8]) -> Result<usize, EncodeError> {
        match self {
            Resp::Data { values } => frame(address, 0x81, values, buf),
            Resp::Ack { status } => frame(address, 0x02, &[*status], buf),
        }
    }
    fn from_fields<'v, F: FnMut(&'static str) -> Option<FieldValue<'v>>>(
        _name: &str,
        _field: F,
    ) -> Result<Self, FieldError> {
        Err(FieldError::UnknownMessage)
    }
}

/// What every frame is checked for before its code, in the interpreter's order: start byte,
/// shortest frame, checksum, address, length byte. Returns the code.
fn check(frame: &[u8]) -> Result<u8, DecodeError> {
    if frame.len() > 11 {
        return Err(DecodeError::TooLong {
            max: 11,
            found: frame.len(),
        });
    }
    if let Some(&b) = frame.first().filter(|&&b| b != 0x7E) {
        return Err(DecodeError::BadStart {
            offset: 0,
            expected: 0x7E,
            found: b,
        });
    }
    if frame.len() < 6 {
        return Err(DecodeError::Truncated {
            needed: 6,
            found: frame.len(),
        });
    }
    let n = frame.len() - 1;
    let sum = busspec_runtime::sum8(&frame[..n]);
    if sum != frame[n] {
        return Err(DecodeError::ChecksumMismatch {
            offset: n,
            expected: u32::from(sum),
            found: u32::from(frame[n]),
            width: 1,
        });
    }
    if !(1..=16).contains(&frame[1]) {
        return Err(DecodeError::BadAddress {
            offset: 1,
            found: frame[1],
            min: 1,
            max: 16,
        });
    }
    if usize::from(frame[2]) + 3 != frame.len() {
        return Err(DecodeError::LengthMismatch {
            offset: 2,
            expected: frame.len() as i64 - 3,
            found: i64::from(frame[2]),
        });
    }
    Ok(frame[3])
}

/// The hand-written fields as their refusals name them.
static READ_REG: FieldDesc = FieldDesc::new("read", "reg");
static WRITE_VALUES: FieldDesc = FieldDesc::new("write", "values");
static ACK_STATUS: FieldDesc = FieldDesc::new("ack", "status");

fn byte(field: &'static FieldDesc, v: u8, max: u8) -> Result<u8, DecodeError> {
    if v > max {
        return Err(DecodeError::OutOfRange {
            field,
            offset: 4,
            found: i64::from(v),
            min: 0,
            max: i64::from(max),
            kind: busspec_runtime::NumKind::Int,
        });
    }
    Ok(v)
}

/// The hand-written messages as their wrong lengths name them.
static VALUES: MessageDesc = MessageDesc::new("values", 0, 0, &[11]);
static READ: MessageDesc = MessageDesc::new("read", 0, 0, &[6]);

fn values(frame: &[u8]) -> Result<Repeated<u8, 6>, DecodeError> {
    Repeated::from_slice(&frame[4..frame.len() - 1]).map_err(|_| DecodeError::WrongLength {
        message: &VALUES,
        found: frame.len(),
        less: 0,
    })
}

/// The length byte: a frame is its value plus 3 bytes, from the shortest message of the code
/// (5: no element) to the longest (11), as the interpreter's `lens_of` bounds it.
const LENGTH: LengthField = LengthField {
    at: 2,
    width: 1,
    le: false,
    excess: 3,
    min: 5,
    max: 11,
};

impl Protocol for Toy {
    type Request = Req;
    type Response = Resp;
    type Buffer = [u8; 11];
    const NAME: &'static str = "toy";
    const SOURCE: Source = Source {
        document: "Toy document",
        revision: "1",
        spec_sha256: "",
        spec_yaml: SPEC,
    };
    const BUS: Bus = Bus {
        baud: 9600,
        inter_frame_gap_ms: None,
        max_frames_per_s: None,
        device_addresses: 1..=16,
        broadcast_address: None,
        host_address: None,
        replies_addressed: true,
        transactions: Transactions::UNDECLARED,
    };
    const MAX_FRAME_LEN: usize = 11;

    fn decode_request(frame: &[u8]) -> Result<Decoded<Req>, DecodeError> {
        let code = check(frame)?;
        let message = match (code, frame.len()) {
            (0x01, 6) => Req::Read {
                reg: byte(&READ_REG, frame[4], 0x7F)?,
            },
            (0x02, 6..) => {
                let values = values(frame)?;
                for v in values.iter() {
                    if *v < 0x10 {
                        return Err(DecodeError::OutOfRange {
                            field: &WRITE_VALUES,
                            offset: 4,
                            found: i64::from(*v),
                            min: 0x10,
                            max: 0xFF,
                            kind: busspec_runtime::NumKind::Int,
                        });
                    }
                }
                Req::Write { values }
            }
            (0x01 | 0x02, _) => {
                return Err(DecodeError::WrongLength {
                    message: &READ,
                    found: frame.len(),
                    less: 0,
                })
            }
            (code, _) => {
                return Err(DecodeError::UnknownCommand {
                    offset: 3,
                    code: u32::from(code),
                    len: 1,
                })
            }
        };
        Ok(Decoded {
            address: frame[1],
            message,
        })
    }
}

impl RequestMessage for Req {
    fn command(&self) -> Command {
        let kind = match self {
            Req::Read { .. } => CommandKind::Getter,
            Req::Write { .. } => CommandKind::Setter,
        };
        Command {
            kind,
            broadcast: Broadcast {
                accepted: false,
                answered: false,
            },
            reply: Reply::Required,
            may_retry: kind.safe_to_repeat(),
        }
    }
}

impl ResponseMessage<Req> for Resp {
    fn answers(&self, request: &Req) -> bool {
        matches!(
            (request, self),
            (Req::Read { .. }, Resp::Data { .. }) | (Req::Write { .. }, Resp::Ack { .. })
        )
    }
    fn is_nak(&self) -> bool {
        false
    }
    fn decode_as_reply(frame: &[u8], _request: Option<&Req>) -> Result<Decoded<Resp>, DecodeError> {
        let code = check(frame)?;
        let message = match (code, frame.len()) {
            (0x81, 6..) => Resp::Data {
                values: values(frame)?,
            },
            (0x02, 6) => Resp::Ack {
                status: byte(&ACK_STATUS, frame[4], 3)?,
            },
            (0x81 | 0x02, _) => {
                return Err(DecodeError::WrongLength {
                    message: &READ,
                    found: frame.len(),
                    less: 0,
                })
            }
            (code, _) => {
                return Err(DecodeError::UnknownResponse {
                    offset: 3,
                    code: u32::from(code),
                    len: 1,
                })
            }
        };
        Ok(Decoded {
            address: frame[1],
            message,
        })
    }
}

impl Framing for Toy {
    const MAX_REQUEST_LEN: usize = 11;
    const MAX_RESPONSE_LEN: usize = 11;
    /// Only the fixed-length messages' length: the variable ones come from the length byte.
    const FRAME_LENGTHS: &'static [usize] = &[6];
    type Span = [u8; 0];
    const EMPTY_SPAN: [u8; 0] = [];

    fn checksum_ok(frame: &[u8]) -> bool {
        frame.len() > 1
            && busspec_runtime::sum8(&frame[..frame.len() - 1]) == frame[frame.len() - 1]
    }

    fn candidates(head: &[u8]) -> Candidates {
        if head.first().is_some_and(|&b| b != 0x7E) {
            return Candidates::default();
        }
        // `read` and `ack` (bit 0: 6 bytes), by the code byte where it has arrived.
        let (requests, responses) = match head.get(3) {
            None => (1, 1),
            Some(0x01) => (1, 0),
            Some(0x02) => (0, 1),
            Some(_) => (0, 0),
        };
        Candidates {
            requests,
            responses,
        }
    }

    fn variable_candidates(head: &[u8]) -> VarLens {
        if head.first().is_some_and(|&b| b != 0x7E) {
            return VarLens::NONE;
        }
        let len = VarLen::of(LENGTH.frame_len(head));
        match head.get(3) {
            None => VarLens {
                requests: len,
                responses: len,
            },
            Some(0x81) => VarLens {
                requests: VarLen::NONE,
                responses: len,
            },
            Some(0x02) => VarLens {
                requests: len,
                responses: VarLen::NONE,
            },
            Some(_) => VarLens::NONE,
        }
    }
}

/// An event as both decoders can say it: what, where, how long.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Frame,
    Ambiguous,
    Skipped,
    OutOfSpec,
}

fn ours(ev: &Event<Req, Resp>) -> (Kind, u64, u64) {
    let kind = match ev {
        Event::Request { .. } | Event::Response { .. } => Kind::Frame,
        Event::Ambiguous { .. } => Kind::Ambiguous,
        Event::Skipped { .. } => Kind::Skipped,
        Event::OutOfSpec { .. } => Kind::OutOfSpec,
    };
    (kind, ev.offset(), ev.len())
}

fn theirs(ev: &interp_stream::Event) -> (Kind, u64, u64) {
    let kind = match ev {
        interp_stream::Event::Frame { .. } => Kind::Frame,
        interp_stream::Event::Ambiguous { .. } => Kind::Ambiguous,
        interp_stream::Event::Skipped { .. } => Kind::Skipped,
        interp_stream::Event::OutOfSpec { .. } => Kind::OutOfSpec,
    };
    (kind, ev.offset(), ev.bytes().len() as u64)
}

/// A random frame of the toy protocol, sometimes damaged: a lying length byte, a bad address,
/// an out-of-range value, a broken checksum, or cut short.
fn random_frame(rng: &mut fastrand::Rng) -> Vec<u8> {
    let mut buf = [0u8; 16];
    let address = rng.u8(1..=16);
    let n = rng.usize(1..=6);
    let values: Vec<u8> = (0..n).map(|_| rng.u8(0x10..)).collect();
    let len = match rng.u8(0..4) {
        0 => Req::Read {
            reg: rng.u8(0..=0x7F),
        }
        .encode(address, &mut buf),
        1 => Req::Write {
            values: Repeated::from_slice(&values).unwrap(),
        }
        .encode(address, &mut buf),
        2 => Resp::Data {
            values: Repeated::from_slice(&values).unwrap(),
        }
        .encode(address, &mut buf),
        _ => Resp::Ack {
            status: rng.u8(0..=3),
        }
        .encode(address, &mut buf),
    }
    .unwrap();
    let mut f = buf[..len].to_vec();
    let reseal = |f: &mut Vec<u8>| {
        let n = f.len() - 1;
        f[n] = busspec_runtime::sum8(&f[..n]);
    };
    match rng.u8(0..12) {
        // The length byte lies (and the checksum agrees, so only the length can tell).
        0 => {
            f[2] = rng.u8(..);
            reseal(&mut f);
        }
        1 => {
            f[2] = f[2].wrapping_add(if rng.bool() { 1 } else { 255 });
            reseal(&mut f);
        }
        // Out of spec: a bad address, an out-of-range value.
        2 => {
            f[1] = if rng.bool() { 0 } else { rng.u8(17..) };
            reseal(&mut f);
        }
        3 => {
            f[4] = rng.u8(0x80..);
            reseal(&mut f);
        }
        4 => f[len - 1] ^= 1 << rng.u8(0..8),
        5 => f.truncate(rng.usize(1..len)),
        _ => {}
    }
    f
}

fn random_capture(rng: &mut fastrand::Rng, frames: usize) -> Vec<u8> {
    let mut cap = Vec::new();
    for _ in 0..frames {
        if rng.u8(0..8) == 0 {
            let noise = rng.usize(1..5);
            cap.extend((0..noise).map(|_| if rng.bool() { 0x7E } else { rng.u8(..) }));
        }
        cap.extend(random_frame(rng));
    }
    cap
}

/// Our decoder over `cap`, pushed in chunks of random sizes (0: `feed` of the whole capture).
fn decode(cap: &[u8], rng: &mut fastrand::Rng, chunked: bool) -> Vec<Event<Req, Resp>> {
    let mut d = StreamDecoder::<Toy>::new(None);
    let mut out = Vec::new();
    if chunked {
        let mut rest = cap;
        while !rest.is_empty() {
            let (chunk, after) = rest.split_at(rng.usize(1..=rest.len().min(13)));
            rest = after;
            if rng.bool() {
                out.extend(d.feed(chunk));
            } else {
                let mut chunk = chunk;
                while !chunk.is_empty() {
                    let n = d.push(chunk);
                    chunk = &chunk[n..];
                    out.extend(std::iter::from_fn(|| d.poll()));
                }
            }
        }
    } else {
        out.extend(d.feed(cap));
    }
    out.extend(std::iter::from_fn(|| d.finish()));
    out
}

#[test]
fn the_toy_spec_is_valid_and_its_examples_decode_by_hand() {
    let p = busspec_model::load_str("toy.yaml", SPEC).expect("toy spec");
    assert_eq!(p.examples.len(), 2);
    for e in &p.examples {
        let d = Toy::decode_request(&e.wire).expect("example decodes");
        let mut buf = [0u8; 11];
        let n = d.message.encode(d.address, &mut buf).unwrap();
        assert_eq!(&buf[..n], &e.wire[..]);
    }
}

#[test]
fn variable_frames_follow_the_interpreters_rule() {
    let p = busspec_model::load_str("toy.yaml", SPEC).expect("toy spec");
    let mut rng = fastrand::Rng::with_seed(14);
    let mut seen = [0usize; 4];
    let mut long = 0;
    for _ in 0..400 {
        let cap = random_capture(&mut rng, 40);
        let mut reference = interp_stream::StreamDecoder::new(&p, None);
        let mut want: Vec<_> = reference.push(&cap).iter().map(theirs).collect();
        want.extend(reference.flush().iter().map(theirs));
        for chunked in [false, true] {
            let got: Vec<_> = decode(&cap, &mut rng, chunked).iter().map(ours).collect();
            assert_eq!(got, want, "capture {}", format_hex(&cap));
        }
        for (k, _, len) in &want {
            seen[*k as usize] += 1;
            long += usize::from(*k == Kind::Frame && *len > 6);
        }
    }
    // Frames of variable length, noise and out-of-spec frames all occurred (ambiguous ones
    // cannot: see the module docs).
    assert!(long > 1000, "{long} frames longer than the fixed ones");
    assert!(
        seen[Kind::Frame as usize] > 0
            && seen[Kind::Skipped as usize] > 0
            && seen[Kind::OutOfSpec as usize] > 0,
        "events by kind: {seen:?}"
    );
}

/// A length byte that lies costs one byte: the frame after it is found.
#[test]
fn a_lying_length_drops_one_byte_and_resynchronises() {
    let mut buf = [0u8; 11];
    let n = Req::Write {
        values: Repeated::from_slice(&[0x19, 0x18, 0x17]).unwrap(),
    }
    .encode(5, &mut buf)
    .unwrap();
    let good = buf[..n].to_vec();
    for lie in [0u8, 1, 2, 4, 6, 9, 200, 255] {
        // A frame whose length byte says `lie`, its checksum sealed over the lie.
        let mut bad = good.clone();
        bad[2] = lie;
        let last = bad.len() - 1;
        bad[last] = busspec_runtime::sum8(&bad[..last]);
        let cap: Vec<u8> = bad.iter().chain(&good).copied().collect();
        let mut rng = fastrand::Rng::with_seed(u64::from(lie));
        for chunked in [false, true] {
            let events = decode(&cap, &mut rng, chunked);
            assert!(
                matches!(
                    events.last(),
                    Some(Event::Request { offset, len, frame })
                        if *offset == bad.len() as u64 && *len == good.len() && frame.address == 5
                ),
                "length {lie}: {events:?}"
            );
            let accounted: u64 = events.iter().map(Event::len).sum();
            assert_eq!(accounted, cap.len() as u64);
        }
    }
}

/// A variable frame waits for its length byte and then for its whole length; cut short at the
/// end of a capture, it is noise.
#[test]
fn a_variable_frame_waits_for_its_length_then_its_bytes() {
    let mut buf = [0u8; 11];
    let n = Resp::Data {
        values: Repeated::from_slice(&[1, 2, 3, 4, 5, 6]).unwrap(),
    }
    .encode(3, &mut buf)
    .unwrap();
    assert_eq!(n, 11);
    let mut d = StreamDecoder::<Toy>::new(None);
    for (i, b) in buf.iter().enumerate() {
        assert_eq!(d.push(&[*b]), 1);
        let ev = d.poll();
        if i + 1 < n {
            assert_eq!(ev, None, "after {} bytes", i + 1);
        } else {
            assert!(
                matches!(ev, Some(Event::Response { len: 11, .. })),
                "{ev:?}"
            );
        }
    }
    // The same frame cut short, then the end of the capture: its bytes are noise, except
    // where a frame could start again inside them (none here: no 0x7E after the first).
    let mut d = StreamDecoder::<Toy>::new(None);
    d.push(&buf[..9]);
    assert_eq!(d.poll(), None);
    let rest: Vec<_> = std::iter::from_fn(|| d.finish()).collect();
    assert_eq!(rest, vec![Event::Skipped { offset: 0, len: 9 }]);
}

/// `VarLen` says what `RepeatAt::frame_len` and `LengthField::frame_len` answer.
#[test]
fn var_len_maps_frame_len() {
    assert_eq!(VarLen::of(None), VarLen::NEED_MORE);
    assert!(VarLen::of(None).needs_more());
    assert_eq!(VarLen::of(Some(0)), VarLen::NONE);
    assert!(VarLen::of(Some(0)).is_none());
    assert_eq!(VarLen::of(Some(9)).get(), Some(9));
    assert_eq!(VarLen::NONE.get(), None);
    assert_eq!(VarLen::NEED_MORE.get(), None);
    assert_eq!(VarLen::len(usize::MAX).get(), Some(u32::MAX as usize - 1));
    assert_eq!(LENGTH.frame_len(&[0x7E, 1]), None);
    assert_eq!(LENGTH.frame_len(&[0x7E, 1, 5]), Some(8));
    assert_eq!(LENGTH.frame_len(&[0x7E, 1, 1]), Some(0));
    assert_eq!(LENGTH.frame_len(&[0x7E, 1, 9]), Some(0));
    let wide = LengthField {
        at: 0,
        width: 2,
        le: true,
        excess: -2,
        min: 0,
        max: 1000,
    };
    assert_eq!(wide.frame_len(&[0x10, 0x01]), Some(0x110 - 2));
    assert_eq!(wide.frame_len(&[0x01, 0x00]), Some(0));
}
