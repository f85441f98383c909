//! YAML text to [`Spec`]: shape errors only, every one of them, each with its path.
//!
//! The file is parsed to a YAML tree first, then each top-level key and each element of each
//! list is deserialized on its own, so one misspelt key in one command does not hide the errors
//! in the next.
//!
//! Nothing here panics or runs long on any input. Before serde_yaml sees the text, [`prescan`]
//! reads it once, in linear time, and refuses what would make libyaml or the YAML tree costly:
//! more than [`MAX_SPEC_BYTES`], control characters, collections nested deeper than
//! [`MAX_DEPTH`] (flow brackets and indentation together: libyaml's scanner is quadratic in flow
//! depth, and serde_yaml's recursion limit fires only after the whole text is scanned), more
//! than [`MAX_ANCHORS`] anchors or [`MAX_ALIASES`] aliases, aliases that would add more than
//! [`MAX_ALIAS_NODES`] nodes to the tree (a "billion laughs"), and scalars longer than
//! [`MAX_SCALAR_BYTES`]. It lexes enough YAML (quoted scalars, comments, block scalars, plain
//! scalars) not to count what only looks like structure. What passes it is small and shallow, and
//! serde_yaml's own bounds (recursion depth 128, alias repetitions) stay behind it.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde_yaml::{Mapping, Value};

use crate::diag::{join, Sink};
use crate::model::{self, Spec, SPEC_KEYS};

/// Top-level keys whose values are lists deserialized element by element.
const LIST_KEYS: &[&str] = &[
    "units",
    "enums",
    "flags",
    "commands",
    "responses",
    "examples",
    "errata",
];

/// Parses spec text. On failure returns every shape error found (or the one limit [`prescan`]
/// found exceeded). A spec read this way cannot `include` files ([`parse_with`] can).
pub fn parse(text: &str, sink: &mut Sink) -> Option<Spec> {
    parse_with(text, None, &mut Included::default(), sink)
}

/// [`parse`] of a spec read from a file in directory `dir`: the files its `include` names are
/// read from there (`included` says which, and what each brought in, also on failure).
pub fn parse_with(
    text: &str,
    dir: Option<&Path>,
    included: &mut Included,
    sink: &mut Sink,
) -> Option<Spec> {
    let mut map = yaml_mapping(text, "spec keys", sink)?;
    if let Some(value) = map.remove("include") {
        let before = sink.items.len();
        include(&mut map, &value, dir, text.len(), included, sink);
        // What the spec refers to in a file not read would only be reported missing.
        if sink.items.len() > before {
            return None;
        }
        if !included.files.is_empty() {
            included.flattened = serde_yaml::to_string(&Value::Mapping(map.clone())).ok();
        }
    }
    for key in map.keys() {
        match key.as_str() {
            Some(k) if SPEC_KEYS.contains(&k) => {}
            Some(k) => sink.error(
                k,
                format!(
                    "unknown key `{k}`, expected one of include, {}",
                    SPEC_KEYS.join(", ")
                ),
            ),
            None => sink.error(
                "",
                format!("top-level keys must be strings, found {}", kind(key)),
            ),
        }
    }

    // Lists are taken out and read element by element, after the rest.
    let mut lists: Vec<(&str, Vec<Value>)> = Vec::new();
    for &key in LIST_KEYS {
        match map.remove(key) {
            None | Some(Value::Null) => lists.push((key, Vec::new())),
            Some(Value::Sequence(items)) => {
                map.insert(Value::from(key), Value::Sequence(Vec::new()));
                lists.push((key, items));
            }
            Some(other) => {
                sink.error(key, format!("expected a list, found {}", kind(&other)));
                lists.push((key, Vec::new()));
            }
        }
    }
    map.retain(|k, _| k.as_str().is_some_and(|k| SPEC_KEYS.contains(&k)));
    // The other keys are read one by one too, so that an error in `serial` does not hide one in
    // `framing`, and every missing key is named, not just the first.
    let errors_before = sink.items.len();
    for (key, value) in &map {
        if let Some(key) = key.as_str() {
            read_key(key, value, sink);
        }
    }
    for key in SPEC_KEYS.iter().filter(|k| required(k)) {
        if !map.contains_key(*key) {
            sink.error("", format!("missing field `{key}`"));
        }
    }
    let head: Option<Spec> = if sink.items.len() == errors_before {
        deserialize_at(&Value::Mapping(map), String::new, sink)
    } else {
        None
    };

    // Every list is read even when the head failed: its errors are reported all the same.
    let mut spec = head;
    for (key, items) in lists {
        let s = spec.as_mut();
        match key {
            "units" => set(s, elements(key, &items, sink), |s| &mut s.units),
            "enums" => set(s, elements(key, &items, sink), |s| &mut s.enums),
            "flags" => set(s, elements(key, &items, sink), |s| &mut s.flags),
            "commands" => set(s, elements(key, &items, sink), |s| &mut s.commands),
            "responses" => set(s, elements(key, &items, sink), |s| &mut s.responses),
            "examples" => set(s, elements(key, &items, sink), |s| &mut s.examples),
            "errata" => set(s, elements(key, &items, sink), |s| &mut s.errata),
            _ => unreachable_key(key, sink),
        }
    }
    spec.filter(|_| sink.is_empty())
}

