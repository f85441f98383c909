//! The generated thermostat codec: every message round-trips, the documented frames decode to
//! what the document says, and code written once against `busspec_runtime::Protocol` works
//! with `Thermo` as it does with the built-in protocols.

use busspec_runtime::stream::{Direction, Event, StreamDecoder};
use busspec_runtime::{
    Ascii, CommandKind, DecodeError, FieldValue, FrameBuffer, Message, Protocol, ProtocolVisitor,
    ResponseMessage,
};
use own_protocol::thermo::{
    DeciCelsius, Humidity, Mode, NakReason, Request, Response, StatusBits, Thermo, MAX_FRAME_LEN,
};
use own_protocol::{with_protocol, PROTOCOLS};

/// Which variant a request is. No wildcard arm: a command added to the spec does not compile
/// here until the lists below cover it.
fn request_index(r: &Request) -> usize {
    match r {
        Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature) => 0,
        Request::SetSetpoint(_) => 1,
        Request::SetMode(_) => 2,
        Request::ReadStatus(own_protocol::thermo::request::ReadStatus) => 3,
    }
}
const REQUESTS: usize = 4;

fn response_index(r: &Response) -> usize {
    match r {
        Response::Temperature(_) => 0,
        Response::SetpointAck(_) => 1,
        Response::ModeAck(_) => 2,
        Response::Status(_) => 3,
        Response::Nak(_) => 4,
    }
}
const RESPONSES: usize = 5;

/// Every request, each field over its whole spec range (`set_mode`'s mode is limited to the
/// four listed modes; responses carry `Unknown` modes too).
fn requests() -> Vec<Request> {
    let mut all = vec![
        Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature),
        Request::ReadStatus(own_protocol::thermo::request::ReadStatus),
    ];
    all.extend((50..=350).map(|raw| {
        Request::SetSetpoint(own_protocol::thermo::request::SetSetpoint {
            setpoint: DeciCelsius::from_raw(raw),
        })
    }));
    all.extend((0..=3u8).map(|raw| {
        Request::SetMode(own_protocol::thermo::request::SetMode {
            mode: Mode::from_raw(raw),
        })
    }));
    all
}

/// What the spec's ranges forbid, encode refuses, naming the field and its range.
#[test]
fn values_outside_a_range_are_refused() {
    let mut buf = [0u8; MAX_FRAME_LEN];
    for raw in 4..=255u8 {
        let request = Request::SetMode(own_protocol::thermo::request::SetMode {
            mode: Mode::from_raw(raw),
        });
        assert_eq!(
            request.encode(0x01, &mut buf),
            Err(busspec_runtime::EncodeError::NotInRange {
                field: "mode",
                value: i64::from(raw),
                min: 0,
                max: 3,
                kind: busspec_runtime::NumKind::Int,
            })
        );
    }
}

/// Every response, each field over its whole wire range or spec range (the firmware string over
/// a few).
fn responses() -> Vec<Response> {
    let mut all = Vec::new();
    for measured in (-32768..=32767).step_by(97).chain([-32768, -1, 0, 32767]) {
        all.push(Response::Temperature(
            own_protocol::thermo::response::Temperature {
                measured: DeciCelsius::from_raw(measured),
                setpoint: DeciCelsius::from_raw(measured + 32768),
                humidity: Humidity::from_raw((measured & 0xFF) as u8 % 201),
            },
        ));
    }
    all.extend((0..=65535).step_by(13).map(|raw| {
        Response::SetpointAck(own_protocol::thermo::response::SetpointAck {
            setpoint: DeciCelsius::from_raw(raw),
        })
    }));
    for raw in 0..=255u8 {
        all.push(Response::ModeAck(own_protocol::thermo::response::ModeAck {
            mode: Mode::from_raw(raw),
        }));
        all.push(Response::Nak(own_protocol::thermo::response::Nak {
            reason: NakReason::from_raw(raw),
        }));
        all.push(Response::Status(own_protocol::thermo::response::Status {
            mode: Mode::from_raw(raw % 5),
            flags: StatusBits::from_raw(raw),
            firmware: Ascii(*[b"1.20", b"2.0b", b"    "][raw as usize % 3]),
        }));
    }
    all
}

