//! Every fuzz target's body, on stable, over its seed corpus (`fuzz/corpus/<target>/seed-*`, and
//! for the spec loader the specs and fixture specs) and every stored regression input
//! (`fuzz/regressions/<target>/`): what a crash once was must stay fixed, and the seeds must keep
//! passing. What a fuzzing run added to a local corpus is not replayed here (it can be large);
//! `fuzz/run TARGET 0 -runs=0` replays a whole local corpus.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use busspec_fuzz_bodies::seeds::{self, repo_root, LOADER_SEED_DIRS};
use busspec_fuzz_bodies::{Target, TARGETS};

fn inputs(t: &Target) -> Vec<PathBuf> {
    let fuzz = repo_root().join("fuzz");
    let corpus = fuzz.join("corpus").join(t.name);
    let mut files: Vec<PathBuf> = seeds::list(&corpus)
        .into_iter()
        .filter(|n| n.starts_with(seeds::SEED_PREFIX))
        .map(|n| corpus.join(n))
        .collect();
    let mut dirs = vec![fuzz.join("regressions").join(t.name)];
    if t.name == "spec_loader" {
        dirs.extend(LOADER_SEED_DIRS.iter().map(|d| repo_root().join(d)));
    }
    files.extend(
        dirs.iter()
            .flat_map(|d| seeds::list(d).into_iter().map(move |n| d.join(n))),
    );
    files
}