/// Text to its top-level YAML mapping (of `what`), after [`prescan`]; errors located by line.
fn yaml_mapping(text: &str, what: &str, sink: &mut Sink) -> Option<Mapping> {
    if let Err(refusal) = prescan(text) {
        sink.error(refusal.path(), refusal.message);
        return None;
    }
    let root: Value = match serde_yaml::from_str(text) {
        Ok(v) => v,
        Err(e) => {
            let at = e
                .location()
                .map(|l| format!("line {} column {}", l.line(), l.column()))
                .unwrap_or_else(|| "(top)".to_owned());
            sink.error(
                at,
                format!(
                    "not valid YAML: {}",
                    explain_big_integer(&strip_location(&e.to_string()))
                ),
            );
            return None;
        }
    };
    match root {
        Value::Mapping(map) => Some(map),
        other => {
            sink.error(
                "",
                format!(
                    "expected a mapping of {what} at the top, found {}",
                    kind(&other)
                ),
            );
            None
        }
    }
}

/// The lists an included file may hold: common types, which any spec may share.
pub const INCLUDED_LISTS: &[&str] = &["units", "enums", "flags"];

/// How deep includes may nest (a file that includes a file that includes ...).
pub const MAX_INCLUDE_DEPTH: usize = 8;

/// Files one spec may include, nested includes counted.
pub const MAX_INCLUDED_FILES: usize = 32;

/// What a spec's `include` read.
#[derive(Debug, Default, Clone)]
pub struct Included {
    /// Each file read, in the order read (a file included twice is read once): its path as
    /// the spec's diagnostics name it (relative to the spec's directory), where it was read
    /// from, and its text.
    pub files: Vec<(String, PathBuf, String)>,
    /// Each unit, enum and flag set an included file brought: list key, name, the file (as
    /// named in `files`).
    pub origin: Vec<(&'static str, String, String)>,
    /// The spec with every included item in place and no `include`: YAML text that loads
    /// without the files (what a generated crate embeds as its spec). `None` without includes.
    pub flattened: Option<String>,
}

impl Included {
    /// The included file unit, enum or flag set `name` of list `key` came from.
    pub fn origin_of(&self, key: &str, name: &str) -> Option<&str> {
        self.origin
            .iter()
            .find(|(k, n, _)| *k == key && n == name)
            .map(|(_, _, f)| f.as_str())
    }

    /// The diagnostic path `path` names something an included file holds: that file's path
    /// before it (`include common.yaml: units.volts.scale`); any other path as it is.
    pub fn locate(&self, path: &str) -> String {
        for key in INCLUDED_LISTS {
            let Some(rest) = path.strip_prefix(key).and_then(|r| r.strip_prefix('.')) else {
                continue;
            };
            let name = rest.split('.').next().unwrap_or(rest);
            if let Some(file) = self.origin_of(key, name) {
                return format!("include {file}: {path}");
            }
        }
        path.to_owned()
    }
}

/// Reads the files `value` (a file name or a list of them) names, relative to `dir`, and puts
/// their units, enums and flag sets into `map`'s lists before the spec's own, in include
/// order. A name defined twice is reported once and its later definition dropped. The spec
/// (`spec_bytes` long) and its included files together stay within [`MAX_SPEC_BYTES`].
fn include(
    map: &mut Mapping,
    value: &Value,
    dir: Option<&Path>,
    spec_bytes: usize,
    included: &mut Included,
    sink: &mut Sink,
) {
    let Some(dir) = dir else {
        sink.error(
            "include",
            "a spec given as text cannot include files (there is no directory to find them in): load it from its file",
        );
        return;
    };
    let mut lists: Vec<(&'static str, Vec<(Value, String)>)> =
        INCLUDED_LISTS.iter().map(|k| (*k, Vec::new())).collect();
    let mut reading = Reading {
        chain: Vec::new(),
        bytes: spec_bytes,
        lists: &mut lists,
        included,
    };
    reading.files(value, dir, Path::new(""), "include", sink);
    for (key, mut items) in lists {
        match map.remove(key) {
            None | Some(Value::Null) => {}
            Some(Value::Sequence(own)) => {
                items.extend(own.into_iter().map(|v| (v, "this spec".to_owned())));
            }
            Some(other) => {
                // Its shape is reported where the lists are read.
                map.insert(Value::from(key), other);
                continue;
            }
        }
        let mut kept: Vec<Value> = Vec::with_capacity(items.len());
        let mut seen: Vec<(String, String)> = Vec::new();
        for (item, from) in items {
            if let Some(name) = item.get("name").and_then(Value::as_str) {
                if let Some((_, first)) = seen.iter().find(|(n, _)| n == name) {
                    sink.error(
                        "include",
                        format!("`{key}` has `{name}` in {first} and again in {from}: a name is defined once"),
                    );
                    continue;
                }
                seen.push((name.to_owned(), from));
            }
            kept.push(item);
        }
        map.insert(Value::from(key), Value::Sequence(kept));
    }
}

/// The state of reading a spec's includes: the files being read (to refuse a cycle), the
/// bytes read in all, and the included lists so far.
struct Reading<'a> {
    chain: Vec<PathBuf>,
    bytes: usize,
    lists: &'a mut Vec<(&'static str, Vec<(Value, String)>)>,
    included: &'a mut Included,
}

