//! How a raw value reads as a number, for the types whose raw value is not the number itself.
//!
//! Every engine carries a field's raw value as an `i64` (the interpreter's `Raw::Int`, the
//! runtime's `FieldValue::Int`). For the integers up to 32 bits and `i64` that is the value; a
//! `u64` travels as its bits (`v as i64`, so values above `i64::MAX` read as negative there),
//! an `f32` as its bits zero-extended and an `f64` as its bits. Ranges in the IR are raw values
//! too, compared as the type compares ([`NumKind::within`]).
//!
//! Texts are one rule everywhere (JSON lines, errors, docs), and the runtime prints alike: an
//! integer in decimal; a finite float as Rust's `{:?}` prints it (the shortest text that reads
//! back to the same bits, `1e-7` and `1e16` with an exponent, `50.0` with a point); `inf`,
//! `-inf`; `NaN` for the canonical quiet NaN (`0x7FC00000`, `0x7FF8000000000000`) and
//! `NaN:0x7FC00001` (every bit, in hex) for any other, so every NaN reads back to its bits.

use std::fmt;

use crate::ir::FieldType;

/// How a raw value reads as a number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NumKind {
    /// The raw value is the integer (every integer type but `u64`).
    Int,
    /// The bits of a `u64`.
    U64,
    /// The bits of an `f32`, zero-extended.
    F32,
    /// The bits of an `f64`.
    F64,
}

impl NumKind {
    pub fn of(ty: FieldType) -> NumKind {
        match ty {
            FieldType::U64 => NumKind::U64,
            FieldType::F32 => NumKind::F32,
            FieldType::F64 => NumKind::F64,
            _ => NumKind::Int,
        }
    }

    pub fn is_float(self) -> bool {
        matches!(self, NumKind::F32 | NumKind::F64)
    }

    /// The raw value as an `f64` (floats), for comparisons; `None` for integers.
    pub fn float(self, raw: i64) -> Option<f64> {
        match self {
            NumKind::F32 => Some(f64::from(f32::from_bits(raw as u32))),
            NumKind::F64 => Some(f64::from_bits(raw as u64)),
            _ => None,
        }
    }

    /// The raw value as an exact integer (integers), `None` for floats.
    pub fn int(self, raw: i64) -> Option<i128> {
        match self {
            NumKind::Int => Some(i128::from(raw)),
            NumKind::U64 => Some(i128::from(raw as u64)),
            _ => None,
        }
    }

    /// Whether `raw` lies in `min..=max` (raw values), as the type orders numbers: a NaN lies
    /// in no range.
    pub fn within(self, raw: i64, min: i64, max: i64) -> bool {
        match self {
            NumKind::Int => (min..=max).contains(&raw),
            NumKind::U64 => (min as u64..=max as u64).contains(&(raw as u64)),
            NumKind::F32 | NumKind::F64 => {
                let f = |r| self.float(r).unwrap_or(f64::NAN);
                let v = f(raw);
                f(min) <= v && v <= f(max)
            }
        }
    }

    /// `raw` as the contract prints it (see the module docs).
    pub fn text(self, raw: i64) -> String {
        Num(self, raw).to_string()
    }

    /// Whether `raw` is a float that JSON has no number for (NaN, infinities): printed as a
    /// string.
    pub fn is_non_finite(self, raw: i64) -> bool {
        self.float(raw).is_some_and(|f| !f.is_finite())
    }

    /// The raw value of `text`, as [`NumKind::text`] prints it (floats: any decimal, rounded
    /// to the nearest value of the type), or `None`.
    pub fn parse(self, text: &str) -> Option<i64> {
        match self {
            NumKind::Int => text.parse().ok(),
            NumKind::U64 => text.parse::<u64>().ok().map(|v| v as i64),
            NumKind::F32 => match special_float(text, 8) {
                Some(Special::Infinite(neg)) => Some(i64::from(
                    if neg {
                        f32::NEG_INFINITY
                    } else {
                        f32::INFINITY
                    }
                    .to_bits(),
                )),
                Some(Special::Nan(bits)) => bits
                    .or(Some(0x7FC0_0000))
                    .filter(|b| *b <= u64::from(u32::MAX) && f32::from_bits(*b as u32).is_nan())
                    .map(|b| b as i64),
                Some(Special::Bad) => None,
                None => float_digits(text)?
                    .parse::<f32>()
                    .ok()
                    .map(|f| i64::from(f.to_bits())),
            },
            NumKind::F64 => match special_float(text, 16) {
                Some(Special::Infinite(neg)) => Some(
                    if neg {
                        f64::NEG_INFINITY
                    } else {
                        f64::INFINITY
                    }
                    .to_bits() as i64,
                ),
                Some(Special::Nan(bits)) => bits
                    .or(Some(0x7FF8_0000_0000_0000))
                    .filter(|b| f64::from_bits(*b).is_nan())
                    .map(|b| b as i64),
                Some(Special::Bad) => None,
                None => float_digits(text)?
                    .parse::<f64>()
                    .ok()
                    .map(|f| f.to_bits() as i64),
            },
        }
    }
}

