//! The generated `StreamDecoder` of protocols with variable-length frames, Modbus RTU (counted
//! by a byte-count field) and Dynamixel 1.0 (a length byte), against the interpreter's
//! (`busspec_model::stream`), as `generated_stream.rs` holds UB2 and SD: captures of example
//! frames mixed with noise, cut-short frames and frames whose count or length byte lies (with
//! a good checksum or not), pushed in random chunks: both report the same events at the same
//! offsets with the same values, and every byte is accounted for once.
//!
//! The generated code is `busspec-protocols`' built-in `modbus` and `dynamixel`.

use busspec_protocols::{dynamixel, modbus};

use busspec_fuzz_bodies::events::{chunks, covers, interp_events, Seen};
use busspec_fuzz_bodies::{seen, spec, stream_events};
use busspec_model::checksum;
use busspec_model::interp;
use busspec_model::ir::{Direction, Protocol as Spec};
use busspec_runtime::Protocol;

/// `frame` with the checksum of its bytes before it.
fn reseal(p: &Spec, frame: &mut [u8]) {
    let c = &p.framing.checksum;
    let at = frame.len() - c.len();
    let v = checksum::compute(&c.algorithm, frame.get(c.covers_from..at).unwrap_or(&[]));
    interp::write_uint(v, &mut frame[at..], c.byte_order);
}

/// An example frame whose length byte, or whose count field, says a little more or less than
/// the frame holds (sometimes resealed, so only the count or length gives it away).
fn lying(p: &Spec, rng: &mut fastrand::Rng, wire: &[u8], d: Direction) -> Vec<u8> {
    let mut f = wire.to_vec();
    let at = match p.framing.length_rule(d) {
        Some(rule) => Some(rule.at),
        None => p
            .messages(d)
            .iter()
            .find(|m| interp::fits_len(p, m, wire) && m.count_field().is_some())
            .and_then(|m| {
                let c = &m.fields[m.count_field()?];
                Some(m.layout.payload + c.offset + c.width - 1)
            }),
    };
    if let Some(at) = at {
        let delta = [1u8, 2, 0xFF, 0xFE, 0x80][rng.usize(..5)];
        f[at] = f[at].wrapping_add(delta);
        if rng.bool() {
            reseal(p, &mut f);
        }
    }
    f
}

/// A capture: example frames in random order, with noise bursts, cut-short frames and lying
/// frames between.
fn capture(p: &Spec, rng: &mut fastrand::Rng, frames: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for _ in 0..frames {
        let e = &p.examples[rng.usize(..p.examples.len())];
        match rng.u8(..12) {
            0 => out.extend((0..rng.usize(1..6)).map(|_| rng.u8(..))),
            1 => out.extend_from_slice(&e.wire[..rng.usize(1..e.wire.len())]),
            2 | 3 => out.extend(lying(p, rng, &e.wire, e.message.direction)),
            _ => {}
        }
        out.extend_from_slice(&e.wire);
    }
    out
}

/// `P`'s generated stream decoder agrees with the interpreter's on random captures of its
/// examples, however they are cut, and accounts for every byte; returns the frames found and
/// the bytes skipped.
fn stream_agrees<P: Protocol>(seed: u64) -> (usize, u64) {
    let p = spec::<P>();
    let mut rng = fastrand::Rng::with_seed(seed);
    let (mut frames, mut skipped) = (0, 0);
    for _ in 0..200 {
        let cap = capture(p, &mut rng, 30);
        let cuts = chunks(rng.u8(..), cap.len(), 24);
        let want = interp_events(p, None, &cap, &cuts);
        let got = seen::<P>(&stream_events::<P>(None, &cap, &cuts));
        assert_eq!(got, want, "capture {}", interp::format_hex(&cap));
        assert_eq!(seen::<P>(&stream_events::<P>(None, &cap, &[])), got);
        covers(&got, cap.len() as u64);
        for e in &got {
            match e {
                // Dynamixel's code-less status packets also read as requests: with no direction
                // given, a frame both ways is ambiguous.
                Seen::Frame { .. } | Seen::Ambiguous { .. } => frames += 1,
                Seen::Skipped { len, .. } => skipped += len,
                _ => {}
            }
        }
    }
    (frames, skipped)
}

