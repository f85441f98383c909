//! The spec's optional `device:` section: the data a device holds and what each command does to
//! it, so that any spec gets a device simulator ([`crate::sim`], `busspec sim`).
//!
//! ```yaml
//! device:
//!   section: "4.3"                         # where the document describes its data (optional)
//!   spaces:                                # named arrays of elements, addressed from 0
//!     - {name: holding_registers, type: u16, size: 10000}
//!     - {name: coils, type: bit, size: 10000}
//!     - {name: control_table, type: u8, size: 74, initial: [{at: 3, values: [1]}]}
//!   refuse:                                # the refusals every command below gets by default
//!     outside: {fields: {exception_code: illegal_data_address}}  # start + count past the space
//!     invalid: {fields: {exception_code: illegal_data_value}}    # a request that breaks the spec's rules
//!   commands:
//!     - {command: read_holding_registers, reads: holding_registers, start: starting_address, count: quantity, into: registers}
//!     - {command: write_single_register, writes: holding_registers, start: register_address, value: register_value}
//!     - {command: write_multiple_registers, writes: holding_registers, start: starting_address, count: quantity, from: values}
//!     - {command: reg_write, writes: control_table, start: address, from: data, staged: true}
//!     - {command: action, commit: true}    # applies the staged write
//!     - {command: reset, reset: true}      # every space back to its initial values
//!     - {command: sync_write, writes: control_table, start: address, from: blocks, records: {length: data_length}}
//! ```
//!
//! A command **reads** `count` elements (1 without `count`) of a space from the element its
//! `start` field names, into the reply's repeated field `into`; or **writes** its `value`
//! field, or the first `count` elements of its repeated field `from` (all of them without
//! `count`), there. With `records`, `from` is a list of records, each the device's address
//! then `length` elements (`length` a field of the command): a device writes the record that
//! carries its own address, and ignores a request without one. `staged` keeps a write until a
//! command with `commit` applies it (one staged write at a time: a later one replaces it, as
//! Dynamixel's REG_WRITE does, so a request sent twice stages once); `reset` restores every
//! space and drops a staged write.
//! A bit space stores 1 for any non-zero value written.
//!
//! The reply is `reply` where given, else the command's first response that is not a refusal
//! (`kind: nak`). Its fields come from the space (`into`), else from the request field of the
//! same name (a Modbus write's echo), else they take their first valid value (0, the range's
//! minimum, the enum's first value; a reply's list as many zeros as its request asks for).
//!
//! A request whose elements lie outside the space gets the `outside` refusal, one that breaks
//! a rule of the spec (a value out of its range: strict decoding refuses it, lenient decoding
//! tells the command) the `invalid` one; each is `reply` (default: the command's only refusal
//! response, or its reply where it has none, as Dynamixel's status packet) with `fields` (raw numbers, enum and special value names, flag name lists; the
//! rest as above). A command's own `refuse` overrides the section's. Without a refusal the
//! device stays silent, as it does for a frame it cannot decode, one for another address, and a
//! broadcast the command does not answer. Commands the section does not list are answered with
//! their reply and change nothing (a ping).

use std::collections::BTreeSet;

use serde_derive::Deserialize;

use crate::diag::{join, Sink};
use crate::ir::{Field, FieldType, MessageKind, Protocol, ResponseKind};
use crate::model::{NumberText, OpenMap, OpenValue};
use crate::rational::Rational;

/// The most elements a space may hold.
pub const MAX_SPACE: u32 = 1 << 20;

