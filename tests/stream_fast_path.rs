//! The generated stream decoder's fast path (`Core::fast`, taken where a whole window of the
//! caller's bytes lies ahead) against its full framing rule (`Core::advance`): two codings of
//! one rule, so this runs both on the same heads from the same states and requires the same
//! event and the same state after it wherever the fast path decides.
//!
//! By construction, for every built-in protocol (`every_head_of_captures_fast_path_is_the_rule`):
//! every head of random captures (examples, noise, damaged and cut frames, random frames), at
//! every byte offset, from fixed states and from the state the decoder pushed a byte at a time
//! is in there. Besides:
//!
//! Heads: every value of each of the first four bytes of every example frame (its checksum
//! written again, and left as it was), every two-byte head before a frame and before zeros,
//! random three-byte heads (all of them, 16.7 million a tail, at the 2–3 µs a comparison takes
//! in a debug build, would be about 40 s a tail and protocol); states: a sniffer fresh and after a request, one direction only (with a default
//! request for responses), each with no noise, one byte or one byte short of a whole run of
//! it before the head (which of the three turns with the state and the head's first byte).
//! Then whole random captures with noise, fed in chunks (the fast path where it can) and
//! pushed byte by byte (the full rule only). The fast path asks `Framing::candidate` (UB2's
//! generated table) before the candidates' mask, so these comparisons run that route; its
//! answers are also held to the candidates' on every two-byte code, and the decoders it calls
//! on a frame whose length the table gave (`decode_request_fixed`, `decode_response_fixed`) to
//! the decoders of any length.

mod common;

use busspec_protocols::crsf::Crsf;
use busspec_protocols::dynamixel::Dynamixel;
use busspec_protocols::dynamixel2::Dynamixel2;
use busspec_protocols::modbus::Modbus;
use busspec_protocols::pelco_d::PelcoD;
use busspec_protocols::pelco_p::PelcoP;
use busspec_protocols::sd::Sd;
use busspec_protocols::stream::{Candidate, Direction, Event, StreamDecoder, MAX_SKIPPED_RUN};
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;
use common::{fix_checksum, random_input, spec};

/// The decoder states the heads are tried from, with the noise before the head in each.
fn states<P: Protocol>(wires: &[Vec<u8>]) -> Vec<StreamDecoder<P>> {
    // A request of the spec's examples, decoded (pairing state comes from one).
    let request = wires.iter().find_map(|w| {
        let mut d = StreamDecoder::<P>::new(None);
        let found = d.feed(w).find_map(|e| match e {
            Event::Request { frame, .. } => Some(frame.message),
            _ => None,
        });
        found.map(|q| (w, q))
    });
    let mut out = vec![StreamDecoder::<P>::new(None)];
    if let Some((wire, q)) = request {
        let mut after = StreamDecoder::<P>::new(None);
        assert!(after.feed(wire).count() > 0);
        out.push(after);
        out.push(StreamDecoder::<P>::new(Some(Direction::Response)).with_default_request(Some(q)));
    }
    out.push(StreamDecoder::<P>::new(Some(Direction::Request)));
    out
}

/// Runs both paths on `window` from every state; counts where the fast path decided.
fn both<P: Protocol>(states: &[StreamDecoder<P>], window: &[u8], decided: &mut Tally) {
    for (i, d) in states.iter().enumerate() {
        let noise = [0, 1, MAX_SKIPPED_RUN - 1][(i + window[0] as usize) % 3];
        compare(d, window, noise, decided, || format!("state {i}"));
    }
}

/// Runs both paths on `window` from `d`'s state with `noise` bytes of noise before the head;
/// the same event and state wherever the fast path decides (`at` says where, if they differ).
fn compare<P: Protocol>(
    d: &StreamDecoder<P>,
    window: &[u8],
    noise: u64,
    decided: &mut Tally,
    at: impl Fn() -> String,
) {
    match d.fast_and_full(window, noise) {
        None => decided.deferred += 1,
        Some([fast, full]) => {
            assert_eq!(
                fast,
                full,
                "{}: the fast path and the full rule differ on {:02X?} ({}, {noise} bytes of noise before)",
                P::NAME,
                window,
                at()
            );
            match fast.event.or(fast.pending) {
                Some(Event::Request { .. } | Event::Response { .. }) => decided.frames += 1,
                _ => decided.noise += 1,
            }
        }
    }
}

