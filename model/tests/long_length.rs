//! A length field whose width the start byte chooses (`framing.length.long`, VESC's
//! `02 len payload crc16 03` and `03 lenH lenL payload crc16 03`): the interpreter reads
//! pyvesc's frames of both forms, refuses a long form whose length the short one holds, encodes
//! the long form only where the length does not fit the short field, locates a short frame's
//! errors on its own bytes, and its stream decoder frames both forms. Docs and diff say it. The
//! generated code is held to the interpreter on the same fixture in
//! `codegen/tests/snapshots_compile.rs` (`long_length_snapshot_agrees_with_the_interpreter`).

#![cfg(feature = "tools")]

mod common;

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn fixture() -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/vesc.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

/// pyvesc's `SetRPM(-4500)`, short.
const SET_RPM: &str = "02 05 08 FF FF EE 6C 18 7A 03";

fn write(p: &Protocol, n: usize) -> Vec<u8> {
    let values = [
        Value {
            name: "offset".into(),
            raw: Raw::Int(0x1000),
        },
        Value {
            name: "data".into(),
            raw: Raw::List((0..n).map(|i| (i % 256) as i64).collect()),
        },
    ];
    interp::encode(p, p.find("write_new_app_data").unwrap(), 0, &values).unwrap()
}

#[test]
fn both_forms_decode_and_the_layout_is_the_long_forms() {
    let p = fixture();
    let l = p.framing.long.unwrap();
    assert_eq!(
        (l.start, l.short_start, l.short_width, l.width),
        (0x03, 0x02, 1, 2)
    );
    assert_eq!(p.framing.length.as_ref().unwrap().width, 2);
    let f = interp::decode(&p, None, None, &hex(SET_RPM)).unwrap();
    assert_eq!(p.message(f.message).name, "set_rpm");
    assert_eq!(f.get("rpm"), Some(&Raw::Int(-4500)));
    // Every example, pyvesc's frames of both forms, decodes to its message.
    let long = p.examples.iter().filter(|e| e.wire[0] == 0x03).count();
    assert_eq!(long, 2);
    for e in &p.examples {
        let f = interp::decode_as(&p, e.message, &e.wire).unwrap();
        assert_eq!(f.message, e.message);
    }
}

/// What strict decoding accepts encodes back byte for byte: a long form whose length the short
/// field holds is refused at the length field, in busspec's words, whatever else it holds.
#[test]
fn a_long_form_the_short_one_holds_is_refused() {
    let p = fixture();
    let long = hex("03 00 05 08 FF FF EE 6C 18 7A 03");
    let e = interp::decode(&p, None, None, &long).unwrap_err();
    assert_eq!(
        e,
        DecodeError::NeedlessLong {
            offset: 1,
            length: 5,
            most: 255
        }
    );
    assert_eq!(
        e.to_string(),
        "long length field at offset 1 says 5: lengths up to 255 take the short form"
    );
    assert_eq!(
        interp::decode_as(&p, p.find("set_rpm").unwrap(), &long),
        Err(e)
    );
    // 255 in the long form: refused; 256: a long frame.
    let mut at_most = write(&p, 250);
    assert_eq!(at_most[0], 0x02);
    at_most.splice(0..2, [0x03, 0x00, 0xFF]);
    assert!(matches!(
        interp::decode(&p, None, None, &at_most),
        Err(DecodeError::NeedlessLong { length: 255, .. })
    ));
    let over = write(&p, 251);
    assert_eq!(&over[..3], [0x03, 0x01, 0x00]);
    assert!(interp::decode(&p, None, None, &over).is_ok());
}

/// The encoder takes the long form only where the length does not fit one byte: 255 payload
/// bytes short (260 bytes), 256 long (262 bytes), and each decodes to what was given.
#[test]
fn the_encoder_sends_the_long_form_only_where_needed() {
    let p = fixture();
    for (n, start, len) in [
        (0, 0x02, 10),
        (250, 0x02, 260),
        (251, 0x03, 262),
        (512, 0x03, 523),
    ] {
        let w = write(&p, n);
        assert_eq!((w[0], w.len()), (start, len), "{n}");
        let f = interp::decode(&p, Some(Direction::Request), None, &w).unwrap();
        assert_eq!(
            f.get("data")
                .map(|d| matches!(d, Raw::List(l) if l.len() == n)),
            Some(true)
        );
    }
    let r = p.find("set_rpm").unwrap();
    let values = [Value {
        name: "rpm".into(),
        raw: Raw::Int(-4500),
    }];
    assert_eq!(interp::encode(&p, r, 0, &values).unwrap(), hex(SET_RPM));
}

