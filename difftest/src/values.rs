//! Random values for a message's leaves (the ones a generated message carries), for the
//! examples the generator derives and the encodes the comparison makes.

use busspec_model::interp::{raw_limits, Raw, Value};
use busspec_model::ir::{Field, FieldType, Leaf, Message, Protocol};
use busspec_model::number::NumKind;

/// Whether leaf `l` of `m` is a value the generated message carries (and both encoders take):
/// not a constant, not a copy of or a value following another field, not a repeat's count, not
/// a constant sub-field. The same rule as `busspec_fuzz_bodies::oracle::interp_values`.
pub fn carried(m: &Message, l: &Leaf<'_>) -> bool {
    match l {
        Leaf::Field(i, _) => !m.is_derived(*i),
        Leaf::Bits(i, _, b) => !m.is_derived(*i) && b.constant.is_none(),
    }
}

/// A raw value in `lo..=hi`, often one of its ends.
fn within(rng: &mut fastrand::Rng, lo: i64, hi: i64) -> i64 {
    match rng.u8(..8) {
        0 => lo,
        1 => hi,
        _ => rng.i64(lo..=hi),
    }
}

/// A 64-bit integer's or a float's raw value (its bits): strict, one in its range (ends
/// included); otherwise often NaN (canonical and with a payload), an infinity, a signed zero,
/// a range's end or any bits, and now and then more bits than an `f32` has.
fn wide(rng: &mut fastrand::Rng, f: &busspec_model::ir::Field, strict: bool) -> i64 {
    let k = f.num_kind();
    let in_range = |rng: &mut fastrand::Rng, (a, b): (i64, i64)| -> i64 {
        match k {
            NumKind::Int => within(rng, a, b),
            NumKind::U64 => match rng.u8(..8) {
                0 => a,
                1 => b,
                _ => rng.u64(a as u64..=b as u64) as i64,
            },
            _ => {
                let (x, y) = (k.float(a).unwrap_or(0.0), k.float(b).unwrap_or(0.0));
                let v = match rng.u8(..8) {
                    0 => x,
                    1 => y,
                    _ => x + (y - x) * rng.f64(),
                };
                let raw = if k == NumKind::F32 {
                    i64::from((v as f32).to_bits())
                } else {
                    v.to_bits() as i64
                };
                // Rounding to an f32 may step just outside: fall back to an end.
                if k.within(raw, a, b) {
                    raw
                } else {
                    a
                }
            }
        }
    };
    if let (Some(r), true) = (f.range, strict || rng.u8(..3) != 0) {
        return in_range(rng, r);
    }
    if strict {
        return any_bits(rng, k);
    }
    match (k, rng.u8(..12)) {
        (NumKind::F32, 0) => 0x7FC0_0000,
        (NumKind::F32, 1) => i64::from(0x7F80_0000u32 | rng.u32(1..0x0080_0000)),
        (NumKind::F32, 2) => i64::from(f32::INFINITY.to_bits()),
        (NumKind::F32, 3) => i64::from(f32::NEG_INFINITY.to_bits()),
        (NumKind::F32, 4) => i64::from((-0.0f32).to_bits()),
        (NumKind::F32, 5) => i64::from(u32::MAX) + 1,
        (NumKind::F64, 0) => 0x7FF8_0000_0000_0000,
        (NumKind::F64, 1) => (0xFFF0_0000_0000_0000u64 | rng.u64(1..1 << 52)) as i64,
        (NumKind::F64, 2) => f64::INFINITY.to_bits() as i64,
        (NumKind::F64, 3) => f64::NEG_INFINITY.to_bits() as i64,
        (NumKind::F64, 4) => (-0.0f64).to_bits() as i64,
        (NumKind::U64 | NumKind::Int, 0) => i64::MIN,
        (NumKind::U64 | NumKind::Int, 1) => -1,
        _ => any_bits(rng, k),
    }
}

fn any_bits(rng: &mut fastrand::Rng, k: NumKind) -> i64 {
    match k {
        NumKind::F32 => i64::from(rng.u32(..)),
        _ => rng.i64(..),
    }
}

