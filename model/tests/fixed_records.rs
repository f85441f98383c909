//! Records of a fixed count (`type: record`, `repeat: {count: 3}`, fixture `ubx_fixed_blocks`)
//! and lists of floats and 64-bit integers counted by a field (fixture `float_lists`): the
//! interpreter, the stream decoder, docs and diff take them (generated code is held to the
//! interpreter in `codegen/tests/snapshots_compile.rs`).

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::diff::{self, Category};
use busspec_model::interp::{self, Raw};
use busspec_model::ir::{Count, Direction};
use busspec_model::Protocol;

fn text(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/valid")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

fn load(name: &str, t: &str) -> Protocol {
    busspec_model::load_str(name, t).unwrap_or_else(|d| panic!("{d}"))
}

/// The spec without its examples (edited specs need not replay them).
fn head(name: &str) -> String {
    let t = text(name);
    format!("{}\nexamples: []\n", &t[..t.find("\nexamples:").unwrap()])
}

#[test]
fn a_fixed_count_of_records_is_exactly_that_many_and_no_count_field() {
    let p = load("ubx", &text("ubx_fixed_blocks.yaml"));
    let m = p.responses.iter().find(|m| m.name == "sat_blocks").unwrap();
    let (f, r) = m.repeat().unwrap();
    assert_eq!(f.name, "blocks");
    assert_eq!((r.count, r.min, r.max), (Count::Fixed(3), 3, 3));
    assert_eq!(m.min_len(), m.max_len);
    let d = interp::decode(&p, Some(Direction::Response), None, &p.examples[1].wire).unwrap();
    match &d.values.iter().find(|v| v.name == "blocks").unwrap().raw {
        Raw::Records(r) => assert_eq!(r.len(), 3),
        other => panic!("{other:?}"),
    }
}

#[test]
fn another_number_of_records_is_refused_both_ways() {
    let p = load("ubx", &text("ubx_fixed_blocks.yaml"));
    let e = &p.examples[1];
    // Two records (the length field and checksum made to agree); four make a frame longer
    // than any of the message's, as for any list.
    let mut short = e.wire.clone();
    short.drain(16..22);
    short[4] -= 6;
    let n = short.len();
    interp::reseal(&p, &mut short[..n]);
    let err = interp::decode(&p, Some(Direction::Response), None, &short).unwrap_err();
    assert_eq!(
        err.to_string(),
        "sat_blocks.blocks at offset 10: 3 elements, expected 2 by the frame's length"
    );
    let d = interp::decode(&p, Some(Direction::Response), None, &e.wire).unwrap();
    let mut values = d.values.clone();
    for v in &mut values {
        if let Raw::Records(r) = &mut v.raw {
            r.pop();
        }
    }
    let err = interp::encode(&p, e.message, 0, &values).unwrap_err();
    assert_eq!(err.to_string(), "blocks takes 3..=3 elements, got 2");
}

/// Without a length field, a stream frames records of a fixed count by their count alone.
#[test]
fn a_stream_frames_fixed_records_by_their_count() {
    let p = load("ubx", &text("ubx_fixed_blocks.yaml"));
    let bare = head("ubx_fixed_blocks.yaml")
        .replace(
            "layout: [start, code, length, payload, checksum]",
            "layout: [start, code, payload, checksum]",
        )
        .replace("  length: {width: 2, counts: [payload]}\n", "");
    let q = load("bare", &bare);
    let mut bytes = Vec::new();
    for e in &p.examples {
        let d = interp::decode(&p, Some(e.message.direction), None, &e.wire).unwrap();
        // The same messages in the same order: the same references.
        bytes.extend(interp::encode(&q, e.message, 0, &d.values).unwrap());
    }
    let mut s = busspec_model::stream::StreamDecoder::new(&q, None);
    let mut names = Vec::new();
    // One byte at a time: the frame's length is known before its records arrive.
    for b in &bytes {
        for ev in s.push(std::slice::from_ref(b)) {
            match ev {
                busspec_model::stream::Event::Frame { frame, .. } => {
                    names.push(q.message(frame.message).name.clone())
                }
                other => panic!("{other:?}"),
            }
        }
    }
    assert_eq!(names, ["poll_sat_blocks", "sat_blocks", "set_ports", "ack"]);
}

#[test]
fn docs_show_records_of_a_fixed_count_as_an_array() {
    let p = load("ubx", &text("ubx_fixed_blocks.yaml"));
    let md = busspec_model::docs::render(&p, "ubx_fixed_blocks.yaml");
    // A record of 6 bytes, three of them (as `f32[4]` is four floats).
    assert!(md.contains("record[6][3]"), "{md}");
    assert!(
        md.contains("3 elements, always, no field counts them"),
        "{md}"
    );
    let p = load("floats", &text("float_lists.yaml"));
    let md = busspec_model::docs::render(&p, "float_lists.yaml");
    assert!(md.contains("f32[0..=8]"), "{md}");
}

#[test]
fn a_changed_count_of_records_is_wire_breaking() {
    let t = head("ubx_fixed_blocks.yaml");
    let old = load("old", &t);
    let new = load(
        "new",
        &t.replace("repeat: {count: 3}", "repeat: {count: 4}")
            .replace("max: 32}}", "max: 40}}"),
    );
    let found = diff::diff(&old, &new);
    let c = found
        .iter()
        .find(|c| c.path == "responses.sat_blocks.fields.blocks")
        .unwrap_or_else(|| panic!("{found:?}"));
    assert_eq!(c.category, Category::WireBreaking);
    assert!(
        c.text
            .contains("a fixed count of 3, 3..=3 elements → a fixed count of 4, 4..=4 elements"),
        "{}",
        c.text
    );
}

#[test]
fn refusals_of_records_of_a_fixed_count_are_located() {
    let t = head("ubx_fixed_blocks.yaml");
    for (edit, path, why) in [
        (
            "repeat: {count: 3, of: bytes}",
            "responses.sat_blocks.fields.blocks.repeat.of",
            "`of` says what a count field counts; a fixed count is of elements",
        ),
        (
            "repeat: {count: 0}",
            "responses.sat_blocks.fields.blocks.repeat.count",
            "a fixed count is 1..=256 elements, not 0",
        ),
        (
            "repeat: {count: 3, max: 4}",
            "responses.sat_blocks.fields.blocks.repeat.max",
            "a list of a fixed count of 3 holds 3 elements; `max: 4` says otherwise (leave it out)",
        ),
    ] {
        let d = busspec_model::load_str("x", &t.replace("repeat: {count: 3}", edit)).unwrap_err();
        let s = d.to_string();
        assert!(s.contains(path) && s.contains(why), "{edit}: {s}");
    }
}

#[test]
fn float_and_wide_elements_read_as_their_type_both_ways() {
    let p = load("floats", &text("float_lists.yaml"));
    for e in &p.examples {
        let d = interp::decode(&p, Some(e.message.direction), None, &e.wire).unwrap();
        let back = interp::encode(&p, e.message, d.address, &d.values).unwrap();
        assert_eq!(back, e.wire);
    }
    let d = interp::decode(&p, Some(Direction::Response), None, &p.examples[1].wire).unwrap();
    match &d.values.iter().find(|v| v.name == "values").unwrap().raw {
        Raw::List(l) => {
            let got: Vec<f32> = l.iter().map(|&r| f32::from_bits(r as u32)).collect();
            assert_eq!(got, [230.1f32, -0.5, 49.98]);
        }
        other => panic!("{other:?}"),
    }
    // A float past its range refused by encode, named with the number.
    let mut values = d.values.clone();
    for v in &mut values {
        if let Raw::List(l) = &mut v.raw {
            l[0] = i64::from(1500.0f32.to_bits());
        }
    }
    let err = interp::encode(&p, p.examples[1].message, 1, &values).unwrap_err();
    assert_eq!(
        err.to_string(),
        "values = 1500.0 is outside its range -1000.0..=1000.0"
    );
}