/// The spec of `P`, its example frames (sorted, each once) and the [`states`] they give.
/// `decode_request_fixed` and `decode_response_fixed` (the fast path's decoders of a frame
/// whose length the table gave: generated, for UB2, a copy of the decoder for each length)
/// against `decode_request` and `decode_response`, on every example cut or padded to every
/// listed length, with each value of each of its first four bytes, its checksum written
/// again and left as it was. Returns how many frames were compared.
fn fixed_decoders_are_the_decoders<P: Protocol>() -> usize {
    let p = spec::<P>();
    let mut n = 0;
    for e in &p.examples {
        for &len in P::FRAME_LENGTHS {
            let mut b = window(&e.wire, len);
            for at in 0..len.min(4) {
                let was = b[at];
                for v in 0..=u8::MAX {
                    b[at] = v;
                    for fix in [false, true] {
                        let mut f = b.clone();
                        if fix {
                            fix_checksum(&p, &mut f);
                        }
                        assert_eq!(
                            P::decode_request_fixed(&f),
                            P::decode_request(&f),
                            "{:02X?}",
                            f
                        );
                        assert_eq!(
                            P::decode_response_fixed(&f),
                            P::decode_response(&f),
                            "{:02X?}",
                            f
                        );
                        n += 1;
                    }
                }
                b[at] = was;
            }
        }
    }
    n
}

#[test]
fn fixed_length_decoders_answer_as_the_decoders() {
    // UB2, the one built-in protocol with a candidate table, has them generated; the others
    // take the defaults, the decoders themselves.
    assert!(fixed_decoders_are_the_decoders::<Ub2>() > 100_000);
}

fn examples<P: Protocol>() -> (
    busspec_model::ir::Protocol,
    Vec<Vec<u8>>,
    Vec<StreamDecoder<P>>,
) {
    let p = spec::<P>();
    let mut wires: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
    wires.sort();
    wires.dedup();
    let states = states::<P>(&wires);
    (p, wires, states)
}

#[derive(Default, Debug)]
struct Tally {
    frames: usize,
    noise: usize,
    deferred: usize,
}

/// `bytes` cut or padded with zeros to `len`.
fn window(bytes: &[u8], len: usize) -> Vec<u8> {
    let mut w: Vec<u8> = bytes.iter().copied().take(len).collect();
    w.resize(len, 0);
    w
}

fn fast_path_is_the_rule<P: Protocol>(frames: usize) {
    let (p, wires, states) = examples::<P>();
    let cap = P::MAX_FRAME_LEN;
    let mut t = Tally::default();
    for (k, wire) in wires.iter().enumerate() {
        // The frame, then the next example's bytes, as in a capture.
        let next = &wires[(k + 1) % wires.len()];
        let bytes: Vec<u8> = wire.iter().chain(next).copied().collect();
        for at in 0..4.min(wire.len()) {
            for v in 0..=255u8 {
                let mut b = bytes.clone();
                b[at] = v;
                both(&states, &window(&b, cap), &mut t);
                fix_checksum(&p, &mut b[..wire.len()]);
                both(&states, &window(&b, cap), &mut t);
            }
        }
    }
    // Every two-byte head, before the first example and before zeros.
    for tail in [&wires[0][..], &[][..]] {
        for h in 0..=u16::MAX {
            let b: Vec<u8> = h.to_be_bytes().iter().chain(tail).copied().collect();
            both(&states[..1], &window(&b, cap), &mut t);
        }
    }
    // Random three-byte heads on every example, checksums written again.
    let mut rng = fastrand::Rng::with_seed(13);
    for wire in &wires {
        for _ in 0..200 {
            let mut b = window(wire, cap.max(wire.len()));
            for x in b.iter_mut().take(3) {
                *x = rng.u8(..);
            }
            fix_checksum(&p, &mut b[..wire.len()]);
            both(&states, &window(&b, cap), &mut t);
        }
    }
    // The comparison is not empty: the fast path decided frames and noise.
    assert!(t.frames >= frames && t.noise > 10_000, "{}: {t:?}", P::NAME);
}

