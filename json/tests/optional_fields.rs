//! Optional fields (`present:`, fixture `optional_sensor`): an absent field is an absent key,
//! a present one its value as ever, from the reference printer and from [`Printer`] alike;
//! every line reads back and encodes to its frame, and a line whose keys disagree with the
//! condition is refused by encode.

use busspec_json::{decode_frame, frame_line, parse_line, Printer, Spec};

fn spec() -> Spec {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid/optional_sensor.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn absent_fields_are_absent_keys_and_lines_read_back_to_their_frames() {
    let p = spec();
    let mut lines = Vec::new();
    for e in &p.examples {
        let f = decode_frame(&p, Some(e.message.direction), None, &e.wire).unwrap();
        let line = frame_line(&p, &f, None);
        let mut out = Vec::new();
        Printer::new(&p).frame(&mut out, &p, &f, None);
        assert_eq!(std::str::from_utf8(&out).unwrap().trim_end(), line);
        assert_eq!(
            parse_line(&p, &line).unwrap().encode(&p).unwrap(),
            e.wire,
            "{line}"
        );
        lines.push(line);
    }
    let fields = |l: &str| l[l.find("\"fields\":").unwrap()..].to_owned();
    assert_eq!(
        fields(&lines[1]),
        "\"fields\":{\"status\":[],\"temperature\":21.5}}"
    );
    assert_eq!(
        fields(&lines[2]),
        "\"fields\":{\"status\":[\"has_humidity\"],\"temperature\":21.5,\"humidity\":45}}"
    );
    assert_eq!(fields(&lines[5]), "\"fields\":{\"kind\":\"stopped\"}}");
    // A key the condition leaves out, or one it needs missing: encode refuses.
    let extra =
        "{\"message\":\"event\",\"address\":1,\"fields\":{\"kind\":\"stopped\",\"detail\":3}}";
    assert_eq!(
        parse_line(&p, extra).unwrap().encode(&p).map(|_| ()),
        Err("value given for detail, which is present only when `kind` = 2".to_owned())
    );
    let missing = "{\"message\":\"event\",\"address\":1,\"fields\":{\"kind\":\"fault\"}}";
    assert_eq!(
        parse_line(&p, missing).unwrap().encode(&p).map(|_| ()),
        Err("no value given for field detail, which is present when `kind` = 2".to_owned())
    );
}
