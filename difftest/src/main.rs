//! `busspec-difftest`: rounds of random specs, each round compiled as one batch crate and run,
//! until the time is spent. See `FUZZING.md` ("Random specs").
//!
//! ```text
//! cargo run -p busspec-difftest -- [--seed N|random] [--specs N] [--seconds T] [--out DIR]
//!     [--workspace-target] [--found DIR] [--budget FRAMES,ENCODES,CAPTURES] [--spec-seed S]... [--print S]
//! ```

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use busspec_difftest::batch::{self, Totals};
use busspec_difftest::gen;

const USAGE: &str = "usage: busspec-difftest [--seed N|random] [--specs N] [--seconds T] [--out DIR] [--found DIR] [--budget FRAMES,ENCODES,CAPTURES] [--spec-seed S]... [--print S]

  --seed N|random   the run's seed (default: random, from the clock; printed as `seed: N`)
  --specs N         specs per round (default 24)
  --seconds T       keep starting rounds until T seconds have passed (default 0: one round)
  --out DIR         where the batch crate and its target dir go
                    (default: $CARGO_TARGET_DIR/difftest, else target/difftest)
  --workspace-target
                    build the batch crate in the workspace's target dir, unoptimised
                    (the dev profile): it reuses what building the workspace compiled,
                    where by default its dependencies compile once more, optimised, under
                    --out (minutes on a fresh machine; comparing is faster after)
  --found DIR       where reproductions go (default: difftest/found)
  --budget F,E,C    per spec: random frames, encodes per message, captures (default 400,24,12)
  --spec-seed S     compare exactly the spec of seed S (repeatable; a seed given twice
                    counts once), one round
  --print S         print the spec of seed S and exit
  --generate-only   generate, validate and emit the specs, without compiling or comparing
  --error-class warn|fail
                    where both engines refuse a frame or an encode for different reasons:
                    report it and exit 0 (warn), or count it as a disagreement (fail, default)";

struct Args {
    seed: u64,
    specs: usize,
    seconds: u64,
    out: PathBuf,
    /// Build in the workspace's target dir, in its dev profile, instead of under `out`.
    workspace_target: Option<PathBuf>,
    found: PathBuf,
    budget: Option<String>,
    spec_seeds: Vec<u64>,
    /// Generate, validate and emit only: no batch crate.
    generate_only: bool,
    /// Where both engines refuse a frame for different reasons: report, do not fail.
    error_class_warn: bool,
}

fn fail(msg: &str) -> ! {
    eprintln!("busspec-difftest: {msg}\n{USAGE}");
    std::process::exit(2)
}

fn number<T: std::str::FromStr>(flag: &str, v: Option<&String>) -> T {
    let Some(v) = v else {
        fail(&format!("{flag} needs a value"))
    };
    v.parse()
        .unwrap_or_else(|_| fail(&format!("{flag}: `{v}` is not a number")))
}

fn parse_args() -> Args {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| batch::repository().join("target"));
    let mut a = Args {
        seed: clock_seed(),
        specs: 24,
        seconds: 0,
        out: target.join("difftest"),
        workspace_target: None,
        found: batch::repository().join("difftest").join("found"),
        budget: None,
        spec_seeds: Vec::new(),
        generate_only: false,
        error_class_warn: false,
    };
    let mut i = 0;
    while i < argv.len() {
        let flag = argv[i].as_str();
        let v = argv.get(i + 1);
        match flag {
            "--seed" => {
                a.seed = match v.map(String::as_str) {
                    Some("random") => clock_seed(),
                    _ => number(flag, v),
                }
            }
            "--specs" => a.specs = number(flag, v),
            "--seconds" => a.seconds = number(flag, v),
            "--out" => a.out = PathBuf::from(v.unwrap_or_else(|| fail("--out needs a value"))),
            "--found" => {
                a.found = PathBuf::from(v.unwrap_or_else(|| fail("--found needs a value")))
            }
            "--budget" => {
                let b = v.unwrap_or_else(|| fail("--budget needs a value"));
                if b.split(',').filter(|x| x.parse::<usize>().is_ok()).count() != 3 {
                    fail("--budget takes three numbers: FRAMES,ENCODES,CAPTURES");
                }
                a.budget = Some(b.clone());
            }
            // A seed given twice is compared once (its module would be emitted twice).
            "--spec-seed" => {
                let s = number(flag, v);
                if !a.spec_seeds.contains(&s) {
                    a.spec_seeds.push(s);
                }
            }
            "--error-class" => match v.map(String::as_str) {
                Some("warn") => a.error_class_warn = true,
                Some("fail") => a.error_class_warn = false,
                _ => fail("--error-class takes `warn` or `fail`"),
            },
            "--workspace-target" => {
                a.workspace_target = Some(target.clone());
                i += 1;
                continue;
            }
            "--generate-only" => {
                a.generate_only = true;
                i += 1;
                continue;
            }
            "--print" => {
                print!("{}", gen::random_spec(number(flag, v)));
                std::process::exit(0);
            }
            "-h" | "--help" => {
                println!("{USAGE}");
                std::process::exit(0);
            }
            other => fail(&format!("unknown argument `{other}`")),
        }
        i += 2;
    }
    if a.specs == 0 {
        fail("--specs must be at least 1");
    }
    a
}