/// A short frame's errors count its own bytes: its checksum at offset 7 (8 laid out), its
/// length as it travelled.
#[test]
fn a_short_frames_errors_are_located_on_its_bytes() {
    let p = fixture();
    let mut bad = hex(SET_RPM);
    bad[7] ^= 1;
    assert!(matches!(
        interp::decode(&p, None, None, &bad),
        Err(DecodeError::ChecksumMismatch { offset: 7, .. })
    ));
    let mut long_by_one = hex("02 06 08 FF FF EE 6C 00 18 7A 03");
    interp::reseal(&p, &mut long_by_one);
    assert_eq!(
        interp::decode(&p, Some(Direction::Request), None, &long_by_one)
            .unwrap_err()
            .to_string(),
        "wrong length for set_rpm: expected 10 bytes, found 11"
    );
    assert_eq!(
        interp::decode(&p, None, None, &hex("02 05 08 FF")),
        Err(DecodeError::Truncated {
            needed: 6,
            found: 4
        })
    );
}

/// The stream decoder frames both forms (the long start byte is a second start byte), skips
/// noise between them, and takes a long form the short one holds for noise.
#[test]
fn the_stream_frames_both_forms() {
    let p = fixture();
    let long = write(&p, 300);
    let mut cap = hex(SET_RPM);
    cap.extend([0x55, 0xAA]);
    cap.extend_from_slice(&long);
    cap.extend(hex("03 00 05 08 FF FF EE 6C 18 7A 03"));
    cap.extend(hex("02 01 04 40 84 03"));
    for chunk in [1, 7, cap.len()] {
        let mut d = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in cap.chunks(chunk) {
            events.extend(d.push(c));
        }
        events.extend(d.flush());
        let seen: Vec<(u64, String)> = events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                Event::Skipped { offset, bytes } => (*offset, format!("skipped {}", bytes.len())),
                other => panic!("{other:?}"),
            })
            .collect();
        let after = 12 + long.len() as u64;
        assert_eq!(
            seen,
            [
                (0, "set_rpm".to_owned()),
                (10, "skipped 2".to_owned()),
                (12, "write_new_app_data".to_owned()),
                (after, "skipped 11".to_owned()),
                (after + 11, "get_values".to_owned()),
            ],
            "chunks of {chunk}"
        );
    }
}

/// Docs show both start bytes and widths; diff classifies a changed long form on its own and
/// compares the length field in the short form's width.
#[test]
fn docs_and_diff_say_it() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "vesc.yaml");
    assert!(
        md.contains("| start | 1 | 0x02, or 0x03 (long form) |"),
        "{md}"
    );
    assert!(
        md.contains("| length | 1 or 2 | bytes of code, payload |"),
        "{md}"
    );
    assert!(md.contains("Long length form: start 0x02 with a 1-byte length, or 0x03 with a 2-byte length for lengths over 255."));
    let (old, new) = common::revisions("vesc", &[("long: {start: 0x03", "long: {start: 0x04")]);
    let changes: Vec<_> = busspec_model::diff::diff(&old, &new)
        .into_iter()
        .filter(|c| c.kind != "example_removed")
        .map(|c| (c.kind, c.path, c.text))
        .collect();
    assert_eq!(
        changes,
        [(
            "long_length_changed",
            "framing.length.long".to_owned(),
            "long length form: start 0x02 with a 1-byte length, or 0x03 with a 2-byte length for lengths over 255 → start 0x02 with a 1-byte length, or 0x04 with a 2-byte length for lengths over 255".to_owned()
        )]
    );
    let (old, new) = common::revisions(
        "vesc",
        &[
            (", long: {start: 0x03, width: 2}", ""),
            ("max: 516}", "max: 255}"),
            ("max: 512}", "max: 250}"),
        ],
    );
    // The long form gone, the longest payloads cut to fit one byte: the short frames travel as
    // they did, so no length field, checksum or frame length changes but the list's.
    let changes: Vec<_> = busspec_model::diff::diff(&old, &new)
        .into_iter()
        .filter(|c| c.kind != "example_removed")
        .map(|c| (c.kind, c.path))
        .collect();
    assert_eq!(
        changes,
        [
            ("long_length_changed", "framing.length.long".to_owned()),
            ("framing_changed", "framing.request.payload".to_owned()),
            (
                "frame_length_changed",
                "commands.write_new_app_data".to_owned()
            ),
            (
                "field_repeat_changed",
                "commands.write_new_app_data.fields.data".to_owned()
            ),
        ]
    );
}
