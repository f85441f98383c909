//! HerkuleX's checksum (`framing.checksum: {algorithm: xor8, mask: 0xFE, complement: true,
//! covers_from: length}` with the checksum before the payload): CS1, the XOR of the size,
//! ID and command before it and of the data after it, kept to 0xFE, then CS2, its complement
//! kept to 0xFE. The interpreter checks and writes both where they sit, its stream decoder
//! finds packets among noise by them, `checksum_ok` takes them, and `busspec diff`, the docs
//! and the dissector say what they are; the validator refuses what it does not carry, located.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};

fn text() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/herkulex.yaml");
    std::fs::read_to_string(path).unwrap()
}

fn fixture() -> busspec_model::Protocol {
    busspec_model::load_str("herkulex.yaml", &text()).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

/// CS1 and CS2 as the HerkuleX manual defines them, apart from busspec.
fn cs(frame: &[u8]) -> (u8, u8) {
    let x = frame[2..5]
        .iter()
        .chain(&frame[7..])
        .fold(0u8, |a, b| a ^ b);
    let cs1 = x & 0xFE;
    (cs1, !cs1 & 0xFE)
}

const STAT_ACK: &str = "FF FF 09 01 47 0C F2 00 42";

#[test]
fn both_bytes_sit_after_the_command_and_cover_both_sides() {
    let p = fixture();
    let f = &p.framing;
    assert_eq!(f.checksum.lead, Some(5));
    assert_eq!(f.checksum.len(), 2);
    assert!(f.covers_around());
    assert_eq!(f.covered_of(Direction::Response, 9), 2..5);
    assert_eq!(f.covered_after_of(Direction::Response, 9), 7..9);
    let wire = hex(STAT_ACK);
    assert_eq!(cs(&wire), (wire[5], wire[6]));
    let d = interp::decode(&p, Some(Direction::Response), None, &wire).unwrap();
    assert_eq!(p.message(d.message).name, "stat_ack");
    assert_eq!(d.values[1].raw, Raw::Int(0x42));
    assert!(interp::checksum_ok(&p, &wire));
    // Encoding a RAM_WRITE writes the size, both checksum bytes and the data.
    let r = MessageRef {
        direction: Direction::Request,
        index: 2,
    };
    let values: Vec<Value> = [("address", 0x30), ("length", 1), ("value", 0xAB)]
        .iter()
        .map(|(n, v)| Value {
            name: (*n).into(),
            raw: Raw::Int(*v),
        })
        .collect();
    let out = interp::encode(&p, r, 0x07, &values).unwrap();
    assert_eq!(out.len(), 10);
    assert_eq!(&out[..5], &[0xFF, 0xFF, 0x0A, 0x07, 0x03]);
    assert_eq!(&out[7..], &[0x30, 0x01, 0xAB]);
    assert_eq!(cs(&out), (out[5], out[6]));
    // Resealing a frame whose data changed writes both bytes anew.
    let mut changed = out.clone();
    changed[9] = 0x11;
    assert!(!interp::checksum_ok(&p, &changed));
    interp::reseal(&p, &mut changed);
    assert_eq!(cs(&changed), (changed[5], changed[6]));
    assert!(interp::checksum_ok(&p, &changed));
}

#[test]
fn a_byte_changed_on_either_side_or_a_wrong_complement_is_a_mismatch_at_offset_5() {
    let p = fixture();
    let good = hex(STAT_ACK);
    for i in [3, 4, 7, 8] {
        let mut wire = good.clone();
        wire[i] ^= 0x20;
        match interp::decode(&p, Some(Direction::Response), None, &wire) {
            Err(DecodeError::ChecksumMismatch { offset, found, .. }) => {
                assert_eq!(offset, 5, "byte {i}");
                assert_eq!(found, 0x0CF2);
            }
            other => panic!("byte {i}: {other:?}"),
        }
        assert!(!interp::checksum_ok(&p, &wire), "byte {i}");
    }
    // CS2 not CS1's complement.
    let mut wire = good.clone();
    wire[6] = 0xF0;
    assert!(matches!(
        interp::decode(&p, Some(Direction::Response), None, &wire),
        Err(DecodeError::ChecksumMismatch {
            offset: 5,
            expected: 0x0CF2,
            found: 0x0CF0,
            ..
        })
    ));
    // The header bytes are not covered: a wrong one is a bad start.
    let mut wire = good.clone();
    wire[0] = 0xFE;
    assert!(matches!(
        interp::decode(&p, Some(Direction::Response), None, &wire),
        Err(DecodeError::BadStart { offset: 0, .. })
    ));
    for n in 0..good.len() {
        assert!(interp::decode(&p, Some(Direction::Response), None, &good[..n]).is_err());
        assert!(!interp::checksum_ok(&p, &good[..n]), "{n} bytes");
    }
}

#[test]
fn the_stream_finds_packets_among_noise_by_their_checksum() {
    let p = fixture();
    let mut bytes = hex("FF FF 09 01 47 0C F3 00 42 00 FF");
    bytes.extend(hex(STAT_ACK));
    bytes.extend(hex("FF FF 0C FD 44 C2 3C 35 01 01 00 42"));
    let mut d = StreamDecoder::new(&p, Some(Direction::Response));
    let mut events = d.push(&bytes);
    events.extend(d.flush());
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
            (11, "stat_ack".to_owned()),
            (20, "ram_read_1_ack".to_owned())
        ]
    );
}

