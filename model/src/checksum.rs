//! Checksums computed straight from their declared parameters.
//!
//! [`crc()`] is a plain bit-by-bit implementation of the catalogue's parameter model, not the
//! table-driven `crc` crate the generated code uses: validation checks every declared check
//! value with it, and a single decode ([`crate::interp::decode`]) uses it. [`Prepared`] is the
//! `crc` crate's table-driven algorithm for the same parameters, made once for decoding many
//! frames ([`crate::interp::Lookup`], the stream decoder); its tests hold it to [`crc()`].

use std::sync::{Mutex, OnceLock};

use crate::ir::{ChecksumAlgorithm, CrcParams};

/// The ASCII bytes every catalogue check value is computed over.
pub const CHECK_INPUT: &[u8] = b"123456789";

/// The 16-bit sum of `data`, modulo 65536.
fn sum16(data: &[u8]) -> u64 {
    data.iter().fold(0u64, |s, b| (s + u64::from(*b)) & 0xFFFF)
}

/// The 8-bit sum of `data` with each carry out of bit 7 added back in (end-around carry, as
/// ones'-complement addition has it): always 0 to 0xFF.
fn sum8_end_around(data: &[u8]) -> u8 {
    let s = data.iter().fold(0u16, |s, b| {
        let s = s + u16::from(*b);
        (s & 0xFF) + (s >> 8)
    });
    s as u8
}

pub fn compute(algorithm: &ChecksumAlgorithm, data: &[u8]) -> u64 {
    match algorithm {
        ChecksumAlgorithm::Sum8 => u64::from(sum8(data)),
        ChecksumAlgorithm::Sum8OnesComplement => u64::from(!sum8(data)),
        ChecksumAlgorithm::Sum8TwosComplement => u64::from(sum8(data).wrapping_neg()),
        ChecksumAlgorithm::Sum8EndAround => u64::from(0xFF - sum8_end_around(data)),
        ChecksumAlgorithm::Xor8 => u64::from(data.iter().fold(0u8, |s, b| s ^ b)),
        ChecksumAlgorithm::Sum16 => sum16(data),
        ChecksumAlgorithm::Sum16OnesComplement => !sum16(data) & 0xFFFF,
        ChecksumAlgorithm::Sum16TwosComplement => sum16(data).wrapping_neg() & 0xFFFF,
        ChecksumAlgorithm::Fletcher8 => {
            let (a, b) = data.iter().fold((0u8, 0u8), |(a, b), x| {
                let a = a.wrapping_add(*x);
                (a, b.wrapping_add(a))
            });
            u64::from(b) << 8 | u64::from(a)
        }
        ChecksumAlgorithm::Fletcher16 => {
            let (a, b) = data.iter().fold((0u64, 0u64), |(a, b), x| {
                let a = (a + u64::from(*x)) % 255;
                (a, (b + a) % 255)
            });
            b << 8 | a
        }
        ChecksumAlgorithm::Crc(p) => crc(p, data),
        ChecksumAlgorithm::Masked(a, mask) => compute(a, data) & mask,
        ChecksumAlgorithm::Complemented(a, mask) => {
            let v = compute(a, data) & 0xFF;
            v << 8 | (!v & mask & 0xFF)
        }
        ChecksumAlgorithm::None => 0,
    }
}

/// A checksum prepared once for many frames: a CRC as the `crc` crate's table-driven
/// algorithm for its parameters; the 8-bit sums as [`compute`] has them.
#[derive(Clone)]
pub struct Prepared {
    algorithm: ChecksumAlgorithm,
    table: Option<crc::Crc<u64, crc::Table<1>>>,
}

impl std::fmt::Debug for Prepared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Prepared")
            .field("algorithm", &self.algorithm)
            .field("table", &self.table.is_some())
            .finish()
    }
}

