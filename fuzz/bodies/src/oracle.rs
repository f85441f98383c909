//! The generated crate held against the interpreter, its independent oracle: the values each
//! engine decodes (compared field by field, raw) and [`agree`], which decodes one frame with both
//! and asserts they say the same. Used by the fuzz targets and by the workspace's tests.

use busspec_model::interp::{self, DecodeError as InterpError, Frame, Raw};
use busspec_model::ir::{Direction, Protocol};
use busspec_protocols::{DecodeError, FieldValue};

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

impl Decoded {
    /// Describes a decoded message; `encode` writes it back into `buf` (filled with a pattern,
    /// so a byte the encoder forgets to write shows).
    pub fn new<const N: usize>(
        name: &'static str,
        address: u8,
        values: Values,
        mut buf: [u8; N],
        encode: impl FnOnce(&mut [u8]) -> Result<usize, busspec_protocols::EncodeError>,
    ) -> Decoded {
        let n = encode(&mut buf).unwrap_or_else(|e| panic!("decoded {name} does not encode: {e}"));
        Decoded {
            name,
            address,
            values,
            reencoded: buf[..n].to_vec(),
        }
    }
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
    /// The spec file the protocol is generated from.
    const FILE: &'static str;
    /// `Request::decode`.
    fn request(frame: &[u8]) -> Result<Decoded, DecodeError>;
    /// `Response::decode`, or `Response::decode_reply` to the request `reply_to` (a whole
    /// request frame, decoded first).
    fn response(frame: &[u8], reply_to: Option<&[u8]>) -> Result<Decoded, DecodeError>;
}

macro_rules! generated {
    ($t:ident, $proto:ident, $file:literal) => {
        /// The generated decoders of this protocol.
        pub struct $t;

        impl Generated for $t {
            const FILE: &'static str = $file;

            fn request(frame: &[u8]) -> Result<Decoded, DecodeError> {
                use busspec_protocols::$proto::{Request, MAX_FRAME_LEN};
                let d = Request::decode(frame)?;
                Ok(Decoded::new(
                    d.message.name(),
                    d.address,
                    visit_values(|f| d.message.visit(f)),
                    [0xA5u8; MAX_FRAME_LEN],
                    |b| d.message.encode(d.address, b),
                ))
            }

            fn response(frame: &[u8], reply_to: Option<&[u8]>) -> Result<Decoded, DecodeError> {
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
                Ok(Decoded::new(
                    d.message.name(),
                    d.address,
                    visit_values(|f| d.message.visit(f)),
                    [0xA5u8; MAX_FRAME_LEN],
                    |b| d.message.encode(d.address, b),
                ))
            }
        }
    };
}

generated!(Ub2, ub2, "ub2.yaml");
generated!(Sd, sd, "sd.yaml");

/// A request frame for command `index`: its first example, if it has one.
pub fn request_example(p: &Protocol, index: usize) -> Option<&[u8]> {
    p.examples
        .iter()
        .find(|e| e.message.direction == Direction::Request && e.message.index == index)
        .map(|e| e.wire.as_slice())
}

/// Decodes `frame` with both engines in `direction` (as the reply to command `reply_to` if
/// given; its first example request is the request) and asserts they agree: both accept or both
/// reject, and where they accept, the same message, address and value for every field, and the
/// generated encoder writes the frame back byte for byte. Returns whether it was accepted.
pub fn agree<G: Generated>(
    p: &Protocol,
    frame: &[u8],
    direction: Direction,
    reply_to: Option<usize>,
) -> bool {
    let reply_frame = reply_to.and_then(|c| request_example(p, c));
    let reply_to = reply_frame.and(reply_to);
    let oracle = interp::decode(p, Some(direction), reply_to, frame);
    let generated = match direction {
        Direction::Request => G::request(frame),
        Direction::Response => G::response(frame, reply_frame),
    };
    // decode_reply admits only responses the request may get; the interpreter uses the request
    // only to settle ambiguity, so hold it to the same rule here.
    let oracle = match (oracle, reply_to) {
        (Ok(f), Some(c))
            if !p.commands[c]
                .responses
                .iter()
                .any(|(r, _)| *r == f.message.index) =>
        {
            Err(None)
        }
        (Ok(f), _) => Ok(f),
        (Err(e), _) => Err(Some(e)),
    };
    let ctx = || {
        format!(
            "{} {direction:?} {} (reply to {reply_to:?})",
            G::FILE,
            interp::format_hex(frame)
        )
    };
    match (oracle, generated) {
        (Ok(f), Ok(g)) => {
            assert_eq!(g.name, p.message(f.message).name, "{}", ctx());
            assert_eq!(g.address, f.address, "{}", ctx());
            assert_eq!(g.values, interp_values(p, &f), "{}", ctx());
            assert_eq!(g.reencoded, frame, "re-encoding {}", ctx());
            true
        }
        (Err(Some(InterpError::Ambiguous { .. })), Err(g)) => {
            assert!(
                matches!(g, DecodeError::Ambiguous { .. }),
                "the interpreter finds it ambiguous, the generated code says {g}: {}",
                ctx()
            );
            false
        }
        (Err(_), Err(_)) => false,
        (Ok(f), Err(g)) => panic!(
            "only the interpreter accepts ({}), generated: {g}: {}",
            p.message(f.message).name,
            ctx()
        ),
        (Err(e), Ok(g)) => panic!(
            "only the generated code accepts ({}), interpreter: {e:?}: {}",
            g.name,
            ctx()
        ),
    }
}