impl Reading<'_> {
    /// Reads each file `value` names (relative to `dir`, shown relative to `shown_dir`).
    fn files(&mut self, value: &Value, dir: &Path, shown_dir: &Path, at: &str, sink: &mut Sink) {
        let names: Vec<&str> = match value {
            Value::String(s) => vec![s.as_str()],
            Value::Sequence(items) => {
                let mut names = Vec::new();
                for (i, item) in items.iter().enumerate() {
                    match item.as_str() {
                        Some(name) => names.push(name),
                        None => sink.error(
                            format!("{at}[{i}]"),
                            format!("expected a file name, found {}", kind(item)),
                        ),
                    }
                }
                names
            }
            other => {
                sink.error(
                    at,
                    format!(
                        "expected a file name or a list of file names, found {}",
                        kind(other)
                    ),
                );
                return;
            }
        };
        for name in names {
            self.file(name, dir, shown_dir, at, sink);
        }
    }

    fn file(&mut self, name: &str, dir: &Path, shown_dir: &Path, at: &str, sink: &mut Sink) {
        let shown = shown_dir.join(name).display().to_string();
        let path = dir.join(name);
        let here = format!("{at} {shown}");
        if self.chain.len() >= MAX_INCLUDE_DEPTH {
            sink.error(
                here,
                format!("includes nest deeper than {MAX_INCLUDE_DEPTH} files"),
            );
            return;
        }
        let canonical = match std::fs::canonicalize(&path) {
            Ok(c) => c,
            Err(e) => {
                sink.error(here, format!("cannot read: {e}"));
                return;
            }
        };
        if let Some(i) = self.chain.iter().position(|c| *c == canonical) {
            let cycle: Vec<String> = self.chain[i..]
                .iter()
                .chain([&canonical])
                .map(|c| {
                    c.file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
                })
                .collect();
            sink.error(here, format!("includes itself: {}", cycle.join(" -> ")));
            return;
        }
        // A file two others include is read once.
        if self.included.files.iter().any(|f| f.1 == canonical) {
            return;
        }
        if self.included.files.len() >= MAX_INCLUDED_FILES {
            sink.error(
                here,
                format!("a spec may include at most {MAX_INCLUDED_FILES} files"),
            );
            return;
        }
        // A spec names what it includes: a device, a pipe or a FIFO (whose opening waits for
        // a writer) would make loading hang or read without end.
        if !canonical.is_file() {
            sink.error(
                here,
                "not a regular file: an included file holds common types (units, enums, flags)",
            );
            return;
        }
        let text = match read_text(&path, MAX_SPEC_BYTES.saturating_sub(self.bytes)) {
            Ok(text) => text,
            Err((p, message)) => {
                sink.error(join_file(&here, &p), message);
                return;
            }
        };
        self.bytes += text.len();
        let mut inner = Sink::default();
        let map = yaml_mapping(
            &text,
            "common types (units, enums, flags, include)",
            &mut inner,
        );
        let before = sink.items.len();
        for d in inner.items.drain(..) {
            sink.error(join_file(&here, &d.path), d.message);
        }
        let Some(mut map) = map else {
            return;
        };
        self.included
            .files
            .push((shown.clone(), canonical.clone(), text));
        for key in map.keys() {
            match key.as_str() {
                Some(k) if k == "include" || INCLUDED_LISTS.contains(&k) => {}
                Some(k) => sink.error(
                    join_file(&here, k),
                    format!("an included file holds common types only (units, enums, flags and include), not `{k}`"),
                ),
                None => sink.error(
                    here.clone(),
                    format!("top-level keys must be strings, found {}", kind(key)),
                ),
            }
        }
        if sink.items.len() > before {
            return;
        }
        // Its own includes come first: what it includes, it builds on.
        if let Some(value) = map.remove("include") {
            self.chain.push(canonical.clone());
            let inner_dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
            let inner_shown = Path::new(&shown)
                .parent()
                .unwrap_or(Path::new(""))
                .to_path_buf();
            self.files(
                &value,
                &inner_dir,
                &inner_shown,
                &format!("{here}: include"),
                sink,
            );
            self.chain.pop();
        }
        for (key, items) in self.lists.iter_mut() {
            match map.remove(*key) {
                None | Some(Value::Null) => {}
                Some(Value::Sequence(list)) => {
                    for item in list {
                        if let Some(name) = item.get("name").and_then(Value::as_str) {
                            self.included
                                .origin
                                .push((key, name.to_owned(), shown.clone()));
                        }
                        items.push((item, shown.clone()));
                    }
                }
                Some(other) => sink.error(
                    join_file(&here, key),
                    format!("expected a list, found {}", kind(&other)),
                ),
            }
        }
    }
}

/// A path inside an included file, after the file (`include common.yaml: line 3 column 1`).
fn join_file(file: &str, path: &str) -> String {
    if path.is_empty() {
        file.to_owned()
    } else {
        format!("{file}: {path}")
    }
}