fn refusal(checksum: &str) -> String {
    let t = text();
    let t = &t[..t.find("\nexamples:").unwrap()];
    let t = t.replace(
        "    algorithm: xor8\n    width: 8\n    mask: 0xFE\n    check: 0x30\n    complement: true\n",
        checksum,
    );
    match busspec_model::load_str("herkulex.yaml", &t) {
        Ok(_) => String::new(),
        Err(d) => d.to_string(),
    }
}

#[test]
fn a_complement_after_anything_but_an_8_bit_sum_or_xor_is_refused_located() {
    // As given, the fixture loads.
    assert_eq!(refusal("    algorithm: xor8\n    width: 8\n    mask: 0xFE\n    check: 0x30\n    complement: true\n"), "");
    let e = refusal("    algorithm: sum16\n    width: 16\n    check: 0x1DD\n    byte_order: big\n    complement: true\n");
    assert!(
        e.contains("framing.checksum.complement") && e.contains("follows an 8-bit sum or XOR"),
        "{e}"
    );
    let e = refusal("    algorithm: fletcher8\n    width: 16\n    check: 0x2ADD\n    byte_order: big\n    complement: true\n");
    assert!(e.contains("framing.checksum.complement"), "{e}");
    let e = refusal("    algorithm: xor8\n    width: 8\n    check: 0x31\n    byte_order: big\n    complement: true\n");
    assert!(
        e.contains("framing.checksum.byte_order") && e.contains("takes no byte order"),
        "{e}"
    );
    // Over two spans, FrSky's end-around sum is not taken (generated code has no two-span
    // form of it), though it takes a complement.
    let e = refusal(
        "    algorithm: sum8_end_around\n    width: 8\n    check: 0x21\n    complement: true\n",
    );
    assert!(
        e.contains("framing.checksum.covers_from")
            && e.contains("over two spans only a sum or XOR"),
        "{e}"
    );
}

#[test]
fn the_complement_and_the_covering_are_wire_breaking_in_busspec_diff() {
    let t = text();
    let t = &t[..t.find("\nexamples:").unwrap()];
    let old = busspec_model::load_str("old.yaml", t).unwrap_or_else(|d| panic!("{d}"));
    let without = t.replace("    complement: true\n", "");
    let new = busspec_model::load_str("new.yaml", &without).unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    let c: Vec<_> = changes
        .iter()
        .filter(|c| c.path == "framing.checksum.complement")
        .collect();
    assert_eq!(c.len(), 1, "{changes:?}");
    assert_eq!(c[0].category, busspec_model::diff::Category::WireBreaking);
    assert_eq!(c[0].text, "checksum followed by its complement → alone");
    // Only the complement changed: no other checksum change is reported.
    assert!(
        !changes.iter().any(|c| c.path == "framing.checksum"),
        "{changes:?}"
    );
    // Covering from the command rather than the size byte.
    let from_code = t.replace("covers_from: length", "covers_from: code");
    let new = busspec_model::load_str("new.yaml", &from_code).unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    assert!(
        changes
            .iter()
            .any(|c| c.path == "framing.checksum.covers_from"
                && c.category == busspec_model::diff::Category::WireBreaking
                && c.text.contains("offset 2 → 4")),
        "{changes:?}"
    );
}

#[test]
fn docs_and_the_dissector_say_what_it_covers_and_that_a_complement_follows() {
    let p = fixture();
    let docs = busspec_model::docs::render(&p, "herkulex.yaml");
    assert!(
        docs.contains(
            "| checksum | 2 | over the bytes from offset 2 to the frame's end, skipping its own |"
        ),
        "{docs}"
    );
    assert!(
        docs.contains("Checksum: XOR of the bytes, kept to the bits of 0xFE,")
            && docs
                .contains("followed by a second, its bitwise complement kept to the bits of 0xFE"),
        "{docs}"
    );
    let lua = busspec_model::dissector::render(&[&p]);
    assert!(lua.contains("covers_from = 2, lead = 5,"), "{lua}");
    assert!(lua.contains("bit32.bnot(v), 254)"), "{lua}");
}
