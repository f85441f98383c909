//! YAML text to [`Spec`]: shape errors only, every one of them, each with its path.
//!
//! The file is parsed to a YAML tree first, then each top-level key and each element of each
//! list is deserialized on its own, so one misspelt key in one command does not hide the errors
//! in the next. Nothing here panics on any input: serde_yaml bounds recursion and alias expansion.

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

/// Parses spec text. On failure returns every shape error found.
pub fn parse(text: &str, sink: &mut Sink) -> Option<Spec> {
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
    let Value::Mapping(mut map) = root else {
        sink.error(
            "",
            format!(
                "expected a mapping of spec keys at the top, found {}",
                kind(&root)
            ),
        );
        return None;
    };
    for key in map.keys() {
        match key.as_str() {
            Some(k) if SPEC_KEYS.contains(&k) => {}
            Some(k) => sink.error(
                k,
                format!(
                    "unknown key `{k}`, expected one of {}",
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

/// Top-level keys with a default when absent: the lists, and `common_responses`.
const DEFAULTED_KEYS: &[&str] = &["common_responses"];

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
