//! The README's walkthrough: a revision 1.1 of the UB2 document (`tests/fixtures/ub2-rev1.1.yaml`)
//! against `spec/ub2.yaml`. Every change of it is listed here with its category, and the output
//! the README prints is the output `busspec diff` gives.
//!
//! When this fails after an edit of `spec/ub2.yaml`, make the same edit in the fixture (it is
//! the spec plus the revision's changes), then update the README block if the output changed.
//!
//! The walkthrough's last step copies the fixture over `spec/ub2.yaml` and runs the tests; in
//! that state (the spec is at revision 1.1.0) these tests check that the two are the same spec.

use std::path::Path;
use std::process::Command;

use busspec_model::diff::{self, Category};
use busspec_model::load_file;
use Category::{ApiBreaking as Api, Compatible as Compat, WireBreaking as Wire};

const OLD: &str = "spec/ub2.yaml";
const NEW: &str = "tests/fixtures/ub2-rev1.1.yaml";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Whether `spec/ub2.yaml` is the revision the walkthrough adopts (its last step).
fn adopted(spec: &busspec_model::Protocol) -> bool {
    spec.document.revision == "1.1.0"
}

#[test]
fn every_change_of_revision_1_1_is_classified() {
    let old = load_file(&root().join(OLD)).unwrap_or_else(|d| panic!("{d}"));
    let new = load_file(&root().join(NEW)).unwrap_or_else(|d| panic!("{d}"));
    let changes = diff::diff(&old, &new);
    if adopted(&old) {
        assert_eq!(changes, [], "{OLD} is at revision 1.1.0 but is not {NEW}");
        return;
    }
    let got: Vec<(Category, &str, &str)> = changes
        .iter()
        .map(|c| (c.category, c.kind, c.path.as_str()))
        .collect();
    assert_eq!(
        got,
        [
            // Provenance.
            (Compat, "document_changed", "document.revision"),
            (Compat, "document_changed", "document.date"),
            // ub2-e31: the reference-run check may get the step-loss reply.
            (
                Compat,
                "documentation_changed",
                "commands.reference_run_status"
            ),
            // ub2-e25: Go-To-Cmin/Cmax and their checks are named after what they do.
            (
                Api,
                "message_renamed",
                "commands.go_to_lower_customer_limit"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_lower_customer_limit"
            ),
            (
                Api,
                "message_renamed",
                "commands.go_to_lower_customer_limit_status"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_lower_customer_limit_status"
            ),
            (
                Api,
                "message_renamed",
                "commands.go_to_upper_customer_limit"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_upper_customer_limit"
            ),
            (
                Api,
                "message_renamed",
                "commands.go_to_upper_customer_limit_status"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_upper_customer_limit_status"
            ),
            // The new command and its reply.
            (Compat, "message_added", "commands.get_current"),
            (Compat, "message_added", "responses.current"),
            (
                Compat,
                "reply_added",
                "commands.reference_run_status.responses"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_lower_customer_limit.response_meanings.nak_limit_reached"
            ),
            (
                Compat,
                "documentation_changed",
                "commands.go_to_upper_customer_limit.response_meanings.nak_limit_reached"
            ),
            (Compat, "example_added", "examples"),
            (Compat, "example_added", "examples"),
            (Compat, "erratum_removed", "errata.ub2-e25"),
            (Compat, "erratum_removed", "errata.ub2-e31"),
        ],
        "spec/ub2.yaml and {NEW} drifted apart, or the diff classifies differently"
    );
    assert!(!changes.iter().any(|c| c.category == Wire));
    let renamed: Vec<&str> = changes
        .iter()
        .filter(|c| c.kind == "message_renamed")
        .map(|c| c.text.as_str())
        .collect();
    assert_eq!(
        renamed[0],
        "command `go_to_cmin` (0x2300) renamed to `go_to_lower_customer_limit`"
    );
    // The revision also generates: the codec and the reference come out of it as they do for
    // the spec it would replace.
    let code = busspec_codegen::emit::emit_module(&new, NEW, NEW).expect("generated code parses");
    assert!(code.contains("GetCurrent"));
    assert!(code.contains(&format!(
        "pub const SPEC_SHA256: &str = \"{}\";",
        new.spec_sha256
    )));
    assert!(busspec_model::docs::render(&new, NEW).contains("revision 1.1.0"));
}

#[test]
fn the_readme_shows_what_busspec_diff_prints() {
    let out = Command::new(env!("CARGO_BIN_EXE_busspec"))
        .args(["diff", OLD, NEW])
        .current_dir(root())
        .output()
        .expect("run busspec");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).expect("UTF-8 output");
    let spec = load_file(&root().join(OLD)).unwrap_or_else(|d| panic!("{d}"));
    if adopted(&spec) {
        assert_eq!(
            stdout.lines().nth(1),
            Some("0 wire-breaking, 0 api-breaking, 0 compatible")
        );
        return;
    }
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let command = format!("cargo run -q -- diff {OLD} {NEW}\n```\n\n```text\n");
    let at = readme
        .find(&command)
        .expect("the walkthrough's diff command in README.md")
        + command.len();
    let block = &readme[at..at + readme[at..].find("```").expect("end of the block")];
    // The first line names both files with a short hash; it changes with any edit of the spec,
    // so only its shape is compared.
    let (head, rest) = block.split_once('\n').expect("a header line");
    let (actual_head, actual_rest) = stdout.split_once('\n').expect("a header line");
    assert_eq!(rest, actual_rest, "README.md's walkthrough output is stale");
    let shape = |l: &str| l.split("sha256").count();
    assert!(
        head.starts_with("ub2: spec/ub2.yaml (rev 1.0.0, ") && shape(head) == shape(actual_head),
        "{head}"
    );
}
