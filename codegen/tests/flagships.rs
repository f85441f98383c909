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

/// A unit's newtype shows its physical value beside the raw one, and converts without
/// identity arithmetic (`value` and `from_value` agree with the unit's scale and offset).
#[test]
fn units_debug_print_the_physical_value_beside_the_raw_one() {
    assert_eq!(
        format!("{:?}", ub2::Capacitance(15000)),
        "Capacitance(15000 = 150 pF)"
    );
    assert_eq!(
        format!("{:?}", sd::Temperature(0)),
        "Temperature(0 = -50 °C)"
    );
    assert_eq!(ub2::Capacitance(15000).value(), 150.0);
    assert_eq!(
        ub2::Capacitance::from_value(150.0),
        Some(ub2::Capacitance(15000))
    );
    assert_eq!(sd::Temperature(75).value(), 25.0);
    assert_eq!(sd::Temperature::from_value(25.0), Some(sd::Temperature(75)));
}

/// An ASCII field is `rt::Ascii<N>`: its bytes as the frame holds them, shown as text in a
/// message's `Debug`, read as text by `as_str`, and written back as they were.
#[test]
fn ascii_fields_show_their_text() {
    let r = ub2::Response::FirmwareVersion(ub2::response::FirmwareVersion {
        firmware_version: busspec_runtime::Ascii(*b"20100433.00"),
    });
    assert_eq!(
        format!("{r:?}"),
        r#"FirmwareVersion(FirmwareVersion { firmware_version: "20100433.00" })"#
    );
    let mut buf = [0u8; 16];
    let n = r.encode(0x21, &mut buf).unwrap();
    let back = ub2::Response::decode(&buf[..n]).unwrap();
    let ub2::Response::FirmwareVersion(ub2::response::FirmwareVersion { firmware_version }) =
        back.message
    else {
        panic!("{back:?}");
    };
    assert_eq!(firmware_version.as_str(), Some("20100433.00"));
    assert_eq!(firmware_version, *b"20100433.00");
}
