//! The generated crate held against the interpreter, its independent oracle: the values each
//! engine decodes (compared field by field, raw) and [`agree`], which decodes one frame with both
//! and asserts they say the same. Used by the fuzz targets and by the workspace's tests.

use busspec_model::interp::{self, Frame, Raw};
use busspec_model::ir::{Direction, Protocol as Spec};
use busspec_protocols::{DecodeError, FieldValue, FrameBuffer, Message, Protocol, ResponseMessage};

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
    pub fn new(
        name: &'static str,
        address: u8,
        values: Values,
        mut buf: impl AsMut<[u8]>,
        encode: impl FnOnce(&mut [u8]) -> Result<usize, busspec_protocols::EncodeError>,
    ) -> Decoded {
        let buf = buf.as_mut();
        let n = encode(buf).unwrap_or_else(|e| panic!("decoded {name} does not encode: {e}"));
        Decoded {
            name,
            address,
            values,
            reencoded: buf[..n].to_vec(),
        }
    }

    /// Describes a message of protocol `P` the generated code decoded, re-encoded into a
    /// buffer of `P`'s longest frame filled with [`pattern_buffer`]'s pattern.
    pub fn of<P: Protocol, M: Message>(d: &busspec_protocols::Decoded<M>) -> Decoded {
        Decoded::new(
            d.message.name(),
            d.address,
            visit_values(|f| d.message.visit(f)),
            pattern_buffer::<P>(),
            |b| d.message.encode(d.address, b),
        )
    }
}

/// A buffer of `P`'s longest frame, every byte 0xA5: a byte an encoder forgets to write shows.
pub fn pattern_buffer<P: Protocol>() -> P::Buffer {
    let mut buf = P::Buffer::ZERO;
    buf.as_mut().fill(0xA5);
    buf
}

/// Collects a generated message's fields through its `visit`.
pub fn visit_values(visit: impl FnOnce(&mut dyn FnMut(&'static str, FieldValue<'_>))) -> Values {
    let mut out = Vec::new();
    visit(&mut |name, v| {
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

/// The interpreter's values for the fields the generated types carry: constants, repeated
/// fields, values following another field, counts of a list and constant bits are checked by
/// both decoders but are not values of the message.
pub fn interp_values(p: &Spec, f: &Frame) -> Values {
    let m = p.message(f.message);
    f.values
        .iter()
        .filter(|v| match interp::leaf_field(m, &v.name) {
            Some((field, bits)) => {
                let i = m.fields.iter().position(|f| f.name == field.name);
                !i.is_some_and(|i| m.is_derived(i)) && bits.map_or(true, |b| b.constant.is_none())
            }
            None => false,
        })
        .map(|v| (v.name.to_string(), v.raw.clone()))
        .collect()
}

/// `frame` through `P`'s generated request decoder.
pub fn request<P: Protocol>(frame: &[u8]) -> Result<Decoded, DecodeError> {
    let d = P::decode_request(frame)?;
    Ok(Decoded::of::<P, _>(&d))
}

/// `frame` through `P`'s generated response decoder: alone, or as the reply to the request
/// `reply_to` (a whole request frame, decoded first).
pub fn response<P: Protocol>(
    frame: &[u8],
    reply_to: Option<&[u8]>,
) -> Result<Decoded, DecodeError> {
    let d = match reply_to {
        None => P::decode_response(frame)?,
        Some(w) => {
            let r = P::decode_request(w)
                .expect("reply_to is a request frame")
                .message;
            // With the request's bytes, which a reply's checksum may take in.
            let d = P::decode_reply_to(frame, w)?;
            assert!(
                d.message.answers(&r),
                "decode_reply gave a response that does not answer"
            );
            return Ok(Decoded::new(
                d.message.name(),
                d.address,
                visit_values(|f| d.message.visit(f)),
                pattern_buffer::<P>(),
                |b| P::encode_reply(&d.message, d.address, w, b),
            ));
        }
    };
    Ok(Decoded::of::<P, _>(&d))
}

/// A request frame for command `index`: its first example, if it has one.
pub fn request_example(p: &Spec, index: usize) -> Option<&[u8]> {
    p.examples
        .iter()
        .find(|e| e.message.direction == Direction::Request && e.message.index == index)
        .map(|e| e.wire.as_slice())
}

/// Decodes `frame` with both engines in `direction` (as the reply to command `reply_to` if
/// given: its first example request is the request, `decode_reply` in both) and asserts they
/// agree: both accept or both
/// reject, and where they accept, the same message, address and value for every field, and the
/// generated encoder writes the frame back byte for byte. Returns whether it was accepted.
pub fn agree<P: Protocol>(
    p: &Spec,
    frame: &[u8],
    direction: Direction,
    reply_to: Option<usize>,
) -> bool {
    let reply_frame = reply_to.and_then(|c| request_example(p, c));
    let reply_to = reply_frame.and(reply_to);
    // As the reply to a whole request, the interpreter checks what follows from its values
    // too (a Modbus echo, a byte count of 2 × quantity), as `decode_reply` does.
    let asked = reply_frame.and_then(|r| interp::decode(p, Some(Direction::Request), None, r).ok());
    let oracle = match (&asked, direction) {
        (Some(q), Direction::Response) => interp::decode_reply_with(p, q, reply_frame, frame),
        _ => interp::decode(p, Some(direction), reply_to, frame),
    };
    let generated = match direction {
        Direction::Request => request::<P>(frame),
        Direction::Response => response::<P>(frame, reply_frame),
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
            P::NAME,
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
        (Err(Some(e)), Err(g)) => {
            // Both refuse it, for the same reason and in the same words.
            assert_eq!(g.to_string(), e.to_string(), "{}", ctx());
            false
        }
        (Err(None), Err(_)) => false,
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
