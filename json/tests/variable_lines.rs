//! The JSON contract for protocols with repeated fields, through generated code: every example
//! of Modbus RTU and Dynamixel 1.0 prints the same line from the generated message
//! (`message_line`) as from the interpreter's frame (`frame_line`), the fields generated
//! messages do not carry (a byte count that counts a list, a byte count following a quantity)
//! included. The generated code is `busspec-protocols`' built-in `modbus` and `dynamixel`.

use busspec_protocols::{dynamixel, modbus, ResponseMessage};

use busspec_json::{frame_line, message_line};
use busspec_model::interp;
use busspec_model::ir::Direction;
use busspec_runtime::Protocol;

fn same_lines<P: Protocol>(file: &str) -> usize {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(file);
    let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    for e in &p.examples {
        let frame = interp::decode_as(&p, e.message, &e.wire).unwrap();
        let want = frame_line(&p, &frame, None);
        let got = match e.message.direction {
            Direction::Request => {
                let d = P::decode_request(&e.wire).unwrap();
                message_line(&p, Direction::Request, d.address, &d.message, None)
            }
            Direction::Response => {
                let d = P::Response::decode_as_reply(&e.wire, None).unwrap();
                message_line(&p, Direction::Response, d.address, &d.message, None)
            }
        }
        .unwrap();
        assert_eq!(got, want, "{file}: {}", p.message(e.message).name);
    }
    p.examples.len()
}

#[test]
fn modbus_lines_print_alike_from_generated_code_and_the_interpreter() {
    assert!(same_lines::<modbus::Modbus>("spec/modbus.yaml") > 10);
}

#[test]
fn dynamixel_lines_print_alike_from_generated_code_and_the_interpreter() {
    assert!(same_lines::<dynamixel::Dynamixel>("spec/dynamixel.yaml") > 5);
}

/// Every example's line parses back to the generated message it was printed from, and a line
/// whose byte count disagrees with its list is refused by both engines.
fn lines_parse_back<P: Protocol>(file: &str, count_field: &str) -> usize {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(file);
    let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    let mut lying = 0;
    for e in &p.examples {
        let frame = interp::decode_as(&p, e.message, &e.wire).unwrap();
        let line = frame_line(&p, &frame, None);
        let parsed = busspec_json::parse_line(&p, &line).unwrap();
        assert_eq!(parsed.encode(&p).unwrap(), e.wire, "{line}");
        match parsed.to_typed::<P>(&p).unwrap() {
            busspec_json::Typed::Request(d) => {
                assert_eq!(Ok(d), P::decode_request(&e.wire), "{line}")
            }
            busspec_json::Typed::Response(d) => {
                assert_eq!(Ok(d), P::Response::decode_as_reply(&e.wire, None), "{line}")
            }
        }
        let key = format!("\"{count_field}\":");
        let Some(at) = line.find(&key) else { continue };
        let rest = &line[at + key.len()..];
        let end = rest.find([',', '}']).unwrap();
        let n: i64 = rest[..end].parse().unwrap();
        let bad = format!("{}{key}{}{}", &line[..at], n + 1, &rest[end..]);
        let parsed = busspec_json::parse_line(&p, &bad).unwrap();
        assert!(parsed.encode(&p).is_err(), "{bad}");
        let refused = parsed.to_typed::<P>(&p).unwrap_err();
        assert!(refused.contains(count_field), "{bad}: {refused}");
        lying += 1;
    }
    lying
}

#[test]
fn modbus_lines_parse_back_and_a_lying_byte_count_is_refused() {
    assert_eq!(
        lines_parse_back::<modbus::Modbus>("spec/modbus.yaml", "byte_count"),
        6
    );
}

#[test]
fn dynamixel_lines_parse_back() {
    lines_parse_back::<dynamixel::Dynamixel>("spec/dynamixel.yaml", "none");
}