/// The section as written.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Section {
    #[serde(default)]
    pub section: Option<String>,
    pub spaces: Vec<SpaceSpec>,
    #[serde(default)]
    pub refuse: Option<RefuseSpec>,
    #[serde(default)]
    pub commands: Vec<CommandSpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceSpec {
    pub name: String,
    #[serde(rename = "type")]
    pub ty: FieldType,
    pub size: NumberText,
    #[serde(default)]
    pub initial: Vec<InitialSpec>,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    pub at: NumberText,
    pub values: Vec<NumberText>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefuseSpec {
    #[serde(default)]
    pub outside: Option<RefusalSpec>,
    #[serde(default)]
    pub invalid: Option<RefusalSpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefusalSpec {
    #[serde(default)]
    pub reply: Option<String>,
    #[serde(default)]
    pub fields: OpenMap,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CommandSpec {
    pub command: String,
    #[serde(default)]
    pub reads: Option<String>,
    #[serde(default)]
    pub writes: Option<String>,
    #[serde(default)]
    pub start: Option<String>,
    #[serde(default)]
    pub count: Option<String>,
    #[serde(default)]
    pub value: Option<String>,
    #[serde(default)]
    pub from: Option<String>,
    #[serde(default)]
    pub into: Option<String>,
    /// Reply fields a read takes from fixed elements of its space: field name → element.
    #[serde(default)]
    pub at: Option<std::collections::BTreeMap<String, u32>>,
    /// A list of the command's whose elements are device addresses: a device acts and
    /// answers only where it is listed (Dynamixel's SYNC READ).
    #[serde(default)]
    pub listed: Option<String>,
    #[serde(default)]
    pub records: Option<RecordsSpec>,
    #[serde(default)]
    pub staged: bool,
    #[serde(default)]
    pub commit: bool,
    #[serde(default)]
    pub reset: bool,
    #[serde(default)]
    pub reply: Option<String>,
    #[serde(default)]
    pub refuse: Option<RefuseSpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordsSpec {
    pub length: String,
}

/// A space, resolved.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Space {
    pub name: String,
    pub ty: FieldType,
    /// Smallest and largest value an element holds.
    pub min: i64,
    pub max: i64,
    pub size: u32,
    /// Elements that do not start at 0, by index.
    pub initial: Vec<(u32, i64)>,
    pub doc: Option<String>,
}

/// Where a write's elements come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// One scalar field.
    Value(String),
    /// A repeated field, the first `count` elements where the rule has a count.
    List(String),
    /// Records: the device's address, then `length` (a field) elements. `big`: `None` where
    /// the list is plain numbers (the address, then the elements, in turn); for a repeated
    /// record of the address and one number, that number's `length` elements, the first
    /// its most significant where `Some(true)`.
    Records {
        list: String,
        length: String,
        big: Option<bool>,
    },
}

/// What a command does to the device's data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// `count` elements (1 without it) from the element `start` names into the reply's list
    /// `into`, and each of `at`'s reply fields from its fixed element (a field wider than the
    /// space's elements from as many as it takes, in the field's byte order).
    Read {
        space: usize,
        start: Option<String>,
        count: Option<String>,
        into: Option<String>,
        at: Vec<At>,
    },
    Write {
        space: usize,
        start: String,
        count: Option<String>,
        source: Source,
        staged: bool,
    },
    Commit,
    Reset,
    /// Answers and changes nothing.
    Nothing,
}

/// A reply field a read takes from fixed elements of its space.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct At {
    pub field: String,
    /// The first element.
    pub element: u32,
    /// How many elements the field takes, and the bits each gives.
    pub elements: u32,
    pub bits: u32,
    /// The first element is the most significant.
    pub big: bool,
    /// The field is signed: the value is sign-extended from its width.
    pub signed: bool,
}

impl At {
    /// The field's value from its elements, in order.
    pub fn value(&self, elements: &[i64]) -> i64 {
        let mask = (1i64 << self.bits) - 1;
        let mut v: i64 = 0;
        for (k, e) in elements.iter().enumerate() {
            let shift = if self.big {
                self.bits * (self.elements - 1 - k as u32)
            } else {
                self.bits * k as u32
            };
            v |= (e & mask) << shift;
        }
        let width = self.bits * self.elements;
        if self.signed && width < 64 && v >> (width - 1) & 1 == 1 {
            v -= 1i64 << width;
        }
        v
    }
}

/// A refusal: the response (index into `Protocol::responses`) and the values it states.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    pub reply: usize,
    pub values: Vec<(String, i64)>,
}

/// One command's rule.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rule {
    pub action: Action,
    /// The command's list of device addresses where a device acts and answers only if it is
    /// listed.
    pub listed: Option<String>,
    /// The reply it sends (index into `Protocol::responses`), if it gets one.
    pub reply: Option<usize>,
    pub outside: Option<Refusal>,
    pub invalid: Option<Refusal>,
}

/// The section, resolved: one rule per command, in the order of `Protocol::commands`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Device {
    /// The spec has the section.
    pub declared: bool,
    pub section: Option<String>,
    pub spaces: Vec<Space>,
    pub rules: Vec<Rule>,
}

