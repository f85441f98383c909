//! The bodies of busspec's fuzz targets, one plain function per target, so that the cargo-fuzz
//! crate (`fuzz/`, nightly) and `cargo test` (stable, over the seed corpus and every stored
//! regression input) run exactly the same checks. Each body panics on a broken promise and
//! returns normally otherwise.
//!
//! For each protocol, one generic body over [`Protocol`] per target, with a thin wrapper per
//! protocol ([`ub2`], [`sd`], [`modbus`], [`dynamixel`], [`pelco_d`], [`pelco_p`], [`crsf`], [`dynamixel2`]) that the fuzz
//! targets call by name:
//! * [`decode`]: arbitrary bytes through `decode_request`, `decode_response` and
//!   `decode_reply`; errors point inside the frame, and every accepted frame
//!   re-encodes to the same bytes;
//! * [`decode`]'s errors of the strict contract's kinds (address, broadcast, range) are the
//!   interpreter's too, for the same reason;
//! * [`roundtrip`]: `Arbitrary` messages → `encode` → `decode` → equal, and the interpreter's
//!   encoder writes the same frame; the encoded frame also goes through [`oracle::agree`]. A
//!   value that does not fit its wire field may be refused with `OutOfRange`; the strict
//!   contract's refusals (`BadAddress`, `BroadcastNotAccepted`, `NotInRange`) must be the
//!   interpreter's too, and the frame written anyway (by the interpreter of the spec stripped
//!   of ranges and address rules) is refused by both decoders for the same reason;
//! * [`stream`]: arbitrary bytes, cut into chunks the input chooses, through the `StreamDecoder`:
//!   bounded buffer, every byte in exactly one event, every frame valid, the same events however
//!   the bytes are cut and the same as the interpreter's stream decoder; then an example frame
//!   placed after the bytes is found;
//! * [`differential`]: the generated decoder and the interpreter agree on every input
//!   ([`oracle::agree`]).
//!
//! Modbus and Dynamixel have the generated `decode` and `stream` bodies
//! (`modbus_generated_decode`, ...), and [`interpreted`] has a decode and a stream body each
//! for the interpreter on its own (`modbus_decode`, ...), from before the generator emitted
//! them. Pelco D, Pelco P, CRSF and Dynamixel 2.0 have the generated `decode` and `stream` bodies alone
//! (`pelco_d_generated_decode`, ...).
//!
//! And [`spec_loader`]: arbitrary text through the loader and validator (and, when it loads,
//! the docs renderer and the code emitter): errors with messages, never a panic.
//!
//! Input layouts (so seeds and regression inputs can be written by hand):
//! * `decode`: the frame;
//! * `differential`: one byte choosing the command whose example request a response answers,
//!   then the frame;
//! * `stream` (and `*_generated_stream`): three bytes — direction (`% 3`: both, requests, responses), which example frame
//!   to place after the capture, the seed of the chunk sizes — then the capture;
//! * [`roundtrip`]: raw material for `arbitrary::Unstructured`;
//! * `spec_loader`: the spec text (invalid UTF-8 replaced).

use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use arbitrary::{Arbitrary, Unstructured};
use busspec_model::interp;
use busspec_model::ir::Direction;
use busspec_protocols::stream::{
    breaks_spec, Direction as StreamDirection, Event, StreamDecoder, MAX_SKIPPED_RUN,
};
use busspec_protocols::{
    DecodeError, Decoded, EncodeError, Message, Protocol, ProtocolVisitor, RequestMessage,
    ResponseMessage,
};

use crate::events::Seen;
use crate::oracle::{agree, visit_values};

pub mod events;
pub mod interpreted;
pub mod oracle;
pub mod seeds;

/// One fuzz target: its name (the `fuzz/fuzz_targets/<name>.rs` file, the corpus and
/// regression directories) and its body.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    pub name: &'static str,
    pub body: fn(&[u8]),
}

/// Every fuzz target, in the order CI runs them.
pub const TARGETS: &[Target] = &[
    Target {
        name: "ub2_decode",
        body: ub2::decode,
    },
    Target {
        name: "ub2_roundtrip",
        body: ub2::roundtrip,
    },
    Target {
        name: "ub2_stream",
        body: ub2::stream,
    },
    Target {
        name: "ub2_differential",
        body: ub2::differential,
    },
    Target {
        name: "sd_decode",
        body: sd::decode,
    },
    Target {
        name: "sd_roundtrip",
        body: sd::roundtrip,
    },
    Target {
        name: "sd_stream",
        body: sd::stream,
    },
    Target {
        name: "sd_differential",
        body: sd::differential,
    },
    Target {
        name: "spec_loader",
        body: spec_loader,
    },
    Target {
        name: "modbus_decode",
        body: modbus::decode,
    },
    Target {
        name: "modbus_stream",
        body: modbus::stream,
    },
    Target {
        name: "dynamixel_decode",
        body: dynamixel::decode,
    },
    Target {
        name: "dynamixel_stream",
        body: dynamixel::stream,
    },
    Target {
        name: "modbus_generated_decode",
        body: modbus::generated_decode,
    },
    Target {
        name: "modbus_generated_stream",
        body: modbus::generated_stream,
    },
    Target {
        name: "dynamixel_generated_decode",
        body: dynamixel::generated_decode,
    },
    Target {
        name: "dynamixel_generated_stream",
        body: dynamixel::generated_stream,
    },
    Target {
        name: "pelco_d_generated_decode",
        body: pelco_d::generated_decode,
    },
    Target {
        name: "pelco_d_generated_stream",
        body: pelco_d::generated_stream,
    },
    Target {
        name: "pelco_p_generated_decode",
        body: pelco_p::generated_decode,
    },
    Target {
        name: "pelco_p_generated_stream",
        body: pelco_p::generated_stream,
    },
    Target {
        name: "crsf_generated_decode",
        body: crsf::generated_decode,
    },
    Target {
        name: "crsf_generated_stream",
        body: crsf::generated_stream,
    },
    Target {
        name: "dynamixel2_generated_decode",
        body: dynamixel2::generated_decode,
    },
    Target {
        name: "dynamixel2_generated_stream",
        body: dynamixel2::generated_stream,
    },
];

