//! The generated `StreamDecoder` against the interpreter's, on captures of example frames
//! (both directions, as a sniffer sees them) mixed with noise and cut short frames, pushed in
//! random chunks: both must report the same events at the same offsets, with the same messages
//! and values; and every byte must be accounted for exactly once.

mod common;

use busspec_fuzz_bodies::events::{covers, interp_events, Seen, Why};
use busspec_fuzz_bodies::{seen, stream_events};
use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, Protocol as Spec};
use busspec_model::stream::{breaks_spec, relaxed};
use busspec_protocols::crsf::Crsf;
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;
use common::spec;

/// A capture: example frames in random order, with noise bursts and cut-short frames between.
fn capture(p: &Spec, rng: &mut fastrand::Rng, frames: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for _ in 0..frames {
        let e = &p.examples[rng.usize(..p.examples.len())];
        match rng.u8(..16) {
            0 => out.extend((0..rng.usize(1..6)).map(|_| rng.u8(..))),
            1 => out.extend_from_slice(&e.wire[..rng.usize(1..e.wire.len())]),
            _ => {}
        }
        out.extend_from_slice(&e.wire);
    }
    out
}

fn chunks(rng: &mut fastrand::Rng, total: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut n = 0;
    while n < total {
        let c = rng.usize(1..24);
        out.push(c);
        n += c;
    }
    out
}

/// `P`'s generated stream decoder agrees with the interpreter's on random captures of its
/// examples, however they are cut, and accounts for every byte; at least `per_capture` of the
/// 40 frames of a capture are found as frames on average (not ambiguous, not cut by noise).
fn stream_agrees<P: Protocol>(seed: u64, per_capture: usize) {
    let p = spec::<P>();
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut frames = 0;
    for _ in 0..300 {
        let cap = capture(&p, &mut rng, 40);
        let cuts = chunks(&mut rng, cap.len());
        let want = interp_events(&p, None, &cap, &cuts);
        let got = seen::<P>(&stream_events::<P>(None, &cap, &cuts));
        assert_eq!(got, want, "capture {}", interp::format_hex(&cap));
        // However the capture is cut, the events are the same.
        assert_eq!(seen::<P>(&stream_events::<P>(None, &cap, &[])), got);
        covers(&got, cap.len() as u64);
        frames += got
            .iter()
            .filter(|e| matches!(e, Seen::Frame { .. }))
            .count();
    }
    assert!(frames > 300 * per_capture, "only {frames} frames found");
}

#[test]
fn ub2_generated_stream_matches_the_interpreter() {
    stream_agrees::<Ub2>(7, 30);
}

#[test]
fn sd_generated_stream_matches_the_interpreter() {
    stream_agrees::<Sd>(8, 30);
}

#[test]
fn modbus_generated_stream_matches_the_interpreter() {
    stream_agrees::<Modbus>(9, 30);
}

/// CRSF: any first byte is an address, so its streams resynchronise by type, length and CRC.
#[test]
fn crsf_generated_stream_matches_the_interpreter() {
    stream_agrees::<Crsf>(11, 30);
}

/// Most Dynamixel examples are status packets, which read as instructions too: ambiguous in a
/// capture without the request before them.
#[test]
fn dynamixel_generated_stream_matches_the_interpreter() {
    stream_agrees::<Dynamixel>(10, 10);
}

