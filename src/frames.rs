//! The decode/encode contract of the CLI: frames ↔ JSON lines.
//!
//! One JSON object per frame, keys in this order:
//! `{"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":79.98}}`
//! (`--stream` puts `"offset":N` first). Field values:
//!
//! - numbers with a unit: the physical value `raw * scale + offset`, exact, in the unit's symbol;
//! - `special` raw values: their name;
//! - enums: the value's name, or the raw number when the enum does not list it;
//! - flags: the names of the set bits, in bit order, then any set bit the spec does not name as
//!   its numeric value (`["oca", 64]`);
//! - constants, repeated (`equals`) fields and other unit-less numbers: the raw number;
//! - text (`ascii`): a string, one character per byte (bytes 0x80..0xFF as U+0080..U+00FF).
//!
//! The shape belongs to the contract, not to the engine: this module speaks the interpreter's
//! [`Frame`]/[`Value`] today, and a generated codec can feed the same JSON later.

use std::collections::BTreeMap;

use busspec_model::interp::{self, DecodeError, Frame, Raw, Value};
use busspec_model::ir::{BitField, Direction, Field, MessageRef, Protocol, Unit};
use busspec_model::rational::Rational;
use busspec_model::stream::Event;
use serde::Deserialize;
use serde_json::value::RawValue;

/// A JSON value, written with keys in the order given.
enum Json {
    /// Number text, already valid JSON.
    Num(String),
    Str(String),
    List(Vec<Json>),
    Obj(Vec<(&'static str, Json)>),
    /// An object with owned keys (the message's fields).
    Fields(Vec<(String, Json)>),
}

fn quote(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".to_owned())
}

/// Writes `{"k":v,...}`, keys in the order given.
fn write_object<'a>(out: &mut String, pairs: impl Iterator<Item = (&'a str, &'a Json)>) {
    out.push('{');
    for (i, (k, v)) in pairs.enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&quote(k));
        out.push(':');
        v.write(out);
    }
    out.push('}');
}

impl Json {
    fn write(&self, out: &mut String) {
        match self {
            Json::Num(n) => out.push_str(n),
            Json::Str(s) => out.push_str(&quote(s)),
            Json::List(items) => {
                out.push('[');
                for (i, v) in items.iter().enumerate() {
                    if i > 0 {
                        out.push(',');
                    }
                    v.write(out);
                }
                out.push(']');
            }
            Json::Obj(pairs) => write_object(out, pairs.iter().map(|(k, v)| (*k, v))),
            Json::Fields(pairs) => write_object(out, pairs.iter().map(|(k, v)| (k.as_str(), v))),
        }
    }

    fn text(&self) -> String {
        let mut s = String::new();
        self.write(&mut s);
        s
    }
}

fn num(v: impl ToString) -> Json {
    Json::Num(v.to_string())
}

/// Uppercase hex, no separators: what `encode` prints and `decode` reads back.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

/// A physical value as JSON number text: exact decimal where one exists, else the nearest
/// double (a unit whose scale has no finite decimal, such as 1/3).
fn physical_text(unit: &Unit, raw: i64) -> String {
    let v = unit.physical(raw);
    let exact = v.to_string();
    if exact.contains('/') {
        format!("{}", v.to_f64())
    } else {
        exact
    }
}

