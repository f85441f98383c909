//! The strict wire contract (issue 12, points 1, 3, 4 and 6), held for the generated code and
//! the interpreter alike:
//!
//! * decode refuses what the spec forbids — a value outside its field's `range` (special values
//!   allowed, open enums open), an address outside the device range that is neither the
//!   broadcast nor the host address, a request to the broadcast address for a command that does
//!   not accept it — with a typed error naming the field;
//! * a frame longer than the protocol's longest is refused for its length before anything else;
//! * encode refuses the same things;
//! * symmetry: what encode writes, decode accepts with the same values; what strict decode
//!   accepts, encode writes back byte for byte.
//!
//! One test per example of the "Why", a test that counts what is now refused (every
//! address of every message, every value of every ranged field up to 16 bits) against numbers
//! derived from the IR, and random-frame properties.

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{self, Direction, Leaf, Message, MessageRef};
use busspec_protocols::{
    sd, ub2, DecodeError, EncodeError, FieldValue, Framing, Message as _, Protocol, ResponseMessage,
};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// The IR of a generated protocol, loaded from the spec text it was generated from.
fn spec<P: Protocol>() -> ir::Protocol {
    busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(text: &str) -> Vec<u8> {
    interp::parse_hex(text).unwrap()
}

/// `frame` with its checksum recomputed over the bytes before it.
fn fix_checksum(p: &ir::Protocol, frame: &mut [u8]) {
    let c = &p.framing.checksum;
    let at = frame.len() - c.len();
    let sum = busspec_model::checksum::compute(&c.algorithm, &frame[..at]);
    interp::write_uint(sum, &mut frame[at..], c.byte_order);
}

/// The protocol with every rule this issue adds lifted: no ranges, every address a device
/// address, broadcast accepted everywhere. Its interpreter writes any frame, so the strict
/// engines can be shown frames the spec forbids.
fn relaxed(p: &ir::Protocol) -> ir::Protocol {
    let mut r = p.clone();
    r.framing.address.min = 0;
    r.framing.address.max = 255;
    for m in r.commands.iter_mut().chain(r.responses.iter_mut()) {
        for f in &mut m.fields {
            f.range = None;
            for b in &mut f.bits {
                b.range = None;
            }
        }
        if let Some(b) = &mut m.broadcast {
            b.accepted = true;
        }
    }
    r
}

/// The leaves of a message that take a value (not constant, not repeated).
fn free_leaves(m: &Message) -> Vec<Leaf<'_>> {
    m.leaves()
        .filter(|l| match l {
            Leaf::Field(_, f) => f.constant.is_none() && f.equals.is_none(),
            Leaf::Bits(_, _, b) => b.constant.is_none(),
        })
        .collect()
}

/// A leaf's spec range, its special values, and the raw values its wire bits can hold.
type Rules = (Option<(i64, i64)>, Vec<i64>, (i64, i64));

/// The spec range of a leaf, its special values, and the raw values its wire bits can hold.
fn leaf_rules(l: &Leaf) -> Rules {
    match l {
        Leaf::Field(_, f) => (
            f.range,
            f.special.iter().map(|s| s.value).collect(),
            interp::raw_limits(8 * f.width as u32, f.signed),
        ),
        Leaf::Bits(_, _, b) => (
            b.range,
            Vec::new(),
            interp::raw_limits(u32::from(b.width()), b.signed),
        ),
    }
}

/// Values for every free leaf: the low end of its range (0 where it has none), spaces for text.
fn baseline(m: &Message) -> Vec<Value<'static>> {
    free_leaves(m)
        .iter()
        .map(|l| {
            let raw = match l {
                Leaf::Field(_, f) if f.is_ascii() => Raw::Text(vec![b' '; f.width]),
                _ => Raw::Int(leaf_rules(l).0.map_or(0, |r| r.0)),
            };
            Value {
                name: l.name().to_owned().into(),
                raw,
            }
        })
        .collect()
}

fn with<'a>(values: &[Value<'a>], name: &str, raw: i64) -> Vec<Value<'a>> {
    let mut v = values.to_vec();
    for x in &mut v {
        if x.name == name {
            x.raw = Raw::Int(raw);
        }
    }
    v
}

/// The first command that may get response `index`: decode replies as its answer.
fn asker(p: &ir::Protocol, index: usize) -> usize {
    p.commands
        .iter()
        .position(|c| c.responses.iter().any(|(r, _)| *r == index))
        .unwrap_or_else(|| panic!("no command gets {}", p.responses[index].name))
}

/// A decoded frame, as either engine saw it: message name, address, free values.
type Seen = (String, u8, Vec<(String, Raw)>);

fn generated_values<M: busspec_protocols::Message>(m: &M) -> Vec<(String, Raw)> {
    let mut out = Vec::new();
    m.visit(|name, v| {
        let raw = match v {
            FieldValue::Int(i) => Raw::Int(i),
            FieldValue::Text(t) => Raw::Text(t.to_vec()),
            FieldValue::List(items) => Raw::List(items.iter().collect()),
            FieldValue::Records(l) => Raw::Records(
                (0..l.len())
                    .map(|k| (0..l.fields()).map(|j| l.get(k, j).unwrap_or(0)).collect())
                    .collect(),
            ),
        };
        out.push((name.to_owned(), raw));
    });
    out
}

