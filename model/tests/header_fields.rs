//! Header fields every message carries (`framing.header`, a `header` part in the layout):
//! MAVLink v1's sequence number, system and component IDs between the length and the message
//! id. The fixture's examples are frames pymavlink 2.4.50 made; here both directions of the
//! interpreter and its stream read the header fields pymavlink put in, encode writes them where
//! the header sits (the CRC over them), docs place them, and diff calls a changed one
//! wire-breaking.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};

fn text() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/mavlink_v1.yaml"),
    )
    .unwrap()
}

fn fixture() -> busspec_model::Protocol {
    busspec_model::load_str("mavlink_v1.yaml", &text()).unwrap_or_else(|d| panic!("{d}"))
}

/// Frames pymavlink 2.4.50 made (tests/reference/mavlink_v1_frames.py), with the message and
/// the header values it was given: (message, frame, sequence, sysid, compid).
const PYMAVLINK: &[(&str, &str, i64, i64, i64)] = &[
    ("heartbeat", "FE 09 00 01 01 00 00 00 00 00 02 03 51 04 03 7D DD", 0, 1, 1),
    ("heartbeat", "FE 09 11 FF BE 00 00 00 00 00 06 08 00 00 03 15 EA", 17, 255, 190),
    ("ping", "FE 0E 05 FF BE 04 40 42 0F 00 00 00 00 00 07 00 00 00 01 01 BE AC", 5, 255, 190),
    ("ping_reply", "FE 0E 2A 01 01 04 40 42 0F 00 00 00 00 00 07 00 00 00 FF BE 24 25", 42, 1, 1),
    ("sys_status", "FE 1F C8 01 01 01 2F FC 20 00 2F FC 20 00 2F FC 20 00 FA 00 76 2F 3E 03 00 00 03 00 00 00 00 00 00 00 00 00 57 6B 76", 200, 1, 1),
    ("attitude", "FE 1C FF 01 01 1E 40 E2 01 00 00 00 80 3D 00 00 00 BE 00 00 C0 3F 00 00 00 3F 00 00 00 BD 00 00 80 3E B3 5F", 255, 1, 1),
    ("request_data_stream", "FE 06 06 FF BE 42 04 00 01 01 00 01 E0 87", 6, 255, 190),
];

fn int(values: &[Value], name: &str) -> i64 {
    match values.iter().find(|v| v.name == name).map(|v| &v.raw) {
        Some(Raw::Int(v)) => *v,
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn the_header_fields_decode_to_what_pymavlink_put_in() {
    let p = fixture();
    for &(name, hex, seq, sysid, compid) in PYMAVLINK {
        let wire = interp::parse_hex(hex).unwrap();
        let d = if matches!(name, "ping" | "request_data_stream") {
            Direction::Request
        } else {
            Direction::Response
        };
        let f = interp::decode(&p, Some(d), None, &wire).unwrap_or_else(|e| panic!("{name}: {e}"));
        let m = p.message(f.message);
        assert_eq!(m.name, name);
        // The header fields lead every message's fields.
        let names: Vec<&str> = m.fields.iter().take(3).map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["sequence", "sysid", "compid"]);
        assert!(m.fields[..3].iter().all(|f| f.header));
        assert_eq!(
            (
                int(&f.values, "sequence"),
                int(&f.values, "sysid"),
                int(&f.values, "compid")
            ),
            (seq, sysid, compid),
            "{name}"
        );
        // Encoding the values decode gave makes pymavlink's frame again.
        let again = interp::encode(&p, f.message, 0, &f.values).unwrap();
        assert_eq!(interp::format_hex(&again), hex, "{name}");
    }
}

#[test]
fn a_stream_of_pymavlink_frames_decodes_each_with_its_header() {
    let p = fixture();
    let mut capture = vec![0x00, 0x55];
    for &(name, hex, ..) in PYMAVLINK {
        if matches!(name, "heartbeat" | "sys_status" | "attitude") {
            capture.extend(interp::parse_hex(hex).unwrap());
        }
    }
    let mut s = StreamDecoder::new(&p, Some(Direction::Response));
    let mut events = s.push(&capture);
    events.extend(s.flush());
    let frames: Vec<(String, i64)> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame { frame, .. } => Some((
                p.message(frame.message).name.clone(),
                int(&frame.values, "sequence"),
            )),
            _ => None,
        })
        .collect();
    assert_eq!(
        frames,
        [
            ("heartbeat".to_owned(), 0),
            ("heartbeat".to_owned(), 17),
            ("sys_status".to_owned(), 200),
            ("attitude".to_owned(), 255)
        ]
    );
}

