//! A short form of the frame (`framing.forms`: M-Bus's short frame `10 C A CS 16` beside its
//! long frame `68 L L 68 C A CI data CS 16`), as generated code takes it: the interpreter's
//! `busspec_model::forms`, written separately and held to it.
//!
//! The generated code lays every frame out in the framing's own (long) layout: a short frame is
//! that layout without a run of parts (the length field's copies and the second start byte),
//! opened by a start byte of its own, and carries only frames with an empty payload.
//! [`ShortForm::lay_out`] turns a frame as it travels into the layout before decoding (a short
//! frame of another length refused as truncated or too long, a long frame whose length field
//! says an empty payload refused as [`DecodeError::NeedlessLong`]), [`ShortForm::locate`]
//! places the decode's errors back on the frame as it travelled, [`ShortForm::travel`] sends an
//! encoded frame with an empty payload short, and [`ShortForm::frame_lens`] frames a stream by
//! the form its head byte starts.

use crate::stream::{VarLen, VarLens};
use crate::DecodeError;

/// A frame's short form (`framing.forms`), emitted as a constant by generated code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShortForm {
    /// The short form's start byte.
    pub start: u8,
    /// The framing's own (the long form's) start byte.
    pub long_start: u8,
    /// Where the start byte sits.
    pub start_at: usize,
    /// Where the parts the short form drops sit in the layout.
    pub at: usize,
    /// The dropped parts' bytes in a frame with an empty payload, as the layout holds them.
    pub fill: &'static [u8],
    /// Where the length field sits in the layout, and its width.
    pub length_at: usize,
    pub width: usize,
    /// Least significant byte first.
    pub le: bool,
    /// The length field's value in a frame with an empty payload.
    pub most: i64,
    /// A frame with an empty payload, laid out.
    pub laid_len: usize,
    /// Per direction (requests, responses), where the length field grows with the frame: the
    /// laid-out frame's length is the field's value less `k`, from `lo` to `hi` bytes.
    pub rules: [Option<(i64, usize, usize)>; 2],
}

impl ShortForm {
    /// How many bytes the short form lacks.
    #[inline(always)]
    pub const fn extra(self) -> usize {
        self.fill.len()
    }

    /// The short frame's length.
    #[inline(always)]
    pub const fn short_len(self) -> usize {
        self.laid_len - self.fill.len()
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
    /// copied) and whether it travelled short: itself where it starts with neither start byte
    /// or is a long frame.
    pub fn lay_out<'b>(
        self,
        frame: &'b [u8],
        buf: &'b mut [u8],
    ) -> Result<(&'b [u8], bool), DecodeError> {
        match frame.get(self.start_at) {
            Some(&b) if b == self.long_start => {
                if let Some(bytes) = frame.get(self.length_at..self.length_at + self.width) {
                    let length = self.read(bytes);
                    if length == self.most {
                        return Err(DecodeError::NeedlessLong {
                            offset: self.length_at,
                            length,
                            most: self.most,
                        });
                    }
                }
                Ok((frame, false))
            }
            Some(&b) if b == self.start => {
                let (n, short) = (frame.len(), self.short_len());
                if n < short {
                    return Err(DecodeError::Truncated {
                        needed: short,
                        found: n,
                    });
                }
                if n > short {
                    return Err(DecodeError::TooLong {
                        max: short,
                        found: n,
                    });
                }
                let (at, extra) = (self.at, self.extra());
                let Some(out) = buf.get_mut(..self.laid_len) else {
                    return Err(DecodeError::TooLong { max: 0, found: n });
                };
                out[..at].copy_from_slice(&frame[..at]);
                out[at..at + extra].copy_from_slice(self.fill);
                out[at + extra..].copy_from_slice(&frame[at..]);
                out[self.start_at] = self.long_start;
                Ok((out, true))
            }
            _ => Ok((frame, false)),
        }
    }

    /// An error the laid-out frame's decode gave, on the frame as it travelled (`short`: as
    /// [`Self::lay_out`] said): offsets after the dropped parts and frame lengths less the
    /// bytes the short form lacks.
    pub fn locate(self, e: DecodeError, short: bool) -> DecodeError {
        if !short {
            return e;
        }
        let (at, extra) = (self.at, self.extra());
        let o = |o: usize| {
            if o >= at + extra {
                o - extra
            } else if o >= at {
                at
            } else {
                o
            }
        };
        crate::long::on_shorter(e, extra, o)
    }

    /// The laid-out frame of `len` bytes in `buf`, as it travels: short (the dropped parts
    /// taken out, its own start byte) where its payload is empty, else itself. Its new length.
    pub fn travel(self, buf: &mut [u8], len: usize) -> usize {
        if len != self.laid_len
            || len > buf.len()
            || buf.get(self.start_at) != Some(&self.long_start)
        {
            return len;
        }
        let (at, extra) = (self.at, self.extra());
        buf.copy_within(at + extra..len, at);
        buf[self.start_at] = self.start;
        len - extra
    }

    /// The frame lengths, as they travel, of a frame at the head of a stream's buffer: the
    /// short form's one length where its start byte opens it, else by the length field.
    pub fn frame_lens(self, head: &[u8]) -> VarLens {
        let (v, extra) = match head.get(self.start_at) {
            Some(&b) if b == self.start => (self.most, self.extra()),
            Some(&b) if b == self.long_start => {
                let Some(bytes) = head.get(self.length_at..self.length_at + self.width) else {
                    return VarLens {
                        requests: VarLen::NEED_MORE,
                        responses: VarLen::NEED_MORE,
                    };
                };
                (self.read(bytes), 0)
            }
            _ => return VarLens::NONE,
        };
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