#[test]
fn every_message_round_trips() {
    let mut seen_requests = [false; REQUESTS];
    let mut seen_responses = [false; RESPONSES];
    let mut buf = [0u8; MAX_FRAME_LEN];
    for address in [0x01, 0x20] {
        for request in requests() {
            seen_requests[request_index(&request)] = true;
            let n = request.encode(address, &mut buf).unwrap();
            assert_eq!(n, request.frame_len());
            let decoded = Request::decode(&buf[..n]).unwrap();
            assert_eq!((decoded.address, decoded.message), (address, request));
        }
        for response in responses() {
            seen_responses[response_index(&response)] = true;
            let n = response.encode(address, &mut buf).unwrap();
            assert_eq!(n, response.frame_len());
            let decoded = Response::decode(&buf[..n]).unwrap();
            assert_eq!((decoded.address, decoded.message), (address, response));
        }
    }
    assert_eq!(seen_requests, [true; REQUESTS]);
    assert_eq!(seen_responses, [true; RESPONSES]);
}

/// Frames of the spec's examples (wire bytes: the CRC travels low byte first, the document
/// prints it high byte first).
#[test]
fn documented_frames_decode_as_documented() {
    // §4.1: "21.5 °C measured, set point 22.0 °C, 45 % humidity", printed
    // `A5 01 90 00D7 00DC 5A 9366`.
    let request = Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature);
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = request.encode(0x01, &mut buf).unwrap();
    assert_eq!(&buf[..n], [0xA5, 0x01, 0x10, 0x61, 0xBF]);
    let frame = [0xA5, 0x01, 0x90, 0x00, 0xD7, 0x00, 0xDC, 0x5A, 0x66, 0x93];
    let reply = Response::decode_reply(&frame, &request).unwrap();
    assert_eq!(reply.address, 0x01);
    let Response::Temperature(own_protocol::thermo::response::Temperature {
        measured,
        setpoint,
        humidity,
    }) = reply.message
    else {
        panic!("not a temperature: {:?}", reply.message);
    };
    assert_eq!(measured.value(), 21.5);
    assert_eq!(setpoint.value(), 22.0);
    assert_eq!(humidity.value(), 45.0);
    assert_eq!(DeciCelsius::SYMBOL, "°C");
    let n = reply.message.encode(0x01, &mut buf).unwrap();
    assert_eq!(buf[..n], frame);

    // §4.1, frost: -5.0 °C travels as 0xFFCE.
    let frost = [0xA5, 0x02, 0x90, 0xFF, 0xCE, 0x00, 0x32, 0xB4, 0x8B, 0x37];
    let reply = Response::decode(&frost).unwrap();
    assert_eq!(
        reply.message,
        Response::Temperature(own_protocol::thermo::response::Temperature {
            measured: DeciCelsius::from_value(-5.0).unwrap(),
            setpoint: DeciCelsius::from_value(5.0).unwrap(),
            humidity: Humidity::from_value(90.0).unwrap(),
        })
    );

    // §4.4: status, heating, firmware "1.20".
    let status = [
        0xA5, 0x01, 0xB0, 0x01, 0x01, 0x31, 0x2E, 0x32, 0x30, 0xFA, 0x30,
    ];
    let reply = Response::decode_reply(
        &status,
        &Request::ReadStatus(own_protocol::thermo::request::ReadStatus),
    )
    .unwrap();
    assert_eq!(
        reply.message,
        Response::Status(own_protocol::thermo::response::Status {
            mode: Mode::Heat,
            flags: StatusBits::HEATING,
            firmware: Ascii(*b"1.20"),
        })
    );

    // §4.5: a set point out of range is refused.
    let nak = [0xA5, 0x01, 0xEE, 0x01, 0xFF, 0x48];
    let setpoint = Request::SetSetpoint(own_protocol::thermo::request::SetSetpoint {
        setpoint: DeciCelsius::from_value(22.5).unwrap(),
    });
    let reply = Response::decode_reply(&nak, &setpoint).unwrap();
    assert_eq!(
        reply.message,
        Response::Nak(own_protocol::thermo::response::Nak {
            reason: NakReason::OutOfRange
        })
    );
    assert!(reply.message.is_nak());
    // ... but is no answer to a read.
    assert_eq!(
        Response::decode_reply(
            &nak,
            &Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature)
        ),
        Err(DecodeError::NotAReply {
            message: "nak",
            request: "read_temperature",
            unasked: false
        })
    );

    // The CRC is checked: one flipped bit is a mismatch.
    let mut damaged = frame;
    damaged[4] ^= 0x01;
    assert!(matches!(
        Response::decode(&damaged),
        Err(DecodeError::ChecksumMismatch { offset: 8, .. })
    ));
}

