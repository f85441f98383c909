//! The soak at CI size: bounded (a few thousand simulated transactions, no real waiting).
//! `BUSSPEC_SOAK=N` runs N transactions per protocol instead (the README's figures use 100,000
//! with `cargo run --release -- soak`).

use busspec_devices::{Sd, Ub2};
use busspec_link::soak::{run, SoakConfig};

fn size() -> u64 {
    std::env::var("BUSSPEC_SOAK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5_000)
}

fn config(seed: u64) -> SoakConfig {
    SoakConfig {
        transactions: size(),
        byte_error_rate: 0.01,
        seed,
        devices: 2,
    }
}

#[test]
fn sd_soak_accepts_no_wrong_value() {
    let r = run::<Sd>(config(1));
    println!("{r}\n{:#?}", r.examples);
    assert_eq!(r.silent_wrong, 0, "{r}\n{:#?}", r.examples);
    assert_eq!(
        r.completed + r.retried + r.failed + r.not_sent + r.refused + r.unseen + r.silent_wrong,
        r.transactions
    );
    // Faults were really injected, and retries really rescued transactions.
    assert!(
        r.faults.corrupted > 0 && r.faults.silenced > 0 && r.faults.delayed > 0,
        "{r}"
    );
    assert!(r.retried > 0, "{r}");
    assert!(r.completed > r.transactions * 8 / 10, "{r}");
}

#[test]
fn ub2_soak_full_checks_accept_fewer_wrong_values_than_the_checksum_alone() {
    let r = run::<Ub2>(config(2));
    println!("{r}\n{:#?}", r.examples);
    assert_eq!(
        r.completed + r.retried + r.failed + r.not_sent + r.refused + r.unseen + r.silent_wrong,
        r.transactions
    );
    assert!(r.retried > 0, "{r}");
    assert!(r.completed > r.transactions * 8 / 10, "{r}");
    // The mix sends some values the spec forbids, as a careless caller would: busspec keeps
    // them off the bus.
    assert!(r.not_sent > 0, "{r}");
    assert!(
        r.silent_wrong < r.checksum_only_silent_wrong,
        "full checks let through more than the checksum alone: {r}"
    );
}