impl Device {
    pub fn space(&self, name: &str) -> Option<usize> {
        self.spaces.iter().position(|s| s.name == name)
    }
}

/// The range of values an element of `ty` holds, if a space may hold it.
fn element_range(ty: FieldType) -> Option<(i64, i64)> {
    Some(match ty {
        FieldType::Bit => (0, 1),
        FieldType::U8 => (0, 0xFF),
        FieldType::U16 => (0, 0xFFFF),
        FieldType::U24 => (0, 0xFF_FFFF),
        FieldType::U32 => (0, 0xFFFF_FFFF),
        FieldType::I8 => (-0x80, 0x7F),
        FieldType::I16 => (-0x8000, 0x7FFF),
        FieldType::I24 => (-0x80_0000, 0x7F_FFFF),
        FieldType::I32 => (-0x8000_0000, 0x7FFF_FFFF),
        _ => return None,
    })
}

/// The bits one element of a space of `ty` takes.
pub fn element_bits(ty: FieldType) -> u32 {
    match ty {
        FieldType::Bit => 1,
        FieldType::U8 | FieldType::I8 => 8,
        FieldType::U16 | FieldType::I16 => 16,
        FieldType::U24 | FieldType::I24 => 24,
        _ => 32,
    }
}

/// A whole number, or why not.
fn whole(n: &NumberText) -> Result<i64, String> {
    let r = Rational::parse(&n.0)?;
    if !r.is_integer() {
        return Err(format!("{} is not a whole number", n.0));
    }
    i64::try_from(r.round()).map_err(|_| format!("{} is out of range", n.0))
}

/// The rule of a command the section does not list: its reply, nothing else.
fn default_rule(p: &Protocol, command: usize) -> Rule {
    Rule {
        action: Action::Nothing,
        listed: None,
        reply: first_reply(p, command),
        outside: None,
        invalid: None,
    }
}

/// The command's first response that is not a refusal, else its first.
fn first_reply(p: &Protocol, command: usize) -> Option<usize> {
    let c = &p.commands[command];
    c.responses
        .iter()
        .map(|(i, _)| *i)
        .find(|&i| !is_nak(&p.responses[i]))
        .or_else(|| c.responses.first().map(|(i, _)| *i))
}

fn is_nak(m: &crate::ir::Message) -> bool {
    matches!(m.kind, MessageKind::Response(ResponseKind::Nak))
}

/// A field of `m` by name, top level (not a packed sub-field).
fn field<'a>(m: &'a crate::ir::Message, name: &str) -> Option<&'a Field> {
    m.fields.iter().find(|f| f.name == name)
}