/// What a transport, a logger or a test harness written once for every protocol does: it knows
/// nothing of thermostats, only the trait.
fn exercise<P: Protocol>(requests: &[P::Request], responses: &[P::Response]) -> usize {
    let mut buf = P::Buffer::ZERO;
    let mut capture = vec![0x00]; // noise first
    let mut frames = 0;
    for request in requests {
        let address = *P::BUS.device_addresses.start();
        let n = request.encode(address, buf.as_mut()).unwrap();
        let frame = &buf.as_ref()[..n];
        assert!(n <= P::MAX_REQUEST_LEN && P::FRAME_LENGTHS.contains(&n));
        assert!(P::checksum_ok(frame));
        assert_ne!(P::candidates(frame).requests, 0);
        let decoded = P::decode_request(frame).unwrap();
        assert_eq!(decoded.message, *request);
        capture.extend_from_slice(frame);
        frames += 1;
        for response in responses.iter().filter(|r| r.answers(request)) {
            let n = response.encode(address, buf.as_mut()).unwrap();
            let frame = &buf.as_ref()[..n];
            assert!(n <= P::MAX_RESPONSE_LEN && P::checksum_ok(frame));
            let reply = P::decode_reply(frame, request).unwrap();
            assert_eq!(reply.message, *response);
            assert_eq!(reply.message.name(), response.name());
            assert_eq!(reply.message.code(), response.code());
            frames += 1;
            // Send it after its request, then the request again for the next reply.
            capture.extend_from_slice(frame);
            capture.extend_from_slice(&{
                let mut b = P::Buffer::ZERO;
                let m = request.encode(address, b.as_mut()).unwrap();
                b.as_ref()[..m].to_vec()
            });
            frames += 1;
        }
    }
    // The stream decoder finds every frame again, in any chunking.
    for chunk in [1, 3, 64] {
        let mut stream = StreamDecoder::<P>::new(None);
        let mut found = 0;
        let mut skipped = 0;
        for part in capture.chunks(chunk) {
            for event in stream.feed(part) {
                match event {
                    Event::Request { .. } | Event::Response { .. } => found += 1,
                    Event::Skipped { len, .. } => skipped += len,
                    Event::Ambiguous { .. } | Event::OutOfSpec { .. } => {
                        panic!("{}: not a frame: {event:?}", P::NAME)
                    }
                }
            }
        }
        assert_eq!(stream.finish(), None, "{}: bytes left over", P::NAME);
        assert_eq!(
            (found, skipped),
            (frames, 1),
            "{} in chunks of {chunk}",
            P::NAME
        );
    }
    frames
}

#[test]
fn generic_code_works_with_the_thermostat() {
    let requests = [
        Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature),
        Request::SetSetpoint(own_protocol::thermo::request::SetSetpoint {
            setpoint: DeciCelsius::from_value(22.5).unwrap(),
        }),
        Request::SetMode(own_protocol::thermo::request::SetMode { mode: Mode::Auto }),
        Request::ReadStatus(own_protocol::thermo::request::ReadStatus),
    ];
    let responses = [
        Response::Temperature(own_protocol::thermo::response::Temperature {
            measured: DeciCelsius::from_value(-0.5).unwrap(),
            setpoint: DeciCelsius::from_value(20.0).unwrap(),
            humidity: Humidity::from_value(55.5).unwrap(),
        }),
        Response::SetpointAck(own_protocol::thermo::response::SetpointAck {
            setpoint: DeciCelsius::from_value(22.5).unwrap(),
        }),
        Response::ModeAck(own_protocol::thermo::response::ModeAck { mode: Mode::Auto }),
        Response::Status(own_protocol::thermo::response::Status {
            mode: Mode::Cool,
            flags: StatusBits::from_raw(0b1010),
            firmware: Ascii(*b"1.20"),
        }),
        Response::Nak(own_protocol::thermo::response::Nak {
            reason: NakReason::Busy,
        }),
    ];
    // 4 requests; set_setpoint and set_mode get an ack or the NAK, the reads one answer each.
    assert_eq!(exercise::<Thermo>(&requests, &responses), 4 + 2 * 6);
}

