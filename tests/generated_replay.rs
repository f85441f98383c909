//! The generated crate replays every example frame of both specs: it decodes each to the
//! message the spec names, at the right address, and re-encodes it into a buffer pre-filled with
//! 0xA5 (so a byte the encoder forgets to write shows up) to exactly the same bytes.

use busspec_model::ir::{Direction, Protocol};
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::{Decoded, Message, Protocol as Generated, ResponseMessage};

/// The spec `P`'s code was generated from.
fn spec<P: Generated>() -> Protocol {
    busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml).unwrap_or_else(|d| panic!("{d}"))
}

/// Replays every example of `P`'s spec through its generated code; returns how many.
fn replay<P: Generated>() -> usize {
    let p = spec::<P>();
    let file = P::NAME;
    let request_of = |cmd: usize| {
        let e = p
            .examples
            .iter()
            .find(|e| e.message.direction == Direction::Request && e.message.index == cmd)?;
        Some(
            P::decode_request(&e.wire)
                .expect("request example decodes")
                .message,
        )
    };
    for (i, e) in p.examples.iter().enumerate() {
        let m = p.message(e.message);
        let mut buf = vec![0xA5u8; P::MAX_FRAME_LEN + 8];
        let (name, address, n) = match e.message.direction {
            Direction::Request => {
                let d = P::decode_request(&e.wire)
                    .unwrap_or_else(|err| panic!("{file} example {i} §{}: {err}", e.section));
                (
                    d.message.name(),
                    d.address,
                    d.message.encode(d.address, &mut buf).unwrap(),
                )
            }
            Direction::Response => {
                let request = e.reply_to.and_then(request_of);
                let d = match (&request, m.needs_request) {
                    (Some(r), true) => P::decode_reply(&e.wire, r),
                    (None, true) => {
                        panic!("example {i}: a needs_request reply without its request's example")
                    }
                    (_, false) => P::decode_response(&e.wire),
                }
                .unwrap_or_else(|err| panic!("{file} example {i} §{}: {err}", e.section));
                if let Some(r) = &request {
                    assert!(d.message.answers(r), "example {i}: pairing");
                }
                (
                    d.message.name(),
                    d.address,
                    d.message.encode(d.address, &mut buf).unwrap(),
                )
            }
        };
        assert_eq!(name, m.name, "{file} example {i} §{}", e.section);
        // Both layouts put the address second: [start, address, ..] and [code, address, ..].
        assert_eq!(Some(&address), e.wire.get(1));
        assert_eq!(
            &buf[..n],
            &e.wire[..],
            "{file} example {i} §{} {}",
            e.section,
            m.name
        );
        assert!(
            buf[n..].iter().all(|&b| b == 0xA5),
            "encode wrote past the frame"
        );
    }
    p.examples.len()
}

#[test]
fn generated_ub2_replays_every_example() {
    assert!(replay::<Ub2>() >= 80);
}

#[test]
fn generated_sd_replays_every_example() {
    assert!(replay::<Sd>() >= 40);
}

#[test]
fn generated_errors_say_what_and_where() {
    use busspec_protocols::ub2::Response;
    // §6.1's reply, little-endian on the wire, with its checksum off by one.
    let bad = [0xAA, 0x21, 0x41, 0x01, 0x3E, 0x1F, 0x00, 0x00, 0x6B];
    assert_eq!(
        Response::decode(&bad).unwrap_err().to_string(),
        "checksum mismatch at offset 8: expected 0x6A, found 0x6B"
    );
    let mut good = bad;
    good[8] = 0x6A;
    let d = Response::decode(&good).unwrap();
    match d.message {
        Response::ActualCapacitance(busspec_protocols::ub2::response::ActualCapacitance {
            capacitance,
        }) => {
            assert!((capacitance.value() - 79.98).abs() < 1e-9)
        }
        other => panic!("decoded {other:?}"),
    }
    let mut small = [0u8; 4];
    assert_eq!(
        d.message.encode(0x21, &mut small).unwrap_err(),
        busspec_protocols::EncodeError::BufferTooSmall {
            needed: 9,
            available: 4
        }
    );
}

/// With the `serde` feature, every decoded example of `P` serializes and deserializes to
/// itself.
fn serde_round_trip<P: Generated>()
where
    Decoded<P::Request>: serde::Serialize + serde::de::DeserializeOwned,
    Decoded<P::Response>: serde::Serialize + serde::de::DeserializeOwned,
{
    let p = spec::<P>();
    let mut n = 0;
    for e in &p.examples {
        let json = match e.message.direction {
            Direction::Request => {
                let d = P::decode_request(&e.wire).unwrap();
                let json = serde_json::to_string(&d).unwrap();
                let back: Decoded<P::Request> = serde_json::from_str(&json).unwrap();
                assert_eq!(back, d, "{json}");
                json
            }
            Direction::Response => {
                let Ok(d) = P::decode_response(&e.wire) else {
                    continue;
                };
                let json = serde_json::to_string(&d).unwrap();
                let back: Decoded<P::Response> = serde_json::from_str(&json).unwrap();
                assert_eq!(back, d, "{json}");
                json
            }
        };
        assert!(
            json.contains(&format!("\"address\":{}", e.wire[1])),
            "{json}"
        );
        n += 1;
    }
    // Replies only their request identifies are skipped here; the replay above covers them.
    assert!(n * 4 >= p.examples.len() * 3, "{n} of {}", p.examples.len());
}

#[test]
fn decoded_messages_round_trip_through_serde() {
    serde_round_trip::<Ub2>();
    serde_round_trip::<Sd>();
}
