//! Optional fields (`present: {field, bit | equals}`): the interpreter's one-frame decoder
//! (plain and through a `Lookup`), its encoder and its stream decoder agree on fixture
//! `optional_sensor`: a field is on the wire exactly when its condition holds, and a frame's
//! length must agree with the fields present. The validator's refusals are in
//! `broken_specs.rs`; `busspec diff`'s `field_presence_changed` is held here.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::diff::{self, Category};
use busspec_model::interp::{self, DecodeError, EncodeError, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn text() -> String {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/optional_sensor.yaml");
    std::fs::read_to_string(path).unwrap()
}

fn fixture() -> Protocol {
    busspec_model::load_str("optional_sensor.yaml", &text()).unwrap_or_else(|d| panic!("{d}"))
}

fn head() -> String {
    let t = text();
    format!(
        "{}examples: []\nerrata: []\n",
        &t[..t.find("examples:").unwrap()]
    )
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn v(name: &str, raw: i64) -> Value<'static> {
    Value {
        name: name.to_owned().into(),
        raw: Raw::Int(raw),
    }
}

fn names(f: &interp::Frame) -> Vec<String> {
    f.values.iter().map(|v| v.name.to_string()).collect()
}

const NONE: &str = "A5 01 03 81 00 00 D7 5C";
const HUMIDITY: &str = "A5 01 05 81 01 00 D7 01 C2 22";
const BOTH: &str = "A5 01 09 81 03 FF 9C 01 C2 00 01 8A 88 FF";
const FAULT: &str = "A5 01 03 82 02 00 07 8F";
const STOPPED: &str = "A5 01 01 82 03 87";

/// Every way the interpreter decodes one frame: plain, either direction, through a lookup.
fn decode_all<'p>(p: &'p Protocol, wire: &[u8]) -> Vec<Result<interp::Frame<'p>, DecodeError>> {
    vec![
        interp::decode(p, None, None, wire),
        interp::decode(p, Some(Direction::Response), None, wire),
        interp::Lookup::new(p, None).decode(p, None, wire),
        interp::Lookup::new(p, Some(Direction::Response)).decode(p, None, wire),
    ]
}

#[test]
fn the_ir_places_optional_fields_after_the_fixed_ones() {
    let p = fixture();
    let m = p.message(p.find("reading").unwrap());
    assert!(m.has_optional() && m.is_variable());
    assert_eq!(m.payload_len, 3);
    assert_eq!((m.min_len(), m.max_len), (8, 14));
    assert_eq!(m.fields[2].offset, 3);
    assert_eq!(m.fields[3].offset, 3);
    assert_eq!(m.optionals().count(), 2);
    assert!(m.listed_lengths(&p.framing).is_empty());
}

#[test]
fn a_field_decodes_exactly_where_its_condition_holds() {
    let p = fixture();
    for (frame, message, expected) in [
        (NONE, "reading", vec![("status", 0), ("temperature", 215)]),
        (
            HUMIDITY,
            "reading",
            vec![("status", 1), ("temperature", 215), ("humidity", 450)],
        ),
        (
            BOTH,
            "reading",
            vec![
                ("status", 3),
                ("temperature", -100),
                ("humidity", 450),
                ("pressure", 101000),
            ],
        ),
        (FAULT, "event", vec![("kind", 2), ("detail", 7)]),
        (STOPPED, "event", vec![("kind", 3)]),
    ] {
        for got in decode_all(&p, &hex(frame)) {
            let f = got.unwrap_or_else(|e| panic!("{frame}: {e}"));
            assert_eq!(p.message(f.message).name, message, "{frame}");
            let want: Vec<String> = expected.iter().map(|(n, _)| n.to_string()).collect();
            assert_eq!(names(&f), want, "{frame}");
            for (n, raw) in &expected {
                assert_eq!(f.get(n), Some(&Raw::Int(*raw)), "{frame}: {n}");
            }
        }
    }
}

#[test]
fn decode_refuses_a_length_the_fields_present_disagree_with() {
    let p = fixture();
    // Bit 0 says humidity follows, but the frame is as long as one without it.
    let mut short = hex(NONE);
    short[4] = 0x01;
    interp::reseal(&p, &mut short);
    // Bit 0 clear, but the frame carries the humidity's bytes.
    let mut long = hex(HUMIDITY);
    long[4] = 0x00;
    interp::reseal(&p, &mut long);
    // A fault's detail missing; a stop with a detail.
    let mut no_detail = hex(STOPPED);
    no_detail[4] = 0x02;
    interp::reseal(&p, &mut no_detail);
    let mut detail = hex(FAULT);
    detail[4] = 0x01;
    interp::reseal(&p, &mut detail);
    for (wire, message, expected, found) in [
        (&short, "reading", 10, 8),
        (&long, "reading", 8, 10),
        (&no_detail, "event", 8, 6),
        (&detail, "event", 6, 8),
    ] {
        for got in decode_all(&p, wire) {
            assert_eq!(
                got,
                Err(DecodeError::WrongLength {
                    message: message.to_owned(),
                    expected: vec![expected],
                    found,
                }),
                "{}",
                interp::format_hex(wire)
            );
        }
        let r = p.find(message).unwrap();
        assert!(interp::decode_as(&p, r, wire).is_err());
    }
    // Worded as every other length refusal.
    assert_eq!(
        interp::decode(&p, None, None, &short)
            .unwrap_err()
            .to_string(),
        "wrong length for reading: expected 10 bytes, found 8"
    );
}

