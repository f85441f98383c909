//! A 1-bit sub-field of no scaled unit and no narrower range is a `bool` in generated code
//! (Pelco P's pan, tilt, zoom, focus and iris bits): decoded from its bit, encoded into it, lent
//! by `visit` as 0 or 1, and taken back by `from_fields` from 0 or 1 only. The module is the
//! code generated for the Pelco P fixture (`codegen/tests/snapshots/pelco_p.rs`, which
//! `busspec-codegen`'s snapshot test keeps current).

include!("../../codegen/tests/snapshots/pelco_p.rs");

use busspec_runtime::FieldValue;

/// The fixture's example: camera 1 pans left at speed 0x20 (only `pan_left` set).
const PAN_LEFT: [u8; 8] = [0xA0, 0x00, 0x00, 0x04, 0x20, 0x00, 0xAF, 0x2B];

#[test]
fn one_bit_fields_decode_and_encode_as_bools() {
    let d = pelco_p::Request::decode(&PAN_LEFT).unwrap();
    let pelco_p::Request::Ptz(pelco_p::request::Ptz {
        pan_left,
        pan_right,
        camera_on,
        pan_speed,
        ..
    }) = d.message
    else {
        panic!("decoded as {:?}", d.message);
    };
    assert!(pan_left && !pan_right && !camera_on);
    assert_eq!(pan_speed, 0x20);
    let mut buf = [0u8; pelco_p::MAX_FRAME_LEN];
    let n = d.message.encode(0x00, &mut buf).unwrap();
    assert_eq!(buf[..n], PAN_LEFT);
    // Every bit set: the top bit (`camera_on`, bit 14 of the command word) as well.
    let all = pelco_p::Request::Ptz(pelco_p::request::Ptz {
        camera_on: true,
        auto_scan: true,
        camera_on_off: true,
        iris_close: true,
        iris_open: true,
        focus_near: true,
        focus_far: true,
        zoom_wide: true,
        zoom_tele: true,
        tilt_down: true,
        tilt_up: true,
        pan_left: true,
        pan_right: true,
        pan_speed: 0,
        tilt_speed: 0,
    });
    let n = all.encode(0x00, &mut buf).unwrap();
    // The fixed zero bits (15 and 7) and bit 0 stay clear.
    assert_eq!(buf[2..4], [0x7F, 0x7E]);
    assert_eq!(pelco_p::Request::decode(&buf[..n]).unwrap().message, all);
}

#[test]
fn visit_lends_a_bool_as_0_or_1_and_from_fields_takes_only_those() {
    let d = pelco_p::Request::decode(&PAN_LEFT).unwrap();
    let mut seen = Vec::new();
    d.message.visit(|name, v| {
        if let FieldValue::Int(i) = v {
            seen.push((name, i));
        }
    });
    assert!(seen.contains(&("pan_left", 1)) && seen.contains(&("pan_right", 0)));
    let back = pelco_p::Request::from_fields("ptz", |name| {
        seen.iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, i)| FieldValue::Int(i))
    })
    .unwrap();
    assert_eq!(back, d.message);
    let two = pelco_p::Request::from_fields("ptz", |name| {
        let i = if name == "zoom_tele" { 2 } else { 0 };
        Some(FieldValue::Int(i))
    });
    assert!(two.is_err(), "zoom_tele = 2 taken as {two:?}");
}