/// Reads a spec file's text: at most `limit` bytes (and one more, to tell a larger file), which
/// must be UTF-8. An error is a diagnostic path (a line and column where one applies) and what
/// is wrong.
pub fn read_text(path: &Path, limit: usize) -> Result<String, (String, String)> {
    use std::io::Read;
    let cannot = |e: std::io::Error| (String::new(), format!("cannot read: {e}"));
    let f = std::fs::File::open(path).map_err(cannot)?;
    let declared = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::new();
    f.take(limit as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() > limit {
        let len = declared.max(bytes.len() as u64) as usize;
        let r = if limit == MAX_SPEC_BYTES {
            too_large(&bytes, len)
        } else {
            Refusal::at(
                &bytes,
                limit,
                format!("the spec and the files it includes are limited to {MAX_SPEC_BYTES} bytes together; this file is {len} bytes"),
            )
        };
        return Err((r.path(), r.message));
    }
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let r = Refusal::at(
            bytes,
            at,
            format!(
                "not UTF-8 text: invalid byte 0x{:02X} at offset {at}",
                bytes.get(at).copied().unwrap_or(0)
            ),
        );
        (r.path(), r.message)
    })
}

/// Top-level keys with a default when absent: the lists, `common_responses`, `transactions` and
/// `device`.
const DEFAULTED_KEYS: &[&str] = &["common_responses", "transactions", "device"];

/// Whether a top-level key must be present: [`Spec`]'s fields without a default.
fn required(key: &str) -> bool {
    !LIST_KEYS.contains(&key) && !DEFAULTED_KEYS.contains(&key)
}

/// Reads one top-level key that is not a list, reporting its shape errors.
fn read_key(key: &str, value: &Value, sink: &mut Sink) {
    fn check<T: DeserializeOwned>(value: &Value, key: &str, sink: &mut Sink) {
        let _: Option<T> = deserialize_at(value, || key.to_owned(), sink);
    }
    match key {
        "protocol" | "title" => check::<String>(value, key, sink),
        "document" => check::<model::Document>(value, key, sink),
        "byte_order" | "printed_byte_order" => check::<model::ByteOrder>(value, key, sink),
        "serial" => check::<model::Serial>(value, key, sink),
        "framing" => check::<model::Framing>(value, key, sink),
        "common_responses" => check::<Vec<String>>(value, key, sink),
        "transactions" => check::<crate::transactions::Section>(value, key, sink),
        "device" => check::<crate::device::Section>(value, key, sink),
        // Lists (emptied above: read element by element) and keys reported as unknown.
        _ => {}
    }
}

fn set<T>(spec: Option<&mut Spec>, items: Vec<T>, field: impl FnOnce(&mut Spec) -> &mut Vec<T>) {
    if let Some(spec) = spec {
        *field(spec) = items;
    }
}

fn unreachable_key(key: &str, sink: &mut Sink) {
    // LIST_KEYS and the match above are kept in step; say so loudly rather than panic.
    sink.error(key, "internal: list key without a reader");
}

/// Reads each element of a list on its own, naming it by its `name` (or `id`) where it has one.
fn elements<T: DeserializeOwned>(key: &str, items: &[Value], sink: &mut Sink) -> Vec<T> {
    let mut out = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let path = || {
            join(
                key,
                &element_label(item).unwrap_or_else(|| format!("[{i}]")),
            )
        };
        if let Some(v) = deserialize_at(item, path, sink) {
            out.push(v);
        }
    }
    out
}

/// The segment naming a list element: its `name`, else its `id`, else its `message` with index.
pub fn element_label(item: &Value) -> Option<String> {
    let map = item.as_mapping()?;
    for key in ["name", "id"] {
        if let Some(s) = map.get(key).and_then(Value::as_str) {
            if !s.is_empty() && !s.contains(['.', '[', ']', ' ']) {
                return Some(s.to_owned());
            }
        }
    }
    None
}

/// Deserializes `value`, or reports its error at `path` (worked out only then) and the path
/// inside it. The value is read without tracking the path first: the path inside is needed
/// only for an error, and the same value gives the same error when read again tracking it.
fn deserialize_at<T: DeserializeOwned>(
    value: &Value,
    path: impl FnOnce() -> String,
    sink: &mut Sink,
) -> Option<T> {
    if let Ok(v) = T::deserialize(value) {
        return Some(v);
    }
    match serde_path_to_error::deserialize::<_, T>(value) {
        Ok(v) => Some(v),
        Err(e) => {
            let inner = named_path(value, e.path());
            let path = path();
            let at = if inner.is_empty() {
                path
            } else {
                join(&path, &inner)
            };
            sink.error(at, strip_location(&e.into_inner().to_string()));
            None
        }
    }
}

/// Renders serde's path inside `value` the way the validator names things, so that one field
/// has one path whichever stage complains: a list element by its `name` (or `id`) where it has
/// one (`fields.target`), by its index otherwise (`examples[3]`).
fn named_path(value: &Value, path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    let mut at = Some(value);
    for segment in path {
        let (label, next) = match segment {
            Segment::Seq { index } => {
                let item = at.and_then(Value::as_sequence).and_then(|s| s.get(*index));
                let label = item
                    .and_then(element_label)
                    .unwrap_or_else(|| format!("[{index}]"));
                (label, item)
            }
            Segment::Map { key } => (key.clone(), at.and_then(|v| v.get(key.as_str()))),
            Segment::Enum { variant } => (variant.clone(), None),
            Segment::Unknown => ("?".to_owned(), None),
        };
        out = join(&out, &label);
        at = next;
    }
    out
}