#[test]
fn encode_writes_the_header_where_the_layout_puts_it_and_the_crc_covers_it() {
    let p = fixture();
    let wire = interp::parse_hex(PYMAVLINK[0].1).unwrap();
    let f = interp::decode(&p, Some(Direction::Response), None, &wire).unwrap();
    let mut values = f.values.clone();
    for v in values.iter_mut() {
        if v.name == "sequence" {
            v.raw = Raw::Int(1);
        }
    }
    let next = interp::encode(&p, f.message, 0, &values).unwrap();
    assert_eq!(next[2], 1);
    assert_eq!(next[..2], wire[..2]);
    assert_eq!(next[3..15], wire[3..15]);
    assert_ne!(next[15..], wire[15..], "the CRC covers the sequence number");
    assert!(interp::decode(&p, Some(Direction::Response), None, &next).is_ok());
    // A value past the header field's type is refused by encode.
    for v in values.iter_mut() {
        if v.name == "sysid" {
            v.raw = Raw::Int(256);
        }
    }
    assert!(interp::encode(&p, f.message, 0, &values).is_err());
}

#[test]
fn docs_place_the_header_and_diff_calls_a_changed_header_field_wire_breaking() {
    let p = fixture();
    let docs = busspec_model::docs::render(&p, "mavlink_v1.yaml");
    assert!(
        docs.contains(
            "header fields every message carries: `sequence` (1), `sysid` (1), `compid` (1)"
        ),
        "{docs}"
    );
    assert!(docs.contains("header + 1"), "{docs}");
    let (_, new) = common::revisions(
        "mavlink_v1",
        &[("{name: compid, type: u8,", "{name: compid, type: u16,")],
    );
    let changes = busspec_model::diff::diff(&p, &new);
    assert!(
        changes.iter().any(|c| c.path == "framing.header.compid"
            && c.kind == "header_field_changed"
            && c.category == busspec_model::diff::Category::WireBreaking),
        "{changes:#?}"
    );
}

/// MSP v2: the flag byte a header field before the code, the checksum covering from it.
#[test]
fn a_header_before_the_code_is_covered_by_a_checksum_from_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/msp_v2.yaml");
    let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    let h = p.framing.head(busspec_model::ir::Direction::Request, 2);
    assert_eq!(
        (h.headers[0], h.code, h.length, h.payload),
        (3, 4, Some(6), 8)
    );
    assert_eq!(p.framing.checksum.covers_from, 3);
    let wire = interp::parse_hex("24 58 3C 01 02 00 00 00 3C").unwrap();
    let f = interp::decode(&p, None, None, &wire).unwrap();
    assert_eq!(int(&f.values, "dont_reply"), 1);
    let mut bad = wire.clone();
    bad[3] = 0;
    let e = interp::decode(&p, None, None, &bad).unwrap_err();
    assert!(e.to_string().contains("checksum mismatch"), "{e}");
    // A reserved flag bit set, the checksum made again: the header's constant sub-field says
    // where.
    let mut reserved = wire.clone();
    reserved[3] = 0x81;
    interp::reseal(&p, &mut reserved);
    let e = interp::decode(&p, None, None, &reserved).unwrap_err();
    assert!(e.to_string().contains("offset 3"), "{e}");
    assert!(e.to_string().contains("reserved_flags"), "{e}");
}

/// A header field's sub-fields changed (a reserved bit taken): wire-breaking, said once.
#[test]
fn diff_calls_a_changed_header_sub_field_wire_breaking() {
    let (old, new) = common::revisions(
        "msp_v2",
        &[(
            "{name: reserved_flags, msb: 7, lsb: 1, value: 0}",
            "{name: reserved_flags, msb: 7, lsb: 2, value: 0}\n        - {name: ack, msb: 1, lsb: 1, unit: count}",
        )],
    );
    let changes = busspec_model::diff::diff(&old, &new);
    let header: Vec<_> = changes
        .iter()
        .filter(|c| c.path.starts_with("framing.header"))
        .collect();
    assert_eq!(header.len(), 1, "{changes:#?}");
    assert_eq!(
        header[0].text,
        "header field `flags`: its sub-fields changed"
    );
    assert_eq!(
        header[0].category,
        busspec_model::diff::Category::WireBreaking
    );
}
