//! A checksum the layout places before the bytes it covers (Septentrio SBF: `$@`, the CRC,
//! then the ID, length and body it covers): the interpreter checks and writes it where it
//! sits, over the bytes from `covers_from` to the frame's end, its stream decoder finds blocks
//! among noise by it, and the validator refuses what it does not carry yet, located.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};

fn fixture() -> busspec_model::Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/sbf_blocks.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

/// CRC-16/XMODEM (poly 0x1021, init 0, no reflection, no final XOR), bit by bit, as the SBF
/// reference describes it: independent of busspec's tables.
fn xmodem(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    for &b in bytes {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

const END_OF_PVT: &str = "24 40 10 50 21 17 10 00 00 70 99 14 29 09 00 00";

#[test]
fn the_crc_sits_at_offset_2_and_covers_from_the_id_to_the_end() {
    let p = fixture();
    assert_eq!(p.framing.checksum.lead, Some(2));
    assert_eq!(p.framing.trailer_len(), 0);
    let wire = hex(END_OF_PVT);
    assert_eq!(u16::from_le_bytes([wire[2], wire[3]]), xmodem(&wire[4..]));
    let f = interp::decode(&p, Some(Direction::Response), None, &wire).unwrap();
    assert_eq!(p.message(f.message).name, "end_of_pvt");
    assert_eq!(f.values[0].raw, Raw::Int(345_600_000));
    // Encoding writes the CRC before the bytes it covers, and the length of the whole block.
    let r = MessageRef {
        direction: Direction::Response,
        index: 1,
    };
    let values = [
        Value {
            name: "tow".into(),
            raw: Raw::Int(1000),
        },
        Value {
            name: "wnc".into(),
            raw: Raw::Int(7),
        },
        Value {
            name: "padding".into(),
            raw: Raw::Int(0),
        },
    ];
    let out = interp::encode(&p, r, 0, &values).unwrap();
    assert_eq!(out.len(), 16);
    assert_eq!(&out[..2], b"$@");
    assert_eq!(u16::from_le_bytes([out[6], out[7]]), 16);
    assert_eq!(u16::from_le_bytes([out[2], out[3]]), xmodem(&out[4..]));
}

#[test]
fn a_byte_changed_anywhere_it_covers_is_a_mismatch_at_offset_2() {
    let p = fixture();
    let good = hex(END_OF_PVT);
    for i in [4, 8, 15] {
        let mut wire = good.clone();
        wire[i] ^= 0x01;
        match interp::decode(&p, Some(Direction::Response), None, &wire) {
            Err(DecodeError::ChecksumMismatch { offset, found, .. }) => {
                assert_eq!(offset, 2, "byte {i}");
                assert_eq!(found, 0x5010);
            }
            other => panic!("byte {i}: {other:?}"),
        }
    }
    // The sync bytes are not covered: a wrong one is a bad start, not a mismatch.
    let mut wire = good.clone();
    wire[1] = 0x41;
    assert!(matches!(
        interp::decode(&p, Some(Direction::Response), None, &wire),
        Err(DecodeError::BadStart { offset: 1, .. })
    ));
    // Nor does a frame cut short read its CRC past its end.
    for n in 0..good.len() {
        assert!(interp::decode(&p, Some(Direction::Response), None, &good[..n]).is_err());
    }
}

#[test]
fn the_stream_finds_blocks_among_noise_by_their_crc() {
    let p = fixture();
    let mut bytes = hex("24 40 00 00 21 17");
    bytes.extend(hex(END_OF_PVT));
    bytes.extend(hex(
        "24 40 35 B2 1A 17 18 00 00 70 99 14 29 09 1A 0B 1D 0A 0F 1E 12 07 00 00",
    ));
    let mut d = StreamDecoder::new(&p, None);
    let events = d.push(&bytes);
    let frames: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame { offset, frame, .. } => {
                Some((*offset, p.message(frame.message).name.clone()))
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        frames,
        [
            (6, "end_of_pvt".to_owned()),
            (22, "receiver_time".to_owned())
        ]
    );
}

fn refusal(layout: &str, checksum_extra: &str) -> String {
    refusal_over(
        layout,
        "xor8, width: 8, mask: 0xFE, check: 0x30",
        checksum_extra,
    )
}

fn refusal_over(layout: &str, algorithm: &str, checksum_extra: &str) -> String {
    let text = format!(
        r#"
protocol: lead
title: "t"
document: {{title: "t", revision: "1", date: "2026-01-01"}}
byte_order: little
printed_byte_order: little
serial: {{section: "1", baud: 9600, data_bits: 8, parity: none, stop_bits: 1}}
framing:
  section: "2"
  layout: {layout}
  start: [0xFF, 0xFF]
  length: {{width: 1, counts: [start, length, address, code, checksum, payload]}}
  address: {{devices: {{min: 0, max: 0xFD}}, broadcast: 0xFE}}
  request:  {{code_lengths: [1], payload: {{min: 0, max: 4}}}}
  response: {{code_lengths: [1], payload: {{min: 0, max: 4}}}}
  checksum: {{algorithm: {algorithm}{checksum_extra}}}
units: [{{name: count, symbol: "", scale: "1"}}]
commands:
  - {{name: stat, title: "STAT", section: "3", kind: getter, code: "0x07", responses: []}}
responses: []
"#
    );
    match busspec_model::load_str("lead.yaml", &text) {
        Ok(_) => String::new(),
        Err(d) => d.to_string(),
    }
}

#[test]
fn a_crc_over_bytes_on_both_sides_of_it_is_refused_located() {
    // HerkuleX's shape (the checksum after the command, covering the size, ID and command
    // before it and the data after it) under a CRC: only a sum or XOR is taken over two
    // spans (tests/herkulex.rs has HerkuleX's XOR).
    let e = refusal_over(
        "[start, length, address, code, checksum, payload]",
        "crc, width: 16, poly: 0x1021, init: 0, refin: false, refout: false, xorout: 0, check: 0x31C3, byte_order: little",
        ", covers_from: length",
    );
    assert!(
        e.contains("framing.checksum.covers_from")
            && e.contains("over two spans only a sum or XOR")
            && e.contains("not crc"),
        "{e}"
    );
    // Fletcher's running sums neither.
    let e = refusal_over(
        "[start, length, address, code, checksum, payload]",
        "fletcher16, width: 16, check: 0x1EDE, byte_order: little",
        ", covers_from: length",
    );
    assert!(
        e.contains("framing.checksum.covers_from") && e.contains("not fletcher16"),
        "{e}"
    );
    // The XOR masked, as HerkuleX's: its covering is taken (the spec fails only on its
    // command's missing responses).
    let e = refusal(
        "[start, length, address, code, checksum, payload]",
        ", complement: true, covers_from: length",
    );
    assert!(!e.contains("framing.checksum"), "{e}");
    let e = refusal("[start, length, address, code, checksum, payload]", "");
    assert!(
        e.contains("framing.checksum.covers_from") && e.contains("say which (`covers_from`)"),
        "{e}"
    );
    // Covering from the payload after it: no part to name (the payload moves nothing, but
    // `covers_from` names a part before the payload).
    let e = refusal(
        "[start, length, address, checksum, code, payload, end]",
        ", covers_from: code",
    );
    assert!(e.contains("not expressible beside end bytes yet"), "{e}");
}

#[test]
fn moving_the_checksum_is_wire_breaking() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/sbf_blocks.yaml");
    let text = std::fs::read_to_string(path).unwrap();
    // Without the examples, whose CRCs sit at offset 2.
    let text = &text[..text.find("\nexamples:").unwrap()];
    let old = busspec_model::load_str("old.yaml", text).unwrap_or_else(|d| panic!("{d}"));
    let moved = text.replace(
        "layout: [start, checksum, code, length, payload]",
        "layout: [start, code, length, payload, checksum]",
    );
    let new = busspec_model::load_str("new.yaml", &moved).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(new.framing.checksum.lead, None);
    let changes = busspec_model::diff::diff(&old, &new);
    let moved: Vec<_> = changes
        .iter()
        .filter(|c| c.kind == "checksum_moved")
        .collect();
    assert_eq!(moved.len(), 1, "{changes:?}");
    assert_eq!(
        moved[0].category,
        busspec_model::diff::Category::WireBreaking
    );
    assert_eq!(moved[0].path, "framing.checksum");
    assert!(
        moved[0]
            .text
            .contains("at offset 2, before the bytes it covers → at the frame's end"),
        "{}",
        moved[0].text
    );
}

#[test]
fn docs_and_the_dissector_say_where_it_sits_and_what_it_covers() {
    let p = fixture();
    let docs = busspec_model::docs::render(&p, "sbf_blocks.yaml");
    assert!(
        docs.contains(
            "| checksum | 2 | over the bytes from offset 4 to the frame's end, after it |"
        ),
        "{docs}"
    );
    let lua = busspec_model::dissector::render(&[&p]);
    assert!(lua.contains("covers_from = 4, lead = 2,"), "{lua}");
}
