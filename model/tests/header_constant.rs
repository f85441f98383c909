//! Header fields whose value every frame holds (`value` in `framing.header`, fixture
//! `header_constant`): decoded, encoded and compared by `busspec diff`.

mod common;

use busspec_model::diff::Category::WireBreaking;
use busspec_model::interp;
use busspec_model::ir::Direction;

fn fixture() -> busspec_model::Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/valid/header_constant.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// Each message's copy of a constant header field holds its value, so a frame with another is
/// refused at that field; the sequence number, not constant, takes any value; an encoder writes
/// the constants without being given them.
#[test]
fn a_constant_header_field_is_checked_and_written() {
    let p = fixture();
    for m in p.commands.iter().chain(&p.responses) {
        let constants: Vec<(&str, Option<u64>)> = m
            .fields
            .iter()
            .take_while(|f| f.header)
            .map(|f| (f.name.as_str(), f.constant))
            .collect();
        assert_eq!(
            constants,
            [
                ("header_length", Some(0x0B)),
                ("sequence", None),
                ("reserved", Some(0x00))
            ],
            "{}",
            m.name
        );
    }
    let unlog = &p.examples[1].wire;
    let mut frame = unlog.clone();
    frame[4] = 0x77; // the sequence number's low byte: any value
    interp::reseal(&p, &mut frame);
    let d = interp::decode(&p, Some(Direction::Request), None, &frame).unwrap();
    assert_eq!(p.message(d.message).name, "unlog_all");
    frame[6] = 0x10; // the reserved byte
    interp::reseal(&p, &mut frame);
    let e = interp::decode(&p, Some(Direction::Request), None, &frame).unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid value for unlog_all.reserved at offset 6: expected 0x00, found 0x10"
    );
}

/// A constant header field's value changed, given or taken away is wire-breaking, said once
/// at the framing (not again for every message that carries it).
#[test]
fn a_constant_header_value_changed_breaks_the_wire_once() {
    let (old, changed) = common::revisions(
        "header_constant",
        &[("type: u8, value: 0x0B,", "type: u8, value: 0x0C,")],
    );
    let (_, any) = common::revisions(
        "header_constant",
        &[(
            "{name: reserved, type: u8, value: 0x00}",
            "{name: reserved, type: u8, unit: count}",
        )],
    );
    let kinds = |new: &busspec_model::Protocol| -> Vec<(String, &'static str, _, String)> {
        busspec_model::diff::diff(&old, new)
            .into_iter()
            .filter(|c| c.path != "examples")
            .map(|c| (c.path, c.kind, c.category, c.text))
            .collect()
    };
    assert_eq!(
        kinds(&changed),
        [(
            "framing.header.header_length".to_owned(),
            "header_field_changed",
            WireBreaking,
            "header field `header_length` holds 0x0B → 0x0C".to_owned()
        )]
    );
    assert_eq!(
        kinds(&any),
        [(
            "framing.header.reserved".to_owned(),
            "header_field_changed",
            WireBreaking,
            "header field `reserved` holds 0x00 → any value".to_owned()
        )]
    );
    assert!(busspec_model::diff::diff(&old, &old).is_empty());
}