/// Validates the section against the resolved protocol; errors located under `device`.
pub fn validate(section: Option<&Section>, p: &Protocol, sink: &mut Sink) -> Device {
    let mut d = Device {
        rules: (0..p.commands.len()).map(|i| default_rule(p, i)).collect(),
        ..Device::default()
    };
    let Some(s) = section else {
        return d;
    };
    let root = "device";
    d.declared = true;
    if let Some(sec) = &s.section {
        if sec.trim().is_empty() {
            sink.error(join(root, "section"), "section is empty");
        }
        d.section = Some(sec.clone());
    }
    if s.spaces.is_empty() {
        sink.error(join(root, "spaces"), "a device needs at least one space");
    }
    for (i, sp) in s.spaces.iter().enumerate() {
        let path = join(&join(root, "spaces"), &format!("[{i}]"));
        if s.spaces[..i].iter().any(|o| o.name == sp.name) {
            sink.error(
                join(&path, "name"),
                format!("space `{}` is declared twice", sp.name),
            );
        }
        let Some((min, max)) = element_range(sp.ty) else {
            sink.error(
                join(&path, "type"),
                "a space holds integers or bits (u8..u32, i8..i32, bit)",
            );
            continue;
        };
        let size = match whole(&sp.size) {
            Ok(n) if (1..=i64::from(MAX_SPACE)).contains(&n) => n as u32,
            Ok(n) => {
                sink.error(
                    join(&path, "size"),
                    format!("size {n}: a space holds 1 to {MAX_SPACE} elements"),
                );
                continue;
            }
            Err(e) => {
                sink.error(join(&path, "size"), e);
                continue;
            }
        };
        let mut initial = Vec::new();
        for (k, init) in sp.initial.iter().enumerate() {
            let ipath = join(&join(&path, "initial"), &format!("[{k}]"));
            let at = match whole(&init.at) {
                Ok(a) if a >= 0 && a < i64::from(size) => a as u32,
                Ok(a) => {
                    sink.error(
                        join(&ipath, "at"),
                        format!("element {a} is outside the space (0..{size})"),
                    );
                    continue;
                }
                Err(e) => {
                    sink.error(join(&ipath, "at"), e);
                    continue;
                }
            };
            if u64::from(at) + init.values.len() as u64 > u64::from(size) {
                sink.error(
                    join(&ipath, "values"),
                    format!(
                        "{} values from element {at} run past the space's {size} elements",
                        init.values.len()
                    ),
                );
                continue;
            }
            for (j, v) in init.values.iter().enumerate() {
                match whole(v) {
                    Ok(v) if (min..=max).contains(&v) => {
                        let at = at + j as u32;
                        initial.retain(|(a, _)| *a != at);
                        initial.push((at, v));
                    }
                    Ok(v) => sink.error(
                        join(&join(&ipath, "values"), &format!("[{j}]")),
                        format!("{v} does not fit an element ({min}..={max})"),
                    ),
                    Err(e) => sink.error(join(&join(&ipath, "values"), &format!("[{j}]")), e),
                }
            }
        }
        initial.sort_unstable();
        d.spaces.push(Space {
            name: sp.name.clone(),
            ty: sp.ty,
            min,
            max,
            size,
            initial,
            doc: sp.doc.clone(),
        });
    }

    let defaults = s.refuse.clone().unwrap_or_default();
    let mut listed = BTreeSet::new();
    for (i, c) in s.commands.iter().enumerate() {
        let path = join(&join(root, "commands"), &format!("[{i}]"));
        let Some(ci) = p.commands.iter().position(|m| m.name == c.command) else {
            sink.error(
                join(&path, "command"),
                format!("unknown command `{}`", c.command),
            );
            continue;
        };
        if !listed.insert(ci) {
            sink.error(
                join(&path, "command"),
                format!("`{}` is listed twice", c.command),
            );
            continue;
        }
        if let Some(rule) = command_rule(p, &d, ci, c, &defaults, &path, sink) {
            d.rules[ci] = rule;
        }
    }
    d
}

