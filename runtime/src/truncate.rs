//! Payload truncation (`framing.truncation: trailing_zeros`, MAVLink v2), as generated code
//! takes it: the interpreter's `busspec_model::truncate`, written separately and held to it.
//!
//! A sender strips the payload's trailing zero bytes (keeping at least one); a receiver pads a
//! shorter payload with zeros up to its message's length. [`Truncation::lay_out`] pads a frame
//! as it travels before decoding: a frame whose start bytes are the framing's, whose length
//! field agrees with its length, whose code names a message and whose payload holds 1 byte up
//! to one less than that message's is checked against its checksum as it travelled (a
//! mismatch is refused there), then padded with zeros, its length field and checksum
//! rewritten; every other frame is decoded as it came. The padded frame's errors keep their
//! offsets. [`Truncation::travel`] strips an encoded frame's trailing zeros (one byte kept),
//! rewriting its length field and checksum; [`Truncation::frame_lens`] frames a stream by the
//! length field, within the lengths the code's message travels in.

use crate::codec::{seal, uint, Frame};
use crate::stream::{VarLen, VarLens};
use crate::DecodeError;

/// A protocol's payload truncation (`framing.truncation`), emitted as a constant by generated
/// code. Validated: a length field that counts the payload, one code length, fixed-length
/// messages, no end bytes, escaping, preamble, transform or other forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Truncation {
    /// Where the start bytes sit, if the frame has them, and each direction's.
    pub start_at: Option<usize>,
    pub sync: &'static [u8],
    pub response_sync: &'static [u8],
    /// Where the length field sits, its width, least significant byte first.
    pub length_at: usize,
    pub width: usize,
    pub le: bool,
    /// The length field's value less the frame's length.
    pub k: i64,
    /// Where the code sits and its length.
    pub code_at: usize,
    pub code_len: usize,
    /// Where the payload begins.
    pub payload_at: usize,
    /// Each code (as [`crate::codec::code`] reads it), the whole payload's length of its
    /// messages, and the directions that have it (bit 0 requests, bit 1 responses).
    pub payloads: &'static [(u32, usize, u8)],
}

impl Truncation {
    /// The whole payload's length of the messages of `code`, and their directions.
    #[inline]
    pub fn full(self, code: u32) -> Option<(usize, u8)> {
        self.payloads
            .iter()
            .find(|(c, _, _)| *c == code)
            .map(|&(_, n, d)| (n, d))
    }

    fn starts(self, frame: &[u8], sync: &[u8]) -> bool {
        match self.start_at {
            Some(at) => frame.get(at..at + sync.len()) == Some(sync),
            None => true,
        }
    }

    /// The length field's value.
    fn length(self, frame: &[u8]) -> Option<i64> {
        frame
            .get(self.length_at..self.length_at + self.width)
            .map(|b| uint(b, self.le) as i64)
    }

    fn write_length(self, buf: &mut [u8], len: usize) {
        let v = (len as i64 + self.k) as u64;
        let field = &mut buf[self.length_at..self.length_at + self.width];
        let n = field.len();
        for (i, b) in field.iter_mut().enumerate() {
            let shift = if self.le { i } else { n - 1 - i };
            *b = (v >> (8 * shift)) as u8;
        }
    }