/// Frames that checksum but break a rule of the spec, each with the reason strict decoding
/// gives: every example re-encoded (with the spec's rules lifted) to each address no frame may
/// carry below and above the device range, every request that refuses broadcast sent to the
/// broadcast address, and every ranged field of every example just outside its range. Only
/// those strict decoding (both directions) refuses for such a rule are kept.
fn out_of_spec_frames(p: &Spec) -> Vec<(Vec<u8>, interp::DecodeError)> {
    let lifted = relaxed(p);
    let a = &p.framing.address;
    let bad: Vec<u8> = [
        (0..a.min).rev().find(|&x| !interp::address_allowed(p, x)),
        (a.max..=u8::MAX).find(|&x| !interp::address_allowed(p, x)),
    ]
    .into_iter()
    .flatten()
    .collect();
    let mut out = Vec::new();
    for e in &p.examples {
        let Ok(frame) = interp::decode_as(p, e.message, &e.wire) else {
            continue;
        };
        let m = p.message(e.message);
        let mut variants: Vec<(u8, Vec<Value>)> = Vec::new();
        for &x in &bad {
            variants.push((x, frame.values.clone()));
        }
        if let Some(b) = a.broadcast.filter(|&b| interp::broadcast_refused(p, m, b)) {
            variants.push((b, frame.values.clone()));
        }
        for (i, v) in frame.values.iter().enumerate() {
            let Some((f, bits)) = interp::leaf_field(m, &v.name) else {
                continue;
            };
            let Some((min, max)) = bits.map_or(f.range, |b| b.range) else {
                continue;
            };
            for y in [min - 1, max + 1] {
                if interp::range_violation(f, bits, y).is_some() {
                    let mut values = frame.values.clone();
                    values[i].raw = Raw::Int(y);
                    variants.push((frame.address, values));
                }
            }
        }
        for (address, values) in variants {
            let Ok(wire) = interp::encode(&lifted, e.message, address, &values) else {
                continue;
            };
            if let Err(why) = interp::decode(p, None, None, &wire) {
                if breaks_spec(&why) {
                    out.push((wire, why));
                }
            }
        }
    }
    out
}

/// A frame that checksums but breaks a range, address or broadcast rule is reported where it
/// is, with its reason, by both decoders alike: never skipped as noise, never a frame; and the
/// frame after it is found whole (resynchronisation does not step into it).
fn out_of_spec_frames_are_reported<P: Protocol>(at_least: usize) {
    let p = spec::<P>();
    let frames = out_of_spec_frames(&p);
    assert!(
        frames.len() >= at_least,
        "{}: only {} out-of-spec frames",
        P::NAME,
        frames.len()
    );
    let good: Vec<&Vec<u8>> = p
        .examples
        .iter()
        .filter(|e| interp::decode_as(&p, e.message, &e.wire).is_ok())
        .map(|e| &e.wire)
        .collect();
    let mut cap = Vec::new();
    let mut bad_at = Vec::new();
    let mut good_at = Vec::new();
    for (i, (wire, why)) in frames.iter().enumerate() {
        bad_at.push((cap.len() as u64, wire.len() as u64, Why::of_interp(why)));
        cap.extend_from_slice(wire);
        let g = good[i % good.len()];
        good_at.push((cap.len() as u64, g.len() as u64));
        cap.extend_from_slice(g);
    }
    let got = seen::<P>(&stream_events::<P>(None, &cap, &[]));
    assert_eq!(
        got,
        interp_events(&p, None, &cap, &[]),
        "capture {}",
        interp::format_hex(&cap)
    );
    covers(&got, cap.len() as u64);
    for (offset, len, reason) in bad_at {
        let want = Seen::OutOfSpec {
            offset,
            len,
            reason,
        };
        assert!(got.contains(&want), "{}: {want:?} not in {got:?}", P::NAME);
    }
    for (offset, len) in good_at {
        assert!(
            got.iter().any(|e| e.span() == (offset, len)
                && matches!(e, Seen::Frame { .. } | Seen::Ambiguous { .. })),
            "{}: the frame at {offset} after an out-of-spec one is lost: {got:?}",
            P::NAME
        );
    }
}

#[test]
fn ub2_out_of_spec_frames_are_reported() {
    out_of_spec_frames_are_reported::<Ub2>(100);
}

#[test]
fn sd_out_of_spec_frames_are_reported() {
    out_of_spec_frames_are_reported::<Sd>(100);
}