/// One protocol's engines behind one interface: the generated code (typed) and the interpreter.
struct Engines<P: Protocol> {
    p: ir::Protocol,
    loose: ir::Protocol,
    /// A typed request per command (its baseline frame decoded), for decoding replies.
    requests: Vec<P::Request>,
}

impl<P: Protocol> Engines<P>
where
    P::Request: Serialize + DeserializeOwned,
    P::Response: Serialize + DeserializeOwned,
{
    fn new() -> Self {
        let p = spec::<P>();
        let loose = relaxed(&p);
        let device = p.framing.address.min;
        let requests = (0..p.commands.len())
            .map(|i| {
                let r = MessageRef {
                    direction: Direction::Request,
                    index: i,
                };
                let frame = interp::encode(&p, r, device, &baseline(p.message(r)))
                    .unwrap_or_else(|e| panic!("baseline of {}: {e}", p.commands[i].name));
                P::decode_request(&frame)
                    .unwrap_or_else(|e| panic!("baseline of {}: {e}", p.commands[i].name))
                    .message
            })
            .collect();
        Engines { p, loose, requests }
    }

    /// Any frame of message `r`, whatever the rules: the relaxed interpreter writes it.
    fn frame(&self, r: MessageRef, address: u8, values: &[Value]) -> Vec<u8> {
        interp::encode(&self.loose, r, address, values)
            .unwrap_or_else(|e| panic!("{}: {e}", self.p.message(r).name))
    }

    /// The command whose request a frame of `r` is decoded as the reply to, if `r` is a response.
    fn reply_to(&self, r: MessageRef) -> Option<usize> {
        (r.direction == Direction::Response).then(|| asker(&self.p, r.index))
    }

    /// The generated decoder's view of a frame of `r`'s direction.
    fn gen_decode(&self, r: MessageRef, frame: &[u8]) -> Result<Seen, DecodeError> {
        match r.direction {
            Direction::Request => P::decode_request(frame).map(|d| {
                (
                    d.message.name().to_owned(),
                    d.address,
                    generated_values(&d.message),
                )
            }),
            Direction::Response => {
                let by = &self.requests[asker(&self.p, r.index)];
                P::Response::decode_as_reply(frame, Some(by)).map(|d| {
                    (
                        d.message.name().to_owned(),
                        d.address,
                        generated_values(&d.message),
                    )
                })
            }
        }
    }

    /// The interpreter's view, held to the reply rule `decode_reply` applies: a response the
    /// request may not get is refused.
    fn interp_decode(&self, r: MessageRef, frame: &[u8]) -> Result<Seen, String> {
        let reply_to = self.reply_to(r);
        let f = interp::decode(&self.p, Some(r.direction), reply_to, frame)
            .map_err(|e| e.to_string())?;
        if let Some(c) = reply_to {
            if !self.p.commands[c]
                .responses
                .iter()
                .any(|(x, _)| *x == f.message.index)
            {
                return Err("not a reply to the request".into());
            }
        }
        let m = self.p.message(f.message);
        let free: Vec<String> = free_leaves(m).iter().map(|l| l.name().to_owned()).collect();
        let values = f
            .values
            .iter()
            .filter(|v| free.iter().any(|n| *n == v.name))
            .map(|v| (v.name.to_string(), v.raw.clone()))
            .collect();
        Ok((m.name.clone(), f.address, values))
    }

    /// Encodes a frame the generated decoder accepted, through the generated encoder.
    fn gen_reencode(&self, r: MessageRef, frame: &[u8]) -> Option<Vec<u8>> {
        let mut buf = vec![0xA5u8; P::MAX_FRAME_LEN];
        let n = match r.direction {
            Direction::Request => {
                let d = P::decode_request(frame).ok()?;
                d.message.encode(d.address, &mut buf)
            }
            Direction::Response => {
                let by = &self.requests[asker(&self.p, r.index)];
                let d = P::Response::decode_as_reply(frame, Some(by)).ok()?;
                d.message.encode(d.address, &mut buf)
            }
        };
        let n = n.unwrap_or_else(|e| panic!("a decoded frame does not encode: {e}"));
        buf.truncate(n);
        Some(buf)
    }

    /// The generated encoder on the baseline typed message of `r` with leaf `field` set to
    /// `raw` (through serde, so any typed value can be written), at `address`. `None` if the
    /// typed field cannot hold `raw`.
    fn gen_encode(
        &self,
        r: MessageRef,
        address: u8,
        field: Option<(&str, i64)>,
    ) -> Option<Result<Vec<u8>, EncodeError>> {
        let base = self.frame(r, self.p.framing.address.min, &baseline(self.p.message(r)));
        let mut buf = vec![0u8; P::MAX_FRAME_LEN];
        fn patched<M: Serialize + DeserializeOwned>(
            m: &M,
            field: Option<(&str, i64)>,
        ) -> Option<M> {
            let Some((name, raw)) = field else {
                return serde_json::from_value(serde_json::to_value(m).ok()?).ok();
            };
            let mut v = serde_json::to_value(m).ok()?;
            let fields = v.as_object_mut()?.values_mut().next()?.as_object_mut()?;
            *fields.get_mut(name)? = serde_json::Value::from(raw);
            serde_json::from_value(v).ok()
        }
        let n = match r.direction {
            Direction::Request => {
                let m = patched(&P::decode_request(&base).ok()?.message, field)?;
                m.encode(address, &mut buf)
            }
            Direction::Response => {
                let by = &self.requests[asker(&self.p, r.index)];
                let m = patched(
                    &P::Response::decode_as_reply(&base, Some(by)).ok()?.message,
                    field,
                )?;
                m.encode(address, &mut buf)
            }
        };
        Some(n.map(|n| buf[..n].to_vec()))
    }

    fn all(&self) -> Vec<MessageRef> {
        let mut out = Vec::new();
        for d in [Direction::Request, Direction::Response] {
            for index in 0..self.p.messages(d).len() {
                out.push(MessageRef {
                    direction: d,
                    index,
                });
            }
        }
        out
    }
}