fn command_rule(
    p: &Protocol,
    d: &Device,
    ci: usize,
    c: &CommandSpec,
    defaults: &RefuseSpec,
    path: &str,
    sink: &mut Sink,
) -> Option<Rule> {
    let m = &p.commands[ci];
    let before = sink.items.len();
    let kinds = [c.reads.is_some(), c.writes.is_some(), c.commit, c.reset]
        .iter()
        .filter(|&&b| b)
        .count();
    if kinds > 1 {
        sink.error(
            path,
            "a command reads, writes, commits or resets: one of them",
        );
        return None;
    }
    let reply = match &c.reply {
        Some(name) => {
            let r = response_of(p, ci, name, &join(path, "reply"), sink)?;
            Some(r)
        }
        None => first_reply(p, ci),
    };
    // A scalar integer field of the command.
    let scalar = |key: &str, name: &Option<String>, sink: &mut Sink| -> Option<Option<String>> {
        let Some(name) = name else {
            return Some(None);
        };
        match field(m, name) {
            Some(f) if f.repeat.is_none() && !f.is_ascii() && f.bits.is_empty() => {
                Some(Some(name.clone()))
            }
            Some(_) => {
                sink.error(
                    join(path, key),
                    format!("`{name}` of `{}` is not a single number", m.name),
                );
                None
            }
            None => {
                sink.error(
                    join(path, key),
                    format!("`{}` has no field `{name}`", m.name),
                );
                None
            }
        }
    };
    let space = |key: &str, name: &str, sink: &mut Sink| -> Option<usize> {
        let s = d.space(name);
        if s.is_none() {
            sink.error(join(path, key), format!("unknown space `{name}`"));
        }
        s
    };
    let start = scalar("start", &c.start, sink)?;
    let count = scalar("count", &c.count, sink)?;
    let value = scalar("value", &c.value, sink)?;
    let stray = |key: &str, present: bool, sink: &mut Sink| {
        if present {
            sink.error(
                join(path, key),
                format!("`{key}` belongs to a read or a write"),
            );
        }
    };
    let action = if let Some(sp) = &c.reads {
        let space = space("reads", sp, sink)?;
        stray("value", value.is_some(), sink);
        stray("from", c.from.is_some(), sink);
        stray("records", c.records.is_some(), sink);
        stray("staged", c.staged, sink);
        let at = c.at.clone().unwrap_or_default();
        match (&start, &c.into) {
            (None, None) if at.is_empty() => {
                sink.error(
                    path,
                    "a read needs `start` and `into` (the reply's list it fills), or `at` (reply fields from fixed elements)",
                );
                return None;
            }
            (Some(_), None) => {
                sink.error(path, "a read needs `into`, the reply's list it fills");
                return None;
            }
            (None, Some(_)) => {
                sink.error(path, "a read needs `start`");
                return None;
            }
            _ => {}
        }
        if c.into.is_none() {
            stray("count", count.is_some(), sink);
        }
        let Some(r) = reply else {
            sink.error(path, format!("`{}` gets no reply to read into", m.name));
            return None;
        };
        let rm = &p.responses[r];
        if let Some(into) = &c.into {
            match field(rm, into) {
                Some(f) if f.is_record() => {
                    sink.error(
                        join(path, "into"),
                        format!(
                            "`{}.{into}` is a repeated record; a space's elements are numbers",
                            rm.name
                        ),
                    );
                    return None;
                }
                Some(f) if f.repeat.is_some() => {}
                _ => {
                    sink.error(
                        join(path, "into"),
                        format!("`{}` has no repeated field `{into}`", rm.name),
                    );
                    return None;
                }
            }
        }
        let sp = &d.spaces[space];
        let elem_bits = element_bits(sp.ty);
        let mut fixed = Vec::new();
        for (name, &element) in &at {
            let key = join(&join(path, "at"), name);
            let f = match field(rm, name) {
                Some(f)
                    if f.repeat.is_none()
                        && !f.is_ascii()
                        && !f.is_float()
                        && f.bits.is_empty()
                        && f.constant.is_none()
                        && f.width <= 4 =>
                {
                    f
                }
                Some(_) => {
                    sink.error(
                        key,
                        format!(
                            "`{}.{name}` is not a single integer of up to 4 bytes",
                            rm.name
                        ),
                    );
                    continue;
                }
                None => {
                    sink.error(key, format!("`{}` has no field `{name}`", rm.name));
                    continue;
                }
            };
            let field_bits = 8 * f.width as u32;
            let (elements, bits) = if sp.ty == FieldType::Bit || elem_bits >= field_bits {
                (1, field_bits.min(elem_bits))
            } else if field_bits % elem_bits == 0 {
                (field_bits / elem_bits, elem_bits)
            } else {
                sink.error(
                    key,
                    format!(
                        "`{}.{name}` ({} bytes) is no whole number of `{}`'s elements",
                        rm.name, f.width, sp.name
                    ),
                );
                continue;
            };
            if u64::from(element) + u64::from(elements) > u64::from(sp.size) {
                let what = match elements {
                    1 => format!("element {element} is"),
                    n => format!(
                        "elements {element} to {} are",
                        u64::from(element) + u64::from(n) - 1
                    ),
                };
                sink.error(
                    key,
                    format!(
                        "{what} past the end of `{}` ({} elements)",
                        sp.name, sp.size
                    ),
                );
                continue;
            }
            fixed.push(At {
                field: name.clone(),
                element,
                elements,
                bits,
                big: f.byte_order == crate::model::ByteOrder::Big,
                signed: f.signed,
            });
        }
        Action::Read {
            space,
            start,
            count,
            into: c.into.clone(),
            at: fixed,
        }
    } else if let Some(sp) = &c.writes {
        let space = space("writes", sp, sink)?;
        let Some(start) = start else {
            sink.error(path, "a write needs `start`");
            return None;
        };
        stray("into", c.into.is_some(), sink);
        if c.at.is_some() {
            sink.error(join(path, "at"), "`at` belongs to a read");
        }
        let list = |name: &str, key: &str, sink: &mut Sink| match field(m, name) {
            Some(f) if f.is_record() => {
                sink.error(
                    join(path, key),
                    format!(
                        "`{}.{name}` is a repeated record; a space's elements are numbers",
                        m.name
                    ),
                );
                false
            }
            Some(f) if f.repeat.is_some() => true,
            _ => {
                sink.error(
                    join(path, key),
                    format!("`{}` has no repeated field `{name}`", m.name),
                );
                false
            }
        };
        let source = match (&value, &c.from, &c.records) {
            (Some(v), None, None) => {
                stray("count", count.is_some(), sink);
                Source::Value(v.clone())
            }
            (None, Some(from), None) => {
                if !list(from, "from", sink) {
                    return None;
                }
                Source::List(from.clone())
            }
            (None, Some(from), Some(rec)) => {
                // A repeated record of the device's address and its data (Dynamixel 2.0's
                // SYNC WRITE blocks), or a plain list of both in turn (1.0's).
                let data = match field(m, from) {
                    Some(f) if f.is_record() => {
                        let whole = |x: &Field| !x.is_ascii() && !x.is_float() && x.bits.is_empty();
                        match &f.record[..] {
                            [a, d] if whole(a) && whole(d) && d.width <= 4 => {
                                Some(d.byte_order == crate::model::ByteOrder::Big)
                            }
                            _ => {
                                sink.error(
                                    join(path, "from"),
                                    format!(
                                        "`{}.{from}`'s records are not a device's address and its data: two integer fields",
                                        m.name
                                    ),
                                );
                                return None;
                            }
                        }
                    }
                    _ => {
                        if !list(from, "from", sink) {
                            return None;
                        }
                        None
                    }
                };
                stray("count", count.is_some(), sink);
                let length = scalar("records", &Some(rec.length.clone()), sink)??;
                Source::Records {
                    list: from.clone(),
                    length,
                    big: data,
                }
            }
            (None, None, Some(_)) => {
                sink.error(path, "`records` needs `from`, the list of records");
                return None;
            }
            _ => {
                sink.error(
                    path,
                    "a write takes its elements from `value` (one field) or `from` (a list): one of them",
                );
                return None;
            }
        };
        Action::Write {
            space,
            start,
            count,
            source,
            staged: c.staged,
        }
    } else {
        for (key, present) in [
            ("start", start.is_some()),
            ("count", count.is_some()),
            ("value", value.is_some()),
            ("from", c.from.is_some()),
            ("into", c.into.is_some()),
            ("at", c.at.is_some()),
            ("records", c.records.is_some()),
            ("staged", c.staged),
        ] {
            stray(key, present, sink);
        }
        if c.commit {
            Action::Commit
        } else if c.reset {
            Action::Reset
        } else {
            Action::Nothing
        }
    };
    let own = c.refuse.clone().unwrap_or_default();
    let mut pick = |key: &str, mine: &Option<RefusalSpec>, default: &Option<RefusalSpec>| {
        let (spec, at) = match (mine, default) {
            (Some(r), _) => (r, join(&join(path, "refuse"), key)),
            (None, Some(r)) => (r, join(&join("device", "refuse"), key)),
            (None, None) => return None,
        };
        refusal(p, ci, spec, &at, sink)
    };
    let outside = pick("outside", &own.outside, &defaults.outside);
    let invalid = pick("invalid", &own.invalid, &defaults.invalid);
    if let Some(l) = &c.listed {
        match field(m, l) {
            Some(f) if f.repeat.is_some() && !f.is_record() && f.packed.is_none() => {}
            _ => sink.error(
                join(path, "listed"),
                format!("`{}` has no repeated field `{l}` of addresses", m.name),
            ),
        }
        if !p.framing.has_address() {
            sink.error(
                join(path, "listed"),
                format!("`{}`'s frames carry no address to be listed", p.name),
            );
        }
    }
    (sink.items.len() == before).then_some(Rule {
        action,
        listed: c.listed.clone(),
        reply,
        outside,
        invalid,
    })
}

