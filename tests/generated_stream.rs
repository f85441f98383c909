//! The generated `StreamDecoder` against the interpreter's, on captures of example frames
//! (both directions, as a sniffer sees them) mixed with noise and cut short frames, pushed in
//! random chunks: both must report the same events at the same offsets, with the same messages
//! and values; and every byte must be accounted for exactly once.

mod common;

use busspec_fuzz_bodies::events::{covers, interp_events, Seen};
use busspec_fuzz_bodies::{seen, stream_events};
use busspec_model::interp;
use busspec_model::ir::{Direction, Protocol as Spec};
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
/// examples, however they are cut, and accounts for every byte.
fn stream_agrees<P: Protocol>(seed: u64) {
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
    assert!(frames > 300 * 30, "only {frames} frames found");
}

#[test]
fn ub2_generated_stream_matches_the_interpreter() {
    stream_agrees::<Ub2>(7);
}

#[test]
fn sd_generated_stream_matches_the_interpreter() {
    stream_agrees::<Sd>(8);
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
    const DOCUMENT: &'static str = Ub2::DOCUMENT;
    const DOCUMENT_REVISION: &'static str = Ub2::DOCUMENT_REVISION;
    const SPEC_SHA256: &'static str = Ub2::SPEC_SHA256;
    const SPEC_YAML: &'static str = Ub2::SPEC_YAML;
    const MAX_REQUEST_LEN: usize = Ub2::MAX_REQUEST_LEN;
    const MAX_RESPONSE_LEN: usize = Ub2::MAX_RESPONSE_LEN;
    const MAX_FRAME_LEN: usize = Ub2::MAX_FRAME_LEN;
    const FRAME_LENGTHS: &'static [usize] = Ub2::FRAME_LENGTHS;
    const EMPTY_BUFFER: [u8; 4] = [0; 4];
    const BAUD: u32 = Ub2::BAUD;
    const INTER_FRAME_GAP_MS: Option<u32> = Ub2::INTER_FRAME_GAP_MS;
    const MAX_FRAMES_PER_S: Option<u32> = Ub2::MAX_FRAMES_PER_S;
    const DEVICE_ADDRESSES: std::ops::RangeInclusive<u8> = Ub2::DEVICE_ADDRESSES;
    const BROADCAST_ADDRESS: Option<u8> = Ub2::BROADCAST_ADDRESS;
    fn decode_request(
        frame: &[u8],
    ) -> Result<busspec_protocols::Decoded<Self::Request>, busspec_protocols::DecodeError> {
        Ub2::decode_request(frame)
    }
    fn decode_response_for(
        frame: &[u8],
        request: Option<&Self::Request>,
    ) -> Result<busspec_protocols::Decoded<Self::Response>, busspec_protocols::DecodeError> {
        Ub2::decode_response_for(frame, request)
    }
    fn answers(request: &Self::Request, response: &Self::Response) -> bool {
        Ub2::answers(request, response)
    }
    fn kind(request: &Self::Request) -> busspec_protocols::CommandKind {
        Ub2::kind(request)
    }
    fn broadcast(request: &Self::Request) -> busspec_protocols::Broadcast {
        Ub2::broadcast(request)
    }
    fn is_nak(response: &Self::Response) -> bool {
        Ub2::is_nak(response)
    }
    fn checksum_ok(frame: &[u8]) -> bool {
        Ub2::checksum_ok(frame)
    }
    fn candidates(head: &[u8]) -> busspec_protocols::stream::Candidates {
        Ub2::candidates(head)
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
