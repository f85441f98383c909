//! Messages whose fields do not all keep a fixed offset: several repeated fields, or fields
//! after one. [`Lists`] holds each repeated field as a [`RepeatAt`] at its offset with every
//! earlier list empty; a frame is taken apart ([`Lists::split`]) into its bytes but the lists'
//! elements (every other field then at a fixed offset, so generated code reads them from an
//! array as for any message) and each list where this frame places it. The counting is the
//! interpreter's (`interp::shape`): each list in wire order, its count field read where the
//! lists before it put it; the last list takes exactly what the frame's length leaves.

use crate::repeated::{CountBy, CountField, RepeatAt};
use crate::{CountRule, DecodeError, EncodeError, FieldDesc};

/// The field [`NONE`] names.
static NO_FIELD: FieldDesc = FieldDesc::new("", "");

/// Every repeated field of a message, in wire order; `base` is the frame's length with every
/// list empty (each list's `base` is too).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lists {
    pub base: usize,
    pub lists: &'static [RepeatAt],
}

/// A frame of a message with [`Lists`], taken apart.
#[derive(Debug, Clone, Copy)]
pub struct Split<'f, const BASE: usize, const K: usize> {
    /// The frame's bytes but the lists' elements: every other field at its offset with every
    /// list empty.
    pub frame: [u8; BASE],
    whole: &'f [u8],
    /// Each list as this frame places it: its offset (and its count field's) moved by the
    /// lists before it, so errors name the frame's offsets.
    pub lists: [RepeatAt; K],
    /// Each list's number of elements.
    pub n: [usize; K],
    bytes: [usize; K],
}

impl<'f, const BASE: usize, const K: usize> Split<'f, BASE, K> {
    /// The bytes of list `k`'s elements.
    #[inline]
    pub fn elements(&self, k: usize) -> &'f [u8] {
        match (self.lists.get(k), self.bytes.get(k)) {
            // Text up to a terminator: its characters, not the terminator after them.
            (Some(r), Some(&b)) => {
                let b = match r.count {
                    CountBy::Until(_) => b.saturating_sub(1),
                    _ => b,
                };
                self.whole.get(r.at..r.at + b).unwrap_or(&[])
            }
            _ => &[],
        }
    }

    /// The bytes the first `j` lists take: how much further than its offset a field after
    /// them sits.
    #[inline]
    pub fn shift(&self, j: usize) -> usize {
        self.bytes.iter().take(j).sum()
    }
}

/// A list with no elements and no count, where a list is missing.
const NONE: RepeatAt = RepeatAt {
    field: &NO_FIELD,
    base: 0,
    at: 0,
    width: 1,
    le: false,
    signed: false,
    count: CountBy::End,
    min: 0,
    max: 0,
};

impl Lists {
    /// List `k`, at its offset with every earlier list empty.
    #[inline]
    fn list(&self, k: usize) -> RepeatAt {
        self.lists.get(k).copied().unwrap_or(NONE)
    }

    /// The bytes of the lists (among the first `bytes.len()`) that sit before offset `at`.
    fn before(&self, at: usize, bytes: &[usize]) -> usize {
        bytes
            .iter()
            .enumerate()
            .filter(|&(j, _)| self.list(j).at <= at)
            .map(|(_, b)| b)
            .sum()
    }

    /// A count field moved by the lists (of `bytes`) before it.
    fn moved(&self, c: CountField, bytes: &[usize]) -> CountField {
        CountField {
            at: c.at + self.before(c.at, bytes),
            ..c
        }
    }