/// The bodies for Modbus RTU, as the fuzz targets call them: the interpreter's own
/// ([`interpreted`]) and the generated code's.
pub mod modbus {
    use busspec_protocols::modbus::Modbus;

    pub use crate::interpreted::modbus::{decode, stream};

    /// [`crate::decode`] for the generated Modbus.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<Modbus>(data)
    }
    /// [`crate::stream`] for the generated Modbus.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<Modbus>(data)
    }
}

/// The bodies for Dynamixel 1.0, as the fuzz targets call them: the interpreter's own
/// ([`interpreted`]) and the generated code's.
pub mod dynamixel {
    use busspec_protocols::dynamixel::Dynamixel;

    pub use crate::interpreted::dynamixel::{decode, stream};

    /// [`crate::decode`] for the generated Dynamixel.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<Dynamixel>(data)
    }
    /// [`crate::stream`] for the generated Dynamixel.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<Dynamixel>(data)
    }
}

/// The bodies for Pelco D, as the fuzz targets call them: the generated code's (no interpreter
/// bodies of its own: [`crate::decode`] and [`crate::stream`] hold it to the interpreter).
pub mod pelco_d {
    use busspec_protocols::pelco_d::PelcoD;

    /// [`crate::decode`] for the generated Pelco D.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<PelcoD>(data)
    }
    /// [`crate::stream`] for the generated Pelco D.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<PelcoD>(data)
    }
}

/// The bodies for Pelco P, as the fuzz targets call them: the generated code's.
pub mod pelco_p {
    use busspec_protocols::pelco_p::PelcoP;

    /// [`crate::decode`] for the generated Pelco P.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<PelcoP>(data)
    }
    /// [`crate::stream`] for the generated Pelco P.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<PelcoP>(data)
    }
}

/// The bodies for Dynamixel 2.0, as the fuzz targets call them: the generated code's (byte
/// stuffing, CRC-16, records whose width a field gives; [`crate::decode`] and [`crate::stream`]
/// hold it to the interpreter).
pub mod dynamixel2 {
    use busspec_protocols::dynamixel2::Dynamixel2;

    /// [`crate::decode`] for the generated Dynamixel 2.0.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<Dynamixel2>(data)
    }
    /// [`crate::stream`] for the generated Dynamixel 2.0.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<Dynamixel2>(data)
    }
}

/// The bodies for CRSF, as the fuzz targets call them: the generated code's (its packed RC
/// channels, telemetry and extended frames; [`crate::decode`] and [`crate::stream`] hold it to
/// the interpreter).
pub mod crsf {
    use busspec_protocols::crsf::Crsf;

    /// [`crate::decode`] for the generated CRSF.
    pub fn generated_decode(data: &[u8]) {
        crate::decode::<Crsf>(data)
    }
    /// [`crate::stream`] for the generated CRSF.
    pub fn generated_stream(data: &[u8]) {
        crate::stream::<Crsf>(data)
    }
}

/// A value made once per process for the type `K`. Generic functions cannot have a `static` of
/// their own per type; this is that. The values are leaked (a handful per protocol) but stay
/// reachable from a `static`, so LeakSanitizer, which the fuzz builds run, does not report them:
/// a thread-local map is gone by the time it looks.
fn once<K: 'static, T: Send + Sync + 'static>(init: impl FnOnce() -> T) -> &'static T {
    type Made = Mutex<HashMap<TypeId, &'static (dyn Any + Send + Sync)>>;
    static MADE: OnceLock<Made> = OnceLock::new();
    let made = MADE.get_or_init(Default::default);
    let key = TypeId::of::<(K, T)>();
    let lock = || made.lock().unwrap_or_else(|e| e.into_inner());
    let found = lock().get(&key).copied();
    let v = match found {
        Some(v) => v,
        None => {
            // Not under the lock: `init` may itself call `once`.
            let v: &'static T = Box::leak(Box::new(init()));
            *lock().entry(key).or_insert(v)
        }
    };
    v.downcast_ref().expect("keyed by its type")
}

/// The spec of protocol `P`, as its code was generated from it
/// ([`Protocol::SOURCE.spec_yaml`]: embedded, so a fuzz binary needs no files), loaded once.
/// Whether protocol `P` escapes its frames (`framing.escaping`).
fn escapes<P: Protocol>() -> bool {
    spec::<P>().framing.escaping.is_some()
}

pub fn spec<P: Protocol>() -> &'static busspec_model::Protocol {
    once::<P, _>(|| {
        busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml).unwrap_or_else(|d| panic!("{d}"))
    })
}

/// The spec of the generated protocol called `name` (one of [`busspec_protocols::PROTOCOLS`]).
pub fn spec_named(name: &str) -> Option<&'static busspec_model::Protocol> {
    struct Spec;
    impl ProtocolVisitor for Spec {
        type Output = &'static busspec_model::Protocol;
        fn visit<P: Protocol>(self) -> Self::Output {
            spec::<P>()
        }
    }
    busspec_protocols::with_protocol(name, Spec)
}

