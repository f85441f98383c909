//! Parsing: a JSON line back to a frame's raw field values, and from those to either engine.

use std::collections::BTreeMap;

use busspec_model::interp::{self, EncodeError, Raw, Value};
use busspec_model::ir::{BitField, Count, Direction, Field, Follows, Message, MessageRef, Unit};
use busspec_model::rational::Rational;
use busspec_runtime::{
    Decoded, Elements, FieldError, FieldValue, Message as _, Protocol, RecordList,
};
use serde::Deserialize;
use serde_json::value::RawValue;

use crate::print::physical_text;
use crate::{Spec, Typed};

/// A frame as a JSON line gives it: the message, the address and every field's raw value
/// (packed sub-fields by name; constants and repeated fields only where the line gives them).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Parsed {
    pub message: MessageRef,
    pub address: u8,
    pub values: Vec<Value<'static>>,
}

impl Parsed {
    /// The frame's bytes, from the interpreter's encoder: constants and repeated fields filled
    /// in, every value checked against its field's width, the address against the spec's.
    pub fn encode(&self, p: &Spec) -> Result<Vec<u8>, String> {
        self.encode_reply(p, None)
    }

    /// [`Self::encode`] of a reply to the request frame `request` (as it travelled), where
    /// given: the checksum of a reply that takes in its request's bytes
    /// (`checksum_over_request`) over them.
    pub fn encode_reply(&self, p: &Spec, request: Option<&[u8]>) -> Result<Vec<u8>, String> {
        let covered = request.and_then(|w| p.checksum_span(w));
        interp::encode_with(p, self.message, self.address, &self.values, covered)
            .map_err(|e| e.to_string())
    }

    /// The frame as a typed message of generated protocol `P` (`p` its spec, from
    /// [`crate::load_spec`]), built directly from the line's raw values with
    /// [`busspec_runtime::Message::from_fields`]. Checked as [`Parsed::encode`] checks it, with
    /// the same reasons: the address against `P`'s, every value against its field's wire type,
    /// and a value the line gives for a constant or repeated field against what it must be.
    pub fn to_typed<P: Protocol>(&self, p: &Spec) -> Result<Typed<P>, String> {
        let m = p.message(self.message);
        let direction = self.message.direction;
        let address = self.address;
        // A constant whole frame is its bytes whatever the address (as `encode` writes it).
        let addressed = p.framing.has_address_in(direction);
        if m.frame.is_none() && !addressed && address != 0 {
            return Err(EncodeError::Unaddressed { address }.to_string());
        }
        if m.frame.is_none() && addressed && !busspec_model::interp::address_allowed(p, address) {
            let a = &p.framing.address;
            return Err(EncodeError::BadAddress {
                address,
                min: a.min,
                max: a.max,
            }
            .to_string());
        }
        // Records lent flat, record after record.
        let flats: Vec<Vec<i64>> = self
            .values
            .iter()
            .map(|v| match &v.raw {
                Raw::Records(r) => r.concat(),
                _ => Vec::new(),
            })
            .collect();
        let field = |name: &'static str| {
            self.values
                .iter()
                .zip(&flats)
                .find(|(v, _)| v.name == name)
                .map(|(v, flat)| match &v.raw {
                    Raw::Int(i) => FieldValue::Int(*i),
                    Raw::Text(t) => FieldValue::Text(t),
                    Raw::List(l) => FieldValue::List(Elements::I64(l)),
                    Raw::Records(_) => FieldValue::Records(RecordList::Flat {
                        values: flat,
                        fields: m
                            .fields
                            .iter()
                            .find(|f| f.name == name)
                            .map_or(0, |f| f.record.len()),
                    }),
                })
        };
        let typed = match direction {
            Direction::Request => P::Request::from_fields(&m.name, field)
                .map(|message| Typed::Request(Decoded { address, message })),
            Direction::Response => P::Response::from_fields(&m.name, field)
                .map(|message| Typed::Response(Decoded { address, message })),
        };
        let typed = typed.map_err(|e| match e {
            // Only a protocol generated from another spec than `p` gets here.
            FieldError::UnknownMessage => format!(
                "the generated {} codec has no {} called {}",
                P::NAME,
                direction.as_str(),
                m.name
            ),
            e => e.to_string(),
        })?;
        check_fixed(m, &self.values)?;
        Ok(typed)
    }
}

