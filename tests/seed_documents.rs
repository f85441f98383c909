//! Cross-checks the specs against the vendor documents themselves, kept beside them in `spec/`:
//! every frame the UB2 document prints appears in `spec/ub2.yaml`,
//! verbatim, in document order, under its section — so a frame cannot be dropped or retyped.

use std::path::PathBuf;

use busspec_model::load_file;

/// Where the vendor documents are: beside the specs that transcribe them.
fn seeds() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("spec")
}

/// `(section, frame text)` for every TX/RX table row of the document whose example column holds
/// a frame, in document order. Sections come from the numbered headings (`4.2.1 Triggering ...`).
fn printed_frames(doc: &str) -> Vec<(String, String)> {
    let mut section = String::new();
    let mut out = Vec::new();
    for line in doc.lines() {
        let first = line.split([' ', '\t']).next().unwrap_or("");
        let numbered = first.contains('.')
            && first
                .split('.')
                .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
        if numbered && !line.contains('\t') {
            section = first.to_owned();
        }
        if !(line.starts_with("→ TX") || line.starts_with("← RX")) {
            continue;
        }
        let last = line.rsplit('\t').next().unwrap_or("").trim();
        let is_frame = last
            .to_ascii_uppercase()
            .replace(' ', "")
            .trim_start_matches("0X")
            .starts_with("AA21")
            && last
                .chars()
                .all(|c| c.is_ascii_hexdigit() || c == ' ' || c == 'x');
        if is_frame {
            out.push((section.clone(), last.to_owned()));
        }
    }
    out
}

#[test]
fn every_frame_printed_in_the_ub2_document_is_in_the_spec_verbatim() {
    let doc = std::fs::read_to_string(seeds().join("comet-ub2-rs485-sb70.txt"))
        .expect("the UB2 document");
    let frames = printed_frames(&doc);
    assert!(
        frames.len() >= 80,
        "found only {} frames in the document",
        frames.len()
    );
    let spec = load_file(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("spec/ub2.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let printed: Vec<(&str, &str)> = spec
        .examples
        .iter()
        .filter_map(|e| e.printed.as_deref().map(|t| (e.section.as_str(), t)))
        .collect();
    for (i, ((doc_section, doc_text), (spec_section, spec_text))) in
        frames.iter().zip(&printed).enumerate()
    {
        assert_eq!(doc_text, spec_text, "frame {i} (document §{doc_section})");
        // A spec may cite a heading's parent where the document nests a figure heading.
        assert!(
            doc_section == spec_section || doc_section.starts_with(&format!("{spec_section}.")),
            "frame {i} `{doc_text}`: document §{doc_section}, spec §{spec_section}"
        );
    }
    assert_eq!(
        frames.len(),
        printed.len(),
        "the document prints {} frames, the spec has {}",
        frames.len(),
        printed.len()
    );
}

#[test]
fn the_sd_document_prints_no_frames_so_every_sd_example_is_derived() {
    let doc =
        std::fs::read_to_string(seeds().join("sd-01-02-rs485-icd.txt")).expect("the SD document");
    // Its command tables list codes and arguments one per line, never a whole frame.
    assert!(!doc.lines().any(|l| l
        .split_whitespace()
        .filter(|w| w.len() == 2 && w.bytes().all(|b| b.is_ascii_hexdigit()))
        .count()
        >= 6));
    let spec = load_file(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("spec/sd.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    assert!(spec.examples.iter().all(|e| e.derived.is_some()));
}

#[test]
fn every_numbered_sd_command_section_is_transcribed() {
    let doc =
        std::fs::read_to_string(seeds().join("sd-01-02-rs485-icd.txt")).expect("the SD document");
    let spec = load_file(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("spec/sd.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let sections: Vec<&str> = doc
        .lines()
        .filter_map(|l| l.trim_start_matches('#').trim().split(' ').next())
        .filter(|s| s.starts_with("3.") && s.len() > 2)
        .collect();
    assert_eq!(
        sections.len(),
        37,
        "the SD document has 37 command sections"
    );
    for s in sections {
        assert!(
            spec.commands.iter().any(|c| c.section == s),
            "no SD command for §{s}"
        );
    }
}

#[test]
fn every_ub2_command_code_in_the_document_is_transcribed() {
    let doc = std::fs::read_to_string(seeds().join("comet-ub2-rs485-sb70.txt"))
        .expect("the UB2 document");
    let spec = load_file(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("spec/ub2.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    let mut codes = Vec::new();
    for line in doc.lines() {
        let cols: Vec<&str> = line.split('\t').map(str::trim).collect();
        // TX rows: arrow, start, address, command code, data, ...
        if cols.first() == Some(&"→ TX") && cols.len() > 4 {
            // Sub-indexed reads put their selector in the data column as a bare `0x01`.
            let selector = cols[4]
                .strip_prefix("0x")
                .filter(|d| d.len() == 2)
                .map(|d| u8::from_str_radix(d, 16).ok());
            codes.push((cols[3].to_owned(), selector.flatten()));
        }
    }
    assert!(codes.len() >= 45, "found {} TX rows", codes.len());
    for (code, selector) in codes {
        let found = spec.commands.iter().any(|c| {
            c.code_hex() == code
                && selector
                    .is_none_or(|s| c.fields.first().and_then(|f| f.constant) == Some(u64::from(s)))
        });
        assert!(
            found,
            "no UB2 command for TX code {code} selector {selector:?}"
        );
    }
}
