//! A CRC that takes a byte of each message's own after the bytes it covers (MAVLink's
//! CRC_EXTRA, `framing.checksum.extra: per_message`): the interpreter finds the byte by the
//! code, checks and writes the checksum with it, and agrees with MAVLink's own CRC routine
//! (written out here, as MAVLink's `crc_accumulate` does it); docs name the byte and diff calls
//! a changed one wire-breaking.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};

fn fixture() -> busspec_model::Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/crc_extra.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// MAVLink's X.25 CRC (`crc_accumulate` over each byte from 0xFFFF), then the extra byte.
fn mavlink_crc(covered: &[u8], extra: u8) -> u16 {
    let acc = |crc: u16, b: u8| {
        let mut tmp = b ^ (crc as u8);
        tmp ^= tmp << 4;
        let t = u16::from(tmp);
        (crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4)
    };
    let crc = covered.iter().fold(0xFFFF, |c, &b| acc(c, b));
    acc(crc, extra)
}

const HEARTBEAT: [u8; 14] = [
    0xFE, 0x09, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x03, 0x51, 0x04, 0x03, 0x37, 0x97,
];

#[test]
fn the_checksum_takes_the_extra_byte_of_the_message_its_code_names() {
    let p = fixture();
    // The heartbeat's CRC is MAVLink's over the covered bytes and HEARTBEAT's 50.
    assert_eq!(
        u16::from_le_bytes([HEARTBEAT[12], HEARTBEAT[13]]),
        mavlink_crc(&HEARTBEAT[1..12], 50)
    );
    let f = interp::decode(&p, Some(Direction::Response), None, &HEARTBEAT).unwrap();
    assert_eq!(p.message(f.message).name, "heartbeat");
    // Every message encodes with its own byte: MAVLink's routine agrees on each.
    for (direction, list) in [
        (Direction::Request, &p.commands),
        (Direction::Response, &p.responses),
    ] {
        for (index, m) in list.iter().enumerate() {
            let values: Vec<Value> = m
                .fields
                .iter()
                .map(|f| Value {
                    name: f.name.clone().into(),
                    raw: Raw::Int(1),
                })
                .collect();
            let wire = interp::encode(&p, MessageRef { direction, index }, 0, &values)
                .unwrap_or_else(|e| panic!("{}: {e}", m.name));
            let n = wire.len();
            let extra = m.checksum_extra.expect("each message has its byte");
            assert_eq!(
                u16::from_le_bytes([wire[n - 2], wire[n - 1]]),
                mavlink_crc(&wire[1..n - 2], extra),
                "{}",
                m.name
            );
        }
    }
}

#[test]
fn a_frame_checked_without_its_extra_byte_or_with_another_is_refused() {
    let p = fixture();
    for extra in [None, Some(237)] {
        let mut wire = HEARTBEAT;
        let crc = match extra {
            Some(x) => mavlink_crc(&wire[1..12], x),
            // Without the byte: the CRC of the covered bytes alone.
            None => {
                let c =
                    busspec_model::checksum::compute(&p.framing.checksum.algorithm, &wire[1..12]);
                c as u16
            }
        };
        wire[12..].copy_from_slice(&crc.to_le_bytes());
        let e = interp::decode(&p, Some(Direction::Response), None, &wire).unwrap_err();
        assert!(
            matches!(e, DecodeError::ChecksumMismatch { offset: 12, .. }),
            "{e}"
        );
    }
}

#[test]
fn docs_name_each_byte_and_diff_calls_a_changed_one_wire_breaking() {
    let p = fixture();
    let docs = busspec_model::docs::render(&p, "crc_extra.yaml");
    assert!(docs.contains("Checksum extra byte 50 (0x32)."), "{docs}");
    assert!(
        docs.contains("its checksum extra byte (MAVLink's CRC_EXTRA)"),
        "{docs}"
    );
    let (_, new) = common::revisions("crc_extra", &[("checksum_extra: 50", "checksum_extra: 51")]);
    let changes = busspec_model::diff::diff(&p, &new);
    let c: Vec<_> = changes
        .iter()
        .filter(|c| c.kind == "checksum_extra_changed")
        .collect();
    assert_eq!(c.len(), 1, "{changes:?}");
    assert_eq!(c[0].path, "responses.heartbeat.checksum_extra");
    assert_eq!(
        c[0].text,
        "response `heartbeat`: checksum extra byte 50 → 51"
    );
}