// ---- The examples of the "Why", each refused by both engines. ----

#[test]
fn sd_set_point_to_id_0x20_is_refused() {
    let frame = hex("76 20 00 00 BA B0");
    assert!(sd::Sd::checksum_ok(&frame), "the frame checksums");
    let e = sd::Request::decode(&frame).unwrap_err();
    assert_eq!(
        e,
        DecodeError::BadAddress {
            offset: 1,
            found: 0x20,
            min: 0x01,
            max: 0x1E
        }
    );
    assert!(e.to_string().contains("0x20"), "{e}");
    let p = spec::<sd::Sd>();
    assert!(matches!(
        interp::decode(&p, None, None, &frame),
        Err(interp::DecodeError::BadAddress { found: 0x20, .. })
    ));
}

#[test]
fn ub2_address_0x41_is_refused() {
    let frame = hex("AA41 4001 2C");
    assert!(ub2::Ub2::checksum_ok(&frame), "the frame checksums");
    assert_eq!(
        ub2::Request::decode(&frame),
        Err(DecodeError::BadAddress {
            offset: 1,
            found: 0x41,
            min: 0x21,
            max: 0x40
        })
    );
    let p = spec::<ub2::Ub2>();
    assert!(matches!(
        interp::decode(&p, None, None, &frame),
        Err(interp::DecodeError::BadAddress { found: 0x41, .. })
    ));
    // The same frame to a device address decodes: only the address is wrong.
    let mut ok = frame.clone();
    ok[1] = 0x40;
    fix_checksum(&p, &mut ok);
    assert!(ub2::Request::decode(&ok).is_ok());
}

/// Address 0x00 is refused by both protocols, for every message, in both directions, by both
/// engines and both encoders.
#[test]
fn address_zero_is_refused() {
    fn check<P: Protocol>()
    where
        P::Request: Serialize + DeserializeOwned,
        P::Response: Serialize + DeserializeOwned,
    {
        let e = Engines::<P>::new();
        for r in e.all() {
            let m = e.p.message(r);
            let frame = e.frame(r, 0, &baseline(m));
            assert!(
                matches!(
                    e.gen_decode(r, &frame),
                    Err(DecodeError::BadAddress { found: 0, .. })
                ),
                "{}: {:?}",
                m.name,
                e.gen_decode(r, &frame)
            );
            assert!(matches!(
                interp::decode(&e.p, Some(r.direction), e.reply_to(r), &frame),
                Err(interp::DecodeError::BadAddress { found: 0, .. })
            ));
            assert!(matches!(
                e.gen_encode(r, 0, None),
                Some(Err(EncodeError::BadAddress { address: 0, .. }))
            ));
            assert!(matches!(
                interp::encode(&e.p, r, 0, &baseline(m)),
                Err(interp::EncodeError::BadAddress { address: 0, .. })
            ));
        }
    }
    check::<ub2::Ub2>();
    check::<sd::Sd>();
}

#[test]
fn sd_string_length_75_is_refused() {
    let frame = hex("10 01 4B 4B FB 8A");
    assert!(sd::Sd::checksum_ok(&frame), "the frame checksums");
    let request =
        sd::Request::ReadElectronicSerialNumber(sd::request::ReadElectronicSerialNumber {
            byte_number: 0,
        });
    for got in [
        sd::Response::decode(&frame),
        sd::Response::decode_reply(&frame, &request),
    ] {
        let e = got.unwrap_err();
        assert_eq!(
            e,
            DecodeError::OutOfRange {
                field: &sd::response::ElectronicSerialNumberCharacter::STRING_LENGTH_DESC,
                offset: 3,
                found: 75,
                min: 0,
                max: 0x20,
                kind: busspec_runtime::NumKind::Int,
            }
        );
        assert!(e.to_string().contains("string_length"), "{e}");
        assert!(e.to_string().contains("0..=32"), "{e}");
    }
    let p = spec::<sd::Sd>();
    assert!(matches!(
        interp::decode(&p, Some(Direction::Response), None, &frame),
        Err(interp::DecodeError::OutOfRange { ref field, found: 75, min: 0, max: 32, .. }) if field == "string_length"
    ));
}

