//! A length field whose width the start byte chooses (`framing.length.long`: VESC's short
//! `02 len …` and long `03 lenH lenL …`), as generated code takes it: the interpreter's
//! `busspec_model::long`, written separately and held to it.
//!
//! The generated code lays every frame out in the long form's width with the short form's
//! start byte (a layout that never travels, but holds every length): [`LongLength::lay_out`]
//! turns a frame as it travels into it before decoding, [`LongLength::locate`] places the
//! decode's errors back on the frame as it travelled, [`LongLength::travel`] turns an encoded
//! frame into the form it travels in (short where its length fits the short width), and
//! [`LongLength::frame_lens`] frames a stream by the form its head byte starts.

use crate::stream::{VarLen, VarLens};
use crate::DecodeError;

/// A length field's long form (`framing.length.long`), emitted as a constant by generated
/// code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LongLength {
    /// The long form's start byte.
    pub start: u8,
    /// The short form's (the framing's own) start byte.
    pub short_start: u8,
    /// Where the start byte sits.
    pub start_at: usize,
    /// Where the length field sits (in both forms).
    pub length_at: usize,
    /// The short form's length width.
    pub short_width: usize,
    /// The long form's length width.
    pub width: usize,
    /// Least significant byte first.
    pub le: bool,
    /// Per direction (requests, responses), where the length field grows with the frame: the
    /// laid-out frame's length is the field's value less `k`, from `lo` to `hi` bytes.
    pub rules: [Option<(i64, usize, usize)>; 2],
}

impl LongLength {
    /// How many bytes longer the long form's length field is.
    #[inline(always)]
    pub const fn extra(self) -> usize {
        self.width - self.short_width
    }

    /// The largest length the short form holds.
    #[inline(always)]
    pub const fn short_max(self) -> i64 {
        (1i64 << (8 * self.short_width)) - 1
    }

    /// Where the long field's high bytes sit in the laid-out frame.
    #[inline(always)]
    const fn inserted_at(self) -> usize {
        if self.le {
            self.length_at + self.short_width
        } else {
            self.length_at
        }
    }

    fn read(self, bytes: &[u8]) -> i64 {
        let mut v: u64 = 0;
        for (i, &b) in bytes.iter().enumerate() {
            if self.le {
                v |= u64::from(b) << (8 * i);
            } else {
                v = v << 8 | u64::from(b);
            }
        }
        v as i64
    }

