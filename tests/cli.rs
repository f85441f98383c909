//! The `busspec` command line: exit codes, summaries, errors that say what and where, and `diff`.

use std::path::Path;
use std::process::{Command, Output};

fn busspec(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_busspec"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run busspec")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn check_passes_on_every_spec_and_summarises_them() {
    let out = busspec(&["check"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 8, "{stdout}");
    for (line, name) in lines.iter().zip([
        "crsf",
        "dynamixel",
        "dynamixel2",
        "modbus",
        "pelco_d",
        "pelco_p",
        "sd",
        "ub2",
    ]) {
        assert!(
            line.starts_with(&format!("spec/{name}.yaml: {name} (")),
            "{stdout}"
        );
    }
    for l in lines {
        assert!(
            l.ends_with(": ok")
                && l.contains(" commands, ")
                && l.contains(" examples (")
                && l.contains(" errata"),
            "{l}"
        );
    }
}

#[test]
fn check_reports_every_error_with_file_and_path_and_fails() {
    let dir = std::env::temp_dir().join(format!("busspec-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("spec/ub2.yaml"))
        .unwrap();
    // Two independent defects: a bad example checksum and a misspelt field key.
    let broken = good
        .replacen(
            "printed: \"0xAA21 1000 DB\"",
            "printed: \"0xAA21 1000 DC\"",
            1,
        )
        .replacen(
            "    code: \"0x2000\"",
            "    code: \"0x2000\"\n    colour: blue",
            1,
        );
    assert_ne!(broken, good);
    let file = dir.join("ub2.yaml");
    std::fs::write(&file, broken).unwrap();
    let out = busspec(&["check", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    let f = file.display().to_string();
    assert!(
        stderr.contains(&format!(
            "{f}: commands.go_to_capacitance.colour: unknown field `colour`"
        )),
        "{stderr}"
    );
    // Shape errors stop validation, so fix that one and the example error shows.
    let only_example = good.replacen(
        "printed: \"0xAA21 1000 DB\"",
        "printed: \"0xAA21 1000 DC\"",
        1,
    );
    std::fs::write(&file, only_example).unwrap();
    let out = busspec(&["check", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains(&format!("{f}: examples[0].printed: §4.1.1 reference_run: checksum mismatch at offset 4: expected 0xDB, found 0xDC")),
        "{stderr}"
    );
    assert!(stderr.contains(&format!("{f}: 1 error")), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn check_on_a_missing_file_says_so() {
    let out = busspec(&["check", "no/such/spec.yaml"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("no/such/spec.yaml: cannot read:"),
        "{}",
        text(&out.stderr)
    );
}

/// A spec that includes a file of common types checks, decodes and encodes through the CLI as
/// one that holds them; a missing included file is named where the spec names it.
#[test]
fn check_follows_include_and_names_an_included_file_that_is_missing() {
    let out = busspec(&["check", "examples/own-protocol/spec/thermo.yaml"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let out = busspec(&[
        "decode",
        "--spec",
        "examples/own-protocol/spec/thermo.yaml",
        "thermo",
        "A5 01 10 61 BF",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/tmp/cli_include");
    std::fs::create_dir_all(&dir).unwrap();
    let spec = std::fs::read_to_string("examples/own-protocol/spec/thermo.yaml").unwrap();
    let broken = dir.join("thermo.yaml");
    std::fs::write(
        &broken,
        spec.replace("include: th_units.yaml", "include: gone.yaml"),
    )
    .unwrap();
    let out = busspec(&["check", &broken.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.contains("thermo.yaml: include gone.yaml: cannot read: "),
        "{err}"
    );
    // Only the include is reported, not every unit the spec then misses.
    assert!(err.contains("thermo.yaml: 1 error"), "{err}");
}

#[test]
fn wrong_arguments_are_a_usage_error() {
    let out = busspec(&["chekc"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("unrecognized subcommand 'chekc'"),
        "{}",
        text(&out.stderr)
    );
    let out = busspec(&["docs", "--frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
}

/// `docs/` is generated from the specs; this fails when someone edits a spec and forgets
/// `busspec docs`, or edits a generated file by hand.
#[test]
fn docs_are_up_to_date() {
    let out = busspec(&["docs", "--check"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn docs_check_notices_a_stale_reference() {
    let dir = std::env::temp_dir().join(format!("busspec-docs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let d = dir.to_str().unwrap();
    let out = busspec(&["docs", "--out", d]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(busspec(&["docs", "--out", d, "--check"]).status.success());
    let ub2 = dir.join("ub2.md");
    let mut edited = std::fs::read_to_string(&ub2).unwrap();
    edited.push_str("hand edit\n");
    std::fs::write(&ub2, edited).unwrap();
    let out = busspec(&["docs", "--out", d, "--check"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("stale documentation"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}

// `busspec diff`: exit codes, `--allow`/`--deny`, the JSON document, the changelog, load errors.

const BASE: &str = "model/tests/fixtures/diff/base.yaml";
const WIRE: &str = "model/tests/fixtures/diff/wire.yaml";
const API: &str = "model/tests/fixtures/diff/api.yaml";
const COMPATIBLE: &str = "model/tests/fixtures/diff/compatible.yaml";

#[test]
fn wire_breaking_changes_fail_unless_allowed() {
    let out = busspec(&["diff", BASE, WIRE]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(
        stdout.lines().nth(1) == Some("23 wire-breaking, 0 api-breaking, 0 compatible"),
        "{stdout}"
    );
    assert!(
        stdout.contains("\nWire-breaking:\n  byte_order: "),
        "{stdout}"
    );
    assert!(
        stdout.contains("\n  commands.reset: command `reset` (0x1000) removed\n"),
        "{stdout}"
    );
    assert_eq!(
        text(&out.stderr),
        "error: 23 wire-breaking changes (pass --allow wire to accept them)\n"
    );
    let out = busspec(&["diff", "--allow", "wire", BASE, WIRE]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stderr.is_empty());
}

#[test]
fn api_breaking_changes_pass_unless_denied() {
    let out = busspec(&["diff", BASE, API]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout)
        .contains("\nAPI-breaking:\n  units.counter: unit `count` renamed to `counter`\n"));
    let out = busspec(&["diff", "--deny", "api", BASE, API]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "error: 8 api-breaking changes (denied by --deny api)\n"
    );
    // Compatible changes pass even with everything denied.
    let out = busspec(&["diff", "--deny", "api", "--deny", "wire", BASE, COMPATIBLE]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

#[test]
fn json_is_one_document_with_sides_counts_and_changes() {
    let out = busspec(&["diff", "--json", BASE, WIRE]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    assert_eq!(v["old"]["file"], BASE);
    assert_eq!(v["new"]["revision"], "1.0");
    assert_eq!(v["old"]["spec_sha256"].as_str().map(str::len), Some(64));
    assert_eq!(v["counts"]["wire-breaking"], 23);
    assert_eq!(v["counts"]["api-breaking"], 0);
    assert_eq!(v["denied"], serde_json::json!(["wire-breaking"]));
    assert_eq!(v["failed"], true);
    let changes = v["changes"].as_array().expect("changes");
    assert_eq!(changes.len(), 23);
    assert_eq!(
        changes[10],
        serde_json::json!({
            "category": "wire-breaking",
            "kind": "code_changed",
            "path": "commands.set_mode",
            "text": "command `set_mode`: code 0x3000 → 0x3100"
        })
    );
    let out = busspec(&["diff", "--json", "--allow", "wire", BASE, WIRE]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    assert_eq!(v["denied"], serde_json::json!([]));
    assert_eq!(v["failed"], false);
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn changelog_is_markdown_for_release_notes() {
    let out = busspec(&["diff", "--changelog", BASE, COMPATIBLE]);
    assert_eq!(out.status.code(), Some(0));
    let md = text(&out.stdout);
    assert!(md.starts_with("## mini: revision 1.1 (2024-06-01)\n\n*Minimal protocol reference*, revision 1.0 → 1.1."), "{md}");
    assert!(md.contains("\n### Compatible (15)\n\n"), "{md}");
    assert!(
        md.contains("\n- command `get_supply` (0x4100, §4.7) added\n"),
        "{md}"
    );
    assert!(md.ends_with("- erratum mini-e01 (§4.7) added\n"), "{md}");
}

#[test]
fn a_spec_that_does_not_load_is_exit_2_with_every_error() {
    let broken = "model/tests/fixtures/broken/bits_overlap.yaml";
    let out = busspec(&["diff", "no/such.yaml", broken]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("no/such.yaml: cannot read:"), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "{broken}: responses.status.fields.position_word.bits.position: bits 11..0 overlap another sub-field"
        )),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn contradicting_or_missing_arguments_are_usage_errors() {
    let out = busspec(&["diff", "--allow", "wire", "--deny", "wire", BASE, WIRE]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("`wire` is both allowed and denied"),
        "{}",
        text(&out.stderr)
    );
    assert_eq!(busspec(&["diff", BASE]).status.code(), Some(2));
    assert_eq!(
        busspec(&["diff", "--json", "--changelog", BASE, WIRE])
            .status
            .code(),
        Some(2)
    );
    assert_eq!(
        busspec(&["diff", "--allow", "everything", BASE, WIRE])
            .status
            .code(),
        Some(2)
    );
}