/// Text Rust's float parser takes as a JSON or YAML decimal: digits, a sign, a point and an
/// exponent only (not `inf`, `nan` or `infinity`, which the texts spell otherwise).
fn float_digits(text: &str) -> Option<&str> {
    text.bytes()
        .all(|b| b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.' | b'e' | b'E'))
        .then_some(text)
        .filter(|t| t.bytes().any(|b| b.is_ascii_digit()))
}

enum Special {
    Infinite(bool),
    /// `NaN` (`None`: the canonical one) or `NaN:0x…` (its bits).
    Nan(Option<u64>),
    /// `NaN:` followed by anything but 1 to `digits` hex digits.
    Bad,
}

/// The texts of the non-finite values; `None` for anything else.
fn special_float(text: &str, digits: usize) -> Option<Special> {
    Some(match text {
        "inf" => Special::Infinite(false),
        "-inf" => Special::Infinite(true),
        "NaN" => Special::Nan(None),
        t => {
            let h = t.strip_prefix("NaN:")?;
            match h.strip_prefix("0x") {
                Some(h)
                    if (1..=digits).contains(&h.len())
                        && h.bytes().all(|b| b.is_ascii_hexdigit()) =>
                {
                    u64::from_str_radix(h, 16).map_or(Special::Bad, |b| Special::Nan(Some(b)))
                }
                _ => Special::Bad,
            }
        }
    })
}

/// A raw value displayed as its [`NumKind`] reads it.
#[derive(Debug, Clone, Copy)]
pub struct Num(pub NumKind, pub i64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Num(kind, raw) = *self;
        match kind {
            NumKind::Int => write!(f, "{raw}"),
            NumKind::U64 => write!(f, "{}", raw as u64),
            NumKind::F32 => {
                let v = f32::from_bits(raw as u32);
                if v.is_nan() {
                    nan(
                        f,
                        raw as u32 == 0x7FC0_0000,
                        format_args!("{:08X}", raw as u32),
                    )
                } else {
                    float(
                        f,
                        v.is_infinite(),
                        v.is_sign_negative(),
                        format_args!("{v:?}"),
                    )
                }
            }
            NumKind::F64 => {
                let v = f64::from_bits(raw as u64);
                if v.is_nan() {
                    nan(
                        f,
                        raw as u64 == 0x7FF8_0000_0000_0000,
                        format_args!("{:016X}", raw as u64),
                    )
                } else {
                    float(
                        f,
                        v.is_infinite(),
                        v.is_sign_negative(),
                        format_args!("{v:?}"),
                    )
                }
            }
        }
    }
}

fn nan(f: &mut fmt::Formatter<'_>, canonical: bool, hex: fmt::Arguments<'_>) -> fmt::Result {
    if canonical {
        f.write_str("NaN")
    } else {
        write!(f, "NaN:0x{hex}")
    }
}

fn float(
    f: &mut fmt::Formatter<'_>,
    infinite: bool,
    negative: bool,
    finite: fmt::Arguments<'_>,
) -> fmt::Result {
    match (infinite, negative) {
        (true, false) => f.write_str("inf"),
        (true, true) => f.write_str("-inf"),
        _ => f.write_fmt(finite),
    }
}

