//! The contract's lines written straight into a byte buffer, for captures of any size: what
//! [`crate::print`] builds as a value tree and a `String` per line, [`Printer`] writes from a
//! plan made once per spec (every key already quoted, each message's fixed keys already
//! joined), with no allocation per frame once its buffers have grown. `print` stays the
//! reference: the tests hold the two to byte-identical lines for every example of every
//! built-in spec and for noisy captures through both engines (`tests/printer.rs`).

use std::collections::HashMap;

use busspec_model::interp::{Frame, Raw};
use busspec_model::ir::{BitField, Count, Direction, Field, Follows, MessageRef, Relation};
use busspec_model::number::{Num, NumKind};
use busspec_runtime::{FieldValue, Message};

use crate::print::physical_text;
use crate::Spec;

/// A leaf of a message (a whole field, or a packed sub-field) as it prints.
#[derive(Debug, Clone)]
struct Leaf {
    name: String,
    /// `"name":`
    key: String,
    /// Index into the message's fields, and into that field's bits for a sub-field.
    field: usize,
    bit: Option<usize>,
    /// What the spec fixes, for a typed message that leaves it out.
    fixed: Fixed,
    /// How its integer values print.
    form: Form,
    /// The address of the spec's name: an interpreted frame's value borrows it, so a value
    /// is matched to its leaf without comparing the text.
    name_at: usize,
}

/// How a leaf's integer values print, decided once from the spec: what [`push_field`] does
/// with them, where that needs no look at the value.
#[derive(Debug, Clone, Copy)]
enum Form {
    /// The number as it is.
    Int,
    /// Its physical value in the spec's unit of this index.
    Physical(usize),
    /// Special values, an enumeration or flags: [`push_field`] decides.
    Field,
    /// A 64-bit integer or a float: [`push_wide`].
    Wide,
}

impl Form {
    fn of(f: &Field, bit: Option<&BitField>) -> Form {
        if bit.is_none() && f.is_wide() {
            return Form::Wide;
        }
        let unit = match bit {
            Some(b) if b.constant.is_none() => b.unit,
            Some(_) => None,
            None if f.constant.is_some() => None,
            None if !f.special.is_empty() || f.enumeration.is_some() || f.flags.is_some() => {
                return Form::Field
            }
            None => f.unit,
        };
        unit.map_or(Form::Int, Form::Physical)
    }
}

/// What a typed message leaves out of a leaf and the line still prints, as
/// [`crate::message_line`] derives it.
#[derive(Debug, Clone)]
enum Fixed {
    None,
    Constant(i64),
    /// The value of the field of this name (a repeated field).
    Equals(String),
    /// A value following the field of this name (`follows: {field: …}`).
    Follows(String, Relation),
    /// A list's count: its elements (`bytes: false`) or the bytes they take, of the message's
    /// repeated field at this index.
    Count {
        list: usize,
        bytes: bool,
    },
}

/// One message's line, less its address, offset and field values.
#[derive(Debug, Clone)]
struct Plan {
    /// The message's direction ([`side`]), for its line's head ([`Printer::heads`]).
    side: usize,
    /// `,"code":"0x…","message":"…","fields":{`
    tail: String,
    /// A constant whole frame (`frame:`): its line has no `"address"`.
    bare: bool,
    leaves: Vec<Leaf>,
    /// Leaf index by name.
    by_name: HashMap<String, usize>,
}

/// A typed message's field value, held past [`Message::visit`]: text as a range of
/// [`Printer::text`], a list's elements as a range of [`Printer::ints`].
#[derive(Debug, Clone)]
enum Given {
    Int(i64),
    Text(std::ops::Range<usize>),
    List(std::ops::Range<usize>),
}