/// serde_yaml reads an integer beyond 64 bits as a u128 or i128, which its `Value` cannot hold,
/// and says "invalid type: integer `N` as u128, expected any YAML value": say what is wrong.
fn explain_big_integer(msg: &str) -> String {
    for ty in ["u128", "i128"] {
        let tail = format!(" as {ty}, expected any YAML value");
        if let (Some(start), Some(end)) = (msg.find("invalid type: integer `"), msg.find(&tail)) {
            if start < end {
                let number = &msg[start + "invalid type: integer ".len()..end];
                return format!(
                    "{}integer {number} is too large: numbers must fit in 64 bits{}",
                    &msg[..start],
                    &msg[end + tail.len()..]
                );
            }
        }
    }
    msg.to_owned()
}

/// serde_yaml appends " at line L column C" to messages; the path already says where.
fn strip_location(msg: &str) -> String {
    match msg.find(" at line ") {
        Some(i) => msg[..i].to_owned(),
        None => msg.to_owned(),
    }
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "nothing",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Sequence(_) => "a list",
        Value::Mapping(_) => "a mapping",
        Value::Tagged(_) => "a tagged value",
    }
}

/// Reads a mapping's entries as `(name, value)` pairs in file order, reporting non-string keys.
pub fn named_entries<'a>(
    map: &'a Mapping,
    path: &str,
    sink: &mut Sink,
) -> Vec<(String, &'a Value)> {
    let mut out = Vec::new();
    for (k, v) in map {
        match k.as_str() {
            Some(s) => out.push((s.to_owned(), v)),
            None => sink.error(path, format!("keys must be names, found {}", kind(k))),
        }
    }
    out
}

pub fn describe(v: &Value) -> &'static str {
    kind(v)
}

// ---- the pre-scan: limits checked in one linear pass before serde_yaml sees the text

/// Specs larger than this are refused before parsing: real ones are under 100 KiB.
pub const MAX_SPEC_BYTES: usize = 4 << 20;

/// Collections nested deeper than this (flow brackets and indentation levels together) are
/// refused. A real spec nests under 10 (`commands`, a command, `fields`, a field, `bits`, ...).
pub const MAX_DEPTH: usize = 64;

/// Anchors (`&name`) a spec may define. Specs need none; a few are allowed for shared lists.
pub const MAX_ANCHORS: usize = 256;

/// Aliases (`*name`) a spec may use.
pub const MAX_ALIASES: usize = 256;

/// Nodes (scalars and collections) that aliases may add to the YAML tree, counted as expanded:
/// an alias of an anchored list of nine aliases of lists of nine scalars adds 91. This is what
/// stops a "billion laughs", where few aliases expand to billions of nodes.
pub const MAX_ALIAS_NODES: u64 = 100_000;

/// Bytes one scalar may hold (quoted, plain or a block scalar's content). A real spec's
/// longest is a doc text of a few KiB.
pub const MAX_SCALAR_BYTES: usize = 64 << 10;

/// A limit [`prescan`] found exceeded, and where: 1-based line and column (in characters).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl Refusal {
    /// A refusal at byte `offset` of `text`.
    pub fn at(text: &[u8], offset: usize, message: String) -> Refusal {
        let (line, column) = line_column(text, offset);
        Refusal {
            line,
            column,
            message,
        }
    }

    /// The diagnostic path: `line L column C`, as for serde_yaml's errors.
    pub fn path(&self) -> String {
        format!("line {} column {}", self.line, self.column)
    }
}

/// 1-based line and column (in characters, counting a byte that is not UTF-8 as one) of byte
/// `offset` of `text`.
pub fn line_column(text: &[u8], offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    // Every byte but a UTF-8 continuation byte starts a character.
    let column = 1 + before[line_start..]
        .iter()
        .filter(|&&b| b & 0xC0 != 0x80)
        .count();
    (line, column)
}

/// Checks the limits above in one pass over `text`, linear in its length, and returns the first
/// one exceeded. Brackets, `&`, `*` and `#` inside quoted scalars, plain scalars, comments and
/// block scalars are not counted.
pub fn prescan(text: &str) -> Result<(), Refusal> {
    let b = text.as_bytes();
    if b.len() > MAX_SPEC_BYTES {
        return Err(too_large(b, b.len()));
    }
    control_characters(text)?;
    Scanner::new(b).run()
}

/// The refusal of a text of `len` bytes, located at its first byte past the limit.
pub fn too_large(text: &[u8], len: usize) -> Refusal {
    Refusal::at(
        text,
        MAX_SPEC_BYTES,
        format!(
            "the file is {len} bytes; specs are limited to {MAX_SPEC_BYTES} bytes ({} MiB)",
            MAX_SPEC_BYTES >> 20
        ),
    )
}