fn sign_extend(v: u64, bits: u32) -> i64 {
    if bits == 0 || bits >= 64 {
        return v as i64;
    }
    let shift = 64 - bits;
    ((v << shift) as i64) >> shift
}

/// Checks the values `values` gives for constant and repeated fields (and constant sub-fields)
/// of `m`: each must be what the frame carries, as the interpreter's encoder checks them. A
/// repeated field repeats the wire word of the field it names; a field following another is
/// computed from it, and a list's count from the list (typed messages carry none of them).
fn check_fixed(m: &Message, values: &[Value]) -> Result<(), String> {
    let int = |name: &str| {
        values
            .iter()
            .find(|v| v.name == name)
            .and_then(|v| match v.raw {
                Raw::Int(i) => Some(i),
                Raw::Text(_) | Raw::List(_) | Raw::Records(_) => None,
            })
    };
    let fixed = |field: &str, expected: i64| match int(field) {
        Some(found) if found != expected => Err(EncodeError::Fixed {
            field: field.to_owned(),
            expected,
            found,
        }
        .to_string()),
        _ => Ok(()),
    };
    let mask = |bits: u32| {
        if bits >= 64 {
            u64::MAX
        } else {
            (1u64 << bits) - 1
        }
    };
    // The value of count field `i`: the number of elements or bytes of the list it counts.
    let counted = |i: usize| {
        let (_, rf, r) = m.counted_by(i)?;
        let n = values.iter().find(|v| v.name == rf.name)?.raw.elements()?;
        Some(match r.count {
            Count::Bytes(_) => rf.elements_len(n),
            Count::Elements(_) | Count::ToEnd | Count::Until(_) | Count::Fixed(_) => n,
        } as i64)
    };
    let mut words: Vec<u64> = Vec::with_capacity(m.fields.len());
    for (i, f) in m.fields.iter().enumerate() {
        let bits = 8 * f.width as u32;
        let derived = match &f.follows {
            Some(Follows::Field(o, rel)) => words.get(*o).map(|&w| rel.apply(w as i64)),
            _ => counted(i),
        };
        let word = if f.is_ascii() {
            0
        } else if let Some(expected) = derived {
            fixed(&f.name, expected)?;
            expected as u64 & mask(bits)
        } else if let Some(c) = f
            .constant
            .or_else(|| f.equals.and_then(|o| words.get(o).copied()))
        {
            let expected = if f.signed {
                sign_extend(c, bits)
            } else {
                c as i64
            };
            fixed(&f.name, expected)?;
            c
        } else if !f.bits.is_empty() {
            let mut word = 0u64;
            for b in &f.bits {
                let v = match b.constant {
                    Some(c) => {
                        fixed(&b.name, c as i64)?;
                        c as i64
                    }
                    None => int(&b.name).unwrap_or(0),
                };
                word |= ((v as u64) & mask(u32::from(b.width()))) << b.lsb;
            }
            word
        } else {
            (int(&f.name).unwrap_or(0) as u64) & mask(bits)
        };
        words.push(word);
    }
    Ok(())
}

/// One input line of `encode`: the object `decode` prints (its `offset` from `--stream` is
/// accepted and ignored).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    #[serde(default, rename = "offset")]
    _offset: Option<serde::de::IgnoredAny>,
    #[serde(default)]
    protocol: Option<String>,
    #[serde(default)]
    direction: Option<String>,
    #[serde(default)]
    address: Option<serde_json::Number>,
    #[serde(default)]
    code: Option<String>,
    message: String,
    #[serde(default)]
    fields: Option<BTreeMap<String, Box<RawValue>>>,
}

/// A serde_json error without its `at line 1 column N` tail (there is only one line).
fn json_error(e: &serde_json::Error) -> String {
    let text = e.to_string();
    let tail = format!(" at line {} column {}", e.line(), e.column());
    let msg = text.strip_suffix(&tail).unwrap_or(&text);
    if e.is_syntax() || e.is_eof() {
        format!("invalid JSON at column {}: {msg}", e.column())
    } else {
        msg.to_owned()
    }
}