/// Values for every carried leaf of `m`. `strict`: values the spec allows (in range, a named
/// enum value most of the time, printable text); otherwise anything the wire type holds, now
/// and then outside it, and lists of any length.
pub fn random_values(
    p: &Protocol,
    m: &Message,
    rng: &mut fastrand::Rng,
    strict: bool,
) -> Vec<Value<'static>> {
    let mut out: Vec<Value<'static>> = Vec::new();
    for l in m.leaves() {
        if !carried(m, &l) {
            continue;
        }
        // An optional field: given where its condition holds on the values drawn so far
        // (always where strict; otherwise now and then the other way, which encode refuses).
        if let Some(c) = l_present(&l) {
            let on = c.holds(condition_raw(m, c.field, &out));
            let flip = !strict && rng.u8(..8) == 0;
            if on == flip {
                continue;
            }
        }
        let raw = match l {
            Leaf::Bits(_, _, b) => {
                let (lo, hi) = raw_limits(u32::from(b.width()), b.signed);
                let (lo, hi) = match b.range {
                    Some(r) if strict || rng.u8(..4) != 0 => r,
                    _ => (lo, hi),
                };
                let mut v = within(rng, lo, hi);
                if !strict && rng.u8(..16) == 0 {
                    v = hi.saturating_add(1);
                }
                Raw::Int(v)
            }
            Leaf::Field(_, f) => {
                if f.ty == FieldType::Ascii {
                    // Counted text: as many characters as a list's elements (now and then one
                    // past its most).
                    let n = match &f.repeat {
                        Some(r) if strict => rng.usize(r.min..=r.max),
                        Some(r) => rng.usize(..=r.max + 1),
                        None => f.width,
                    };
                    // Text up to a terminator holds it only where not strict (drawn the same:
                    // the byte is moved off the terminator after the draw).
                    let t: Vec<u8> = (0..n)
                        .map(|_| {
                            if strict || rng.bool() {
                                rng.u8(0x20..0x7F)
                            } else {
                                rng.u8(..)
                            }
                        })
                        .map(|b| match f.terminator() {
                            Some(t) if strict && b == t => b ^ 1,
                            _ => b,
                        })
                        .collect();
                    Raw::Text(t)
                } else if let Some(pk) = f.fixed_count() {
                    // A list of a fixed count: its count (now and then one more or fewer), each
                    // element drawn as a field of its type is (its enum, unit, range).
                    let e = f.element();
                    let n = if strict || rng.u8(..8) != 0 {
                        pk.count
                    } else {
                        rng.usize(pk.count.saturating_sub(1)..=pk.count + 1)
                    };
                    Raw::List(
                        (0..n)
                            .map(|_| {
                                if e.is_wide() {
                                    wide(rng, &e, strict)
                                } else {
                                    scalar(p, &e, rng, strict)
                                }
                            })
                            .collect(),
                    )
                } else if let Some(pk) = &f.packed {
                    // Packed elements: their count (now and then one more or fewer), each
                    // within the range or the element's bits (now and then one past them).
                    let (elo, ehi) = match f.range {
                        Some(rg) if strict || rng.u8(..4) != 0 => rg,
                        _ if strict => (0, pk.max()),
                        _ => (0, pk.max() + 1),
                    };
                    let n = if strict || rng.u8(..8) != 0 {
                        pk.count
                    } else {
                        rng.usize(pk.count.saturating_sub(1)..=pk.count + 1)
                    };
                    Raw::List((0..n).map(|_| within(rng, elo, ehi)).collect())
                } else if let (Some(r), true) = (&f.repeat, f.is_record()) {
                    let n = if strict {
                        rng.usize(r.min..=r.max)
                    } else {
                        rng.usize(..=r.max + 1)
                    };
                    // Records whose last field's bytes a field gives: that field's value
                    // within 1..=the most (always where strict, mostly otherwise), and each
                    // last field within the bytes it gives.
                    let sized = f.record_bytes_from().zip(f.record.last());
                    let mut bytes = None;
                    if let Some((wi, g)) = sized {
                        let name = m.fields[wi].name.as_str();
                        if let Some(w) = out.iter_mut().find(|v| v.name == name) {
                            if strict || rng.u8(..4) != 0 {
                                if let Raw::Int(x) = &mut w.raw {
                                    if !(1..=g.width as i64).contains(x) {
                                        *x = rng.i64(1..=g.width as i64);
                                    }
                                }
                            }
                            if let Raw::Int(x) = w.raw {
                                bytes = Some(x.clamp(1, g.width as i64) as u32);
                            }
                        }
                    }
                    let last = f.record.len().saturating_sub(1);
                    Raw::Records(
                        (0..n)
                            .map(|_| {
                                f.record
                                    .iter()
                                    .enumerate()
                                    .map(|(j, g)| match bytes {
                                        Some(b) if j == last && (strict || rng.u8(..8) != 0) => {
                                            let (lo, hi) = raw_limits(8 * b, g.signed);
                                            let (lo, hi) = match g.range {
                                                Some((a, c)) if a.max(lo) <= c.min(hi) => {
                                                    (a.max(lo), c.min(hi))
                                                }
                                                _ => (lo, hi),
                                            };
                                            within(rng, lo, hi)
                                        }
                                        _ => scalar(p, g, rng, strict),
                                    })
                                    .collect()
                            })
                            .collect(),
                    )
                } else if let Some(r) = &f.repeat {
                    let bit = f.ty == FieldType::Bit;
                    let (lo, hi) = if bit {
                        (0, 1)
                    } else {
                        raw_limits(8 * f.width as u32, f.signed)
                    };
                    let (elo, ehi) = match f.range {
                        Some(rg) if strict || rng.u8(..4) != 0 => rg,
                        _ => (lo, hi),
                    };
                    let bound = if bit { r.max.div_ceil(8) * 8 } else { r.max };
                    let n = if strict {
                        let (a, b) = if bit {
                            (r.min.div_ceil(8) * 8, bound)
                        } else {
                            (r.min, r.max)
                        };
                        let mut n = rng.usize(a..=b.max(a));
                        if bit {
                            n = n / 8 * 8;
                            if n < r.min {
                                n = a;
                            }
                        }
                        n
                    } else {
                        rng.usize(..=bound + 1)
                    };
                    if f.is_wide() {
                        // Floats and 64-bit integers: each as a field of its type is drawn.
                        Raw::List((0..n).map(|_| wide(rng, f, strict)).collect())
                    } else {
                        Raw::List((0..n).map(|_| within(rng, elo, ehi)).collect())
                    }
                } else if f.is_wide() {
                    Raw::Int(wide(rng, f, strict))
                } else {
                    Raw::Int(scalar(p, f, rng, strict))
                }
            }
        };
        out.push(Value {
            name: l.name().to_owned().into(),
            raw,
        });
    }
    out
}