fn clock_seed() -> u64 {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    splitmix(t.as_nanos() as u64 ^ u64::from(std::process::id()))
}

fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of spec `i` of round `round` of a run seeded `seed`, kept below 2^48 so names and
/// file names stay short.
fn spec_seed(seed: u64, round: u64, i: u64) -> u64 {
    splitmix(splitmix(seed ^ round.wrapping_mul(0x1000_0001)) ^ i) >> 16
}

#[derive(Default)]
struct Figures {
    generated: usize,
    refused: usize,
    gaps: usize,
    no_examples: usize,
    compiled: usize,
    totals: Totals,
    rounds: usize,
    failed_builds: usize,
    signatures: BTreeMap<String, usize>,
    /// Specs with each construct, over every round.
    coverage: BTreeMap<&'static str, usize>,
}

fn main() {
    let args = parse_args();
    let started = Instant::now();
    println!("seed: {}", args.seed);
    println!(
        "reproduce: cargo run -p busspec-difftest -- --seed {} --specs {}{}",
        args.seed,
        args.specs,
        if args.seconds > 0 {
            format!(" --seconds {}", args.seconds)
        } else {
            String::new()
        }
    );
    let mut f = Figures::default();
    let dir = args.out.join("batch");
    let mut round = 0u64;
    loop {
        let seeds: Vec<u64> = if args.spec_seeds.is_empty() {
            (0..args.specs as u64)
                .map(|i| spec_seed(args.seed, round, i))
                .collect()
        } else {
            args.spec_seeds.clone()
        };
        run_round(&args, &dir, round, &seeds, &mut f);
        round += 1;
        if !args.spec_seeds.is_empty() || started.elapsed() >= Duration::from_secs(args.seconds) {
            break;
        }
    }
    let t = &f.totals;
    println!(
        "\nrun of seed {}: {} rounds in {:.0?}\n  specs generated  {}\n  refused by the validator (generator bugs) {}\n  not emitted (generator gaps) {}\n  without examples {}\n  specs compiled   {}\n  specs compared   {}\n  frames compared  {}\n  encodes compared {}\n  stream captures compared {}\n  disagreements    {} (on {} specs)\n  failed builds    {}",
        args.seed,
        f.rounds,
        started.elapsed(),
        f.generated,
        f.refused,
        f.gaps,
        f.no_examples,
        f.compiled,
        t.specs,
        t.frames,
        t.encodes,
        t.captures,
        t.disagreements,
        t.specs_disagreeing,
        f.failed_builds
    );
    // The constructs the language added last, over the whole run.
    let count = |k: &str| f.coverage.get(k).copied().unwrap_or(0);
    println!(
        "  specs with optional fields {}, with a preamble {}, with counted text {}, with a long length form {}, with text up to a terminator {}, with a payload over 255 bytes {} ({} without a length field)",
        count("optional fields"),
        count("preamble"),
        count("counted text"),
        count("long length form"),
        count("text up to a terminator"),
        count("payload over 255 bytes"),
        count("payload over 255 bytes without a length field")
    );
    println!(
        "  specs with a reply's checksum over its request's bytes {}, such replies both engines accepted {}",
        count("a reply's checksum over its request's bytes"),
        t.over_request
    );
    println!(
        "  specs with a layout by direction {} (the header in one direction only {}, the address in one direction only {}, the code at another offset by direction {}, the checksum covering from another offset by direction {}, header fields by direction {})",
        count("layout by direction"),
        count("header in one direction only"),
        count("address in one direction only"),
        count("code at another offset by direction"),
        count("checksum covering from another offset by direction"),
        count("header fields by direction")
    );
    println!(
        "  specs with a checksum before the bytes it covers {}",
        count("checksum before the payload")
    );
    println!(
        "  specs with a checksum covering bytes on both sides of it {}, followed by its complement {}",
        count("checksum covering both sides of it"),
        count("checksum followed by its complement")
    );
    if !f.signatures.is_empty() {
        println!("disagreements by what differs (count, what):");
        for (sig, n) in &f.signatures {
            println!("  {n:>8}  {sig}");
        }
    }
    let serious = t.disagreements
        - if args.error_class_warn {
            t.class_only
        } else {
            0
        };
    if args.error_class_warn && t.class_only > 0 {
        println!(
            "({} disagreements on the error class only, not counted: --error-class warn)",
            t.class_only
        );
    }
    if serious > 0 || f.refused > 0 || f.failed_builds > 0 {
        if t.disagreements > 0 {
            println!("reproductions: {}", args.found.display());
        }
        std::process::exit(1);
    }
}

