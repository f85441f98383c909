//! `include`: a spec takes its units, enums and flag sets from files of common types, read
//! relative to the spec's own file. Every way an include can go wrong is refused with the file
//! and the place named, and nothing an include does can loop or grow without bound.

use std::path::{Path, PathBuf};

use busspec_model::load::{MAX_INCLUDE_DEPTH, MAX_SPEC_BYTES};
use busspec_model::{load_file, load_file_with_includes, load_str, spec_sha256, Diagnostics};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn minimal() -> String {
    std::fs::read_to_string(root().join("model/tests/fixtures/valid/minimal.yaml"))
        .expect("fixture")
}

/// The minimal fixture's `units:` and `enums:` sections, and the spec without them.
fn split_minimal() -> (String, String) {
    let text = minimal();
    let (a, b) = (
        text.find("units:").expect("units"),
        text.find("flags:").expect("flags"),
    );
    (
        text[a..b].to_owned(),
        format!("{}{}", &text[..a], &text[b..]),
    )
}

/// A fresh directory of its own for each test.
fn dir(name: &str) -> PathBuf {
    let d = root().join("target/tmp/include").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create dir");
    d
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().expect("parent")).expect("create");
    std::fs::write(&path, text).expect("write");
    path
}

fn errors(d: &Diagnostics) -> Vec<String> {
    d.items.iter().map(|i| i.to_string()).collect()
}

#[test]
fn a_spec_takes_its_units_and_enums_from_an_included_file() {
    let d = dir("plain");
    let (common, rest) = split_minimal();
    write(&d, "types/common.yaml", &common);
    let spec = write(
        &d,
        "mini.yaml",
        &format!("include: types/common.yaml\n{rest}"),
    );
    let whole = load_str("minimal.yaml", &minimal()).expect("the fixture loads");
    let loaded = load_file_with_includes(&spec).unwrap_or_else(|d| panic!("{d}"));
    let p = &loaded.protocol;
    // The same units and enums, in the same order, as the spec that holds them itself.
    let names = |p: &busspec_model::Protocol| {
        let units: Vec<String> = p.units.iter().map(|u| u.name.clone()).collect();
        let enums: Vec<String> = p.enums.iter().map(|e| e.name.clone()).collect();
        (units, enums, p.commands.len(), p.responses.len())
    };
    assert_eq!(names(p), names(&whole));
    // Traced by the spec's text followed by the included file's.
    assert_eq!(
        p.spec_sha256,
        spec_sha256(&format!("include: types/common.yaml\n{rest}{common}"))
    );
    assert_eq!(loaded.included.files.len(), 1);
    assert_eq!(loaded.included.files[0].0, "types/common.yaml");
    // The flattened text loads without the file, to the same protocol.
    let flat = loaded.included.flattened.as_deref().expect("flattened");
    assert!(!flat.contains("include"), "{flat}");
    let again = load_str("flat.yaml", flat).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(names(&again), names(p));
    assert_eq!(format!("{:?}", again.units), format!("{:?}", p.units));
}

#[test]
fn nested_and_shared_includes_are_read_relative_to_their_file_and_once_each() {
    let d = dir("nested");
    let (common, rest) = split_minimal();
    let (units, enums) = common.split_at(common.find("enums:").expect("enums"));
    write(&d, "lib/units.yaml", units);
    // lib/enums.yaml includes units.yaml beside it; the spec includes both: units.yaml is read
    // once, and nothing is defined twice.
    write(
        &d,
        "lib/enums.yaml",
        &format!("include: [units.yaml]\n{enums}"),
    );
    let spec = write(
        &d,
        "mini.yaml",
        &format!("include: [lib/enums.yaml, lib/units.yaml]\n{rest}"),
    );
    let loaded = load_file_with_includes(&spec).unwrap_or_else(|d| panic!("{d}"));
    let files: Vec<&str> = loaded.included.files.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(files, ["lib/enums.yaml", "lib/units.yaml"]);
    assert_eq!(loaded.protocol.units.len(), 4);
    assert_eq!(loaded.protocol.enums.len(), 1);
}

