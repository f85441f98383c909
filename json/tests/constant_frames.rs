//! A constant whole frame (`frame:`, M-Bus's `E5`): its line names the message, with no address,
//! the empty code and no fields, from the reference printer and from [`Printer`] alike; the
//! line reads back and encodes to the same byte, with any address or none.

use busspec_json::{decode_frame, frame_line, parse_line, Printer, Spec};

fn spec() -> Spec {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid/mbus_short.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn the_constant_frames_line_reads_back_to_its_byte() {
    let p = spec();
    let f = decode_frame(&p, None, None, &[0xE5]).unwrap();
    let line = frame_line(&p, &f, None);
    assert_eq!(
        line,
        "{\"protocol\":\"mbus_short\",\"direction\":\"response\",\"code\":\"0x\",\"message\":\"ack\",\"fields\":{}}"
    );
    let mut out = Vec::new();
    Printer::new(&p).frame(&mut out, &p, &f, None);
    assert_eq!(std::str::from_utf8(&out).unwrap().trim_end(), line);
    assert_eq!(parse_line(&p, &line).unwrap().encode(&p).unwrap(), [0xE5]);
    // It carries no address: none, or any, gives the same byte.
    for l in [
        "{\"message\":\"ack\"}",
        "{\"message\":\"ack\",\"address\":254,\"fields\":{}}",
    ] {
        assert_eq!(
            parse_line(&p, l).unwrap().encode(&p).unwrap(),
            [0xE5],
            "{l}"
        );
    }
    // A field it does not have is refused; a framed message still needs its address.
    assert!(parse_line(&p, "{\"message\":\"ack\",\"fields\":{\"x\":1}}").is_err());
    assert_eq!(
        parse_line(&p, "{\"message\":\"status_of_link\"}").map(|_| ()),
        Err("missing field `address`".to_owned())
    );
    // Every example's line reads back to its frame.
    for e in &p.examples {
        let f = decode_frame(&p, Some(e.message.direction), None, &e.wire).unwrap();
        let line = frame_line(&p, &f, None);
        assert_eq!(
            parse_line(&p, &line).unwrap().encode(&p).unwrap(),
            e.wire,
            "{line}"
        );
    }
}