/// The frames of the issue, sniffed: SD set point to 0x20 (outside 0x01..0x1E), a temperature
/// reply of another Volz dialect read as an SD serial-number character with string length 75,
/// read_temperatures to the broadcast ID, and UB2's address 0x41 (erratum ub2-e02).
#[test]
fn the_issues_frames_are_out_of_spec_in_a_stream() {
    use busspec_protocols::stream::Event;
    use busspec_protocols::DecodeError;
    let cap = interp::parse_hex("76 20 00 00 BA B0 10 01 4B 4B FB 8A A0 1F 00 00 81 98").unwrap();
    let got = stream_events::<Sd>(None, &cap, &[]);
    assert!(
        matches!(
            got[..],
            [
                Event::OutOfSpec {
                    offset: 0,
                    len: 6,
                    reason: DecodeError::BadAddress { found: 0x20, .. },
                },
                Event::OutOfSpec {
                    offset: 6,
                    len: 6,
                    reason: DecodeError::OutOfRange {
                        field: busspec_runtime::FieldDesc {
                            name: "string_length",
                            ..
                        },
                        found: 75,
                        ..
                    },
                },
                Event::OutOfSpec {
                    offset: 12,
                    len: 6,
                    reason: DecodeError::BroadcastNotAccepted { address: 0x1F, .. },
                },
            ]
        ),
        "{got:?}"
    );
    let p = spec::<Sd>();
    assert_eq!(seen::<Sd>(&got), interp_events(&p, None, &cap, &[]));
    let cap = interp::parse_hex("AA41 4001 2C AA21 1000 DB").unwrap();
    let got = stream_events::<Ub2>(None, &cap, &[]);
    assert!(
        matches!(
            got[..],
            [
                Event::OutOfSpec {
                    offset: 0,
                    len: 5,
                    reason: DecodeError::BadAddress { found: 0x41, .. },
                },
                Event::Request {
                    offset: 5,
                    len: 5,
                    ..
                },
            ]
        ),
        "{got:?}"
    );
}

/// Random frames that checksum (any address, payloads near zero: valid, out of spec, or with
/// a wrong constant) mixed into captures of examples and noise: both decoders report the same
/// events, however the capture is cut; at least `at_least` of them out of spec.
fn stream_agrees_on_out_of_spec<P: Protocol>(seed: u64, at_least: usize) {
    let p = spec::<P>();
    let messages = common::all_messages(&p);
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut out_of_spec = 0;
    for _ in 0..200 {
        let mut cap = capture(&p, &mut rng, 10);
        for _ in 0..10 {
            let m = p.message(messages[rng.usize(..messages.len())]);
            cap.extend_from_slice(&common::random_frame(&p, m, &mut rng));
            cap.extend_from_slice(&capture(&p, &mut rng, 1));
        }
        let cuts = chunks(&mut rng, cap.len());
        let want = interp_events(&p, None, &cap, &cuts);
        let got = seen::<P>(&stream_events::<P>(None, &cap, &cuts));
        assert_eq!(got, want, "capture {}", interp::format_hex(&cap));
        covers(&got, cap.len() as u64);
        out_of_spec += got
            .iter()
            .filter(|e| matches!(e, Seen::OutOfSpec { .. }))
            .count();
    }
    assert!(
        out_of_spec >= at_least,
        "only {out_of_spec} out-of-spec frames"
    );
}

#[test]
fn ub2_streams_agree_on_out_of_spec_frames() {
    stream_agrees_on_out_of_spec::<Ub2>(17, 201);
}

#[test]
fn sd_streams_agree_on_out_of_spec_frames() {
    stream_agrees_on_out_of_spec::<Sd>(18, 201);
}

#[test]
fn modbus_streams_agree_on_out_of_spec_frames() {
    stream_agrees_on_out_of_spec::<Modbus>(19, 201);
}

/// Dynamixel's spec has no range, address or broadcast rule a random frame breaks often enough
/// to count on: the decoders agree, which is the point here.
#[test]
fn dynamixel_streams_agree_on_out_of_spec_frames() {
    stream_agrees_on_out_of_spec::<Dynamixel>(20, 0);
}

