//! The command line: a spec seed given twice is generated and compared once (its module
//! emitted twice did not compile).

use std::process::Command;

#[test]
fn a_spec_seed_given_twice_counts_once() {
    let out = std::env::temp_dir().join(format!("busspec-difftest-cli-{}", std::process::id()));
    let run = Command::new(env!("CARGO_BIN_EXE_busspec-difftest"))
        .args([
            "--spec-seed",
            "7",
            "--spec-seed",
            "7",
            "--generate-only",
            "--out",
        ])
        .arg(&out)
        .arg("--found")
        .arg(out.join("found"))
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&out);
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(text.contains("spec seeds 7\n"), "{text}");
    assert!(text.contains("generated and emitted 1 "), "{text}");
}
