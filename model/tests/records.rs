//! Repeated records (`type: record`) through the interpreter, its stream decoder, docs and
//! diff: `fixtures/valid/records.yaml` (records counted by a field with a field after them,
//! records counted in bytes, records to the end counted by the request; little-endian wire
//! printed big-endian).

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError, EncodeError, Raw, Value};
use busspec_model::ir::{Direction, FieldType, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::{load_file, load_str, Protocol};

fn path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/records.yaml")
}

fn records() -> Protocol {
    load_file(&path()).unwrap_or_else(|d| panic!("{d}"))
}

fn text() -> String {
    std::fs::read_to_string(path()).unwrap()
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn cmd(p: &Protocol, name: &str) -> MessageRef {
    p.find_in(name, Direction::Request).unwrap()
}

fn v(name: &str, raw: Raw) -> Value<'_> {
    Value {
        name: name.into(),
        raw,
    }
}

#[test]
fn a_record_resolves_to_fields_of_fixed_offsets_and_one_element_width() {
    let p = records();
    let m = p.message(cmd(&p, "sync_write"));
    let f = &m.fields[1];
    assert_eq!(f.ty, FieldType::Record);
    assert_eq!(f.width, 4);
    let names: Vec<(&str, usize, usize)> = f
        .record
        .iter()
        .map(|g| (g.name.as_str(), g.offset, g.width))
        .collect();
    assert_eq!(names, [("id", 0, 1), ("position", 1, 2), ("mode", 3, 1)]);
    assert!(f.record[2].enumeration.is_some());
    assert_eq!(f.record[0].range, Some((1, 252)));
    // Two blocks at most eight: the longest frame holds eight records.
    assert_eq!(m.max_len, m.layout.len + 8 * 4);
}

#[test]
fn records_decode_with_each_field_in_the_wire_byte_order() {
    let p = records();
    // Little-endian on the wire: 0x0200 travels 00 02.
    let wire = hex("7E 01 83 02 01 0002 00 05 FF03 01 07 7C");
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(f.message, cmd(&p, "sync_write"));
    assert_eq!(
        f.get("blocks"),
        Some(&Raw::Records(vec![vec![1, 0x200, 0], vec![5, 0x3FF, 1]]))
    );
    assert_eq!(f.get("flags"), Some(&Raw::Int(7)));
    // The example's printed (big-endian) text is these bytes.
    assert_eq!(p.examples[0].wire, wire);
}

#[test]
fn encode_writes_records_and_their_count_and_decode_reads_them_back() {
    let p = records();
    let r = cmd(&p, "write_pairs");
    let values = [v(
        "pairs",
        Raw::Records(vec![vec![0x10, -2, 1], vec![0x11, 5, 2]]),
    )];
    let wire = interp::encode(&p, r, 1, &values).unwrap();
    assert_eq!(wire, p.examples[1].wire);
    // The byte count (10) was computed from two 5-byte records.
    assert_eq!(wire[3], 10);
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(f.get("pairs"), Some(&values[0].raw));
}

#[test]
fn encode_refuses_records_out_of_range_of_the_wrong_shape_or_count() {
    let p = records();
    let r = cmd(&p, "sync_write");
    let enc = |recs: Vec<Vec<i64>>| {
        interp::encode(
            &p,
            r,
            1,
            &[v("blocks", Raw::Records(recs)), v("flags", Raw::Int(0))],
        )
    };
    assert_eq!(
        enc(vec![vec![0, 0, 0]]),
        Err(EncodeError::NotInRange {
            field: "blocks.id".into(),
            value: 0,
            min: 1,
            max: 252,
            kind: busspec_model::number::NumKind::Int,
        })
    );
    assert_eq!(
        enc(vec![vec![1, 0]]),
        Err(EncodeError::MissingValue {
            field: "blocks.mode".into()
        })
    );
    assert!(matches!(
        enc(vec![]),
        Err(EncodeError::WrongCount {
            min: 1,
            max: 8,
            found: 0,
            ..
        })
    ));
    assert!(matches!(
        enc(vec![vec![1, 0, 0]; 9]),
        Err(EncodeError::WrongCount { found: 9, .. })
    ));
    // A plain list is not a list of records.
    assert!(matches!(
        interp::encode(
            &p,
            r,
            1,
            &[
                v("blocks", Raw::List(vec![1, 2, 3])),
                v("flags", Raw::Int(0))
            ]
        ),
        Err(EncodeError::NotList { .. })
    ));
}

#[test]
fn a_record_field_out_of_its_range_is_refused_at_its_offset() {
    let p = records();
    // The second block's id is 0 (range 1..=252): offset 3 (payload) + 1 + 4 + 0 = 8.
    let mut wire = hex("7E 01 83 02 01 0002 00 00 FF03 01 07 00");
    interp::reseal(&p, &mut wire);
    let e = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap_err();
    let e2 = e.clone();
    match e {
        DecodeError::OutOfRange {
            field,
            offset,
            found,
            ..
        } => {
            assert_eq!((field.as_str(), offset, found), ("blocks.id", 8, 0));
        }
        other => panic!("{other}"),
    }
    // Lenient decoding still lists the records.
    let relaxed = busspec_model::stream::relaxed(&p);
    let (f, errors) =
        busspec_model::stream::decode_lenient(&p, &relaxed, Some(Direction::Request), None, &wire)
            .unwrap();
    assert!(matches!(f.get("blocks"), Some(Raw::Records(r)) if r.len() == 2));
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0], e2);
}

