//! Text a count field counts (`type: ascii` with `repeat`, fixture `text_counted`): the
//! interpreter decodes its characters as text (not a list of numbers), encodes text back and
//! computes its count field, refuses text longer than `repeat.max` and a value that is not
//! text, refuses a count over `max`, and its stream decoder frames it by its count field with
//! fields after it. Generated code is held to it in `codegen/tests/snapshots_compile.rs`.

#![cfg(feature = "tools")]

use std::borrow::Cow;
use std::path::Path;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn fixture() -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/text_counted.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

const INFO: [u8; 15] = [
    0x7E, 0x03, 0x21, 0x05, b'A', b'C', b'M', b'E', b'1', 0x00, 0x01, 0xE2, 0x40, 0x07, 0xB8,
];

fn value(name: &'static str, raw: Raw) -> Value<'static> {
    Value {
        name: Cow::Borrowed(name),
        raw,
    }
}

#[test]
fn counted_text_is_in_the_ir_as_text_framed_as_a_list_of_bytes() {
    let p = fixture();
    let m = p.message(p.find("device_info").unwrap());
    let f = m.fields.iter().find(|f| f.name == "name").unwrap();
    assert!(f.is_counted_text() && f.is_ascii() && !f.is_list());
    assert_eq!((f.width, f.repeat.as_ref().unwrap().max), (1, 16));
    assert!(p.generator_gaps().is_empty());
}

#[test]
fn decode_reads_text_and_the_fields_after_it() {
    let p = fixture();
    let frame = interp::decode(&p, Some(Direction::Response), None, &INFO).unwrap();
    let get = |n: &str| {
        frame
            .values
            .iter()
            .find(|v| v.name == n)
            .map(|v| v.raw.clone())
    };
    assert_eq!(get("name"), Some(Raw::Text(b"ACME1".to_vec())));
    assert_eq!(get("serial"), Some(Raw::Int(123_456)));
    assert_eq!(get("version"), Some(Raw::Int(7)));
    // Encoded back byte for byte, the count computed.
    let values: Vec<Value> = frame
        .values
        .iter()
        .filter(|v| v.name != "name_len")
        .cloned()
        .collect();
    assert_eq!(interp::encode(&p, frame.message, 3, &values).unwrap(), INFO);
}

#[test]
fn encode_refuses_text_too_long_and_values_that_are_not_text() {
    let p = fixture();
    let r = p.find("set_name").unwrap();
    let ok = interp::encode(
        &p,
        r,
        3,
        &[
            value("name", Raw::Text(b"pump-3".to_vec())),
            value("channel", Raw::Int(2)),
        ],
    )
    .unwrap();
    assert_eq!(
        ok,
        [0x7E, 0x03, 0x20, 0x06, b'p', b'u', b'm', b'p', b'-', b'3', 0x02, 0x21]
    );
    let long = interp::encode(
        &p,
        r,
        3,
        &[
            value("name", Raw::Text(vec![b'x'; 17])),
            value("channel", Raw::Int(2)),
        ],
    )
    .unwrap_err();
    assert_eq!(long.to_string(), "name takes 0..=16 elements, got 17");
    let list = interp::encode(
        &p,
        r,
        3,
        &[
            value("name", Raw::List(vec![65, 66])),
            value("channel", Raw::Int(2)),
        ],
    )
    .unwrap_err();
    assert_eq!(list.to_string(), "name takes text");
}

#[test]
fn a_count_over_max_is_refused() {
    let p = fixture();
    // name_len 17 > max 16: 17 characters and the fields after them.
    let mut wire = vec![0x7E, 0x03, 0x21, 17];
    wire.extend_from_slice(&[b'a'; 17]);
    wire.extend_from_slice(&[0, 0, 0, 1, 7, 0]);
    interp::reseal(&p, &mut wire);
    let err = interp::decode(&p, Some(Direction::Response), None, &wire).unwrap_err();
    // Longer than the spec's longest frame (payload max 24), refused before any field.
    assert_eq!(
        err.to_string(),
        "frame too long: 27 bytes, the longest frame has 26"
    );
}

#[test]
fn the_stream_frames_counted_text_by_its_count_field() {
    let p = fixture();
    let empty = [0x7E, 0x03, 0x20, 0x00, 0x05, 0x26];
    let capture = [&INFO[..], &empty[..], &INFO[..]].concat();
    for cut in 0..capture.len() {
        let mut s = StreamDecoder::new(&p, None);
        let mut events = s.push(&capture[..cut]);
        events.extend(s.push(&capture[cut..]));
        events.extend(s.flush());
        let frames: Vec<_> = events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                other => panic!("cut {cut}: {other:?}"),
            })
            .collect();
        assert_eq!(
            frames,
            [
                (0, "device_info".to_owned()),
                (15, "set_name".to_owned()),
                (21, "device_info".to_owned())
            ],
            "cut {cut}"
        );
    }
}