#[test]
fn encode_writes_the_fields_present_and_refuses_presence_against_the_condition() {
    let p = fixture();
    let r = p.find("reading").unwrap();
    let e = p.find("event").unwrap();
    for (msg, vals, frame) in [
        (r, vec![v("status", 0), v("temperature", 215)], NONE),
        (
            r,
            vec![v("status", 1), v("temperature", 215), v("humidity", 450)],
            HUMIDITY,
        ),
        (
            r,
            vec![
                v("status", 3),
                v("temperature", -100),
                v("humidity", 450),
                v("pressure", 101000),
            ],
            BOTH,
        ),
        (e, vec![v("kind", 2), v("detail", 7)], FAULT),
        (e, vec![v("kind", 3)], STOPPED),
    ] {
        assert_eq!(interp::encode(&p, msg, 1, &vals), Ok(hex(frame)), "{frame}");
    }
    // Pressure alone: bit 1 only, the pressure right after the temperature.
    let wire = interp::encode(
        &p,
        r,
        1,
        &[v("status", 2), v("temperature", 1), v("pressure", 7)],
    )
    .unwrap();
    assert_eq!(wire.len(), 12);
    assert_eq!(&wire[2..11], &hex("07 81 02 00 01 00 00 00 07")[..]);
    let f = interp::decode(&p, None, None, &wire).unwrap();
    assert_eq!(names(&f), ["status", "temperature", "pressure"]);

    let missing = interp::encode(&p, r, 1, &[v("status", 1), v("temperature", 1)]);
    assert_eq!(
        missing,
        Err(EncodeError::Optional {
            field: "humidity".into(),
            condition: "bit 0 of `status` is set".into(),
            given: false,
        })
    );
    assert_eq!(
        missing.unwrap_err().to_string(),
        "no value given for field humidity, which is present when bit 0 of `status` is set"
    );
    let extra = interp::encode(&p, e, 1, &[v("kind", 1), v("detail", 3)]);
    assert_eq!(
        extra,
        Err(EncodeError::Optional {
            field: "detail".into(),
            condition: "`kind` = 2".into(),
            given: true,
        })
    );
    assert_eq!(
        extra.unwrap_err().to_string(),
        "value given for detail, which is present only when `kind` = 2"
    );
    // The range of a present field still holds.
    assert!(matches!(
        interp::encode(
            &p,
            r,
            1,
            &[v("status", 1), v("temperature", 1), v("humidity", 1001)]
        ),
        Err(EncodeError::NotInRange { .. })
    ));
}

#[test]
fn the_stream_decoder_frames_every_presence_by_the_length_field() {
    let p = fixture();
    let mut bytes = vec![0x00, 0x13];
    let frames = [NONE, BOTH, "A5 01 00 01 02", HUMIDITY, FAULT, STOPPED];
    let mut offsets = Vec::new();
    for f in frames {
        offsets.push(bytes.len() as u64);
        bytes.extend(hex(f));
    }
    // Fed whole, and a byte at a time.
    for chunk in [bytes.len(), 1] {
        let mut s = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in bytes.chunks(chunk) {
            events.extend(s.push(c));
        }
        events.extend(s.flush());
        let got: Vec<(u64, String)> = events
            .iter()
            .filter_map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    Some((*offset, p.message(frame.message).name.clone()))
                }
                _ => None,
            })
            .collect();
        let want: Vec<(u64, String)> = offsets
            .iter()
            .zip(["reading", "reading", "read", "reading", "event", "stopped"])
            .map(|(o, n)| {
                (
                    *o,
                    if n == "stopped" {
                        "event".to_owned()
                    } else {
                        n.to_owned()
                    },
                )
            })
            .collect();
        assert_eq!(got, want, "chunk {chunk}");
        let skipped: usize = events
            .iter()
            .filter(|e| matches!(e, Event::Skipped { .. }))
            .map(|e| e.bytes().len())
            .sum();
        assert_eq!(skipped, 2, "chunk {chunk}");
    }
    // A frame whose presence disagrees with its length is never a frame.
    let mut short = hex(NONE);
    short[4] = 0x01;
    interp::reseal(&p, &mut short);
    let mut s = StreamDecoder::new(&p, None);
    let mut events = s.push(&short);
    events.extend(s.flush());
    assert!(
        events.iter().all(|e| !matches!(e, Event::Frame { .. })),
        "{events:?}"
    );
}

