//! The generated crate replays every example frame of both specs: it decodes each to the
//! message the spec names, at the right address, and re-encodes it into a buffer pre-filled with
//! 0xA5 (so a byte the encoder forgets to write shows up) to exactly the same bytes.

use busspec_model::ir::{Direction, Protocol};
use busspec_model::load_file;

fn spec(name: &str) -> Protocol {
    load_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("spec")
            .join(name),
    )
    .unwrap_or_else(|d| panic!("{d}"))
}

macro_rules! replay {
    ($proto:ident, $file:literal) => {{
        use busspec_protocols::$proto::{Request, Response, MAX_FRAME_LEN};
        let p = spec($file);
        let request_of = |cmd: usize| {
            let e = p.examples.iter().find(|e| e.message.direction == Direction::Request && e.message.index == cmd)?;
            Some(Request::decode(&e.wire).expect("request example decodes").message)
        };
        for (i, e) in p.examples.iter().enumerate() {
            let m = p.message(e.message);
            let mut buf = [0xA5u8; MAX_FRAME_LEN + 8];
            let (name, address, n) = match e.message.direction {
                Direction::Request => {
                    let d = Request::decode(&e.wire).unwrap_or_else(|err| panic!("{} example {i} §{}: {err}", $file, e.section));
                    (d.message.name(), d.address, d.message.encode(d.address, &mut buf).unwrap())
                }
                Direction::Response => {
                    let request = e.reply_to.and_then(request_of);
                    let d = match (&request, m.needs_request) {
                        (Some(r), true) => Response::decode_reply(&e.wire, r),
                        (None, true) => panic!("example {i}: a needs_request reply without its request's example"),
                        (_, false) => Response::decode(&e.wire),
                    }
                    .unwrap_or_else(|err| panic!("{} example {i} §{}: {err}", $file, e.section));
                    if let Some(r) = &request {
                        assert!(d.message.answers(r), "example {i}: pairing");
                    }
                    (d.message.name(), d.address, d.message.encode(d.address, &mut buf).unwrap())
                }
            };
            assert_eq!(name, m.name, "{} example {i} §{}", $file, e.section);
            // Both layouts put the address second: [start, address, ..] and [code, address, ..].
            assert_eq!(Some(&address), e.wire.get(1));
            assert_eq!(&buf[..n], &e.wire[..], "{} example {i} §{} {}", $file, e.section, m.name);
            assert!(buf[n..].iter().all(|&b| b == 0xA5), "encode wrote past the frame");
        }
        p.examples.len()
    }};
}

#[test]
fn generated_ub2_replays_every_example() {
    assert!(replay!(ub2, "ub2.yaml") >= 80);
}

#[test]
fn generated_sd_replays_every_example() {
    assert!(replay!(sd, "sd.yaml") >= 40);
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
        Response::ActualCapacitance { capacitance } => {
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

/// With the `serde` feature, every decoded example serializes and deserializes to itself.
macro_rules! serde_round_trip {
    ($proto:ident, $file:literal) => {{
        use busspec_protocols::$proto::{Request, Response};
        let p = spec($file);
        let mut n = 0;
        for e in &p.examples {
            let json = match e.message.direction {
                Direction::Request => {
                    let d = Request::decode(&e.wire).unwrap();
                    let json = serde_json::to_string(&d).unwrap();
                    let back: busspec_protocols::Decoded<Request> =
                        serde_json::from_str(&json).unwrap();
                    assert_eq!(back, d, "{json}");
                    json
                }
                Direction::Response => {
                    let Ok(d) = Response::decode(&e.wire) else {
                        continue;
                    };
                    let json = serde_json::to_string(&d).unwrap();
                    let back: busspec_protocols::Decoded<Response> =
                        serde_json::from_str(&json).unwrap();
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
    }};
}

#[test]
fn decoded_messages_round_trip_through_serde() {
    serde_round_trip!(ub2, "ub2.yaml");
    serde_round_trip!(sd, "sd.yaml");
}
