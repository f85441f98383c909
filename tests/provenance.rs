//! Every generated artifact says which revision of which document, and which exact spec file,
//! it came from.

use std::path::Path;

fn spec(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("spec")
            .join(name),
    )
    .expect("the spec")
}

#[test]
fn the_generated_modules_carry_the_revision_and_hash_of_their_spec() {
    let cases = [
        (
            "ub2.yaml",
            busspec_protocols::ub2::DOCUMENT_REVISION,
            busspec_protocols::ub2::DOCUMENT_DATE,
            busspec_protocols::ub2::SPEC_SHA256,
        ),
        (
            "sd.yaml",
            busspec_protocols::sd::DOCUMENT_REVISION,
            busspec_protocols::sd::DOCUMENT_DATE,
            busspec_protocols::sd::SPEC_SHA256,
        ),
    ];
    for (file, revision, date, hash) in cases {
        let text = spec(file);
        let p = busspec_model::load_str(file, &text).unwrap_or_else(|d| panic!("{d}"));
        assert_eq!(revision, p.document.revision, "{file}");
        assert_eq!(date, p.document.date, "{file}");
        assert_eq!(hash, busspec_model::spec_sha256(&text), "{file}");
        assert_eq!(hash.len(), 64, "{file}");
    }
}

#[test]
fn the_rendered_docs_show_revision_and_hash() {
    for (file, doc) in [("ub2.yaml", "ub2.md"), ("sd.yaml", "sd.md")] {
        let text = spec(file);
        let p = busspec_model::load_str(file, &text).unwrap_or_else(|d| panic!("{d}"));
        let md =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs").join(doc))
                .expect("the rendered reference");
        let source_line = md
            .lines()
            .find(|l| l.starts_with("Source: "))
            .expect("a Source: line");
        assert!(
            source_line.contains(&format!("(SHA-256 `{}`)", p.spec_sha256))
                && source_line.contains(&format!("revision {}", p.document.revision)),
            "{source_line}"
        );
    }
}