/// A decode error must say where, and the place must be inside the `len`-byte frame. `escaped`:
/// the protocol escapes its frames (`framing.escaping`), whose lengths the errors give
/// unescaped, at most the bytes that travelled (offsets stay those of the bytes that travelled).
fn check_error(e: &DecodeError, len: usize, escaped: bool) {
    let same_len = |found: usize| if escaped { found <= len } else { found == len };
    assert!(!e.to_string().is_empty());
    match *e {
        DecodeError::Truncated { needed, found } => {
            assert!(same_len(found), "{e}");
            assert!(needed > found, "{e}");
        }
        DecodeError::BadStart {
            offset,
            expected,
            found,
        } => {
            assert!(offset < len && expected != found, "{e}")
        }
        DecodeError::BadEnd {
            offset,
            expected,
            found,
        } => assert!(offset < len && expected != found, "{e}"),
        DecodeError::ChecksumMismatch {
            offset,
            expected,
            found,
            width,
        } => assert!(offset < len && expected != found && width > 0, "{e}"),
        DecodeError::UnknownCommand { offset, .. }
        | DecodeError::UnknownResponse { offset, .. }
        | DecodeError::InvalidValue { offset, .. }
        | DecodeError::NotEqual { offset, .. }
        | DecodeError::NotBcd { offset, .. }
        | DecodeError::NotFollowing { offset, .. }
        | DecodeError::ByteCount { offset, .. }
        | DecodeError::BadEscape { offset, .. }
        | DecodeError::NeedsRequest { offset, .. } => {
            assert!(offset < len, "{e}")
        }
        DecodeError::NoTerminator { offset, within, .. } => {
            assert!(offset < len && offset + within <= len, "{e}")
        }
        DecodeError::EndInside { offset, end, .. } => {
            // Before the frame's own end bytes, which the frame holds after it.
            assert!(!end.is_empty() && offset + 2 * end.len() <= len, "{e}")
        }
        DecodeError::BadWidth {
            offset,
            found,
            most,
            ..
        } => assert!(offset < len && !(1..=most as i64).contains(&found), "{e}"),
        DecodeError::LengthMismatch {
            offset,
            expected,
            found,
        } => assert!(offset < len && expected != found, "{e}"),
        DecodeError::WrongLength {
            message,
            found,
            less,
        } => {
            assert!(
                same_len(found)
                    && !message
                        .lengths
                        .iter()
                        .any(|n| n.saturating_sub(less) == found)
                    && !message.name.is_empty(),
                "{e}"
            )
        }
        DecodeError::Ambiguous { .. } | DecodeError::NotAReply { .. } => {}
        DecodeError::TooLong { max, found } => assert!(same_len(found) && found > max, "{e}"),
        DecodeError::OutOfRange { offset, .. } | DecodeError::BadAddress { offset, .. } => {
            assert!(offset < len, "{e}")
        }
        DecodeError::BroadcastNotAccepted { .. } => {}
        DecodeError::NeedlessLong {
            offset,
            length,
            most,
        } => assert!(offset < len && length <= most, "{e}"),
        DecodeError::BadCount { offset, field, .. } => {
            assert!(offset < len && !field.message.is_empty(), "{e}")
        }
    }
}

/// The bodies for the generated protocol UB2, as the fuzz targets call them.
pub mod ub2 {
    use busspec_protocols::ub2::Ub2;

    /// [`crate::decode`] for UB2.
    pub fn decode(data: &[u8]) {
        crate::decode::<Ub2>(data)
    }
    /// [`crate::roundtrip`] for UB2.
    pub fn roundtrip(data: &[u8]) {
        crate::roundtrip::<Ub2>(data)
    }
    /// [`crate::stream`] for UB2.
    pub fn stream(data: &[u8]) {
        crate::stream::<Ub2>(data)
    }
    /// [`crate::differential`] for UB2.
    pub fn differential(data: &[u8]) {
        crate::differential::<Ub2>(data)
    }
}

/// The bodies for the generated protocol SD, as the fuzz targets call them.
pub mod sd {
    use busspec_protocols::sd::Sd;

    /// [`crate::decode`] for SD.
    pub fn decode(data: &[u8]) {
        crate::decode::<Sd>(data)
    }
    /// [`crate::roundtrip`] for SD.
    pub fn roundtrip(data: &[u8]) {
        crate::roundtrip::<Sd>(data)
    }
    /// [`crate::stream`] for SD.
    pub fn stream(data: &[u8]) {
        crate::stream::<Sd>(data)
    }
    /// [`crate::differential`] for SD.
    pub fn differential(data: &[u8]) {
        crate::differential::<Sd>(data)
    }
}

/// The first example request of every command of `P` that has one, with its command index.
pub fn example_requests<P: Protocol>() -> &'static [(usize, P::Request)] {
    once::<P, Vec<(usize, P::Request)>>(|| {
        let p = spec::<P>();
        (0..p.commands.len())
            .filter_map(|c| {
                let wire = oracle::request_example(p, c)?;
                let r = P::decode_request(wire).expect("an example request decodes");
                Some((c, r.message))
            })
            .collect()
    })
}

/// The frame `d` encodes to, into a buffer of `P`'s longest frame pre-filled with a pattern.
fn reencode<P: Protocol, M: Message>(d: &Decoded<M>) -> Vec<u8> {
    oracle::Decoded::new("", 0, Vec::new(), oracle::pattern_buffer::<P>(), |b| {
        d.message.encode(d.address, b)
    })
    .reencoded
}

