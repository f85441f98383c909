//! A length field whose width the start byte chooses (`framing.length.long`: VESC's short
//! `02 len …` and long `03 lenH lenL …`): the frame as the IR lays it out and the bytes as they
//! travel, each turned into the other.
//!
//! The IR lays every frame out in the long form's width with the framing's own (short) start
//! byte: a layout that never travels, but holds every length. Decoding turns a frame as it
//! travels into it ([`canonical`]): a short frame gets the long field's high bytes (zeros), a
//! long one the short start byte; a long frame whose length the short form holds is refused
//! ([`DecodeError::NeedlessLong`]), so what strict decoding accepts encodes back byte for byte.
//! Encoding lays the frame out so, then [`travel`] sends it short where its length fits the
//! short width and long otherwise. The checksum covers neither the start byte nor the length
//! field (validated), so it is the same in both forms and in the layout. Errors found in the
//! layout are located on the bytes as they travelled ([`Canonical::locate`]). The generated
//! code's `rt::LongLength` does the same, written separately.

use std::borrow::Cow;

use crate::interp::{read_uint, DecodeError};
use crate::ir::{LongForm, Protocol};
use crate::model::ByteOrder;

/// A frame in the IR's layout, with what [`Canonical::locate`] needs.
#[derive(Debug, Clone)]
pub struct Canonical<'w> {
    /// The frame as the IR lays it out.
    pub frame: Cow<'w, [u8]>,
    /// Set where the frame travelled short: the long form and how many bytes were inserted.
    pub(crate) short: Option<LongForm>,
    /// Set where the frame travelled in a short form (`framing.forms`): where the parts it
    /// drops sit in the layout, and how many bytes they are.
    pub(crate) dropped: Option<(usize, usize)>,
}

impl Canonical<'_> {
    /// An error the laid-out frame's decode gave, located on the frame as it travelled.
    pub fn locate(&self, e: DecodeError) -> DecodeError {
        if let Some((at, n)) = self.dropped {
            return crate::forms::locate(at, n, e);
        }
        match self.short {
            Some(l) => locate(&l, e),
            None => e,
        }
    }
}

/// Where the high bytes of the long length field sit in the layout: before the short field's
/// byte(s) in big-endian order, after them in little-endian.
fn inserted_at(l: &LongForm, order: ByteOrder) -> usize {
    match order {
        ByteOrder::Big => l.length_at,
        ByteOrder::Little => l.length_at + l.short_width,
    }
}

/// `wire` in the IR's layout: itself where the framing has no long form, or the frame is too
/// short or starts with neither start byte (decoding then says what is wrong with it).
pub fn canonical<'w>(p: &Protocol, wire: &'w [u8]) -> Result<Canonical<'w>, DecodeError> {
    // A truncated payload (`framing.truncation`) padded to its message's.
    if let Some(out) = crate::truncate::canonical(p, wire)? {
        return Ok(Canonical {
            frame: Cow::Owned(out),
            short: None,
            dropped: None,
        });
    }
    if let Some(f) = &p.framing.form {
        return crate::forms::canonical(p, f, wire);
    }
    let borrowed = Canonical {
        frame: Cow::Borrowed(wire),
        short: None,
        dropped: None,
    };
    let Some(l) = p.framing.long else {
        return Ok(borrowed);
    };
    match wire.get(l.start_at) {
        Some(&b) if b == l.start => {
            if let Some(bytes) = wire.get(l.length_at..l.length_at + l.width) {
                let length = read_uint(bytes, p.byte_order) as i64;
                if length <= l.short_max() {
                    return Err(DecodeError::NeedlessLong {
                        offset: l.length_at,
                        length,
                        most: l.short_max(),
                    });
                }
            }
            let mut out = wire.to_vec();
            out[l.start_at] = l.short_start;
            Ok(Canonical {
                frame: Cow::Owned(out),
                short: None,
                dropped: None,
            })
        }
        Some(&b) if b == l.short_start && wire.len() >= l.length_at + l.short_width => {
            let at = inserted_at(&l, p.byte_order);
            let mut out = Vec::with_capacity(wire.len() + l.extra());
            out.extend_from_slice(&wire[..at]);
            out.resize(at + l.extra(), 0);
            out.extend_from_slice(&wire[at..]);
            Ok(Canonical {
                frame: Cow::Owned(out),
                short: Some(l),
                dropped: None,
            })
        }
        _ => Ok(borrowed),
    }
}

/// A frame the IR laid out (`frame`), as it travels: short where its length field's value
/// fits the short width, else long. `frame` itself without a long form.
pub fn travel(p: &Protocol, mut frame: Vec<u8>) -> Vec<u8> {
    if p.framing.truncation.is_some() {
        return crate::truncate::travel(p, frame);
    }
    if let Some(f) = &p.framing.form {
        return crate::forms::travel(f, frame);
    }
    let Some(l) = p.framing.long else {
        return frame;
    };
    let Some(bytes) = frame.get(l.length_at..l.length_at + l.width) else {
        return frame;
    };
    if read_uint(bytes, p.byte_order) as i64 > l.short_max() {
        frame[l.start_at] = l.start;
        return frame;
    }
    let at = inserted_at(&l, p.byte_order);
    frame.drain(at..at + l.extra());
    frame
}

