//! A protocol whose frames carry no address: its lines have no `"address"` key, from the
//! reference printer and from [`Printer`] alike; a line without one reads back and encodes to
//! the same bytes; a line may say address 0 and no other. A protocol with addresses still
//! needs one in every line.

use busspec_json::{decode_frame, frame_line, parse_line, Printer, Spec};

fn spec(file: &str) -> Spec {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid")
        .join(file);
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn lines_of_frames_without_an_address_have_no_address_and_read_back() {
    let p = spec("unaddressed.yaml");
    let printer = Printer::new(&p);
    assert!(p.examples.len() >= 5);
    for e in &p.examples {
        let f = decode_frame(&p, Some(e.message.direction), None, &e.wire).unwrap();
        let line = frame_line(&p, &f, None);
        assert!(!line.contains("\"address\""), "{line}");
        let mut out = Vec::new();
        printer.frame(&mut out, &p, &f, None);
        assert_eq!(std::str::from_utf8(&out).unwrap().trim_end(), line);
        let parsed = parse_line(&p, &line).unwrap();
        assert_eq!(parsed.address, 0);
        assert_eq!(parsed.encode(&p).unwrap(), e.wire, "{line}");
        // Address 0 may be given; no other.
        let zero = line.replacen(",\"code\"", ",\"address\":0,\"code\"", 1);
        assert_eq!(parse_line(&p, &zero).unwrap().encode(&p).unwrap(), e.wire);
        let three = line.replacen(",\"code\"", ",\"address\":3,\"code\"", 1);
        let err = parse_line(&p, &three).unwrap().encode(&p).unwrap_err();
        assert_eq!(
            err,
            "the protocol's frames carry no address: give address 0, not 0x03"
        );
    }
}

#[test]
fn a_line_of_a_protocol_with_addresses_must_give_one() {
    let p = spec("minimal.yaml");
    let e = &p.examples[0];
    let f = decode_frame(&p, Some(e.message.direction), None, &e.wire).unwrap();
    let line = frame_line(&p, &f, None);
    assert!(line.contains("\"address\":"), "{line}");
    let start = line.find(",\"address\":").unwrap();
    let end = start + line[start + 1..].find(',').unwrap() + 1;
    let without = format!("{}{}", &line[..start], &line[end..]);
    assert_eq!(
        parse_line(&p, &without).map(|_| ()),
        Err("missing field `address`".to_owned())
    );
}