/// Arbitrary bytes through every decoder of `P`.
pub fn decode<P: Protocol>(data: &[u8]) {
    match P::decode_request(data) {
        Ok(d) => {
            assert_eq!(reencode::<P, _>(&d), data, "{d:?} re-encodes differently");
        }
        Err(e) => {
            check_error(&e, data.len(), escapes::<P>());
            interp_refuses_alike::<P>(data, Direction::Request, &e);
        }
    }
    let alone = P::decode_response(data);
    match &alone {
        Ok(d) => {
            assert_eq!(reencode::<P, _>(d), data, "{d:?} re-encodes differently");
        }
        Err(e) => {
            check_error(e, data.len(), escapes::<P>());
            interp_refuses_alike::<P>(data, Direction::Response, e);
        }
    }
    for (_, r) in example_requests::<P>() {
        match P::decode_reply(data, r) {
            Ok(d) => {
                assert!(d.message.answers(r), "{d:?} does not answer {r:?}");
                // A reply decodes alone too, unless only its request can tell it.
                match alone {
                    Ok(a) => assert_eq!(a, d),
                    Err(DecodeError::Ambiguous { .. }) => {}
                    Err(e) => panic!("{d:?} decodes as a reply but alone: {e}"),
                }
                assert_eq!(reencode::<P, _>(&d), data, "{d:?} re-encodes differently");
            }
            Err(e) => {
                check_error(&e, data.len(), escapes::<P>());
                if let Ok(a) = alone {
                    assert!(
                        !a.message.answers(r),
                        "{a:?} answers {r:?}, but decode_reply says {e}"
                    );
                }
            }
        }
    }
}

/// Arbitrary typed messages of `P` through encode and back.
pub fn roundtrip<P: Protocol>(data: &[u8])
where
    P::Request: for<'a> Arbitrary<'a>,
    P::Response: for<'a> Arbitrary<'a>,
{
    let mut u = Unstructured::new(data);
    // Several messages per input, while the input lasts.
    for _ in 0..64 {
        if u.is_empty() {
            break;
        }
        let Ok(request) = u.arbitrary::<Decoded<P::Request>>() else {
            break;
        };
        request_roundtrip::<P>(&request);
        let Ok(response) = u.arbitrary::<Decoded<P::Response>>() else {
            break;
        };
        response_roundtrip::<P>(&response);
    }
}

/// What the strict contract refuses, in words both engines and both directions share: an
/// address no frame may carry, the broadcast address for a command that does not accept it, a
/// value outside its field's spec range.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Refusal {
    Address(u8),
    Broadcast {
        message: String,
        address: u8,
    },
    Range {
        field: String,
        value: i64,
        min: i64,
        max: i64,
    },
    /// A list with a count its spec does not allow.
    Count {
        field: String,
        min: usize,
        max: usize,
        found: usize,
    },
}

impl Refusal {
    fn of_encode(e: &EncodeError) -> Option<Refusal> {
        Some(match *e {
            EncodeError::BadAddress { address, .. } | EncodeError::Unaddressed { address } => {
                Refusal::Address(address)
            }
            EncodeError::BroadcastNotAccepted { message, address } => Refusal::Broadcast {
                message: message.name.to_owned(),
                address,
            },
            EncodeError::NotInRange {
                field,
                value,
                min,
                max,
                ..
            } => Refusal::Range {
                field: field.to_owned(),
                value,
                min,
                max,
            },
            EncodeError::WrongCount {
                field,
                min,
                max,
                found,
            } => Refusal::Count {
                field: field.to_owned(),
                min,
                max,
                found,
            },
            _ => return None,
        })
    }

    fn of_interp_encode(e: &interp::EncodeError) -> Option<Refusal> {
        Some(match e {
            interp::EncodeError::BadAddress { address, .. }
            | interp::EncodeError::Unaddressed { address } => Refusal::Address(*address),
            interp::EncodeError::BroadcastNotAccepted { message, address } => Refusal::Broadcast {
                message: message.clone(),
                address: *address,
            },
            interp::EncodeError::NotInRange {
                field,
                value,
                min,
                max,
                ..
            } => Refusal::Range {
                field: field.clone(),
                value: *value,
                min: *min,
                max: *max,
            },
            interp::EncodeError::WrongCount {
                field,
                min,
                max,
                found,
            } => Refusal::Count {
                field: field.clone(),
                min: *min,
                max: *max,
                found: *found,
            },
            _ => return None,
        })
    }

    fn of_decode(e: &DecodeError) -> Option<Refusal> {
        Some(match *e {
            DecodeError::BadAddress { found, .. } => Refusal::Address(found),
            DecodeError::BroadcastNotAccepted { message, address } => Refusal::Broadcast {
                message: message.name.to_owned(),
                address,
            },
            DecodeError::OutOfRange {
                field,
                found,
                min,
                max,
                ..
            } => Refusal::Range {
                field: field.name.to_owned(),
                value: found,
                min,
                max,
            },
            _ => return None,
        })
    }

    fn of_interp_decode(e: &interp::DecodeError) -> Option<Refusal> {
        Some(match e {
            interp::DecodeError::BadAddress { found, .. } => Refusal::Address(*found),
            interp::DecodeError::BroadcastNotAccepted {
                message, address, ..
            } => Refusal::Broadcast {
                message: message.clone(),
                address: *address,
            },
            interp::DecodeError::OutOfRange {
                field,
                found,
                min,
                max,
                ..
            } => Refusal::Range {
                field: field.clone(),
                value: *found,
                min: *min,
                max: *max,
            },
            _ => return None,
        })
    }
}

/// A decode error of the strict contract's kinds (address, broadcast, range) from the generated
/// decoder of `P`: the interpreter refuses the same frame in the same direction for the same
/// reason.
fn interp_refuses_alike<P: Protocol>(frame: &[u8], direction: Direction, e: &DecodeError) {
    let Some(want) = Refusal::of_decode(e) else {
        return;
    };
    let p = spec::<P>();
    match interp::decode(p, Some(direction), None, frame) {
        Ok(f) => panic!(
            "the generated decoder says {e}, the interpreter accepts {}: {}",
            p.message(f.message).name,
            events::hex(frame)
        ),
        Err(i) => assert!(
            same_refusal(p, Refusal::of_interp_decode(&i).as_ref(), &want),
            "the generated decoder says {e}, the interpreter {i:?}: {}",
            events::hex(frame)
        ),
    }
}