impl Prepared {
    pub fn new(algorithm: &ChecksumAlgorithm) -> Prepared {
        let table = match algorithm {
            ChecksumAlgorithm::Crc(p) => Some(crc::Crc::<u64, crc::Table<1>>::new(interned(p))),
            _ => None,
        };
        Prepared {
            algorithm: algorithm.clone(),
            table,
        }
    }

    /// The checksum of `data`, as [`compute`] gives it.
    pub fn compute(&self, data: &[u8]) -> u64 {
        match &self.table {
            Some(table) => table.checksum(data),
            None => compute(&self.algorithm, data),
        }
    }
}

/// The `crc` crate's algorithm for `p`: the crate takes only `'static` ones, so each set of
/// parameters a process meets is made once and kept (a spec has one; a process meets few).
fn interned(p: &CrcParams) -> &'static crc::Algorithm<u64> {
    static MADE: OnceLock<Mutex<Vec<&'static crc::Algorithm<u64>>>> = OnceLock::new();
    let width = p.width.clamp(1, 64);
    let mask = if width == 64 {
        u64::MAX
    } else {
        (1u64 << width) - 1
    };
    let wanted = crc::Algorithm {
        width,
        poly: p.poly & mask,
        init: p.init & mask,
        refin: p.refin,
        refout: p.refout,
        xorout: p.xorout & mask,
        check: crc(p, CHECK_INPUT),
        residue: 0,
    };
    let same = |a: &crc::Algorithm<u64>| {
        (a.width, a.poly, a.init, a.refin, a.refout, a.xorout)
            == (
                wanted.width,
                wanted.poly,
                wanted.init,
                wanted.refin,
                wanted.refout,
                wanted.xorout,
            )
    };
    let mut made = MADE
        .get_or_init(Mutex::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(a) = made.iter().find(|a| same(a)) {
        return a;
    }
    let a: &'static crc::Algorithm<u64> = Box::leak(Box::new(wanted));
    made.push(a);
    a
}

fn sum8(data: &[u8]) -> u8 {
    data.iter().fold(0u8, |s, b| s.wrapping_add(*b))
}

fn reflect(mut v: u64, bits: u8) -> u64 {
    let mut r = 0;
    for _ in 0..bits {
        r = (r << 1) | (v & 1);
        v >>= 1;
    }
    r
}

