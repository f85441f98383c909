//! What changed between two revisions of a spec, and what each change breaks.
//!
//! Both sides are validated IR, so offsets, widths, byte orders and scales are already resolved
//! and compared as the wire sees them. Every change gets one [`Category`]:
//!
//! - **wire-breaking**: a peer built from the old spec reads or writes some frame differently:
//!   a code removed, changed or reused; a field's offset, width, signedness, byte order, scale,
//!   packing or constant changed; an enum, flag or special value removed or renumbered; a reply
//!   a command may get removed; the checksum, framing, address range or serial settings changed;
//!   a frame's length changed.
//! - **API-breaking**: the bytes mean the same, but code written against the old generated crate
//!   or JSON contract must change: a message, field, unit, enum or value renamed; a field's type
//!   changed without a wire change (a raw number becoming an enum); a range narrowed; a unit or
//!   enum removed.
//! - **compatible**: a command, response, reply, enum value or flag added, a range widened, or
//!   documentation changed (titles, docs, sections, examples, errata, provenance).
//!
//! Messages are matched by name first, then by direction and code (with any constant selector
//! fields), so a renamed message is one change, not a removal and an addition; fields are
//! matched by offset. A message that keeps its code but gets another name *and* another layout
//! is reported as a reused code.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use serde_derive::Serialize;

use crate::ir::{Direction, Enum, Field, FlagSet, Message, Protocol, Unit};
use crate::number::NumKind;
use crate::rational::Rational;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Category {
    WireBreaking,
    ApiBreaking,
    Compatible,
}

impl Category {
    pub const ALL: [Category; 3] = [
        Category::WireBreaking,
        Category::ApiBreaking,
        Category::Compatible,
    ];

    /// The name used in output and in JSON: `wire-breaking`, `api-breaking`, `compatible`.
    pub fn as_str(self) -> &'static str {
        match self {
            Category::WireBreaking => "wire-breaking",
            Category::ApiBreaking => "api-breaking",
            Category::Compatible => "compatible",
        }
    }

    fn heading(self) -> &'static str {
        match self {
            Category::WireBreaking => "Wire-breaking",
            Category::ApiBreaking => "API-breaking",
            Category::Compatible => "Compatible",
        }
    }
}

/// One change between two specs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Change {
    pub category: Category,
    /// A stable identifier of what changed (`message_renamed`, `field_width_changed`, ...).
    pub kind: &'static str,
    /// Where, in the spec's path notation; names are the new spec's where the item still exists.
    pub path: String,
    /// The change in words, naming both sides.
    pub text: String,
}

/// Every change from `old` to `new`, in spec order: document, serial, framing, units, enums,
/// flags, commands, responses, examples, errata.
pub fn diff(old: &Protocol, new: &Protocol) -> Vec<Change> {
    let mut d = Differ {
        old,
        new,
        out: Vec::new(),
    };
    d.protocol();
    d.serial();
    d.transactions();
    d.device();
    d.framing();
    let units = d.units();
    let enums = d.enums();
    let flags = d.flag_sets();
    let maps = Maps {
        units,
        enums,
        flags,
        messages: BTreeMap::new(),
    };
    let mut maps = maps;
    for dir in [Direction::Request, Direction::Response] {
        let pairs = d.messages(dir, &maps);
        maps.messages.insert(dir, pairs);
    }
    d.replies(&maps);
    d.examples();
    d.errata();
    d.out
}

/// Counts per category.
pub fn counts(changes: &[Change]) -> BTreeMap<Category, usize> {
    let mut c: BTreeMap<Category, usize> = Category::ALL.iter().map(|&c| (c, 0)).collect();
    for ch in changes {
        *c.entry(ch.category).or_default() += 1;
    }
    c
}

/// One side of a diff as the renderers show it.
#[derive(Debug, Clone, Serialize)]
pub struct Side {
    pub file: String,
    pub protocol: String,
    pub document: String,
    pub revision: String,
    pub date: String,
    pub spec_sha256: String,
}

impl Side {
    pub fn of(file: &str, p: &Protocol) -> Side {
        Side {
            file: file.to_owned(),
            protocol: p.name.clone(),
            document: p.document.title.clone(),
            revision: p.document.revision.clone(),
            date: p.document.date.clone(),
            spec_sha256: p.spec_sha256.clone(),
        }
    }

    fn short_hash(&self) -> &str {
        self.spec_sha256.get(..12).unwrap_or(&self.spec_sha256)
    }
}

/// The human-readable report: a header naming both sides, the counts, then the changes grouped
/// by category, each as `path: text`.
pub fn render_text(old: &Side, new: &Side, changes: &[Change]) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "{}: {} (rev {}, {}, sha256 {}) → {} (rev {}, {}, sha256 {})",
        new.protocol,
        old.file,
        old.revision,
        old.date,
        old.short_hash(),
        new.file,
        new.revision,
        new.date,
        new.short_hash()
    );
    let c = counts(changes);
    let summary: Vec<String> = Category::ALL
        .iter()
        .map(|k| format!("{} {}", c[k], k.as_str()))
        .collect();
    let _ = writeln!(o, "{}", summary.join(", "));
    for cat in Category::ALL {
        let these: Vec<&Change> = changes.iter().filter(|ch| ch.category == cat).collect();
        if these.is_empty() {
            continue;
        }
        let _ = writeln!(o, "\n{}:", cat.heading());
        for ch in these {
            let _ = writeln!(o, "  {}: {}", ch.path, ch.text);
        }
    }
    o
}

/// A Markdown changelog entry for release notes: the new revision as heading, provenance, then
/// the changes as bullet lists under one heading per category, breaking ones first.
pub fn render_markdown(old: &Side, new: &Side, changes: &[Change]) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "## {}: revision {} ({})\n",
        new.protocol, new.revision, new.date
    );
    let _ = writeln!(
        o,
        "*{}*, revision {} → {}. Spec `{}` (SHA-256 `{}`), previously `{}` (SHA-256 `{}`).\n",
        new.document,
        old.revision,
        new.revision,
        new.file,
        new.spec_sha256,
        old.file,
        old.spec_sha256
    );
    if changes.is_empty() {
        let _ = writeln!(o, "No changes.");
        return o;
    }
    for cat in Category::ALL {
        let these: Vec<&Change> = changes.iter().filter(|ch| ch.category == cat).collect();
        if these.is_empty() {
            continue;
        }
        let _ = writeln!(o, "### {} ({})\n", cat.heading(), these.len());
        for ch in these {
            let _ = writeln!(o, "- {}", ch.text);
        }
        o.push('\n');
    }
    o.truncate(o.trim_end().len());
    o.push('\n');
    o
}

/// Which old item became which new one.
struct Maps {
    units: Vec<Option<usize>>,
    enums: Vec<Option<usize>>,
    flags: Vec<Option<usize>>,
    /// Per direction: old message index → new message index.
    messages: BTreeMap<Direction, Vec<Option<usize>>>,
}

struct Differ<'a> {
    old: &'a Protocol,
    new: &'a Protocol,
    out: Vec<Change>,
}

/// An enum or a flag set, as the diff compares it.
struct ValueSet<'a> {
    name: &'a str,
    section: &'a str,
    doc: &'a str,
    values: Vec<(i64, &'a str)>,
    value_docs: String,
}

/// How changes to enums or to flag sets are named.
struct SetWords {
    what: &'static str,
    list: &'static str,
    values: &'static str,
    value: &'static str,
    value_docs: &'static str,
    removed: &'static str,
    renamed: &'static str,
    added: &'static str,
}

const ENUMS: SetWords = SetWords {
    what: "enum",
    list: "enums",
    values: "values",
    value: "",
    value_docs: "value docs",
    removed: "enum_removed",
    renamed: "enum_renamed",
    added: "enum_added",
};

const FLAGS: SetWords = SetWords {
    what: "flag set",
    list: "flags",
    values: "bits",
    value: " bit",
    value_docs: "bit docs",
    removed: "flags_removed",
    renamed: "flags_renamed",
    added: "flags_added",
};