/// How many messages [`roundtrip`] checked on this thread, by outcome.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RoundtripCounts {
    /// Encoded by both engines alike (and decoded back equal).
    pub encoded: usize,
    /// Refused by both encoders for the same strict-contract reason.
    pub refused: usize,
    /// Of those, written anyway by the lenient interpreter and refused by both decoders for
    /// that reason.
    pub refused_on_decode: usize,
}

thread_local! {
    static COUNTS: std::cell::Cell<RoundtripCounts> = std::cell::Cell::new(RoundtripCounts::default());
}

/// What [`roundtrip`] has checked on this thread so far (tests use it to see that the strict
/// refusals are exercised, not only possible).
pub fn roundtrip_counts() -> RoundtripCounts {
    COUNTS.with(|c| c.get())
}

fn count(f: impl FnOnce(&mut RoundtripCounts)) {
    COUNTS.with(|c| {
        let mut v = c.get();
        f(&mut v);
        c.set(v);
    });
}

/// Whether decode refused for the reason encode gave. The broadcast check comes before the
/// constant arguments that tell apart requests sharing a code (SD 0xA7: read or reset), so
/// decode may name another request with the same code that refuses broadcast too.
fn same_refusal(p: &busspec_model::ir::Protocol, decoded: Option<&Refusal>, why: &Refusal) -> bool {
    match (decoded, why) {
        (
            Some(Refusal::Broadcast { message, address }),
            Refusal::Broadcast {
                message: encoded,
                address: to,
            },
        ) => {
            let code = |name: &str| {
                p.find_in(name, Direction::Request)
                    .map(|r| p.message(r).code.clone())
            };
            address == to && code(message).is_some() && code(message) == code(encoded)
        }
        (d, w) => d == Some(w),
    }
}

/// What encoding one message gave.
enum Encoded {
    /// The frame, written alike into buffers of every size that holds it.
    Frame(Vec<u8>),
    /// A typed value does not fit its wire field (`EncodeError::OutOfRange`).
    DoesNotFit,
    /// The strict contract refuses the message.
    Refused(Refusal),
}

/// Encodes `d` into a buffer of exactly its length and into one a byte short.
fn encode_checked<P: Protocol>(
    encode: impl Fn(&mut [u8]) -> Result<usize, EncodeError>,
    frame_len: usize,
) -> Encoded {
    let mut buf = oracle::pattern_buffer::<P>();
    let buf = buf.as_mut();
    match encode(buf) {
        Ok(n) => {
            assert_eq!(n, frame_len, "encode and frame_len disagree");
            let mut exact = vec![0x5Au8; n];
            assert_eq!(encode(&mut exact), Ok(n));
            assert_eq!(exact, buf[..n], "encode depends on the buffer");
            let mut short = vec![0u8; n - 1];
            assert_eq!(
                encode(&mut short),
                Err(EncodeError::BufferTooSmall {
                    needed: n,
                    available: n - 1
                })
            );
            Encoded::Frame(exact)
        }
        Err(EncodeError::OutOfRange { .. }) => Encoded::DoesNotFit,
        Err(e) => match Refusal::of_encode(&e) {
            Some(r) => Encoded::Refused(r),
            None => panic!("encode into MAX_FRAME_LEN bytes: {e}"),
        },
    }
}

/// `P`'s spec with nothing of the strict contract: no ranges, every address allowed, no
/// broadcast rule. Its interpreter writes the frames the strict encoders refuse.
fn lenient<P: Protocol>() -> &'static busspec_model::ir::Protocol {
    struct Lenient;
    once::<(P, Lenient), _>(|| {
        let mut p = spec::<P>().clone();
        p.framing.address.min = 0;
        p.framing.address.max = u8::MAX;
        p.framing.address.broadcast = None;
        p.framing.address.host = None;
        for m in p.commands.iter_mut().chain(p.responses.iter_mut()) {
            for f in &mut m.fields {
                f.range = None;
                for b in &mut f.bits {
                    b.range = None;
                }
            }
        }
        p
    })
}

/// The message `name` of `direction`, for `address` with `values`, through the interpreter of
/// `p`.
fn interp_encode(
    p: &busspec_model::ir::Protocol,
    direction: Direction,
    name: &str,
    address: u8,
    values: &oracle::Values,
) -> Result<Vec<u8>, interp::EncodeError> {
    let r = p
        .find_in(name, direction)
        .unwrap_or_else(|| panic!("{name} is not a {direction:?} of the spec"));
    let values: Vec<interp::Value> = values
        .iter()
        .map(|(name, raw)| interp::Value {
            name: name.clone().into(),
            raw: raw.clone(),
        })
        .collect();
    interp::encode(p, r, address, &values)
}

