//! UB2 and SD, the two vendor-document protocols, generated (`snapshots/ub2.rs`,
//! `snapshots/sd.rs`, kept current by `snapshots.rs`): they compile, replay every example, and
//! agree with the interpreter on every example and on frames mutated from them (every example
//! also encodes back to its bytes in both engines, `agree::check`).

include!("snapshots/ub2.rs");
include!("snapshots/sd.rs");

mod agree;

#[test]
fn ub2_snapshot_replays_and_agrees_with_the_interpreter() {
    let p = agree::fixture("spec/ub2.yaml");
    let t = agree::agree::<ub2::Ub2>(&p);
    eprintln!("ub2: {t:?}");
    assert!(t.accepted >= p.examples.len() && t.refused > 1000, "{t:?}");
}

#[test]
fn sd_snapshot_replays_and_agrees_with_the_interpreter() {
    let p = agree::fixture("spec/sd.yaml");
    let t = agree::agree::<sd::Sd>(&p);
    eprintln!("sd: {t:?}");
    assert!(t.accepted >= p.examples.len() && t.refused > 1000, "{t:?}");
}
