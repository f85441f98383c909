//! Shared by the tests that hold the generated crate against the interpreter: loading the specs
//! and random frames. The comparison itself (the values each engine decodes, field by field,
//! raw; `agree`) lives in busspec-fuzz-bodies, which the fuzz targets use too.

#![allow(dead_code, unused_imports)]

use busspec_model::checksum;
use busspec_model::interp;
use busspec_model::ir::{Direction, Message, MessageRef, Protocol};

pub use busspec_fuzz_bodies::oracle::{
    agree, interp_values, request_example, visit_values, Decoded, Values,
};

/// The interpreter's view of generated protocol `P`: the spec text its code was generated
/// from ([`Source::spec_yaml`](busspec_runtime::Source::spec_yaml)), loaded and validated.
pub fn spec<P: busspec_protocols::Protocol>() -> Protocol {
    busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml).unwrap_or_else(|d| panic!("{d}"))
}

/// Writes the checksum of the bytes before it it covers into `frame`'s last bytes (before
/// the end bytes).
pub fn fix_checksum(p: &Protocol, frame: &mut [u8]) {
    interp::reseal(p, frame);
}

/// A frame shaped like message `m` (start byte, code, right length and length byte, valid
/// checksum; a repeated field without elements), with a random address (usually a device's)
/// and random payload.
pub fn random_frame(p: &Protocol, m: &Message, rng: &mut fastrand::Rng) -> Vec<u8> {
    let len = p.frame_len(m);
    let o = m.layout;
    let mut f: Vec<u8> = (0..len).map(|_| rng.u8(..)).collect();
    if let Some(at) = o.start {
        // A sync sequence, whole (Dynamixel's FF FF), the message's direction's.
        let sync = p.framing.sync_of(m.direction);
        if let Some(to) = f.get_mut(at..at + sync.len()) {
            to.copy_from_slice(sync);
        }
    }
    f[o.code..o.code + m.code.len()].copy_from_slice(&m.code);
    if let (Some(at), true) = (o.address, rng.u8(..) < 224) {
        f[at] = rng.u8(p.framing.address.min..=p.framing.address.max);
    }
    // Small payload values are where constants, enums and specials live.
    for b in &mut f[o.payload..o.payload + m.payload_len] {
        if rng.bool() {
            *b = rng.u8(..4);
        }
    }
    // A length byte that says the frame's length (a single byte: Dynamixel's).
    let rule = p.framing.length_rule(m.direction);
    if let Some((r, v)) = rule.and_then(|r| Some((r, r.value(len)?))) {
        if r.width == 1 {
            f[r.at] = v as u8;
        }
    }
    fix_checksum(p, &mut f);
    f
}

/// Every message of both directions.
pub fn all_messages(p: &Protocol) -> Vec<MessageRef> {
    let mut out = Vec::new();
    for d in [Direction::Request, Direction::Response] {
        for index in 0..p.messages(d).len() {
            out.push(MessageRef {
                direction: d,
                index,
            });
        }
    }
    out
}

/// A random input for the decoders: pure noise, a mutated example, or a well-formed frame of a
/// random message with random contents.
pub fn random_input(p: &Protocol, rng: &mut fastrand::Rng) -> Vec<u8> {
    let max = p
        .max_frame_len(Direction::Request)
        .max(p.max_frame_len(Direction::Response));
    match rng.u8(..8) {
        0 => (0..rng.usize(..=max + 2)).map(|_| rng.u8(..)).collect(),
        1..=3 => {
            let e = &p.examples[rng.usize(..p.examples.len())];
            let mut f = e.wire.clone();
            for _ in 0..rng.usize(1..=3) {
                let i = rng.usize(..f.len());
                f[i] = rng.u8(..);
            }
            match rng.u8(..8) {
                0 => {
                    f.pop();
                }
                1 => f.push(rng.u8(..)),
                _ => {}
            }
            if rng.u8(..4) != 0 {
                fix_checksum(p, &mut f);
            }
            f
        }
        _ => {
            let all = all_messages(p);
            let r = all[rng.usize(..all.len())];
            random_frame(p, p.message(r), rng)
        }
    }
}