    /// `frame` (a whole frame of the message) taken apart: each list counted and checked in
    /// wire order (its element size, the bytes the frame has left, its bounds), the other
    /// bytes copied into [`Split::frame`].
    pub fn split<'f, const BASE: usize, const K: usize>(
        &self,
        frame: &'f [u8],
    ) -> Result<Split<'f, BASE, K>, DecodeError> {
        let mut rest = crate::repeated::beyond(frame, self.base)?;
        let mut lists = [NONE; K];
        let mut n = [0usize; K];
        let mut bytes = [0usize; K];
        let mut shift = 0usize;
        for k in 0..K {
            let mut r = self.list(k);
            r.at += shift;
            r.count = match r.count {
                // Records whose width a field gives are a message's only list (validated):
                // never in `Lists`.
                CountBy::End | CountBy::EndSized(_) => CountBy::End,
                // A list end bytes delimit is the only list (validated), maybe before fields.
                CountBy::Delimited(end) => CountBy::Delimited(end),
                CountBy::Until(t) => CountBy::Until(t),
                CountBy::Fixed(v) => CountBy::Fixed(v),
                CountBy::Elements(c) => CountBy::Elements(self.moved(c, &bytes[..k])),
                CountBy::Bytes(c) => CountBy::Bytes(self.moved(c, &bytes[..k])),
            };
            let last = k + 1 == K;
            let bits = r.width == 0;
            let w = r.width.max(1);
            let per_byte = |b: usize| if bits { b.saturating_mul(8) } else { b / w };
            let bad = |found: i64, expected: CountRule| DecodeError::BadCount {
                field: r.field,
                offset: r.at,
                found,
                expected,
            };
            if let Some(e) = r.end_inside(frame) {
                return Err(e);
            }
            let count = match r.count {
                CountBy::Until(t) => r.until(frame, t, rest, last)?,
                CountBy::End | CountBy::EndSized(_) | CountBy::Delimited(_) => {
                    if !bits && rest % w != 0 {
                        return Err(bad(rest as i64, CountRule::Whole(r.width)));
                    }
                    per_byte(rest)
                }
                CountBy::Elements(c) => {
                    let v = c.read(frame).unwrap_or(0);
                    let held = usize::try_from(v).unwrap_or(usize::MAX);
                    let b = r.bytes_of(held);
                    if last && b != rest {
                        return Err(bad(v as i64, CountRule::ByLength(rest / w)));
                    }
                    if b > rest {
                        return Err(bad(v as i64, CountRule::AtMost(rest / w)));
                    }
                    held
                }
                // As a count field saying that many would.
                CountBy::Fixed(held) => {
                    let b = r.bytes_of(held);
                    if last && b != rest {
                        return Err(bad(held as i64, CountRule::ByLength(rest / w)));
                    }
                    if b > rest {
                        return Err(bad(held as i64, CountRule::AtMost(rest / w)));
                    }
                    held
                }
                CountBy::Bytes(c) => {
                    let v = c.read(frame).unwrap_or(0);
                    if last {
                        if !(bits || rest % w == 0) || usize::try_from(v) != Ok(rest) {
                            return Err(DecodeError::ByteCount {
                                list: r.field,
                                field: c.name,
                                offset: c.at,
                                expected: rest as i64,
                                found: v as i64,
                            });
                        }
                        per_byte(rest)
                    } else {
                        let b = usize::try_from(v).unwrap_or(usize::MAX);
                        if !bits && b % w != 0 {
                            return Err(bad(v as i64, CountRule::Whole(r.width)));
                        }
                        if b > rest {
                            return Err(bad(per_byte(b) as i64, CountRule::AtMost(per_byte(rest))));
                        }
                        per_byte(b)
                    }
                }
            };
            let (lo, hi) = if bits {
                (r.min.div_ceil(8) * 8, r.max.div_ceil(8) * 8)
            } else {
                (r.min, r.max)
            };
            if count < lo || count > hi {
                return Err(bad(count as i64, CountRule::Between(r.min, r.max)));
            }
            let b = r.bytes_of(count).min(rest);
            rest -= b;
            shift += b;
            lists[k] = r;
            n[k] = count;
            bytes[k] = b;
        }
        // Every byte but the lists' elements, in order.
        let mut compact = [0u8; BASE];
        let (mut src, mut dst) = (0usize, 0usize);
        for (k, &b) in bytes.iter().enumerate() {
            let len = self.list(k).at.saturating_sub(dst);
            copy(frame, src, &mut compact, dst, len);
            src += len + b;
            dst += len;
        }
        copy(frame, src, &mut compact, dst, BASE.saturating_sub(dst));
        Ok(Split {
            frame: compact,
            whole: frame,
            lists,
            n,
            bytes,
        })
    }

    /// The length of the frame that starts `head`, once every count field has arrived (each
    /// read where the lists before it put it): `None` for a list to the end (the frame's length
    /// comes from a length field) or while a count field is missing; for a list end bytes
    /// delimit, its [`RepeatAt::frame_len`]; `Some(0)`, which no frame
    /// has, where a list's count could not hold `min..=max` whole elements.
    pub fn frame_len(&self, head: &[u8]) -> Option<usize> {
        // The validator allows at most 64 lists in a message (`MAX_LISTS`).
        let mut bytes = [0usize; 64];
        let mut total = self.base;
        for (k, r) in self.lists.iter().enumerate().take(64) {
            let (c, by_bytes) = match r.count {
                // The only list (validated): up to the first end bytes from its first byte.
                CountBy::Delimited(_) => return r.frame_len(head),
                // Without a length field, text up to a terminator is the only list
                // (validated): up to its first terminator.
                CountBy::Until(_) if self.lists.len() == 1 => return r.frame_len(head),
                CountBy::End | CountBy::EndSized(_) | CountBy::Until(_) => return None,
                CountBy::Fixed(v) => {
                    bytes[k] = r.bytes_of(v);
                    total += bytes[k];
                    continue;
                }
                CountBy::Elements(c) => (c, false),
                CountBy::Bytes(c) => (c, true),
            };
            let c = self.moved(c, &bytes[..k]);
            let v = usize::try_from(c.read(head)?).unwrap_or(usize::MAX);
            let extra = if by_bytes { v } else { r.bytes_of(v) };
            let fits = extra >= r.bytes_of(r.min)
                && extra <= r.bytes_of(r.max)
                && (r.width == 0 || extra % r.width == 0);
            if !fits {
                return Some(0);
            }
            bytes[k] = extra;
            total += extra;
        }
        Some(total)
    }

    /// The frame of `compact` (every byte but the lists' elements, as [`Split::frame`] holds
    /// them) with lists of `bytes` bytes each, taken from `buf`: the lists' bytes are left for
    /// the encoder to write.
    pub fn expand<'b>(
        &self,
        compact: &[u8],
        bytes: &[usize],
        buf: &'b mut [u8],
    ) -> Result<&'b mut [u8], EncodeError> {
        let len = self.base + bytes.iter().sum::<usize>();
        let out = crate::codec::frame_mut_len(buf, len, &[])?;
        let (mut src, mut dst) = (0usize, 0usize);
        for (k, &b) in bytes.iter().enumerate() {
            let seg = self.list(k).at.saturating_sub(src);
            copy(compact, src, out, dst, seg);
            src += seg;
            dst += seg + b;
        }
        copy(compact, src, out, dst, compact.len().saturating_sub(src));
        Ok(out)
    }

    /// Where list `k`'s elements start in a frame whose lists take `bytes` bytes each.
    #[inline]
    pub fn at(&self, k: usize, bytes: &[usize]) -> usize {
        self.list(k).at + bytes.iter().take(k).sum::<usize>()
    }
}

/// `len` bytes from `from[src..]` to `to[dst..]`, as many as both hold.
fn copy(from: &[u8], src: usize, to: &mut [u8], dst: usize, len: usize) {
    if let (Some(a), Some(b)) = (from.get(src..), to.get_mut(dst..)) {
        let n = len.min(a.len()).min(b.len());
        b[..n].copy_from_slice(&a[..n]);
    }
}
