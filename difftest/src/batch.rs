//! A batch of specs as one crate: one rustc run serves them all. [`write()`] lays the crate out
//! (its own workspace, path dependencies on this repository, a copy of its lock file, the
//! generated modules and a `main` that `include!`s them); the batch's `main` calls [`main`]
//! with one entry per spec, which runs [`crate::compare::compare`] on each and writes every
//! disagreement as a reproduction file.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::compare::{self, Budget, Report};

/// One spec of a batch: the seed that generated it, and its protocol type's comparison.
/// And its spec text (the module's `SPEC_YAML`).
pub type Entry = (u64, &'static str, fn(u64, Budget) -> Report, &'static str);

/// The repository this crate belongs to.
pub fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("difftest/ sits in the repository")
        .to_path_buf()
}

/// The comparison for protocol `P`, as a batch entry calls it.
pub fn entry<P: busspec_runtime::Protocol>(seed: u64, budget: Budget) -> Report {
    compare::compare::<P>(seed, budget)
}

/// [`entry`] with the module's borrowed views held to its owned decode (see
/// [`compare::ViewFns`]).
pub fn entry_views<P: busspec_runtime::Protocol>(
    seed: u64,
    budget: Budget,
    views: compare::ViewFns<P>,
) -> Report {
    compare::compare_with_views::<P>(seed, budget, views)
}

/// The glue of the batch's `main` for module `name` (protocol type `ty`) whose code is `code`:
/// where it has views, a function running [`entry_views`] with them, and the entry's function.
fn views_glue(name: &str, ty: &str, code: &str) -> (String, String) {
    let request = code.contains("pub enum RequestView<'a>");
    let response = code.contains("pub enum ResponseView<'a>");
    if !request && !response {
        return (
            String::new(),
            format!("busspec_difftest::batch::entry::<{name}::{ty}>"),
        );
    }
    let request = if request {
        format!(
            "Some(|f| {name}::RequestView::decode(f).map(|d| (d.address, d.message.to_owned())))"
        )
    } else {
        "None".to_owned()
    };
    let response = if response {
        format!(
            "Some(|f, r| match r {{ Some(r) => {name}::ResponseView::decode_reply(f, r), None => {name}::ResponseView::decode(f) }}.map(|d| (d.address, d.message.to_owned())))"
        )
    } else {
        "None".to_owned()
    };
    let f = format!("views_{name}");
    (
        format!(
            "fn {f}(seed: u64, budget: busspec_difftest::compare::Budget) -> busspec_difftest::compare::Report {{\n    busspec_difftest::batch::entry_views::<{name}::{ty}>(seed, budget, busspec_difftest::compare::ViewFns {{ request: {request}, response: {response} }})\n}}\n"
        ),
        f,
    )
}

/// How the batch crate is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// In a target dir of its own, its dependencies optimised: they compile once (minutes on a
    /// fresh machine), then every round compares quickly.
    Optimised,
    /// In the workspace's target dir with the workspace's (default) dev profile, so it reuses
    /// the dependencies building the workspace compiled; comparing is slower.
    Workspace,
}

/// Writes the batch crate into `dir` for `specs` (seed, protocol name, emitted module), so
/// that `cargo build` there builds one binary comparing them all. Files are rewritten only
/// when they change; `profile` says how it is built.
pub fn write(dir: &Path, specs: &[(u64, String, String)], profile: Profile) -> std::io::Result<()> {
    let repo = repository();
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("gen"))?;
    let profile = match profile {
        Profile::Optimised => {
            "\n# The dependencies compile once, optimised; the batch's own code, new every round, quickly.\n\
             [profile.dev]\ndebug = false\nincremental = false\n[profile.dev.package.\"*\"]\nopt-level = 2\n"
        }
        // The workspace's dev profile, unchanged, so its compiled dependencies are reused.
        Profile::Workspace => "",
    };
    let manifest = format!(
        r#"# Written by busspec-difftest: a batch of random specs, compiled together.
[package]
name = "busspec-difftest-batch"
version = "0.0.0"
edition = "2021"
publish = false

[workspace]

[dependencies]
busspec-difftest = {{ path = "{repo}/difftest" }}
busspec-runtime = {{ path = "{repo}/runtime" }}
{profile}
# Generated derives sit behind features named `serde` and `arbitrary`, which the batch has not.
[lints.rust]
unexpected_cfgs = {{ level = "allow" }}
"#,
        repo = repo.display()
    );
    busspec_codegen::write_if_changed(&dir.join("Cargo.toml"), &manifest)?;
    let lock = std::fs::read_to_string(repo.join("Cargo.lock"))?;
    if !dir.join("Cargo.lock").exists() {
        std::fs::write(dir.join("Cargo.lock"), lock)?;
    }
    let mut main = String::from(
        "// Written by busspec-difftest: every module of the batch and one entry each.\n\
         #![allow(clippy::all, dead_code, unused)]\n",
    );
    for (_, name, code) in specs {
        busspec_codegen::write_if_changed(&src.join("gen").join(format!("{name}.rs")), code)?;
        main.push_str(&format!("include!(\"gen/{name}.rs\");\n"));
    }
    // Modules with borrowed views run them beside their owned decode.
    let glue: Vec<(String, String)> = specs
        .iter()
        .map(|(_, name, code)| views_glue(name, &busspec_codegen::emit::camel(name), code))
        .collect();
    for (f, _) in &glue {
        main.push_str(f);
    }
    main.push_str("\nconst SPECS: &[busspec_difftest::batch::Entry] = &[\n");
    for ((seed, name, _), (_, run)) in specs.iter().zip(&glue) {
        main.push_str(&format!(
            "    ({seed}, \"{name}\", {run}, {name}::SPEC_YAML),\n"
        ));
    }
    main.push_str("];\n\nfn main() {\n    busspec_difftest::batch::main(SPECS);\n}\n");
    busspec_codegen::write_if_changed(&src.join("main.rs"), &main)
}