fn run_round(args: &Args, dir: &std::path::Path, round: u64, seeds: &[u64], f: &mut Figures) {
    f.rounds += 1;
    let t0 = Instant::now();
    let specs_dir = dir.join("specs");
    std::fs::create_dir_all(&specs_dir)
        .unwrap_or_else(|e| fail(&format!("{}: {e}", specs_dir.display())));
    // Last round's modules go: only this round's are compiled.
    let _ = std::fs::remove_dir_all(dir.join("src").join("gen"));
    let mut modules = Vec::new();
    let mut tally: BTreeMap<&'static str, usize> = BTreeMap::new();
    for &s in seeds {
        f.generated += 1;
        let text = gen::random_spec(s);
        let p = match busspec_model::load_str(&format!("s{s}.yaml"), &text) {
            Ok(p) => p,
            Err(d) => {
                f.refused += 1;
                println!("GENERATOR BUG: the validator refuses the spec of seed {s}:\n{d}\n--- spec ---\n{text}--- end ---");
                continue;
            }
        };
        if p.examples.is_empty() {
            f.no_examples += 1;
            println!("spec seed {s}: no example decodes on its own; not compared");
            continue;
        }
        let gaps = p.generator_gaps();
        if !gaps.is_empty() {
            f.gaps += 1;
            println!(
                "spec seed {s}: the generator cannot emit it: {}",
                gaps.join("; ")
            );
            continue;
        }
        for c in gen::constructs(&p) {
            *tally.entry(c).or_default() += 1;
        }
        let path = specs_dir.join(format!("{}.yaml", p.name));
        if let Err(e) = busspec_codegen::write_if_changed(&path, &text) {
            fail(&format!("{}: {e}", path.display()));
        }
        let mut abs = std::fs::canonicalize(&path).unwrap_or(path.clone());
        // One spec in three takes its units, enums and flag sets from a file it includes: it
        // must load to the same protocol, and the code is generated from the spec with the
        // file in place (as a build script embeds it), which the comparison then loads.
        if s % 3 == 0 {
            match with_include(&specs_dir, &p, &text) {
                Ok(Some(flat)) => {
                    *tally.entry("include").or_default() += 1;
                    abs = std::fs::canonicalize(&flat).unwrap_or(flat);
                }
                Ok(None) => {}
                Err(e) => {
                    f.refused += 1;
                    println!("spec seed {s}: {e}\n--- spec ---\n{text}--- end ---");
                    continue;
                }
            }
        }
        match busspec_codegen::emit::emit_module(
            &p,
            &path.display().to_string(),
            &abs.to_string_lossy(),
        ) {
            Ok(code) => modules.push((s, p.name.clone(), code)),
            Err(e) => {
                f.refused += 1;
                println!(
                    "spec seed {s}: the code generator fails: {e}\n--- spec ---\n{text}--- end ---"
                );
            }
        }
    }
    let gen_time = t0.elapsed();
    let compared = modules.len();
    let spec_names: Vec<String> = modules.iter().map(|m| m.0.to_string()).collect();
    println!(
        "round {round}: spec seeds {}\n  generated and emitted {compared} in {gen_time:.1?}",
        spec_names.join(" ")
    );
    let cov: Vec<String> = tally.iter().map(|(k, v)| format!("{k} {v}")).collect();
    println!("  coverage (specs with each construct): {}", cov.join(", "));
    for (k, v) in &tally {
        *f.coverage.entry(*k).or_default() += v;
    }
    if modules.is_empty() || args.generate_only {
        return;
    }
    let profile = match args.workspace_target {
        Some(_) => batch::Profile::Workspace,
        None => batch::Profile::Optimised,
    };
    if let Err(e) = batch::write(dir, &modules, profile) {
        fail(&format!(
            "writing the batch crate in {}: {e}",
            dir.display()
        ));
    }
    let t1 = Instant::now();
    let target = args
        .workspace_target
        .clone()
        .unwrap_or_else(|| args.out.join("target"));
    let status = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["build", "--offline", "--quiet", "--manifest-path"])
        .arg(dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", &target)
        .env_remove("RUSTFLAGS")
        .status();
    let build_time = t1.elapsed();
    match status {
        Ok(s) if s.success() => {}
        _ => {
            f.failed_builds += 1;
            println!(
                "  the batch crate does not build ({build_time:.1?}): see {}",
                dir.display()
            );
            return;
        }
    }
    f.compiled += compared;
    let t2 = Instant::now();
    let mut cmd = Command::new(target.join("debug").join("busspec-difftest-batch"));
    cmd.arg("--found").arg(&args.found);
    if let Some(b) = &args.budget {
        cmd.args(["--budget", b]);
    }
    let out = cmd.output();
    let run_time = t2.elapsed();
    let Ok(out) = out else {
        f.failed_builds += 1;
        println!("  the batch binary does not run");
        return;
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut totals = None;
    for line in stdout.lines() {
        if let Some(rest) = line.strip_prefix("SIGNATURE ") {
            if let Some((n, sig)) = rest.split_once(' ') {
                *f.signatures.entry(sig.to_owned()).or_default() += n.parse::<usize>().unwrap_or(0);
            }
            continue;
        }
        match Totals::parse(line) {
            Some(t) => totals = Some(t),
            None => println!("  {line}"),
        }
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !stderr.trim().is_empty() {
        println!("  batch stderr: {}", stderr.trim());
    }
    match totals {
        Some(t) => {
            println!(
                "  compiled in {build_time:.1?}, compared in {run_time:.1?}: {} frames, {} encodes, {} captures, {} disagreements",
                t.frames, t.encodes, t.captures, t.disagreements
            );
            f.totals.add(&t);
        }
        None => {
            f.failed_builds += 1;
            println!("  the batch binary ended without totals ({})", out.status);
        }
    }
}

/// Writes spec `text` (loaded as `p`) as two files, its units, enums and flag sets in
/// `NAME.types.yaml` and the rest in `NAME.inc.yaml` with `include: NAME.types.yaml`; loads
/// that, which must give `p` again (its digest aside), and writes the spec with the file in
/// place, which must load to `p` too. Returns where that flattened text is (`None`: a spec
/// without those sections).
fn with_include(
    dir: &std::path::Path,
    p: &busspec_model::Protocol,
    text: &str,
) -> Result<Option<std::path::PathBuf>, String> {
    let mut types = String::new();
    let mut rest = String::new();
    let mut in_types = false;
    for line in text.split_inclusive('\n') {
        if !line.starts_with([' ', '#', '-', '\n']) {
            in_types = ["units:", "enums:", "flags:"]
                .iter()
                .any(|k| line.starts_with(k));
        }
        if in_types {
            types.push_str(line);
        } else {
            rest.push_str(line);
        }
    }
    if types.is_empty() {
        return Ok(None);
    }
    let name = &p.name;
    let write = |file: String, text: &str| {
        let path = dir.join(file);
        busspec_codegen::write_if_changed(&path, text)
            .map(|()| path)
            .map_err(|e| e.to_string())
    };
    write(format!("{name}.types.yaml"), &types)?;
    let main = write(
        format!("{name}.inc.yaml"),
        &format!("include: {name}.types.yaml\n{rest}"),
    )?;
    let loaded = busspec_model::load_file_with_includes(&main)
        .map_err(|d| format!("the spec with an include is refused:\n{d}"))?;
    let same = |q: &busspec_model::Protocol| {
        let mut q = q.clone();
        q.spec_sha256.clone_from(&p.spec_sha256);
        format!("{q:?}") == format!("{p:?}")
    };
    if !same(&loaded.protocol) {
        return Err("the spec with an include loads to another protocol".to_owned());
    }
    let flat = loaded
        .included
        .flattened
        .ok_or("the spec with an include has no flattened text")?;
    let again = busspec_model::load_str("flat.yaml", &flat)
        .map_err(|d| format!("the flattened spec is refused:\n{d}"))?;
    if !same(&again) {
        return Err("the flattened spec loads to another protocol".to_owned());
    }
    write(format!("{name}.flat.yaml"), &flat).map(Some)
}