/// The permutation a word-swapped number's bytes take: byte `i` of the number as its byte
/// order puts it travels at `swap_index(i, width)`. Its own inverse.
pub fn swap_index(i: usize, width: usize) -> usize {
    (width / 2 - 1 - i / 2) * 2 + i % 2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texts_read_back_to_the_same_bits() {
        let f32s = [
            0.0f32,
            -0.0,
            1.0,
            230.1,
            1e-7,
            3.4028235e38,
            f32::MIN_POSITIVE,
            1e-45,
            -2.5,
        ];
        for v in f32s {
            let raw = i64::from(v.to_bits());
            let t = NumKind::F32.text(raw);
            assert_eq!(NumKind::F32.parse(&t), Some(raw), "{t}");
        }
        for bits in [
            0x7FC0_0000u32,
            0x7FC0_0001,
            0xFF80_0001,
            0x7F80_0000,
            0xFF80_0000,
        ] {
            let raw = i64::from(bits);
            let t = NumKind::F32.text(raw);
            assert_eq!(NumKind::F32.parse(&t), Some(raw), "{t}");
        }
        let f64s = [
            0.0f64,
            -0.0,
            0.1,
            1e300,
            1e-300,
            f64::MAX,
            5e-324,
            123456789.125,
        ];
        for v in f64s {
            let raw = v.to_bits() as i64;
            let t = NumKind::F64.text(raw);
            assert_eq!(NumKind::F64.parse(&t), Some(raw), "{t}");
        }
        for bits in [
            0x7FF8_0000_0000_0000u64,
            0xFFF0_0000_0000_0001,
            0x7FF0_0000_0000_0000,
        ] {
            let raw = bits as i64;
            let t = NumKind::F64.text(raw);
            assert_eq!(NumKind::F64.parse(&t), Some(raw), "{t}");
        }
        assert_eq!(NumKind::F32.text(0x7FC0_0000), "NaN");
        assert_eq!(NumKind::F32.text(0x7FC0_0001), "NaN:0x7FC00001");
        assert_eq!(NumKind::F64.text(1e16f64.to_bits() as i64), "1e16");
        assert_eq!(NumKind::U64.text(-1), "18446744073709551615");
        assert_eq!(NumKind::U64.parse("18446744073709551615"), Some(-1));
    }

    #[test]
    fn bad_texts_are_refused() {
        for t in [
            "",
            "nan",
            "infinity",
            "NaN:0x",
            "NaN:0x0",
            "NaN:0x3F800000",
            "NaN:0xZZ",
            "1.0.0",
            "e",
        ] {
            assert_eq!(NumKind::F32.parse(t), None, "{t:?}");
        }
        assert_eq!(NumKind::F32.parse("NaN:0x123456789"), None);
        assert_eq!(NumKind::U64.parse("-1"), None);
    }

    #[test]
    fn nan_lies_in_no_range_and_u64_orders_unsigned() {
        let b = |v: f32| i64::from(v.to_bits());
        assert!(NumKind::F32.within(b(1.5), b(-2.0), b(2.0)));
        assert!(!NumKind::F32.within(b(f32::NAN), b(-2.0), b(2.0)));
        assert!(!NumKind::F32.within(b(f32::INFINITY), b(-2.0), b(2.0)));
        assert!(NumKind::U64.within(-1, 0, -1));
        assert!(!NumKind::U64.within(-1, 0, i64::MAX));
    }

    #[test]
    fn swap_index_reverses_words() {
        assert_eq!(
            (0..4).map(|i| swap_index(i, 4)).collect::<Vec<_>>(),
            [2, 3, 0, 1]
        );
        assert_eq!(
            (0..8).map(|i| swap_index(i, 8)).collect::<Vec<_>>(),
            [6, 7, 4, 5, 2, 3, 0, 1]
        );
    }
}

/// The number binary-coded decimal `bcd` stands for (each 4 bits a digit, the high ones the
/// more significant): `None` where a digit is above 9.
pub fn from_bcd(bcd: u64) -> Option<u64> {
    let mut v = 0u64;
    for i in (0..16).rev() {
        let d = (bcd >> (4 * i)) & 0xF;
        if d > 9 {
            return None;
        }
        v = v * 10 + d;
    }
    Some(v)
}

/// `v` (at most 16 decimal digits) in binary-coded decimal: [`from_bcd`]'s inverse.
pub fn to_bcd(mut v: u64) -> u64 {
    let mut bcd = 0u64;
    for i in 0..16 {
        bcd |= (v % 10) << (4 * i);
        v /= 10;
    }
    bcd
}

#[cfg(test)]
mod bcd_tests {
    use super::*;

    #[test]
    fn bcd_round_trips_and_refuses_a_digit_above_nine() {
        assert_eq!(from_bcd(0x1234), Some(1234));
        assert_eq!(from_bcd(0x9999_9999), Some(99_999_999));
        assert_eq!(from_bcd(0x12A4), None);
        assert_eq!(from_bcd(0xF0), None);
        for v in [0, 7, 10, 99, 1234, 99_999_999] {
            assert_eq!(from_bcd(to_bcd(v)), Some(v));
        }
        assert_eq!(to_bcd(1234), 0x1234);
    }
}