/// The condition of optional leaf `l`, if it is an optional field.
fn l_present(l: &Leaf<'_>) -> Option<busspec_model::ir::Presence> {
    match l {
        Leaf::Field(_, f) => f.present,
        Leaf::Bits(..) => None,
    }
}

/// The raw value field `fi` of `m` takes from the values drawn so far (`out`), as encode
/// writes it: a constant, its sub-fields put together, or its own value (0 where none is).
fn condition_raw(m: &Message, fi: usize, out: &[Value<'static>]) -> i64 {
    let Some(g) = m.fields.get(fi) else {
        return 0;
    };
    let int = |name: &str| {
        out.iter()
            .find(|v| v.name == name)
            .and_then(|v| match v.raw {
                Raw::Int(x) => Some(x),
                _ => None,
            })
            .unwrap_or(0)
    };
    if let Some(c) = g.constant {
        return c as i64;
    }
    if g.bits.is_empty() {
        return int(&g.name);
    }
    let mut word = 0u64;
    for b in &g.bits {
        let v = b.constant.map_or_else(|| int(&b.name), |c| c as i64);
        let mask = 1u64
            .checked_shl(u32::from(b.width()))
            .map_or(u64::MAX, |x| x - 1);
        word |= ((v as u64) & mask) << b.lsb;
    }
    word as i64
}

/// A value of a whole integer field (a record's field too): a named enum value, a special
/// value or one in range most of the time; strict, always what the spec allows.
fn scalar(p: &Protocol, f: &Field, rng: &mut fastrand::Rng, strict: bool) -> i64 {
    let (lo, hi) = raw_limits(8 * f.width as u32, f.signed);
    let e = f.enumeration.map(|e| &p.enums[e]);
    let v = if let (Some(e), true) = (e, rng.u8(..4) != 0) {
        e.values[rng.usize(..e.values.len())].value as i64
    } else if !f.special.is_empty() && rng.u8(..4) == 0 {
        f.special[rng.usize(..f.special.len())].value
    } else if let (Some((a, b)), true) = (f.range, strict || rng.u8(..4) != 0) {
        within(rng, a, b)
    } else {
        within(rng, lo, hi)
    };
    let v = match f.range {
        Some((a, b))
            if strict && !(a..=b).contains(&v) && !f.special.iter().any(|s| s.value == v) =>
        {
            within(rng, a, b)
        }
        _ => v,
    };
    if !strict && rng.u8(..32) == 0 {
        hi.saturating_add(1)
    } else {
        v
    }
}
