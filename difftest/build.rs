//! Generates a module per fixture spec (`fixtures/*.yaml`) and one `#[test]` each, named after
//! its protocol, which holds the generated code to the interpreter (`tests/fixtures.rs`).

use std::fmt::Write as _;

fn main() {
    let dir = std::path::Path::new("fixtures");
    println!("cargo::rerun-if-changed=fixtures");
    let mut specs: Vec<_> = std::fs::read_dir(dir)
        .expect("difftest/fixtures")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    specs.sort();
    busspec_codegen::Builder::new().specs(&specs).compile();
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"));
    let mut tests = String::new();
    for spec in &specs {
        let text = std::fs::read_to_string(spec).expect("a fixture reads");
        let name = text
            .lines()
            .find_map(|l| l.strip_prefix("protocol:"))
            .map(|n| n.trim().to_owned())
            .expect("a fixture names its protocol");
        let ty = busspec_codegen::emit::camel(&name);
        // A spec a run found is compared with the seed it was found with (`spec seed N` in its
        // header), so the test replays that very run; others with seed 1.
        let seed: u64 = text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .find_map(|l| l.split("spec seed ").nth(1))
            .and_then(|rest| {
                rest.split(|c: char| !c.is_ascii_digit())
                    .next()?
                    .parse()
                    .ok()
            })
            .unwrap_or(1);
        let _ = writeln!(
            tests,
            "/// `{}`\n#[test]\nfn {name}() {{\n    check::<{name}::{ty}>({seed});\n}}\n",
            spec.display()
        );
    }
    busspec_codegen::write_if_changed(&out.join("fixture_tests.rs"), &tests)
        .expect("fixture_tests.rs written");
}
