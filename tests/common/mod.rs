//! Shared by the tests that hold the generated crate against the interpreter: loading the specs,
//! the values each engine decodes (compared field by field, raw), and random frames.

#![allow(dead_code)]

use busspec_codegen::interp::{self, Frame, Raw};
use busspec_codegen::ir::{Direction, Message, MessageRef, Protocol};
use busspec_codegen::{checksum, load_file};
use busspec_protocols::FieldValue;

pub fn spec(name: &str) -> Protocol {
    load_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("spec")
            .join(name),
    )
    .unwrap_or_else(|d| panic!("{d}"))
}

/// One decoded field: name and raw wire value.
pub type Values = Vec<(String, Raw)>;

/// What the generated code made of a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Decoded {
    pub name: &'static str,
    pub address: u8,
    pub values: Values,
    /// The frame the generated encoder writes back for the decoded message.
    pub reencoded: Vec<u8>,
}

/// Collects a generated message's fields through its `visit`.
pub fn visit_values(visit: impl FnOnce(&mut dyn FnMut(&'static str, FieldValue<'_>))) -> Values {
    let mut out = Vec::new();
    visit(&mut |name, v| {
        let raw = match v {
            FieldValue::Int(i) => Raw::Int(i),
            FieldValue::Text(t) => Raw::Text(t.to_vec()),
        };
        out.push((name.to_owned(), raw));
    });
    out
}

/// The interpreter's values for the fields the generated types carry: constants, repeated
/// fields and constant bits are checked by both decoders but are not values of the message.
pub fn interp_values(p: &Protocol, f: &Frame) -> Values {
    let m = p.message(f.message);
    f.values
        .iter()
        .filter(|v| match interp::leaf_field(m, &v.name) {
            Some((field, bits)) => {
                field.constant.is_none()
                    && field.equals.is_none()
                    && bits.map_or(true, |b| b.constant.is_none())
            }
            None => false,
        })
        .map(|v| (v.name.clone(), v.raw.clone()))
        .collect()
}

/// The generated decoders of one protocol, behind one interface so the checks are written once.
pub trait Generated {
    const FILE: &'static str;
    /// `Request::decode`.
    fn request(frame: &[u8]) -> Result<Decoded, busspec_protocols::DecodeError>;
    /// `Response::decode`, or `Response::decode_reply` to the request `reply_to` (a whole
    /// request frame, decoded first).
    fn response(
        frame: &[u8],
        reply_to: Option<&[u8]>,
    ) -> Result<Decoded, busspec_protocols::DecodeError>;
}

#[macro_export]
macro_rules! generated {
    ($t:ident, $proto:ident, $file:literal) => {
        pub struct $t;
        impl $crate::common::Generated for $t {
            const FILE: &'static str = $file;
            fn request(
                frame: &[u8],
            ) -> Result<$crate::common::Decoded, busspec_protocols::DecodeError> {
                use busspec_protocols::$proto::{Request, MAX_FRAME_LEN};
                let d = Request::decode(frame)?;
                let mut buf = [0xA5u8; MAX_FRAME_LEN];
                let n = d
                    .message
                    .encode(d.address, &mut buf)
                    .expect("a decoded message encodes");
                Ok($crate::common::Decoded {
                    name: d.message.name(),
                    address: d.address,
                    values: $crate::common::visit_values(|f| d.message.visit(f)),
                    reencoded: buf[..n].to_vec(),
                })
            }
            fn response(
                frame: &[u8],
                reply_to: Option<&[u8]>,
            ) -> Result<$crate::common::Decoded, busspec_protocols::DecodeError> {
                use busspec_protocols::$proto::{Request, Response, MAX_FRAME_LEN};
                let d = match reply_to {
                    None => Response::decode(frame)?,
                    Some(r) => {
                        let r = Request::decode(r)
                            .expect("reply_to is a request frame")
                            .message;
                        let d = Response::decode_reply(frame, &r)?;
                        assert!(
                            d.message.answers(&r),
                            "decode_reply gave a response that does not answer"
                        );
                        d
                    }
                };
                let mut buf = [0xA5u8; MAX_FRAME_LEN];
                let n = d
                    .message
                    .encode(d.address, &mut buf)
                    .expect("a decoded message encodes");
                Ok($crate::common::Decoded {
                    name: d.message.name(),
                    address: d.address,
                    values: $crate::common::visit_values(|f| d.message.visit(f)),
                    reencoded: buf[..n].to_vec(),
                })
            }
        }
    };
}

/// Writes the checksum of `frame`'s bytes before it into its last bytes.
pub fn fix_checksum(p: &Protocol, frame: &mut [u8]) {
    let c = &p.framing.checksum;
    let n = c.len();
    if frame.len() < n {
        return;
    }
    let at = frame.len() - n;
    let v = checksum::compute(&c.algorithm, &frame[..at]);
    interp::write_uint(v, &mut frame[at..], c.byte_order);
}

/// A frame shaped like message `m` (start byte, code, right length, valid checksum), with a
/// random address (usually a device's) and random payload.
pub fn random_frame(p: &Protocol, m: &Message, rng: &mut fastrand::Rng) -> Vec<u8> {
    let len = p.frame_len(m);
    let o = interp::offsets(p, m.code.len(), m.payload_len);
    let mut f: Vec<u8> = (0..len).map(|_| rng.u8(..)).collect();
    if let (Some(at), Some(s)) = (o.start, p.framing.start) {
        f[at] = s;
    }
    f[o.code..o.code + m.code.len()].copy_from_slice(&m.code);
    if rng.u8(..) < 224 {
        f[o.address] = rng.u8(p.framing.address.min..=p.framing.address.max);
    }
    // Small payload values are where constants, enums and specials live.
    for b in &mut f[o.payload..o.payload + m.payload_len] {
        if rng.bool() {
            *b = rng.u8(..4);
        }
    }
    fix_checksum(p, &mut f);
    f
}

/// Every message of both directions.
pub fn all_messages(p: &Protocol) -> Vec<MessageRef> {
    let mut out = Vec::new();
    for d in [Direction::Request, Direction::Response] {
        for index in 0..p.messages(d).len() {
            out.push(MessageRef {
                direction: d,
                index,
            });
        }
    }
    out
}

/// A random input for the decoders: pure noise, a mutated example, or a well-formed frame of a
/// random message with random contents.
pub fn random_input(p: &Protocol, rng: &mut fastrand::Rng) -> Vec<u8> {
    let max = p
        .max_frame_len(Direction::Request)
        .max(p.max_frame_len(Direction::Response));
    match rng.u8(..8) {
        0 => (0..rng.usize(..=max + 2)).map(|_| rng.u8(..)).collect(),
        1..=3 => {
            let e = &p.examples[rng.usize(..p.examples.len())];
            let mut f = e.wire.clone();
            for _ in 0..rng.usize(1..=3) {
                let i = rng.usize(..f.len());
                f[i] = rng.u8(..);
            }
            match rng.u8(..8) {
                0 => {
                    f.pop();
                }
                1 => f.push(rng.u8(..)),
                _ => {}
            }
            if rng.u8(..4) != 0 {
                fix_checksum(p, &mut f);
            }
            f
        }
        _ => {
            let all = all_messages(p);
            let r = all[rng.usize(..all.len())];
            random_frame(p, p.message(r), rng)
        }
    }
}

/// A request frame for command `index`: its first example, if it has one.
pub fn request_example(p: &Protocol, index: usize) -> Option<&[u8]> {
    p.examples
        .iter()
        .find(|e| e.message.direction == Direction::Request && e.message.index == index)
        .map(|e| e.wire.as_slice())
}