/// A response of command `ci` by name.
fn response_of(p: &Protocol, ci: usize, name: &str, path: &str, sink: &mut Sink) -> Option<usize> {
    let c = &p.commands[ci];
    match c
        .responses
        .iter()
        .map(|(i, _)| *i)
        .find(|&i| p.responses[i].name == name)
    {
        Some(i) => Some(i),
        None => {
            sink.error(
                path,
                format!("`{name}` is not a response `{}` gets", c.name),
            );
            None
        }
    }
}

fn refusal(
    p: &Protocol,
    ci: usize,
    r: &RefusalSpec,
    path: &str,
    sink: &mut Sink,
) -> Option<Refusal> {
    let c = &p.commands[ci];
    let reply = match &r.reply {
        Some(name) => response_of(p, ci, name, &join(path, "reply"), sink)?,
        None => {
            let naks: Vec<usize> = c
                .responses
                .iter()
                .map(|(i, _)| *i)
                .filter(|&i| is_nak(&p.responses[i]))
                .collect();
            match (naks.as_slice(), first_reply(p, ci)) {
                (&[one], _) => one,
                (&[], Some(first)) => first,
                _ => {
                    sink.error(
                        path,
                        format!(
                            "`{}` has {} refusal responses: name the reply",
                            c.name,
                            naks.len()
                        ),
                    );
                    return None;
                }
            }
        }
    };
    let m = &p.responses[reply];
    let mut values = Vec::new();
    for (k, v) in r.fields.iter() {
        let Some(name) = k.as_str() else {
            sink.error(join(path, "fields"), "field names are text");
            continue;
        };
        let fpath = join(&join(path, "fields"), name);
        let Some((f, bits)) = crate::interp::leaf_field(m, name) else {
            sink.error(fpath, format!("`{}` has no field `{name}`", m.name));
            continue;
        };
        match raw_value(p, f, bits.is_some(), v) {
            Ok(raw) => values.push((name.to_owned(), raw)),
            Err(e) => sink.error(fpath, e),
        }
    }
    Some(Refusal { reply, values })
}