#[test]
fn the_protocol_constants_are_the_spec() {
    assert_eq!(Thermo::NAME, "thermo");
    assert_eq!(Thermo::SOURCE.revision, "1.2");
    assert_eq!(Thermo::BUS.baud, 9600);
    assert_eq!(Thermo::BUS.inter_frame_gap_ms, Some(5));
    assert_eq!(Thermo::BUS.device_addresses, 0x01..=0x20);
    assert_eq!(Thermo::BUS.broadcast_address, Some(0x00));
    // The frame lengths the stream decoder walks (its framing table, not a user's API).
    assert_eq!(
        <Thermo as busspec_runtime::Framing>::FRAME_LENGTHS,
        [11, 10, 7, 6, 5]
    );
    assert_eq!(Thermo::MAX_FRAME_LEN, 11);
    // The spec embedded is the one in this crate with the units it includes in place
    // (`spec/th_units.yaml`): one text that loads on its own.
    assert!(
        !Thermo::SOURCE.spec_yaml.contains("include"),
        "{}",
        Thermo::SOURCE.spec_yaml
    );
    for part in [
        "protocol: thermo",
        "name: deci_celsius",
        "name: humidity",
        "name: set_mode",
    ] {
        assert!(
            Thermo::SOURCE.spec_yaml.contains(part),
            "{part} in {}",
            Thermo::SOURCE.spec_yaml
        );
    }
    assert_eq!(Thermo::SOURCE.spec_sha256.len(), 64);
    let heat = Request::SetMode(own_protocol::thermo::request::SetMode { mode: Mode::Heat });
    assert_eq!(heat.command().kind, CommandKind::Setter);
    assert!(heat.command().broadcast.accepted && !heat.command().broadcast.answered);
    assert!(
        !Request::ReadStatus(own_protocol::thermo::request::ReadStatus)
            .command()
            .broadcast
            .accepted
    );
    let mut fields = Vec::new();
    heat.visit(|name, value| fields.push((name, value == FieldValue::Int(1))));
    assert_eq!(fields, [("mode", true)]);
}

#[test]
fn the_protocol_is_found_by_name() {
    struct Describe;
    impl ProtocolVisitor for Describe {
        type Output = (&'static str, usize, u32);
        fn visit<P: Protocol>(self) -> Self::Output {
            (P::NAME, P::MAX_FRAME_LEN, P::BUS.baud)
        }
    }
    assert_eq!(PROTOCOLS, ["thermo"]);
    assert_eq!(
        with_protocol("thermo", Describe),
        Some(("thermo", 11, 9600))
    );
    assert_eq!(with_protocol("ub2", Describe), None);
}

#[test]
fn a_sniffer_reads_both_directions() {
    // The §4.2 exchange with noise around it, as a sniffer on the bus sees it.
    let capture = [
        0xFF, 0xA5, 0x01, 0x20, 0x00, 0xE1, 0xA8, 0x67, 0xA5, 0x01, 0xA0, 0x00, 0xE1, 0xA9, 0x8F,
        0x00,
    ];
    let mut stream = own_protocol::thermo::StreamDecoder::new(None);
    let mut events: Vec<_> = stream.feed(&capture).collect();
    events.extend(std::iter::from_fn(|| stream.finish()));
    let setpoint = DeciCelsius::from_value(22.5).unwrap();
    assert!(matches!(events[..], [
        Event::Skipped { offset: 0, len: 1 },
        Event::Request { offset: 1, len: 7, frame },
        Event::Response { offset: 8, len: 7, frame: reply },
        Event::Skipped { offset: 15, len: 1 },
    ] if frame.message == Request::SetSetpoint(own_protocol::thermo::request::SetSetpoint { setpoint })
        && reply.message == Response::SetpointAck(own_protocol::thermo::response::SetpointAck { setpoint })));
    // Told to expect only responses, it skips the request.
    let mut stream = StreamDecoder::<Thermo>::new(Some(Direction::Response));
    let mut events: Vec<_> = stream.feed(&capture).collect();
    events.extend(std::iter::from_fn(|| stream.finish()));
    let frames: Vec<_> = events
        .iter()
        .filter(|e| !matches!(e, Event::Skipped { .. }))
        .collect();
    assert!(
        matches!(frames[..], [Event::Response { offset: 8, .. }]),
        "{events:?}"
    );
}
