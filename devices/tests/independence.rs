//! The master crates name no protocol: `busspec-link-core` and `busspec-link` depend on
//! `busspec-protocols` (the generated codecs) neither directly nor through another crate, with
//! any of their features, so firmware built on the core compiles only the protocols it names.
//! The UB2 and SD rules live in this crate instead. Asked of cargo's resolved graph (`cargo
//! tree`, normal and build dependencies; dev-dependencies may name protocols: the tests drive
//! the master through UB2 and SD).

use std::process::Command;

/// The packages `package` builds on (normal and build dependencies, all its features), one
/// `name vX.Y.Z` per line, itself first.
fn dependencies(package: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../Cargo.toml");
    let out = Command::new(cargo)
        .args([
            "tree",
            "--manifest-path",
            manifest,
            "--locked",
            "-p",
            package,
        ])
        .args(["-e", "normal,build", "--all-features"])
        .args(["--prefix", "none", "--format", "{p}"])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("cargo tree prints UTF-8");
    let lines: Vec<String> = text.lines().map(str::to_owned).collect();
    assert!(
        lines
            .first()
            .is_some_and(|l| l.starts_with(&format!("{package} "))),
        "cargo tree -p {package} printed:\n{text}"
    );
    lines
}

fn assert_free_of_protocols(package: &str) {
    let deps = dependencies(package);
    let named: Vec<&String> = deps
        .iter()
        .filter(|l| l.starts_with("busspec-protocols ") || l.starts_with("busspec-devices "))
        .collect();
    assert!(
        named.is_empty(),
        "{package} depends on {named:?}: the master crates stay generic over Protocol and \
         Link; protocol rules belong in busspec-devices\n{}",
        deps.join("\n")
    );
    assert!(
        deps.iter().any(|l| l.starts_with("busspec-runtime ")),
        "{package} no longer builds on busspec-runtime?\n{}",
        deps.join("\n")
    );
}

#[test]
fn link_core_depends_on_no_protocol() {
    assert_free_of_protocols("busspec-link-core");
}

#[test]
fn link_depends_on_no_protocol() {
    assert_free_of_protocols("busspec-link");
}

/// This crate builds on the codecs it names, so the check above looks at the right graph.
#[test]
fn devices_depend_on_the_protocols() {
    assert!(dependencies("busspec-devices")
        .iter()
        .any(|l| l.starts_with("busspec-protocols ")));
}