/// A stated value as the raw number it is: a whole raw number, an enum or special value's
/// name, or a list of flag names.
fn raw_value(p: &Protocol, f: &Field, packed: bool, v: &OpenValue) -> Result<i64, String> {
    match v {
        OpenValue::Number(t) => whole(&NumberText(t.clone())),
        OpenValue::String(name) if !packed => {
            if let Some(e) = f.enumeration.map(|e| &p.enums[e]) {
                if let Some(v) = e.values.iter().find(|v| &v.name == name) {
                    return Ok(v.value as i64);
                }
                return Err(format!("`{name}` is not a value of enum `{}`", e.name));
            }
            match f.special.iter().find(|s| &s.name == name) {
                Some(s) => Ok(s.value),
                None => Err(format!("`{name}` is not a named value of this field")),
            }
        }
        OpenValue::List(names) if !packed && f.flags.is_some() => {
            let fs = &p.flags[f.flags.unwrap_or_default()];
            let mut raw = 0i64;
            for n in names {
                let OpenValue::String(n) = n else {
                    return Err("a flag field takes a list of flag names".to_owned());
                };
                match fs.bits.iter().find(|b| &b.name == n) {
                    Some(b) => raw |= 1 << b.bit,
                    None => return Err(format!("`{n}` is not a flag of `{}`", fs.name)),
                }
            }
            Ok(raw)
        }
        _ => Err(
            "state a raw number, an enum or special value's name, or a list of flag names"
                .to_owned(),
        ),
    }
}

/// The reference section of the Markdown docs ("Device model"), or nothing.
pub fn render(p: &Protocol) -> String {
    let d = &p.device;
    if !d.declared {
        return String::new();
    }
    let mut o = String::from("\n## Device model\n\n");
    if let Some(s) = &d.section {
        o.push_str(&format!("Section {s}. "));
    }
    o.push_str("What a device holds, and what each command does to it (`busspec sim`).\n\n");
    o.push_str("| space | elements | each |\n|---|---|---|\n");
    for s in &d.spaces {
        o.push_str(&format!(
            "| `{}` | {} | {}..={} |\n",
            s.name, s.size, s.min, s.max
        ));
    }
    o.push_str("\n| command | does | reply | refused when |\n|---|---|---|---|\n");
    for (i, r) in d.rules.iter().enumerate() {
        let Some(does) = does(d, r) else {
            continue;
        };
        let reply = r
            .reply
            .map_or("none".to_owned(), |x| format!("`{}`", p.responses[x].name));
        let mut refused = Vec::new();
        if let Some(x) = &r.outside {
            refused.push(format!("outside: `{}`", p.responses[x.reply].name));
        }
        if let Some(x) = &r.invalid {
            refused.push(format!("invalid: `{}`", p.responses[x.reply].name));
        }
        o.push_str(&format!(
            "| `{}` | {does} | {reply} | {} |\n",
            p.commands[i].name,
            if refused.is_empty() {
                "—".to_owned()
            } else {
                refused.join("; ")
            }
        ));
    }
    o
}