/// YAML text holds printable characters, tab, line feed and carriage return only (YAML 1.2
/// `c-printable`); libyaml refuses the rest too, but only once it reaches them.
fn control_characters(text: &str) -> Result<(), Refusal> {
    let bad = |c: char| match c {
        '\t' | '\n' | '\r' | '\u{85}' => false,
        '\0'..='\u{1F}' | '\u{7F}'..='\u{9F}' | '\u{FFFE}' | '\u{FFFF}' => true,
        _ => false,
    };
    match text.char_indices().find(|&(_, c)| bad(c)) {
        None => Ok(()),
        Some((i, c)) => Err(Refusal::at(
            text.as_bytes(),
            i,
            format!(
                "control character U+{:04X}{} is not allowed: a spec holds printable text, tabs and line breaks only",
                c as u32,
                if c == '\0' { " (NUL)" } else { "" }
            ),
        )),
    }
}

/// A block scalar (`|` or `>`) whose content lines are being skipped.
struct BlockScalar {
    /// Content lines are indented more than this (the column of the key or `-` owning it).
    above: usize,
    /// The content's indentation, set by its first non-blank line.
    indent: Option<usize>,
    /// Where its header is, and its content's length so far.
    start: usize,
    len: usize,
}

/// Where an anchored collection ends.
#[derive(Clone, Copy)]
enum End {
    /// When the flow depth falls back to this.
    Flow(usize),
    /// At the first line indented at most this.
    Block(usize),
}

/// An anchored collection not yet closed: its size is the nodes counted while it is open.
struct Open<'t> {
    name: &'t [u8],
    nodes_before: u64,
    end: End,
}

struct Scanner<'t> {
    b: &'t [u8],
    i: usize,
    line_start: usize,
    /// Flow depth (`[` and `{` open).
    flow: usize,
    /// The indentation of each open block level.
    block: Vec<usize>,
    /// Column of the key or `-` whose value comes next on this line.
    node_col: usize,
    /// Column of the last scalar on this line: the key, if a `:` follows.
    key_col: usize,
    block_scalar: Option<BlockScalar>,
    anchors: usize,
    aliases: usize,
    /// Nodes so far, aliases counted as what they expand to.
    nodes: u64,
    alias_nodes: u64,
    /// The size in nodes of each anchored node.
    defined: std::collections::HashMap<&'t [u8], u64>,
    open: Vec<Open<'t>>,
    /// An anchor whose node has not started yet.
    pending: Option<&'t [u8]>,
}

fn is_space(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r' | b'\n')
}

fn is_flow_indicator(c: u8) -> bool {
    matches!(c, b',' | b'[' | b']' | b'{' | b'}')
}

impl<'t> Scanner<'t> {
    fn new(b: &'t [u8]) -> Self {
        Scanner {
            b,
            // A byte order mark is not content.
            i: if b.starts_with("\u{FEFF}".as_bytes()) {
                3
            } else {
                0
            },
            line_start: 0,
            flow: 0,
            block: Vec::new(),
            node_col: 0,
            key_col: 0,
            block_scalar: None,
            anchors: 0,
            aliases: 0,
            nodes: 0,
            alias_nodes: 0,
            defined: std::collections::HashMap::new(),
            open: Vec::new(),
            pending: None,
        }
    }

    fn run(mut self) -> Result<(), Refusal> {
        let mut at_line_start = true;
        while self.i < self.b.len() {
            if at_line_start {
                at_line_start = false;
                self.line()?;
                continue;
            }
            let c = self.b[self.i];
            match c {
                b'\n' => {
                    if self.flow == 0 {
                        if let Some(name) = self.pending.take() {
                            // `key: &a` and the node on the lines below.
                            self.open.push(Open {
                                name,
                                nodes_before: self.nodes,
                                end: End::Block(self.node_col),
                            });
                        }
                    }
                    self.i += 1;
                    self.line_start = self.i;
                    at_line_start = true;
                }
                b' ' | b'\t' | b'\r' => self.i += 1,
                b'#' => self.i = self.eol(self.i),
                b'\'' | b'"' => self.quoted(c)?,
                b'[' | b'{' => {
                    if let Some(name) = self.pending.take() {
                        self.open.push(Open {
                            name,
                            nodes_before: self.nodes,
                            end: End::Flow(self.flow),
                        });
                    }
                    self.flow += 1;
                    self.nodes += 1;
                    self.deeper(self.i)?;
                    self.i += 1;
                }
                b']' | b'}' => {
                    self.flow = self.flow.saturating_sub(1);
                    while let Some(o) = self.open.last() {
                        match o.end {
                            End::Flow(d) if d >= self.flow => self.close(),
                            _ => break,
                        }
                    }
                    self.i += 1;
                }
                b',' if self.flow > 0 => self.i += 1,
                b'&' => self.anchor()?,
                b'*' => self.alias()?,
                // A tag: it says what the node is, not what it holds.
                b'!' => self.i = self.word_end(self.i),
                b'|' | b'>' if self.flow == 0 => self.block_scalar_header(),
                b'-' | b'?' | b':' if self.separated(self.i + 1) => self.indicator(c)?,
                _ => self.plain()?,
            }
        }
        Ok(())
    }

    /// Whether the byte at `j` ends a token: the end, white space, or a flow indicator in flow.
    fn separated(&self, j: usize) -> bool {
        match self.b.get(j) {
            None => true,
            Some(&c) => is_space(c) || (self.flow > 0 && is_flow_indicator(c)),
        }
    }