#[test]
fn records_to_the_end_follow_the_request_count() {
    let p = records();
    let req = interp::decode(&p, Some(Direction::Request), None, &hex("7E 01 85 02 86")).unwrap();
    let reply = &p.examples[3].wire;
    let f = interp::decode_reply(&p, &req, reply).unwrap();
    assert_eq!(
        f.get("readings"),
        Some(&Raw::Records(vec![vec![1, 256], vec![2, -200]]))
    );
    // Asked for three: two records do not answer it.
    let req3 = interp::decode(&p, Some(Direction::Request), None, &{
        let mut w = hex("7E 01 85 03 00");
        interp::reseal(&p, &mut w);
        w
    })
    .unwrap();
    assert!(matches!(
        interp::decode_reply(&p, &req3, reply),
        Err(DecodeError::BadCount { .. })
    ));
    // A reply whose bytes are not whole records is refused.
    let mut short = reply[..reply.len() - 2].to_vec();
    short.push(0);
    interp::reseal(&p, &mut short);
    assert!(interp::decode(&p, Some(Direction::Response), None, &short).is_err());
}

#[test]
fn the_stream_frames_records_by_count_times_width() {
    let p = records();
    let mut bytes = vec![0x00, 0x13];
    let mut frames = Vec::new();
    for e in p
        .examples
        .iter()
        .filter(|e| e.message.direction == Direction::Request)
    {
        bytes.extend_from_slice(&e.wire);
        bytes.push(0x55);
        frames.push(e.wire.clone());
    }
    for chunk in [1, 3, bytes.len()] {
        let mut s = StreamDecoder::new(&p, Some(Direction::Request));
        let mut got = Vec::new();
        for c in bytes.chunks(chunk) {
            got.extend(s.push(c));
        }
        got.extend(s.flush());
        let got: Vec<Vec<u8>> = got
            .into_iter()
            .filter_map(|e| match e {
                Event::Frame { bytes, .. } => Some(bytes),
                _ => None,
            })
            .collect();
        assert_eq!(got, frames, "chunks of {chunk}");
    }
}

#[test]
fn an_example_stating_a_wrong_record_value_is_refused() {
    let bad = text().replace("position: 102.3", "position: 102.4");
    let e = load_str("records.yaml", &bad).unwrap_err().to_string();
    assert!(e.contains("record 1: position"), "{e}");
    let bad = text().replace("{id: 1, position: 51.2", "{id: 1, speed: 51.2");
    let e = load_str("records.yaml", &bad).unwrap_err().to_string();
    assert!(e.contains("`speed`"), "{e}");
}

#[test]
fn docs_show_each_record_field_and_the_examples_records() {
    let p = records();
    let d = busspec_model::docs::render(&p, "records.yaml");
    assert!(d.contains("record[4]"), "{d}");
    assert!(d.contains("blocks.position"), "{d}");
    assert!(d.contains("{id: 1, position: 51.2, mode: velocity}"), "{d}");
}

#[test]
fn diff_says_changing_a_records_fields_breaks_the_wire() {
    let old = records();
    let widened = text().replace(
        "{name: id, type: u8, unit: count, range: {min: 1, max: 252}}",
        "{name: id, type: u16, unit: count, range: {min: 1, max: 252}}",
    );
    let widened = widened.replace(
        "7E 01 83 02 01 0200 00 05 03FF 01 07 7C",
        "7E 01 83 02 0001 0200 00 0005 03FF 01 07 7C",
    );
    let new = load_str("records.yaml", &widened).unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    assert!(
        changes.iter().any(
            |c| c.category == busspec_model::diff::Category::WireBreaking
                && c.path.contains("blocks")
        ),
        "{changes:#?}"
    );
    assert!(busspec_model::diff::diff(&old, &old).is_empty());
}

#[test]
fn diff_compares_each_record_field() {
    let old = records();
    let scaled = text().replace(
        "{name: id, type: u8, unit: count, range: {min: 1, max: 252}}",
        "{name: id, type: u8, unit: count, range: {min: 1, max: 200}}",
    );
    let new = load_str("records.yaml", &scaled).unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    assert!(
        changes.iter().any(|c| c.text.contains("blocks.id")),
        "{changes:#?}"
    );
    let renamed = text()
        .replace("{name: bank,", "{name: page,")
        .replace("bank: 1}", "page: 1}")
        .replace("bank: 2}", "page: 2}");
    let new = load_str("records.yaml", &renamed).unwrap_or_else(|d| panic!("{d}"));
    let changes = busspec_model::diff::diff(&old, &new);
    assert!(
        changes
            .iter()
            .any(|c| c.kind == "field_renamed" && c.text.contains("pairs.page")),
        "{changes:#?}"
    );
}

#[test]
fn a_device_space_refuses_a_record_list() {
    let spec = format!(
        "{}\ndevice:\n  spaces:\n    - {{name: table, type: u8, size: 16}}\n  commands:\n    - {{command: sync_write, writes: table, start: flags, from: blocks}}\n",
        text()
    );
    let e = load_str("records.yaml", &spec).unwrap_err().to_string();
    assert!(
        e.contains("`sync_write.blocks` is a repeated record; a space's elements are numbers"),
        "{e}"
    );
}