/// `candidate` (the fast path's one lookup, which it asks before `candidates`) against
/// `candidates`, on every value of each pair of neighbouring bytes among the first four of
/// every example, in a whole window: the frames the candidates hold where it fixes them
/// (`Candidate::of`), none where they hold none, else `MANY`. Returns how many heads it
/// fixed the frames for.
fn candidate_is_the_candidates<P: Protocol>() -> usize {
    let p = spec::<P>();
    let mut fixed = 0;
    for e in &p.examples {
        let mut b = window(&e.wire, P::MAX_FRAME_LEN);
        for at in 0..3 {
            let was = [b[at], b[at + 1]];
            for h in 0..=u16::MAX {
                b[at..at + 2].copy_from_slice(&h.to_be_bytes());
                let got = P::candidate(&b);
                if got != Candidate::MANY {
                    let want = Candidate::of(P::candidates(&b), P::FRAME_LENGTHS);
                    assert_eq!(got, want, "{}: {:02X?}", P::NAME, &b);
                    fixed += 1;
                }
            }
            b[at..at + 2].copy_from_slice(&was);
        }
    }
    fixed
}

#[test]
fn candidate_is_one_lookup_of_the_candidates() {
    // UB2 has more than one frame length and a table. SD has one length, and Modbus and
    // Dynamixel variable-length messages: their decoders walk the candidates' mask, which
    // costs less there (no table: `MANY`).
    assert!(candidate_is_the_candidates::<Ub2>() > 100_000);
    assert_eq!(candidate_is_the_candidates::<Sd>(), 0);
    assert_eq!(candidate_is_the_candidates::<Modbus>(), 0);
    assert_eq!(candidate_is_the_candidates::<Dynamixel>(), 0);
}

#[test]
fn ub2_fast_path_is_the_rule() {
    fast_path_is_the_rule::<Ub2>(1000);
}

#[test]
fn sd_fast_path_is_the_rule() {
    fast_path_is_the_rule::<Sd>(1000);
}

#[test]
fn modbus_fast_path_is_the_rule() {
    fast_path_is_the_rule::<Modbus>(1000);
}

#[test]
fn dynamixel_fast_path_is_the_rule() {
    fast_path_is_the_rule::<Dynamixel>(500);
}

/// Events of `capture` through `feed` in chunks of random size (the fast path wherever a whole
/// window lies ahead in a chunk), then `finish`: taken with `next` (`by_next`) or with
/// `for_each`, which runs `Feed`'s own loop (`fold`).
fn fed<P: Protocol>(
    capture: &[u8],
    rng: &mut fastrand::Rng,
    by_next: bool,
) -> Vec<Event<P::Request, P::Response>> {
    let mut d = StreamDecoder::<P>::new(None);
    let mut out = Vec::new();
    let mut rest = capture;
    while !rest.is_empty() {
        let (chunk, r) = rest.split_at(rng.usize(1..=rest.len().min(200)));
        rest = r;
        if by_next {
            // A `for` loop calls `next` for each event.
            for e in d.feed(chunk) {
                out.push(e);
            }
        } else {
            d.feed(chunk).for_each(|e| out.push(e));
        }
    }
    out.extend(std::iter::from_fn(|| d.finish()));
    out
}

/// The same through `push` a byte at a time and `poll`: the buffer is never a whole window
/// of the caller's bytes, so only the full rule runs.
fn pushed<P: Protocol>(capture: &[u8]) -> Vec<Event<P::Request, P::Response>> {
    let mut d = StreamDecoder::<P>::new(None);
    let mut out = Vec::new();
    for b in capture {
        assert_eq!(d.push(std::slice::from_ref(b)), 1);
        out.extend(std::iter::from_fn(|| d.poll()));
    }
    out.extend(std::iter::from_fn(|| d.finish()));
    out
}

