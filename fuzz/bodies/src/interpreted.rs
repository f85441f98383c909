//! Fuzz bodies for the interpreter on its own, over Modbus RTU and Dynamixel 1.0 (the
//! variable-length language): written before the generator emitted them, kept because they
//! hold the interpreter to its own promises (re-encoding, `answers`, stream offsets) where the
//! generated bodies hold the generated code to the interpreter.
//!
//! * [`decode`]: one byte choosing an example request, then the frame: through
//!   `interp::decode` in each direction and through `decode_reply` to the chosen request. Errors
//!   name a place inside the frame; every accepted frame re-encodes to the same bytes; a reply
//!   `decode_reply` accepts also passes `answers`.
//! * [`stream`]: two bytes (direction `% 3`: both, requests, responses; the seed of the chunk
//!   sizes), then the capture, through the interpreter's stream decoder: every byte in exactly one
//!   event, offsets contiguous, the same events however the bytes are cut, and every frame event
//!   decoding alone, as its message, to the same values.

use busspec_model::interp::{self, DecodeError, Frame};
use busspec_model::ir::{Direction, Protocol};
use busspec_model::stream::{Event, StreamDecoder};
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::modbus::Modbus;

/// Modbus RTU (`spec/modbus.yaml`, as the generated code embeds it), loaded once.
pub fn modbus_spec() -> &'static Protocol {
    crate::spec::<Modbus>()
}

/// Dynamixel 1.0 (`spec/dynamixel.yaml`, as the generated code embeds it), loaded once.
pub fn dynamixel_spec() -> &'static Protocol {
    crate::spec::<Dynamixel>()
}

/// The interpreted specs, by protocol name.
pub fn specs() -> [(&'static str, &'static Protocol); 2] {
    [("modbus", modbus_spec()), ("dynamixel", dynamixel_spec())]
}

/// The example requests of `p`, decoded.
fn requests(p: &Protocol) -> Vec<Frame<'_>> {
    p.examples
        .iter()
        .filter(|e| e.message.direction == Direction::Request)
        .filter_map(|e| interp::decode(p, Some(Direction::Request), None, &e.wire).ok())
        .collect()
}

/// An error must say something, and any place it names must lie inside the frame.
fn check_error(e: &DecodeError, len: usize) {
    assert!(!e.to_string().is_empty());
    let offset = match e {
        DecodeError::ChecksumMismatch { offset, .. }
        | DecodeError::UnknownCode { offset, .. }
        | DecodeError::ConstantMismatch { offset, .. }
        | DecodeError::NotEqual { offset, .. }
        | DecodeError::NotBcd { offset, .. }
        | DecodeError::OutOfRange { offset, .. }
        | DecodeError::BadAddress { offset, .. }
        | DecodeError::LengthMismatch { offset, .. }
        | DecodeError::BadCount { offset, .. }
        | DecodeError::NotFollowing { offset, .. }
        | DecodeError::ByteCount { offset, .. } => Some(*offset),
        _ => None,
    };
    if let Some(o) = offset {
        assert!(o < len.max(1), "{e} (frame of {len} bytes)");
    }
}

/// A frame decode accepted must encode back to exactly its bytes.
fn reencodes(p: &Protocol, f: &Frame, wire: &[u8]) {
    match interp::encode(p, f.message, f.address, &f.values) {
        Ok(again) => assert_eq!(again, wire, "{f:?} re-encodes differently"),
        Err(e) => panic!("{f:?} decoded from {wire:02X?} does not encode: {e}"),
    }
}

/// See the module docs.
pub fn decode(p: &Protocol, data: &[u8]) {
    let Some((&pick, frame)) = data.split_first() else {
        return;
    };
    for d in [None, Some(Direction::Request), Some(Direction::Response)] {
        match interp::decode(p, d, None, frame) {
            Ok(f) => reencodes(p, &f, frame),
            Err(e) => check_error(&e, frame.len()),
        }
    }
    let reqs = requests(p);
    if let Some(req) = reqs.get(usize::from(pick) % reqs.len().max(1)) {
        match interp::decode_reply(p, req, frame) {
            Ok(f) => {
                reencodes(p, &f, frame);
                assert_eq!(interp::answers(p, req, &f), Ok(()));
            }
            Err(e) => check_error(&e, frame.len()),
        }
    }
}

fn events<'p>(
    p: &'p Protocol,
    d: Option<Direction>,
    capture: &[u8],
    sizes: &mut impl FnMut() -> usize,
) -> Vec<Event<'p>> {
    let mut s = StreamDecoder::new(p, d);
    let mut out = Vec::new();
    let mut rest = capture;
    while !rest.is_empty() {
        let n = sizes().clamp(1, rest.len());
        out.extend(s.push(&rest[..n]));
        rest = &rest[n..];
    }
    out.extend(s.flush());
    out
}

/// See the module docs.
pub fn stream(p: &Protocol, data: &[u8]) {
    let [mode, seed, capture @ ..] = data else {
        return;
    };
    let d = match mode % 3 {
        0 => None,
        1 => Some(Direction::Request),
        _ => Some(Direction::Response),
    };
    let whole = events(p, d, capture, &mut || capture.len());
    let mut state = u32::from(*seed) | 1;
    let chunked = events(p, d, capture, &mut || {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        1 + (state >> 16) as usize % 17
    });
    assert_eq!(whole, chunked, "events depend on how the bytes are cut");
    let mut at = 0u64;
    for e in &whole {
        assert_eq!(e.offset(), at, "{e:?}");
        assert!(!e.bytes().is_empty(), "{e:?}");
        at += e.bytes().len() as u64;
        if let Event::Frame { bytes, frame, .. } = e {
            assert_eq!(
                interp::decode_as(p, frame.message, bytes).as_ref(),
                Ok(frame),
                "a stream frame does not decode alone"
            );
        }
    }
    assert_eq!(at, capture.len() as u64, "bytes left unaccounted");
}

/// The bodies for Modbus RTU, as the fuzz targets call them.
pub mod modbus {
    /// [`super::decode`] for Modbus.
    pub fn decode(data: &[u8]) {
        super::decode(super::modbus_spec(), data)
    }
    /// [`super::stream`] for Modbus.
    pub fn stream(data: &[u8]) {
        super::stream(super::modbus_spec(), data)
    }
}

/// The bodies for Dynamixel 1.0, as the fuzz targets call them.
pub mod dynamixel {
    /// [`super::decode`] for Dynamixel.
    pub fn decode(data: &[u8]) {
        super::decode(super::dynamixel_spec(), data)
    }
    /// [`super::stream`] for Dynamixel.
    pub fn stream(data: &[u8]) {
        super::stream(super::dynamixel_spec(), data)
    }
}
