//! Text up to a terminator (`repeat: {until: 0x00}`, fixture `text_terminated`): the
//! interpreter's rules, each with the frame that breaks it.
#![cfg(feature = "tools")]

use std::borrow::Cow;
use std::path::Path;

use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, Protocol};

fn fixture() -> Protocol {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/text_terminated.yaml");
    let text = std::fs::read_to_string(path).unwrap();
    busspec_model::load_str("text_terminated.yaml", &text).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn text(f: &interp::Frame, name: &str) -> Vec<u8> {
    match f.get(name) {
        Some(Raw::Text(t)) => t.clone(),
        other => panic!("{name}: {other:?}"),
    }
}

/// Two texts in one message, each up to its NUL, the fields after them where the texts put
/// them; the terminators are no characters.
#[test]
fn each_text_ends_at_its_terminator() {
    let p = fixture();
    let f = interp::decode(
        &p,
        Some(Direction::Response),
        None,
        &hex("C8 0E 2B 04 506F776572 00 6D57 00 00FA B0"),
    )
    .unwrap();
    assert_eq!(text(&f, "label"), b"Power");
    assert_eq!(text(&f, "unit"), b"mW");
    assert!(matches!(f.get("value"), Some(Raw::Int(250))));
}

/// No terminator among the bytes the frame's length leaves the text: refused, located.
#[test]
fn text_without_its_terminator_is_refused() {
    let p = fixture();
    let e = interp::decode(
        &p,
        Some(Direction::Request),
        None,
        &hex("C8 0A 2A 70756D702D33 01 02 2F"),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "set_name.name at offset 3: no terminator 0x00 in the 7 bytes the frame's length leaves it"
    );
}

/// The last text takes exactly what the frame's length leaves: a terminator before that is
/// refused (the bytes after it would belong to no field).
#[test]
fn the_last_text_ends_where_the_frame_leaves_it() {
    let p = fixture();
    let e = interp::decode(
        &p,
        Some(Direction::Request),
        None,
        &hex("C8 0B 2A 70756D702D33 00 02 00 2E"),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "set_name.name at offset 3: 6 elements, expected 7 by the frame's length"
    );
}

/// Encoding writes the characters and the terminator; text holding the terminator would end
/// early, and is refused.
#[test]
fn encode_writes_the_terminator_and_refuses_text_holding_it() {
    let p = fixture();
    let r = p.find("set_name").unwrap();
    let values = |t: &[u8]| {
        vec![
            Value {
                name: Cow::Borrowed("name"),
                raw: Raw::Text(t.to_vec()),
            },
            Value {
                name: Cow::Borrowed("channel"),
                raw: Raw::Int(2),
            },
        ]
    };
    assert_eq!(
        interp::encode(&p, r, 0, &values(b"pump-3")).unwrap(),
        hex("C8 0A 2A 70756D702D33 00 02 2E")
    );
    let e = interp::encode(&p, r, 0, &values(b"pu\0mp")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "name holds its terminator 0x00 (character 2), which would end it there"
    );
}

/// A terminator other than NUL, and the frame's shortest and longest lengths: the terminator
/// is counted.
#[test]
fn another_terminator_and_the_lengths_count_it() {
    let p = fixture();
    let r = p.find("set_name").unwrap();
    let m = p.message(r);
    // Start, length, code, NUL, channel, checksum: 6 bytes with no characters; 16 more at most.
    assert_eq!((m.min_len(), m.max_len), (6, 22));
    let yaml = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/text_terminated.yaml"),
    )
    .unwrap();
    let head = &yaml[..yaml.find("examples:").unwrap()];
    let semi = format!(
        "{}examples: []\nerrata: []\n",
        head.replacen(
            "repeat: {until: 0x00, max: 16}",
            "repeat: {until: 0x3B, max: 16}",
            1
        )
    );
    let p = busspec_model::load_str("semi.yaml", &semi).unwrap_or_else(|d| panic!("{d}"));
    let wire = interp::encode(
        &p,
        r,
        0,
        &[
            Value {
                name: Cow::Borrowed("name"),
                raw: Raw::Text(b"a\0b".to_vec()),
            },
            Value {
                name: Cow::Borrowed("channel"),
                raw: Raw::Int(1),
            },
        ],
    )
    .unwrap();
    assert_eq!(&wire[3..8], &[b'a', 0, b'b', 0x3B, 1]);
    let f = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap();
    assert_eq!(text(&f, "name"), b"a\0b");
}