fn captures_agree<P: Protocol>(seed: u64, at_least: usize) {
    let p = spec::<P>();
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut frames = 0;
    for _ in 0..200 {
        let mut cap = Vec::new();
        for _ in 0..30 {
            let e = &p.examples[rng.usize(..p.examples.len())];
            let mut wire = e.wire.clone();
            match rng.u8(..8) {
                // Noise before it (now and then more than a run of it), a byte of it
                // changed (checksum written again or not), or cut short.
                0 => {
                    let n = if rng.u8(..8) == 0 {
                        300
                    } else {
                        rng.usize(1..8)
                    };
                    cap.extend((0..n).map(|_| rng.u8(..)));
                }
                1 => {
                    let at = rng.usize(..wire.len());
                    wire[at] = rng.u8(..);
                    if rng.bool() {
                        fix_checksum(&p, &mut wire);
                    }
                }
                2 => wire.truncate(rng.usize(1..wire.len())),
                _ => {}
            }
            cap.extend_from_slice(&wire);
        }
        let want = pushed::<P>(&cap);
        let got = fed::<P>(&cap, &mut rng, true);
        assert_eq!(got, want, "{}: {:02X?}", P::NAME, cap);
        let folded = fed::<P>(&cap, &mut rng, false);
        assert_eq!(folded, want, "{}: {:02X?} (for_each)", P::NAME, cap);
        frames += got
            .iter()
            .filter(|e| matches!(e, Event::Request { .. } | Event::Response { .. }))
            .count();
    }
    assert!(frames > at_least, "{}: only {frames} frames", P::NAME);
}

#[test]
fn captures_fed_and_pushed_agree() {
    captures_agree::<Ub2>(1, 4000);
    captures_agree::<Sd>(2, 3000);
    captures_agree::<Modbus>(3, 3000);
    captures_agree::<Dynamixel>(4, 1000);
}

/// A capture of `frames` inputs as the stream tests make them: example frames (now and then
/// with noise before them, a byte changed with or without the checksum written again, or cut
/// short) and the random inputs of `common::random_input` (noise, mutated examples, random
/// frames of random messages).
fn capture(p: &busspec_model::ir::Protocol, rng: &mut fastrand::Rng) -> Vec<u8> {
    let mut cap = Vec::new();
    for _ in 0..30 {
        if rng.u8(..4) == 0 {
            cap.extend(random_input(p, rng));
            continue;
        }
        let mut wire = p.examples[rng.usize(..p.examples.len())].wire.clone();
        match rng.u8(..8) {
            0 => cap.extend((0..rng.usize(1..8)).map(|_| rng.u8(..))),
            1 => {
                let at = rng.usize(..wire.len());
                wire[at] = rng.u8(..);
                if rng.bool() {
                    fix_checksum(p, &mut wire);
                }
            }
            2 => wire.truncate(rng.usize(1..wire.len())),
            _ => {}
        }
        cap.extend_from_slice(&wire);
    }
    cap
}

/// The fast path held to the rule by construction: every head of random captures (every
/// byte offset, the window there, zeros past the capture's end) through both from every state
/// of [`states`], and every head the decoder reaches when the capture is pushed a byte at a
/// time (the full rule alone) from the state it is in there, pairing included; the fast path's
/// answer, where it gives one, must be the rule's, event and state. Returns the tally.
fn every_head_is_the_rule<P: Protocol>(seed: u64, captures: usize) -> Tally {
    let (p, _, states) = examples::<P>();
    let cap = P::MAX_FRAME_LEN;
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut t = Tally::default();
    for _ in 0..captures {
        let bytes = capture(&p, &mut rng);
        for at in 0..bytes.len() {
            both(&states, &window(&bytes[at..], cap), &mut t);
        }
        // The decoder's own states along the capture.
        let mut d = StreamDecoder::<P>::new(None);
        let mut last = None;
        for (i, b) in bytes.iter().enumerate() {
            let head = d.position() - d.buffered() as u64;
            if last != Some(head) {
                last = Some(head);
                let at = head as usize;
                let noise = [0, 1, MAX_SKIPPED_RUN - 1][i % 3];
                let w = window(&bytes[at..], cap);
                compare(&d, &w, noise, &mut t, || {
                    format!("the decoder's state at offset {at} of {bytes:02X?}")
                });
            }
            assert_eq!(d.push(std::slice::from_ref(b)), 1);
            while d.poll().is_some() {}
        }
    }
    t
}