/// Reads one JSON line: checks it against the spec and converts each field to its raw value.
pub fn parse_line(p: &Spec, line: &str) -> Result<Parsed, String> {
    let input: Input = match serde_json::from_str(line) {
        Ok(i) => i,
        Err(e) => {
            // A `--stream` noise or ambiguity report is not a frame; say so plainly.
            if let Ok(serde_json::Value::Object(o)) = serde_json::from_str(line) {
                if o.contains_key("skipped") {
                    return Err("a skipped-bytes report, not a frame".to_owned());
                }
                if o.contains_key("ambiguous") {
                    return Err(
                        "an ambiguous-frame report, not a frame: name the message instead"
                            .to_owned(),
                    );
                }
            }
            return Err(json_error(&e));
        }
    };
    if let Some(name) = &input.protocol {
        if *name != p.name {
            return Err(format!(
                "protocol `{name}` does not match this spec (`{}`)",
                p.name
            ));
        }
    }
    let direction = match input.direction.as_deref() {
        None => None,
        Some("request") => Some(Direction::Request),
        Some("response") => Some(Direction::Response),
        Some(other) => {
            return Err(format!(
                "direction `{other}` is neither `request` nor `response`"
            ))
        }
    };
    let r = find_message(p, &input.message, direction)?;
    let m = p.message(r);
    // A protocol whose frames carry no address prints none; a line may still give 0. A
    // constant whole frame carries none either: its line prints 0, and may give any or none.
    let address = match (
        &input.address,
        p.framing.has_address_in(r.direction) && m.frame.is_none(),
    ) {
        (Some(n), _) => match n.as_u64().map(u8::try_from) {
            Some(Ok(a)) => a,
            _ => return Err(format!("address {n} is not a byte (0..=255)")),
        },
        (None, false) => 0,
        (None, true) => return Err("missing field `address`".to_owned()),
    };
    if let Some(code) = &input.code {
        let bytes = if matches!(code.trim(), "" | "0x" | "0X") {
            // A message without a code (a Dynamixel status packet) prints as "0x".
            Vec::new()
        } else {
            interp::parse_hex(code).map_err(|e| format!("code `{code}`: {e}"))?
        };
        if bytes != m.code {
            return Err(format!(
                "code {code} does not match {} ({})",
                m.name,
                m.code_hex()
            ));
        }
    }
    let mut values = Vec::new();
    for (name, raw) in input.fields.iter().flatten() {
        let Some((f, bit)) = interp::leaf_field(m, name) else {
            let all: Vec<String> = m.leaves().map(|l| l.name().to_owned()).collect();
            return Err(format!(
                "{} has no field `{name}`{}",
                m.name,
                if all.is_empty() {
                    " (it has no fields)".to_owned()
                } else {
                    format!(" (its fields: {})", all.join(", "))
                }
            ));
        };
        let v = field_value(p, f, bit, name, raw.get())?;
        values.push(Value {
            name: name.clone().into(),
            raw: v,
        });
    }
    Ok(Parsed {
        message: r,
        address,
        values,
    })
}

fn find_message(p: &Spec, name: &str, d: Option<Direction>) -> Result<MessageRef, String> {
    match (d, p.find(name)) {
        (_, None) => Err(format!("unknown message `{name}` in {}", p.name)),
        (Some(want), Some(r)) if r.direction != want => Err(format!(
            "{name} is a {}, not a {}",
            want_other(want).as_str(),
            want.as_str()
        )),
        (_, Some(r)) => Ok(r),
    }
}

fn want_other(d: Direction) -> Direction {
    match d {
        Direction::Request => Direction::Response,
        Direction::Response => Direction::Request,
    }
}

/// Parses JSON number text (`-12.5`, `1e3`, `2.5E-2`) exactly.
fn parse_number(text: &str) -> Option<Rational> {
    let (mantissa, exp) = match text.find(['e', 'E']) {
        Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
        None => (text, 0),
    };
    let m = Rational::parse(mantissa).ok()?;
    if exp.unsigned_abs() > 36 {
        return None;
    }
    let p = Rational::int(10i128.checked_pow(exp.unsigned_abs())?);
    if exp >= 0 {
        m.times(p)
    } else {
        m.over(p)
    }
}

