//! Header fields in several places (`header` more than once in the layout, each field with
//! its `part`; fixture `novatel_oem`, NovAtel's OEM binary header around the message id and
//! the length): placed, decoded and compared by `busspec diff`.

mod common;

use busspec_model::diff::Category::WireBreaking;
use busspec_model::interp::{self, Raw};
use busspec_model::ir::Direction;

/// Every header field sits where NovAtel's header table puts it (offsets from the sync), the
/// code at 4 and the length at 8 between the parts, and the receiver's own BESTPOSB log
/// decodes to the values its ASCII twin states.
#[test]
fn header_fields_sit_in_their_parts() {
    let p = busspec_model::load_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/valid/novatel_oem.yaml"),
    )
    .unwrap_or_else(|d| panic!("{d}"));
    let m = &p.responses[0];
    let places: Vec<(&str, usize)> = m
        .fields
        .iter()
        .take_while(|f| f.header)
        .map(|f| (f.name.as_str(), f.frame_at(&m.layout)))
        .collect();
    assert_eq!(
        places,
        [
            ("header_length", 3),
            ("message_type", 6),
            ("port_address", 7),
            ("sequence", 10),
            ("idle_time", 12),
            ("time_status", 13),
            ("week", 14),
            ("milliseconds", 16),
            ("receiver_status", 20),
            ("reserved", 24),
            ("software_version", 26),
        ]
    );
    assert_eq!(
        (m.layout.code, m.layout.length, m.layout.payload),
        (4, Some(8), 28)
    );
    let d = interp::decode(&p, Some(Direction::Response), None, &p.examples[0].wire).unwrap();
    let value = |name: &str| match d.values.iter().find(|v| v.name == name) {
        Some(v) => match v.raw {
            Raw::Int(n) => n,
            ref other => panic!("{name}: {other:?}"),
        },
        None => panic!("{name} not decoded"),
    };
    assert_eq!(value("port_address"), 0x20);
    assert_eq!(value("time_status"), 180);
    assert_eq!(value("software_version"), 9603);
    // The frame's length field, between parts 2 and 3, counts the body's 72 bytes.
    assert_eq!(&p.examples[0].wire[8..10], &[0x48, 0x00]);
}

/// A header field moved from one part to the next is wire-breaking at that field, and every
/// field it pushed along says where it went.
#[test]
fn a_header_field_moved_to_another_part_breaks_the_wire() {
    let moved = "    - {name: port_address, type: u8, unit: raw, part: 2, doc: \"The port the log was generated on (0x20 COM1).\"}\n";
    let (old, new) = common::revisions(
        "novatel_oem",
        &[
            (moved, ""),
            (
                "    - {name: idle_time,",
                &format!(
                    "{}    - {{name: idle_time,",
                    moved.replace("part: 2", "part: 3")
                ),
            ),
        ],
    );
    let changes: Vec<(String, &'static str, _, String)> = busspec_model::diff::diff(&old, &new)
        .into_iter()
        .filter(|c| c.path != "examples")
        .map(|c| (c.path, c.kind, c.category, c.text))
        .collect();
    assert_eq!(
        changes[0],
        (
            "framing.header.port_address".to_owned(),
            "header_field_changed",
            WireBreaking,
            "header field `port_address`: u8 at header part 2 + 1 → u8 at header part 3 + 2"
                .to_owned()
        )
    );
    // `idle_time` and every field after it in part 3 moved one byte on; `sequence` stayed.
    let paths: Vec<&str> = changes.iter().map(|c| c.0.as_str()).collect();
    assert_eq!(
        paths,
        [
            "framing.header.port_address",
            "framing.header.idle_time",
            "framing.header.time_status",
            "framing.header.week",
            "framing.header.milliseconds",
            "framing.header.receiver_status",
            "framing.header.reserved",
            "framing.header.software_version",
        ]
    );
    assert!(changes.iter().all(|c| c.2 == WireBreaking));
    assert!(busspec_model::diff::diff(&old, &old).is_empty());
}
