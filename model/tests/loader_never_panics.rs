//! The loader and validator return `Ok` or `Err` for any text; they never panic and never hang.
//!
//! Two halves:
//! * seeded, deterministic mutation of the real specs and of every fixture (truncation, byte
//!   flips, inserts and deletes, line deletes, duplicates and swaps, numbers replaced with huge
//!   or negative ones, scalars replaced with lists and mappings, and combinations), a few
//!   thousand cases in all; an input that panics is written to `target/tmp/loader_never_panics/`;
//! * hand-written nasties (deep nesting, an alias bomb, empty and NUL-filled files, a huge
//!   integer, non-UTF-8 bytes, ...) that must each give a clear error, within a time limit.
//!
//! The random numbers come from a hand-written xorshift64*, so every run tries the same cases.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use busspec_model::{load_file, load_str, Diagnostics, Protocol, MAX_SPEC_BYTES};

/// xorshift64* (Vigna): small, fast, and good enough to pick mutation sites.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        // The state must never be zero; mix the seed so nearby seeds diverge at once.
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (0 when `n` is 0).
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Bytes that mean something to YAML, and some that mean something to us.
const INSERTS: &[&[u8]] = &[
    b"[",
    b"]",
    b"{",
    b"}",
    b":",
    b": ",
    b",",
    b"- ",
    b"&a ",
    b"*a",
    b"!",
    b"!!str ",
    b"|",
    b">",
    b"'",
    b"\"",
    b"#",
    b"%",
    b"@",
    b"`",
    b"?",
    b"\n",
    b"\t",
    b"  ",
    b"~",
    b"0x",
    b"-",
    b"9",
    b"\0",
    b"\r",
    b"\xEF\xBB\xBF",
    b"<<: ",
    b"---\n",
    b"...\n",
    b"\\",
];

/// Replacements for numbers.
const NUMBERS: &[&str] = &[
    "99999999999999999999999",
    "-99999999999999999999999",
    "18446744073709551616",
    "18446744073709551615",
    "9223372036854775808",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967296",
    "-1",
    "0",
    "-0",
    "0x",
    "0xFFFFFFFFFFFFFFFF",
    "0x10000000000000000",
    "1e308",
    "1e999",
    "-1e999",
    ".nan",
    ".inf",
    "0.0000000000000000001",
    "255",
    "256",
    "65536",
];

/// Replacements for a scalar value `v` (the placeholder `V`).
const SHAPES: &[&str] = &[
    "[V]",
    "[V, V]",
    "[]",
    "{}",
    "~",
    "[[V]]",
    "{a: V}",
    "{name: V}",
    "[{}]",
    "!!binary aGVsbG8=",
    "\"\"",
    "V V",
    "&x V",
    "*nowhere",
];

fn lines(text: &[u8]) -> Vec<&[u8]> {
    text.split_inclusive(|&b| b == b'\n').collect()
}

/// Where numbers are: runs of hex-ish digits starting with a decimal digit.
fn number_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if text[i].is_ascii_digit() && (i == 0 || !text[i - 1].is_ascii_alphanumeric()) {
            let start = if i > 0 && text[i - 1] == b'-' {
                i - 1
            } else {
                i
            };
            let mut end = i;
            while end < text.len() && (text[end].is_ascii_hexdigit() || text[end] == b'x') {
                end += 1;
            }
            spans.push((start, end));
            i = end;
        } else {
            i += 1;
        }
    }
    spans
}

/// Where plain scalar values are: after `key: ` up to the end of the line or an inline `,`/`}`.
fn value_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    for i in 0..text.len().saturating_sub(2) {
        if text[i] == b':'
            && text[i + 1] == b' '
            && !matches!(text[i + 2], b'[' | b'{' | b'|' | b'>' | b'\n')
        {
            let start = i + 2;
            let mut end = start;
            while end < text.len() && !matches!(text[end], b'\n' | b',' | b'}' | b'#') {
                end += 1;
            }
            if end > start {
                spans.push((start, end));
            }
        }
    }
    spans
}

