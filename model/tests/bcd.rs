//! BCD fields (`encoding: bcd`): the interpreter reads the decimal number the digits give,
//! refuses a digit above 9 where it lies, writes a value's digits and refuses one its digits
//! cannot hold; docs, diff and JSON show the decimal number.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::Direction;

fn path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/bcd_meter.yaml")
}

fn fixture() -> busspec_model::Protocol {
    busspec_model::load_file(&path()).unwrap_or_else(|d| panic!("{d}"))
}

const ENERGY: [u8; 10] = [0x68, 0x01, 0x91, 0x56, 0x34, 0x12, 0x00, 0x02, 0x98, 0x16];

#[test]
fn a_bcd_field_reads_as_the_decimal_number_of_its_digits() {
    let p = fixture();
    let f = interp::decode(&p, Some(Direction::Response), None, &ENERGY).unwrap();
    let raw = |n: &str| f.values.iter().find(|v| v.name == n).map(|v| v.raw.clone());
    // 56 34 12 00, low byte first: the digits 00123456.
    assert_eq!(raw("energy"), Some(Raw::Int(123_456)));
    assert_eq!(raw("tariff"), Some(Raw::Int(2)));
}

#[test]
fn a_digit_above_nine_is_refused_where_it_lies() {
    let p = fixture();
    let mut bad = ENERGY;
    bad[3] = 0x5A;
    bad[8] = 0x9C;
    let e = interp::decode(&p, Some(Direction::Response), None, &bad).unwrap_err();
    assert!(
        matches!(
            e,
            DecodeError::NotBcd {
                offset: 3,
                found: 0x0012_345A,
                ..
            }
        ),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "invalid value for energy.energy at offset 3: 0x12345A is not BCD (a digit above 9)"
    );
}

#[test]
fn encode_writes_the_digits_and_refuses_a_value_they_cannot_hold() {
    let p = fixture();
    let r = p.find("set_clock").unwrap();
    let values = |year: i64| {
        [("hour", 7), ("minute", 5), ("year", year)]
            .into_iter()
            .map(|(n, v)| Value {
                name: n.into(),
                raw: Raw::Int(v),
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(
        interp::encode(&p, r, 1, &values(1999)).unwrap(),
        [0x68, 0x01, 0x08, 0x07, 0x05, 0x99, 0x19, 0x2F, 0x16]
    );
    let e = interp::encode(&p, r, 1, &values(10_000)).unwrap_err();
    assert_eq!(e.to_string(), "year = 10000 is outside its range 0..=9999");
}

#[test]
fn docs_and_diff_name_the_encoding() {
    let p = fixture();
    let docs = busspec_model::docs::render(&p, "bcd_meter.yaml");
    assert!(docs.contains("| `energy` | u32 BCD | 4 |"), "{docs}");
    let (_, new) = common::revisions(
        "bcd_meter",
        &[(
            "{name: year, type: u16, encoding: bcd,",
            "{name: year, type: u16,",
        )],
    );
    let changes = busspec_model::diff::diff(&p, &new);
    let c: Vec<_> = changes
        .iter()
        .filter(|c| c.kind == "field_encoding_changed")
        .collect();
    assert_eq!(c.len(), 1, "{changes:?}");
    assert_eq!(c[0].path, "commands.set_clock.fields.year");
    assert_eq!(c[0].text, "field `set_clock.year`: encoding bcd → binary");
    assert!(busspec_model::diff::diff(&p, &p).is_empty());
}
