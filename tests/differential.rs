//! The generated crate against the interpreter, its independent oracle: on every example, on
//! random inputs (noise, mutated examples with and without a repaired checksum, well-formed
//! frames of every message with random contents), and exhaustively over small domains. Both
//! must accept and reject the same frames and, where they accept, decode the same message, the
//! same address and the same value for every field; the generated encoder must write every
//! accepted frame back byte for byte. No decoder may panic on any of it.
//!
//! `BUSSPEC_RANDOM_INPUTS` sets the number of random inputs per protocol (default 500,000, so
//! at least a million across the two).

mod common;

use busspec_model::ir::Direction;
use busspec_protocols::crsf::Crsf;
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::dynamixel2::Dynamixel2;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;
use common::{agree, random_input, spec};

fn random_inputs() -> usize {
    std::env::var("BUSSPEC_RANDOM_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(500_000)
}

fn every_example<P: Protocol>() {
    let p = spec::<P>();
    for e in &p.examples {
        let reply_to = if p.message(e.message).needs_request {
            e.reply_to
        } else {
            None
        };
        assert!(
            agree::<P>(&p, &e.wire, e.message.direction, reply_to),
            "{} example §{} does not decode",
            P::NAME,
            e.section
        );
    }
}

fn random<P: Protocol>(seed: u64) -> (usize, usize) {
    let p = spec::<P>();
    let mut rng = fastrand::Rng::with_seed(seed);
    let (mut accepted, n) = (0, random_inputs());
    for _ in 0..n {
        let frame = random_input(&p, &mut rng);
        let reply_to = rng.bool().then(|| rng.usize(..p.commands.len()));
        for d in [Direction::Request, Direction::Response] {
            accepted += usize::from(agree::<P>(&p, &frame, d, None));
        }
        if reply_to.is_some() {
            agree::<P>(&p, &frame, Direction::Response, reply_to);
        }
    }
    (accepted, n)
}

#[test]
fn ub2_generated_and_interpreter_agree_on_every_example() {
    every_example::<Ub2>();
}

#[test]
fn sd_generated_and_interpreter_agree_on_every_example() {
    every_example::<Sd>();
}

#[test]
fn ub2_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Ub2>(0x0B2);
    // The inputs must reach past the checksum into field decoding, or this proves little.
    assert!(
        accepted * 8 > n,
        "only {accepted} of {n} random UB2 inputs decoded"
    );
}

#[test]
fn sd_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Sd>(0x5D);
    assert!(
        accepted * 8 > n,
        "only {accepted} of {n} random SD inputs decoded"
    );
}

#[test]
fn modbus_generated_and_interpreter_agree_on_every_example() {
    every_example::<Modbus>();
}

#[test]
fn dynamixel_generated_and_interpreter_agree_on_every_example() {
    every_example::<Dynamixel>();
}

#[test]
fn modbus_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Modbus>(0x3B);
    assert!(
        accepted * 8 > n,
        "only {accepted} of {n} random Modbus inputs decoded"
    );
}

#[test]
fn dynamixel_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Dynamixel>(0xD1);
    assert!(
        accepted * 8 > n,
        "only {accepted} of {n} random Dynamixel inputs decoded"
    );
}

/// CRSF: its packed RC channels, telemetry and extended frames, both engines alike.
#[test]
fn crsf_generated_and_interpreter_agree_on_every_example() {
    every_example::<Crsf>();
}

#[test]
fn crsf_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Crsf>(0xC5);
    assert!(
        accepted * 8 > n,
        "only {accepted} of {n} random CRSF inputs decoded"
    );
}

/// Dynamixel 2.0: byte stuffing, CRC-16, SYNC_WRITE's records whose width `data_length`
/// gives, the status packets only their request tells apart; both engines alike.
#[test]
fn dynamixel2_generated_and_interpreter_agree_on_every_example() {
    every_example::<Dynamixel2>();
}

#[test]
fn dynamixel2_generated_and_interpreter_agree_on_random_inputs() {
    let (accepted, n) = random::<Dynamixel2>(0xD2);
    // Fewer decode than elsewhere (19,371 of 500,000 at this seed): a status packet of 2 to 5
    // parameter bytes is ambiguous without its request, a SYNC_WRITE's random data length is
    // rarely 1 to 4, and a random parameter FF FF FD is an unstuffed escape. Every one of them
    // is still held to the interpreter (refused alike).
    assert!(
        accepted * 40 > n,
        "only {accepted} of {n} random Dynamixel 2.0 inputs decoded"
    );
}

/// CRSF's telemetry is sent unasked on the receiver-to-flight-controller link (`unasked:
/// true`): the generated code says so of each telemetry frame, and a telemetry frame heard
/// after a device ping is refused as its reply in the same words by both engines, as sent
/// unasked. The module's answers only in the handset's slot (device information, timing
/// correction) are not.
#[test]
fn crsf_telemetry_is_sent_unasked_in_both_engines() {
    let p = spec::<Crsf>();
    let wire_of = |name: &str| {
        p.examples
            .iter()
            .find(|e| p.message(e.message).name == name)
            .unwrap_or_else(|| panic!("an example of {name}"))
            .wire
            .clone()
    };
    let mut unasked = Vec::new();
    for m in &p.responses {
        let d = Crsf::decode_response(&wire_of(&m.name)).unwrap();
        assert_eq!(d.message.name(), m.name);
        assert_eq!(d.message.is_unasked(), m.unasked, "{}", m.name);
        if m.unasked {
            unasked.push(m.name.as_str());
        }
    }
    assert_eq!(
        unasked,
        [
            "gps",
            "battery_sensor",
            "heartbeat",
            "link_statistics",
            "attitude",
            "flight_mode"
        ]
    );
    let ping = wire_of("device_ping");
    let stats = wire_of("link_statistics");
    let generated = Crsf::decode_reply_to(&stats, &ping).unwrap_err();
    let request = busspec_model::interp::decode(&p, Some(Direction::Request), None, &ping).unwrap();
    let interpreted = busspec_model::interp::decode_reply(&p, &request, &stats).unwrap_err();
    assert_eq!(generated.to_string(), interpreted.to_string());
    assert_eq!(
        generated.to_string(),
        "link_statistics is sent unasked, not a reply device_ping gets"
    );
}
