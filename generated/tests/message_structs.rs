//! One struct per message (issue 26, point 1): each message of a generated module is a struct
//! in its direction's module (`modbus::request::ReadCoils`) with its constants (`NAME`, `CODE`,
//! `LEN` or `MIN_LEN`/`MAX_LEN`, the byte range of each field at a fixed offset), `visit` and
//! `encode`; `Request`/`Response` hold one of them. Held here to the frames the enums encode.

use busspec_protocols::modbus::{request, response, CoilState, Request, Response};
use busspec_protocols::sd;
use busspec_runtime::FieldValue;

#[test]
fn constants_say_what_the_spec_says() {
    assert_eq!(request::ReadCoils::NAME, "read_coils");
    assert_eq!(request::ReadCoils::CODE, [0x01]);
    assert_eq!(request::ReadCoils::LEN, 8);
    assert_eq!(request::ReadCoils::STARTING_ADDRESS, 2..4);
    assert_eq!(request::ReadCoils::QUANTITY, 4..6);
    assert_eq!(request::WriteMultipleRegisters::MIN_LEN, 11);
    assert_eq!(request::WriteMultipleRegisters::MAX_LEN, 255);
    assert_eq!(response::ReadCoilsException::CODE, [0x81]);
    assert_eq!(response::ReadCoilsException::EXCEPTION_CODE, 2..3);
    // A message without fields is a unit struct with the same constants.
    assert_eq!(
        sd::request::ReadActualPosition::NAME,
        "read_actual_position"
    );
    assert_eq!(sd::request::ReadActualPosition::LEN, 6);
    assert_eq!(sd::request::ReadActualPosition::CODE, [0x69]);
}

#[test]
fn each_range_holds_its_field_in_the_encoded_frame() {
    let m = request::WriteSingleCoil {
        output_address: 0x1234,
        output_value: CoilState::On,
    };
    let mut buf = [0u8; 8];
    let n = m.encode(0x11, &mut buf).unwrap();
    assert_eq!(n, request::WriteSingleCoil::LEN);
    assert_eq!(buf[request::WriteSingleCoil::OUTPUT_ADDRESS], [0x12, 0x34]);
    assert_eq!(buf[request::WriteSingleCoil::OUTPUT_VALUE], [0xFF, 0x00]);
    assert_eq!(buf[1..2], request::WriteSingleCoil::CODE[..]);
    let m = request::ReadHoldingRegisters {
        starting_address: 0xBEEF,
        quantity: 125,
    };
    m.encode(0x01, &mut buf).unwrap();
    assert_eq!(
        buf[request::ReadHoldingRegisters::STARTING_ADDRESS],
        [0xBE, 0xEF]
    );
    assert_eq!(buf[request::ReadHoldingRegisters::QUANTITY], [0x00, 125]);
}

#[test]
fn a_struct_encodes_and_visits_as_its_enum_does() {
    let m = request::ReadInputRegisters {
        starting_address: 7,
        quantity: 3,
    };
    let (mut a, mut b) = ([0u8; 8], [0u8; 8]);
    let n = m.encode(0x05, &mut a).unwrap();
    assert_eq!(Request::ReadInputRegisters(m).encode(0x05, &mut b), Ok(n));
    assert_eq!(a, b);
    // Its own refusals too: a quantity outside 1..=125.
    let bad = request::ReadInputRegisters {
        starting_address: 7,
        quantity: 126,
    };
    assert!(bad.encode(0x05, &mut a).is_err());
    let mut seen = Vec::new();
    m.visit(|name, v| {
        if let FieldValue::Int(i) = v {
            seen.push((name, i));
        }
    });
    assert_eq!(seen, [("starting_address", 7), ("quantity", 3)]);
    // Decode gives the struct back inside its variant.
    let d = Request::decode(&a[..n]).unwrap();
    assert_eq!(d.message, Request::ReadInputRegisters(m));
    let r = Response::decode(&[0x05, 0x84, 0x02, 0x83, 0x00]);
    assert!(matches!(
        r.map(|d| d.message),
        Ok(Response::ReadInputRegistersException(_))
    ));
}