    /// `frame` padded to its message's whole payload (into `buf`, which holds the longest
    /// frame) where it travelled truncated, else itself; a truncated frame whose checksum
    /// (`sum` of the bytes before it, as [`Frame`] places it) fails is refused.
    pub fn lay_out<'b>(
        self,
        frame: &'b [u8],
        buf: &'b mut [u8],
        f: &Frame,
        sum: impl Fn(&[u8]) -> u32,
    ) -> Result<&'b [u8], DecodeError> {
        let trailer = f.checksum_len;
        let len = frame.len();
        if len < self.payload_at + trailer {
            return Ok(frame);
        }
        if !self.starts(frame, self.sync) && !self.starts(frame, self.response_sync) {
            return Ok(frame);
        }
        if self.length(frame) != Some(len as i64 + self.k) {
            return Ok(frame);
        }
        let code = crate::codec::code(frame, self.code_at, self.code_len);
        let Some((full, _)) = self.full(code) else {
            return Ok(frame);
        };
        let n = len - self.payload_at - trailer;
        if n == 0 || n >= full {
            return Ok(frame);
        }
        let at = len - trailer;
        let found = uint(&frame[at..], !f.checksum_be) as u32;
        let expected = sum(&frame[..at]);
        if found != expected {
            return Err(DecodeError::ChecksumMismatch {
                offset: at,
                expected,
                found,
                width: f.checksum_len as u8,
            });
        }
        let laid = self.payload_at + full + trailer;
        // A frame of the other direction's, longer padded than this direction's longest:
        // refused as the interpreter refuses the padded frame, before anything else.
        let max = buf.len();
        let Some(out) = buf.get_mut(..laid) else {
            return Err(DecodeError::TooLong { max, found: laid });
        };
        out[..at].copy_from_slice(&frame[..at]);
        out[at..].fill(0);
        self.write_length(out, laid);
        seal(out, laid, sum, f.checksum_len, f.checksum_be);
        Ok(out)
    }

    /// The encoded frame of `len` bytes in `buf` (its whole payload), as it travels: the
    /// payload's trailing zeros stripped (one byte kept), its length field and checksum
    /// rewritten. Its new length.
    pub fn travel(
        self,
        buf: &mut [u8],
        len: usize,
        f: &Frame,
        sum: impl Fn(&[u8]) -> u32,
    ) -> usize {
        let trailer = f.checksum_len;
        let Some(end) = len.checked_sub(trailer).filter(|&e| e > self.payload_at) else {
            return len;
        };
        let Some(payload) = buf.get(self.payload_at..end) else {
            return len;
        };
        let kept = payload.iter().rposition(|&b| b != 0).map_or(1, |i| i + 1);
        if self.payload_at + kept == end {
            return len;
        }
        let new = len - (end - self.payload_at - kept);
        self.write_length(buf, new);
        seal(buf, new, sum, f.checksum_len, f.checksum_be);
        new
    }

    /// The frame lengths, as they travel, of a frame at the head of a stream's buffer: as its
    /// length field says, where that is one the code's message travels in (one payload byte
    /// to the whole), for each direction with the code whose start bytes the head has.
    pub fn frame_lens(self, head: &[u8], trailer: usize) -> VarLens {
        let agree = |sync: &[u8]| match self.start_at {
            Some(at) => sync
                .iter()
                .enumerate()
                .all(|(i, s)| head.get(at + i).map_or(true, |b| b == s)),
            None => true,
        };
        let (rq, rs) = (agree(self.sync), agree(self.response_sync));
        if !rq && !rs {
            return VarLens::NONE;
        }
        let Some(v) = self.length(head) else {
            return VarLens {
                requests: VarLen::NEED_MORE,
                responses: VarLen::NEED_MORE,
            };
        };
        let Some(code) = head.get(self.code_at..self.code_at + self.code_len) else {
            return VarLens {
                requests: VarLen::NEED_MORE,
                responses: VarLen::NEED_MORE,
            };
        };
        let Some((payload, dirs)) = self.full(uint(code, false) as u32) else {
            return VarLens::NONE;
        };
        let full = self.payload_at + payload + trailer;
        let least = full - payload.saturating_sub(1);
        let len = match usize::try_from(v - self.k) {
            Ok(n) if n >= least && n <= full => VarLen::len(n),
            _ => VarLen::NONE,
        };
        VarLens {
            requests: if rq && dirs & 1 != 0 {
                len
            } else {
                VarLen::NONE
            },
            responses: if rs && dirs & 2 != 0 {
                len
            } else {
                VarLen::NONE
            },
        }
    }
}