/// The strict contract both ways for one typed message: the interpreter's encoder agrees with
/// the generated one (the same frame, or the same refusal), and a refused message, written
/// anyway by the interpreter of the [`lenient`] spec, is refused by both decoders for the same
/// reason. Returns the frame if it encoded; if it was refused, the reason and the frame the
/// lenient interpreter wrote (if a value did not also overflow its wire field).
fn encode_both_ways<P: Protocol, M: Message>(
    d: &Decoded<M>,
    direction: Direction,
    decode: impl Fn(&[u8]) -> Result<Decoded<M>, DecodeError>,
) -> Result<Vec<u8>, Option<(Refusal, Vec<u8>)>> {
    let p = spec::<P>();
    let name = d.message.name();
    let values = visit_values(|f| d.message.visit(f));
    let encoded = encode_checked::<P>(|b| d.message.encode(d.address, b), d.message.frame_len());
    let interp = interp_encode(p, direction, name, d.address, &values);
    match encoded {
        Encoded::Frame(frame) => {
            assert_eq!(
                interp.as_ref(),
                Ok(&frame),
                "{d:?}: the interpreter does not write the generated frame {}",
                events::hex(&frame)
            );
            count(|c| c.encoded += 1);
            Ok(frame)
        }
        Encoded::DoesNotFit => Err(None),
        Encoded::Refused(why) => {
            match &interp {
                Ok(f) => panic!(
                    "{d:?} refused ({why:?}), but the interpreter writes {}",
                    events::hex(f)
                ),
                Err(e) => assert_eq!(
                    Refusal::of_interp_encode(e).as_ref(),
                    Some(&why),
                    "{d:?}: the interpreter refuses with {e}"
                ),
            }
            count(|c| c.refused += 1);
            // The same bytes another way: the lenient spec's interpreter writes them (unless a
            // value does not fit its wire field either); both strict decoders refuse them for
            // the reason encode gave (both check address, broadcast, then fields in order).
            let Ok(frame) = interp_encode(lenient::<P>(), direction, name, d.address, &values)
            else {
                return Err(None);
            };
            match decode(&frame) {
                // Responses that share code and length (only their request tells them apart)
                // may be another message, one whose values are in range: still not `d`. The
                // reply to `d`'s requests is checked by the caller.
                Ok(back) if direction == Direction::Response && back.message.name() != name => {
                    assert!(
                        agree::<P>(p, &frame, direction, None),
                        "{}",
                        events::hex(&frame)
                    );
                }
                Ok(back) => panic!(
                    "{d:?} refused ({why:?}), but {} decodes as {back:?}",
                    events::hex(&frame)
                ),
                Err(e) => {
                    match e {
                        DecodeError::Ambiguous { .. } => {
                            assert_eq!(direction, Direction::Response, "{}", events::hex(&frame));
                        }
                        e => {
                            check_error(&e, frame.len(), escapes::<P>());
                            assert!(
                                same_refusal(p, Refusal::of_decode(&e).as_ref(), &why),
                                "{d:?} refused ({why:?}), {} decodes to {e}",
                                events::hex(&frame)
                            );
                            interp_refuses_alike::<P>(&frame, direction, &e);
                        }
                    }
                    assert!(
                        !agree::<P>(p, &frame, direction, None),
                        "{}",
                        events::hex(&frame)
                    );
                }
            }
            count(|c| c.refused_on_decode += 1);
            Err(Some((why, frame)))
        }
    }
}

fn request_roundtrip<P: Protocol>(d: &Decoded<P::Request>) {
    let Ok(frame) = encode_both_ways::<P, _>(d, Direction::Request, P::decode_request) else {
        return;
    };
    assert_eq!(P::decode_request(&frame), Ok(*d), "{}", events::hex(&frame));
    assert_eq!(
        d.message.code(),
        code_of::<P>(&frame, d.message.code().len())
    );
    assert!(agree::<P>(spec::<P>(), &frame, Direction::Request, None));
}

fn response_roundtrip<P: Protocol>(d: &Decoded<P::Response>) {
    let frame = match encode_both_ways::<P, _>(d, Direction::Response, P::decode_response) {
        Ok(frame) => frame,
        Err(None) => return,
        Err(Some((why, frame))) => {
            // Refused: as the reply to every example request it answers, refused alike.
            let p = spec::<P>();
            for (c, r) in example_requests::<P>() {
                if d.message.answers(r) {
                    match P::decode_reply(&frame, r) {
                        Ok(back) => panic!(
                            "{d:?} refused ({why:?}), but {} decodes as the reply to {r:?}: {back:?}",
                            events::hex(&frame)
                        ),
                        Err(e) => {
                            check_error(&e, frame.len(), escapes::<P>());
                            assert!(
                                same_refusal(p, Refusal::of_decode(&e).as_ref(), &why),
                                "{d:?} as the reply to {r:?}: {e}"
                            );
                        }
                    }
                    assert!(!agree::<P>(p, &frame, Direction::Response, Some(*c)));
                }
            }
            return;
        }
    };
    let p = spec::<P>();
    let needs_request = match P::decode_response(&frame) {
        Ok(back) => {
            assert_eq!(back, *d, "{}", events::hex(&frame));
            assert!(agree::<P>(p, &frame, Direction::Response, None));
            false
        }
        Err(DecodeError::Ambiguous { .. }) => {
            assert!(!agree::<P>(p, &frame, Direction::Response, None));
            true
        }
        Err(e) => panic!("{d:?} encodes to {} but: {e}", events::hex(&frame)),
    };
    let mut answered = false;
    for (c, r) in example_requests::<P>() {
        if d.message.answers(r) {
            answered = true;
            assert_eq!(
                P::decode_reply(&frame, r),
                Ok(*d),
                "as the reply to {r:?}: {}",
                events::hex(&frame)
            );
            assert!(agree::<P>(p, &frame, Direction::Response, Some(*c)));
        }
    }
    assert!(
        answered || !needs_request,
        "{} needs its request, but no example request gets it",
        d.message.name()
    );
}

/// Where `encode` wrote the code: the bytes of the code in the frame.
fn code_of<P: Protocol>(frame: &[u8], len: usize) -> &[u8] {
    let p = spec::<P>();
    let o = p.framing.head(busspec_model::ir::Direction::Request, len);
    &frame[o.code..o.code + len]
}

