//! Printing: a frame's JSON line from its message, address and fields (name and raw value).

use busspec_model::interp::{self, Frame, Raw};
use busspec_model::ir::{
    BitField, Count, Direction, Field, Follows, Leaf, Message as IrMessage, MessageRef, Unit,
};
use busspec_runtime::{Elements, FieldValue, Message, RecordList};

use crate::{hex, Spec};

/// A JSON value, written with keys in the order given.
pub(crate) enum Json {
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

    pub(crate) fn text(&self) -> String {
        let mut s = String::new();
        self.write(&mut s);
        s
    }
}

fn num(v: impl ToString) -> Json {
    Json::Num(v.to_string())
}

/// A physical value as JSON number text: exact decimal where one exists, else the nearest
/// double (a unit whose scale has no finite decimal, such as 1/3).
pub(crate) fn physical_text(unit: &Unit, raw: i64) -> String {
    let v = unit.physical(raw);
    let exact = v.to_string();
    if exact.contains('/') {
        format!("{}", v.to_f64())
    } else {
        exact
    }
}

/// A 64-bit integer or float field's value (its raw value is its bits, its unit's scale 1):
/// the number as [`busspec_model::number`] prints it; NaN and the infinities, which JSON has
/// no number for, as that text in a string.
pub(crate) fn wide_json(f: &Field, raw: i64) -> Json {
    let k = f.num_kind();
    let text = k.text(raw);
    if k.is_non_finite(raw) {
        Json::Str(text)
    } else {
        Json::Num(text)
    }
}

