//! `interp::Lookup` decodes exactly as `interp::decode` does, errors included, and
//! `Lookup::decode_paired` exactly as the stream decoder paired a response before it (decode
//! without the request; where that is ambiguous, with the request if that settles it): on
//! every example of the four specs and a variable-length fixture, and on thousands of variations of them (a byte changed, cut
//! short, one byte more), for every direction and with and without a request.

use busspec_model::checksum;
use busspec_model::interp::{self, DecodeError, Lookup};
use busspec_model::ir::Direction;
use busspec_model::{load_str, Protocol};

fn specs() -> Vec<Protocol> {
    [
        ("ub2.yaml", include_str!("../../spec/ub2.yaml")),
        ("sd.yaml", include_str!("../../spec/sd.yaml")),
        // Variable-length frames: a variable message stands in the lookup under every length
        // it can have.
        ("modbus.yaml", include_str!("../../spec/modbus.yaml")),
        ("dynamixel.yaml", include_str!("../../spec/dynamixel.yaml")),
        (
            "minimal_variable.yaml",
            include_str!("fixtures/valid/minimal_variable.yaml"),
        ),
    ]
    .into_iter()
    .map(|(file, text)| load_str(file, text).unwrap_or_else(|d| panic!("{d}")))
    .collect()
}

/// `wire` with its checksum made right again.
fn repaired(p: &Protocol, mut wire: Vec<u8>) -> Vec<u8> {
    let c = &p.framing.checksum;
    if let Some(at) = wire.len().checked_sub(c.len()) {
        let sum = checksum::compute(&c.algorithm, &wire[..at]);
        interp::write_uint(sum, &mut wire[at..], c.byte_order);
    }
    wire
}

/// Each example, and each with one byte changed (with and without its checksum repaired),
/// cut short or one byte longer.
fn frames(p: &Protocol) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for e in &p.examples {
        out.push(e.wire.clone());
        for i in 0..e.wire.len() {
            for v in [0x00, 0x1F, 0x7F, 0xFF] {
                let mut w = e.wire.clone();
                w[i] = v;
                out.push(repaired(p, w.clone()));
                out.push(w);
            }
            out.push(e.wire[..i].to_vec());
        }
        let mut longer = e.wire.clone();
        longer.push(0x00);
        out.push(longer);
    }
    out
}

/// The stream decoder's pairing as it was written: two decodes; a frame that is a request and
/// a response too stays ambiguous (pairing never decides a frame's direction).
fn paired_twice<'p>(
    p: &'p Protocol,
    direction: Option<Direction>,
    request: Option<usize>,
    wire: &[u8],
) -> Result<interp::Frame<'p>, DecodeError> {
    match interp::decode(p, direction, None, wire) {
        Err(DecodeError::Ambiguous { candidates })
            if [Direction::Request, Direction::Response]
                .iter()
                .all(|&d| candidates.iter().any(|c| p.find_in(c, d).is_some())) =>
        {
            Err(DecodeError::Ambiguous { candidates })
        }
        Err(DecodeError::Ambiguous { candidates }) => {
            match request.map(|r| interp::decode(p, direction, Some(r), wire)) {
                Some(Ok(frame)) => Ok(frame),
                _ => Err(DecodeError::Ambiguous { candidates }),
            }
        }
        other => other,
    }
}

#[test]
fn lookup_decodes_as_decode_does() {
    let mut checked = 0;
    let mut kinds = std::collections::BTreeSet::new();
    for p in specs() {
        // No request, and each request an example answers.
        let mut requests: Vec<Option<usize>> = std::iter::once(None)
            .chain(p.examples.iter().filter_map(|e| e.reply_to).map(Some))
            .collect();
        requests.sort_unstable();
        requests.dedup();
        for direction in [None, Some(Direction::Request), Some(Direction::Response)] {
            let lookup = Lookup::new(&p, direction);
            for wire in frames(&p) {
                // Every request where the frame is ambiguous without one; else one request
                // (any other settles nothing either: `decode` only filters among several).
                let ambiguous = matches!(
                    interp::decode(&p, direction, None, &wire),
                    Err(DecodeError::Ambiguous { .. })
                );
                let tried = if ambiguous {
                    &requests[..]
                } else {
                    requests.get(..2).unwrap_or(&requests)
                };
                for &r in tried {
                    let want = interp::decode(&p, direction, r, &wire);
                    assert_eq!(
                        lookup.decode(&p, r, &wire),
                        want,
                        "{} {direction:?} reply_to {r:?} {wire:02X?}",
                        p.name
                    );
                    assert_eq!(
                        lookup.decode_paired(&p, r, &wire),
                        paired_twice(&p, direction, r, &wire),
                        "{} {direction:?} paired with {r:?} {wire:02X?}",
                        p.name
                    );
                    kinds.insert(match &want {
                        Ok(_) => "frame".to_owned(),
                        Err(e) => format!("{e:?}")
                            .split([' ', '{'])
                            .next()
                            .unwrap_or("")
                            .to_owned(),
                    });
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 20_000, "{checked}");
    // The variations reach every kind of outcome the lookup could get wrong.
    for kind in [
        "frame",
        "Ambiguous",
        "ChecksumMismatch",
        "Truncated",
        "TooLong",
        "UnknownCode",
        "BadAddress",
        "ConstantMismatch",
    ] {
        assert!(kinds.contains(kind), "no {kind} among {kinds:?}");
    }
}