#[test]
fn sd_humidity_101_and_new_id_0_are_refused() {
    let p = spec::<sd::Sd>();
    let loose = relaxed(&p);
    let humidity = p.find("humidity").unwrap();
    let frame = interp::encode(
        &loose,
        humidity,
        1,
        &[Value {
            name: "humidity".into(),
            raw: Raw::Int(101),
        }],
    )
    .unwrap();
    assert!(matches!(
        sd::Response::decode(&frame),
        Err(DecodeError::OutOfRange {
            field: busspec_protocols::FieldDesc {
                name: "humidity",
                ..
            },
            found: 101,
            min: 1,
            max: 100,
            ..
        })
    ));
    assert!(matches!(
        interp::decode(&p, Some(Direction::Response), None, &frame),
        Err(interp::DecodeError::OutOfRange { ref field, found: 101, .. }) if field == "humidity"
    ));
    // 100 is in range and 0 is the special value "no sensor": both decode.
    for ok in [100, 0] {
        let frame = interp::encode(
            &p,
            humidity,
            1,
            &[Value {
                name: "humidity".into(),
                raw: Raw::Int(ok),
            }],
        )
        .unwrap();
        assert!(sd::Response::decode(&frame).is_ok());
    }
    assert_eq!(
        sd::Response::Humidity(sd::response::Humidity { humidity: 101 }).encode(1, &mut [0; 6]),
        Err(EncodeError::NotInRange {
            field: "humidity",
            value: 101,
            min: 1,
            max: 100,
            kind: busspec_runtime::NumKind::Int,
        })
    );

    let set_id = p.find("set_servo_id").unwrap();
    let frame = interp::encode(
        &loose,
        set_id,
        1,
        &[Value {
            name: "new_id".into(),
            raw: Raw::Int(0),
        }],
    )
    .unwrap();
    assert!(matches!(
        sd::Request::decode(&frame),
        Err(DecodeError::OutOfRange {
            field: busspec_protocols::FieldDesc { name: "new_id", .. },
            found: 0,
            min: 1,
            max: 0x1E,
            ..
        })
    ));
    assert!(matches!(
        interp::decode(&p, Some(Direction::Request), None, &frame),
        Err(interp::DecodeError::OutOfRange { ref field, found: 0, .. }) if field == "new_id"
    ));
    assert_eq!(
        sd::Request::SetServoId(sd::request::SetServoId { new_id: 0 }).encode(1, &mut [0; 6]),
        Err(EncodeError::NotInRange {
            field: "new_id",
            value: 0,
            min: 1,
            max: 0x1E,
            kind: busspec_runtime::NumKind::Int,
        })
    );
}

#[test]
fn sd_encode_byte_number_37_is_refused() {
    let mut buf = [0u8; sd::MAX_FRAME_LEN];
    let e = sd::Request::ReadElectronicSerialNumber(sd::request::ReadElectronicSerialNumber {
        byte_number: 37,
    })
    .encode(1, &mut buf)
    .unwrap_err();
    assert_eq!(
        e,
        EncodeError::NotInRange {
            field: "byte_number",
            value: 37,
            min: 0,
            max: 0x1F,
            kind: busspec_runtime::NumKind::Int,
        }
    );
    assert_eq!(
        e.to_string(),
        "byte_number = 37 is outside its range 0..=31"
    );
    let p = spec::<sd::Sd>();
    let r = p.find("read_electronic_serial_number").unwrap();
    assert_eq!(
        interp::encode(
            &p,
            r,
            1,
            &[Value {
                name: "byte_number".into(),
                raw: Raw::Int(37)
            }]
        ),
        Err(interp::EncodeError::NotInRange {
            field: "byte_number".into(),
            value: 37,
            min: 0,
            max: 31,
            kind: busspec_model::number::NumKind::Int,
        })
    );
    // The frame the issue quotes (`F0010025C0C6`) is refused by decode too.
    let frame = hex("F0010025C0C6");
    assert!(sd::Sd::checksum_ok(&frame));
    assert!(matches!(
        sd::Request::decode(&frame),
        Err(DecodeError::OutOfRange {
            field: busspec_protocols::FieldDesc {
                name: "byte_number",
                ..
            },
            found: 37,
            ..
        })
    ));
}

