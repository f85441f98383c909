//! The two public protocols with repeated fields, Modbus RTU and Dynamixel 1.0, generated
//! (`snapshots/modbus.rs`, `snapshots/dynamixel.rs`, kept current by `snapshots.rs`): they
//! compile, replay every example, and agree with the interpreter on every example, on frames
//! mutated from them (bytes changed, counts and length bytes that lie, frames cut and
//! lengthened) and on lists of every length encoded from the examples' values.

include!("snapshots/modbus.rs");
include!("snapshots/dynamixel.rs");

mod agree;

use busspec_runtime::{DecodeError, EncodeError, Repeated};

#[test]
fn modbus_replays_and_agrees_with_the_interpreter() {
    // Every example decodes in both engines and encodes back to its bytes (`agree::check`).
    let p = agree::fixture("spec/modbus.yaml");
    let t = agree::agree::<modbus::Modbus>(&p);
    eprintln!("modbus: {t:?}");
    assert!(t.accepted >= p.examples.len() && t.refused > 1000, "{t:?}");
    assert!(t.encoded > 20 && t.encode_refused > 20, "{t:?}");
}

#[test]
fn dynamixel_replays_and_agrees_with_the_interpreter() {
    let p = agree::fixture("spec/dynamixel.yaml");
    let t = agree::agree::<dynamixel::Dynamixel>(&p);
    eprintln!("dynamixel: {t:?}");
    assert!(t.accepted >= p.examples.len() && t.refused > 500, "{t:?}");
    assert!(t.encoded > 10 && t.encode_refused > 10, "{t:?}");
}

/// Coils travel packed: Modbus application protocol 6.1's reply (coils 20..=38, CD 6B 05), and
/// the reply's byte count follows the request's quantity (checked by `decode_reply`), computed
/// by encode from the list.
#[test]
fn modbus_coils_and_registers() {
    let p = agree::fixture("spec/modbus.yaml");
    let wire = |name: &str| {
        p.examples
            .iter()
            .find(|e| p.message(e.message).name == name)
            .unwrap()
            .wire
            .clone()
    };
    let read = modbus::Request::decode(&wire("read_coils"))
        .unwrap()
        .message;
    let reply = modbus::Response::decode_reply(&wire("read_coils_reply"), &read)
        .unwrap()
        .message;
    let modbus::Response::ReadCoilsReply(modbus::response::ReadCoilsReply { coils }) = reply else {
        panic!("{reply:?}")
    };
    assert_eq!(coils.as_bytes(), &[0xCD, 0x6B, 0x05]);
    assert_eq!(coils.len(), 24);
    assert_eq!(coils.get(0), Some(true));
    assert_eq!(coils.get(1), Some(false));
    // A request for 25 coils is answered with 4 bytes, not 3.
    let more = modbus::Request::ReadCoils(modbus::request::ReadCoils {
        starting_address: 19,
        quantity: 25,
    });
    assert!(matches!(
        modbus::Response::decode_reply(&wire("read_coils_reply"), &more),
        Err(DecodeError::NotFollowing {
            field: busspec_runtime::FieldDesc {
                message: "read_coils_reply",
                name: "byte_count",
            },
            offset: 2,
            expected: 4,
            found: 3,
            ..
        })
    ));
    assert!(!reply.answers(&more) && reply.answers(&read));
    // Registers: 555, 0, 100 (6.3), and 126 are more than the 125 the spec allows.
    let registers = Repeated::from_slice(&[555u16, 0, 100]).unwrap();
    let r =
        modbus::Response::ReadHoldingRegistersReply(modbus::response::ReadHoldingRegistersReply {
            registers,
        });
    let mut buf = [0u8; modbus::MAX_FRAME_LEN];
    let n = r.encode(0x11, &mut buf).unwrap();
    assert_eq!(&buf[..n], &wire("read_holding_registers_reply")[..]);
    assert_eq!(r.frame_len(), n);
    let w = modbus::Request::WriteMultipleRegisters(modbus::request::WriteMultipleRegisters {
        starting_address: 1,
        quantity: 2,
        values: Repeated::from_slice(&[10, 258]).unwrap(),
    });
    let n = w.encode(0x11, &mut buf).unwrap();
    assert_eq!(&buf[1..11], &[0x10, 0, 1, 0, 2, 4, 0, 10, 1, 2]);
    assert_eq!(modbus::Request::decode(&buf[..n]).unwrap().message, w);
    let wrong = modbus::Request::WriteMultipleRegisters(modbus::request::WriteMultipleRegisters {
        starting_address: 1,
        quantity: 3,
        values: Repeated::from_slice(&[10, 258]).unwrap(),
    });
    assert!(matches!(
        wrong.encode(0x11, &mut buf),
        Err(EncodeError::WrongCount {
            field: "values",
            min: 3,
            max: 3,
            found: 2,
        })
    ));
}