/// What a rule does, in words; `None` for a command that changes nothing.
fn does(d: &Device, r: &Rule) -> Option<String> {
    let listed = r
        .listed
        .as_ref()
        .map(|l| format!(" (only a device listed in `{l}` acts and answers)"));
    let text = does_action(d, r)?;
    Some(text + listed.as_deref().unwrap_or(""))
}

fn does_action(d: &Device, r: &Rule) -> Option<String> {
    Some(match &r.action {
        Action::Nothing => return None,
        Action::Read {
            space,
            start,
            count,
            into,
            at,
        } => {
            let name = &d.spaces[*space].name;
            let mut parts = Vec::new();
            if let (Some(start), Some(into)) = (start, into) {
                let n = count
                    .as_deref()
                    .map_or("1".to_owned(), |c| format!("`{c}`"));
                parts.push(format!(
                    "reads {n} of `{name}` from `{start}` into `{into}`"
                ));
            }
            for a in at {
                let what = if a.elements == 1 {
                    format!("element {}", a.element)
                } else {
                    format!("elements {} to {}", a.element, a.element + a.elements - 1)
                };
                parts.push(format!("reads `{}` from {what} of `{name}`", a.field));
            }
            parts.join("; ")
        }
        Action::Write {
            space,
            start,
            source,
            staged,
            ..
        } => {
            let what = match source {
                Source::Value(v) => format!("`{v}`"),
                Source::List(l) => format!("`{l}`"),
                Source::Records { list, .. } => format!("its record in `{list}`"),
            };
            format!(
                "{} {what} to `{}` at `{start}`",
                if *staged { "stages" } else { "writes" },
                d.spaces[*space].name
            )
        }
        Action::Commit => "applies the staged write".to_owned(),
        Action::Reset => "restores every space".to_owned(),
    })
}

/// A rule in words, with the names of its replies: what two revisions compare.
fn rule_text(p: &Protocol, r: &Rule) -> String {
    let name = |i: usize| p.responses.get(i).map_or("?", |m| m.name.as_str());
    let refusal = |x: &Option<Refusal>| {
        x.as_ref()
            .map(|x| format!("{} {:?}", name(x.reply), x.values))
    };
    format!(
        "{:?}; reply {:?}; outside {:?}; invalid {:?}",
        does(&p.device, r),
        r.reply.map(name),
        refusal(&r.outside),
        refusal(&r.invalid)
    )
}

/// What changed between two device models, for `busspec diff`: each as (path, text). None of
/// it changes a frame; it changes what the simulator answers.
pub fn diff(old_p: &Protocol, new_p: &Protocol) -> Vec<(String, String)> {
    let (old, new) = (&old_p.device, &new_p.device);
    let mut out = Vec::new();
    if !old.declared && !new.declared {
        return out;
    }
    if old.declared != new.declared {
        out.push((
            "device".to_owned(),
            if new.declared {
                "device model added".to_owned()
            } else {
                "device model removed".to_owned()
            },
        ));
        return out;
    }
    for s in &old.spaces {
        match new.spaces.iter().find(|n| n.name == s.name) {
            None => out.push((
                format!("device.spaces.{}", s.name),
                "space removed".to_owned(),
            )),
            Some(n) if n != s => out.push((
                format!("device.spaces.{}", s.name),
                format!(
                    "space changed: {} × {}..={} → {} × {}..={}",
                    s.size, s.min, s.max, n.size, n.min, n.max
                ),
            )),
            Some(_) => {}
        }
    }
    for n in &new.spaces {
        if !old.spaces.iter().any(|s| s.name == n.name) {
            out.push((
                format!("device.spaces.{}", n.name),
                "space added".to_owned(),
            ));
        }
    }
    for (i, c) in new_p.commands.iter().enumerate() {
        let now = rule_text(new_p, &new.rules[i]);
        let was = old_p
            .commands
            .iter()
            .position(|o| o.name == c.name)
            .map(|j| rule_text(old_p, &old.rules[j]));
        if was.is_some_and(|w| w != now) {
            out.push((
                format!("device.commands.{}", c.name),
                format!("what `{}` does to the device changed", c.name),
            ));
        }
    }
    out
}