enum Given {
    Number(String, Rational),
    Text(String),
    List(Vec<serde_json::Value>),
}

fn given(name: &str, raw: &str) -> Result<Given, String> {
    let t = raw.trim();
    match t.as_bytes().first() {
        Some(b'"') => serde_json::from_str::<String>(t)
            .map(Given::Text)
            .map_err(|e| format!("{name}: {}", json_error(&e))),
        Some(b'[') => serde_json::from_str::<Vec<serde_json::Value>>(t)
            .map(Given::List)
            .map_err(|e| format!("{name}: {}", json_error(&e))),
        Some(c) if *c == b'-' || c.is_ascii_digit() => match parse_number(t) {
            Some(r) => Ok(Given::Number(t.to_owned(), r)),
            None => Err(format!(
                "{name}: {t} is not a number busspec can take exactly"
            )),
        },
        _ => Err(format!(
            "{name}: {t} is not a number, a string or a list of names"
        )),
    }
}

fn integer(name: &str, text: &str, r: Rational) -> Result<i64, String> {
    if !r.is_integer() {
        return Err(format!("{name}: {text} is not a whole number"));
    }
    i64::try_from(r.num).map_err(|_| format!("{name}: {text} is too large"))
}

fn kind_of(f: &Field, bit: Option<&BitField>) -> &'static str {
    match bit {
        Some(_) => "a number",
        None if f.is_ascii() => "text",
        None if f.flags.is_some() => "a list of flag names",
        None if f.enumeration.is_some() => "a value name or number",
        None => "a number",
    }
}