#[test]
fn every_head_of_captures_fast_path_is_the_rule() {
    fn run<P: Protocol>(seed: u64) {
        let t = every_head_is_the_rule::<P>(seed, 150);
        // Both paths ran: the fast path decided frames and noise, and left few heads to the
        // full rule alone (a candidate breaking only a rule of the spec, a head whose field
        // is not there).
        assert!(
            t.frames > 300 && t.noise > 500 && t.deferred * 10 < t.frames + t.noise,
            "{}: {t:?}",
            P::NAME
        );
    }
    run::<Ub2>(21);
    run::<Sd>(22);
    run::<Modbus>(23);
    run::<Dynamixel>(24);
    run::<PelcoD>(25);
    run::<PelcoP>(26);
    run::<Crsf>(27);
    run::<Dynamixel2>(28);
}

/// Where a protocol's generated `Framing::REPLY_BY_REQUEST` is `false` (the stream decoder then
/// keeps no request and decodes every response on its own), its claim: a frame that decodes
/// as the reply to a request decodes on its own to the same, and none is ambiguous on its own.
/// Every request of the spec's examples against the examples and random frames of both
/// directions. Where it is `true`, some response needs its request (or its request's bytes).
#[test]
fn a_reply_decodes_as_on_its_own_where_no_response_needs_its_request() {
    fn run<P: Protocol>(seed: u64) -> bool {
        let p = spec::<P>();
        let by_request = <P as busspec_protocols::Framing>::REPLY_BY_REQUEST;
        assert_eq!(
            by_request,
            p.responses
                .iter()
                .any(|m| m.needs_request || m.over_request.is_some()),
            "{}",
            P::NAME
        );
        if by_request {
            return false;
        }
        let requests: Vec<P::Request> = p
            .examples
            .iter()
            .filter_map(|e| P::decode_request(&e.wire).ok().map(|d| d.message))
            .collect();
        assert!(!requests.is_empty(), "{}", P::NAME);
        let mut rng = fastrand::Rng::with_seed(seed);
        let mut frames: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
        frames.extend((0..20_000).map(|_| random_input(&p, &mut rng)));
        let mut paired = 0;
        for f in &frames {
            let alone = P::decode_response(f);
            assert!(
                !matches!(alone, Err(busspec_protocols::DecodeError::Ambiguous { .. })),
                "{}: {f:02X?}",
                P::NAME
            );
            for q in &requests {
                if let Ok(d) = P::decode_reply(f, q) {
                    assert_eq!(Ok(d), alone, "{}: {f:02X?} after {q:?}", P::NAME);
                    paired += 1;
                }
            }
        }
        assert!(paired > 0, "{}", P::NAME);
        true
    }
    let unpaired = [
        run::<Ub2>(31),
        run::<Sd>(32),
        run::<Modbus>(33),
        run::<Dynamixel>(34),
        run::<PelcoD>(35),
        run::<PelcoP>(36),
        run::<Crsf>(37),
        run::<Dynamixel2>(38),
    ];
    // UB2, Modbus, Dynamixel 1.0 among them; SD (replies only the request tells apart) and
    // Pelco D (a reply's checksum over its request's bytes) not.
    assert_eq!(unpaired.iter().filter(|&&u| u).count(), 5, "{unpaired:?}");
    assert!(unpaired[0] && !unpaired[1] && unpaired[2] && unpaired[3] && !unpaired[4]);
}