/// Random bytes are noise: a random byte where the address sits does not make an out-of-spec
/// frame, the checksum must pass too. Counted, and both decoders agree.
#[test]
fn noise_is_not_a_stream_of_out_of_spec_frames() {
    fn count<P: Protocol>(seed: u64) -> (usize, usize) {
        let p = spec::<P>();
        let mut rng = fastrand::Rng::with_seed(seed);
        let noise: Vec<u8> = (0..100_000).map(|_| rng.u8(..)).collect();
        let got = seen::<P>(&stream_events::<P>(None, &noise, &[]));
        assert_eq!(got, interp_events(&p, None, &noise, &[]));
        let n = |f: fn(&Seen) -> bool| got.iter().filter(|e| f(e)).count();
        (
            n(|e| matches!(e, Seen::OutOfSpec { .. })),
            n(|e| matches!(e, Seen::Frame { .. } | Seen::Ambiguous { .. })),
        )
    }
    for (name, (out_of_spec, frames)) in [("ub2", count::<Ub2>(1)), ("sd", count::<Sd>(2))] {
        eprintln!("{name}: 100000 random bytes: {out_of_spec} out of spec, {frames} frames");
        assert!(
            out_of_spec <= 20,
            "{name}: {out_of_spec} out-of-spec frames in noise"
        );
    }
}

/// A valid frame placed after garbage of any length is found, whole, at its offset.
#[test]
fn a_frame_after_garbage_is_found() {
    use busspec_protocols::stream::Event;
    let p = spec::<Sd>();
    let frame = &p.examples[0].wire;
    let mut rng = fastrand::Rng::with_seed(3);
    for garbage in 0..600 {
        let mut cap: Vec<u8> = (0..garbage).map(|_| rng.u8(..)).collect();
        cap.extend_from_slice(frame);
        let mut d = busspec_protocols::sd::StreamDecoder::new(Some(
            busspec_protocols::stream::Direction::Request,
        ));
        let mut events: Vec<_> = d.feed(&cap).collect();
        while let Some(e) = d.finish() {
            events.push(e);
        }
        let found = events.iter().any(
            |e| matches!(e, Event::Request { offset, len: 6, .. } if *offset == garbage as u64),
        );
        // Garbage may itself end in bytes that form a frame overlapping ours; count that out.
        let swallowed = events.iter().any(|e| matches!(e, Event::Request { offset, len, .. } if *offset < garbage as u64 && offset + *len as u64 > garbage as u64));
        assert!(
            found || swallowed,
            "frame after {garbage} bytes of garbage lost: {events:?}"
        );
        assert!(events.iter().all(|e| !matches!(e, Event::Skipped { len, .. } if *len > busspec_protocols::stream::MAX_SKIPPED_RUN)));
    }
}

/// The master's view, responses only: a reply that only its request identifies is ambiguous
/// alone, and decodes as the reply to the default request when one is given.
#[test]
fn direction_and_default_request() {
    use busspec_protocols::sd::{Request, Response, StreamDecoder};
    use busspec_protocols::stream::{Direction as D, Event};
    let p = spec::<Sd>();
    let reply = p
        .examples
        .iter()
        .find(|e| {
            e.message.direction == Direction::Response
                && matches!(
                    Response::decode(&e.wire),
                    Err(busspec_protocols::DecodeError::Ambiguous { .. })
                )
        })
        .expect("an SD reply that only its request identifies");
    let request_wire = common::request_example(&p, reply.reply_to.unwrap()).unwrap();
    let request = Request::decode(request_wire).unwrap().message;
    let mut plain = StreamDecoder::new(Some(D::Response));
    let mut all: Vec<_> = plain.feed(&reply.wire).collect();
    while let Some(e) = plain.finish() {
        all.push(e);
    }
    assert!(
        matches!(
            all[..],
            [Event::Ambiguous {
                offset: 0,
                len: 6,
                ..
            }]
        ),
        "{all:?}"
    );
    let mut paired = StreamDecoder::new(Some(D::Response)).with_default_request(Some(request));
    let mut all: Vec<_> = paired.feed(&reply.wire).collect();
    while let Some(e) = paired.finish() {
        all.push(e);
    }
    let want = Response::decode_reply(&reply.wire, &request).unwrap();
    assert!(
        matches!(all[..], [Event::Response { offset: 0, len: 6, frame }] if frame == want),
        "{all:?}"
    );
}

/// UB2 with a 4-byte stream buffer, shorter than most of its frames: a protocol implemented
/// by hand can declare any buffer, and the decoder must cope.
#[derive(Debug, Clone, Copy, Default)]
struct Ub2SmallBuffer;