/// Converts one JSON field value to the raw value the interpreter takes.
fn field_value(
    p: &Spec,
    f: &Field,
    bit: Option<&BitField>,
    name: &str,
    raw: &str,
) -> Result<Raw, String> {
    if f.is_record() && bit.is_none() {
        return records_value(p, f, name, raw);
    }
    if f.is_list() && bit.is_none() {
        let Ok(items) = serde_json::from_str::<Vec<Box<RawValue>>>(raw.trim()) else {
            return Err(format!(
                "{name} takes a list of numbers, got {}",
                raw.trim()
            ));
        };
        let mut scalar = f.clone();
        scalar.repeat = None;
        if let Some(pk) = scalar.packed.take() {
            scalar.width = pk.elem_width;
        }
        let mut list = Vec::with_capacity(items.len());
        for (k, item) in items.iter().enumerate() {
            let v = if f.ty == busspec_model::ir::FieldType::Bit {
                match item.get().trim() {
                    "0" | "false" => 0,
                    "1" | "true" => 1,
                    other => return Err(format!("{name}[{k}]: a bit is 0 or 1, got {other}")),
                }
            } else {
                match field_value(p, &scalar, None, &format!("{name}[{k}]"), item.get())? {
                    Raw::Int(i) => i,
                    _ => return Err(format!("{name}[{k}] takes a number")),
                }
            };
            list.push(v);
        }
        return Ok(Raw::List(list));
    }
    if bit.is_none() && f.is_wide() {
        return wide_value(f, name, raw.trim()).map(Raw::Int);
    }
    let g = given(name, raw)?;
    let wrong = || format!("{name} takes {}, got {}", kind_of(f, bit), raw.trim());
    if let Some(b) = bit {
        let Given::Number(text, r) = g else {
            return Err(wrong());
        };
        return match (b.constant, b.unit.and_then(|u| p.units.get(u))) {
            (None, Some(unit)) => {
                physical_to_raw(unit, name, &text, r, u32::from(b.width()), b.signed).map(Raw::Int)
            }
            _ => integer(name, &text, r).map(Raw::Int),
        };
    }
    if f.is_ascii() {
        let Given::Text(s) = g else {
            return Err(wrong());
        };
        let mut bytes = Vec::with_capacity(s.len());
        for c in s.chars() {
            let b = u8::try_from(u32::from(c)).map_err(|_| {
                format!("{name}: character {c:?} is not a byte (text fields hold U+0000..U+00FF)")
            })?;
            bytes.push(b);
        }
        return Ok(Raw::Text(bytes));
    }
    if f.constant.is_some() || f.equals.is_some() {
        let Given::Number(text, r) = g else {
            return Err(wrong());
        };
        return integer(name, &text, r).map(Raw::Int);
    }
    if let Some(e) = f.enumeration.and_then(|e| p.enums.get(e)) {
        return match g {
            Given::Text(s) => match e.values.iter().find(|v| v.name == s) {
                Some(v) => Ok(Raw::Int(v.value as i64)),
                None => Err(format!(
                    "{name}: `{s}` is not a value of {} (one of: {})",
                    e.name,
                    e.values
                        .iter()
                        .map(|v| v.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            },
            Given::Number(text, r) => integer(name, &text, r).map(Raw::Int),
            Given::List(_) => Err(wrong()),
        };
    }
    if let Some(set) = f.flags.and_then(|i| p.flags.get(i)) {
        let Given::List(items) = g else {
            return Err(wrong());
        };
        let mut word: i64 = 0;
        for item in items {
            match item {
                serde_json::Value::String(s) => match set.bits.iter().find(|b| b.name == s) {
                    Some(b) => word |= 1i64.checked_shl(u32::from(b.bit)).unwrap_or(0),
                    None => {
                        return Err(format!(
                            "{name}: `{s}` is not a flag of {} (one of: {})",
                            set.name,
                            set.bits
                                .iter()
                                .map(|b| b.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ))
                    }
                },
                serde_json::Value::Number(n) => match n.as_i64() {
                    Some(v) if v >= 0 => word |= v,
                    _ => return Err(format!("{name}: {n} is not a bit mask")),
                },
                other => return Err(format!("{name}: {other} is not a flag name or bit mask")),
            }
        }
        return Ok(Raw::Int(word));
    }
    if let Given::Text(s) = &g {
        return match f.special.iter().find(|x| x.name == *s) {
            Some(x) => Ok(Raw::Int(x.value)),
            None if f.special.is_empty() => Err(wrong()),
            None => Err(format!(
                "{name}: `{s}` is not a special value of the field (one of: {})",
                f.special
                    .iter()
                    .map(|x| x.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        };
    }
    let Given::Number(text, r) = g else {
        return Err(wrong());
    };
    match f.unit.and_then(|u| p.units.get(u)) {
        Some(unit) => {
            physical_to_raw(unit, name, &text, r, 8 * f.width as u32, f.signed).map(Raw::Int)
        }
        None => integer(name, &text, r).map(Raw::Int),
    }
}

/// A repeated record's raw values from its JSON text: a list of objects, each giving every
/// field of the record by name, as the printer writes them (`blocks[1].position`: where a
/// value is wrong).
fn records_value(p: &Spec, f: &Field, name: &str, raw: &str) -> Result<Raw, String> {
    let Ok(items) = serde_json::from_str::<Vec<BTreeMap<String, Box<RawValue>>>>(raw.trim()) else {
        return Err(format!(
            "{name} takes a list of records (objects of {}), got {}",
            f.record
                .iter()
                .map(|g| g.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            raw.trim()
        ));
    };
    let mut out = Vec::with_capacity(items.len());
    for (k, item) in items.iter().enumerate() {
        if let Some(extra) = item
            .keys()
            .find(|key| !f.record.iter().any(|g| &g.name == *key))
        {
            return Err(format!("{name}[{k}]: the record has no field `{extra}`"));
        }
        let mut rec = Vec::with_capacity(f.record.len());
        for g in &f.record {
            let label = format!("{name}[{k}].{}", g.name);
            let Some(text) = item.get(&g.name) else {
                return Err(format!("{label}: missing"));
            };
            match field_value(p, g, None, &label, text.get())? {
                Raw::Int(i) => rec.push(i),
                _ => return Err(format!("{label} takes a number")),
            }
        }
        out.push(rec);
    }
    Ok(Raw::Records(out))
}

/// A 64-bit integer or float field's raw value (its bits) from its JSON text: a whole number
/// of its type; for a float any JSON number (the nearest value of its type, so the text the
/// printer writes reads back to the same bits) or the string of a value JSON has no number
/// for (`"inf"`, `"-inf"`, `"NaN"`, `"NaN:0x7FC00001"`).
fn wide_value(f: &Field, name: &str, t: &str) -> Result<i64, String> {
    let k = f.num_kind();
    let ty = match f.ty {
        busspec_model::ir::FieldType::U64 => "u64",
        busspec_model::ir::FieldType::I64 => "i64",
        busspec_model::ir::FieldType::F32 => "f32",
        _ => "f64",
    };
    if t.starts_with('"') {
        let s =
            serde_json::from_str::<String>(t).map_err(|e| format!("{name}: {}", json_error(&e)))?;
        return match k.parse(&s) {
            Some(v) if k.is_non_finite(v) => Ok(v),
            _ if k.is_float() => Err(format!(
                "{name}: \"{s}\" is not a number; a {ty} field takes a number, or \"inf\", \"-inf\", \"NaN\" or \"NaN:0x…\" (its bits)"
            )),
            _ => Err(format!("{name} takes a number, got {t}")),
        };
    }
    let numeric = t.bytes().all(|b| b.is_ascii_digit() || b == b'-')
        || (k.is_float()
            && t.bytes()
                .all(|b| b.is_ascii_digit() || b"-+.eE".contains(&b)));
    match k.parse(t) {
        Some(v) if numeric && !t.is_empty() => Ok(v),
        _ if t
            .bytes()
            .next()
            .is_some_and(|b| b == b'-' || b.is_ascii_digit()) =>
        {
            Err(format!("{name}: {t} is not a value of a {ty} field"))
        }
        _ => Err(format!("{name} takes a number, got {t}")),
    }
}

fn with_symbol(v: &str, unit: &Unit) -> String {
    if unit.symbol.is_empty() {
        v.to_owned()
    } else {
        format!("{v} {}", unit.symbol)
    }
}

/// The raw value of a physical one, exactly; else an error naming the field, the value and the
/// unit's step.
fn physical_to_raw(
    unit: &Unit,
    name: &str,
    text: &str,
    v: Rational,
    bits: u32,
    signed: bool,
) -> Result<i64, String> {
    let raw = match unit.raw_exact(v) {
        Some(raw) => raw,
        None => {
            // A unit without a finite decimal step (1/3) prints the nearest double; take back
            // exactly what decode prints.
            let nearest = v
                .minus(unit.offset)
                .and_then(|x| x.over(unit.scale))
                .map(|x| x.round());
            match nearest.and_then(|n| i64::try_from(n).ok()) {
                Some(n) if physical_text(unit, n) == text => i128::from(n),
                _ => {
                    let offset = if unit.offset == Rational::ZERO {
                        String::new()
                    } else {
                        format!(" from {}", with_symbol(&unit.offset.to_string(), unit))
                    };
                    return Err(format!(
                        "{name}: {} is not a whole number of steps of {}{offset}",
                        with_symbol(text, unit),
                        with_symbol(&unit.scale.to_string(), unit),
                    ));
                }
            }
        }
    };
    let (min, max) = interp::raw_limits(bits, signed);
    match i64::try_from(raw) {
        Ok(r) if (min..=max).contains(&r) => Ok(r),
        _ => Err(format!(
            "{name}: {} is out of range: the field holds {} to {}",
            with_symbol(text, unit),
            with_symbol(&physical_text(unit, min), unit),
            with_symbol(&physical_text(unit, max), unit),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_numbers_parse_exactly() {
        let r = |n, d| Rational::new(n, d).unwrap();
        assert_eq!(parse_number("79.98"), Some(r(7998, 100)));
        assert_eq!(parse_number("-0.5"), Some(r(-1, 2)));
        assert_eq!(parse_number("1e3"), Some(r(1000, 1)));
        assert_eq!(parse_number("2.5E-2"), Some(r(1, 40)));
        assert_eq!(parse_number("1e99"), None);
        assert_eq!(parse_number("abc"), None);
    }
}