fn splice(text: &[u8], (start, end): (usize, usize), with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len() + with.len());
    out.extend_from_slice(&text[..start]);
    out.extend_from_slice(with);
    out.extend_from_slice(&text[end..]);
    out
}

/// One random mutation of `text`; `kind` chooses which.
fn mutate(text: &[u8], kind: usize, rng: &mut Rng) -> Vec<u8> {
    let n = text.len();
    match kind {
        // truncate
        0 => text[..rng.below(n + 1)].to_vec(),
        // flip bits in a few bytes
        1 => {
            let mut out = text.to_vec();
            for _ in 0..=rng.below(4) {
                if n > 0 {
                    let at = rng.below(n);
                    out[at] ^= 1 << rng.below(8);
                }
            }
            out
        }
        // insert syntax, or a random byte
        2 => {
            let mut out = text.to_vec();
            for _ in 0..=rng.below(3) {
                let at = rng.below(out.len() + 1);
                let ins: Vec<u8> = if rng.below(4) == 0 {
                    vec![rng.next() as u8]
                } else {
                    rng.pick(INSERTS).to_vec()
                };
                out.splice(at..at, ins);
            }
            out
        }
        // delete a run of bytes
        3 => {
            let start = rng.below(n + 1);
            let end = (start + 1 + rng.below(16)).min(n);
            splice(text, (start, end), b"")
        }
        // delete, duplicate or swap lines; indent or dedent one
        4..=7 => {
            let mut ls = lines(text);
            if ls.is_empty() {
                return text.to_vec();
            }
            let a = rng.below(ls.len());
            let b = rng.below(ls.len());
            let mut reindented = Vec::new();
            match kind {
                4 => {
                    ls.remove(a);
                }
                5 => ls.insert(b, ls[a]),
                6 => ls.swap(a, b),
                _ => {
                    reindented = if rng.below(2) == 0 {
                        [b"  ".as_slice(), ls[a]].concat()
                    } else {
                        ls[a].strip_prefix(b"  ").unwrap_or(ls[a]).to_vec()
                    };
                }
            }
            if kind == 7 {
                ls[a] = &reindented;
            }
            ls.concat()
        }
        // a number becomes huge, negative, or not a number
        8 => {
            let spans = number_spans(text);
            if spans.is_empty() {
                return text.to_vec();
            }
            let span = *rng.pick(&spans);
            splice(text, span, rng.pick(NUMBERS).as_bytes())
        }
        // a scalar becomes a list, a mapping, nothing, an alias, ...
        9 => {
            let spans = value_spans(text);
            if spans.is_empty() {
                return text.to_vec();
            }
            let span = *rng.pick(&spans);
            let value = String::from_utf8_lossy(&text[span.0..span.1]).into_owned();
            let with = rng.pick(SHAPES).replace('V', &value);
            splice(text, span, with.as_bytes())
        }
        // several at once
        _ => {
            let mut out = text.to_vec();
            for _ in 0..2 + rng.below(3) {
                let k = 1 + rng.below(9);
                out = mutate(&out, k, rng);
            }
            out
        }
    }
}

const KINDS: usize = 11;

/// The outcome of one load: `Err(why)` if it panicked or gave an error without a message.
fn check_one(label: &str, text: &str) -> Result<Result<Protocol, Diagnostics>, String> {
    let result = catch_unwind(AssertUnwindSafe(|| load_str(label, text))).map_err(|payload| {
        let msg = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "(non-text panic payload)".to_owned());
        format!("panicked: {msg}")
    })?;
    if let Err(d) = &result {
        if d.items.is_empty() {
            return Err("returned Err without a single diagnostic".to_owned());
        }
        if let Some(blank) = d.items.iter().find(|i| i.message.trim().is_empty()) {
            return Err(format!("diagnostic at `{}` has no message", blank.path));
        }
        if d.file != label {
            return Err(format!("diagnostics name file `{}`, not `{label}`", d.file));
        }
    }
    Ok(result)
}