impl busspec_protocols::Protocol for Ub2SmallBuffer {
    type Request = <Ub2 as busspec_protocols::Protocol>::Request;
    type Response = <Ub2 as busspec_protocols::Protocol>::Response;
    type Buffer = [u8; 4];
    const NAME: &'static str = Ub2::NAME;
    const SOURCE: busspec_protocols::Source = Ub2::SOURCE;
    const BUS: busspec_protocols::Bus = Ub2::BUS;
    const MAX_FRAME_LEN: usize = Ub2::MAX_FRAME_LEN;
    fn decode_request(
        frame: &[u8],
    ) -> Result<busspec_protocols::Decoded<Self::Request>, busspec_protocols::DecodeError> {
        Ub2::decode_request(frame)
    }
}

impl busspec_protocols::Framing for Ub2SmallBuffer {
    const MAX_REQUEST_LEN: usize = Ub2::MAX_REQUEST_LEN;
    const MAX_RESPONSE_LEN: usize = Ub2::MAX_RESPONSE_LEN;
    const FRAME_LENGTHS: &'static [usize] = Ub2::FRAME_LENGTHS;
    type Span = [u8; 0];
    const EMPTY_SPAN: [u8; 0] = [];
    fn candidates(head: &[u8]) -> busspec_protocols::stream::Candidates {
        Ub2::candidates(head)
    }
    fn checksum_ok(frame: &[u8]) -> bool {
        Ub2::checksum_ok(frame)
    }
}

/// A decoder whose buffer is shorter than the longest frame still makes progress: it settles
/// a full buffer instead of waiting forever for room it will never have.
#[test]
fn a_too_small_buffer_never_hangs() {
    use busspec_protocols::stream::{Event, StreamDecoder};
    let p = spec::<Ub2>();
    let cap: Vec<u8> = p.examples.iter().flat_map(|e| e.wire.clone()).collect();
    let mut d: StreamDecoder<Ub2SmallBuffer> = StreamDecoder::new(None);
    let mut accounted = 0;
    for e in d.feed(&cap) {
        accounted += e.len();
        assert!(!matches!(e, Event::Request { len, .. } | Event::Response { len, .. } if len > 4));
    }
    while let Some(e) = d.finish() {
        accounted += e.len();
    }
    assert_eq!(accounted, cap.len() as u64);
}

/// `feed` decides on the caller's bytes in place where it can, handing buffered bytes back to
/// the input to do so. Whatever it has reached when the iterator is dropped, `remaining()` and
/// `position()` agree, and feeding the rest on gives the events a single feed gives.
#[test]
fn a_feed_dropped_partway_leaves_exactly_the_rest() {
    use busspec_protocols::ub2::StreamDecoder;
    let p = spec::<Ub2>();
    let mut rng = fastrand::Rng::with_seed(11);
    for _ in 0..200 {
        let cap = capture(&p, &mut rng, 30);
        let mut one = StreamDecoder::new(None);
        let mut want: Vec<_> = one.feed(&cap).collect();
        want.extend(std::iter::from_fn(|| one.finish()));

        let mut d = StreamDecoder::new(None);
        let mut got = Vec::new();
        let mut carry: Vec<u8> = Vec::new();
        let mut rest: &[u8] = &cap;
        while !rest.is_empty() || !carry.is_empty() {
            let (chunk, after) = rest.split_at(rng.usize(0..=rest.len().min(40)));
            let mut input = std::mem::take(&mut carry);
            input.extend_from_slice(chunk);
            rest = after;
            let mut feed = d.feed(&input);
            got.extend(feed.by_ref().take(rng.usize(1..=4)));
            // The iterator ends here, with bytes of its input possibly unread.
            carry = feed.remaining().to_vec();
            assert_eq!(
                d.position() + carry.len() as u64,
                (cap.len() - rest.len()) as u64,
                "position() and remaining() disagree"
            );
        }
        got.extend(std::iter::from_fn(|| d.finish()));
        assert_eq!(got, want, "capture {}", interp::format_hex(&cap));
    }
}