    /// `frame` laid out (into `buf`, which holds the longest frame laid out, where it must be
    /// copied) and whether it travelled short: itself where it is too short or starts with
    /// neither start byte (decoding then says what is wrong with it). A long frame whose
    /// length the short form holds is refused ([`DecodeError::NeedlessLong`]); a short one
    /// too long to lay out is refused as too long, as it travelled.
    pub fn lay_out<'b>(
        self,
        frame: &'b [u8],
        buf: &'b mut [u8],
    ) -> Result<(&'b [u8], bool), DecodeError> {
        match frame.get(self.start_at) {
            Some(&b) if b == self.start => {
                if let Some(bytes) = frame.get(self.length_at..self.length_at + self.width) {
                    let length = self.read(bytes);
                    if length <= self.short_max() {
                        return Err(DecodeError::NeedlessLong {
                            offset: self.length_at,
                            length,
                            most: self.short_max(),
                        });
                    }
                }
                let Some(out) = buf.get_mut(..frame.len()) else {
                    return Ok((frame, false));
                };
                out.copy_from_slice(frame);
                out[self.start_at] = self.short_start;
                Ok((out, false))
            }
            Some(&b)
                if b == self.short_start && frame.len() >= self.length_at + self.short_width =>
            {
                let (n, extra, at) = (frame.len(), self.extra(), self.inserted_at());
                if n + extra > buf.len() {
                    return Err(DecodeError::TooLong {
                        max: buf.len() - extra,
                        found: n,
                    });
                }
                buf[..at].copy_from_slice(&frame[..at]);
                buf[at..at + extra].fill(0);
                buf[at + extra..n + extra].copy_from_slice(&frame[at..]);
                Ok((&buf[..n + extra], true))
            }
            _ => Ok((frame, false)),
        }
    }

    /// An error the laid-out frame's decode gave, on the frame as it travelled (`short`: as
    /// [`Self::lay_out`] said): offsets after the length field and frame lengths less the
    /// bytes the short field lacks.
    pub fn locate(self, e: DecodeError, short: bool) -> DecodeError {
        if !short {
            return e;
        }
        let extra = self.extra();
        let o = |at: usize| {
            if at >= self.length_at + self.width {
                at - extra
            } else if at >= self.length_at {
                self.length_at
            } else {
                at
            }
        };
        on_shorter(e, extra, o)
    }

    /// The laid-out frame of `len` bytes in `buf`, as it travels: short (the long field's
    /// high bytes taken out) where its length fits the short width, else with the long
    /// form's start byte. Its new length.
    pub fn travel(self, buf: &mut [u8], len: usize) -> usize {
        let Some(bytes) = buf.get(self.length_at..self.length_at + self.width) else {
            return len;
        };
        if self.read(bytes) > self.short_max() {
            if let Some(b) = buf.get_mut(self.start_at) {
                *b = self.start;
            }
            return len;
        }
        let (at, extra) = (self.inserted_at(), self.extra());
        if len < at + extra || len > buf.len() {
            return len;
        }
        buf.copy_within(at + extra..len, at);
        len - extra
    }

    /// The frame lengths, as they travel, of a frame at the head of a stream's buffer: by the
    /// length field of the form its start byte opens, per direction (`max`: the longest
    /// frame laid out).
    pub fn frame_lens(self, head: &[u8]) -> VarLens {
        let (width, extra) = match head.get(self.start_at) {
            Some(&b) if b == self.start => (self.width, 0),
            Some(&b) if b == self.short_start => (self.short_width, self.extra()),
            _ => return VarLens::NONE,
        };
        let Some(bytes) = head.get(self.length_at..self.length_at + width) else {
            return VarLens {
                requests: VarLen::NEED_MORE,
                responses: VarLen::NEED_MORE,
            };
        };
        let v = self.read(bytes);
        let of = |rule: Option<(i64, usize, usize)>| match rule {
            Some((k, lo, hi)) => match usize::try_from(v - k) {
                Ok(n) if n >= lo && n <= hi => VarLen::len(n - extra),
                _ => VarLen::NONE,
            },
            None => VarLen::NONE,
        };
        VarLens {
            requests: of(self.rules[0]),
            responses: of(self.rules[1]),
        }
    }
}

/// `e`, an error of a laid-out frame `extra` bytes longer than the frame as it travelled, on
/// that frame: every offset through `o`, frame lengths `extra` shorter. The long length form
/// ([`LongLength::locate`]) and the short form (`ShortForm::locate`) both place errors so.
pub(crate) fn on_shorter(e: DecodeError, extra: usize, o: impl Fn(usize) -> usize) -> DecodeError {
    let n = |len: usize| len.saturating_sub(extra);
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
        E::WrongLength { found, less, .. } => {
            *found = n(*found);
            *less += extra;
        }
        E::BadStart { offset, .. }
        | E::BadEnd { offset, .. }
        | E::ChecksumMismatch { offset, .. }
        | E::NeedsRequest { offset, .. }
        | E::UnknownCommand { offset, .. }
        | E::UnknownResponse { offset, .. }
        | E::InvalidValue { offset, .. }
        | E::NotBcd { offset, .. }
        | E::NotEqual { offset, .. }
        | E::NotFollowing { offset, .. }
        | E::ByteCount { offset, .. }
        | E::LengthMismatch { offset, .. }
        | E::OutOfRange { offset, .. }
        | E::BadAddress { offset, .. }
        | E::BadCount { offset, .. }
        | E::BadEscape { offset, .. }
        | E::NeedlessLong { offset, .. }
        | E::BadWidth { offset, .. }
        | E::NoTerminator { offset, .. }
        | E::EndInside { offset, .. } => *offset = o(*offset),
        E::Ambiguous { .. } | E::NotAReply { .. } | E::BroadcastNotAccepted { .. } => {}
    }
    e
}