/// The status packet has no code and a length byte: a read's reply carries as many bytes as
/// asked, and a length byte that lies is refused.
#[test]
fn dynamixel_status_and_length_byte() {
    let read = dynamixel::Request::Read(dynamixel::request::Read {
        address: 0x2B,
        length: 1,
    });
    let status = [0xFF, 0xFF, 0x01, 0x03, 0x00, 0x20, 0xDB];
    let d = dynamixel::Response::decode_reply(&status, &read).unwrap();
    let dynamixel::Response::ReadStatus(dynamixel::response::ReadStatus { data, .. }) = d.message
    else {
        panic!("{d:?}")
    };
    assert_eq!(data.as_slice(), &[0x20]);
    let two = dynamixel::Request::Read(dynamixel::request::Read {
        address: 0x2B,
        length: 2,
    });
    assert!(matches!(
        dynamixel::Response::decode_reply(&status, &two),
        Err(DecodeError::BadCount {
            field: busspec_runtime::FieldDesc { name: "data", .. },
            ..
        })
    ));
    let mut lying = status;
    lying[3] = 4;
    lying[6] = !(1u8 + 4 + 0x20);
    assert_eq!(
        dynamixel::Response::decode(&lying),
        Err(DecodeError::LengthMismatch {
            offset: 3,
            expected: 3,
            found: 4
        })
    );
    let w = dynamixel::Request::Write(dynamixel::request::Write {
        address: 30,
        data: Repeated::from_slice(&[0xF4, 0x01]).unwrap(),
    });
    let mut buf = [0u8; dynamixel::MAX_FRAME_LEN];
    let n = w.encode(1, &mut buf).unwrap();
    assert_eq!(&buf[..n], &[0xFF, 0xFF, 1, 5, 3, 30, 0xF4, 0x01, 0xE3]);
}

crate::views!(modbus::Modbus, modbus, request, response);
crate::views!(dynamixel::Dynamixel, dynamixel, request, response);

/// The borrowed views (`RequestView`/`ResponseView`) are made of exactly the frames the owned
/// decode accepts, refuse the others with its error, and hold its values: every example, its
/// mutations and random frames near it.
#[test]
fn modbus_and_dynamixel_views_agree_with_the_owned_decode() {
    let p = agree::fixture("spec/modbus.yaml");
    let (made, refused) = agree::views_agree::<modbus::Modbus>(&p, 400);
    eprintln!("modbus views: {made} made, {refused} refused");
    assert!(
        made > 2 * p.examples.len() && refused > 2000,
        "{made} {refused}"
    );
    let p = agree::fixture("spec/dynamixel.yaml");
    let (made, refused) = agree::views_agree::<dynamixel::Dynamixel>(&p, 400);
    eprintln!("dynamixel views: {made} made, {refused} refused");
    assert!(
        made > 2 * p.examples.len() && refused > 1000,
        "{made} {refused}"
    );
}

/// A view lends the registers where the frame holds them, and reads each as the owned list
/// holds it.
#[test]
fn a_modbus_view_lends_its_registers_in_place() {
    let p = agree::fixture("spec/modbus.yaml");
    let e = p
        .examples
        .iter()
        .find(|e| p.message(e.message).name == "read_holding_registers_reply")
        .unwrap();
    let owned = modbus::Response::decode(&e.wire).unwrap().message;
    let view = modbus::ResponseView::decode(&e.wire).unwrap().message;
    let (
        modbus::Response::ReadHoldingRegistersReply(modbus::response::ReadHoldingRegistersReply {
            registers: o,
        }),
        modbus::ResponseView::ReadHoldingRegistersReply { registers: v },
    ) = (owned, view)
    else {
        panic!("{owned:?} / {view:?}");
    };
    assert!(!o.is_empty());
    assert_eq!(v.len(), o.len());
    assert_eq!(v.as_bytes().as_ptr(), e.wire[3..].as_ptr());
    assert!(v.iter().eq(o.iter().copied()));
    for (i, r) in o.iter().enumerate() {
        assert_eq!(v.get(i), Some(*r));
    }
    assert_eq!(v.get(o.len()), None);
    assert_eq!(view.to_owned(), owned);
    assert_eq!(view.name(), "read_holding_registers_reply");
}