/// A value the printer writes: a number, text, or a repeated field's elements (each printed
/// as the field's single value would be, as [`crate::print`] does).
#[derive(Debug, Clone, Copy)]
enum Scalar<'a> {
    Int(i64),
    Text(&'a [u8]),
    List(&'a [i64]),
}

/// Writes JSON lines of one spec (see the module docs), each ended by `\n`, to a `Vec<u8>`.
#[derive(Debug, Clone)]
pub struct Printer {
    /// Plans of the requests and of the responses, in spec order.
    plans: [Vec<Plan>; 2],
    /// Message index by name, per direction.
    names: [HashMap<String, usize>; 2],
    /// Per direction and address (256 of them), the line's keys and values from the
    /// protocol to the address: `,"protocol":"…","direction":"…","address":N` (the comma for
    /// after the offset).
    heads: [Vec<String>; 2],
    /// Message index by the address and length of a generated message's `&'static str` name,
    /// per direction: a direct-mapped cache in front of `names`.
    seen: [[(usize, usize, usize); 64]; 2],
    /// Unit index to its fast decimal form ([`Decimal`]), where it has one.
    decimals: Vec<Option<Decimal>>,
    given: Vec<(&'static str, Given)>,
    text: Vec<u8>,
    ints: Vec<i64>,
}

/// A unit whose physical values `raw * scale + offset` are all decimals with at most `places`
/// digits after the point: the value is `(raw * mul + add) / 10^places`, exactly. Printed as
/// [`Rational`]'s `Display` prints it (no trailing zeros, no point for a whole number), with
/// integer arithmetic and no allocation.
#[derive(Debug, Clone, Copy)]
struct Decimal {
    mul: i128,
    add: i128,
    /// `mul` and `add` where both fit an `i64`: most values then need no 128-bit arithmetic.
    small: Option<(i64, i64)>,
    places: u32,
}

impl Decimal {
    fn new(unit: &busspec_model::ir::Unit) -> Option<Decimal> {
        let (scale, offset) = (unit.scale, unit.offset);
        let den = scale.den.checked_mul(offset.den)?;
        let places = busspec_model::rational::decimal_places(den)?;
        let per = 10i128.checked_pow(places)? / den;
        let mul = scale.num.checked_mul(offset.den)?.checked_mul(per)?;
        let add = offset.num.checked_mul(scale.den)?.checked_mul(per)?;
        Some(Decimal {
            mul,
            add,
            small: i64::try_from(mul).ok().zip(i64::try_from(add).ok()),
            places,
        })
    }

    /// `raw * mul + add`, in 64 bits where it fits.
    fn scaled(&self, raw: i64) -> Option<i128> {
        let small = self
            .small
            .and_then(|(mul, add)| raw.checked_mul(mul)?.checked_add(add));
        match small {
            Some(n) => Some(i128::from(n)),
            None => i128::from(raw)
                .checked_mul(self.mul)
                .and_then(|v| v.checked_add(self.add)),
        }
    }

    /// Writes the physical value of `raw`; `false` (nothing written) where it does not fit.
    fn write(&self, out: &mut Vec<u8>, raw: i64) -> bool {
        let Some(n) = self.scaled(raw) else {
            return false;
        };
        let Ok(mut a) = u64::try_from(n.unsigned_abs()) else {
            return false;
        };
        let mut places = self.places;
        while places > 0 && a % 10 == 0 {
            a /= 10;
            places -= 1;
        }
        // 10^19 is the largest power of ten a `u64` holds.
        if places > 19 {
            return false;
        }
        // The digits once, the point put in among them (after a `0.` and zeros where they
        // are fewer than the places).
        let mut digits = itoa::Buffer::new();
        let digits = digits.format(a).as_bytes();
        let places = places as usize;
        out.reserve(digits.len() + places + 3);
        if n < 0 {
            out.push(b'-');
        }
        // Byte by byte: a call to copy a few bytes costs more than they do.
        let put = |out: &mut Vec<u8>, bytes: &[u8]| bytes.iter().for_each(|&b| out.push(b));
        match digits.len().checked_sub(places) {
            _ if places == 0 => put(out, digits),
            Some(whole) if whole > 0 => {
                put(out, &digits[..whole]);
                out.push(b'.');
                put(out, &digits[whole..]);
            }
            _ => {
                out.push(b'0');
                out.push(b'.');
                (digits.len()..places).for_each(|_| out.push(b'0'));
                put(out, digits);
            }
        }
        true
    }
}

/// A physical value as [`physical_text`] prints it, through `decimal` where it fits.
fn push_physical(
    out: &mut Vec<u8>,
    decimal: Option<&Decimal>,
    unit: &busspec_model::ir::Unit,
    raw: i64,
) {
    let at = out.len();
    if !decimal.is_some_and(|d| d.write(out, raw)) {
        out.truncate(at);
        out.extend_from_slice(physical_text(unit, raw).as_bytes());
    }
}

fn quote(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".to_owned())
}

fn side(d: Direction) -> usize {
    match d {
        Direction::Request => 0,
        Direction::Response => 1,
    }
}

fn push_quoted(out: &mut Vec<u8>, s: &str) {
    if s.bytes()
        .all(|b| b >= 0x20 && b != b'"' && b != b'\\' && b < 0x7F)
    {
        out.push(b'"');
        out.extend_from_slice(s.as_bytes());
        out.push(b'"');
    } else if serde_json::to_writer(&mut *out, s).is_err() {
        out.extend_from_slice(b"\"\"");
    }
}

fn push_int(out: &mut Vec<u8>, v: impl itoa::Integer) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// Uppercase hex, no separators (as [`crate::hex`]).
pub fn push_hex(out: &mut Vec<u8>, bytes: &[u8]) {
    const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
    for &b in bytes {
        out.push(DIGITS[usize::from(b >> 4)]);
        out.push(DIGITS[usize::from(b & 0xF)]);
    }
}

/// Text, one character per byte (bytes 0x80..0xFF as U+0080..U+00FF), quoted.
fn push_text(out: &mut Vec<u8>, bytes: &[u8]) {
    let s: String = bytes.iter().map(|&b| char::from(b)).collect();
    push_quoted(out, &s);
}

/// `[a,b,…]`, each element written by `item`.
fn push_list(out: &mut Vec<u8>, items: &[i64], mut item: impl FnMut(&mut Vec<u8>, i64)) {
    out.push(b'[');
    for (i, &v) in items.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        item(out, v);
    }
    out.push(b']');
}

/// A value no leaf of the message describes: the raw number, the text or the numbers.
fn push_plain(out: &mut Vec<u8>, raw: Scalar<'_>) {
    match raw {
        Scalar::Int(v) => push_int(out, v),
        Scalar::Text(t) => push_text(out, t),
        Scalar::List(items) => push_list(out, items, push_int),
    }
}

/// One field value as [`crate::print`]'s `field_json` prints it; `decimals` as in
/// [`Printer`].
fn push_field(
    out: &mut Vec<u8>,
    p: &Spec,
    decimals: &[Option<Decimal>],
    f: &Field,
    bit: Option<&BitField>,
    raw: Scalar,
) {
    let v = match raw {
        Scalar::Text(t) => return push_text(out, t),
        Scalar::List(items) => {
            return push_list(out, items, |out, v| {
                push_field(out, p, decimals, f, bit, Scalar::Int(v))
            })
        }
        Scalar::Int(v) => v,
    };
    if bit.is_none() && f.is_wide() {
        return push_wide(out, f, v);
    }
    let physical = |out: &mut Vec<u8>, u: usize, unit| {
        push_physical(out, decimals.get(u).and_then(Option::as_ref), unit, v)
    };
    if let Some(b) = bit {
        return match (b.constant, b.unit.and_then(|u| Some((u, p.units.get(u)?)))) {
            (None, Some((u, unit))) => physical(out, u, unit),
            _ => push_int(out, v),
        };
    }
    if f.constant.is_some() {
        return push_int(out, v);
    }
    if let Some(s) = f.special.iter().find(|s| s.value == v) {
        return push_quoted(out, &s.name);
    }
    if let Some(e) = f.enumeration.and_then(|e| p.enums.get(e)) {
        return match e.values.iter().find(|x| x.value as i64 == v) {
            Some(x) => push_quoted(out, &x.name),
            None => push_int(out, v),
        };
    }
    if let Some(set) = f.flags.and_then(|i| p.flags.get(i)) {
        let bits = v as u64;
        let mut named = 0u64;
        let mut first = true;
        let mut sep = |out: &mut Vec<u8>| {
            if !std::mem::take(&mut first) {
                out.push(b',');
            }
        };
        out.push(b'[');
        for flag in &set.bits {
            let mask = 1u64.checked_shl(u32::from(flag.bit)).unwrap_or(0);
            named |= mask;
            if bits & mask != 0 {
                sep(out);
                push_quoted(out, &flag.name);
            }
        }
        for bit in 0..64u32 {
            let mask = 1u64 << bit;
            if bits & mask != 0 && named & mask == 0 {
                sep(out);
                push_int(out, mask);
            }
        }
        out.push(b']');
        return;
    }
    match f.unit.and_then(|u| Some((u, p.units.get(u)?))) {
        Some((u, unit)) => physical(out, u, unit),
        None => push_int(out, v),
    }
}

/// A number as a leaf of form `form` prints: as [`push_field`] prints it, without its look
/// at the field where the form already says what that finds.
#[inline(always)]
fn push_form(
    out: &mut Vec<u8>,
    p: &Spec,
    decimals: &[Option<Decimal>],
    form: Form,
    f: &Field,
    bit: Option<&BitField>,
    v: i64,
) {
    match form {
        Form::Int => push_int(out, v),
        // A unit the spec does not have prints the number, as in `push_field`.
        Form::Physical(u) => match p.units.get(u) {
            Some(unit) => push_physical(out, decimals.get(u).and_then(Option::as_ref), unit, v),
            None => push_int(out, v),
        },
        Form::Field => push_field(out, p, decimals, f, bit, Scalar::Int(v)),
        Form::Wide => push_wide(out, f, v),
    }
}

/// A 64-bit integer or float field's value as [`crate::print`]'s `wide_json` prints it.
fn push_wide(out: &mut Vec<u8>, f: &Field, v: i64) {
    let k = f.num_kind();
    match k {
        NumKind::Int => push_int(out, v),
        NumKind::U64 => push_int(out, v as u64),
        _ if k.is_non_finite(v) => push_quoted(out, &k.text(v)),
        _ => {
            use std::io::Write as _;
            let _ = write!(out, "{}", Num(k, v));
        }
    }
}

impl Printer {
    /// The plans of every message of `p`.
    pub fn new(p: &Spec) -> Printer {
        let protocol = quote(&p.name);
        let mut plans: [Vec<Plan>; 2] = [Vec::new(), Vec::new()];
        let mut names: [HashMap<String, usize>; 2] = [HashMap::new(), HashMap::new()];
        for d in [Direction::Request, Direction::Response] {
            for (index, m) in p.messages(d).iter().enumerate() {
                let mut leaves = Vec::new();
                for (fi, f) in m.fields.iter().enumerate() {
                    if f.bits.is_empty() {
                        let fixed = match (f.constant, f.equals, &f.follows) {
                            (Some(c), _, _) => Fixed::Constant(c as i64),
                            (None, Some(i), _) => m
                                .fields
                                .get(i)
                                .map_or(Fixed::None, |e| Fixed::Equals(e.name.clone())),
                            (None, None, Some(Follows::Field(o, rel))) => {
                                m.fields.get(*o).map_or(Fixed::None, |o| {
                                    Fixed::Follows(o.name.clone(), rel.clone())
                                })
                            }
                            _ => match m.counted_by(fi) {
                                Some((list, _, r)) => Fixed::Count {
                                    list,
                                    bytes: matches!(r.count, Count::Bytes(_)),
                                },
                                None => Fixed::None,
                            },
                        };
                        leaves.push((&f.name, fi, None, fixed, Form::of(f, None)));
                    }
                    for (bi, b) in f.bits.iter().enumerate() {
                        let fixed = b
                            .constant
                            .map_or(Fixed::None, |c| Fixed::Constant(c as i64));
                        leaves.push((&b.name, fi, Some(bi), fixed, Form::of(f, Some(b))));
                    }
                }
                let mut by_name = HashMap::new();
                let leaves: Vec<Leaf> = leaves
                    .into_iter()
                    .enumerate()
                    .map(|(i, (name, field, bit, fixed, form))| {
                        // The first leaf of a name, as `interp::leaf_field` finds it.
                        by_name.entry(name.clone()).or_insert(i);
                        Leaf {
                            key: format!("{}:", quote(name)),
                            name: name.clone(),
                            field,
                            bit,
                            fixed,
                            form,
                            name_at: name.as_ptr() as usize,
                        }
                    })
                    .collect();
                names[side(d)].entry(m.name.clone()).or_insert(index);
                plans[side(d)].push(Plan {
                    side: side(d),
                    tail: format!(
                        ",\"code\":{},\"message\":{},\"fields\":{{",
                        quote(&m.code_hex()),
                        quote(&m.name)
                    ),
                    leaves,
                    by_name,
                    bare: m.frame.is_some(),
                });
            }
        }
        let heads = [Direction::Request, Direction::Response].map(|d| {
            let addressed = p.framing.has_address_in(d);
            (0..=u8::MAX)
                .map(|address| {
                    let head = format!(
                        ",\"protocol\":{protocol},\"direction\":{}",
                        quote(d.as_str())
                    );
                    if addressed {
                        format!("{head},\"address\":{address}")
                    } else {
                        head
                    }
                })
                .collect()
        });
        Printer {
            plans,
            heads,
            names,
            seen: [[(0, 0, 0); 64]; 2],
            decimals: p.units.iter().map(Decimal::new).collect(),
            given: Vec::new(),
            text: Vec::new(),
            ints: Vec::new(),
        }
    }

    fn plan(&self, r: MessageRef) -> Option<&Plan> {
        self.plans[side(r.direction)].get(r.index)
    }

    /// `{` and `"offset":N,` in stream mode, the fixed keys and the address, up to the first
    /// field.
    fn open(
        out: &mut Vec<u8>,
        heads: &[Vec<String>; 2],
        plan: &Plan,
        address: u8,
        offset: Option<u64>,
    ) {
        let head = heads
            .get(plan.side)
            .and_then(|h| h.get(usize::from(if plan.bare { 0 } else { address })))
            .map_or(&[][..], |h| h.as_bytes());
        // A constant frame's head without the address (where the protocol's have one).
        let head = match plan.bare {
            true => head.strip_suffix(b",\"address\":0").unwrap_or(head),
            false => head,
        };
        // The digits of the offset, and the braces after the fields.
        out.reserve(head.len() + plan.tail.len() + 32);
        match offset {
            Some(o) => {
                out.extend_from_slice(b"{\"offset\":");
                push_int(out, o);
                out.extend_from_slice(head);
            }
            None => {
                out.push(b'{');
                out.extend_from_slice(head.get(1..).unwrap_or_default());
            }
        }
        out.extend_from_slice(plan.tail.as_bytes());
    }

    /// The line of a frame the interpreter decoded, as [`crate::frame_line`] prints it.
    pub fn frame(&self, out: &mut Vec<u8>, p: &Spec, frame: &Frame, offset: Option<u64>) {
        // Another spec's frame: the reference prints it.
        let reference = |out: &mut Vec<u8>| {
            out.extend_from_slice(crate::frame_line(p, frame, offset).as_bytes());
            out.push(b'\n');
        };
        let (Some(plan), Some(m)) = (
            self.plan(frame.message),
            p.messages(frame.message.direction).get(frame.message.index),
        ) else {
            return reference(out);
        };
        // Records (a list of objects) are printed by the reference printer.
        if m.fields.iter().any(|f| f.is_record()) {
            return reference(out);
        }
        Self::open(out, &self.heads, plan, frame.address, offset);
        for (i, v) in frame.values.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            let raw = match &v.raw {
                Raw::Int(i) => Scalar::Int(*i),
                Raw::Text(t) => Scalar::Text(t),
                Raw::List(items) => Scalar::List(items),
                Raw::Records(_) => Scalar::List(&[]),
            };
            // Values come in leaf order, their names borrowed from the spec the plan was made
            // from; look the name up only where they do not.
            let same = |l: &Leaf| {
                (l.name_at == v.name.as_ptr() as usize && l.name.len() == v.name.len())
                    || l.name == v.name
            };
            let leaf = match plan.leaves.get(i) {
                Some(l) if same(l) => Some(l),
                _ => plan.by_name.get(&*v.name).and_then(|&k| plan.leaves.get(k)),
            };
            Self::value(out, p, &self.decimals, m, leaf, &v.name, raw);
        }
        out.extend_from_slice(b"}}\n");
    }

    /// `"name":value`, by the leaf's plan where the message has one.
    fn value(
        out: &mut Vec<u8>,
        p: &Spec,
        decimals: &[Option<Decimal>],
        m: &busspec_model::ir::Message,
        leaf: Option<&Leaf>,
        name: &str,
        raw: Scalar<'_>,
    ) {
        let found = leaf.and_then(|l| {
            let f = m.fields.get(l.field)?;
            let bit = match l.bit {
                Some(b) => Some(f.bits.get(b)?),
                None => None,
            };
            Some((l, f, bit))
        });
        match found {
            Some((l, f, bit)) => {
                out.extend_from_slice(l.key.as_bytes());
                // A number, or each element of a list, as the leaf's form says.
                match raw {
                    Scalar::Int(v) => push_form(out, p, decimals, l.form, f, bit, v),
                    Scalar::List(items) => push_list(out, items, |out, v| {
                        push_form(out, p, decimals, l.form, f, bit, v)
                    }),
                    Scalar::Text(_) => push_field(out, p, decimals, f, bit, raw),
                }
            }
            None => {
                push_quoted(out, name);
                out.push(b':');
                push_plain(out, raw);
            }
        }
    }

    /// The line of a typed message of a generated protocol, as [`crate::message_line`] prints
    /// it (its error, for a message `p` does not have, too).
    pub fn message<M: Message>(
        &mut self,
        out: &mut Vec<u8>,
        p: &Spec,
        direction: Direction,
        address: u8,
        message: &M,
        offset: Option<u64>,
    ) -> Result<(), String> {
        let name = message.name();
        let key = (name.as_ptr() as usize, name.len());
        let slot = &mut self.seen[side(direction)][(key.0 >> 3) % 64];
        let index = if (slot.0, slot.1) == key && key.0 != 0 {
            Some(slot.2)
        } else {
            let found = self.names[side(direction)].get(name).copied();
            if let Some(i) = found {
                *slot = (key.0, key.1, i);
            }
            found
        };
        let (Some(plan), Some(m)) = (
            index.and_then(|i| self.plans[side(direction)].get(i)),
            index.and_then(|i| p.messages(direction).get(i)),
        ) else {
            return crate::message_line(p, direction, address, message, offset).map(|line| {
                out.extend_from_slice(line.as_bytes());
                out.push(b'\n');
            });
        };
        // Records (a list of objects) are printed by the reference printer.
        if m.fields.iter().any(|f| f.is_record()) {
            return crate::message_line(p, direction, address, message, offset).map(|line| {
                out.extend_from_slice(line.as_bytes());
                out.push(b'\n');
            });
        }
        let (given, text, ints) = (&mut self.given, &mut self.text, &mut self.ints);
        given.clear();
        text.clear();
        ints.clear();
        message.visit(|name, raw| {
            let v = match raw {
                FieldValue::Int(i) => Given::Int(i),
                FieldValue::Text(t) => {
                    let from = text.len();
                    text.extend_from_slice(t);
                    Given::Text(from..text.len())
                }
                FieldValue::List(items) => {
                    let from = ints.len();
                    ints.extend(items.iter());
                    Given::List(from..ints.len())
                }
                // Not reached: a message with records is printed by the reference printer.
                FieldValue::Records(_) => Given::List(0..0),
            };
            given.push((name, v));
        });
        let as_field = |g: &Given| match g {
            Given::Int(i) => Scalar::Int(*i),
            Given::Text(r) => Scalar::Text(text.get(r.clone()).unwrap_or_default()),
            Given::List(r) => Scalar::List(ints.get(r.clone()).unwrap_or_default()),
        };
        let lookup = |name: &str| given.iter().find(|(n, _)| *n == name).map(|(_, v)| v);
        Self::open(out, &self.heads, plan, address, offset);
        let mut first = true;
        // Given fields come in leaf order, less the fixed ones: try the next one first.
        let (mut next, mut matched) = (0, 0);
        // Typed messages leave out what the spec fixes (constants, repeated fields); the
        // contract prints every leaf of the message, as the frame carries it.
        for leaf in &plan.leaves {
            let own = match given.get(next) {
                Some((n, g)) if *n == leaf.name => {
                    next += 1;
                    Some(g)
                }
                _ => lookup(&leaf.name),
            };
            matched += usize::from(own.is_some());
            let value = match own {
                Some(g) => as_field(g),
                None => match &leaf.fixed {
                    Fixed::Constant(c) => Scalar::Int(*c),
                    Fixed::Equals(of) => match lookup(of) {
                        Some(g) => as_field(g),
                        None => continue,
                    },
                    Fixed::Follows(of, rel) => match lookup(of) {
                        Some(Given::Int(v)) => Scalar::Int(rel.apply(*v)),
                        _ => continue,
                    },
                    Fixed::Count { list, bytes } => {
                        let Some(f) = m.fields.get(*list) else {
                            continue;
                        };
                        let Some(Given::List(r)) = lookup(&f.name) else {
                            continue;
                        };
                        let n = if *bytes {
                            f.elements_len(r.len())
                        } else {
                            r.len()
                        };
                        Scalar::Int(n as i64)
                    }
                    Fixed::None => continue,
                },
            };
            if !std::mem::take(&mut first) {
                out.push(b',');
            }
            Self::value(out, p, &self.decimals, m, Some(leaf), &leaf.name, value);
        }
        // Leaf names are unique, so each given field matched at most one leaf.
        if matched < given.len() {
            for (name, g) in given.iter() {
                if !plan.by_name.contains_key(*name) {
                    if !std::mem::take(&mut first) {
                        out.push(b',');
                    }
                    Self::value(out, p, &self.decimals, m, None, name, as_field(g));
                }
            }
        }
        out.extend_from_slice(b"}}\n");
        Ok(())
    }

    /// The stream line of a frame that could be any of `candidates`, as
    /// [`crate::ambiguous_line`] prints it.
    pub fn ambiguous<S: AsRef<str>>(
        out: &mut Vec<u8>,
        offset: u64,
        candidates: &[S],
        bytes: &[u8],
    ) {
        out.extend_from_slice(b"{\"offset\":");
        push_int(out, offset);
        out.extend_from_slice(b",\"ambiguous\":[");
        for (i, c) in candidates.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            push_quoted(out, c.as_ref());
        }
        out.extend_from_slice(b"],\"bytes\":\"");
        push_hex(out, bytes);
        out.extend_from_slice(b"\"}\n");
    }

    /// The stream line of bytes that start no frame, as [`crate::skipped_line`] prints it.
    pub fn skipped(out: &mut Vec<u8>, offset: u64, bytes: &[u8]) {
        out.extend_from_slice(b"{\"offset\":");
        push_int(out, offset);
        out.extend_from_slice(b",\"skipped\":");
        push_int(out, bytes.len());
        out.extend_from_slice(b",\"bytes\":\"");
        push_hex(out, bytes);
        out.extend_from_slice(b"\"}\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use busspec_model::ir::Unit;
    use busspec_model::rational::Rational;

    fn unit(scale: &str, offset: &str) -> Unit {
        Unit {
            name: "u".into(),
            symbol: "u".into(),
            scale: Rational::parse(scale).expect("scale"),
            offset: Rational::parse(offset).expect("offset"),
            doc: String::new(),
        }
    }

    /// Every unit of the built-in specs and units chosen to be awkward print every raw value
    /// as `physical_text` does: through [`Decimal`] where the unit has one, the reference
    /// where it does not or the value does not fit.
    #[test]
    fn physical_values_print_as_the_reference_prints_them() {
        let mut units: Vec<Unit> = Vec::new();
        for (file, text) in [
            ("ub2.yaml", include_str!("../../spec/ub2.yaml")),
            ("sd.yaml", include_str!("../../spec/sd.yaml")),
        ] {
            let p = busspec_model::load_str(file, text).unwrap_or_else(|d| panic!("{d}"));
            units.extend(p.units);
        }
        for (scale, offset) in [
            ("1", "0"),
            ("0.01", "0"),
            ("0.5", "-40"),
            ("360/4096", "0"),
            ("1/3", "0"),
            ("2.5", "0.125"),
            ("-0.001", "273.15"),
            ("1/1048576", "0"),
            ("1/1099511627776", "0"),
            ("123456789012345678", "0"),
            ("0.00000000000000001", "-0.1"),
        ] {
            units.push(unit(scale, offset));
        }
        let mut raws: Vec<i64> = (-1100..=1100).collect();
        raws.extend([
            i64::MIN,
            i64::MIN + 1,
            i64::MAX,
            i64::MAX - 1,
            1 << 40,
            -(1 << 53),
        ]);
        let mut fast = 0;
        for u in &units {
            let decimal = Decimal::new(u);
            fast += usize::from(decimal.is_some());
            for &raw in &raws {
                let mut out = Vec::new();
                push_physical(&mut out, decimal.as_ref(), u, raw);
                assert_eq!(
                    std::str::from_utf8(&out).unwrap(),
                    physical_text(u, raw),
                    "scale {:?} offset {:?} raw {raw}",
                    u.scale,
                    u.offset
                );
            }
        }
        assert!(fast >= units.len() / 2, "{fast} of {} units", units.len());
    }
}
