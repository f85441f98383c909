//! The JSON contract for repeated records through the interpreter: a record list prints as a
//! list of objects (units as physical values, enums by name), and `decode | encode` gives the
//! same bytes back; the fast printer prints what the reference printer does.

use busspec_json::{frame_line, parse_line, Printer};
use busspec_model::interp;

fn spec() -> busspec_json::Spec {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid/records.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn records_print_as_lists_of_objects_and_parse_back_to_the_same_bytes() {
    let p = spec();
    let e = &p.examples[0];
    let frame = interp::decode_as(&p, e.message, &e.wire).unwrap();
    let line = frame_line(&p, &frame, None);
    assert!(
        line.contains(r#""blocks":[{"id":1,"position":51.2,"mode":"velocity"},{"id":5,"position":102.3,"mode":"position"}]"#),
        "{line}"
    );
    let mut printed = Vec::new();
    Printer::new(&p).frame(&mut printed, &p, &frame, None);
    assert_eq!(String::from_utf8(printed).unwrap(), format!("{line}\n"));
    for e in &p.examples {
        let frame = interp::decode_as(&p, e.message, &e.wire).unwrap();
        let line = frame_line(&p, &frame, None);
        let parsed = parse_line(&p, &line).unwrap_or_else(|err| panic!("{line}: {err}"));
        assert_eq!(parsed.encode(&p).unwrap(), e.wire, "{line}");
    }
}

#[test]
fn a_record_missing_a_field_or_with_an_unknown_one_is_refused_by_name() {
    let p = spec();
    let e = &p.examples[0];
    let frame = interp::decode_as(&p, e.message, &e.wire).unwrap();
    let line = frame_line(&p, &frame, None);
    let missing = line.replace(r#""id":5,"#, "");
    let err = parse_line(&p, &missing).unwrap_err();
    assert!(err.contains("blocks[1].id: missing"), "{err}");
    let extra = line.replace(r#""id":5,"#, r#""id":5,"speed":3,"#);
    let err = parse_line(&p, &extra).unwrap_err();
    assert!(err.contains("no field `speed`"), "{err}");
    let out_of_range = line.replace(r#""id":5,"#, r#""id":0,"#);
    let err = parse_line(&p, &out_of_range)
        .unwrap()
        .encode(&p)
        .unwrap_err();
    assert!(err.contains("blocks.id"), "{err}");
}