fn text_of(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

fn field_json(p: &Protocol, f: &Field, bit: Option<&BitField>, raw: &Raw) -> Json {
    let v = match raw {
        Raw::Text(t) => return Json::Str(text_of(t)),
        Raw::Int(v) => *v,
    };
    if let Some(b) = bit {
        return match (b.constant, b.unit.and_then(|u| p.units.get(u))) {
            (None, Some(unit)) => Json::Num(physical_text(unit, v)),
            _ => num(v),
        };
    }
    if f.constant.is_some() {
        return num(v);
    }
    if let Some(s) = f.special.iter().find(|s| s.value == v) {
        return Json::Str(s.name.clone());
    }
    if let Some(e) = f.enumeration.and_then(|e| p.enums.get(e)) {
        return match e.values.iter().find(|x| x.value as i64 == v) {
            Some(x) => Json::Str(x.name.clone()),
            None => num(v),
        };
    }
    if let Some(set) = f.flags.and_then(|i| p.flags.get(i)) {
        let bits = v as u64;
        let mut items = Vec::new();
        let mut named = 0u64;
        for flag in &set.bits {
            let mask = 1u64.checked_shl(u32::from(flag.bit)).unwrap_or(0);
            named |= mask;
            if bits & mask != 0 {
                items.push(Json::Str(flag.name.clone()));
            }
        }
        for bit in 0..64u32 {
            let mask = 1u64 << bit;
            if bits & mask != 0 && named & mask == 0 {
                items.push(num(mask));
            }
        }
        return Json::List(items);
    }
    match f.unit.and_then(|u| p.units.get(u)) {
        Some(unit) => Json::Num(physical_text(unit, v)),
        None => num(v),
    }
}

/// The JSON line of a decoded frame; `offset` (stream mode) goes first.
pub fn frame_line(p: &Protocol, frame: &Frame, offset: Option<u64>) -> String {
    let m = p.message(frame.message);
    let mut fields = Vec::new();
    for v in &frame.values {
        let json = match interp::leaf_field(m, &v.name) {
            Some((f, bit)) => field_json(p, f, bit, &v.raw),
            None => match &v.raw {
                Raw::Int(i) => num(i),
                Raw::Text(t) => Json::Str(text_of(t)),
            },
        };
        fields.push((v.name.clone(), json));
    }
    let mut obj = Vec::new();
    if let Some(o) = offset {
        obj.push(("offset", num(o)));
    }
    obj.extend([
        ("protocol", Json::Str(p.name.clone())),
        (
            "direction",
            Json::Str(frame.message.direction.as_str().to_owned()),
        ),
        ("address", num(frame.address)),
        ("code", Json::Str(m.code_hex())),
        ("message", Json::Str(m.name.clone())),
        ("fields", Json::Fields(fields)),
    ]);
    Json::Obj(obj).text()
}

/// The JSON line of a stream event.
pub fn event_line(p: &Protocol, e: &Event) -> String {
    match e {
        Event::Frame { offset, frame, .. } => frame_line(p, frame, Some(*offset)),
        Event::Skipped { offset, bytes } => Json::Obj(vec![
            ("offset", num(offset)),
            ("skipped", num(bytes.len())),
            ("bytes", Json::Str(hex(bytes))),
        ])
        .text(),
        Event::Ambiguous {
            offset,
            bytes,
            candidates,
        } => Json::Obj(vec![
            ("offset", num(offset)),
            (
                "ambiguous",
                Json::List(candidates.iter().map(|c| Json::Str(c.clone())).collect()),
            ),
            ("bytes", Json::Str(hex(bytes))),
        ])
        .text(),
    }
}

/// The commands whose request would settle an ambiguous frame.
fn settling_requests(p: &Protocol, candidates: &[String]) -> Vec<String> {
    let mut names = Vec::new();
    for c in &p.commands {
        let answers = c.responses.iter().any(|(i, _)| {
            p.responses
                .get(*i)
                .is_some_and(|r| candidates.contains(&r.name))
        });
        if answers {
            names.push(c.name.clone());
        }
    }
    names
}

/// Decodes one frame for the CLI: like [`interp::decode`], but an ambiguity says how to settle
/// it, and a `--reply-to` that settles nothing says so.
pub fn decode_frame(
    p: &Protocol,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    wire: &[u8],
) -> Result<Frame, String> {
    match interp::decode(p, direction, None, wire) {
        Ok(f) => Ok(f),
        Err(DecodeError::Ambiguous { candidates }) => {
            let listed = candidates.join(" or ");
            match reply_to {
                None => {
                    let requests = settling_requests(p, &candidates);
                    Err(format!(
                        "ambiguous frame: could be {listed}; only the request it answers tells them apart: give --reply-to {}",
                        if requests.is_empty() {
                            "<command>".to_owned()
                        } else {
                            requests.join(" or --reply-to ")
                        }
                    ))
                }
                Some(cmd) => interp::decode(p, direction, Some(cmd), wire).map_err(|_| {
                    let name = p.commands.get(cmd).map(|c| c.name.as_str()).unwrap_or("?");
                    format!("ambiguous frame: could be {listed}, and {name} (--reply-to) gets none of them")
                }),
            }
        }
        Err(e) => Err(e.to_string()),
    }
}

// ------------------------------------------------------------------------------------ encode

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
    address: serde_json::Number,
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

/// Encodes one JSON line to wire bytes.
pub fn encode_line(p: &Protocol, line: &str) -> Result<Vec<u8>, String> {
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
    let address = match input.address.as_u64().map(u8::try_from) {
        Some(Ok(a)) => a,
        _ => return Err(format!("address {} is not a byte (0..=255)", input.address)),
    };
    let r = find_message(p, &input.message, direction)?;
    let m = p.message(r);
    if let Some(code) = &input.code {
        let bytes = interp::parse_hex(code).map_err(|e| format!("code `{code}`: {e}"))?;
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
            name: name.clone(),
            raw: v,
        });
    }
    interp::encode(p, r, address, &values).map_err(|e| e.to_string())
}

fn find_message(p: &Protocol, name: &str, d: Option<Direction>) -> Result<MessageRef, String> {
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
    p: &Protocol,
    f: &Field,
    bit: Option<&BitField>,
    name: &str,
    raw: &str,
) -> Result<Raw, String> {
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