/// The events of `P`'s stream decoder.
pub type Events<P> = Vec<Event<<P as Protocol>::Request, <P as Protocol>::Response>>;

/// `capture` cut into pieces of the lengths in `chunks` (the last up to the end), none empty.
fn pieces<'c>(capture: &'c [u8], chunks: &'c [usize]) -> impl Iterator<Item = &'c [u8]> + 'c {
    let mut rest = capture;
    let mut cuts = chunks.iter().copied().chain(std::iter::once(usize::MAX));
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let (chunk, r) = rest.split_at(cuts.next().unwrap_or(1).min(rest.len()));
        rest = r;
        Some(chunk)
    })
}

/// `capture` through the generated stream decoder of `P` for `direction`, pushed in `chunks`
/// (the rest in one piece) with push/poll, then finished. Asserts the buffer never grows past
/// the longest frame and the decoder never stalls.
pub fn stream_events<P: Protocol>(
    direction: Option<StreamDirection>,
    capture: &[u8],
    chunks: &[usize],
) -> Events<P> {
    let mut d = StreamDecoder::<P>::new(direction);
    let mut out = Vec::new();
    for mut chunk in pieces(capture, chunks) {
        while !chunk.is_empty() {
            let n = d.push(chunk);
            chunk = &chunk[n..];
            let before = out.len();
            while let Some(e) = d.poll() {
                out.push(e);
            }
            assert!(
                d.buffered() <= P::MAX_FRAME_LEN,
                "buffer past the longest frame"
            );
            assert!(
                n > 0 || out.len() > before,
                "the decoder takes no bytes and settles nothing"
            );
        }
    }
    while let Some(e) = d.finish() {
        out.push(e);
    }
    assert_eq!(d.buffered(), 0, "finish left bytes buffered");
    assert_eq!(d.position(), capture.len() as u64);
    out
}

/// `capture` through [`StreamDecoder::feed`] in `chunks` (the rest in one piece), each chunk's
/// events taken with `for_each` (the iterator's own loop, which runs the fast path), then
/// finished: the same events as [`stream_events`] must give.
pub fn fed_events<P: Protocol>(
    direction: Option<StreamDirection>,
    capture: &[u8],
    chunks: &[usize],
) -> Events<P> {
    let mut d = StreamDecoder::<P>::new(direction);
    let mut out = Vec::new();
    for chunk in pieces(capture, chunks) {
        d.feed(chunk).for_each(|e| out.push(e));
    }
    out.extend(std::iter::from_fn(|| d.finish()));
    out
}

/// The generated decoder's events, for comparing with the interpreter's.
pub fn seen<P: Protocol>(events: &[Event<P::Request, P::Response>]) -> Vec<Seen> {
    events::merge(events.iter().map(|e| match *e {
        Event::Request { offset, len, frame } => Seen::Frame {
            offset,
            len: len as u64,
            name: frame.message.name().to_owned(),
            address: frame.address,
            values: visit_values(|f| frame.message.visit(f)),
        },
        Event::Response { offset, len, frame } => Seen::Frame {
            offset,
            len: len as u64,
            name: frame.message.name().to_owned(),
            address: frame.address,
            values: visit_values(|f| frame.message.visit(f)),
        },
        Event::Ambiguous { offset, len, .. } => Seen::Ambiguous {
            offset,
            len: len as u64,
        },
        Event::Skipped { offset, len } => Seen::Skipped { offset, len },
        Event::OutOfSpec {
            offset,
            len,
            reason,
        } => Seen::OutOfSpec {
            offset,
            len: len as u64,
            reason: events::Why::of(&reason),
        },
    }))
}

/// Every event is what it claims to be.
fn check_events<P: Protocol>(
    direction: Option<StreamDirection>,
    capture: &[u8],
    evs: &[Event<P::Request, P::Response>],
) {
    // The last request's bytes, which a reply's checksum may take in.
    let mut request: &[u8] = &[];
    for e in evs {
        let bytes = events::bytes_of(capture, e.offset(), e.len());
        match *e {
            Event::Request { frame, .. } => {
                assert_ne!(direction, Some(StreamDirection::Response));
                assert_eq!(P::decode_request(bytes), Ok(frame));
                request = bytes;
                continue;
            }
            Event::Response { frame, .. } => {
                assert_ne!(direction, Some(StreamDirection::Request));
                if let Err(DecodeError::NeedsRequest { .. }) = P::decode_response(bytes) {
                    // A reply whose checksum takes in the bytes of the request before it.
                    let mut buf = oracle::pattern_buffer::<P>();
                    let n = P::encode_reply(&frame.message, frame.address, request, buf.as_mut())
                        .unwrap_or_else(|e| panic!("{frame:?} does not encode: {e}"));
                    assert_eq!(&buf.as_ref()[..n], bytes, "{frame:?} is not its bytes");
                    let covered = Some(P::Request::covered(request));
                    assert_eq!(
                        P::Response::decode_as_reply_over(bytes, None, covered),
                        Ok(frame)
                    );
                    request = &[];
                    continue;
                }
                assert_eq!(
                    reencode::<P, _>(&frame),
                    bytes,
                    "{frame:?} is not its bytes"
                );
                match P::decode_response(bytes) {
                    Ok(d) => assert_eq!(d, frame),
                    Err(DecodeError::Ambiguous { .. }) => {}
                    Err(e) => panic!("{frame:?} found in bytes that say {e}"),
                }
            }
            Event::Ambiguous { .. } => {
                let both = P::decode_request(bytes).is_ok()
                    && P::decode_response(bytes).is_ok()
                    && direction.is_none();
                let reply = matches!(
                    P::decode_response(bytes),
                    Err(DecodeError::Ambiguous { .. })
                );
                assert!(both || reply, "ambiguous {}", events::hex(bytes));
            }
            Event::Skipped { len, .. } => {
                assert!(len > 0 && len <= MAX_SKIPPED_RUN, "skipped {len}");
                // Noise leaves the pairing as it was.
                continue;
            }
            Event::OutOfSpec { reason, .. } => {
                // It checksums (a reply whose checksum takes in its request's bytes: over
                // those of the request before it), and strict decoding refuses it for a rule
                // of the spec: that reason, in a direction the decoder decodes.
                let covered = Some(P::Request::covered(request));
                let over = !request.is_empty()
                    && P::decode_response(bytes)
                        .is_err_and(|e| matches!(e, DecodeError::NeedsRequest { .. }));
                assert!(
                    P::checksum_ok(bytes) || over,
                    "out of spec {}",
                    events::hex(bytes)
                );
                assert!(breaks_spec(&reason), "out of spec for {reason}");
                let as_request = direction != Some(StreamDirection::Response)
                    && P::decode_request(bytes) == Err(reason);
                let as_response = direction != Some(StreamDirection::Request)
                    && (P::decode_response(bytes) == Err(reason)
                        || (over
                            && P::Response::decode_as_reply_over(bytes, None, covered)
                                == Err(reason)));
                assert!(
                    as_request || as_response,
                    "out of spec for {reason}: {}",
                    events::hex(bytes)
                );
            }
        }
        // A response, an ambiguous or out-of-spec frame: no request to pair with after it.
        request = &[];
    }
}

