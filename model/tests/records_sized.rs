//! Records whose width a field gives (`bytes:` on a record's last field, Dynamixel 2.0's
//! SYNC_WRITE): `fixtures/valid/records_sized.yaml` through the interpreter, its stream
//! decoder, lenient decoding and encode.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError, EncodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::{load_file, Protocol};

fn spec() -> Protocol {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/records_sized.yaml");
    load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn cmd(p: &Protocol, name: &str) -> MessageRef {
    p.find_in(name, Direction::Request).unwrap()
}

fn v(name: &str, raw: Raw) -> Value<'_> {
    Value {
        name: name.into(),
        raw,
    }
}

#[test]
fn the_width_field_resolves_and_bounds_the_frames() {
    let p = spec();
    let m = p.message(cmd(&p, "sync_write"));
    let f = &m.fields[2];
    assert_eq!(f.record_bytes_from(), Some(1));
    // At its widest (a u32) and narrowest (one byte) the record takes 5 and 2 bytes.
    assert_eq!(f.width, 5);
    assert_eq!(f.min_element_width(), 2);
    assert_eq!(m.min_len(), m.layout.len + 2);
}

#[test]
fn records_decode_at_the_width_the_frame_gives() {
    let p = spec();
    // Wire order: little-endian.
    let wire = hex("C5 01 0F 83 7400 0400 01 78563412 02 00040000 26");
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(
        f.get("blocks"),
        Some(&Raw::Records(vec![vec![1, 0x1234_5678], vec![2, 1024]]))
    );
    let wire = hex("C5 01 0B 83 4000 0100 01 01 02 00 03 FF D6");
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(
        f.get("blocks"),
        Some(&Raw::Records(vec![vec![1, 1], vec![2, 0], vec![3, 255]]))
    );
    // A signed last field is sign-extended from the bytes it has.
    let wire = hex("C5 01 06 84 01 01 80 02 7F 8E");
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(
        f.get("offsets"),
        Some(&Raw::Records(vec![vec![1, -128], vec![2, 127]]))
    );
}

#[test]
fn a_width_outside_one_to_the_type_is_refused_at_the_width_field() {
    let p = spec();
    // data_length 0 and 5 (a u32 takes at most four bytes).
    for (len, sum) in [(0u8, 0u8), (5, 0)] {
        let mut wire = hex("C5 01 07 83 4000 0000 01 01 00");
        wire[6] = len;
        let s = wire[1..wire.len() - 1]
            .iter()
            .fold(sum, |a, b| a.wrapping_add(*b));
        let n = wire.len();
        wire[n - 1] = s;
        let e = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap_err();
        assert!(
            matches!(&e, DecodeError::BadWidth { field, offset: 6, most: 4, .. } if field == "data_length"),
            "{e}"
        );
        assert_eq!(
            e.to_string(),
            format!("sync_write.data_length at offset 6 is {len}: each record's last field takes 1..=4 bytes")
        );
    }
    // Three bytes of records at a width of two: no whole record.
    let wire = hex("C5 01 05 84 02 07 7C FC 0B");
    assert!(interp::decode(&p, Some(Direction::Request), None, &wire).is_ok());
    let mut bad = hex("C5 01 06 84 02 07 7C FC 00 00");
    let n = bad.len();
    bad[n - 1] = bad[1..n - 1].iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let e = interp::decode(&p, Some(Direction::Request), None, &bad).unwrap_err();
    assert!(e.to_string().contains("whole 3-byte elements"), "{e}");
}

#[test]
fn a_last_field_out_of_its_range_is_refused_where_it_sits() {
    let p = spec();
    // offset -1000 (0xFC18) in two bytes: outside -900..=900, at the second record byte.
    let mut wire = hex("C5 01 05 84 02 07 18 FC 00");
    let n = wire.len();
    wire[n - 1] = wire[1..n - 1].iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let e = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap_err();
    assert_eq!(
        e.to_string(),
        "trim.offsets.offset at offset 6 is -1000, outside its range -900..=900"
    );
}

#[test]
fn encode_writes_each_record_at_the_width_given_and_refuses_what_does_not_fit() {
    let p = spec();
    let m = cmd(&p, "sync_write");
    let values = |len: i64, data: i64| {
        vec![
            v("start_address", Raw::Int(64)),
            v("data_length", Raw::Int(len)),
            v(
                "blocks",
                Raw::Records(vec![vec![1, data], vec![2, 0], vec![3, 255]]),
            ),
        ]
    };
    let wire = interp::encode(&p, m, 1, &values(1, 1)).unwrap();
    assert_eq!(wire, hex("C5 01 0B 83 4000 0100 01 01 02 00 03 FF D6"));
    // 256 does not fit one byte.
    let e = interp::encode(&p, m, 1, &values(1, 256)).unwrap_err();
    assert!(
        matches!(&e, EncodeError::OutOfRange { field, min: 0, max: 255, .. } if field == "blocks.data"),
        "{e}"
    );
    // A width the type cannot take.
    let e = interp::encode(&p, m, 1, &values(5, 1)).unwrap_err();
    assert!(
        matches!(&e, EncodeError::NotInRange { field, min: 1, max: 4, .. } if field == "data_length"),
        "{e}"
    );
    let e = interp::encode(&p, m, 1, &values(0, 1)).unwrap_err();
    assert!(matches!(&e, EncodeError::NotInRange { .. }), "{e}");
}

#[test]
fn a_stream_frames_them_by_the_length_field_between_noise() {
    let p = spec();
    let frames = [
        hex("C5 01 0F 83 7400 0400 01 78563412 02 00040000 26"),
        hex("C5 01 06 84 01 01 80 02 7F 8E"),
    ];
    let mut bytes = vec![0x00, 0xC5, 0x13];
    for f in &frames {
        bytes.extend_from_slice(f);
        bytes.push(0x42);
    }
    let mut d = busspec_model::stream::StreamDecoder::new(&p, Some(Direction::Request));
    let mut got = Vec::new();
    let mut events = d.push(&bytes);
    events.extend(d.flush());
    for ev in events {
        if let busspec_model::stream::Event::Frame { frame, .. } = ev {
            got.push(p.message(frame.message).name.clone());
        }
    }
    assert_eq!(got, ["sync_write", "trim"]);
}

#[test]
fn docs_show_the_width_field_and_the_records_widths() {
    let p = spec();
    let d = busspec_model::docs::render(&p, "records_sized.yaml");
    assert!(d.contains("record[2..=5]"), "{d}");
    assert!(d.contains("takes `data_length` bytes (1 to 4)"), "{d}");
}

#[test]
fn diff_says_a_width_from_another_field_breaks_the_wire() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/records_sized.yaml"),
    )
    .unwrap();
    let old = spec();
    assert!(busspec_model::diff::diff(&old, &old).is_empty());
    // The trim offsets at their type's width: the examples go, their widths change.
    let fixed = text.replace(", bytes: width}", "}");
    let fixed = &fixed[..fixed.find("examples:").unwrap()];
    let new = busspec_model::load_str(
        "records_sized.yaml",
        &format!("{fixed}examples: []\nerrata: []\n"),
    )
    .unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    assert!(
        changes
            .iter()
            .any(|c| c.kind == "record_field_width_changed"
                && c.category == busspec_model::diff::Category::WireBreaking
                && c.path.ends_with("offsets.fields.offset.bytes")),
        "{changes:#?}"
    );
}