/// Runs `t` over all its inputs; returns how many, failing with every input that panicked.
fn replay(t: &Target) -> usize {
    let files = inputs(t);
    let mut failures = Vec::new();
    for f in &files {
        let data = std::fs::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        if let Err(p) = catch_unwind(AssertUnwindSafe(|| (t.body)(&data))) {
            let why = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            failures.push(format!("{}: {why}", f.display()));
        }
    }
    assert!(
        failures.is_empty(),
        "{}: {} of {} inputs fail:\n{}",
        t.name,
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    files.len()
}

/// Replays the target called `name`, which must have at least three inputs.
fn replay_target(name: &str) {
    let t = TARGETS
        .iter()
        .find(|t| t.name == name)
        .expect("a target of this name");
    assert!(replay(t) >= 3, "too few inputs for {}", t.name);
}

#[test]
fn ub2_decode() {
    replay_target("ub2_decode");
}

#[test]
fn ub2_roundtrip() {
    replay_target("ub2_roundtrip");
}

#[test]
fn ub2_stream() {
    replay_target("ub2_stream");
}

#[test]
fn ub2_differential() {
    replay_target("ub2_differential");
}

#[test]
fn sd_decode() {
    replay_target("sd_decode");
}

#[test]
fn sd_roundtrip() {
    replay_target("sd_roundtrip");
}

#[test]
fn sd_stream() {
    replay_target("sd_stream");
}

#[test]
fn sd_differential() {
    replay_target("sd_differential");
}

#[test]
fn spec_loader() {
    replay_target("spec_loader");
}

#[test]
fn modbus_decode() {
    replay_target("modbus_decode");
}

#[test]
fn modbus_stream() {
    replay_target("modbus_stream");
}

#[test]
fn dynamixel_decode() {
    replay_target("dynamixel_decode");
}

#[test]
fn dynamixel_stream() {
    replay_target("dynamixel_stream");
}

#[test]
fn modbus_generated_decode() {
    replay_target("modbus_generated_decode");
}

#[test]
fn modbus_generated_stream() {
    replay_target("modbus_generated_stream");
}

#[test]
fn dynamixel_generated_decode() {
    replay_target("dynamixel_generated_decode");
}

#[test]
fn dynamixel_generated_stream() {
    replay_target("dynamixel_generated_stream");
}

#[test]
fn pelco_d_generated_decode() {
    replay_target("pelco_d_generated_decode");
}

#[test]
fn pelco_d_generated_stream() {
    replay_target("pelco_d_generated_stream");
}

#[test]
fn pelco_p_generated_decode() {
    replay_target("pelco_p_generated_decode");
}

#[test]
fn pelco_p_generated_stream() {
    replay_target("pelco_p_generated_stream");
}

#[test]
fn crsf_generated_decode() {
    replay_target("crsf_generated_decode");
}

#[test]
fn crsf_generated_stream() {
    replay_target("crsf_generated_stream");
}

#[test]
fn dynamixel2_generated_decode() {
    replay_target("dynamixel2_generated_decode");
}

#[test]
fn dynamixel2_generated_stream() {
    replay_target("dynamixel2_generated_stream");
}

#[test]
fn every_target_has_a_replay_test_a_fuzz_target_and_a_nightly_job() {
    let names = [
        "ub2_decode",
        "ub2_roundtrip",
        "ub2_stream",
        "ub2_differential",
        "sd_decode",
        "sd_roundtrip",
        "sd_stream",
        "sd_differential",
        "spec_loader",
        "modbus_decode",
        "modbus_stream",
        "dynamixel_decode",
        "dynamixel_stream",
        "modbus_generated_decode",
        "modbus_generated_stream",
        "dynamixel_generated_decode",
        "dynamixel_generated_stream",
        "pelco_d_generated_decode",
        "pelco_d_generated_stream",
        "pelco_p_generated_decode",
        "pelco_p_generated_stream",
        "crsf_generated_decode",
        "crsf_generated_stream",
        "dynamixel2_generated_decode",
        "dynamixel2_generated_stream",
    ];
    let targets: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
    assert_eq!(targets, names);
    let manifest = std::fs::read_to_string(repo_root().join("fuzz/Cargo.toml")).unwrap();
    let nightly = std::fs::read_to_string(repo_root().join(".github/workflows/fuzz.yml")).unwrap();
    for t in TARGETS {
        let file = repo_root().join(format!("fuzz/fuzz_targets/{}.rs", t.name));
        let body =
            std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        // `<protocol module>::<body>(`, the protocol's name perhaps holding underscores
        // itself (`pelco_d::generated_decode`), or the loader's body alone.
        let calls = t.name.match_indices('_').map(|(i, _)| {
            format!(
                "busspec_fuzz_bodies::{}::{}(",
                &t.name[..i],
                &t.name[i + 1..]
            )
        });
        let call_loader = format!("busspec_fuzz_bodies::{}(", t.name);
        assert!(
            calls.into_iter().any(|c| body.contains(&c)) || body.contains(&call_loader),
            "{} does not call its body",
            file.display()
        );
        assert!(
            manifest.contains(&format!("name = \"{}\"", t.name)),
            "fuzz/Cargo.toml has no [[bin]] {}",
            t.name
        );
        assert!(
            nightly.contains(&format!("          - {}\n", t.name)),
            "the nightly workflow's matrix lacks {}",
            t.name
        );
    }
}

#[test]
fn seed_corpus_and_dictionaries_are_up_to_date() {
    let stale = seeds::stale(&repo_root().join("fuzz"));
    assert!(
        stale.is_empty(),
        "run `cargo run -p busspec-fuzz-bodies --bin make-corpus`:\n{}",
        stale.join("\n")
    );
}

/// The round trip resolves a response only its request identifies through the example
/// requests: each such response must be answered by a command that has one.
#[test]
fn every_reply_that_needs_its_request_has_an_example_request() {
    use busspec_model::ir::Direction;
    for name in busspec_protocols::PROTOCOLS {
        let p = busspec_fuzz_bodies::spec_named(name).expect("a generated protocol");
        for (i, m) in p.messages(Direction::Response).iter().enumerate() {
            if !m.needs_request {
                continue;
            }
            let answered = p.commands.iter().enumerate().any(|(c, cmd)| {
                cmd.responses.iter().any(|(r, _)| *r == i)
                    && busspec_fuzz_bodies::oracle::request_example(p, c).is_some()
            });
            assert!(answered, "{name}: no example request gets {}", m.name);
        }
    }
}

/// The roundtrip bodies over pseudo-random inputs (a fixed xorshift stream, so a failure
/// replays): messages the strict contract refuses (an address outside the device range, the
/// broadcast address for a command that refuses it, a value outside its spec range) come up and
/// are checked both ways, and in-range ones encode and decode back.
#[test]
fn roundtrip_exercises_the_strict_refusals() {
    use busspec_fuzz_bodies::{roundtrip_counts, RoundtripCounts};
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x9E37_79B9_7F4A_7C15)
    };
    for (name, body) in [
        ("ub2", busspec_fuzz_bodies::ub2::roundtrip as fn(&[u8])),
        ("sd", busspec_fuzz_bodies::sd::roundtrip),
    ] {
        let before = roundtrip_counts();
        for _ in 0..300 {
            let data: Vec<u8> = (0..256).map(|_| next() as u8).collect();
            body(&data);
        }
        let after = roundtrip_counts();
        let got = RoundtripCounts {
            encoded: after.encoded - before.encoded,
            refused: after.refused - before.refused,
            refused_on_decode: after.refused_on_decode - before.refused_on_decode,
        };
        println!("{name}: {got:?}");
        assert!(got.encoded >= 100, "{name}: {got:?}");
        assert!(got.refused >= 100, "{name}: {got:?}");
        assert!(got.refused_on_decode >= 50, "{name}: {got:?}");
    }
}

/// libFuzzer refuses a dictionary with an empty entry (a message without a code once made one
/// and stopped every Dynamixel target before it ran).
#[test]
fn no_dictionary_entry_is_empty() {
    for (path, bytes) in seeds::files() {
        if path.starts_with("dict") {
            let text = String::from_utf8(bytes).unwrap();
            for line in text.lines().filter(|l| !l.starts_with('#')) {
                assert!(!line.ends_with("=\"\""), "{}: {line}", path.display());
            }
        }
    }
}