fn text_of(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

fn field_json(p: &Spec, f: &Field, bit: Option<&BitField>, raw: FieldValue<'_>) -> Json {
    let v = match raw {
        FieldValue::Text(t) => return Json::Str(text_of(t)),
        FieldValue::List(items) => {
            let items = items
                .iter()
                .map(|i| field_json(p, f, bit, FieldValue::Int(i)));
            return Json::List(items.collect());
        }
        FieldValue::Records(list) => return records_json(p, f, list),
        FieldValue::Int(v) => v,
    };
    if bit.is_none() && f.is_wide() {
        return wide_json(f, v);
    }
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

/// A repeated record's records: a list of objects, each field by its name as a field of its
/// own prints (units as physical values, enums by name).
fn records_json(p: &Spec, f: &Field, list: RecordList<'_>) -> Json {
    Json::List(
        (0..list.len())
            .map(|k| {
                Json::Fields(
                    f.record
                        .iter()
                        .enumerate()
                        .map(|(j, g)| {
                            let v = list.get(k, j).unwrap_or(0);
                            (g.name.clone(), field_json(p, g, None, FieldValue::Int(v)))
                        })
                        .collect(),
                )
            })
            .collect(),
    )
}

/// One field of message `m`, by its spec name and raw value: the engine-neutral core.
fn field(p: &Spec, m: &IrMessage, name: &str, raw: FieldValue<'_>) -> (String, Json) {
    let json = match interp::leaf_field(m, name) {
        Some((f, bit)) => field_json(p, f, bit, raw),
        None => match raw {
            FieldValue::Int(i) => num(i),
            FieldValue::Text(t) => Json::Str(text_of(t)),
            FieldValue::List(items) => Json::List(items.iter().map(num).collect()),
            FieldValue::Records(list) => Json::List(
                (0..list.len())
                    .map(|k| {
                        Json::List(
                            (0..list.fields())
                                .map(|j| num(list.get(k, j).unwrap_or(0)))
                                .collect(),
                        )
                    })
                    .collect(),
            ),
        },
    };
    (name.to_owned(), json)
}

/// A frame's keys, in the contract's order, after `"offset"` (if any); no `"address"` where
/// the protocol's frames carry none, nor for a constant whole frame (`frame:`).
fn frame_keys(
    p: &Spec,
    r: MessageRef,
    address: u8,
    fields: Vec<(String, Json)>,
) -> Vec<(&'static str, Json)> {
    let m = p.message(r);
    let mut keys = vec![
        ("protocol", Json::Str(p.name.clone())),
        ("direction", Json::Str(r.direction.as_str().to_owned())),
    ];
    // A constant whole frame carries no address either, nor a frame of a direction whose
    // layout has none.
    if p.framing.has_address_in(r.direction) && m.frame.is_none() {
        keys.push(("address", num(address)));
    }
    keys.extend([
        ("code", Json::Str(m.code_hex())),
        ("message", Json::Str(m.name.clone())),
        ("fields", Json::Fields(fields)),
    ]);
    keys
}

fn line(
    p: &Spec,
    r: MessageRef,
    address: u8,
    fields: Vec<(String, Json)>,
    offset: Option<u64>,
) -> String {
    let mut obj = Vec::new();
    if let Some(o) = offset {
        obj.push(("offset", num(o)));
    }
    obj.extend(frame_keys(p, r, address, fields));
    Json::Obj(obj).text()
}

/// The printed fields of a frame the interpreter decoded.
fn frame_fields(p: &Spec, frame: &Frame) -> Vec<(String, Json)> {
    let m = p.message(frame.message);
    frame
        .values
        .iter()
        .map(|v| {
            let flat;
            let raw = match &v.raw {
                Raw::Int(i) => FieldValue::Int(*i),
                Raw::Text(t) => FieldValue::Text(t),
                Raw::List(list) => FieldValue::List(Elements::I64(list)),
                Raw::Records(recs) => {
                    flat = recs.concat();
                    FieldValue::Records(RecordList::Flat {
                        values: &flat,
                        fields: m
                            .fields
                            .iter()
                            .find(|f| f.name == v.name)
                            .map_or(0, |f| f.record.len()),
                    })
                }
            };
            field(p, m, &v.name, raw)
        })
        .collect()
}

/// The JSON line of a frame the interpreter decoded; `offset` (stream mode) goes first.
pub fn frame_line(p: &Spec, frame: &Frame, offset: Option<u64>) -> String {
    line(
        p,
        frame.message,
        frame.address,
        frame_fields(p, frame),
        offset,
    )
}

/// The line `decode --lenient` prints for a frame strict decoding refuses only for rules of
/// the spec (a value out of its range, an address outside the allowed ones, a broadcast the
/// command does not accept): the frame's line, values as they decode with those rules lifted,
/// then `"violations"`, each broken rule as strict decoding words it, in the order it checks
/// them (`busspec_model::stream::decode_lenient`).
pub fn lenient_line<S: AsRef<str>>(p: &Spec, frame: &Frame, violations: &[S]) -> String {
    let mut obj: Vec<(&'static str, Json)> =
        frame_keys(p, frame.message, frame.address, frame_fields(p, frame));
    obj.push((
        "violations",
        Json::List(
            violations
                .iter()
                .map(|v| Json::Str(v.as_ref().to_owned()))
                .collect(),
        ),
    ));
    Json::Obj(obj).text()
}

/// The stream line of an out-of-spec frame at `offset` (the stream decoders'
/// `Event::OutOfSpec`): `{"offset":N,"out_of_spec":"<reason>", the frame's keys as a frame's
/// line has them when its values decode with the spec's rules lifted, "bytes":"<hex>"}`.
pub fn out_of_spec_line(
    p: &Spec,
    offset: u64,
    reason: &str,
    frame: Option<&Frame>,
    bytes: &[u8],
) -> String {
    let mut obj = vec![
        ("offset", num(offset)),
        ("out_of_spec", Json::Str(reason.to_owned())),
    ];
    if let Some(f) = frame {
        obj.extend(frame_keys(p, f.message, f.address, frame_fields(p, f)));
    }
    obj.push(("bytes", Json::Str(hex(bytes))));
    Json::Obj(obj).text()
}

/// The JSON line of a typed message of a generated protocol (a `Request` or `Response`, as
/// `direction` says) from `address`; `offset` (stream mode) goes first. `p` is the spec the
/// code was generated from ([`crate::load_spec`]); a message it does not have is an error.
pub fn message_line<M: Message>(
    p: &Spec,
    direction: Direction,
    address: u8,
    message: &M,
    offset: Option<u64>,
) -> Result<String, String> {
    let name = message.name();
    let r = p.find_in(name, direction).ok_or_else(|| {
        format!(
            "{} has no {} `{name}`: the code was generated from another spec",
            p.name,
            direction.as_str()
        )
    })?;
    let m = p.message(r);
    let mut given: Vec<(&'static str, Owned)> = Vec::new();
    message.visit(|name, raw| {
        given.push((
            name,
            match raw {
                FieldValue::Int(i) => Owned::Int(i),
                FieldValue::Text(t) => Owned::Text(t.to_vec()),
                FieldValue::List(items) => Owned::List(items.iter().collect()),
                FieldValue::Records(list) => Owned::Records(
                    (0..list.len())
                        .flat_map(|k| (0..list.fields()).map(move |j| (k, j)))
                        .map(|(k, j)| list.get(k, j).unwrap_or(0))
                        .collect(),
                    list.fields(),
                ),
            },
        ))
    });
    let lookup = |name: &str| given.iter().find(|(n, _)| *n == name).map(|(_, v)| v);
    // Typed messages leave out what the spec fixes (constants, repeated fields) or what follows
    // from the rest (a value following another field, a list's count); the contract prints
    // every leaf of the message, as the frame carries it.
    let derived = |i: usize| -> Option<Owned> {
        let f = m.fields.get(i)?;
        if let Some(Follows::Field(o, rel)) = &f.follows {
            return match lookup(&m.fields.get(*o)?.name)? {
                Owned::Int(v) => Some(Owned::Int(rel.apply(*v))),
                _ => None,
            };
        }
        let (_, rf, r) = m.counted_by(i)?;
        let len = match lookup(&rf.name)? {
            Owned::List(l) => l.len(),
            Owned::Records(l, w) => l.len() / (*w).max(1),
            _ => return None,
        };
        let n = match r.count {
            Count::Bytes(_) => rf.elements_len(len),
            Count::Elements(_) | Count::ToEnd | Count::Until(_) | Count::Fixed(_) => len,
        };
        Some(Owned::Int(n as i64))
    };
    let mut fields = Vec::new();
    for leaf in m.leaves() {
        let name = leaf.name();
        let fixed = match leaf {
            Leaf::Field(i, f) => match (f.constant, f.equals) {
                (Some(c), _) => Some(Owned::Int(c as i64)),
                (None, Some(i)) => m.fields.get(i).and_then(|e| lookup(&e.name)).cloned(),
                (None, None) => derived(i),
            },
            Leaf::Bits(_, _, b) => b.constant.map(|c| Owned::Int(c as i64)),
        };
        if let Some(v) = lookup(name).or(fixed.as_ref()) {
            fields.push(field(p, m, name, v.as_field()));
        }
    }
    for (name, v) in &given {
        if !m.leaves().any(|l| l.name() == *name) {
            fields.push(field(p, m, name, v.as_field()));
        }
    }
    Ok(line(p, r, address, fields, offset))
}

/// A field value held past [`Message::visit`].
#[derive(Clone)]
enum Owned {
    Int(i64),
    Text(Vec<u8>),
    List(Vec<i64>),
    /// Records' raw values, record after record, and the fields to a record.
    Records(Vec<i64>, usize),
}

impl Owned {
    fn as_field(&self) -> FieldValue<'_> {
        match self {
            Owned::Int(i) => FieldValue::Int(*i),
            Owned::Text(t) => FieldValue::Text(t),
            Owned::List(l) => FieldValue::List(Elements::I64(l)),
            Owned::Records(l, w) => FieldValue::Records(RecordList::Flat {
                values: l,
                fields: *w,
            }),
        }
    }
}

/// The stream line of `bytes` at `offset` that start no frame.
pub fn skipped_line(offset: u64, bytes: &[u8]) -> String {
    Json::Obj(vec![
        ("offset", num(offset)),
        ("skipped", num(bytes.len())),
        ("bytes", Json::Str(hex(bytes))),
    ])
    .text()
}

/// The stream line of a frame at `offset` that could be any of `candidates` (message names)
/// and that no request settles.
pub fn ambiguous_line<S: AsRef<str>>(offset: u64, candidates: &[S], bytes: &[u8]) -> String {
    Json::Obj(vec![
        ("offset", num(offset)),
        (
            "ambiguous",
            Json::List(
                candidates
                    .iter()
                    .map(|c| Json::Str(c.as_ref().to_owned()))
                    .collect(),
            ),
        ),
        ("bytes", Json::Str(hex(bytes))),
    ])
    .text()
}
