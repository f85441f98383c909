//! The model's layers point one way: the validator builds the IR, the IR owns the arithmetic
//! every reader shares (frame lengths, length fields), and the generator reads the IR. A call
//! from the IR or the generator back into the validator would make a circle, so this reads the
//! sources and fails on one.

use std::path::Path;

/// The lines of `path` that are code, not comments.
fn code_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l.to_string()))
        .collect()
}

fn rust_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

fn uses_of_validate(files: &[std::path::PathBuf]) -> Vec<String> {
    let mut found = Vec::new();
    for f in files {
        for (n, line) in code_lines(f) {
            if line.contains("validate::") {
                found.push(format!("{}:{n}: {}", f.display(), line.trim()));
            }
        }
    }
    found
}

#[test]
fn the_ir_imports_nothing_of_the_validator() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let found = uses_of_validate(&[root.join("src/ir.rs")]);
    assert!(
        found.is_empty(),
        "the IR calls the validator:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_generator_reads_the_ir_not_the_validator() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../codegen/src");
    let files = rust_files(&root);
    assert!(
        !files.is_empty(),
        "no generator sources under {}",
        root.display()
    );
    let found = uses_of_validate(&files);
    assert!(
        found.is_empty(),
        "the generator calls the validator:\n{}",
        found.join("\n")
    );
}
