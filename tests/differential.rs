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

use busspec_codegen::interp::{self, DecodeError as InterpError};
use busspec_codegen::ir::{Direction, Protocol};
use common::{interp_values, random_input, request_example, spec, Generated};

generated!(Ub2, ub2, "ub2.yaml");
generated!(Sd, sd, "sd.yaml");

fn random_inputs() -> usize {
    std::env::var("BUSSPEC_RANDOM_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(500_000)
}

/// Decodes `frame` with both engines in `direction` (as the reply to command `reply_to` if
/// given) and asserts they agree; returns whether it was accepted.
fn agree<G: Generated>(
    p: &Protocol,
    frame: &[u8],
    direction: Direction,
    reply_to: Option<usize>,
) -> bool {
    let reply_frame = reply_to.and_then(|c| request_example(p, c));
    let reply_to = reply_frame.and(reply_to);
    let oracle = interp::decode(p, Some(direction), reply_to, frame);
    let generated = match direction {
        Direction::Request => G::request(frame),
        Direction::Response => G::response(frame, reply_frame),
    };
    // decode_reply admits only responses the request may get; the interpreter uses the request
    // only to settle ambiguity, so hold it to the same rule here.
    let oracle = match (oracle, reply_to) {
        (Ok(f), Some(c))
            if !p.commands[c]
                .responses
                .iter()
                .any(|(r, _)| *r == f.message.index) =>
        {
            Err(None)
        }
        (Ok(f), _) => Ok(f),
        (Err(e), _) => Err(Some(e)),
    };
    let ctx = || {
        format!(
            "{} {direction:?} {} (reply to {reply_to:?})",
            G::FILE,
            interp::format_hex(frame)
        )
    };
    match (oracle, generated) {
        (Ok(f), Ok(g)) => {
            assert_eq!(g.name, p.message(f.message).name, "{}", ctx());
            assert_eq!(g.address, f.address, "{}", ctx());
            assert_eq!(g.values, interp_values(p, &f), "{}", ctx());
            assert_eq!(g.reencoded, frame, "re-encoding {}", ctx());
            true
        }
        (Err(Some(InterpError::Ambiguous { .. })), Err(g)) => {
            assert!(
                matches!(g, busspec_protocols::DecodeError::Ambiguous { .. }),
                "the interpreter finds it ambiguous, the generated code says {g}: {}",
                ctx()
            );
            false
        }
        (Err(_), Err(_)) => false,
        (Ok(f), Err(g)) => panic!(
            "only the interpreter accepts ({}), generated: {g}: {}",
            p.message(f.message).name,
            ctx()
        ),
        (Err(e), Ok(g)) => panic!(
            "only the generated code accepts ({}), interpreter: {e:?}: {}",
            g.name,
            ctx()
        ),
    }
}

fn every_example<G: Generated>() {
    let p = spec(G::FILE);
    for e in &p.examples {
        let reply_to = if p.message(e.message).needs_request {
            e.reply_to
        } else {
            None
        };
        assert!(
            agree::<G>(&p, &e.wire, e.message.direction, reply_to),
            "{} example §{} does not decode",
            G::FILE,
            e.section
        );
    }
}

fn random<G: Generated>(seed: u64) -> (usize, usize) {
    let p = spec(G::FILE);
    let mut rng = fastrand::Rng::with_seed(seed);
    let (mut accepted, n) = (0, random_inputs());
    for _ in 0..n {
        let frame = random_input(&p, &mut rng);
        let reply_to = rng.bool().then(|| rng.usize(..p.commands.len()));
        for d in [Direction::Request, Direction::Response] {
            accepted += usize::from(agree::<G>(&p, &frame, d, None));
        }
        if reply_to.is_some() {
            agree::<G>(&p, &frame, Direction::Response, reply_to);
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