#[test]
fn sd_read_temperatures_to_broadcast_is_refused() {
    let mut buf = [0u8; sd::MAX_FRAME_LEN];
    assert_eq!(
        sd::Request::ReadTemperatures(sd::request::ReadTemperatures).encode(0x1F, &mut buf),
        Err(EncodeError::BroadcastNotAccepted {
            message: &sd::request::ReadTemperatures::DESC,
            address: 0x1F
        })
    );
    assert_eq!(
        sd::request::ReadTemperatures::DESC,
        busspec_protocols::MessageDesc::new("read_temperatures", 0xA0, 1, &[6])
    );
    let p = spec::<sd::Sd>();
    let r = p.find("read_temperatures").unwrap();
    assert!(matches!(
        interp::encode(&p, r, 0x1F, &[]),
        Err(interp::EncodeError::BroadcastNotAccepted { address: 0x1F, .. })
    ));
    // The frame the issue quotes (`A01F00008198`) is refused by decode.
    let frame = hex("A01F00008198");
    assert!(sd::Sd::checksum_ok(&frame));
    assert_eq!(
        sd::Request::decode(&frame),
        Err(DecodeError::BroadcastNotAccepted {
            message: &sd::request::ReadTemperatures::DESC,
            address: 0x1F
        })
    );
    assert!(matches!(
        interp::decode(&p, None, None, &frame),
        Err(interp::DecodeError::BroadcastNotAccepted { address: 0x1F, .. })
    ));
    // A command that accepts broadcast still goes there.
    assert!(
        sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
            .encode(0x1F, &mut buf)
            .is_ok()
    );
}

#[test]
fn ub2_50000_byte_frame_is_refused_for_its_length() {
    let mut frame = vec![0u8; 50_000];
    frame[0] = 0xAA;
    frame[1] = 0x21;
    let too_long = |max| DecodeError::TooLong { max, found: 50_000 };
    assert_eq!(
        ub2::Request::decode(&frame),
        Err(too_long(ub2::MAX_REQUEST_LEN))
    );
    assert_eq!(
        ub2::Response::decode(&frame),
        Err(too_long(ub2::MAX_RESPONSE_LEN))
    );
    // Before the start byte: a frame too long is refused for its length whatever it holds.
    frame[0] = 0x00;
    assert_eq!(
        ub2::Request::decode(&frame),
        Err(too_long(ub2::MAX_REQUEST_LEN))
    );
    let p = spec::<ub2::Ub2>();
    assert_eq!(
        interp::decode(&p, None, None, &frame),
        Err(interp::DecodeError::TooLong {
            max: ub2::MAX_FRAME_LEN,
            found: 50_000
        })
    );
    let e = ub2::Request::decode(&frame).unwrap_err().to_string();
    assert!(e.len() < 100, "{e}");
    // One byte over the longest is refused the same way, one byte under is not.
    let mut buf = vec![0u8; ub2::MAX_REQUEST_LEN + 1];
    buf[0] = 0xAA;
    assert_eq!(
        ub2::Request::decode(&buf),
        Err(DecodeError::TooLong {
            max: ub2::MAX_REQUEST_LEN,
            found: ub2::MAX_REQUEST_LEN + 1
        })
    );
    assert!(!matches!(
        ub2::Request::decode(&buf[..ub2::MAX_REQUEST_LEN]),
        Err(DecodeError::TooLong { .. })
    ));
}

// ---- What is now refused, counted exhaustively and held to the IR. ----

/// Per protocol: how many leaves have a range, how many (leaf, raw value) pairs of ranged
/// leaves up to 16 bits are refused, and how many (message, address) pairs are refused for the
/// address or the broadcast rule.
#[derive(Debug, Default, PartialEq, Eq)]
struct Counts {
    ranged_leaves: usize,
    refused_values: usize,
    bad_addresses: usize,
    broadcast_refusals: usize,
}

