//! Payload truncation (`framing.truncation: trailing_zeros`, MAVLink v2): a sender strips the
//! payload's trailing zero bytes, keeping at least one, and a receiver pads a shorter payload
//! with zeros up to its message's length. The frame as the IR lays it out and the bytes as
//! they travel, each turned into the other.
//!
//! The IR lays every frame out with its message's whole payload. Decoding turns a frame as it
//! travels into it ([`canonical`]): a frame whose start bytes are the framing's, whose length
//! field agrees with its length, whose code names a message and whose payload holds 1 byte up
//! to one less than that message's is checked against its checksum as it travelled (a
//! mismatch is refused there, at its offset on the wire), then padded with zeros to the whole
//! payload, its length field and checksum rewritten; every other frame is decoded as it came
//! (a payload of none or of more bytes than the message's is refused as before). Errors of
//! the padded frame's decode keep their offsets: the bytes before the padding sit where they
//! travelled, and a field in the padding is named where the whole payload puts it.
//! Encoding lays the frame out so, then [`travel`] strips the payload's trailing zeros (at
//! least one byte stays), rewrites the length field and reseals the checksum over the bytes as
//! they travel. A frame with trailing zeros that were not stripped decodes all the same (a
//! MAVLink receiver accepts both), and encodes back stripped.
//!
//! Validated: a length field (once) that counts the payload, every code of one length (at
//! least one byte), every message of one code of one payload length, fixed-length messages
//! only; no escaping, preamble, transform, end bytes, second start, long length form, forms or
//! constant whole frames. The generated code's `rt::Truncation` does the same, written
//! separately.

use crate::interp::{read_uint, reseal, write_uint, DecodeError};
use crate::ir::{Direction, Protocol};

/// Where the parts sit in every frame of a truncating framing: `(length field at, its width,
/// code at, code length, payload at)`; `None` where the framing does not truncate.
fn parts(p: &Protocol) -> Option<(usize, usize, usize, usize, usize)> {
    p.framing.truncation?;
    let code_len = p.framing.request.code_lengths.first().copied().unwrap_or(0);
    let head = p.framing.head(Direction::Request, code_len);
    let l = p.framing.length.as_ref()?;
    Some((head.length?, l.width, head.code, code_len, head.payload))
}

/// The whole payload's length of the messages of `code` (validated: one for every message
/// of a code), `None` where no message has it.
pub fn full_payload(p: &Protocol, code: &[u8]) -> Option<usize> {
    [Direction::Request, Direction::Response]
        .iter()
        .flat_map(|&d| p.framed(d))
        .find(|m| m.code == code)
        .map(|m| m.payload_len)
}

/// `wire` padded to its message's whole payload where it travelled truncated (see the module
/// docs); `None` where it is to be decoded as it came. A truncated frame whose checksum
/// fails is refused.
pub fn canonical(p: &Protocol, wire: &[u8]) -> Result<Option<Vec<u8>>, DecodeError> {
    let Some((length_at, width, code_at, code_len, payload_at)) = parts(p) else {
        return Ok(None);
    };
    let head = p.framing.head(Direction::Request, code_len);
    let trailer = p.framing.trailer_len();
    if wire.len() < payload_at + trailer {
        return Ok(None);
    }
    if let Some(at) = head.start {
        let starts = |d: Direction| {
            let sync = p.framing.sync_of(d);
            wire.get(at..at + sync.len()) == Some(sync)
        };
        if !starts(Direction::Request) && !starts(Direction::Response) {
            return Ok(None);
        }
    }
    let Some(rule) = p.framing.length_rule(Direction::Request) else {
        return Ok(None);
    };
    let found = read_uint(&wire[length_at..length_at + width], p.byte_order) as i64;
    if rule.value(wire.len()) != Some(found) {
        return Ok(None);
    }
    let Some(full) = full_payload(p, &wire[code_at..code_at + code_len]) else {
        return Ok(None);
    };
    let n = wire.len() - payload_at - trailer;
    if n == 0 || n >= full {
        return Ok(None);
    }
    crate::interp::check_checksum(p, crate::ir::Direction::Request, None, wire)?;
    let mut out = Vec::with_capacity(payload_at + full + trailer);
    out.extend_from_slice(&wire[..payload_at + n]);
    out.resize(payload_at + full + trailer, 0);
    reseal_at_length(p, &mut out);
    Ok(Some(out))
}

/// `frame`'s length field set to what its length gives (the one length field a truncating
/// framing has), then its checksum.
fn reseal_at_length(p: &Protocol, frame: &mut [u8]) {
    if let Some(rule) = p.framing.length_rule(Direction::Request) {
        if let Some(v) = rule.value(frame.len()) {
            write_uint(
                v as u64,
                &mut frame[rule.at..rule.at + rule.width],
                p.byte_order,
            );
        }
    }
    reseal(p, frame);
}

/// A frame the IR laid out (its whole payload), as it travels: the payload's trailing zeros
/// stripped (at least one byte kept), the length field and checksum rewritten. `frame`
/// itself where the framing does not truncate or nothing is stripped.
pub fn travel(p: &Protocol, mut frame: Vec<u8>) -> Vec<u8> {
    let Some((_, _, _, _, payload_at)) = parts(p) else {
        return frame;
    };
    let trailer = p.framing.trailer_len();
    let Some(end) = frame.len().checked_sub(trailer).filter(|&e| e > payload_at) else {
        return frame;
    };
    let kept = frame[payload_at..end]
        .iter()
        .rposition(|&b| b != 0)
        .map_or(1, |i| i + 1);
    if payload_at + kept == end {
        return frame;
    }
    frame.drain(payload_at + kept..end);
    reseal_at_length(p, &mut frame);
    frame
}

/// The frame lengths a message of `payload` bytes travels in, beside `full` its laid-out
/// length: from one payload byte to the whole (none for an empty payload but itself).
pub fn lens(full: usize, payload: usize) -> std::ops::RangeInclusive<usize> {
    let least = full - payload.saturating_sub(1);
    least..=full
}