#[test]
fn what_an_included_file_gets_wrong_is_located_in_that_file() {
    let d = dir("located");
    let (common, rest) = split_minimal();
    write(
        &d,
        "common.yaml",
        &common.replace("scale: \"0.01\"", "scale: \"0\""),
    );
    let spec = write(&d, "mini.yaml", &format!("include: common.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("scale 0");
    assert_eq!(
        errors(&e),
        ["include common.yaml: units.capacitance.scale: scale 0 must be greater than zero"]
    );
    // A shape error, and YAML that does not parse.
    write(
        &d,
        "common.yaml",
        &common.replace("symbol: pF", "symbol: pF\n    colour: red"),
    );
    let e = load_file(&spec).expect_err("unknown key");
    assert!(
        errors(&e)[0]
            .starts_with("include common.yaml: units.capacitance.colour: unknown field `colour`"),
        "{e}"
    );
    write(&d, "common.yaml", "units: [ {name: x\n");
    let e = load_file(&spec).expect_err("not YAML");
    assert!(
        errors(&e)[0].starts_with("include common.yaml: line "),
        "{e}"
    );
    assert!(errors(&e)[0].contains("not valid YAML"), "{e}");
}

#[test]
fn an_included_file_holds_common_types_only_and_defines_each_name_once() {
    let d = dir("only_types");
    let (common, rest) = split_minimal();
    let commands = &rest[rest.find("commands:").expect("commands")..];
    let spec = write(&d, "mini.yaml", &format!("include: common.yaml\n{rest}"));
    write(&d, "common.yaml", &format!("{common}{commands}"));
    let e = load_file(&spec).expect_err("commands");
    // Each key named where it is; nothing else is reported.
    assert_eq!(
        errors(&e),
        ["commands", "responses", "examples", "errata"].map(|k| format!(
            "include common.yaml: {k}: an included file holds common types only (units, enums, flags and include), not `{k}`"
        ))
    );
    // `count` in the file and again in the spec.
    write(&d, "common.yaml", &common);
    let twice = format!(
        "include: common.yaml\n{}",
        rest.replacen(
            "\nflags:",
            "\nunits:\n  - {name: count, symbol: \"\", scale: \"1\"}\nflags:",
            1
        )
    );
    let spec = write(&d, "mini.yaml", &twice);
    let e = load_file(&spec).expect_err("count twice");
    assert_eq!(
        errors(&e),
        ["include: `units` has `count` in common.yaml and again in this spec: a name is defined once"]
    );
}

#[test]
fn missing_files_cycles_depth_and_size_are_refused() {
    let d = dir("refused");
    let (_, rest) = split_minimal();
    let spec = write(&d, "mini.yaml", &format!("include: nowhere.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("missing");
    assert!(
        errors(&e)[0].starts_with("include nowhere.yaml: cannot read: "),
        "{e}"
    );
    // A device (its reading would not end) and a directory.
    for (name, what) in [("/dev/zero", "/dev/zero"), ("..", "..")] {
        let spec = write(&d, "mini.yaml", &format!("include: {name}\n{rest}"));
        let e = load_file(&spec).expect_err(what);
        assert_eq!(
            errors(&e),
            [format!("include {name}: not a regular file: an included file holds common types (units, enums, flags)")]
        );
    }
    // A FIFO, whose opening would wait for a writer: refused without being opened.
    let fifo = d.join("fifo.yaml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", fifo.display());
    let spec = write(&d, "mini.yaml", &format!("include: fifo.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("a FIFO");
    assert!(errors(&e)[0].contains("not a regular file"), "{e}");
    // a.yaml includes b.yaml includes a.yaml.
    write(&d, "a.yaml", "include: b.yaml\n");
    write(&d, "b.yaml", "include: a.yaml\n");
    let spec = write(&d, "mini.yaml", &format!("include: a.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("cycle");
    assert_eq!(
        errors(&e),
        ["include a.yaml: include b.yaml: include a.yaml: includes itself: a.yaml -> b.yaml -> a.yaml"]
    );
    // A chain deeper than the limit: f0 includes f1 includes ... includes f{depth}.
    for i in 0..=MAX_INCLUDE_DEPTH {
        write(
            &d,
            &format!("f{i}.yaml"),
            &format!("include: f{}.yaml\n", i + 1),
        );
    }
    write(
        &d,
        &format!("f{}.yaml", MAX_INCLUDE_DEPTH + 1),
        "units: []\n",
    );
    let spec = write(&d, "mini.yaml", &format!("include: f0.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("too deep");
    assert!(
        errors(&e)[0].ends_with(&format!(
            "includes nest deeper than {MAX_INCLUDE_DEPTH} files"
        )),
        "{e}"
    );
    // The spec and its includes share one size limit.
    let big = format!("units: []\n#{}\n", "x".repeat(MAX_SPEC_BYTES - rest.len()));
    write(&d, "big.yaml", &big);
    let spec = write(&d, "mini.yaml", &format!("include: big.yaml\n{rest}"));
    let e = load_file(&spec).expect_err("too large together");
    assert!(
        errors(&e)[0].contains(&format!("limited to {MAX_SPEC_BYTES} bytes together")),
        "{e}"
    );
    // Not file names.
    let last = MAX_INCLUDE_DEPTH + 1;
    let spec = write(
        &d,
        "mini.yaml",
        &format!("include: [f{last}.yaml, 7]\n{rest}"),
    );
    let e = load_file(&spec).expect_err("a number");
    assert_eq!(
        errors(&e),
        ["include[1]: expected a file name, found a number"]
    );
    let spec = write(
        &d,
        "mini.yaml",
        &format!("include: {{file: x.yaml}}\n{rest}"),
    );
    let e = load_file(&spec).expect_err("a mapping");
    assert_eq!(
        errors(&e),
        ["include: expected a file name or a list of file names, found a mapping"]
    );
}

#[test]
fn spec_text_without_a_file_cannot_include() {
    let (_, rest) = split_minimal();
    let e = load_str("mini.yaml", &format!("include: common.yaml\n{rest}")).expect_err("text");
    assert!(
        errors(&e)[0].starts_with("include: a spec given as text cannot include files"),
        "{e}"
    );
}
