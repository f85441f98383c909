//! Hostile spec text is refused by the loader's pre-scan (`load::prescan`) with one located
//! error naming the limit, before serde_yaml reads it; what only looks like structure (brackets,
//! `&`, `*` and `#` in quotes, comments and block scalars) is not counted, and real specs load.

use std::path::{Path, PathBuf};

use busspec_model::load::{
    MAX_ALIASES, MAX_ALIAS_NODES, MAX_ANCHORS, MAX_DEPTH, MAX_SCALAR_BYTES, MAX_SPEC_BYTES,
};
use busspec_model::{load_file, load_str, Diagnostics};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn minimal() -> String {
    let path = root().join("model/tests/fixtures/valid/minimal.yaml");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The one diagnostic `text` must give: its path and message.
fn refused(text: &str) -> (String, String) {
    let d: Diagnostics = match load_str("hostile.yaml", text) {
        Ok(_) => panic!("hostile text loaded"),
        Err(d) => d,
    };
    assert_eq!(d.items.len(), 1, "{d}");
    (d.items[0].path.clone(), d.items[0].message.clone())
}

const DEPTH: &str = "collections nested more than 64 levels deep";

#[test]
fn deep_flow_nesting_is_refused_at_the_first_bracket_too_deep() {
    // The user's file: 200,000 levels.
    let text = format!("a: {}{}\n", "[".repeat(200_000), "]".repeat(200_000));
    let (path, message) = refused(&text);
    // `a:` opens one level by indentation; the 64th bracket is the 65th level.
    assert_eq!(path, format!("line 1 column {}", 3 + MAX_DEPTH));
    assert_eq!(
        message,
        format!("{DEPTH} (64 by brackets, 1 by indentation); specs are limited to {MAX_DEPTH}")
    );
    let (path, message) = refused(&"{a: ".repeat(100));
    assert_eq!(path, format!("line 1 column {}", 4 * (MAX_DEPTH - 1) + 1));
    assert!(message.starts_with(DEPTH), "{message}");
}

#[test]
fn deep_block_nesting_is_refused() {
    let text: String = (0..1_000)
        .map(|i| format!("{}k{i}:\n", " ".repeat(i)))
        .collect();
    let (path, message) = refused(&text);
    assert_eq!(
        path,
        format!("line {0} column {0}", MAX_DEPTH + 1),
        "{message}"
    );
    assert_eq!(
        message,
        format!("{DEPTH} (0 by brackets, 65 by indentation); specs are limited to {MAX_DEPTH}")
    );
    // Sequences in sequences on one line.
    let (path, message) = refused(&format!("{}x\n", "- ".repeat(100)));
    assert!(path.starts_with("line 1 column "), "{path}");
    assert!(message.starts_with(DEPTH), "{message}");
}

#[test]
fn nesting_within_the_limit_is_left_to_the_parser() {
    // 60 levels pass the pre-scan; the spec is then wrong, not refused for depth.
    let text = format!("a: {}{}\n", "[".repeat(60), "]".repeat(60));
    let d = load_str("shallow.yaml", &text).expect_err("not a spec");
    assert!(d.items.iter().all(|i| !i.message.contains("nested")), "{d}");
    assert!(d.items[0].message.starts_with("unknown key `a`"), "{d}");
}

/// "Billion laughs": nine levels of nine aliases each would expand to 9^9 strings.
fn alias_bomb(levels: usize) -> String {
    let mut text = String::from("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n");
    let names: Vec<char> = ('a'..='z').collect();
    for i in 1..levels {
        let refs = vec![format!("*{}", names[i - 1]); 9].join(", ");
        text.push_str(&format!("{0}: &{0} [{refs}]\n", names[i]));
    }
    text
}

#[test]
fn alias_bomb_is_refused_where_its_expansion_passes_the_limit() {
    let (path, message) = refused(&alias_bomb(9));
    // Levels a..e expand to 10, 91, 820, 7381 and 66430 nodes; the second alias of `e` on
    // line 6 brings the aliases' total past 100,000.
    assert!(path.starts_with("line 6 column "), "{path}: {message}");
    assert_eq!(
        message,
        format!("aliases expand to more than {MAX_ALIAS_NODES} nodes by here (a \"billion laughs\"?); specs are limited to {MAX_ALIAS_NODES}")
    );
    // Block lists are sized as well as flow ones.
    let block = "a: &a\n  - x\n  - y\nb: &b\n  - *a\n  - *a\n";
    let mut text = block.to_owned();
    for i in 0..200 {
        text.push_str(&format!("c{i}: [*b, *b]\n"));
    }
    let (_, message) = refused(&text);
    assert!(message.starts_with("more than 256 aliases"), "{message}");
}

#[test]
fn anchors_and_aliases_are_counted() {
    let anchors: String = (0..=MAX_ANCHORS)
        .map(|i| format!("a{i}: &x{i} 1\n"))
        .collect();
    let (path, message) = refused(&anchors);
    let column = format!("a{MAX_ANCHORS}: ").len() + 1;
    assert_eq!(path, format!("line {} column {column}", MAX_ANCHORS + 1));
    assert_eq!(
        message,
        format!("more than {MAX_ANCHORS} anchors (`&name`); specs are limited to {MAX_ANCHORS}")
    );
    let aliases = format!("a: &a 1\nb: [{}]\n", vec!["*a"; MAX_ALIASES + 1].join(", "));
    let (path, message) = refused(&aliases);
    assert_eq!(path, format!("line 2 column {}", 5 + 4 * MAX_ALIASES));
    assert_eq!(
        message,
        format!("more than {MAX_ALIASES} aliases (`*name`); specs are limited to {MAX_ALIASES}")
    );
}

#[test]
fn huge_scalars_are_refused_where_they_start() {
    let long = "x".repeat(MAX_SCALAR_BYTES + 1);
    let limit = format!(
        "a scalar longer than {MAX_SCALAR_BYTES} bytes starts here; specs are limited to {MAX_SCALAR_BYTES} bytes a scalar"
    );
    for (text, at) in [
        (format!("protocol: {long}\n"), "line 1 column 11"),
        (format!("a: 1\ntitle: \"{long}\"\n"), "line 2 column 8"),
        (format!("a: 1\ntitle: '{long}'\n"), "line 2 column 8"),
        (format!("doc: |\n  {long}\n"), "line 1 column 6"),
    ] {
        assert_eq!(refused(&text), (at.to_owned(), limit.clone()));
    }
}

#[test]
fn oversize_text_is_refused_where_it_passes_the_limit() {
    let line = format!("# {}\n", "x".repeat(1021));
    assert_eq!(line.len(), 1024);
    let text = line.repeat(MAX_SPEC_BYTES / 1024 + 1);
    let (path, message) = refused(&text);
    assert_eq!(path, format!("line {} column 1", MAX_SPEC_BYTES / 1024 + 1));
    assert_eq!(
        message,
        format!(
            "the file is {} bytes; specs are limited to {MAX_SPEC_BYTES} bytes (4 MiB)",
            text.len()
        )
    );
}

fn temp_dir() -> PathBuf {
    let dir = root().join("target/tmp/hostile_input");
    std::fs::create_dir_all(&dir).expect("create target/tmp dir");
    dir
}

#[test]
fn load_file_says_where_a_byte_is_not_utf8_and_reads_no_more_than_the_limit() {
    let dir = temp_dir();
    let path = dir.join("latin1.yaml");
    let text = minimal().replace("title: \"Minimal sum8", "title: \"Minimal\u{FF} sum8");
    let mut bytes = text.into_bytes();
    let at = bytes
        .windows(2)
        .position(|w| w == "\u{FF}".as_bytes())
        .expect("the marker");
    // ÿ in Latin-1: one byte, not UTF-8.
    bytes.splice(at..at + 2, [0xFF]);
    std::fs::write(&path, &bytes).expect("write");
    let d = load_file(&path).expect_err("not UTF-8");
    assert_eq!(d.items.len(), 1, "{d}");
    // `title: "Minimal` is 15 characters.
    assert_eq!(d.items[0].path, "line 4 column 16");
    assert_eq!(
        d.items[0].message,
        format!("not UTF-8 text: invalid byte 0xFF at offset {at}")
    );

    let big = dir.join("big.yaml");
    let size = MAX_SPEC_BYTES + 5000;
    std::fs::write(&big, "#".repeat(size)).expect("write");
    let d = load_file(&big).expect_err("too big");
    assert_eq!(
        d.items[0].path,
        format!("line 1 column {}", MAX_SPEC_BYTES + 1)
    );
    assert_eq!(
        d.items[0].message,
        format!("the file is {size} bytes; specs are limited to {MAX_SPEC_BYTES} bytes (4 MiB)")
    );
}

#[test]
fn nul_and_control_characters_are_refused() {
    let text = minimal().replace("protocol: mini", "protocol: mi\0ni");
    assert_eq!(
        refused(&text),
        (
            "line 3 column 13".to_owned(),
            "control character U+0000 (NUL) is not allowed: a spec holds printable text, tabs and line breaks only".to_owned()
        )
    );
    let text = minimal().replace("protocol: mini", "protocol: mi\u{1B}ni");
    let (path, message) = refused(&text);
    assert_eq!(path, "line 3 column 13");
    assert!(
        message.starts_with("control character U+001B is not allowed"),
        "{message}"
    );
}

/// Brackets, anchors, aliases and `#` that are text do not count, however many.
#[test]
fn structure_inside_text_is_not_counted() {
    let brackets = "[{".repeat(200);
    let stars = "*a &b ".repeat(300);
    let spec = minimal()
        .replace(
            "title: \"Minimal sum8 test protocol\"",
            &format!("title: \"{brackets} {stars} \\\" {brackets}\"\n# {brackets} {stars}"),
        )
        .replace(
            "    title: \"Go to capacitance\"",
            &format!(
                "    title: '{brackets} it''s {stars}'\n    doc: |\n      {brackets}\n        {stars}\n\n      # {brackets}"
            ),
        )
        .replace(
            "    title: \"Set mode\"",
            &format!("    title: Set {brackets} mode {stars} x#y"),
        );
    if let Err(d) = load_str("texty.yaml", &spec) {
        panic!("{d}");
    }
}

/// Every spec and valid fixture of the repository loads as before.
#[test]
fn real_specs_pass_the_prescan() {
    let mut files = Vec::new();
    for dir in [
        "spec",
        "model/tests/fixtures/valid",
        "codegen/tests/fixtures",
        "examples/own-protocol/spec",
    ] {
        for entry in std::fs::read_dir(root().join(dir)).expect("read dir") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "yaml") {
                files.push(path);
            }
        }
    }
    assert!(files.len() >= 10, "{files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read");
        if let Err(r) = busspec_model::load::prescan(&text) {
            panic!("{}: {} {}", path.display(), r.path(), r.message);
        }
        // A file of common types (`include`d by a spec) is no spec of its own.
        if !text.lines().any(|l| l.starts_with("protocol:")) {
            continue;
        }
        if let Err(d) = load_file(&path) {
            panic!("{d}");
        }
    }
}