fn failure_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("loader_never_panics")
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn fixture_paths() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut out = Vec::new();
    for sub in ["valid", "broken"] {
        let dir = root.join(sub);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("directory entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
            .collect();
        files.sort();
        out.extend(files);
    }
    out
}

/// `LOADER_FUZZ_SCALE=N` runs N times as many cases (with other seeds past the first round);
/// the default run is always the same.
fn scale() -> usize {
    std::env::var("LOADER_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// Runs `cases` mutations of each source; returns how many loads ended Ok and Err. Panics at
/// the end, listing every input that panicked (each saved under `target/tmp/`).
fn fuzz(sources: &[PathBuf], cases: usize, seed: u64) -> (usize, usize) {
    let (mut ok, mut err) = (0, 0);
    let mut slowest = (Duration::ZERO, String::new());
    for round in 0..scale() as u64 {
        let (o, e, slow) = fuzz_round(sources, cases, seed.wrapping_add(round << 40));
        ok += o;
        err += e;
        slowest = slowest.max(slow);
    }
    eprintln!(
        "{} cases: {ok} loaded, {err} rejected; slowest {:?} ({})",
        ok + err,
        slowest.0,
        slowest.1
    );
    (ok, err)
}

fn fuzz_round(sources: &[PathBuf], cases: usize, seed: u64) -> (usize, usize, (Duration, String)) {
    let mut failures = Vec::new();
    let (mut ok, mut err) = (0, 0);
    let mut slowest = (Duration::ZERO, String::new());
    for (s, path) in sources.iter().enumerate() {
        let original = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let stem = path.file_stem().and_then(|x| x.to_str()).unwrap_or("spec");
        let mut rng = Rng::new(seed ^ ((s as u64) << 32));
        for case in 0..cases {
            // Truncation is swept evenly over the file on top of the random cuts.
            let mutated = if case < cases / 8 {
                original[..original.len() * case / (cases / 8)].to_vec()
            } else {
                let kind = rng.below(KINDS);
                mutate(&original, kind, &mut rng)
            };
            let text = String::from_utf8_lossy(&mutated);
            let label = format!("{stem}#{case}");
            let started = Instant::now();
            let outcome = check_one(&label, &text);
            let took = started.elapsed();
            if took > slowest.0 {
                slowest = (took, label.clone());
            }
            match outcome {
                Ok(Ok(_)) => ok += 1,
                Ok(Err(_)) => err += 1,
                Err(why) => {
                    let dir = failure_dir();
                    let _ = std::fs::create_dir_all(&dir);
                    let file = dir.join(format!("{stem}-{seed}-{case}.yaml"));
                    let _ = std::fs::write(&file, text.as_bytes());
                    failures.push(format!(
                        "{label}: {why} (input saved to {})",
                        file.display()
                    ));
                }
            }
            if took > Duration::from_secs(5) {
                failures.push(format!("{label}: took {took:?}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} mutated inputs failed:\n{}",
        failures.len(),
        ok + err + failures.len(),
        failures.join("\n")
    );
    (ok, err, slowest)
}

#[test]
fn mutated_ub2_spec_never_panics() {
    let (ok, err) = fuzz(&[repo().join("spec/ub2.yaml")], 280, 0xB2);
    // Most mutations break the spec; some (inside doc strings, say) leave it valid.
    assert!(ok > 0 && err > ok, "ok {ok}, err {err}");
}

#[test]
fn mutated_sd_spec_never_panics() {
    let (ok, err) = fuzz(&[repo().join("spec/sd.yaml")], 280, 0x5D);
    assert!(ok > 0 && err > ok, "ok {ok}, err {err}");
}

#[test]
fn mutated_fixtures_never_panic() {
    let sources = fixture_paths();
    assert!(sources.len() > 30);
    let (ok, err) = fuzz(&sources, 36, 0xF1);
    assert!(ok > 0 && err > ok, "ok {ok}, err {err}");
}

/// Loads `text` on another thread and waits at most `limit`: a hang fails the test instead of
/// stalling it. Returns the diagnostics, which must exist and say something.
fn must_fail_quickly(name: &str, text: String, limit: Duration) -> Diagnostics {
    let (tx, rx) = mpsc::channel();
    let label = format!("nasty/{name}");
    let thread_label = label.clone();
    std::thread::spawn(move || {
        let _ = tx.send(check_one(&thread_label, &text));
    });
    let outcome = match rx.recv_timeout(limit) {
        Ok(outcome) => outcome,
        Err(_) => panic!("{name}: no answer within {limit:?}"),
    };
    match outcome {
        Err(why) => panic!("{name}: {why}"),
        Ok(Ok(_)) => panic!("{name}: loaded as a valid spec"),
        Ok(Err(d)) => {
            assert!(!d.to_string().trim().is_empty(), "{name}: empty display");
            d
        }
    }
}

fn minimal() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/minimal.yaml");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The first diagnostic's message, for asserting on.
fn first(d: &Diagnostics) -> &str {
    &d.items[0].message
}

const LIMIT: Duration = Duration::from_secs(20);

#[test]
fn deep_nesting_is_refused() {
    for (name, text) in [
        ("open_lists", "[".repeat(10_000)),
        (
            "closed_lists",
            format!("{}{}", "[".repeat(10_000), "]".repeat(10_000)),
        ),
        ("open_maps", "{a: ".repeat(2_000)),
        (
            "block_lists",
            (0..2_000)
                .map(|i| format!("{}-\n", " ".repeat(i)))
                .collect(),
        ),
        (
            "nested_commands",
            minimal().replace(
                "\ncommands:\n",
                &format!(
                    "\ncommands: {}{}\nunused:\n",
                    "[".repeat(10_000),
                    "]".repeat(10_000)
                ),
            ),
        ),
    ] {
        let d = must_fail_quickly(name, text, LIMIT);
        assert_eq!(d.items.len(), 1, "{name}: {d}");
        assert!(d.items[0].path.starts_with("line "), "{name}: {d}");
        assert!(
            first(&d).contains("nested more than 64 levels deep"),
            "{name}: {d}"
        );
    }
}

/// "Billion laughs": nine levels of nine aliases each would expand to 9^9 strings.
fn alias_bomb(levels: usize) -> String {
    let mut text = String::from(
        "a: &a [\"lol\",\"lol\",\"lol\",\"lol\",\"lol\",\"lol\",\"lol\",\"lol\",\"lol\"]\n",
    );
    let names: Vec<char> = ('a'..='z').collect();
    for i in 1..levels {
        let refs = vec![format!("*{}", names[i - 1]); 9].join(",");
        text.push_str(&format!("{0}: &{0} [{refs}]\n", names[i]));
    }
    text
}

#[test]
fn alias_bomb_is_refused() {
    let d = must_fail_quickly("billion_laughs", alias_bomb(9), LIMIT);
    assert!(
        first(&d).contains("aliases expand to more than 100000 nodes"),
        "{d}"
    );
    // The same bomb where the spec would read it: as the list of units.
    let spec = minimal().replace(
        "\nunits:\n",
        &format!(
            "\nbomb_{}units: *i\nunused:\n",
            alias_bomb(9).replace("\na", "\nbomb_a")
        ),
    );
    must_fail_quickly("billion_laughs_in_spec", spec, LIMIT);
}

#[test]
fn empty_and_blank_files_are_refused() {
    for (name, text) in [
        ("empty", ""),
        ("spaces", "   \n\n  \n"),
        ("comment_only", "# nothing here\n"),
        ("null", "~\n"),
        ("document_marker", "---\n"),
    ] {
        let d = must_fail_quickly(name, text.to_owned(), LIMIT);
        assert_eq!(
            first(&d),
            "expected a mapping of spec keys at the top, found nothing",
            "{name}"
        );
    }
    let d = must_fail_quickly("two_documents", "---\na: 1\n---\nb: 2\n".to_owned(), LIMIT);
    assert!(first(&d).contains("more than one document"), "{d}");
}

#[test]
fn nul_bytes_are_refused() {
    let d = must_fail_quickly("nul_bytes", "\0".repeat(4096), LIMIT);
    assert_eq!(d.items[0].path, "line 1 column 1", "{d}");
    assert!(
        first(&d).starts_with("control character U+0000 (NUL) is not allowed"),
        "{d}"
    );
    let d = must_fail_quickly(
        "nul_in_spec",
        minimal().replace("mini\n", "mini\0\n"),
        LIMIT,
    );
    assert_eq!(d.items[0].path, "line 3 column 15", "{d}");
    assert!(first(&d).starts_with("control character U+0000"), "{d}");
}

#[test]
fn huge_integers_are_refused() {
    let d = must_fail_quickly(
        "huge_integer",
        minimal().replace("baud: 9600", "baud: 123456789012345678901234567890"),
        LIMIT,
    );
    assert!(
        first(&d).contains("integer `123456789012345678901234567890` is too large"),
        "{d}"
    );
    // Beyond 128 bits YAML reads it as text.
    let d = must_fail_quickly(
        "enormous_integer",
        minimal().replace("baud: 9600", &format!("baud: {}", "9".repeat(5_000))),
        LIMIT,
    );
    assert_eq!(d.items[0].path, "serial.baud", "{d}");
    let d = must_fail_quickly(
        "u64_max_in_i64",
        minimal().replace("max: 100000}", "max: 18446744073709551615}"),
        LIMIT,
    );
    assert_eq!(
        d.items[0].path, "commands.go_to.fields.target.range.max",
        "{d}"
    );
}

#[test]
fn oversized_file_is_refused_before_parsing() {
    let d = must_fail_quickly("oversized", "#".repeat(MAX_SPEC_BYTES + 1), LIMIT);
    assert!(first(&d).contains("specs are limited to"), "{d}");
}

#[test]
fn non_utf8_file_is_refused_by_load_file() {
    let dir = failure_dir();
    std::fs::create_dir_all(&dir).expect("create target/tmp dir");
    let path = dir.join("non_utf8.yaml");
    let mut bytes = minimal().into_bytes();
    bytes.insert(100, 0xFF);
    std::fs::write(&path, &bytes).expect("write non-UTF-8 file");
    let d = load_file(&path).expect_err("non-UTF-8 file loaded");
    assert_eq!(d.file, path.display().to_string());
    assert_eq!(d.items.len(), 1);
    // Where byte 100 of the (ASCII) fixture is.
    let text = minimal();
    let before = &text.as_bytes()[..100];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    assert_eq!(
        d.items[0].path,
        format!("line {line} column {}", 100 - line_start + 1)
    );
    assert_eq!(
        d.items[0].message,
        "not UTF-8 text: invalid byte 0xFF at offset 100"
    );

    let missing = dir.join("does_not_exist.yaml");
    let d = load_file(&missing).expect_err("missing file loaded");
    assert!(first(&d).starts_with("cannot read: "), "{d}");
}

#[test]
fn odd_but_harmless_inputs_do_not_panic() {
    // These may or may not be valid; they must only not panic.
    let long_doc = minimal().replace(
        "title: \"Minimal sum8 test protocol\"",
        &format!("title: \"{}\"", "x".repeat(1 << 20)),
    );
    for (name, text) in [
        ("byte_order_mark", format!("\u{FEFF}{}", minimal())),
        ("crlf", minimal().replace('\n', "\r\n")),
        ("tabs_after_colons", minimal().replace(": ", ":\t")),
        ("long_title", long_doc),
        (
            "merge_key",
            format!("{}\nx: &x {{a: 1}}\ny: {{<<: *x}}\n", minimal()),
        ),
        (
            "tagged",
            minimal().replace("protocol: mini", "protocol: !custom mini"),
        ),
        (
            "binary",
            minimal().replace("protocol: mini", "protocol: !!binary bWluaQ=="),
        ),
    ] {
        if let Err(why) = check_one(name, &text) {
            panic!("{name}: {why}");
        }
    }
}
