//! Messages with optional fields (`present:` in the spec): a field on the wire only where an
//! earlier field says so, by one of its bits or by its value. Optional fields end the payload
//! (validated: at most [`MAX_OPTIONAL`], no list beside them, a length field in the framing),
//! each right after the fields before it that are on the wire.
//!
//! [`Optionals`] describes a message's optional fields. Decode takes a frame apart
//! ([`Optionals::split`]): the fields present from their conditions, the frame's length
//! checked against them, and the frame copied into the layout where every optional field is
//! present ([`Present::frame`]), so generated code reads every field at a fixed offset from an
//! array, as for any message. Encode writes that layout and packs it into the frame
//! ([`Optionals::pack`]), leaving out the fields that are absent. The rules are the
//! interpreter's (`interp::shape`, `interp::encode`).

use crate::repeated::CountField;
use crate::{DecodeError, EncodeError, MessageDesc};

/// What [`Optionals::naming`] falls back on for a table with no descriptor (generated tables
/// always have one for each length).
static NAMELESS: MessageDesc = MessageDesc::new("", 0, 0, &[]);

/// The most optional fields a message has (the validator's `MAX_OPTIONAL`).
pub const MAX_OPTIONAL: usize = 4;

/// When an optional field is on the wire: a condition on the raw value of an earlier field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// That bit (0 = least significant) is set.
    Bit(u32),
    /// The field holds this value.
    Equals(u64),
}

impl When {
    /// Whether the condition holds for raw value `raw`.
    #[inline]
    pub const fn holds(self, raw: u64) -> bool {
        match self {
            When::Bit(b) => b < 64 && raw >> b & 1 == 1,
            When::Equals(v) => raw == v,
        }
    }
}

/// One optional field: its name, its width and its condition (the field it reads, where it
/// sits in the frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptionalAt {
    pub name: &'static str,
    /// Its width, bytes.
    pub width: usize,
    /// The field its condition reads (an unsigned integer always on the wire, before it).
    pub on: CountField,
    pub when: When,
}

/// The optional fields of a message, in wire order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Optionals {
    /// The message as a wrong length names it, once for each of [`Self::lengths`]: with that
    /// one length (the one the fields present make).
    pub by_length: &'static [MessageDesc],
    /// The frame's length with no optional field present.
    pub base: usize,
    /// Where the first optional field sits in the frame (each sits after those before it that
    /// are present).
    pub at: usize,
    pub fields: &'static [OptionalAt],
    /// Every length a frame can have (the fields present make it), sorted: a wrong length is
    /// refused naming the one the fields present make.
    pub lengths: &'static [usize],
}

/// A frame of a message with [`Optionals`], taken apart.
#[derive(Debug, Clone, Copy)]
pub struct Present<const MAX: usize> {
    /// The frame with every optional field where it sits when all are present (absent ones
    /// 0), its trailer after them: every field at a fixed offset.
    pub frame: [u8; MAX],
    /// Bit `k`: optional field `k` is present.
    pub on: u8,
    /// Where each optional field sits in the frame (where it would, if absent).
    pub offsets: [usize; MAX_OPTIONAL],
}

impl<const MAX: usize> Present<MAX> {
    /// Whether optional field `k` is present.
    #[inline]
    pub const fn has(&self, k: usize) -> bool {
        k < 8 && self.on >> k & 1 == 1
    }

    /// Where optional field `k` sits in the frame, as errors name it.
    #[inline]
    pub fn at(&self, k: usize) -> usize {
        self.offsets.get(k).copied().unwrap_or(0)
    }
}

impl Optionals {
    /// Which optional fields `frame` (at least [`Self::base`] long) holds, bit `k` for field `k`,
    /// and the length they make.
    #[inline]
    fn present_in(&self, frame: &[u8]) -> (u8, usize) {
        let mut on = 0u8;
        let mut len = self.base;
        for (k, f) in self.fields.iter().enumerate().take(MAX_OPTIONAL) {
            if f.when.holds(f.on.read(frame).unwrap_or(0)) {
                on |= 1 << k;
                len += f.width;
            }
        }
        (on, len)
    }

