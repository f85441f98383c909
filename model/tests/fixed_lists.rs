//! Lists of a fixed count (`repeat: {count: 3}`, fixture `packed_channels`'s `calibrate` and
//! `trim`): whole elements in the protocol's byte order (signed, 24- and 64-bit, float, enum
//! ones too), with no count field. They are packed elements of their type's width in the IR, so
//! both engines, the streams, the dissector and the generated code take them as such (generated
//! code is held to the interpreter in `codegen/tests/snapshots_compile.rs`); here, what they
//! mean in either byte order.

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

/// `trim`'s body in either byte order: deltas -5 and 900 (i16), factors 1.5 and -0.25 (f32),
/// modes 2 and 0 (u8 of an enum), trims -2 and 0x123456 (i24), stamp 0x0102030405060708 (u64),
/// scale 1.0 (f64, its 16-bit words swapped).
fn trim_body(little: bool) -> Vec<u8> {
    let mut b = vec![0x1A];
    let mut put = |bytes: &[u8]| {
        let mut v = bytes.to_vec();
        if little {
            v.reverse();
        }
        b.extend_from_slice(&v);
    };
    put(&(-5i16).to_be_bytes());
    put(&900i16.to_be_bytes());
    put(&1.5f32.to_be_bytes());
    put(&(-0.25f32).to_be_bytes());
    put(&[2]);
    put(&[0]);
    put(&(-2i32).to_be_bytes()[1..]);
    put(&0x123456i32.to_be_bytes()[1..]);
    put(&0x0102030405060708u64.to_be_bytes());
    // 1.0's words swapped: its last word (in the byte order) travels first.
    let mut one = 1.0f64.to_be_bytes();
    if little {
        one.reverse();
    }
    for w in one.chunks(2).rev() {
        b.extend_from_slice(w);
    }
    b
}

#[test]
fn signed_wide_float_and_enum_elements_read_as_their_type_both_ways() {
    for little in [false, true] {
        let p = fixture(little);
        let wire = frame(&trim_body(little));
        let d = interp::decode(&p, Some(Direction::Request), None, &wire)
            .unwrap_or_else(|e| panic!("little-endian {little}: {e}"));
        let get = |n: &str| d.values.iter().find(|v| v.name == n).unwrap().raw.clone();
        assert_eq!(get("deltas"), Raw::List(vec![-5, 900]));
        assert_eq!(
            get("factors"),
            Raw::List(vec![
                i64::from(1.5f32.to_bits()),
                i64::from((-0.25f32).to_bits())
            ])
        );
        assert_eq!(get("modes"), Raw::List(vec![2, 0]));
        assert_eq!(get("trims"), Raw::List(vec![-2, 0x123456]));
        assert_eq!(get("stamp"), Raw::List(vec![0x0102030405060708]));
        assert_eq!(get("scale"), Raw::List(vec![1.0f64.to_bits() as i64]));
        let back = interp::encode(&p, p.find("trim").unwrap(), 0, &d.values).unwrap();
        assert_eq!(back, wire, "little-endian: {little}");
    }
}

#[test]
fn a_signed_element_outside_its_type_or_range_is_refused() {
    let p = fixture(false);
    let r = p.find("trim").unwrap();
    let wire = frame(&trim_body(false));
    let d = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    let with = |name: &str, list: Vec<i64>| {
        let mut v = d.values.clone();
        v.iter_mut().find(|x| x.name == name).unwrap().raw = Raw::List(list);
        interp::encode(&p, r, 0, &v).unwrap_err().to_string()
    };
    // -901 is below deltas' range; 0x800000 is past what an i24 holds; 3.0 past factors'.
    assert!(with("deltas", vec![-901, 0]).contains("deltas"));
    assert!(with("trims", vec![0x800000, 0]).contains("trims"));
    let e = with("factors", vec![i64::from(3.0f32.to_bits()), 0]);
    assert!(e.contains("factors") && e.contains('3'), "{e}");
    // A frame whose first delta is -901 (0xFC7B) is refused there.
    let mut body = trim_body(false);
    body[1..3].copy_from_slice(&(-901i16).to_be_bytes());
    let e = interp::decode(&p, Some(Direction::Request), None, &frame(&body))
        .unwrap_err()
        .to_string();
    assert!(e.contains("deltas"), "{e}");
}

/// Packed elements of whole bytes in the other bit order than the protocol's byte order
/// (`bit_order: lsb_first` in a big-endian protocol) are no list of a fixed count: each
/// element's bytes travel least significant first, as the bit stream puts them. (A whole-byte
/// read in the protocol's byte order took them for a fixed count: random specs found it.)
#[test]
fn whole_packed_elements_in_the_other_bit_order_keep_their_bit_order() {
    let mut t = text();
    t.truncate(t.find("\nexamples:").unwrap());
    t = t.replace(
        "{name: offsets, type: u16, unit: ticks, repeat: {count: 3}}",
        "{name: offsets, type: u16, unit: ticks, packed: {count: 3, bits: 16, bit_order: lsb_first}}",
    );
    t.push_str("\nexamples: []\n");
    let p = busspec_model::load_str("packed_channels.yaml", &t).unwrap_or_else(|d| panic!("{d}"));
    let m = p.message(p.find("calibrate").unwrap());
    let f = m.fields.iter().find(|f| f.name == "offsets").unwrap();
    assert!(f.packed.unwrap().whole() && f.fixed_count().is_none());
    let wire = frame(&[0x19, 0x00, 0x01, 0x02, 0x03, 0xFF, 0xFF, 0x07, 0x09]);
    let (offsets, gains) = lists(&p, &wire);
    assert_eq!(offsets, Raw::List(vec![0x0100, 0x0302, 0xFFFF]));
    let values = [
        Value {
            name: Cow::Borrowed("offsets"),
            raw: offsets,
        },
        Value {
            name: Cow::Borrowed("gains"),
            raw: gains,
        },
    ];
    let back = interp::encode(&p, p.find("calibrate").unwrap(), 0, &values).unwrap();
    assert_eq!(back, wire);
}
