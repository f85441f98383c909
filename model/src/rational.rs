//! Exact rationals for scales and offsets, so that `raw * 0.01` and `360/4096` compare exactly
//! against the values the documents state.

use std::cmp::Ordering;
use std::fmt;

/// `num / den`, always reduced, `den > 0`. Components stay far inside `i128` for the magnitudes
/// specs use (32-bit raw values times scales with a few digits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rational {
    pub num: i128,
    pub den: i128,
}

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

impl Rational {
    pub const ZERO: Rational = Rational { num: 0, den: 1 };
    pub const ONE: Rational = Rational { num: 1, den: 1 };

    /// `None` when `den` is zero or the value does not fit.
    pub fn new(num: i128, den: i128) -> Option<Rational> {
        if den == 0 {
            return None;
        }
        let g = gcd(num, den).max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = n.checked_neg()?;
            d = d.checked_neg()?;
        }
        Some(Rational { num: n, den: d })
    }

    pub fn int(v: i128) -> Rational {
        Rational { num: v, den: 1 }
    }

    /// Parses `"12"`, `"-0.05"`, `"+1.5"`, `"360/4096"`. Text with more than 18 digits is refused.
    pub fn parse(text: &str) -> Result<Rational, String> {
        let t = text.trim();
        if let Some((a, b)) = t.split_once('/') {
            let a = Self::parse_decimal(a.trim())?;
            let b = Self::parse_decimal(b.trim())?;
            if b.num == 0 {
                return Err(format!("`{text}` divides by zero"));
            }
            return a.over(b).ok_or_else(|| format!("`{text}` is too large"));
        }
        Self::parse_decimal(t)
    }

    fn parse_decimal(t: &str) -> Result<Rational, String> {
        let bad = || format!("`{t}` is not a decimal number or fraction");
        let (neg, body) = match t.as_bytes().first() {
            Some(b'-') => (true, &t[1..]),
            Some(b'+') => (false, &t[1..]),
            _ => (false, t),
        };
        let (int_part, frac_part) = body.split_once('.').unwrap_or((body, ""));
        if int_part.is_empty() && frac_part.is_empty() {
            return Err(bad());
        }
        if !int_part.bytes().all(|b| b.is_ascii_digit())
            || !frac_part.bytes().all(|b| b.is_ascii_digit())
        {
            return Err(bad());
        }
        if int_part.len() + frac_part.len() > 18 {
            return Err(format!("`{t}` has too many digits"));
        }
        let digits = format!("{int_part}{frac_part}");
        let mut num: i128 = digits.parse().map_err(|_| bad())?;
        if neg {
            num = -num;
        }
        let den = 10i128.pow(frac_part.len() as u32);
        Rational::new(num, den).ok_or_else(bad)
    }

    pub fn times(self, o: Rational) -> Option<Rational> {
        Rational::new(self.num.checked_mul(o.num)?, self.den.checked_mul(o.den)?)
    }

    pub fn over(self, o: Rational) -> Option<Rational> {
        Rational::new(self.num.checked_mul(o.den)?, self.den.checked_mul(o.num)?)
    }

    pub fn plus(self, o: Rational) -> Option<Rational> {
        let n = self
            .num
            .checked_mul(o.den)?
            .checked_add(o.num.checked_mul(self.den)?)?;
        Rational::new(n, self.den.checked_mul(o.den)?)
    }

    pub fn minus(self, o: Rational) -> Option<Rational> {
        self.plus(Rational {
            num: o.num.checked_neg()?,
            den: o.den,
        })
    }

    pub fn is_integer(self) -> bool {
        self.den == 1
    }

    pub fn to_f64(self) -> f64 {
        self.num as f64 / self.den as f64
    }

    /// The nearest integer, ties away from zero.
    pub fn round(self) -> i128 {
        let twice = 2 * self.num.abs() + self.den;
        let q = twice / (2 * self.den);
        if self.num < 0 {
            -q
        } else {
            q
        }
    }
}

impl PartialOrd for Rational {
    fn partial_cmp(&self, o: &Rational) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Rational {
    fn cmp(&self, o: &Rational) -> Ordering {
        // Denominators are positive, so cross-multiplication keeps the order. Saturate rather
        // than overflow: the magnitudes in specs never get near it.
        self.num
            .saturating_mul(o.den)
            .cmp(&o.num.saturating_mul(self.den))
    }
}

/// The decimal places a fraction with (positive) denominator `den` needs, if it has a finite
/// decimal: the larger power of 2 and 5 in `den`, when `den` has no other factor.
pub fn decimal_places(den: i128) -> Option<u32> {
    if den <= 0 {
        return None;
    }
    let (mut d, mut twos, mut fives) = (den, 0u32, 0u32);
    while d % 2 == 0 {
        d /= 2;
        twos += 1;
    }
    while d % 5 == 0 {
        d /= 5;
        fives += 1;
    }
    (d == 1).then_some(twos.max(fives))
}

impl fmt::Display for Rational {
    /// Exact decimal where the denominator divides a power of ten, else `num/den`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // A denominator like 2^40 needs 40 decimal places, more than i128 holds: print such
        // values (and any other whose scaling would overflow) as a fraction.
        let places = decimal_places(self.den);
        let scaled = places
            .and_then(|places| 10i128.checked_pow(places))
            .and_then(|p| Some((p, self.num.checked_mul(p / self.den)?)));
        let (Some(places), Some((p, scaled))) = (places, scaled) else {
            return write!(f, "{}/{}", self.num, self.den);
        };
        if places == 0 {
            return write!(f, "{scaled}");
        }
        let sign = if scaled < 0 { "-" } else { "" };
        let (a, p) = (scaled.unsigned_abs(), p.unsigned_abs());
        write!(
            f,
            "{sign}{}.{:0width$}",
            a / p,
            a % p,
            width = places as usize
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_decimals_and_fractions() {
        assert_eq!(
            Rational::parse("0.01").unwrap(),
            Rational::new(1, 100).unwrap()
        );
        assert_eq!(Rational::parse("-50").unwrap(), Rational::int(-50));
        assert_eq!(
            Rational::parse("360/4096").unwrap(),
            Rational::new(45, 512).unwrap()
        );
        assert_eq!(Rational::parse(".5").unwrap(), Rational::new(1, 2).unwrap());
        for bad in [
            "",
            "-",
            "1.2.3",
            "abc",
            "1/0",
            "1e5",
            "0x10",
            "99999999999999999999",
        ] {
            assert!(Rational::parse(bad).is_err(), "{bad} should not parse");
        }
    }

    #[test]
    fn displays_exact_decimals() {
        assert_eq!(Rational::parse("150.00").unwrap().to_string(), "150");
        assert_eq!(Rational::parse("-0.25").unwrap().to_string(), "-0.25");
        assert_eq!(
            Rational::parse("360/4096").unwrap().to_string(),
            "0.087890625"
        );
        assert_eq!(Rational::new(1, 3).unwrap().to_string(), "1/3");
        // 2^40 would need 40 decimal places; i128 cannot scale that far.
        assert_eq!(
            Rational::new(-1, 1 << 40).unwrap().to_string(),
            "-1/1099511627776"
        );
        assert_eq!(
            Rational::new(1, 1 << 20).unwrap().to_string(),
            "0.00000095367431640625"
        );
    }

    #[test]
    fn rounds_half_away_from_zero() {
        assert_eq!(Rational::new(5, 2).unwrap().round(), 3);
        assert_eq!(Rational::new(-5, 2).unwrap().round(), -3);
        assert_eq!(Rational::new(7, 3).unwrap().round(), 2);
    }
}