/// The frame lengths as they travel of a frame at the head of `buf` (a stream's buffer),
/// from its start byte and length field: `(wire length, laid-out length)`, or `None` where
/// the head byte is neither start byte, and `Some(None)` while its length field is not
/// buffered yet. `laid_out` gives the frame's length in the IR's layout from the length
/// field's value (per direction: the caller's).
pub fn wire_len(p: &Protocol, buf: &[u8]) -> Option<Option<(i64, usize)>> {
    if let Some(f) = &p.framing.form {
        return crate::forms::wire_len(p, f, buf);
    }
    let l = p.framing.long?;
    let (width, extra) = match *buf.get(l.start_at)? {
        b if b == l.start => (l.width, 0),
        b if b == l.short_start => (l.short_width, l.extra()),
        _ => return None,
    };
    Some(
        buf.get(l.length_at..l.length_at + width)
            .map(|bytes| (read_uint(bytes, p.byte_order) as i64, extra)),
    )
}

/// An error found in the IR's layout of `wire` (a frame as it travelled) after its decode
/// (a reply's check against its request), located on `wire`.
pub fn locate_on(p: &Protocol, wire: &[u8], e: DecodeError) -> DecodeError {
    match canonical(p, wire) {
        Ok(c) => c.locate(e),
        Err(_) => e,
    }
}

/// An offset in the layout of a frame that travelled short, on the wire.
fn offset(l: &LongForm, o: usize) -> usize {
    if o >= l.length_at + l.width {
        o - l.extra()
    } else if o >= l.length_at {
        l.length_at
    } else {
        o
    }
}

/// An error of a frame that travelled short, found in its layout: offsets and frame lengths
/// as on the wire.
fn locate(l: &LongForm, e: DecodeError) -> DecodeError {
    relocate(e, |len| len.saturating_sub(l.extra()), |at| offset(l, at))
}

/// An error with its frame lengths mapped by `n` and its offsets by `o`.
pub(crate) fn relocate(
    e: DecodeError,
    n: impl Fn(usize) -> usize,
    o: impl Fn(usize) -> usize,
) -> DecodeError {
    use DecodeError as E;
    let mut e = e;
    match &mut e {
        E::Truncated { needed, found } => {
            *needed = n(*needed);
            *found = n(*found);
        }
        E::TooLong { max, found } => {
            *max = n(*max);
            *found = n(*found);
        }
        E::WrongLength {
            expected, found, ..
        } => {
            for x in expected.iter_mut() {
                *x = n(*x);
            }
            *found = n(*found);
        }
        E::BadStart { offset, .. }
        | E::BadEnd { offset, .. }
        | E::ChecksumMismatch { offset, .. }
        | E::NeedsRequest { offset, .. }
        | E::UnknownCode { offset, .. }
        | E::ConstantMismatch { offset, .. }
        | E::NotBcd { offset, .. }
        | E::NotEqual { offset, .. }
        | E::OutOfRange { offset, .. }
        | E::BadAddress { offset, .. }
        | E::LengthMismatch { offset, .. }
        | E::BadCount { offset, .. }
        | E::BadWidth { offset, .. }
        | E::NoTerminator { offset, .. }
        | E::ByteCount { offset, .. }
        | E::NotFollowing { offset, .. }
        | E::BadEscape { offset, .. }
        | E::NeedlessLong { offset, .. }
        | E::EndInside { offset, .. } => *offset = o(*offset),
        E::Ambiguous { .. } | E::BroadcastNotAccepted { .. } | E::NotAnAnswer { .. } => {}
    }
    e
}

/// Sets the length field of `frame` (as it travels, either form; direction `d`) to what its
/// length gives, in the width its start byte chooses: what test helpers take to make a frame
/// whose length field agrees. Nothing where the framing has no long form or no length rule,
/// or the frame is too short.
pub fn fix_length(p: &Protocol, d: crate::ir::Direction, frame: &mut [u8]) {
    let (Some(l), Some(rule)) = (p.framing.long, p.framing.length_rule(d)) else {
        return;
    };
    let (width, extra) = match frame.get(l.start_at) {
        Some(&b) if b == l.short_start => (l.short_width, l.extra()),
        _ => (l.width, 0),
    };
    let Some(v) = rule.value(frame.len() + extra) else {
        return;
    };
    let Some(field) = frame.get_mut(l.length_at..l.length_at + width) else {
        return;
    };
    crate::interp::write_uint(v as u64, field, p.byte_order);
}