/// Every value of every ranged leaf (up to 16 bits) and every address of every message, through
/// both decoders and both encoders; returns (measured, expected from the IR).
fn count<P: Protocol>() -> (Counts, Counts)
where
    P::Request: Serialize + DeserializeOwned,
    P::Response: Serialize + DeserializeOwned,
{
    let e = Engines::<P>::new();
    let p = &e.p;
    let mut measured = Counts::default();
    let mut expected = Counts::default();
    let device = p.framing.address.min;
    for r in e.all() {
        let m = p.message(r);
        let base = baseline(m);
        for l in free_leaves(m) {
            let (range, special, (lo, hi)) = leaf_rules(&l);
            let Some((min, max)) = range else { continue };
            expected.ranged_leaves += 1;
            measured.ranged_leaves += 1;
            if hi - lo > 0xFFFF {
                continue;
            }
            let name = l.name().to_owned();
            // From the IR: the wire domain less the range less the specials outside it.
            let outside_specials = special
                .iter()
                .filter(|s| !(min..=max).contains(*s) && (lo..=hi).contains(*s))
                .count();
            expected.refused_values += (hi - lo + 1 - (max - min + 1)) as usize - outside_specials;
            for raw in lo..=hi {
                let values = with(&base, &name, raw);
                let frame = e.frame(r, device, &values);
                let gen = e.gen_decode(r, &frame);
                let int = e.interp_decode(r, &frame);
                let gen_enc = e
                    .gen_encode(r, device, Some((&name, raw)))
                    .unwrap_or_else(|| panic!("{}.{name} cannot hold {raw}", m.name));
                let int_enc = interp::encode(p, r, device, &values);
                let refused = gen.is_err();
                assert_eq!(
                    int.is_err(),
                    refused,
                    "{}.{name} = {raw}: {int:?} vs {gen:?}",
                    m.name
                );
                assert_eq!(
                    gen_enc.is_err(),
                    refused,
                    "{}.{name} = {raw}: {gen_enc:?}",
                    m.name
                );
                assert_eq!(
                    int_enc.is_err(),
                    refused,
                    "{}.{name} = {raw}: {int_enc:?}",
                    m.name
                );
                if refused {
                    measured.refused_values += 1;
                    assert!(
                        matches!(gen, Err(DecodeError::OutOfRange { field, found, min: a, max: b, .. })
                            if field.name == name && found == raw && (a, b) == (min, max)),
                        "{}.{name} = {raw}: {gen:?}",
                        m.name
                    );
                    assert!(
                        matches!(gen_enc, Err(EncodeError::NotInRange { field, value, min: a, max: b, .. })
                            if field == name && value == raw && (a, b) == (min, max)),
                        "{}.{name} = {raw}: {gen_enc:?}",
                        m.name
                    );
                    assert!(
                        matches!(&int_enc, Err(interp::EncodeError::NotInRange { field, value, .. })
                            if *field == name && *value == raw),
                        "{}.{name} = {raw}: {int_enc:?}",
                        m.name
                    );
                } else {
                    assert_eq!(gen_enc.unwrap(), frame, "{}.{name} = {raw}", m.name);
                    assert_eq!(int_enc.unwrap(), frame, "{}.{name} = {raw}", m.name);
                    assert_eq!(gen.unwrap(), int.unwrap(), "{}.{name} = {raw}", m.name);
                }
            }
        }
        let a = &p.framing.address;
        for address in 0..=255u8 {
            // From the IR: the device range, the broadcast and host addresses, and the
            // command's broadcast rule.
            let allowed = (a.min..=a.max).contains(&address)
                || a.broadcast == Some(address)
                || a.host == Some(address);
            let no_broadcast = allowed
                && r.direction == Direction::Request
                && a.broadcast == Some(address)
                && !m.broadcast.as_ref().is_some_and(|b| b.accepted);
            expected.bad_addresses += usize::from(!allowed);
            expected.broadcast_refusals += usize::from(no_broadcast);

            let frame = e.frame(r, address, &base);
            let gen = e.gen_decode(r, &frame);
            let int = interp::decode(p, Some(r.direction), e.reply_to(r), &frame);
            let gen_enc = e
                .gen_encode(r, address, None)
                .expect("the baseline is typed");
            let int_enc = interp::encode(p, r, address, &base);
            let ctx = || format!("{} to 0x{address:02X}", m.name);
            match gen {
                Err(DecodeError::BadAddress { found, .. }) => {
                    assert_eq!(found, address, "{}", ctx());
                    measured.bad_addresses += 1;
                    assert!(
                        matches!(int, Err(interp::DecodeError::BadAddress { .. })),
                        "{}",
                        ctx()
                    );
                    assert!(
                        matches!(gen_enc, Err(EncodeError::BadAddress { .. })),
                        "{}",
                        ctx()
                    );
                    assert!(
                        matches!(int_enc, Err(interp::EncodeError::BadAddress { .. })),
                        "{}",
                        ctx()
                    );
                }
                Err(DecodeError::BroadcastNotAccepted { address: at, .. }) => {
                    assert_eq!(at, address, "{}", ctx());
                    measured.broadcast_refusals += 1;
                    assert!(
                        matches!(int, Err(interp::DecodeError::BroadcastNotAccepted { .. })),
                        "{}",
                        ctx()
                    );
                    assert!(
                        matches!(gen_enc, Err(EncodeError::BroadcastNotAccepted { .. })),
                        "{}",
                        ctx()
                    );
                    assert!(
                        matches!(
                            int_enc,
                            Err(interp::EncodeError::BroadcastNotAccepted { .. })
                        ),
                        "{}",
                        ctx()
                    );
                }
                Ok(_) => {
                    assert!(int.is_ok(), "{}: {int:?}", ctx());
                    assert_eq!(gen_enc.as_ref().ok(), Some(&frame), "{}", ctx());
                    assert_eq!(int_enc.as_ref().ok(), Some(&frame), "{}", ctx());
                }
                Err(other) => panic!("{}: {other}", ctx()),
            }
        }
    }
    println!("{}: {measured:?}", P::NAME);
    (measured, expected)
}

