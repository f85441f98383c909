//! The `busspec` command line: exit codes, summaries, and errors that say what and where.

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
fn check_passes_on_both_specs_and_summarises_them() {
    let out = busspec(&["check"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    assert!(lines[0].starts_with("spec/sd.yaml: sd ("), "{stdout}");
    assert!(lines[1].starts_with("spec/ub2.yaml: ub2 ("), "{stdout}");
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
