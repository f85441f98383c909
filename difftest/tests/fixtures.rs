//! Every spec in `difftest/fixtures/` (a disagreement once found, minimised where easy), its
//! generated code held to the interpreter by the same comparison the random specs get: one
//! `#[test]` per fixture, named after its protocol (`pelco_d2` for `pelco_d_codeless.yaml`).

use busspec_difftest::compare::{compare, quiet_panics, Budget};

include!(concat!(env!("OUT_DIR"), "/protocols.rs"));
include!(concat!(env!("OUT_DIR"), "/fixture_tests.rs"));

/// The comparison on protocol `P` (with `seed`, the one a found spec was compared with):
/// no disagreement.
fn check<P: busspec_runtime::Protocol>(seed: u64) {
    quiet_panics();
    let r = compare::<P>(seed, Budget::default());
    let _ = std::panic::take_hook();
    let mut shown = String::new();
    for d in &r.found {
        shown.push_str(&format!(
            "\n{}\n  how:         {}\n  input:       {}\n  generated:   {}\n  interpreter: {}",
            d.signature, d.how, d.input, d.generated, d.interpreter
        ));
    }
    assert!(r.frames > 0, "{}: nothing compared", P::NAME);
    assert_eq!(
        r.disagreements,
        0,
        "{}: {} disagreements ({} frames, {} encodes, {} captures compared); the first of each kind:{shown}",
        P::NAME,
        r.disagreements,
        r.frames,
        r.encodes,
        r.captures
    );
}