/// Figures of one batch run, printed as one `totals:` line for the driver to read.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Totals {
    pub specs: usize,
    pub frames: usize,
    pub encodes: usize,
    pub captures: usize,
    pub disagreements: usize,
    pub specs_disagreeing: usize,
    /// Disagreements where both engines refuse, for different reasons.
    pub class_only: usize,
    /// Replies whose checksum takes in their request's bytes both engines accepted.
    pub over_request: usize,
}

impl Totals {
    pub fn line(&self) -> String {
        format!(
            "totals: specs {} frames {} encodes {} captures {} disagreements {} specs_disagreeing {} class_only {} over_request {}",
            self.specs,
            self.frames,
            self.encodes,
            self.captures,
            self.disagreements,
            self.specs_disagreeing,
            self.class_only,
            self.over_request
        )
    }

    pub fn parse(line: &str) -> Option<Totals> {
        let rest = line.strip_prefix("totals: ")?;
        let w: Vec<&str> = rest.split_whitespace().collect();
        let get = |k: &str| -> Option<usize> {
            let i = w.iter().position(|x| *x == k)?;
            w.get(i + 1)?.parse().ok()
        };
        Some(Totals {
            specs: get("specs")?,
            frames: get("frames")?,
            encodes: get("encodes")?,
            captures: get("captures")?,
            disagreements: get("disagreements")?,
            specs_disagreeing: get("specs_disagreeing")?,
            class_only: get("class_only")?,
            over_request: get("over_request").unwrap_or(0),
        })
    }

    pub fn add(&mut self, o: &Totals) {
        self.specs += o.specs;
        self.frames += o.frames;
        self.encodes += o.encodes;
        self.captures += o.captures;
        self.disagreements += o.disagreements;
        self.specs_disagreeing += o.specs_disagreeing;
        self.class_only += o.class_only;
        self.over_request += o.over_request;
    }
}

/// The batch binary's `main`: compares every entry (arguments: `--found DIR`, where the
/// reproductions go, and `--budget FRAMES,ENCODES,CAPTURES`), prints each disagreement and
/// the totals, and exits with status 1 if any.
pub fn main(specs: &[Entry]) {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut found = repository().join("difftest").join("found");
    let mut budget = Budget::default();
    let mut i = 0;
    while i < args.len() {
        match (args[i].as_str(), args.get(i + 1)) {
            ("--found", Some(v)) => found = PathBuf::from(v),
            ("--budget", Some(v)) => {
                let n: Vec<usize> = v.split(',').filter_map(|x| x.parse().ok()).collect();
                if let [a, b, c] = n[..] {
                    budget = Budget {
                        random_frames: a,
                        encodes_per_message: b,
                        captures: c,
                    };
                }
            }
            (a, _) => {
                eprintln!("batch: unknown argument {a}");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    compare::quiet_panics();
    let mut t = Totals::default();
    for &(seed, name, run, yaml) in specs {
        let r = run(seed, budget);
        t.specs += 1;
        t.frames += r.frames;
        t.encodes += r.encodes;
        t.captures += r.captures;
        t.disagreements += r.disagreements;
        t.class_only += r.class_only;
        t.over_request += r.over_request;
        for (sig, n) in &r.signatures {
            println!("SIGNATURE {n} {sig}");
        }
        if r.disagreements == 0 {
            continue;
        }
        t.specs_disagreeing += 1;
        let _ = std::fs::create_dir_all(&found);
        for (n, d) in r.found.iter().enumerate() {
            let text = compare::reproduction(yaml, seed, d);
            let path = found.join(format!("{seed}-{n}.yaml"));
            let _ = std::fs::write(&path, &text);
            println!(
                "DISAGREEMENT {name} (spec seed {seed}) {}\n  how:         {}\n  input:       {}\n  generated:   {}\n  interpreter: {}\n  written to {}",
                d.signature,
                d.how,
                d.input,
                d.generated,
                d.interpreter,
                path.display()
            );
        }
        if r.disagreements > r.found.len() {
            println!(
                "  ({} more disagreements on {name} not written)",
                r.disagreements - r.found.len()
            );
        }
    }
    println!("{}", t.line());
    let _ = std::io::stdout().flush();
    if t.disagreements > 0 {
        std::process::exit(1);
    }
}