/// A CRC of any width 1..=64 in the Rocksoft model.
pub fn crc(p: &CrcParams, data: &[u8]) -> u64 {
    let w = u32::from(p.width.clamp(1, 64));
    let mask = if w == 64 { u64::MAX } else { (1u64 << w) - 1 };
    let top = 1u64 << (w - 1);
    let mut reg = p.init & mask;
    for &byte in data {
        let b = if p.refin {
            reflect(u64::from(byte), 8)
        } else {
            u64::from(byte)
        };
        for i in (0..8).rev() {
            let bit = (b >> i) & 1;
            let msb = u64::from(reg & top != 0);
            reg = (reg << 1) & mask;
            if msb ^ bit != 0 {
                reg ^= p.poly & mask;
            }
        }
    }
    if p.refout {
        reg = reflect(reg, w as u8);
    }
    (reg ^ p.xorout) & mask
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(
        width: u8,
        poly: u64,
        init: u64,
        refin: bool,
        refout: bool,
        xorout: u64,
    ) -> CrcParams {
        CrcParams {
            width,
            poly,
            init,
            refin,
            refout,
            xorout,
        }
    }

    #[test]
    fn catalogue_check_values() {
        // CRC-16/CMS, the SD protocol's CRC.
        assert_eq!(
            crc(&params(16, 0x8005, 0xFFFF, false, false, 0), CHECK_INPUT),
            0xAEE7
        );
        // CRC-16/MODBUS (reflected) and CRC-32/ISO-HDLC exercise refin/refout/xorout.
        assert_eq!(
            crc(&params(16, 0x8005, 0xFFFF, true, true, 0), CHECK_INPUT),
            0x4B37
        );
        assert_eq!(
            crc(
                &params(32, 0x04C1_1DB7, 0xFFFF_FFFF, true, true, 0xFFFF_FFFF),
                CHECK_INPUT
            ),
            0xCBF4_3926
        );
        assert_eq!(crc(&params(8, 0x07, 0, false, false, 0), CHECK_INPUT), 0xF4);
    }

    #[test]
    fn eight_bit_variants() {
        // Dynamixel 1.0 manual, instruction packet example: FF FF 01 04 02 2B 01 CC.
        let ping = [0x01, 0x04, 0x02, 0x2B, 0x01];
        assert_eq!(compute(&ChecksumAlgorithm::Sum8OnesComplement, &ping), 0xCC);
        assert_eq!(compute(&ChecksumAlgorithm::Sum8TwosComplement, &ping), 0xCD);
        assert_eq!(compute(&ChecksumAlgorithm::Xor8, &[0x0F, 0xF0, 0x01]), 0xFE);
        assert_eq!(compute(&ChecksumAlgorithm::Xor8, CHECK_INPUT), 0x31);
    }

    #[test]
    fn prepared_agrees_with_bit_by_bit() {
        // Every width, both reflections, odd polynomials and assorted init/xorout, over data
        // of every length up to 40 from a fixed generator.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let data: Vec<u8> = (0..40).map(|_| next() as u8).collect();
        for width in 1..=64u8 {
            for (refin, refout) in [(false, false), (true, true), (true, false), (false, true)] {
                let p = params(width, next() | 1, next(), refin, refout, next());
                let prepared = Prepared::new(&ChecksumAlgorithm::Crc(p));
                for len in 0..=data.len() {
                    assert_eq!(
                        prepared.compute(&data[..len]),
                        crc(&p, &data[..len]),
                        "width {width} refin {refin} refout {refout} len {len}"
                    );
                }
            }
        }
        // The 8-bit sums as `compute` has them.
        let ping = [0x01, 0x04, 0x02, 0x2B, 0x01];
        let prepared = Prepared::new(&ChecksumAlgorithm::Sum8OnesComplement);
        assert_eq!(prepared.compute(&ping), 0xCC);
    }

    #[test]
    fn sixteen_bit_complements() {
        // JBD's battery management protocol: the request DD A5 03 00 FF FD 77 sums its command
        // and length bytes, 03 00; the reply to it sums from its status byte to its data.
        assert_eq!(
            compute(&ChecksumAlgorithm::Sum16TwosComplement, &[0x03, 0x00]),
            0xFFFD
        );
        let reply = [
            0x00, 0x1B, 0x17, 0x00, 0x00, 0x00, 0x02, 0xD0, 0x03, 0xE8, 0x00, 0x00, 0x20, 0x78,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x10, 0x48, 0x03, 0x0F, 0x02, 0x0B, 0x76, 0x0B,
            0x82,
        ];
        assert_eq!(
            compute(&ChecksumAlgorithm::Sum16TwosComplement, &reply),
            0xFBFF
        );
        // Inverted is negated less one; both wrap at 16 bits past 255 bytes of 0xFF.
        let long = [0xFF; 300];
        assert_eq!(compute(&ChecksumAlgorithm::Sum16, &long), 300 * 255 % 65536);
        for data in [&[][..], &[0x03, 0x00], &long] {
            let neg = compute(&ChecksumAlgorithm::Sum16TwosComplement, data);
            let inv = compute(&ChecksumAlgorithm::Sum16OnesComplement, data);
            assert_eq!((neg + 0xFFFF) & 0xFFFF, inv);
            assert_eq!((compute(&ChecksumAlgorithm::Sum16, data) + neg) & 0xFFFF, 0);
        }
    }

    #[test]
    fn sum8_end_around_adds_each_carry_back_in() {
        let a = ChecksumAlgorithm::Sum8EndAround;
        // "123456789": 0x31 + … + 0x36 = 0x135 carries once: 0x35 + 1 = 0x36; then + 0x37,
        // 0x38, 0x39 = 0xDE; inverted 0x21. The plain sum is 0x1DD, inverted 0x22.
        assert_eq!(compute(&a, CHECK_INPUT), 0x21);
        assert_eq!(
            compute(&ChecksumAlgorithm::Sum8OnesComplement, CHECK_INPUT),
            0x22
        );
        // No carry: the same as the plain sum inverted.
        assert_eq!(compute(&a, &[]), 0xFF);
        assert_eq!(compute(&a, &[0x08, 0x01]), 0xF6);
        // FF + 01 = 0x100 carries: 0x00 + 1 = 0x01, inverted 0xFE (the plain sum's: 0xFF).
        assert_eq!(compute(&a, &[0xFF, 0x01]), 0xFE);
        assert_eq!(
            compute(&ChecksumAlgorithm::Sum8OnesComplement, &[0xFF, 0x01]),
            0xFF
        );
        // FF + FF = 0x1FE: 0xFE + 1 = 0xFF, inverted 0; a carry in every step of FF × 3.
        assert_eq!(compute(&a, &[0xFF, 0xFF]), 0x00);
        assert_eq!(compute(&a, &[0xFF, 0xFF, 0xFF]), 0x00);
        assert_eq!(compute(&a, &[0x80, 0x80, 0x80]), 0x7E);
        // ArduPilot's F.Port control frame (RCProtocolTest.cpp): 7E 19 00 … 00 38 FA 7E, its
        // CRC FA over the length byte through the RSSI byte; the plain sum's would be 0x04.
        let control = [
            0x19, 0x00, 0xE7, 0x3B, 0xDF, 0x5A, 0xCE, 0x07, 0x10, 0x75, 0x49, 0x9C, 0x15, 0xE0,
            0x03, 0x1F, 0xF8, 0xC0, 0x07, 0x3E, 0xF0, 0x81, 0x0F, 0x7C, 0x00, 0x38,
        ];
        assert_eq!(compute(&a, &control), 0xFA);
        assert_eq!(
            compute(&ChecksumAlgorithm::Sum8OnesComplement, &control),
            0x04
        );
        // The receiver's rule: the end-around sum of the covered bytes and the CRC is 0xFF.
        let mut with_crc = control.to_vec();
        with_crc.push(0xFA);
        assert_eq!(compute(&a, &with_crc), 0x00);
        // It is the sum modulo 255 (0xFF for a non-zero multiple of 255), inverted.
        for data in [&control[..], CHECK_INPUT, &[0xFF; 300], &[0x01; 255]] {
            let total: u64 = data.iter().map(|b| u64::from(*b)).sum();
            let folded = if total == 0 { 0 } else { (total - 1) % 255 + 1 };
            assert_eq!(compute(&a, data), 0xFF - folded);
        }
        assert_eq!(Prepared::new(&a).compute(&control), 0xFA);
    }

    #[test]
    fn sum8_wraps() {
        assert_eq!(compute(&ChecksumAlgorithm::Sum8, CHECK_INPUT), 0xDD);
        assert_eq!(compute(&ChecksumAlgorithm::Sum8, &[0xAA, 0x21, 0x50]), 0x1B);
    }

    #[test]
    fn agrees_with_the_sd_documents_c_routine() {
        // The SD ICD's §4 routine, transcribed literally.
        fn doc_crc(data: &[u8]) -> u16 {
            let mut crc: u16 = 0xFFFF;
            for &d in data {
                crc ^= u16::from(d) << 8;
                for _ in 0..8 {
                    crc = if crc & 0x8000 != 0 {
                        (crc << 1) ^ 0x8005
                    } else {
                        crc << 1
                    };
                }
            }
            crc
        }
        let p = params(16, 0x8005, 0xFFFF, false, false, 0);
        for frame in [
            [0x76u8, 0x01, 0x12, 0x00],
            [0x69, 0x1F, 0, 0],
            [0xFF; 4],
            [0; 4],
        ] {
            assert_eq!(crc(&p, &frame), u64::from(doc_crc(&frame)));
        }
    }
}