/// The figures of the closing note, per protocol, each derived from the IR and
/// measured by running every case through both decoders and both encoders.
#[test]
fn refusals_counted_against_the_ir() {
    fn check<P: Protocol>()
    where
        P::Request: Serialize + DeserializeOwned,
        P::Response: Serialize + DeserializeOwned,
    {
        let p = spec::<P>();
        let (measured, expected) = count::<P>();
        assert_eq!(measured, expected, "{}", P::NAME);

        // And the same figures in closed form from the IR, independently of the loop above.
        let messages = p.commands.len() + p.responses.len();
        let a = &p.framing.address;
        let special_addresses = [a.broadcast, a.host]
            .iter()
            .flatten()
            .filter(|x| !(a.min..=a.max).contains(*x))
            .count();
        let per_message = 256 - (usize::from(a.max - a.min) + 1) - special_addresses;
        assert_eq!(
            expected.bad_addresses,
            messages * per_message,
            "{}",
            P::NAME
        );
        let refusing = p
            .commands
            .iter()
            .filter(|c| !c.broadcast.as_ref().is_some_and(|b| b.accepted))
            .count();
        assert_eq!(
            expected.broadcast_refusals,
            if a.broadcast.is_some() { refusing } else { 0 },
            "{}",
            P::NAME
        );
        let ranged = p
            .commands
            .iter()
            .chain(&p.responses)
            .flat_map(free_leaves)
            .filter(|l| leaf_rules(l).0.is_some())
            .count();
        assert_eq!(expected.ranged_leaves, ranged, "{}", P::NAME);
        assert!(ranged > 0 && expected.refused_values > 0, "{}", P::NAME);
    }
    check::<ub2::Ub2>();
    check::<sd::Sd>();
}

// ---- Symmetry, as properties over random frames and random in-range messages. ----

/// Random frames of random messages: payload bytes partly random, any address, a right
/// checksum. Wherever strict decode accepts, both engines agree on message, address and values,
/// and both encoders write the frame back byte for byte; where one refuses, so does the other.
fn random_frames<P: Protocol>(n: usize, seed: u64) -> usize
where
    P::Request: Serialize + DeserializeOwned,
    P::Response: Serialize + DeserializeOwned,
{
    let e = Engines::<P>::new();
    let p = &e.p;
    let all = e.all();
    let mut rng = fastrand::Rng::with_seed(seed);
    let a = &p.framing.address;
    let mut accepted = 0;
    for _ in 0..n {
        let r = all[rng.usize(..all.len())];
        let m = p.message(r);
        let address = match rng.u8(..4) {
            0 => rng.u8(..),
            1 => a.broadcast.or(a.host).unwrap_or(a.min),
            _ => rng.u8(a.min..=a.max),
        };
        let mut frame = e.frame(r, address, &baseline(m));
        let o = m.layout;
        for b in &mut frame[o.payload..o.payload + m.payload_len] {
            if rng.u8(..3) != 0 {
                *b = if rng.bool() {
                    rng.u8(..)
                } else {
                    rng.u8(..0x40)
                };
            }
        }
        fix_checksum(p, &mut frame);
        let gen = e.gen_decode(r, &frame);
        let int = e.interp_decode(r, &frame);
        let ctx = || format!("{} {}", m.name, interp::format_hex(&frame));
        match (&gen, &int) {
            (Ok(g), Ok(i)) => {
                accepted += 1;
                assert_eq!(g, i, "{}", ctx());
                assert_eq!(
                    e.gen_reencode(r, &frame).as_ref(),
                    Some(&frame),
                    "{}",
                    ctx()
                );
                let f = interp::decode(p, Some(r.direction), e.reply_to(r), &frame).unwrap();
                let values: Vec<Value> = f
                    .values
                    .iter()
                    .filter(|v| i.2.iter().any(|(n, _)| *n == v.name))
                    .cloned()
                    .collect();
                assert_eq!(
                    interp::encode(p, f.message, f.address, &values).as_ref(),
                    Ok(&frame),
                    "{}",
                    ctx()
                );
            }
            (Err(_), Err(_)) => {}
            _ => panic!("{}: generated {gen:?}, interpreter {int:?}", ctx()),
        }
    }
    accepted
}