/// Arbitrary bytes through the stream decoder of `P`, then an example frame after them.
pub fn stream<P: Protocol>(data: &[u8]) {
    let Some((&[mode, pick, cut], capture)) = data.split_first_chunk::<3>() else {
        return;
    };
    let p = spec::<P>();
    let direction = match mode % 3 {
        0 => None,
        1 => Some(StreamDirection::Request),
        _ => Some(StreamDirection::Response),
    };
    let chunks = events::chunks(cut, capture.len(), 2 * P::MAX_FRAME_LEN);
    let evs = stream_events::<P>(direction, capture, &chunks);
    check_events::<P>(direction, capture, &evs);
    let got = seen::<P>(&evs);
    events::covers(&got, capture.len() as u64);
    assert_eq!(
        stream_events::<P>(direction, capture, &[]),
        evs,
        "events depend on how the bytes are cut"
    );
    assert_eq!(
        fed_events::<P>(direction, capture, &chunks),
        evs,
        "feed and push/poll differ"
    );
    let want = events::interp_events(p, events::direction(direction), capture, &chunks);
    assert_eq!(got, want, "capture {}", events::hex(capture));

    // An example frame after the bytes is found, unless a frame that starts in them runs into
    // it.
    let e = &p.examples[usize::from(pick) % p.examples.len()];
    let dir = match e.message.direction {
        Direction::Request => Some(StreamDirection::Request),
        // A reply whose checksum takes in its request's bytes comes after its request (the
        // example gives it), both directions decoded.
        Direction::Response if e.request.is_some() => None,
        Direction::Response => Some(StreamDirection::Response),
    };
    let mut whole = capture.to_vec();
    // Where the frames after the bytes begin, and where the example begins.
    let first = capture.len() as u64;
    whole.extend_from_slice(e.request.as_deref().unwrap_or_default());
    let at = whole.len() as u64;
    whole.extend_from_slice(&e.wire);
    let evs = stream_events::<P>(dir, &whole, &chunks);
    check_events::<P>(dir, &whole, &evs);
    let found = evs.iter().any(|ev| {
        !matches!(ev, Event::Skipped { .. }) && ev.offset() == at && ev.len() == e.wire.len() as u64
    });
    let swallowed = evs.iter().any(|ev| {
        !matches!(ev, Event::Skipped { .. })
            && ev.offset() < first
            && ev.offset() + ev.len() > first
    });
    assert!(
        found || swallowed,
        "example §{} after {} lost: {evs:?}",
        e.section,
        events::hex(capture)
    );
}

/// The generated decoder of `P` and the interpreter on the same bytes, both directions and as
/// the reply to a chosen command.
pub fn differential<P: Protocol>(data: &[u8]) {
    let Some((&pick, frame)) = data.split_first() else {
        return;
    };
    let p = spec::<P>();
    agree::<P>(p, frame, Direction::Request, None);
    agree::<P>(p, frame, Direction::Response, None);
    let command = usize::from(pick) % p.commands.len();
    agree::<P>(p, frame, Direction::Response, Some(command));
}

/// Arbitrary text through the loader and validator; a spec that loads is also rendered as docs
/// and emitted as code.
pub fn spec_loader(data: &[u8]) {
    const LABEL: &str = "fuzz.yaml";
    let text = String::from_utf8_lossy(data);
    match busspec_model::load_str(LABEL, &text) {
        Ok(p) => {
            let _ = busspec_model::docs::render(&p, LABEL);
            let emitted = busspec_codegen::emit::emit_module(&p, LABEL, LABEL);
            match (p.generator_gaps().is_empty(), emitted) {
                (true, Err(e)) => panic!("a spec that loads does not emit: {e}"),
                // What the generator cannot emit yet it refuses by name, never half-emits.
                (false, Ok(_)) => panic!("a spec the generator cannot emit was emitted"),
                _ => {}
            }
        }
        Err(d) => {
            assert!(!d.items.is_empty(), "an error without a diagnostic");
            assert_eq!(d.file, LABEL);
            for i in &d.items {
                assert!(
                    !i.message.trim().is_empty(),
                    "empty message at `{}`",
                    i.path
                );
            }
        }
    }
}