    /// The end of the line holding `j`: the offset of its line feed, or of the text's end.
    fn eol(&self, j: usize) -> usize {
        self.b[j.min(self.b.len())..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(self.b.len(), |k| j + k)
    }

    /// The end of an anchor's, alias's or tag's name starting at `j`.
    fn word_end(&self, j: usize) -> usize {
        let mut k = j + 1;
        while k < self.b.len() && !is_space(self.b[k]) && !is_flow_indicator(self.b[k]) {
            k += 1;
        }
        k
    }

    fn col(&self, j: usize) -> usize {
        j - self.line_start
    }

    fn deeper(&self, at: usize) -> Result<(), Refusal> {
        if self.block.len() + self.flow <= MAX_DEPTH {
            return Ok(());
        }
        Err(Refusal::at(
            self.b,
            at,
            format!(
                "collections nested more than {MAX_DEPTH} levels deep ({} by brackets, {} by indentation); specs are limited to {MAX_DEPTH}",
                self.flow,
                self.block.len()
            ),
        ))
    }

    /// A line's start: block scalar content, or indentation opening and closing block levels.
    fn line(&mut self) -> Result<(), Refusal> {
        let b = self.b;
        let start = self.i;
        let mut j = start;
        while j < b.len() && b[j] == b' ' {
            j += 1;
        }
        let ind = j - start;
        let mut k = j;
        while k < b.len() && matches!(b[k], b' ' | b'\t' | b'\r') {
            k += 1;
        }
        let blank = k >= b.len() || b[k] == b'\n';
        let end = self.eol(start);
        if let Some(bs) = &mut self.block_scalar {
            let content = blank
                || match bs.indent {
                    Some(n) => ind >= n,
                    None => ind > bs.above,
                };
            if content {
                if !blank && bs.indent.is_none() {
                    bs.indent = Some(ind);
                }
                bs.len += end - start + 1;
                if bs.len > MAX_SCALAR_BYTES {
                    let at = bs.start;
                    return Err(self.long_scalar(at));
                }
                self.i = end;
                return Ok(());
            }
            self.block_scalar = None;
        }
        self.i = j;
        if blank || b[k] == b'#' || self.flow > 0 {
            // Inside a flow collection indentation means nothing.
            return Ok(());
        }
        let marker = b[j..].starts_with(b"---") || b[j..].starts_with(b"...");
        if ind == 0 && marker && self.separated(j + 3) {
            // A document marker: every node is closed.
            self.block.clear();
            while !self.open.is_empty() {
                self.close();
            }
            self.i = j + 3;
            return Ok(());
        }
        if ind == 0 && b[j] == b'%' {
            // A directive.
            self.i = self.eol(j);
            return Ok(());
        }
        while let Some(o) = self.open.last() {
            match o.end {
                End::Block(above) if ind <= above => self.close(),
                _ => break,
            }
        }
        while self.block.last().is_some_and(|&top| top > ind) {
            self.block.pop();
        }
        if self.block.last().map_or(true, |&top| top < ind) {
            self.block.push(ind);
            self.deeper(j)?;
        }
        self.node_col = ind;
        self.key_col = ind;
        Ok(())
    }

    /// `-`, `?` or `:` followed by white space.
    fn indicator(&mut self, c: u8) -> Result<(), Refusal> {
        let col = self.col(self.i);
        match c {
            b'-' | b'?' if self.flow == 0 => {
                // A block sequence entry (or complex key): what follows nests inside it.
                self.node_col = col;
                self.key_col = col + 2;
                if self.block.last().map_or(true, |&top| top <= col) {
                    self.block.push(col + 1);
                    self.deeper(self.i)?;
                }
            }
            b':' => self.node_col = self.key_col,
            _ => {}
        }
        self.i += 1;
        Ok(())
    }

    /// A node of `size` nodes (1, or an alias's expansion) starts and ends here.
    fn node(&mut self, size: u64) {
        self.nodes = self.nodes.saturating_add(size);
        if let Some(name) = self.pending.take() {
            self.defined.insert(name, size);
        }
    }

    /// Closes the innermost open anchored collection, recording its size.
    fn close(&mut self) {
        if let Some(o) = self.open.pop() {
            self.defined
                .insert(o.name, self.nodes.saturating_sub(o.nodes_before).max(1));
        }
    }

    fn long_scalar(&self, start: usize) -> Refusal {
        Refusal::at(
            self.b,
            start,
            format!(
                "a scalar longer than {MAX_SCALAR_BYTES} bytes starts here; specs are limited to {MAX_SCALAR_BYTES} bytes a scalar"
            ),
        )
    }

    fn quoted(&mut self, q: u8) -> Result<(), Refusal> {
        let b = self.b;
        let start = self.i;
        let mut j = start + 1;
        while j < b.len() {
            let c = b[j];
            if q == b'\'' && c == b'\'' {
                if b.get(j + 1) == Some(&b'\'') {
                    j += 2;
                    continue;
                }
                j += 1;
                break;
            }
            if q == b'"' && c == b'\\' {
                j += 2;
                continue;
            }
            if q == b'"' && c == b'"' {
                j += 1;
                break;
            }
            j += 1;
        }
        let j = j.min(b.len());
        if j - start > MAX_SCALAR_BYTES + 2 {
            return Err(self.long_scalar(start));
        }
        self.key_col = self.col(start);
        if let Some(k) = b[start..j].iter().rposition(|&c| c == b'\n') {
            self.line_start = start + k + 1;
        }
        self.node(1);
        self.i = j;
        Ok(())
    }

    fn plain(&mut self) -> Result<(), Refusal> {
        let b = self.b;
        let start = self.i;
        let mut j = start;
        while j < b.len() {
            let c = b[j];
            let ends = c == b'\n'
                || (c == b':' && self.separated(j + 1))
                || (c == b'#' && j > start && matches!(b[j - 1], b' ' | b'\t'))
                || (self.flow > 0 && is_flow_indicator(c));
            if ends {
                break;
            }
            j += 1;
        }
        let j = j.max(start + 1);
        if j - start > MAX_SCALAR_BYTES {
            return Err(self.long_scalar(start));
        }
        self.key_col = self.col(start);
        self.node(1);
        self.i = j;
        Ok(())
    }

    fn anchor(&mut self) -> Result<(), Refusal> {
        self.anchors += 1;
        if self.anchors > MAX_ANCHORS {
            return Err(Refusal::at(
                self.b,
                self.i,
                format!(
                    "more than {MAX_ANCHORS} anchors (`&name`); specs are limited to {MAX_ANCHORS}"
                ),
            ));
        }
        let end = self.word_end(self.i);
        self.pending = Some(&self.b[self.i + 1..end]);
        self.i = end;
        Ok(())
    }

    fn alias(&mut self) -> Result<(), Refusal> {
        self.aliases += 1;
        if self.aliases > MAX_ALIASES {
            return Err(Refusal::at(
                self.b,
                self.i,
                format!(
                    "more than {MAX_ALIASES} aliases (`*name`); specs are limited to {MAX_ALIASES}"
                ),
            ));
        }
        let end = self.word_end(self.i);
        let size = self
            .defined
            .get(&self.b[self.i + 1..end])
            .copied()
            .unwrap_or(1);
        self.alias_nodes = self.alias_nodes.saturating_add(size);
        if self.alias_nodes > MAX_ALIAS_NODES {
            return Err(Refusal::at(
                self.b,
                self.i,
                format!(
                    "aliases expand to more than {MAX_ALIAS_NODES} nodes by here (a \"billion laughs\"?); specs are limited to {MAX_ALIAS_NODES}"
                ),
            ));
        }
        self.node(size);
        self.i = end;
        Ok(())
    }

    /// `|` or `>`: the header's line is skipped, then the content lines (see [`Self::line`]).
    fn block_scalar_header(&mut self) {
        let above =
            if self.col(self.i) == self.node_col && self.block.last() == Some(&self.node_col) {
                // The first thing on its line: its parent is less indented.
                self.node_col.saturating_sub(1)
            } else {
                self.node_col
            };
        self.node(1);
        self.block_scalar = Some(BlockScalar {
            above,
            indent: None,
            start: self.i,
            len: 0,
        });
        self.i = self.eol(self.i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `required` agrees with serde: dropping a key from a valid spec makes deserialization fail
    /// for that key exactly when `required` says so.
    #[test]
    fn required_keys_are_the_fields_without_a_default() {
        let text = include_str!("../tests/fixtures/valid/minimal.yaml");
        let root: Value = serde_yaml::from_str(text).expect("the fixture is YAML");
        for key in SPEC_KEYS {
            let mut map = root.as_mapping().expect("a mapping").clone();
            map.remove(*key);
            let serde_requires = match serde_yaml::from_value::<Spec>(Value::Mapping(map)) {
                Ok(_) => false,
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains("missing field"), "key `{key}`: {e}");
                    e.contains(&format!("missing field `{key}`"))
                }
            };
            assert_eq!(serde_requires, required(key), "key `{key}`");
        }
    }

    /// The model's open values read YAML the way the validator needs: file order, numbers as
    /// decimal text, tags kept as such, `~` as no entries, anything else not a mapping refused.
    #[test]
    fn open_maps_keep_what_was_written() {
        use model::{OpenMap, OpenValue as V};
        let read = |text: &str| {
            let v: Value = serde_yaml::from_str(text).expect("YAML");
            serde_yaml::from_value::<OpenMap>(v).map_err(|e| e.to_string())
        };
        let m = read("{b: 1, a: -2, c: 1.5, d: x, e: [x, 1], f: ~, g: true, h: !t x, 3: {j: k}}")
            .expect("a mapping");
        let s = |t: &str| V::String(t.to_owned());
        let n = |t: &str| V::Number(t.to_owned());
        assert_eq!(
            m.0,
            vec![
                (s("b"), n("1")),
                (s("a"), n("-2")),
                (s("c"), n("1.5")),
                (s("d"), s("x")),
                (s("e"), V::List(vec![s("x"), n("1")])),
                (s("f"), V::Null),
                (s("g"), V::Bool(true)),
                (s("h"), V::Tagged(Box::new(s("x")))),
                (n("3"), V::Map(OpenMap(vec![(s("j"), s("k"))]))),
            ]
        );
        assert_eq!(m.0[7].1.as_str(), Some("x"));
        assert_eq!(m.0[7].1.kind(), "a tagged value");
        assert!(read("~").expect("nothing").is_empty());
        assert_eq!(
            read("[a]").unwrap_err(),
            "invalid type: sequence, expected a YAML mapping"
        );
    }
}