#[test]
fn modbus_generated_stream_matches_the_interpreter() {
    let (frames, skipped) = stream_agrees::<modbus::Modbus>(21);
    assert!(frames > 200 * 25 && skipped > 1000, "{frames} {skipped}");
}

#[test]
fn dynamixel_generated_stream_matches_the_interpreter() {
    let (frames, skipped) = stream_agrees::<dynamixel::Dynamixel>(22);
    assert!(frames > 200 * 25 && skipped > 1000, "{frames} {skipped}");
}

/// Where `P`'s stream decoder finds responses in `cap` (offset, length), read as responses.
fn responses<P: Protocol>(cap: &[u8]) -> Vec<(u64, usize)> {
    let direction = Some(busspec_runtime::stream::Direction::Response);
    stream_events::<P>(direction, cap, &[])
        .iter()
        .filter_map(|e| match e {
            busspec_runtime::stream::Event::Response { offset, len, .. } => Some((*offset, *len)),
            _ => None,
        })
        .collect()
}

/// A Dynamixel length byte that lies drops one byte, and the frame behind it is found whole;
/// Modbus's register reply whose byte count says more than the frame holds likewise.
#[test]
fn a_lying_length_resynchronises() {
    let status = [0xFF, 0xFF, 0x01, 0x03, 0x00, 0x20, 0xDB];
    let mut lie = status;
    lie[3] = 0x09;
    let mut cap = lie.to_vec();
    cap.extend_from_slice(&status);
    assert_eq!(
        responses::<dynamixel::Dynamixel>(&cap),
        [(7, 7)],
        "{cap:02X?}"
    );
    let p = spec::<modbus::Modbus>();
    let reply = &p
        .examples
        .iter()
        .find(|e| p.message(e.message).name == "read_holding_registers_reply")
        .unwrap()
        .wire;
    let mut lie = reply.clone();
    lie[2] = 0x08;
    let mut cap = lie.clone();
    cap.extend_from_slice(reply);
    assert_eq!(responses::<modbus::Modbus>(&cap), [(11, 11)], "{cap:02X?}");
}

/// A frame that reads both as a request and as a response: a Modbus read_coils request whose
/// starting address has the high byte 0x03 is also a read_coils_reply with 3 bytes of coils
/// (same code, same length, good CRC). Alone, after a read_coils request it could answer, and
/// after one it could not: both stream decoders report it as ambiguous (the rule in their
/// module docs: pairing never decides a frame's direction). The interpreter's took it for the
/// reply after a read_coils request, the generated one for ambiguous.
#[test]
fn a_frame_of_both_directions_is_reported_alike_after_any_request() {
    let p = spec::<modbus::Modbus>();
    let frame = |bytes: &[u8]| {
        let mut f = bytes.to_vec();
        f.extend_from_slice(&[0, 0]);
        reseal(p, &mut f);
        f
    };
    // read_coils 0x0313, quantity 0x0011 (17 coils, 3 bytes of reply): also a reply 03 13 00 11.
    let both = frame(&[0x11, 0x01, 0x03, 0x13, 0x00, 0x11]);
    assert!(modbus::Modbus::decode_request(&both).is_ok());
    assert!(modbus::Modbus::decode_response(&both).is_ok());
    let asks_3_bytes = frame(&[0x11, 0x01, 0x00, 0x13, 0x00, 0x13]);
    let asks_1_byte = frame(&[0x11, 0x01, 0x00, 0x13, 0x00, 0x05]);
    let read_registers = frame(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03]);
    for before in [&[][..], &asks_3_bytes, &asks_1_byte, &read_registers, &both] {
        let cap = [before, &both[..], &both[..]].concat();
        for d in [None, Some(busspec_protocols::stream::Direction::Response)] {
            let got = seen::<modbus::Modbus>(&stream_events::<modbus::Modbus>(d, &cap, &[]));
            let want = interp_events(p, busspec_fuzz_bodies::events::direction(d), &cap, &[]);
            assert_eq!(got, want, "{d:?} {}", interp::format_hex(&cap));
            let at = before.len() as u64;
            if d.is_none() {
                assert!(
                    got.contains(&Seen::Ambiguous { offset: at, len: 8 }),
                    "{got:?}"
                );
            }
        }
    }
}
