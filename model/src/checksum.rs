//! Checksums computed straight from their declared parameters.
//!
//! This is deliberately a plain bit-by-bit implementation of the catalogue's parameter model and
//! not the table-driven `crc` crate the generated code uses: the interpreter is the independent
//! oracle the generated code is tested against, so the two must not share an implementation.

use crate::ir::{ChecksumAlgorithm, CrcParams};

/// The ASCII bytes every catalogue check value is computed over.
pub const CHECK_INPUT: &[u8] = b"123456789";

pub fn compute(algorithm: &ChecksumAlgorithm, data: &[u8]) -> u64 {
    match algorithm {
        ChecksumAlgorithm::Sum8 => u64::from(sum8(data)),
        ChecksumAlgorithm::Sum8OnesComplement => u64::from(!sum8(data)),
        ChecksumAlgorithm::Sum8TwosComplement => u64::from(sum8(data).wrapping_neg()),
        ChecksumAlgorithm::Xor8 => u64::from(data.iter().fold(0u8, |s, b| s ^ b)),
        ChecksumAlgorithm::Crc(p) => crc(p, data),
    }
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
