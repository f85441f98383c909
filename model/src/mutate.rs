//! Frames near a valid one, for the tests that hold the generated code to the interpreter
//! (`busspec-codegen`'s fixture tests, `busspec-difftest`): one frame's bytes changed, cut and
//! lengthened, each with its checksum as it was and repaired, its length field kept or made to
//! agree. Every function takes a frame as it travels, preamble bytes (`framing.preamble`)
//! included, and leaves those bytes as they are.

use crate::interp;
use crate::ir::{Direction, Protocol};

/// `frame` with its checksum recomputed over what it covers (and its end bytes); a
/// request's, where each direction's checksum covers from its own byte ([`reseal_as`]).
pub fn reseal(p: &Protocol, frame: &mut [u8]) {
    interp::reseal(p, after_preamble(p, frame));
}

/// [`reseal`] of a frame of direction `d`: its checksum over what that direction's covers.
pub fn reseal_as(p: &Protocol, d: Direction, frame: &mut [u8]) {
    interp::reseal_as(p, d, after_preamble(p, frame));
}

/// `frame` after its preamble bytes: where the frame's offsets count from.
pub fn after_preamble<'f>(p: &Protocol, frame: &'f mut [u8]) -> &'f mut [u8] {
    let k = frame.len() - p.framing.after_preamble(frame).len();
    &mut frame[k..]
}

/// `frame` with its length field set to what its length gives, where the framing has one.
pub fn fix_length(p: &Protocol, d: Direction, frame: &mut [u8]) {
    let frame = after_preamble(p, frame);
    if p.framing.long.is_some() {
        return crate::long::fix_length(p, d, frame);
    }
    // A short frame (`framing.forms`) has no length field.
    if crate::forms::is_short(p, frame) {
        return;
    }
    let Some(rule) = p.framing.length_rule(d) else {
        return;
    };
    let Some(v) = rule.value(frame.len()) else {
        return;
    };
    if let Some(at) = frame.get_mut(rule.at..rule.at + rule.width) {
        interp::write_uint(v as u64, at, p.byte_order);
    }
}

/// Frames made from `wire`: every byte changed four ways (where that changes it), the frame
/// cut and lengthened by one to three bytes before its checksum (its length field kept, or
/// made to agree), each with its checksum as it was and recomputed.
pub fn mutations(p: &Protocol, d: Direction, wire: &[u8]) -> Vec<Vec<u8>> {
    // A frame without a checksum (`checksum: none`) is cut and lengthened at its end.
    let clen = if p.unchecked(&[d], wire).is_some() {
        0
    } else {
        p.framing.trailer_len_of(d)
    };
    let mut out = Vec::new();
    for i in 0..wire.len() {
        for f in [|b: u8| b ^ 0x01, |b: u8| b ^ 0x80, |_| 0x00, |_| 0xFF] {
            let mut m = wire.to_vec();
            m[i] = f(m[i]);
            if m == wire {
                continue;
            }
            out.push(m.clone());
            if i + clen < wire.len() {
                reseal_as(p, d, &mut m);
                out.push(m);
            }
        }
    }
    let body = wire.len().saturating_sub(clen);
    for k in 1..=3 {
        let mut variants = Vec::new();
        if body > k {
            let mut cut = wire[..body - k].to_vec();
            cut.extend_from_slice(&wire[body..]);
            variants.push(cut);
        }
        let mut long = wire[..body].to_vec();
        long.extend(vec![0x5Au8; k]);
        long.extend_from_slice(&wire[body..]);
        variants.push(long);
        for v in variants {
            let mut sealed = v.clone();
            reseal_as(p, d, &mut sealed);
            let mut agreed = v.clone();
            fix_length(p, d, &mut agreed);
            reseal_as(p, d, &mut agreed);
            out.extend([v, sealed, agreed]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dynamixel() -> Protocol {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/dynamixel.yaml");
        match crate::load_file(&path) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn mutations_change_the_frame_and_repair_what_they_say() {
        let p = dynamixel();
        let d = Direction::Request;
        // PING to device 1: FF FF id length instruction checksum.
        let wire = [0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB];
        assert!(interp::decode(&p, Some(d), None, &wire).is_ok());
        let all = mutations(&p, d, &wire);
        assert!(all.iter().all(|m| m.as_slice() != wire));
        // The frame lengthened by one byte before its checksum, its length field made to
        // agree and its checksum repaired: length 3, checksum !(1 + 3 + 1 + 0x5A).
        let long = [0xFF, 0xFF, 0x01, 0x03, 0x01, 0x5A, 0xA0];
        assert!(all.iter().any(|m| m.as_slice() == long));
        let mut fixed = [0xFF, 0xFF, 0x01, 0x02, 0x01, 0x5A, 0x00];
        fix_length(&p, d, &mut fixed);
        reseal(&p, &mut fixed);
        assert_eq!(fixed, long);
        // A changed byte with the checksum repaired: the checksum is what the bytes give.
        let mut changed = [0xFF, 0xFF, 0x01 ^ 0x01, 0x02, 0x01, 0xFB];
        reseal(&p, &mut changed);
        assert_eq!(changed[5], !(0x02u8 + 0x01));
        assert!(all.iter().any(|m| m.as_slice() == changed));
    }
}