/// Random messages with every value in its range (or a special value, or anywhere its wire
/// field holds where it has no range), to a random allowed address: both encoders accept, both
/// decoders give the values back.
fn random_messages<P: Protocol>(n: usize, seed: u64)
where
    P::Request: Serialize + DeserializeOwned,
    P::Response: Serialize + DeserializeOwned,
{
    let e = Engines::<P>::new();
    let p = &e.p;
    let all = e.all();
    let mut rng = fastrand::Rng::with_seed(seed);
    let a = &p.framing.address;
    for _ in 0..n {
        let r = all[rng.usize(..all.len())];
        let m = p.message(r);
        let mut addresses: Vec<u8> = (a.min..=a.max).collect();
        addresses.extend(a.host);
        if let Some(b) = a.broadcast {
            if r.direction == Direction::Response
                || m.broadcast.as_ref().is_some_and(|x| x.accepted)
            {
                addresses.push(b);
            }
        }
        let address = addresses[rng.usize(..addresses.len())];
        let values: Vec<Value> = free_leaves(m)
            .iter()
            .map(|l| {
                let raw = match l {
                    Leaf::Field(_, f) if f.is_ascii() => {
                        Raw::Text((0..f.width).map(|_| rng.u8(0x20..0x7F)).collect())
                    }
                    _ => {
                        let (range, special, (lo, hi)) = leaf_rules(l);
                        let (lo, hi) = range.unwrap_or((lo, hi));
                        if !special.is_empty() && rng.u8(..8) == 0 {
                            Raw::Int(special[rng.usize(..special.len())])
                        } else {
                            Raw::Int(rng.i64(lo..=hi))
                        }
                    }
                };
                Value {
                    name: l.name().to_owned().into(),
                    raw,
                }
            })
            .collect();
        let frame = interp::encode(p, r, address, &values)
            .unwrap_or_else(|err| panic!("{} to 0x{address:02X}: {err}", m.name));
        let want: Vec<(String, Raw)> = values
            .iter()
            .map(|v| (v.name.to_string(), v.raw.clone()))
            .collect();
        let seen = (m.name.clone(), address, want);
        let ctx = || format!("{} {}", m.name, interp::format_hex(&frame));
        assert_eq!(e.interp_decode(r, &frame).as_ref(), Ok(&seen), "{}", ctx());
        assert_eq!(e.gen_decode(r, &frame).as_ref(), Ok(&seen), "{}", ctx());
        assert_eq!(
            e.gen_reencode(r, &frame).as_ref(),
            Some(&frame),
            "{}",
            ctx()
        );
    }
}

#[test]
fn strict_decode_accepts_only_what_encode_writes_back_ub2() {
    let accepted = random_frames::<ub2::Ub2>(150_000, 12);
    assert!(accepted > 10_000, "only {accepted} frames accepted");
    random_messages::<ub2::Ub2>(50_000, 13);
}

#[test]
fn strict_decode_accepts_only_what_encode_writes_back_sd() {
    let accepted = random_frames::<sd::Sd>(150_000, 14);
    assert!(accepted > 10_000, "only {accepted} frames accepted");
    random_messages::<sd::Sd>(50_000, 15);
}

/// A list with fewer elements than its spec allows is refused by both encoders in the same
/// words: Dynamixel's `read_status` carries 1 to 253 data bytes. (The generated encoder
/// worded it as a value out of range, `data = 0 is outside its range 1..=253`, until both
/// said what the interpreter says.)
#[test]
fn a_wrong_count_is_refused_in_the_same_words_by_both_encoders() {
    use busspec_protocols::dynamixel;
    let generated = dynamixel::Response::ReadStatus(dynamixel::response::ReadStatus {
        error: dynamixel::StatusError(0),
        data: busspec_runtime::Repeated::new(),
    })
    .encode(1, &mut [0; dynamixel::MAX_FRAME_LEN])
    .unwrap_err();
    assert_eq!(
        generated,
        EncodeError::WrongCount {
            field: "data",
            min: 1,
            max: 253,
            found: 0,
        }
    );
    let p = spec::<dynamixel::Dynamixel>();
    let read_status = p.find("read_status").unwrap();
    let interpreted = interp::encode(
        &p,
        read_status,
        1,
        &[
            Value {
                name: "error".into(),
                raw: Raw::Int(0),
            },
            Value {
                name: "data".into(),
                raw: Raw::List(vec![]),
            },
        ],
    )
    .unwrap_err();
    assert_eq!(generated.to_string(), interpreted.to_string());
    assert_eq!(generated.to_string(), "data takes 1..=253 elements, got 0");
}

/// Values with two faults are refused for the same one by both encoders: the lists' counts
/// before the fields at their places. Modbus's `write_multiple_registers` given a quantity out
/// of its range and no values: both name the values' count. (The generated encoder named the
/// quantity, `quantity = 0 is outside its range 1..=123`, until it checked in the
/// interpreter's order.)
#[test]
fn two_faults_are_refused_for_the_same_one_by_both_encoders() {
    use busspec_protocols::modbus;
    let generated =
        modbus::Request::WriteMultipleRegisters(modbus::request::WriteMultipleRegisters {
            starting_address: 0,
            quantity: 0,
            values: busspec_runtime::Repeated::new(),
        })
        .encode(1, &mut [0; modbus::MAX_FRAME_LEN])
        .unwrap_err();
    let p = spec::<modbus::Modbus>();
    let r = p.find("write_multiple_registers").unwrap();
    fn value(name: &'static str, raw: Raw) -> Value<'static> {
        Value {
            name: name.into(),
            raw,
        }
    }
    let interpreted = interp::encode(
        &p,
        r,
        1,
        &[
            value("starting_address", Raw::Int(0)),
            value("quantity", Raw::Int(0)),
            value("values", Raw::List(vec![])),
        ],
    )
    .unwrap_err();
    assert_eq!(generated.to_string(), interpreted.to_string());
    assert_eq!(
        generated.to_string(),
        "values takes 1..=123 elements, got 0"
    );
}