    /// The message's descriptor naming length `len` of [`Self::lengths`] (the first where
    /// none is `len`, which no frame meets: `len` is one the fields present make).
    fn naming(&self, len: usize) -> &'static MessageDesc {
        let by_length: &'static [MessageDesc] = self.by_length;
        let i = self.lengths.iter().position(|&l| l == len).unwrap_or(0);
        match by_length.get(i).or(by_length.first()) {
            Some(d) => d,
            None => &NAMELESS,
        }
    }

    /// `frame` (a whole frame of the message) taken apart: shorter than a frame without
    /// optional fields, it is truncated; otherwise its length must be what the fields present
    /// make ([`DecodeError::WrongLength`], as the interpreter refuses it). `MAX` is the length
    /// of a frame with every optional field.
    pub fn split<const MAX: usize>(&self, frame: &[u8]) -> Result<Present<MAX>, DecodeError> {
        if frame.len() < self.base {
            return Err(DecodeError::Truncated {
                needed: self.base,
                found: frame.len(),
            });
        }
        let (on, len) = self.present_in(frame);
        if frame.len() != len {
            return Err(DecodeError::WrongLength {
                message: self.naming(len),
                found: frame.len(),
                less: 0,
            });
        }
        let mut out = Present {
            frame: [0u8; MAX],
            on,
            offsets: [0; MAX_OPTIONAL],
        };
        copy(frame, 0, &mut out.frame, 0, self.at);
        let (mut src, mut dst) = (self.at, self.at);
        for (k, f) in self.fields.iter().enumerate().take(MAX_OPTIONAL) {
            out.offsets[k] = src;
            if on >> k & 1 == 1 {
                copy(frame, src, &mut out.frame, dst, f.width);
                src += f.width;
            }
            dst += f.width;
        }
        // The trailer (checksum, end bytes) after the last optional field.
        copy(
            frame,
            src,
            &mut out.frame,
            dst,
            frame.len().saturating_sub(src),
        );
        Ok(out)
    }

    /// The frame of `full` (every optional field where it sits when all are present, as
    /// [`Present::frame`] holds them) with only the fields `present` says, taken from `buf`;
    /// its trailer is left for the encoder to write.
    pub fn pack<'b>(
        &self,
        full: &[u8],
        present: &[bool],
        buf: &'b mut [u8],
    ) -> Result<&'b mut [u8], EncodeError> {
        let on = |k: usize| present.get(k).copied().unwrap_or(false);
        let len = self.frame_len(present);
        let out = crate::codec::frame_mut_len(buf, len, &[])?;
        copy(full, 0, out, 0, self.at);
        let (mut src, mut dst) = (self.at, self.at);
        for (k, f) in self.fields.iter().enumerate() {
            if on(k) {
                copy(full, src, out, dst, f.width);
                dst += f.width;
            }
            src += f.width;
        }
        copy(full, src, out, dst, len.saturating_sub(dst));
        Ok(out)
    }

    /// The length of a frame whose optional fields are present where `present` says.
    pub const fn frame_len(&self, present: &[bool]) -> usize {
        let mut len = self.base;
        let mut k = 0;
        while k < self.fields.len() && k < present.len() {
            if present[k] {
                len += self.fields[k].width;
            }
            k += 1;
        }
        len
    }
}

/// Encode's check of optional field `field`: a value is given (`given`) exactly where its
/// condition holds (`on`), else [`EncodeError::Optional`], as the interpreter refuses it.
#[inline]
pub fn presence(
    field: &'static str,
    on: bool,
    given: bool,
    condition: &'static str,
) -> Result<(), EncodeError> {
    if on == given {
        return Ok(());
    }
    Err(EncodeError::Optional {
        field,
        condition,
        given,
    })
}

/// `len` bytes from `from[src..]` to `to[dst..]`, as many as both hold.
fn copy(from: &[u8], src: usize, to: &mut [u8], dst: usize, len: usize) {
    if let (Some(a), Some(b)) = (from.get(src..), to.get_mut(dst..)) {
        let n = len.min(a.len()).min(b.len());
        b[..n].copy_from_slice(&a[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `optional_sensor`'s reading: status, temperature, then humidity (bit 0) and pressure
    /// (bit 1); start, address, length, code before the payload, a sum-8 after it.
    const READING: Optionals = Optionals {
        by_length: &[
            MessageDesc::new("reading", 0x81, 1, &[8]),
            MessageDesc::new("reading", 0x81, 1, &[10]),
            MessageDesc::new("reading", 0x81, 1, &[12]),
            MessageDesc::new("reading", 0x81, 1, &[14]),
        ],
        base: 8,
        at: 7,
        fields: &[
            OptionalAt {
                name: "humidity",
                width: 2,
                on: CountField {
                    name: "status",
                    at: 4,
                    width: 1,
                    le: false,
                },
                when: When::Bit(0),
            },
            OptionalAt {
                name: "pressure",
                width: 4,
                on: CountField {
                    name: "status",
                    at: 4,
                    width: 1,
                    le: false,
                },
                when: When::Bit(1),
            },
        ],
        lengths: &[8, 10, 12, 14],
    };

    #[test]
    fn a_frame_is_laid_out_as_if_every_field_were_present_and_back() {
        // Pressure alone: it sits where humidity would.
        let frame = [0xA5, 1, 7, 0x81, 2, 0, 1, 0xAA, 0xBB, 0xCC, 0xDD, 0x99];
        let s = READING.split::<14>(&frame).unwrap();
        assert_eq!(s.on, 0b10);
        assert!(!s.has(0) && s.has(1));
        assert_eq!((s.at(0), s.at(1)), (7, 7));
        assert_eq!(
            s.frame,
            [0xA5, 1, 7, 0x81, 2, 0, 1, 0, 0, 0xAA, 0xBB, 0xCC, 0xDD, 0x99]
        );
        let mut buf = [0u8; 20];
        let out = READING.pack(&s.frame, &[false, true], &mut buf).unwrap();
        assert_eq!(out, &frame[..]);
        assert_eq!(READING.frame_len(&[false, true]), 12);
    }

    #[test]
    fn a_length_the_fields_present_do_not_make_is_refused() {
        let frame = [0xA5, 1, 5, 0x81, 2, 0, 1, 0xAA, 0xBB, 0x99];
        match READING.split::<14>(&frame) {
            Err(DecodeError::WrongLength {
                message:
                    MessageDesc {
                        name: "reading",
                        lengths: &[12],
                        ..
                    },
                found: 10,
                less: 0,
            }) => {}
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            READING.split::<14>(&frame[..6]),
            Err(DecodeError::Truncated {
                needed: 8,
                found: 6
            })
        ));
        assert!(matches!(
            presence("humidity", false, true, "bit 0 of `status` is set"),
            Err(EncodeError::Optional { given: true, .. })
        ));
        let mut small = [0u8; 9];
        assert!(READING.pack(&[0; 14], &[true, false], &mut small).is_err());
    }
}
