//! Lists of a fixed count (`repeat: {count: 3}`, fixture `packed_channels`'s `calibrate`): whole
//! elements in the protocol's byte order, with no count field. They are packed elements of their
//! type's width in the IR, so both engines, the streams, the dissector and the generated code
//! take them as such (generated code is held to the interpreter in
//! `codegen/tests/snapshots_compile.rs`); here, what they mean in either byte order.

#![cfg(feature = "tools")]

use std::borrow::Cow;
use std::path::Path;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::Protocol;

fn text() -> String {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/packed_channels.yaml");
    std::fs::read_to_string(path).unwrap()
}

/// The fixture as it is (big-endian), or little-endian without its (big-endian) examples.
fn fixture(little: bool) -> Protocol {
    let mut t = text();
    if little {
        let at = t.find("\nexamples:").unwrap();
        t.truncate(at);
        t = t.replace("byte_order: big", "byte_order: little");
        t.push_str("\nexamples: []\n");
    }
    busspec_model::load_str("packed_channels.yaml", &t).unwrap_or_else(|d| panic!("{d}"))
}

fn crc8(data: &[u8]) -> u8 {
    let mut c = 0u8;
    for &b in data {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0xD5
            } else {
                c << 1
            };
        }
    }
    c
}

fn frame(body: &[u8]) -> Vec<u8> {
    let mut f = vec![0xC8, body.len() as u8 + 1];
    f.extend_from_slice(body);
    f.push(crc8(body));
    f
}

fn lists(p: &Protocol, wire: &[u8]) -> (Raw, Raw) {
    let d = interp::decode(p, Some(Direction::Request), None, wire).unwrap();
    let get = |n: &str| d.values.iter().find(|v| v.name == n).unwrap().raw.clone();
    (get("offsets"), get("gains"))
}

#[test]
fn a_fixed_count_is_whole_elements_and_no_count_field() {
    let p = fixture(false);
    let m = p.message(p.find("calibrate").unwrap());
    let f = m.fields.iter().find(|f| f.name == "offsets").unwrap();
    let pk = f.packed.as_ref().unwrap();
    assert!(pk.whole() && f.repeat.is_none());
    assert_eq!((pk.count, f.width, m.fields.len()), (3, 6, 2));
    assert!(p.generator_gaps().is_empty());
}

#[test]
fn elements_follow_the_protocols_byte_order_both_ways() {
    let body = [0x19, 0x00, 0x01, 0x02, 0x03, 0xFF, 0xFF, 0x07, 0x09];
    for (little, offsets) in [
        (false, vec![1, 0x0203, 0xFFFF]),
        (true, vec![0x0100, 0x0302, 0xFFFF]),
    ] {
        let p = fixture(little);
        let wire = frame(&body);
        assert_eq!(
            lists(&p, &wire),
            (Raw::List(offsets.clone()), Raw::List(vec![7, 9]))
        );
        let values = [
            Value {
                name: Cow::Borrowed("offsets"),
                raw: Raw::List(offsets),
            },
            Value {
                name: Cow::Borrowed("gains"),
                raw: Raw::List(vec![7, 9]),
            },
        ];
        let back = interp::encode(&p, p.find("calibrate").unwrap(), 0, &values).unwrap();
        assert_eq!(back, wire, "little-endian: {little}");
    }
}

#[test]
fn another_number_of_elements_or_one_out_of_range_is_refused() {
    let p = fixture(false);
    let r = p.find("calibrate").unwrap();
    let two = [
        Value {
            name: Cow::Borrowed("offsets"),
            raw: Raw::List(vec![1, 2]),
        },
        Value {
            name: Cow::Borrowed("gains"),
            raw: Raw::List(vec![7, 9]),
        },
    ];
    let e = interp::encode(&p, r, 0, &two).unwrap_err().to_string();
    assert!(e.contains("offsets") && e.contains("3..=3"), "{e}");
    // A gain of 0 is below the range 1..=9 every element takes.
    let wire = frame(&[0x19, 0x00, 0x01, 0x02, 0x03, 0xFF, 0xFF, 0x00, 0x09]);
    let e = interp::decode(&p, Some(Direction::Request), None, &wire)
        .unwrap_err()
        .to_string();
    assert!(e.contains("gains"), "{e}");
}