#[test]
fn diff_calls_a_changed_presence_wire_breaking() {
    let old = busspec_model::load_str("old", &head()).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(diff::diff(&old, &old), []);
    let edited = head()
        .replace(
            "present: {field: status, bit: 1}",
            "present: {field: status, bit: 2}",
        )
        .replace(", present: {field: kind, equals: 2}", "");
    let new = busspec_model::load_str("new", &edited).unwrap_or_else(|d| panic!("{d}"));
    let found = diff::diff(&old, &new);
    let kinds: Vec<(Category, &str, &str, &str)> = found
        .iter()
        .map(|c| (c.category, c.kind, c.path.as_str(), c.text.as_str()))
        .filter(|c| c.1 == "field_presence_changed")
        .collect();
    assert_eq!(
        kinds,
        [
            (
                Category::WireBreaking,
                "field_presence_changed",
                "responses.reading.fields.pressure",
                "field `reading.pressure`: present only when bit 1 of `status` is set → present only when bit 2 of `status` is set"
            ),
            (
                Category::WireBreaking,
                "field_presence_changed",
                "responses.event.fields.detail",
                "field `event.detail`: present only when `kind` = 2 → always present"
            ),
        ]
    );
}

#[test]
fn docs_say_when_each_optional_field_is_present() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "optional_sensor.yaml");
    for note in [
        "optional: present only when bit 0 of `status` is set (else absent, and the frame shorter by 2 bytes)",
        "optional: present only when bit 1 of `status` is set (else absent, and the frame shorter by 4 bytes)",
        "optional: present only when `kind` = 2 (else absent, and the frame shorter by 2 bytes)",
    ] {
        assert!(md.contains(note), "{note}\n{md}");
    }
    // The second optional field sits after the first where it is present.
    assert!(md.contains("| 3 + earlier optional | `pressure` |"), "{md}");
}

/// A document that prints numbers in another byte order than the wire's: example text is
/// reordered field by field, an optional field only where it is present and where the fields
/// present put it (pressure right after temperature when humidity is absent).
#[test]
fn printed_byte_order_reorders_only_the_fields_present() {
    let little = head().replace(
        "byte_order: big\nprinted_byte_order: big",
        "byte_order: little\nprinted_byte_order: big",
    );
    assert!(little.contains("printed_byte_order: big"), "{little}");
    let p =
        busspec_model::load_str("optional_sensor.yaml", &little).unwrap_or_else(|d| panic!("{d}"));
    let r = p.find("reading").unwrap();
    let m = p.message(r);
    // Pressure alone: status 2, temperature -100, pressure 101000 (0x00018A88).
    let values = [
        v("status", 2),
        v("temperature", -100),
        v("pressure", 101_000),
    ];
    let wire = interp::encode(&p, r, 1, &values).unwrap();
    assert_eq!(&wire[4..11], &[2, 0x9C, 0xFF, 0x88, 0x8A, 0x01, 0x00]);
    let printed = interp::wire_to_printed(&p, m, &wire);
    assert_eq!(&printed[4..11], &[2, 0xFF, 0x9C, 0x00, 0x01, 0x8A, 0x88]);
    assert_eq!(interp::printed_to_wire(&p, m, &printed), wire);
    // Both present: each reversed where it sits.
    let values = [
        v("status", 3),
        v("temperature", 1),
        v("humidity", 0x0102),
        v("pressure", 0x0304_0506),
    ];
    let wire = interp::encode(&p, r, 1, &values).unwrap();
    let printed = interp::wire_to_printed(&p, m, &wire);
    assert_eq!(&printed[4..13], &[3, 0, 1, 1, 2, 3, 4, 5, 6]);
    assert_eq!(interp::printed_to_wire(&p, m, &printed), wire);
}

/// The same with a per-byte transform of the payload (`framing.transform`): the presence of an
/// optional field is read from its condition's value, not from the byte as it travels (status
/// 2 travels as 0x03, whose bit 0 would put humidity in). Random specs found it: the validator
/// refused an example the interpreter had encoded and printed.
#[test]
fn printed_byte_order_reads_presence_through_the_transform() {
    let little = head()
        .replace(
            "byte_order: big\nprinted_byte_order: big",
            "byte_order: little\nprinted_byte_order: big",
        )
        .replace(
            "    check: 0xDD\n",
            "    check: 0xDD\n  transform: {xor: 0x01}\n",
        );
    assert!(little.contains("transform: {xor: 0x01}"), "{little}");
    let p =
        busspec_model::load_str("optional_sensor.yaml", &little).unwrap_or_else(|d| panic!("{d}"));
    let r = p.find("reading").unwrap();
    let m = p.message(r);
    let values = [
        v("status", 2),
        v("temperature", -100),
        v("pressure", 101_000),
    ];
    let wire = interp::encode(&p, r, 1, &values).unwrap();
    let plain: Vec<u8> = [2u8, 0x9C, 0xFF, 0x88, 0x8A, 0x01, 0x00]
        .iter()
        .map(|b| b ^ 0x01)
        .collect();
    assert_eq!(&wire[4..11], &plain[..]);
    let printed = interp::wire_to_printed(&p, m, &wire);
    let expected: Vec<u8> = [2u8, 0xFF, 0x9C, 0x00, 0x01, 0x8A, 0x88]
        .iter()
        .map(|b| b ^ 0x01)
        .collect();
    assert_eq!(&printed[4..11], &expected[..]);
    assert_eq!(interp::printed_to_wire(&p, m, &printed), wire);
}