/// What happened to one named value of an enum, flag set or `special` list.
enum ValueChange<'a> {
    Removed(i64, &'a str),
    Renumbered(&'a str, i64, i64),
    Renamed(i64, &'a str, &'a str),
    Added(i64, &'a str),
}

/// Compares two lists of `(value, name)`: a value keeps its identity by number, a name that
/// moved to another number was renumbered.
fn value_changes<'a>(old: &[(i64, &'a str)], new: &[(i64, &'a str)]) -> Vec<ValueChange<'a>> {
    let by_value = |l: &[(i64, &'a str)], v: i64| l.iter().find(|(x, _)| *x == v).map(|p| p.1);
    let by_name = |l: &[(i64, &'a str)], n: &str| l.iter().find(|(_, x)| *x == n).map(|p| p.0);
    let mut out = Vec::new();
    for &(v, name) in old {
        match (by_value(new, v), by_name(new, name)) {
            (Some(n), _) if n == name => {}
            (_, Some(nv)) if nv != v => out.push(ValueChange::Renumbered(name, v, nv)),
            (Some(n), _) => out.push(ValueChange::Renamed(v, name, n)),
            (None, _) => out.push(ValueChange::Removed(v, name)),
        }
    }
    for &(v, name) in new {
        if by_value(old, v).is_none() && by_name(old, name).is_none() {
            out.push(ValueChange::Added(v, name));
        }
    }
    out
}

/// Pairs named items: by name, then an unmatched old item with the first unmatched new one of
/// the same content (a rename). Returns old index → new index.
fn pair_named<T>(
    old: &[T],
    new: &[T],
    name: impl Fn(&T) -> &str,
    same: impl Fn(&T, &T) -> bool,
) -> Vec<Option<usize>> {
    let mut map: Vec<Option<usize>> = old
        .iter()
        .map(|o| new.iter().position(|n| name(n) == name(o)))
        .collect();
    for (i, o) in old.iter().enumerate() {
        if map[i].is_some() {
            continue;
        }
        map[i] = (0..new.len()).find(|&j| {
            !map.contains(&Some(j))
                && !old.iter().any(|x| name(x) == name(&new[j]))
                && same(o, &new[j])
        });
    }
    map
}

fn taken(map: &[Option<usize>], j: usize) -> bool {
    map.contains(&Some(j))
}

fn enum_values(e: &Enum) -> Vec<(i64, &str)> {
    e.values
        .iter()
        .map(|v| (v.value as i64, v.name.as_str()))
        .collect()
}

fn flag_bits(f: &FlagSet) -> Vec<(i64, &str)> {
    f.bits
        .iter()
        .map(|b| (i64::from(b.bit), b.name.as_str()))
        .collect()
}

fn specials(f: &Field) -> Vec<(i64, &str)> {
    f.special
        .iter()
        .map(|s| (s.value, s.name.as_str()))
        .collect()
}

fn direction_word(d: Direction) -> &'static str {
    match d {
        Direction::Request => "command",
        Direction::Response => "response",
    }
}

fn list_key(d: Direction) -> &'static str {
    match d {
        Direction::Request => "commands",
        Direction::Response => "responses",
    }
}

fn conversion(u: &Unit) -> String {
    if u.offset == Rational::ZERO {
        format!("raw × {}", u.scale)
    } else if u.offset < Rational::ZERO {
        let magnitude = Rational::ZERO.minus(u.offset).unwrap_or(u.offset);
        format!("raw × {} − {magnitude}", u.scale)
    } else {
        format!("raw × {} + {}", u.scale, u.offset)
    }
}

fn range_text(r: Option<(i64, i64)>) -> String {
    match r {
        Some((a, b)) => format!("{a}..={b}"),
        None => "any".to_owned(),
    }
}

fn type_name(f: &Field) -> String {
    if let Some(pk) = f.fixed_count() {
        // A list of a fixed count: `i16[4]`, `f32[4]`.
        return format!("{}[{}]", type_name(&f.element()), pk.count);
    }
    if let Some(pk) = &f.packed {
        let order = if pk.lsb_first { "lsb" } else { "msb" };
        format!(
            "u{}[{}] × {} bits {order} first",
            8 * pk.elem_width,
            pk.count,
            pk.bits
        )
    } else if f.is_ascii() {
        format!("ascii[{}]", f.width)
    } else if f.ty == crate::ir::FieldType::Bit {
        "bit".to_owned()
    } else if f.is_record() && f.record_bytes_from().is_some() {
        format!("record[{}..={}]", f.min_element_width(), f.width)
    } else if f.is_record() {
        format!("record[{}]", f.width)
    } else if f.is_float() {
        format!("f{}", f.width * 8)
    } else {
        format!("{}{}", if f.signed { "i" } else { "u" }, f.width * 8)
    }
}

/// How a repeated field's count is found, with the count field named by its offset (a field
/// keeps its place when renamed): for comparing two specs.
fn repeat_shape(m: &Message, f: &Field) -> Option<String> {
    let r = f.repeat.as_ref()?;
    let at = |i: usize| m.place(i);
    let count = match r.count {
        crate::ir::Count::Elements(i) => {
            format!("elements counted by the field at payload offset {}", at(i))
        }
        crate::ir::Count::Bytes(i) => {
            format!("bytes counted by the field at payload offset {}", at(i))
        }
        crate::ir::Count::ToEnd => "to the end of the frame".to_owned(),
        crate::ir::Count::Until(t) => format!("up to a terminator 0x{t:02X}"),
        crate::ir::Count::Fixed(n) => format!("a fixed count of {n}"),
    };
    Some(format!("{count}, {}..={} elements", r.min, r.max))
}

/// What a field's value follows from, for comparing two specs.
fn follows_shape(m: &Message, f: &Field) -> Option<String> {
    let reply_count = f.repeat.as_ref().and_then(|r| r.request.as_ref());
    match (&f.follows, reply_count) {
        (Some(crate::ir::Follows::Field(i, rel)), _) => Some(format!(
            "{} of this frame",
            rel.describe(&format!("the field at payload offset {}", m.place(*i)))
        )),
        (Some(crate::ir::Follows::Request(rel)), _) => {
            Some(format!("{} of the request", rel.describe(&rel.field)))
        }
        (None, Some(rel)) => Some(format!(
            "element count {} of the request",
            rel.describe(&rel.field)
        )),
        (None, None) => None,
    }
}

/// `Some(true)`: `new` contains `old`; `Some(false)`: it does not; `None`: equal.
fn widened(old: Option<(i64, i64)>, new: Option<(i64, i64)>) -> Option<bool> {
    match (old, new) {
        _ if old == new => None,
        (_, None) => Some(true),
        (None, Some(_)) => Some(false),
        (Some((a, b)), Some((c, d))) => Some(c <= a && b <= d),
    }
}

impl<'a> Differ<'a> {
    fn push(&mut self, category: Category, kind: &'static str, path: String, text: String) {
        self.out.push(Change {
            category,
            kind,
            path,
            text,
        });
    }

    fn wire(&mut self, kind: &'static str, path: impl Into<String>, text: String) {
        self.push(Category::WireBreaking, kind, path.into(), text);
    }

    fn api(&mut self, kind: &'static str, path: impl Into<String>, text: String) {
        self.push(Category::ApiBreaking, kind, path.into(), text);
    }

    fn compatible(&mut self, kind: &'static str, path: impl Into<String>, text: String) {
        self.push(Category::Compatible, kind, path.into(), text);
    }

    /// A documentation-only change of one item: which of its texts changed.
    fn doc_change(&mut self, path: String, what: &str, pairs: &[(&str, &str, &str)]) {
        let changed: Vec<String> = pairs
            .iter()
            .filter(|(_, a, b)| a != b)
            .map(|(k, a, b)| {
                if *k == "section" {
                    let show = |s: &str| {
                        if s.is_empty() {
                            "none".to_owned()
                        } else {
                            format!("§{s}")
                        }
                    };
                    format!("section {} → {}", show(a), show(b))
                } else {
                    (*k).to_owned()
                }
            })
            .collect();
        if !changed.is_empty() {
            self.compatible(
                "documentation_changed",
                path,
                format!("{what}: {} changed", changed.join(", ")),
            );
        }
    }

    fn protocol(&mut self) {
        let (o, n) = (self.old, self.new);
        if o.name != n.name {
            self.api(
                "protocol_renamed",
                "protocol",
                format!(
                    "protocol `{}` renamed to `{}` (the generated module's name)",
                    o.name, n.name
                ),
            );
        }
        let (od, nd) = (&o.document, &n.document);
        let fields = [
            ("title", &od.title, &nd.title),
            ("revision", &od.revision, &nd.revision),
            ("date", &od.date, &nd.date),
        ];
        for (k, a, b) in fields {
            if a != b {
                self.compatible(
                    "document_changed",
                    format!("document.{k}"),
                    format!("document {k}: {a} → {b}"),
                );
            }
        }
        if od.file != nd.file {
            self.compatible(
                "document_changed",
                "document.file",
                format!(
                    "document file: {} → {}",
                    od.file.as_deref().unwrap_or("none"),
                    nd.file.as_deref().unwrap_or("none")
                ),
            );
        }
        self.doc_change("title".into(), "protocol", &[("title", &o.title, &n.title)]);
        if o.byte_order != n.byte_order {
            self.wire(
                "byte_order_changed",
                "byte_order",
                format!(
                    "numbers travel {:?} instead of {:?} endian: every multi-byte field reads differently",
                    n.byte_order, o.byte_order
                )
                .to_lowercase(),
            );
        }
        if o.printed_byte_order != n.printed_byte_order {
            self.compatible(
                "documentation_changed",
                "printed_byte_order",
                format!(
                    "the document prints numbers {:?} instead of {:?} endian (examples only)",
                    n.printed_byte_order, o.printed_byte_order
                )
                .to_lowercase(),
            );
        }
    }

    fn serial(&mut self) {
        let (o, n) = (&self.old.serial, &self.new.serial);
        let settings = [
            ("baud", o.baud.to_string(), n.baud.to_string()),
            (
                "data_bits",
                o.data_bits.to_string(),
                n.data_bits.to_string(),
            ),
            (
                "parity",
                format!("{:?}", o.parity).to_lowercase(),
                format!("{:?}", n.parity).to_lowercase(),
            ),
            (
                "stop_bits",
                o.stop_bits.to_string(),
                n.stop_bits.to_string(),
            ),
        ];
        for (k, a, b) in settings {
            if a != b {
                self.wire(
                    "serial_changed",
                    format!("serial.{k}"),
                    format!("serial {k}: {a} → {b}"),
                );
            }
        }
        let (og, ng) = (
            o.inter_frame_gap_ms.unwrap_or(0),
            n.inter_frame_gap_ms.unwrap_or(0),
        );
        if og != ng {
            let text = format!("minimum gap between frames: {og} ms → {ng} ms");
            if ng > og {
                self.wire("timing_changed", "serial.inter_frame_gap_ms", text);
            } else {
                self.compatible("timing_changed", "serial.inter_frame_gap_ms", text);
            }
        }
        let rate = |r: &Option<crate::ir::FrameRate>| r.as_ref().map(|r| r.max_per_s);
        let (orate, nrate) = (rate(&o.frame_rate), rate(&n.frame_rate));
        if orate != nrate {
            let show = |r: Option<u32>| r.map_or("unlimited".to_owned(), |r| format!("{r}/s"));
            let text = format!("maximum frame rate: {} → {}", show(orate), show(nrate));
            // Fewer frames per second allowed: a host sending at the old rate now overruns.
            if nrate.unwrap_or(u32::MAX) < orate.unwrap_or(u32::MAX) {
                self.wire("timing_changed", "serial.frame_rate", text);
            } else {
                self.compatible("timing_changed", "serial.frame_rate", text);
            }
        }
        let sec = |s: &Option<String>| s.clone().unwrap_or_default();
        self.doc_change(
            "serial".into(),
            "serial",
            &[("section", &sec(&o.section), &sec(&n.section))],
        );
    }

    /// The `transactions:` section ([`crate::transactions::diff`]) and each command's retry
    /// safety: a command no longer safe to send twice breaks a master that would.
    fn transactions(&mut self) {
        let (o, n) = (&self.old.transactions, &self.new.transactions);
        for (breaks, path, text) in crate::transactions::diff(o, n) {
            if breaks {
                self.wire("timing_changed", path, text);
            } else {
                self.compatible("timing_changed", path, text);
            }
        }
        for (name, was, now) in crate::transactions::retry_changes(self.old, self.new) {
            let safe = |s: bool| if s { "safe" } else { "not safe" };
            let path = format!("commands.{name}");
            let text = format!("{name} to retry: {} → {}", safe(was), safe(now));
            if was {
                self.wire("retry_changed", path, text);
            } else {
                self.compatible("retry_changed", path, text);
            }
        }
    }

    /// The `device:` section: what the simulator holds and answers. No frame changes, so
    /// nothing breaks a peer.
    fn device(&mut self) {
        for (path, text) in crate::device::diff(self.old, self.new) {
            self.compatible("device_changed", path, text);
        }
    }

    fn framing(&mut self) {
        let (o, n) = (&self.old.framing, &self.new.framing);
        if !o.layout_by_direction() && !n.layout_by_direction() {
            if o.layout != n.layout {
                self.wire(
                    "framing_changed",
                    "framing.layout",
                    format!("frame layout: {:?} → {:?}", o.layout, n.layout).to_lowercase(),
                );
            }
        } else {
            // A layout per direction (`framing.layout: {request, response}`) on either side:
            // each direction's layout compared, as a layout is.
            for d in [Direction::Request, Direction::Response] {
                let (a, b) = (o.layout_of(d), n.layout_of(d));
                if a != b {
                    self.wire(
                        "framing_changed",
                        format!("framing.layout.{}", d.as_str()),
                        format!("{} frame layout: {:?} → {:?}", d.as_str(), a, b).to_lowercase(),
                    );
                }
            }
        }
        if o.start != n.start {
            let show = |s: Option<u8>| s.map_or("none".to_owned(), |s| format!("0x{s:02X}"));
            self.wire(
                "framing_changed",
                "framing.start",
                format!("start byte: {} → {}", show(o.start), show(n.start)),
            );
        }
        if o.sync != n.sync && o.start == n.start {
            self.wire(
                "framing_changed",
                "framing.start",
                format!("sync bytes: {} → {}", bytes(&o.sync), bytes(&n.sync)),
            );
        }
        if o.response_sync != n.response_sync && o.sync == n.sync {
            self.wire(
                "framing_changed",
                "framing.start.response",
                format!(
                    "a response's sync bytes: {} → {}",
                    bytes(&o.response_sync),
                    bytes(&n.response_sync)
                ),
            );
        }
        self.header();
        if o.end != n.end {
            self.wire(
                "framing_changed",
                "framing.end",
                format!("end bytes: {} → {}", bytes(&o.end), bytes(&n.end)),
            );
        }
        // Escaping added, removed or changed (its kind, bytes, or where the checksum and
        // length are computed): every frame with a byte it touches travels otherwise.
        let (oe, ne) = (o.escaping.as_ref(), n.escaping.as_ref());
        if oe.map(|e| (&e.kind, e.computed)) != ne.map(|e| (&e.kind, e.computed)) {
            self.wire(
                "escaping_changed",
                "framing.escaping",
                format!(
                    "escaping: {} → {}",
                    crate::escape::describe(oe),
                    crate::escape::describe(ne)
                ),
            );
        }
        // A preamble added, removed, or sending another byte or count: every frame travels
        // otherwise; fewer taken refuses what a sender may send, more taken refuses nothing.
        let (op, np) = (o.preamble.as_ref(), n.preamble.as_ref());
        if op.map(|p| (p.byte, p.send, p.max)) != np.map(|p| (p.byte, p.send, p.max)) {
            let show =
                |p: Option<&crate::ir::Preamble>| p.map_or("none".to_owned(), |p| p.describe());
            let text = format!("preamble: {} → {}", show(op), show(np));
            match (op, np) {
                (Some(a), Some(b)) if (a.byte, a.send) == (b.byte, b.send) && b.max > a.max => {
                    self.compatible("preamble_changed", "framing.preamble", text)
                }
                _ => self.wire("preamble_changed", "framing.preamble", text),
            }
        }
        // A transform added, removed or changed: every payload byte travels otherwise.
        let (ot, nt) = (o.transform.as_ref(), n.transform.as_ref());
        if ot.map(|t| t.kind) != nt.map(|t| t.kind) {
            let show =
                |t: Option<&crate::ir::Transform>| t.map_or("none".to_owned(), |t| t.describe());
            let text = format!("transform: {} → {}", show(ot), show(nt));
            self.wire("transform_changed", "framing.transform", text);
        }
        // Payload truncation added or removed (`framing.truncation`): frames whose payload
        // ends in zeros travel shorter (or whole), and a receiver that does not pad refuses
        // them.
        if o.truncation != n.truncation {
            let show = |t: Option<crate::model::Truncation>| {
                t.map_or("none", |_| "trailing zeros stripped")
            };
            let text = format!(
                "payload truncation: {} → {}",
                show(o.truncation),
                show(n.truncation)
            );
            self.wire("truncation_changed", "framing.truncation", text);
        }
        // A long length form added, removed or changed (`framing.length.long`): frames whose
        // length the short form cannot hold travel otherwise. The length field itself is
        // compared in the short form's width (the IR lays frames out in the long one's).
        if o.long != n.long {
            let show =
                |l: Option<crate::ir::LongForm>| l.map_or("none".to_owned(), |l| l.describe());
            let text = format!("long length form: {} → {}", show(o.long), show(n.long));
            self.wire("long_length_changed", "framing.length.long", text);
        }
        // A short form of the frame added, removed or changed (`framing.forms`): frames with
        // an empty payload travel otherwise. The layout's own (long) frames are compared as
        // they were.
        if o.form != n.form {
            let show = |f: Option<&crate::ir::ShortForm>| {
                f.map_or("none".to_owned(), crate::ir::ShortForm::describe)
            };
            let text = format!(
                "short form: {} → {}",
                show(o.form.as_ref()),
                show(n.form.as_ref())
            );
            self.wire("form_changed", "framing.forms", text);
        }
        let short = |f: &crate::ir::Framing| {
            f.length.clone().map(|mut l| {
                if let Some(g) = f.long {
                    l.width = g.short_width;
                }
                l
            })
        };
        let (o_length, n_length) = (short(o), short(n));
        if o_length != n_length {
            let (o, n) = (&o_length, &n_length);
            let show = |l: &Option<crate::ir::LengthField>| match l {
                None => "none".to_owned(),
                Some(l) => format!("{} byte(s) counting {:?}{:+}", l.width, l.counts, l.adjust)
                    .to_lowercase(),
            };
            self.wire(
                "framing_changed",
                "framing.length",
                format!("length field: {} → {}", show(o), show(n)),
            );
        }
        let (oc, nc) = (&o.checksum, &n.checksum);
        // Where it starts in a frame as it travels short (a long length form lays frames out
        // longer).
        let (ocf, ncf) = (o.short_covers_from(), n.short_covers_from());
        if ocf != ncf {
            self.wire(
                "checksum_changed",
                "framing.checksum.covers_from",
                format!("checksum covers from offset {ocf} → {ncf}"),
            );
        }
        // Moved before the bytes it covers, back to the end, or elsewhere before them: every
        // frame's checksum travels at another offset (the layout's change says where).
        if oc.lead != nc.lead {
            let show = |l: Option<usize>| match l {
                Some(at) => format!("at offset {at}, before the bytes it covers"),
                None => "at the frame's end".to_owned(),
            };
            self.wire(
                "checksum_moved",
                "framing.checksum",
                format!("checksum {} → {}", show(oc.lead), show(nc.lead)),
            );
        }
        // A response's, where each direction's checksum covers from its own byte
        // (`covers_from: {request, response}`): unchanged with the request's where neither
        // protocol's differs by direction.
        let (orf, nrf) = (
            oc.response_covers_from as i64 - oc.covers_from as i64 + ocf as i64,
            nc.response_covers_from as i64 - nc.covers_from as i64 + ncf as i64,
        );
        if orf != nrf && (oc.covers_by_direction() || nc.covers_by_direction()) {
            self.wire(
                "checksum_changed",
                "framing.checksum.covers_from.response",
                format!("a response's checksum covers from offset {orf} → {nrf}"),
            );
        }
        // The byte order of a one-byte checksum means nothing on the wire.
        let order_changed = oc.byte_order != nc.byte_order && oc.width.max(nc.width) > 8;
        // Followed by its complement or not (`complement`, HerkuleX's CS2): every frame's
        // checksum takes another number of bytes. Said apart from the rest of the checksum.
        let bare = |c: &crate::ir::Checksum| match &c.algorithm {
            crate::ir::ChecksumAlgorithm::Complemented(inner, _) => ((**inner).clone(), 8, true),
            a => (a.clone(), c.width, false),
        };
        let ((oa, ow, ox), (na, nw, nx)) = (bare(oc), bare(nc));
        if ox != nx {
            let show = |x: bool| {
                if x {
                    "followed by its complement"
                } else {
                    "alone"
                }
            };
            self.wire(
                "checksum_changed",
                "framing.checksum.complement",
                format!("checksum {} → {}", show(ox), show(nx)),
            );
        }
        let order_changed = order_changed && !(ox || nx);
        if oa != na || ow != nw || order_changed {
            let show = |c: &crate::ir::Checksum| {
                let name = match &c.algorithm {
                    crate::ir::ChecksumAlgorithm::Crc(_) => {
                        c.catalogue.clone().unwrap_or_else(|| "crc".to_owned())
                    }
                    a => a.name(),
                };
                let order = match (c.width, c.byte_order) {
                    (0 | 8, _) => "",
                    (_, crate::ir::ByteOrder::Big) => ", high byte first",
                    (_, crate::ir::ByteOrder::Little) => ", low byte first",
                };
                format!("{name} ({} bits, check 0x{:X}{order})", c.width, c.check)
            };
            self.wire(
                "checksum_changed",
                "framing.checksum",
                format!("checksum: {} → {}", show(oc), show(nc)),
            );
        } else if oc.catalogue != nc.catalogue {
            self.compatible(
                "documentation_changed",
                "framing.checksum.catalogue",
                "checksum catalogue name changed".to_owned(),
            );
        }
        let (oa, na) = (&o.address, &n.address);
        // Addresses that appear or vanish are a change of layout, reported above.
        let both = o.has_address() && n.has_address();
        if both && (oa.min, oa.max) != (na.min, na.max) {
            let text = format!(
                "device addresses: 0x{:02X}..=0x{:02X} → 0x{:02X}..=0x{:02X}",
                oa.min, oa.max, na.min, na.max
            );
            if na.min <= oa.min && oa.max <= na.max {
                self.compatible("address_range_widened", "framing.address.devices", text);
            } else {
                self.wire("address_range_narrowed", "framing.address.devices", text);
            }
        }
        let show = |a: Option<u8>| a.map_or("none".to_owned(), |a| format!("0x{a:02X}"));
        for (k, a, b) in [
            ("host", oa.host, na.host),
            ("broadcast", oa.broadcast, na.broadcast),
            ("default", oa.default, na.default),
        ] {
            if a == b || !both {
                continue;
            }
            let text = format!("{k} address: {} → {}", show(a), show(b));
            if k == "broadcast" && a.is_none() {
                self.compatible("address_changed", format!("framing.address.{k}"), text);
            } else {
                self.wire("address_changed", format!("framing.address.{k}"), text);
            }
        }
        for dir in [Direction::Request, Direction::Response] {
            let (of, nf) = (o.direction(dir), n.direction(dir));
            let key = format!("framing.{}", dir.as_str());
            if of.code_lengths != nf.code_lengths {
                let text = format!(
                    "{} code lengths: {:?} → {:?} bytes",
                    dir.as_str(),
                    of.code_lengths,
                    nf.code_lengths
                );
                if of.code_lengths.iter().all(|l| nf.code_lengths.contains(l)) {
                    self.compatible("framing_widened", format!("{key}.code_lengths"), text);
                } else {
                    self.wire("framing_changed", format!("{key}.code_lengths"), text);
                }
            }
            if (of.payload_min, of.payload_max) != (nf.payload_min, nf.payload_max) {
                let text = format!(
                    "{} payload: {}..={} → {}..={} bytes",
                    dir.as_str(),
                    of.payload_min,
                    of.payload_max,
                    nf.payload_min,
                    nf.payload_max
                );
                if nf.payload_min <= of.payload_min && of.payload_max <= nf.payload_max {
                    self.compatible("framing_widened", format!("{key}.payload"), text);
                } else {
                    self.wire("framing_changed", format!("{key}.payload"), text);
                }
            }
        }
        let sec = |s: &Option<String>| s.clone().unwrap_or_default();
        self.doc_change(
            "framing".into(),
            "framing",
            &[("section", &sec(&o.section), &sec(&n.section))],
        );
    }

    fn units(&mut self) -> Vec<Option<usize>> {
        let (o, n) = (&self.old.units, &self.new.units);
        let map = pair_named(
            o,
            n,
            |u| &u.name,
            |a, b| a.scale == b.scale && a.offset == b.offset && a.symbol == b.symbol,
        );
        for (i, u) in o.iter().enumerate() {
            let Some(j) = map[i] else {
                self.api(
                    "unit_removed",
                    format!("units.{}", u.name),
                    format!("unit `{}` removed", u.name),
                );
                continue;
            };
            let v = &n[j];
            let path = format!("units.{}", v.name);
            if u.name != v.name {
                self.api(
                    "unit_renamed",
                    path.clone(),
                    format!("unit `{}` renamed to `{}`", u.name, v.name),
                );
            }
            if u.scale != v.scale || u.offset != v.offset {
                self.wire(
                    "unit_scale_changed",
                    path.clone(),
                    format!(
                        "unit `{}`: physical value {} → {}; every field in it reads differently",
                        v.name,
                        conversion(u),
                        conversion(v)
                    ),
                );
            }
            self.doc_change(
                path,
                &format!("unit `{}`", v.name),
                &[("symbol", &u.symbol, &v.symbol), ("doc", &u.doc, &v.doc)],
            );
        }
        for (j, v) in n.iter().enumerate() {
            if !taken(&map, j) {
                self.compatible(
                    "unit_added",
                    format!("units.{}", v.name),
                    format!("unit `{}` added ({} {})", v.name, conversion(v), v.symbol)
                        .trim_end()
                        .to_owned(),
                );
            }
        }
        map
    }

    /// Reports what happened to each value of a matched enum, flag set or special list.
    fn values(&mut self, path: &str, what: &str, changes: Vec<ValueChange>) {
        for c in changes {
            match c {
                ValueChange::Removed(v, name) => self.wire(
                    "value_removed",
                    format!("{path}.{name}"),
                    format!("{what}: `{name}` ({v}) removed"),
                ),
                ValueChange::Renumbered(name, a, b) => self.wire(
                    "value_renumbered",
                    format!("{path}.{name}"),
                    format!("{what}: `{name}` renumbered from {a} to {b}"),
                ),
                ValueChange::Renamed(v, a, b) => self.api(
                    "value_renamed",
                    format!("{path}.{b}"),
                    format!("{what}: {v} renamed from `{a}` to `{b}`"),
                ),
                ValueChange::Added(v, name) => self.compatible(
                    "value_added",
                    format!("{path}.{name}"),
                    format!("{what}: `{name}` ({v}) added"),
                ),
            }
        }
    }

    fn enums(&mut self) -> Vec<Option<usize>> {
        let sets = |p: &'a Protocol| -> Vec<ValueSet<'a>> {
            p.enums
                .iter()
                .map(|e| ValueSet {
                    name: &e.name,
                    section: e.section.as_deref().unwrap_or(""),
                    doc: &e.doc,
                    values: enum_values(e),
                    value_docs: e.values.iter().map(|v| v.doc.as_str()).collect(),
                })
                .collect()
        };
        self.value_sets(&ENUMS, &sets(self.old), &sets(self.new))
    }

    fn flag_sets(&mut self) -> Vec<Option<usize>> {
        let sets = |p: &'a Protocol| -> Vec<ValueSet<'a>> {
            p.flags
                .iter()
                .map(|f| ValueSet {
                    name: &f.name,
                    section: f.section.as_deref().unwrap_or(""),
                    doc: &f.doc,
                    values: flag_bits(f),
                    value_docs: f.bits.iter().map(|b| b.doc.as_str()).collect(),
                })
                .collect()
        };
        self.value_sets(&FLAGS, &sets(self.old), &sets(self.new))
    }

    /// Pairs enums (or flag sets) by name, then by identical values, and compares each pair
    /// value by value. Returns old index → new index.
    fn value_sets(
        &mut self,
        w: &SetWords,
        old: &[ValueSet<'a>],
        new: &[ValueSet<'a>],
    ) -> Vec<Option<usize>> {
        let map = pair_named(old, new, |s| s.name, |a, b| a.values == b.values);
        for (i, e) in old.iter().enumerate() {
            let Some(j) = map[i] else {
                self.api(
                    w.removed,
                    format!("{}.{}", w.list, e.name),
                    format!("{} `{}` removed", w.what, e.name),
                );
                continue;
            };
            let f = &new[j];
            let path = format!("{}.{}", w.list, f.name);
            let what = format!("{} `{}`", w.what, f.name);
            if e.name != f.name {
                self.api(
                    w.renamed,
                    path.clone(),
                    format!("{} `{}` renamed to `{}`", w.what, e.name, f.name),
                );
            }
            let changes = value_changes(&e.values, &f.values);
            self.values(
                &format!("{path}.{}", w.values),
                &format!("{what}{}", w.value),
                changes,
            );
            self.doc_change(
                path,
                &what,
                &[
                    ("section", e.section, f.section),
                    ("doc", e.doc, f.doc),
                    (w.value_docs, &e.value_docs, &f.value_docs),
                ],
            );
        }
        for (j, f) in new.iter().enumerate() {
            if !taken(&map, j) {
                self.compatible(
                    w.added,
                    format!("{}.{}", w.list, f.name),
                    format!("{} `{}` added", w.what, f.name),
                );
            }
        }
        map
    }

    /// Pairs and compares the messages of one direction; returns old index → new index.
    fn messages(&mut self, dir: Direction, maps: &Maps) -> Vec<Option<usize>> {
        let (o, n) = (self.old.messages(dir), self.new.messages(dir));
        let word = direction_word(dir);
        let list = list_key(dir);
        // By name first; then by wire identity (code and constant selector fields).
        let mut map: Vec<Option<usize>> = o
            .iter()
            .map(|m| n.iter().position(|x| x.name == m.name))
            .collect();
        for (i, m) in o.iter().enumerate() {
            if map[i].is_some() {
                continue;
            }
            map[i] = (0..n.len()).find(|&j| {
                !taken(&map, j) && !o.iter().any(|x| x.name == n[j].name) && key(m) == key(&n[j])
            });
        }
        for (i, m) in o.iter().enumerate() {
            let Some(j) = map[i] else {
                self.wire(
                    "message_removed",
                    format!("{list}.{}", m.name),
                    format!("{word} `{}` ({}) removed", m.name, code_of(m)),
                );
                continue;
            };
            let x = &n[j];
            let path = format!("{list}.{}", x.name);
            let mut sub = Differ {
                old: self.old,
                new: self.new,
                out: Vec::new(),
            };
            sub.message_body(m, x, &path, maps);
            let wire_changed = sub.out.iter().any(|c| c.category == Category::WireBreaking);
            if m.name != x.name && wire_changed {
                let first: Vec<&str> = sub
                    .out
                    .iter()
                    .filter(|c| c.category == Category::WireBreaking)
                    .map(|c| c.text.as_str())
                    .collect();
                self.wire(
                    "code_reused",
                    path,
                    format!(
                        "{word} code {} reused: `{}` replaced by `{}` with a different layout ({})",
                        x.code_hex(),
                        m.name,
                        x.name,
                        first.join("; ")
                    ),
                );
                continue;
            }
            if m.name != x.name {
                self.api(
                    "message_renamed",
                    path.clone(),
                    format!(
                        "{word} `{}` ({}) renamed to `{}`",
                        m.name,
                        code_of(x),
                        x.name
                    ),
                );
            }
            if m.code != x.code && m.frame.is_none() && x.frame.is_none() {
                self.wire(
                    "code_changed",
                    path.clone(),
                    format!(
                        "{word} `{}`: code {} → {}",
                        x.name,
                        m.code_hex(),
                        x.code_hex()
                    ),
                );
            }
            self.out.append(&mut sub.out);
        }
        for (j, x) in n.iter().enumerate() {
            if !taken(&map, j) {
                self.compatible(
                    "message_added",
                    format!("{list}.{}", x.name),
                    format!("{word} `{}` ({}, §{}) added", x.name, code_of(x), x.section),
                );
            }
        }
        map
    }

    /// Everything about a matched message except its name and code.
    /// The header fields every message carries (`framing.header`), once for all messages: one
    /// removed, added, moved, widened or re-signed changes every frame; a changed unit, range,
    /// enum or flag set changes what the values mean.
    ///
    /// Where either protocol's header fields differ by direction (`framing.header: {request,
    /// response}`), each direction's are compared, at `framing.header.request.<name>` and
    /// `framing.header.response.<name>`.
    fn header(&mut self) {
        let (of, nf) = (&self.old.framing, &self.new.framing);
        if !of.header_by_direction() && !nf.header_by_direction() {
            return self.header_of(Direction::Request, "framing.header");
        }
        self.header_of(Direction::Request, "framing.header.request");
        self.header_of(Direction::Response, "framing.header.response");
    }

    /// [`Self::header`] of direction `d`'s header fields, at `at.<name>`.
    fn header_of(&mut self, d: Direction, at: &str) {
        let (o, n) = (self.old.framing.header_of(d), self.new.framing.header_of(d));
        for f in o {
            let path = format!("{at}.{}", f.name);
            let Some(g) = n.iter().find(|g| g.name == f.name) else {
                self.wire(
                    "header_field_removed",
                    path,
                    format!(
                        "header field `{}` ({} at {}) removed",
                        f.name,
                        type_name(f),
                        f.header_place()
                    ),
                );
                continue;
            };
            let subs = |f: &Field| -> Vec<(String, u8, u8, bool, Option<u64>)> {
                f.bits
                    .iter()
                    .map(|b| (b.name.clone(), b.msb, b.lsb, b.signed, b.constant))
                    .collect()
            };
            if subs(f) != subs(g) && (f.part, f.offset, f.width) == (g.part, g.offset, g.width) {
                self.wire(
                    "header_field_changed",
                    path,
                    format!("header field `{}`: its sub-fields changed", f.name),
                );
                continue;
            }
            if (f.part, f.offset, f.width, f.signed) != (g.part, g.offset, g.width, g.signed) {
                self.wire(
                    "header_field_changed",
                    path,
                    format!(
                        "header field `{}`: {} at {} → {} at {}",
                        f.name,
                        type_name(f),
                        f.header_place(),
                        type_name(g),
                        g.header_place()
                    ),
                );
                continue;
            }
            // A constant every message carries (`value`): a frame with another is no frame.
            if f.constant != g.constant {
                let show =
                    |c: Option<u64>| c.map_or("any value".to_owned(), |c| format!("0x{c:02X}"));
                self.wire(
                    "header_field_changed",
                    path,
                    format!(
                        "header field `{}` holds {} → {}",
                        f.name,
                        show(f.constant),
                        show(g.constant)
                    ),
                );
                continue;
            }
            let unit = |p: &Protocol, f: &Field| f.unit.map(|u| p.units[u].name.clone());
            let en = |p: &Protocol, f: &Field| f.enumeration.map(|e| p.enums[e].name.clone());
            let fl = |p: &Protocol, f: &Field| f.flags.map(|e| p.flags[e].name.clone());
            if f.range != g.range
                || unit(self.old, f) != unit(self.new, g)
                || en(self.old, f) != en(self.new, g)
                || fl(self.old, f) != fl(self.new, g)
            {
                self.api(
                    "header_field_changed",
                    path,
                    format!(
                        "header field `{}`: its unit, range, enum or flags changed",
                        f.name
                    ),
                );
            }
        }
        for g in n.iter().filter(|g| !o.iter().any(|f| f.name == g.name)) {
            self.wire(
                "header_field_added",
                format!("{at}.{}", g.name),
                format!(
                    "header field `{}` ({} at {}) added",
                    g.name,
                    type_name(g),
                    g.header_place()
                ),
            );
        }
    }

    fn message_body(&mut self, m: &Message, x: &Message, path: &str, maps: &Maps) {
        let (o, n) = (self.old, self.new);
        let word = direction_word(m.direction);
        // As the frames travel (a long length form lays them out longer).
        let (ol, nl) = (
            o.framing.travelled_len(m.direction, o.frame_len(m)),
            n.framing.travelled_len(x.direction, n.frame_len(x)),
        );
        let (om, nm) = (
            o.framing.travelled_len(m.direction, m.max_len),
            n.framing.travelled_len(x.direction, x.max_len),
        );
        // A constant whole frame changed, added to or taken from a message: its bytes say it
        // all (its length, its code).
        if m.frame.is_some() || x.frame.is_some() {
            if m.frame != x.frame {
                self.wire(
                    "constant_frame_changed",
                    format!("{path}.frame"),
                    format!("{word} `{}`: {} → {}", x.name, code_of(m), code_of(x)),
                );
            }
        } else if ol != nl {
            self.wire(
                "frame_length_changed",
                path.to_owned(),
                format!("{word} `{}`: frame length {ol} → {nl} bytes", x.name),
            );
        } else if om != nm {
            self.wire(
                "frame_length_changed",
                path.to_owned(),
                format!("{word} `{}`: longest frame {om} → {nm} bytes", x.name),
            );
        }
        if m.checksum_extra != x.checksum_extra {
            let show = |c: Option<u8>| c.map_or("none".to_owned(), |c| c.to_string());
            self.wire(
                "checksum_extra_changed",
                format!("{path}.checksum_extra"),
                format!(
                    "{word} `{}`: checksum extra byte {} → {}",
                    x.name,
                    show(m.checksum_extra),
                    show(x.checksum_extra)
                ),
            );
        }
        if m.unchecked != x.unchecked {
            let show = |u: bool| if u { "none" } else { "the framing's" };
            self.wire(
                "checksum_none_changed",
                format!("{path}.checksum"),
                format!(
                    "{word} `{}`: checksum {} → {}",
                    x.name,
                    show(m.unchecked),
                    show(x.unchecked)
                ),
            );
        }
        if m.over_request != x.over_request {
            let show = |c: Option<usize>| {
                c.map_or("its own bytes".to_owned(), |from| {
                    format!("its request's bytes, then its own from offset {from}")
                })
            };
            self.wire(
                "checksum_over_request_changed",
                format!("{path}.checksum_over_request"),
                format!(
                    "{word} `{}`: checksum over {} → {}",
                    x.name,
                    show(m.over_request),
                    show(x.over_request)
                ),
            );
        }
        if m.code_from_request != x.code_from_request {
            let show = |c: Option<u8>| {
                c.map_or("its own".to_owned(), |c| {
                    format!("the request's | 0x{c:02X}")
                })
            };
            self.wire(
                "code_from_request_changed",
                format!("{path}.code_from_request"),
                format!(
                    "{word} `{}`: code is {} → {}",
                    x.name,
                    show(m.code_from_request),
                    show(x.code_from_request)
                ),
            );
        }
        // A field keeps its name where it moved; otherwise what sits at its offset is it. The
        // header fields every message carries lead its fields: `header` compares them once.
        // With a layout per direction only the messages of a direction whose layout has
        // `header` carry them.
        let headers = |m: &Message| m.fields.iter().take_while(|f| f.header).count();
        let (mh, xh) = (headers(m), headers(x));
        // A message's own values for its header fields (`header:`): a frame with another value
        // is not this message, so giving, taking away or changing one reads frames differently.
        // (A constant of `framing.header` itself changed is said once, by `header`.)
        let framing_value = |p: &Protocol, name: &str| {
            let h = p.framing.header_of(m.direction).iter();
            h.filter(|h| h.name == name).find_map(|h| h.constant)
        };
        for f in &m.fields[..mh] {
            let Some(g) = x.fields[..xh].iter().find(|g| g.name == f.name) else {
                continue;
            };
            if framing_value(self.old, &f.name) != framing_value(self.new, &f.name) {
                continue;
            }
            if f.constant != g.constant {
                let show =
                    |c: Option<u64>| c.map_or("any value".to_owned(), |c| format!("0x{c:02X}"));
                self.wire(
                    "header_value_changed",
                    format!("{path}.header.{}", f.name),
                    format!(
                        "{word} `{}`: header field `{}` holds {} → {}",
                        x.name,
                        f.name,
                        show(f.constant),
                        show(g.constant)
                    ),
                );
            }
        }
        let (mf, xf) = (
            &m.fields[mh.min(m.fields.len())..],
            &x.fields[xh.min(x.fields.len())..],
        );
        let fmap = pair_named(mf, xf, |f| &f.name, |f, g| f.offset == g.offset);
        let place = |m: &Message, f: &Field| {
            m.fields
                .iter()
                .position(|g| std::ptr::eq(g, f))
                .map_or_else(String::new, |i| m.place(i))
        };
        for (i, f) in mf.iter().enumerate() {
            let Some(g) = fmap[i].map(|j| &xf[j]) else {
                self.wire(
                    "field_removed",
                    format!("{path}.fields.{}", f.name),
                    format!(
                        "{word} `{}`: field `{}` ({} at offset {}) removed",
                        x.name,
                        f.name,
                        type_name(f),
                        place(m, f)
                    ),
                );
                continue;
            };
            let fpath = format!("{path}.fields.{}", g.name);
            let (fp, gp) = (place(m, f), place(x, g));
            if fp != gp {
                self.wire(
                    "field_offset_changed",
                    fpath.clone(),
                    format!("field `{}.{}`: offset {fp} → {gp}", x.name, g.name),
                );
            }
            self.field((m, f), (x, g), &fpath, maps);
        }
        for (j, g) in xf.iter().enumerate() {
            if !taken(&fmap, j) {
                self.wire(
                    "field_added",
                    format!("{path}.fields.{}", g.name),
                    format!(
                        "{word} `{}`: field `{}` ({} at offset {}) added",
                        x.name,
                        g.name,
                        type_name(g),
                        place(x, g)
                    ),
                );
            }
        }
        if m.needs_request != x.needs_request {
            self.api(
                "needs_request_changed",
                path.to_owned(),
                format!(
                    "response `{}` {} be told apart without its request",
                    x.name,
                    if x.needs_request {
                        "can no longer"
                    } else {
                        "can now"
                    }
                ),
            );
        }
        // Sent unasked (`unasked: true`): made so, a decoder that took it as a reply still does,
        // and one heard after another request is set aside rather than refused; no longer
        // so, a device that still sends it on its own breaks the master waiting for a reply
        // (and the response must now be listed by a command).
        match (m.unasked, x.unasked) {
            (false, true) => self.compatible(
                "unasked_added",
                format!("{path}.unasked"),
                format!(
                    "response `{}` is now also sent unasked: heard after a request that does not list it, it is set aside, not that request's reply",
                    x.name
                ),
            ),
            (true, false) => self.wire(
                "unasked_removed",
                format!("{path}.unasked"),
                format!(
                    "response `{}` is no longer sent unasked: heard after a request that does not list it, it is refused as that request's reply (a master waiting for one fails)",
                    x.name
                ),
            ),
            _ => {}
        }
        if m.reply != x.reply {
            let word = |r: crate::ir::Reply| format!("{r:?}").to_lowercase();
            self.wire(
                "reply_changed",
                format!("{path}.reply"),
                format!(
                    "command `{}`: reply {} → {}",
                    x.name,
                    word(m.reply),
                    word(x.reply)
                ),
            );
        }
        let bc = |b: &Option<crate::ir::Broadcast>| {
            b.as_ref()
                .map_or((false, false), |b| (b.accepted, b.answered))
        };
        let (ob, nb) = (bc(&m.broadcast), bc(&x.broadcast));
        if ob != nb {
            let text = format!(
                "command `{}`: broadcast accepted {} → {}, answered {} → {}",
                x.name, ob.0, nb.0, ob.1, nb.1
            );
            if (!ob.0 || nb.0) && ob.1 == nb.1 {
                self.compatible("broadcast_changed", format!("{path}.broadcast"), text);
            } else {
                self.api("broadcast_changed", format!("{path}.broadcast"), text);
            }
        }
        let kind = |m: &Message| format!("{:?}", m.kind);
        self.doc_change(
            path.to_owned(),
            &format!("{word} `{}`", x.name),
            &[
                ("section", &m.section, &x.section),
                ("title", &m.title, &x.title),
                ("doc", &m.doc, &x.doc),
                ("kind", &kind(m), &kind(x)),
            ],
        );
    }

    fn field(
        &mut self,
        (m, f): (&Message, &Field),
        (x, g): (&Message, &Field),
        path: &str,
        maps: &Maps,
    ) {
        let msg = x.name.as_str();
        let what = format!("`{msg}.{}`", g.name);
        if f.name != g.name {
            self.api(
                "field_renamed",
                path.to_owned(),
                format!("field `{msg}.{}` renamed to `{}`", f.name, g.name),
            );
        }
        let presence = |m: &Message, f: &Field| {
            f.present.map(|c| {
                let of = m.fields.get(c.field).map_or("", |h| h.name.as_str());
                c.describe(of)
            })
        };
        let (was, now) = (presence(m, f), presence(x, g));
        if was != now {
            // Optional or not, or present by another condition: the frames' lengths differ.
            let text = |c: &Option<String>| match c {
                Some(c) => format!("present only when {c}"),
                None => "always present".to_owned(),
            };
            self.wire(
                "field_presence_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", text(&was), text(&now)),
            );
        }
        if f.width != g.width {
            self.wire(
                "field_width_changed",
                path.to_owned(),
                format!(
                    "field {what}: {} → {} ({} → {} bytes)",
                    type_name(f),
                    type_name(g),
                    f.width,
                    g.width
                ),
            );
        } else if f.packed != g.packed {
            // Packed elements regrouped (their count, width or bit order; the bytes unchanged).
            self.wire(
                "field_packing_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", type_name(f), type_name(g)),
            );
        } else if f.signed != g.signed {
            self.wire(
                "field_signedness_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", type_name(f), type_name(g)),
            );
        } else if f.is_float() != g.is_float() {
            // The same bits read as another kind of number (`u32` ↔ `f32`, `u64` ↔ `f64`).
            self.wire(
                "field_number_kind_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", type_name(f), type_name(g)),
            );
        } else if f.is_ascii() != g.is_ascii() || f.ty != g.ty {
            self.api(
                "field_type_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", type_name(f), type_name(g)),
            );
        }
        if f.bcd != g.bcd {
            let show = |bcd: bool| if bcd { "bcd" } else { "binary" };
            self.wire(
                "field_encoding_changed",
                path.to_owned(),
                format!("field {what}: encoding {} → {}", show(f.bcd), show(g.bcd)),
            );
        }
        if f.word_swapped != g.word_swapped {
            let show = |swapped: bool| if swapped { "swapped" } else { "normal" };
            self.wire(
                "field_word_order_changed",
                path.to_owned(),
                format!(
                    "field {what}: word order {} → {}",
                    show(f.word_swapped),
                    show(g.word_swapped)
                ),
            );
        }
        if f.constant != g.constant {
            let show =
                |c: Option<u64>| c.map_or("not constant".to_owned(), |c| format!("0x{c:02X}"));
            self.wire(
                "constant_changed",
                path.to_owned(),
                format!(
                    "field {what}: constant {} → {}",
                    show(f.constant),
                    show(g.constant)
                ),
            );
        }
        // `equals` points at an earlier field of the same message; compare where it points.
        let (oe, ne) = (
            f.equals.and_then(|i| m.fields.get(i)).map(|e| e.offset),
            g.equals.and_then(|i| x.fields.get(i)).map(|e| e.offset),
        );
        if oe != ne {
            self.wire(
                "field_equals_changed",
                path.to_owned(),
                format!("field {what}: which earlier field it repeats changed"),
            );
        }
        let (or, nr) = (repeat_shape(m, f), repeat_shape(x, g));
        if or != nr {
            let show = |s: &Option<String>| s.clone().unwrap_or_else(|| "not repeated".to_owned());
            self.wire(
                "field_repeat_changed",
                path.to_owned(),
                format!("field {what}: {} → {}", show(&or), show(&nr)),
            );
        }
        let (of, nf) = (follows_shape(m, f), follows_shape(x, g));
        if of != nf {
            let show = |s: &Option<String>| s.clone().unwrap_or_else(|| "free".to_owned());
            self.wire(
                "field_follows_changed",
                path.to_owned(),
                format!("field {what}: value follows {} → {}", show(&of), show(&nf)),
            );
        }
        self.field_meaning(
            (f.unit, f.enumeration, f.flags),
            (g.unit, g.enumeration, g.flags),
            path,
            &what,
            maps,
        );
        if f.num_kind() == g.num_kind() {
            self.range_of(f.num_kind(), f.range, g.range, path, &what);
        } else if f.range != g.range || f.range.is_some() {
            let (ka, kb) = (f.num_kind(), g.num_kind());
            let show = |k: NumKind, r: Option<(i64, i64)>| {
                r.map_or("any".to_owned(), |(a, b)| {
                    format!("{}..={}", k.text(a), k.text(b))
                })
            };
            let text = format!(
                "field {what}: range {} → {}",
                show(ka, f.range),
                show(kb, g.range)
            );
            if g.range.is_none() {
                self.compatible("range_widened", format!("{path}.range"), text);
            } else {
                self.api(
                    "range_narrowed",
                    format!("{path}.range"),
                    format!("{text}; values valid before are now out of range"),
                );
            }
        }
        let changes = value_changes(&specials(f), &specials(g));
        self.values(
            &format!("{path}.special"),
            &format!("field {what} special value"),
            changes,
        );
        // Packed sub-fields, matched by their lowest bit.
        if f.bits.is_empty() != g.bits.is_empty() {
            self.wire(
                "field_packing_changed",
                path.to_owned(),
                format!(
                    "field {what}: {} → {}",
                    if f.bits.is_empty() {
                        "one value"
                    } else {
                        "packed sub-fields"
                    },
                    if g.bits.is_empty() {
                        "one value"
                    } else {
                        "packed sub-fields"
                    }
                ),
            );
        }
        if !f.bits.is_empty() && !g.bits.is_empty() {
            for b in &f.bits {
                let Some(c) = g.bits.iter().find(|c| c.lsb == b.lsb) else {
                    self.wire(
                        "field_removed",
                        format!("{path}.bits.{}", b.name),
                        format!(
                            "field {what}: sub-field `{}` (bits {}..{}) removed",
                            b.name, b.msb, b.lsb
                        ),
                    );
                    continue;
                };
                let bpath = format!("{path}.bits.{}", c.name);
                let bwhat = format!("`{msg}.{}`", c.name);
                if b.name != c.name {
                    self.api(
                        "field_renamed",
                        bpath.clone(),
                        format!("sub-field `{msg}.{}` renamed to `{}`", b.name, c.name),
                    );
                }
                if (b.msb, b.signed) != (c.msb, c.signed) || b.constant != c.constant {
                    self.wire(
                        "bits_changed",
                        bpath.clone(),
                        format!(
                            "sub-field {bwhat}: bits {}..{} {} → bits {}..{} {}",
                            b.msb,
                            b.lsb,
                            if b.signed { "signed" } else { "unsigned" },
                            c.msb,
                            c.lsb,
                            if c.signed { "signed" } else { "unsigned" }
                        ),
                    );
                }
                self.field_meaning(
                    (b.unit, None, None),
                    (c.unit, None, None),
                    &bpath,
                    &bwhat,
                    maps,
                );
                self.range(b.range, c.range, &bpath, &bwhat);
                self.doc_change(
                    bpath,
                    &format!("sub-field {bwhat}"),
                    &[("doc", &b.doc, &c.doc)],
                );
            }
            for c in &g.bits {
                if !f.bits.iter().any(|b| b.lsb == c.lsb) {
                    self.wire(
                        "field_added",
                        format!("{path}.bits.{}", c.name),
                        format!(
                            "field {what}: sub-field `{}` (bits {}..{}) added",
                            c.name, c.msb, c.lsb
                        ),
                    );
                }
            }
        }
        self.record_fields((m, f), (x, g), path, maps);
        self.doc_change(
            path.to_owned(),
            &format!("field {what}"),
            &[("doc", &f.doc, &g.doc)],
        );
    }

    /// A repeated record's fields, paired by their offset in the record: one added, removed
    /// or moved changes every record's bytes (wire-breaking); each pair is compared as a field
    /// (`blocks.position`), its width, type, meaning and range.
    fn record_fields(
        &mut self,
        (m, f): (&Message, &Field),
        (x, g): (&Message, &Field),
        path: &str,
        maps: &Maps,
    ) {
        let what = format!("`{}.{}`", x.name, g.name);
        for a in &f.record {
            let Some(b) = g.record.iter().find(|b| b.offset == a.offset) else {
                self.wire(
                    "record_field_removed",
                    format!("{path}.fields.{}", a.name),
                    format!(
                        "record {what}: field `{}` ({} at record offset {}) removed",
                        a.name,
                        type_name(a),
                        a.offset
                    ),
                );
                continue;
            };
            // Bytes given by another field, or another field giving them: every record moves.
            let from = |m: &Message, i: Option<usize>| i.map(|i| m.fields[i].name.clone());
            let (fa, fb) = (from(m, a.bytes_from), from(x, b.bytes_from));
            if fa != fb {
                let said = |n: &Option<String>| match n {
                    Some(n) => format!("`{n}` bytes"),
                    None => "its type's width".to_owned(),
                };
                self.wire(
                    "record_field_width_changed",
                    format!("{path}.fields.{}.bytes", b.name),
                    format!(
                        "record {what}: field `{}` takes {} → {}",
                        b.name,
                        said(&fa),
                        said(&fb)
                    ),
                );
            }
            let (mut a, mut b) = (a.clone(), b.clone());
            a.name = format!("{}.{}", f.name, a.name);
            b.name = format!("{}.{}", g.name, b.name);
            let bpath = format!("{path}.fields.{}", b.name);
            self.field((m, &a), (x, &b), &bpath, maps);
        }
        for b in &g.record {
            if !f.record.iter().any(|a| a.offset == b.offset) {
                self.wire(
                    "record_field_added",
                    format!("{path}.fields.{}", b.name),
                    format!(
                        "record {what}: field `{}` ({} at record offset {}) added",
                        b.name,
                        type_name(b),
                        b.offset
                    ),
                );
            }
        }
    }

    /// How a field's raw value is read: unit (scale and offset), enum, flags, or a plain number.
    fn field_meaning(
        &mut self,
        old: (Option<usize>, Option<usize>, Option<usize>),
        new: (Option<usize>, Option<usize>, Option<usize>),
        path: &str,
        what: &str,
        maps: &Maps,
    ) {
        let (o, n) = (self.old, self.new);
        let describe = |p: &Protocol, m: (Option<usize>, Option<usize>, Option<usize>)| match m {
            (Some(u), _, _) => format!("unit `{}`", p.units[u].name),
            (_, Some(e), _) => format!("enum `{}`", p.enums[e].name),
            (_, _, Some(f)) => format!("flags `{}`", p.flags[f].name),
            _ => "a plain number".to_owned(),
        };
        let text = format!("field {what}: {} → {}", describe(o, old), describe(n, new));
        match (old, new) {
            ((Some(a), ..), (Some(b), ..)) => {
                if maps.units[a] == Some(b) {
                    return; // the unit itself is compared once, under `units`
                }
                let (ua, ub) = (&o.units[a], &n.units[b]);
                if (ua.scale, ua.offset) != (ub.scale, ub.offset) {
                    self.wire(
                        "field_scale_changed",
                        path.to_owned(),
                        format!(
                            "{text}: physical value {} → {}",
                            conversion(ua),
                            conversion(ub)
                        ),
                    );
                } else {
                    self.api("field_type_changed", path.to_owned(), text);
                }
            }
            ((_, Some(a), _), (_, Some(b), _)) => {
                if maps.enums[a] == Some(b) {
                    return;
                }
                let lost = value_changes(&enum_values(&o.enums[a]), &enum_values(&n.enums[b]))
                    .iter()
                    .any(|c| !matches!(c, ValueChange::Added(..)));
                if lost {
                    self.wire(
                        "field_enum_changed",
                        path.to_owned(),
                        format!("{text}, whose values differ"),
                    );
                } else {
                    self.api("field_type_changed", path.to_owned(), text);
                }
            }
            ((_, _, Some(a)), (_, _, Some(b))) => {
                if maps.flags[a] == Some(b) {
                    return;
                }
                let lost = value_changes(&flag_bits(&o.flags[a]), &flag_bits(&n.flags[b]))
                    .iter()
                    .any(|c| !matches!(c, ValueChange::Added(..)));
                if lost {
                    self.wire(
                        "field_flags_changed",
                        path.to_owned(),
                        format!("{text}, whose bits differ"),
                    );
                } else {
                    self.api("field_type_changed", path.to_owned(), text);
                }
            }
            _ if old == (None, None, None) && new == (None, None, None) => {}
            ((Some(a), ..), _)
                if o.units[a].scale != Rational::ONE || o.units[a].offset != Rational::ZERO =>
            {
                // A scaled number becoming an enum, flags or plain number: its value changes.
                self.wire("field_scale_changed", path.to_owned(), text);
            }
            (_, (Some(b), ..))
                if n.units[b].scale != Rational::ONE || n.units[b].offset != Rational::ZERO =>
            {
                self.wire("field_scale_changed", path.to_owned(), text);
            }
            _ => self.api("field_type_changed", path.to_owned(), text),
        }
    }

    fn range(&mut self, a: Option<(i64, i64)>, b: Option<(i64, i64)>, path: &str, what: &str) {
        self.range_of(NumKind::Int, a, b, path, what);
    }

    /// A range change, its raw values read as `k` reads them (a `u64`'s or a float's bits).
    fn range_of(
        &mut self,
        k: NumKind,
        a: Option<(i64, i64)>,
        b: Option<(i64, i64)>,
        path: &str,
        what: &str,
    ) {
        let wider = match (a, b) {
            _ if a == b => None,
            (Some((lo, hi)), Some((c, d))) => Some(k.within(lo, c, d) && k.within(hi, c, d)),
            _ => widened(a, b),
        };
        let Some(wider) = wider else {
            return;
        };
        let show = |r: Option<(i64, i64)>| match r {
            Some((x, y)) => format!("{}..={}", k.text(x), k.text(y)),
            None => range_text(None),
        };
        let text = format!("field {what}: range {} → {}", show(a), show(b));
        if wider {
            self.compatible("range_widened", format!("{path}.range"), text);
        } else {
            self.api(
                "range_narrowed",
                format!("{path}.range"),
                format!("{text}; values valid before are now out of range"),
            );
        }
    }

    /// The replies each command may get, and the common ones.
    fn replies(&mut self, maps: &Maps) {
        let (o, n) = (self.old, self.new);
        let rmap = &maps.messages[&Direction::Response];
        let cmap = &maps.messages[&Direction::Request];
        let mapped =
            |set: &[usize]| -> BTreeSet<Option<usize>> { set.iter().map(|&r| rmap[r]).collect() };
        let old_common = mapped(&o.common_responses);
        let new_common: BTreeSet<Option<usize>> =
            n.common_responses.iter().map(|&r| Some(r)).collect();
        let name = |r: Option<usize>| r.map_or("?", |r| n.responses[r].name.as_str());
        for r in &o.common_responses {
            if !new_common.contains(&rmap[*r]) {
                self.wire(
                    "reply_removed",
                    "common_responses".to_owned(),
                    format!(
                        "`{}` is no longer a response every command may get",
                        o.responses[*r].name
                    ),
                );
            }
        }
        for r in new_common.difference(&old_common) {
            self.compatible(
                "reply_added",
                "common_responses".to_owned(),
                format!("`{}` is now a response every command may get", name(*r)),
            );
        }
        for (i, c) in o.commands.iter().enumerate() {
            let Some(j) = cmap[i] else { continue };
            let d = &n.commands[j];
            let before: BTreeMap<Option<usize>, Option<&String>> = c
                .responses
                .iter()
                .map(|(r, meaning)| (rmap[*r], meaning.as_ref()))
                .collect();
            let after: BTreeMap<Option<usize>, Option<&String>> = d
                .responses
                .iter()
                .map(|(r, meaning)| (Some(*r), meaning.as_ref()))
                .collect();
            let path = format!("commands.{}.responses", d.name);
            for (idx, _) in &c.responses {
                let r = &rmap[*idx];
                let common_change = old_common.contains(r) && !new_common.contains(r);
                if !after.contains_key(r) && !common_change {
                    self.wire(
                        "reply_removed",
                        path.clone(),
                        format!(
                            "command `{}` no longer gets `{}`",
                            d.name, o.responses[*idx].name
                        ),
                    );
                }
            }
            for (r, meaning) in &after {
                match before.get(r) {
                    None if !new_common.contains(r) || old_common.contains(r) => self.compatible(
                        "reply_added",
                        path.clone(),
                        format!("command `{}` may now get `{}`", d.name, name(*r)),
                    ),
                    Some(m) if m != meaning => self.compatible(
                        "documentation_changed",
                        format!("commands.{}.response_meanings.{}", d.name, name(*r)),
                        format!("command `{}`: meaning of `{}` changed", d.name, name(*r)),
                    ),
                    _ => {}
                }
            }
        }
    }

    fn examples(&mut self) {
        let (o, n) = (&self.old.examples, &self.new.examples);
        let key = |e: &crate::ir::Example| {
            (
                e.section.clone(),
                e.printed
                    .clone()
                    .or_else(|| e.derived.clone())
                    .unwrap_or_default(),
            )
        };
        let label = |p: &Protocol, e: &crate::ir::Example| {
            format!(
                "§{} `{}` `{}`",
                e.section,
                p.message(e.message).name,
                e.printed.as_deref().or(e.derived.as_deref()).unwrap_or("")
            )
        };
        let mut used = vec![false; n.len()];
        for e in o {
            let found = (0..n.len()).find(|&j| !used[j] && key(&n[j]) == key(e));
            match found {
                Some(j) => {
                    used[j] = true;
                    let f = &n[j];
                    let erratum = |p: &Protocol, e: &crate::ir::Example| {
                        e.erratum.map(|i| p.errata[i].id.clone())
                    };
                    if e.values != f.values
                        || e.comment != f.comment
                        || e.corrected != f.corrected
                        || erratum(self.old, e) != erratum(self.new, f)
                    {
                        self.compatible(
                            "example_changed",
                            "examples".to_owned(),
                            format!("example {} changed", label(self.new, f)),
                        );
                    }
                }
                None => self.compatible(
                    "example_removed",
                    "examples".to_owned(),
                    format!("example {} removed", label(self.old, e)),
                ),
            }
        }
        for (j, f) in n.iter().enumerate() {
            if !used[j] {
                self.compatible(
                    "example_added",
                    "examples".to_owned(),
                    format!("example {} added", label(self.new, f)),
                );
            }
        }
    }

    fn errata(&mut self) {
        let (o, n) = (&self.old.errata, &self.new.errata);
        for e in o {
            match n.iter().find(|f| f.id == e.id) {
                None => self.compatible(
                    "erratum_removed",
                    format!("errata.{}", e.id),
                    format!("erratum {} (§{}) removed", e.id, e.section),
                ),
                Some(f) => self.doc_change(
                    format!("errata.{}", f.id),
                    &format!("erratum {}", f.id),
                    &[
                        ("section", &e.section, &f.section),
                        ("says", &e.says, &f.says),
                        ("decision", &e.decision, &f.decision),
                        ("why", &e.why, &f.why),
                    ],
                ),
            }
        }
        for f in n {
            if !o.iter().any(|e| e.id == f.id) {
                self.compatible(
                    "erratum_added",
                    format!("errata.{}", f.id),
                    format!("erratum {} (§{}) added", f.id, f.section),
                );
            }
        }
    }
}

/// A message's wire identity within its direction: its code and its constant fields
/// (offset, value), which select between messages sharing a code.
/// What tells a message apart on the wire: its code, its constant fields (offset, value) and
/// its constant whole frame.
type WireKey = (Vec<u8>, Vec<(usize, u64)>, Option<Vec<u8>>);

fn key(m: &Message) -> WireKey {
    let constants = m
        .fields
        .iter()
        .filter_map(|f| f.constant.map(|c| (f.offset, c)))
        .collect();
    (m.code.clone(), constants, m.frame.clone())
}

/// A message's code as the texts give it (`0x2000`), or a constant whole frame's bytes
/// (`frame E5`).
fn code_of(m: &Message) -> String {
    match &m.frame {
        Some(f) => format!("frame {}", bytes(f)),
        None => m.code_hex(),
    }
}

/// Bytes in hex, `none` for none (sync and end bytes).
fn bytes(s: &[u8]) -> String {
    if s.is_empty() {
        return "none".to_owned();
    }
    s.iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_matched_by_number_and_a_moved_name_is_renumbered() {
        let old = [(0, "idle"), (1, "manual"), (2, "auto")];
        let new = [(0, "idle"), (1, "hand"), (3, "auto"), (4, "service")];
        let got: Vec<String> = value_changes(&old, &new)
            .into_iter()
            .map(|c| match c {
                ValueChange::Removed(v, n) => format!("-{v}{n}"),
                ValueChange::Renumbered(n, a, b) => format!("{n}:{a}>{b}"),
                ValueChange::Renamed(v, a, b) => format!("{v}:{a}>{b}"),
                ValueChange::Added(v, n) => format!("+{v}{n}"),
            })
            .collect();
        assert_eq!(got, ["1:manual>hand", "auto:2>3", "+4service"]);
    }

    #[test]
    fn a_range_that_contains_the_old_one_is_wider() {
        assert_eq!(widened(Some((0, 9)), Some((0, 9))), None);
        assert_eq!(widened(Some((0, 9)), Some((0, 10))), Some(true));
        assert_eq!(widened(Some((0, 9)), None), Some(true));
        assert_eq!(widened(None, Some((0, 9))), Some(false));
        assert_eq!(widened(Some((0, 9)), Some((1, 12))), Some(false));
    }
}