/// `Framing::decodes_both_ways` (generated where both directions check a frame alike: the
/// framing checked once, then each direction's code) against the two checks asked apart, the
/// trait's default: the same answer, error included, on every value of each of the first four
/// bytes of every example (its checksum written again, and left as it was), every prefix of
/// each, and random frames and inputs of the spec.
#[test]
fn decodes_both_ways_is_each_direction_asked_apart() {
    use busspec_protocols::DecodeError;
    fn apart<P: Protocol>(frame: &[u8]) -> Result<bool, DecodeError> {
        P::request_decodes(frame)?;
        Ok(matches!(
            P::response_decodes(frame, None, None),
            Ok(()) | Err(DecodeError::Ambiguous { .. })
        ))
    }
    fn run<P: Protocol>(seed: u64) -> usize {
        let (p, wires, _) = examples::<P>();
        let mut rng = fastrand::Rng::with_seed(seed);
        let mut frames: Vec<Vec<u8>> = Vec::new();
        for wire in &wires {
            frames.extend((0..=wire.len()).map(|n| wire[..n].to_vec()));
            for at in 0..4.min(wire.len()) {
                for v in 0..=255u8 {
                    let mut b = wire.clone();
                    b[at] = v;
                    frames.push(b.clone());
                    fix_checksum(&p, &mut b);
                    frames.push(b);
                }
            }
        }
        for _ in 0..5_000 {
            frames.push(random_input(&p, &mut rng));
        }
        let mut both = 0;
        for f in &frames {
            let fast = P::decodes_both_ways(f);
            assert_eq!(fast, apart::<P>(f), "{}: {f:02X?}", P::NAME);
            both += usize::from(fast == Ok(true));
        }
        both
    }
    // Where the protocol has the combined check, frames decode both ways among these.
    assert!(run::<Dynamixel>(31) > 100);
    assert!(run::<Modbus>(32) > 100);
    run::<Ub2>(33);
    run::<Sd>(34);
    run::<PelcoD>(35);
    run::<PelcoP>(36);
    run::<Crsf>(37);
    run::<Dynamixel2>(38);
}

/// A Modbus request candidate longer than another candidate whose checks past the framing
/// fail (`Framing::request_may_decode`) is passed over, its checksum not computed: a short
/// read-coils reply, whose 8-byte request candidate takes in the next frame's first bytes,
/// is decided by the fast path as the reply; where the request's checksum holds (a request
/// out of range) and the reply does not decode, the request is out of spec, which the fast
/// path leaves to the full rule.
#[test]
fn a_modbus_request_candidate_passed_over_is_the_rule() {
    use busspec_protocols::modbus::checksum;
    let cap = <Modbus as Protocol>::MAX_FRAME_LEN;
    let seal = |f: &mut Vec<u8>| {
        let c = checksum(f).to_le_bytes();
        f.extend_from_slice(&c);
    };
    let fresh = StreamDecoder::<Modbus>::new(None);
    // A read-coils reply of one byte of coils: 6 bytes, then the next frame's.
    let mut decided = 0;
    for coils in 0..=255u8 {
        let mut reply = vec![0x01, 0x01, 0x01, coils];
        seal(&mut reply);
        let mut w = reply.clone();
        w.extend_from_slice(&[0x01, 0x03]);
        let quantity = u16::from_be_bytes([w[4], w[5]]);
        let w = window(&w, cap);
        let [fast, full] = fresh
            .fast_and_full(&w, 0)
            .expect("the fast path decides a reply whose request candidate it passes over");
        assert_eq!(fast, full, "{w:02X?}");
        // The request candidate's quantity (the reply's checksum) out of its range: passed
        // over; in it, decoded whole and refused by its checksum. A reply either way.
        assert!(
            matches!(fast.event, Some(Event::Response { len: 6, .. })),
            "{:?}",
            fast.event
        );
        decided += usize::from(!(1..=2000).contains(&quantity));
    }
    assert!(decided > 200, "{decided}");
    // A read-coils request of quantity 0 (out of range) whose checksum holds, its third byte
    // counting a one-byte reply, which does not decode: out of spec, by the full rule.
    let mut request = vec![0x01, 0x01, 0x01, 0x00, 0x00, 0x00];
    seal(&mut request);
    let w = window(&request, cap);
    assert!(
        fresh.fast_and_full(&w, 0).is_none(),
        "left to the full rule"
    );
    let mut d = StreamDecoder::<Modbus>::new(None);
    let events: Vec<_> = d.feed(&w).collect();
    assert!(
        matches!(
            events.first(),
            Some(Event::OutOfSpec {
                offset: 0,
                len: 8,
                ..
            })
        ),
        "{events:?}"
    );
}
