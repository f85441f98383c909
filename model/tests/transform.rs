//! A per-byte transform of the payload (`framing.transform`, DL/T 645's +33H on every data
//! byte): the interpreter reads go645's frames to the real values (data identifier 00 01 00 00
//! as 0x00010000), the checksum over the bytes as they travel; its encoder writes the fields,
//! transforms the payload (never the header, code or length) and then sums; `xor` works alike;
//! its stream decoder compares the constants that lead a variable message's payload as they
//! travel. The generated code is held to the interpreter on the same fixture in
//! `codegen/tests/snapshots_compile.rs` (`transform_snapshot_agrees_with_the_interpreter`).

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::{Direction, TransformKind};
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn text() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/dlt645.yaml");
    std::fs::read_to_string(path).unwrap()
}

fn fixture() -> Protocol {
    busspec_model::load_str("dlt645.yaml", &text()).unwrap_or_else(|d| panic!("{d}"))
}

/// The fixture with each `(from, to)` edit made and its examples dropped.
fn edited(edits: &[(&str, &str)]) -> Protocol {
    let mut t = text();
    for (from, to) in edits {
        assert!(t.contains(from), "no `{from}`");
        t = t.replace(from, to);
    }
    let head = &t[..t.find("examples:").unwrap()];
    busspec_model::load_str("dlt645.yaml", &format!("{head}examples: []\nerrata: []\n"))
        .unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn int(f: &interp::Frame, name: &str) -> i64 {
    match f.get(name) {
        Some(Raw::Int(v)) => *v,
        other => panic!("{name}: {other:?}"),
    }
}

fn values(pairs: &[(&'static str, i64)]) -> Vec<Value<'static>> {
    pairs
        .iter()
        .map(|(n, v)| Value {
            name: (*n).into(),
            raw: Raw::Int(*v),
        })
        .collect()
}

/// Read data identifier 00 01 00 00 from meter 000000000001, and the meter's reply.
const READ_DATA: &str = "68 01 00 00 00 00 00 68 11 04 33 33 34 33 B3 16";
const DATA_REPLY: &str = "68 01 00 00 00 00 00 68 91 08 33 33 34 33 59 B3 55 44 DC 16";

#[test]
fn the_transform_is_in_the_ir_and_the_examples_hold_the_real_values() {
    let p = fixture();
    let t = p.framing.transform.as_ref().expect("a transform");
    assert_eq!(t.kind, TransformKind::Add(0x33));
    assert_eq!(
        t.describe(),
        "every payload byte travels plus 0x33 (mod 256)"
    );
    // The payload of a 16-byte frame: after 68 A0..A5 68 C L, before CS 16.
    assert_eq!(p.framing.transformed(16), 10..14);
    let f = interp::decode(&p, None, None, &hex(READ_DATA)).unwrap();
    assert_eq!(int(&f, "data_id"), 0x0001_0000);
    // The header (the address) travels as it is.
    assert_eq!(int(&f, "address_low"), 1);
    let f = interp::decode(&p, Some(Direction::Response), Some(1), &hex(DATA_REPLY)).unwrap();
    assert_eq!(int(&f, "data_id"), 0x0001_0000);
    assert_eq!(int(&f, "value"), 11_228_026);
    // The meter number reply's constant data identifier 04000402, sent 35 37 33 37.
    let m = p.find("meter_number_reply").unwrap();
    let c = p.message(m).fields.iter().find(|f| f.name == "data_id");
    assert_eq!(c.and_then(|f| f.constant), Some(0x0400_0402));
}

#[test]
fn encode_transforms_the_payload_then_sums_the_bytes_as_they_travel() {
    let p = fixture();
    let r = p.find("read_data").unwrap();
    let v = values(&[
        ("address_low", 1),
        ("address_high", 0),
        ("data_id", 0x0001_0000),
    ]);
    let wire = interp::encode(&p, r, 0, &v).unwrap();
    assert_eq!(wire, [vec![0xFE; 4], hex(READ_DATA)].concat());
    let r = p.find("data_reply").unwrap();
    let v = values(&[
        ("address_low", 1),
        ("address_high", 0),
        ("data_id", 0x0001_0000),
        ("value", 11_228_026),
    ]);
    assert_eq!(
        interp::encode(&p, r, 0, &v).unwrap(),
        [vec![0xFE; 4], hex(DATA_REPLY)].concat()
    );
}

#[test]
fn decode_checks_the_sum_over_the_bytes_as_they_travel_and_reads_them_transformed_back() {
    let p = fixture();
    // The data sent untransformed, the sum over it: the sum checks, the fields read otherwise
    // (00 00 01 00 less 33H each), and the data identifier is no meter number's constant.
    let mut plain = hex(READ_DATA);
    plain[10..14].copy_from_slice(&[0x00, 0x00, 0x01, 0x00]);
    interp::reseal(&p, &mut plain);
    let f = interp::decode(&p, None, None, &plain).unwrap();
    assert_eq!(int(&f, "data_id"), 0xCDCE_CDCD_u32 as i64);
    // A data byte changed and the sum left: refused at the checksum, over the wire bytes.
    let mut bad = hex(READ_DATA);
    bad[12] ^= 1;
    assert!(matches!(
        interp::decode(&p, None, None, &bad),
        Err(DecodeError::ChecksumMismatch { offset: 14, .. })
    ));
    // A value's digit undone above 9 is refused at the field, at its offset in the frame.
    let mut not_bcd = hex(DATA_REPLY);
    not_bcd[14] = 0x33 + 0x0A;
    interp::reseal(&p, &mut not_bcd);
    let e = interp::decode(&p, Some(Direction::Response), Some(1), &not_bcd).unwrap_err();
    assert!(e.to_string().contains("value"), "{e}");
    assert!(e.to_string().contains("14"), "{e}");
}

#[test]
fn xor_transforms_alike() {
    let p = edited(&[("add: 0x33", "xor: 0x55")]);
    assert_eq!(
        p.framing.transform.as_ref().map(|t| t.kind),
        Some(TransformKind::Xor(0x55))
    );
    let r = p.find("read_data").unwrap();
    let v = values(&[
        ("address_low", 1),
        ("address_high", 0),
        ("data_id", 0x0001_0000),
    ]);
    let wire = interp::encode(&p, r, 0, &v).unwrap();
    assert_eq!(&wire[4 + 10..4 + 14], [0x55, 0x55, 0x54, 0x55]);
    let f = interp::decode(&p, None, None, &wire).unwrap();
    assert_eq!(int(&f, "data_id"), 0x0001_0000);
}

/// A variable-length reply told apart in a stream by the constant leading its payload: the
/// stream decoder compares it as it travels (+33H), so its frames are found, and decode as the
/// one-frame decoder decodes them.
#[test]
fn a_stream_compares_leading_constants_as_they_travel() {
    let p = edited(&[
        ("payload: {min: 6, max: 10}", "payload: {min: 5, max: 10}"),
        (
            "responses: [data_reply, meter_number_reply]",
            "responses: [data_reply, meter_number_reply, block_reply]",
        ),
        (
            "responses:\n",
            "responses:\n  - name: block_reply\n    title: \"A block\"\n    section: \"7.2\"\n    kind: data\n    code: \"0xB1\"\n    fields:\n      - {name: data_id, type: u32, value: 0x0001FF00}\n      - {name: values, type: u8, unit: count, repeat: {count: end, min: 1, max: 6}}\n",
        ),
    ]);
    let r = p.find("block_reply").unwrap();
    let mut capture = Vec::new();
    let mut frames = Vec::new();
    for n in 1..=6i64 {
        let mut v = values(&[("address_low", 1), ("address_high", 0)]);
        v.push(Value {
            name: "values".into(),
            raw: Raw::List((0..n).collect()),
        });
        let wire = interp::encode(&p, r, 0, &v).unwrap();
        // Its data identifier as it travels.
        assert_eq!(&wire[4 + 10..4 + 14], [0x33, 0x32, 0x34, 0x33]);
        capture.extend_from_slice(&wire);
        capture.push(0x00);
        frames.push(wire);
    }
    let mut d = StreamDecoder::new(&p, Some(Direction::Response));
    let mut events = d.push(&capture);
    events.extend(d.flush());
    let found: Vec<Vec<u8>> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame { bytes, frame, .. } => {
                assert_eq!(p.message(frame.message).name, "block_reply");
                Some(bytes.clone())
            }
            _ => None,
        })
        .collect();
    assert_eq!(found, frames);
}

#[test]
fn docs_state_the_transform_under_the_frame_layout() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "dlt645.yaml");
    let at = md.find("Transform (§5.3): every payload byte travels plus 0x33 (mod 256)");
    let pre = md.find("Preamble (§5.1)");
    assert!(at.is_some() && pre.is_some(), "{md}");
    assert!(at > pre);
}
