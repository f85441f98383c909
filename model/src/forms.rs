//! A short form of the frame (`framing.forms`: M-Bus's short frame `10 C A CS 16` beside its
//! long frame `68 L L 68 C A CI data CS 16`): the frame as the IR lays it out and the bytes as
//! they travel, each turned into the other.
//!
//! The IR lays every frame out in the framing's own (long) layout: a short frame is that
//! layout without a run of parts (the length field's copies and the second start byte), opened
//! by a start byte of its own, and carries only frames with an empty payload. Decoding turns a
//! short frame into the layout ([`canonical`]: its own start byte replaced, the dropped parts'
//! bytes of an empty payload put back); a short frame of another length is refused as
//! truncated or too long, and a long frame whose length field says an empty payload is refused
//! ([`DecodeError::NeedlessLong`]), so what strict decoding accepts encodes back byte for
//! byte. Encoding lays the frame out so, then [`travel`] sends it short where its payload is
//! empty. The checksum covers none of the dropped parts nor the start byte (validated), so it
//! is the same in both forms. Errors found in the layout are located on the bytes as they
//! travelled ([`locate`]). The generated code's `rt::ShortForm` does the same, written
//! separately.

use std::borrow::Cow;

use crate::interp::{read_uint, DecodeError};
use crate::ir::{Protocol, ShortForm};
use crate::long::Canonical;

/// `wire` in the IR's layout: itself where it starts with neither start byte (decoding then
/// says what is wrong with it) or is a long frame.
pub fn canonical<'w>(
    p: &Protocol,
    f: &ShortForm,
    wire: &'w [u8],
) -> Result<Canonical<'w>, DecodeError> {
    match wire.get(f.start_at) {
        Some(&b) if b == f.long_start => {
            if let Some(bytes) = wire.get(f.length_at..f.length_at + f.width) {
                let length = read_uint(bytes, p.byte_order) as i64;
                if length == f.most {
                    return Err(DecodeError::NeedlessLong {
                        offset: f.length_at,
                        length,
                        most: f.most,
                    });
                }
            }
            Ok(Canonical::borrowed(wire))
        }
        Some(&b) if b == f.start => {
            let short = f.short_len();
            if wire.len() < short {
                return Err(DecodeError::Truncated {
                    needed: short,
                    found: wire.len(),
                });
            }
            if wire.len() > short {
                return Err(DecodeError::TooLong {
                    max: short,
                    found: wire.len(),
                });
            }
            let mut out = Vec::with_capacity(f.laid_len);
            out.extend_from_slice(&wire[..f.at]);
            out.extend_from_slice(&f.fill);
            out.extend_from_slice(&wire[f.at..]);
            out[f.start_at] = f.long_start;
            Ok(Canonical::dropped(out, f.at, f.extra()))
        }
        _ => Ok(Canonical::borrowed(wire)),
    }
}

/// A frame the IR laid out, as it travels: short where its payload is empty (the layout's
/// length with an empty payload), else itself.
pub fn travel(f: &ShortForm, mut frame: Vec<u8>) -> Vec<u8> {
    if frame.len() != f.laid_len || frame.get(f.start_at) != Some(&f.long_start) {
        return frame;
    }
    frame.drain(f.at..f.at + f.extra());
    frame[f.start_at] = f.start;
    frame
}

/// [`crate::long::wire_len`] of a framing with a short form: a short frame's head gives the
/// length value of an empty payload, with the bytes the short form lacks; a long frame's its
/// length field.
pub fn wire_len(p: &Protocol, f: &ShortForm, buf: &[u8]) -> Option<Option<(i64, usize)>> {
    match *buf.get(f.start_at)? {
        b if b == f.start => Some(Some((f.most, f.extra()))),
        b if b == f.long_start => Some(
            buf.get(f.length_at..f.length_at + f.width)
                .map(|bytes| (read_uint(bytes, p.byte_order) as i64, 0)),
        ),
        _ => None,
    }
}

/// An error of a frame that travelled short (the layout's `n` bytes from `at` dropped), found
/// in its layout: offsets and frame lengths as on the wire.
pub fn locate(at: usize, n: usize, e: DecodeError) -> DecodeError {
    crate::long::relocate(
        e,
        |len| len.saturating_sub(n),
        |o| {
            if o >= at + n {
                o - n
            } else if o >= at {
                at
            } else {
                o
            }
        },
    )
}

/// Whether `frame` (as it travels) is a short frame.
pub fn is_short(p: &Protocol, frame: &[u8]) -> bool {
    p.framing
        .form
        .as_ref()
        .is_some_and(|f| frame.get(f.start_at) == Some(&f.start))
}

impl<'w> Canonical<'w> {
    fn borrowed(wire: &'w [u8]) -> Self {
        Canonical {
            frame: Cow::Borrowed(wire),
            short: None,
            dropped: None,
        }
    }

    fn dropped(frame: Vec<u8>, at: usize, n: usize) -> Self {
        Canonical {
            frame: Cow::Owned(frame),
            short: None,
            dropped: Some((at, n)),
        }
    }
}
