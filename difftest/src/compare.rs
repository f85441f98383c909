//! The two engines on one generated protocol: decode (examples, random frames, mutated,
//! truncated and lengthened frames, noise; as request, response and reply to each command),
//! encode (example and random values) and stream events (captures cut into random chunks, in
//! both directions). Every disagreement is recorded with what each engine said, and the run
//! goes on; a panic in either engine is one.
//!
//! The decoded values and stream events are reduced to what both engines report by
//! `busspec_fuzz_bodies` (`oracle::interp_values`, `visit_values`, `events::interp_events`,
//! `seen`, `stream_events`), the same reductions the fuzz targets compare. A frame both refuse
//! is refused in the same words ([`same_error`]); a message both encoders refuse is refused
//! for the same fault of the same field ([`same_encode_error`]), but where the generated code's
//! typed check (`from_fields`) refuses first: the interpreter's values are untyped.

use std::cell::RefCell;
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};

use busspec_fuzz_bodies::events::{self, Seen};
use busspec_fuzz_bodies::oracle::{interp_values, visit_values, Values};
use busspec_fuzz_bodies::{seen, stream_events};
use busspec_model::interp::{self, DecodeError as InterpError, Raw, Value};
use busspec_model::ir::{self, Count, Direction, MessageRef};
use busspec_model::mutate::{after_preamble, mutations, reseal_as};
use busspec_runtime::stream::Direction as StreamDirection;
use busspec_runtime::{
    DecodeError, Elements, EncodeError, FieldValue, Message, Protocol, RequestMessage,
    ResponseMessage,
};

use crate::values::random_values;

/// How much to compare per spec.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    /// Random inputs (random frames, noise, mutations of random frames) per spec.
    pub random_frames: usize,
    /// Random value sets per message for encoding.
    pub encodes_per_message: usize,
    /// Random captures per direction.
    pub captures: usize,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            random_frames: 400,
            encodes_per_message: 24,
            captures: 12,
        }
    }
}

/// One disagreement, self-contained: what was compared and what each engine said.
#[derive(Debug, Clone)]
pub struct Disagreement {
    /// decode, encode, stream, or panic.
    pub kind: &'static str,
    /// What differs, in a few words that repeat across frames (`decode: generated refuses
    /// (wrong length), interpreter accepts`): disagreements are grouped by it.
    pub signature: String,
    /// Both engines refuse, for different reasons (see [`same_error`]).
    pub class_only: bool,
    /// Direction, request, address, values: how the input was given.
    pub how: String,
    /// The frame or capture (hex), or the values encoded.
    pub input: String,
    pub generated: String,
    pub interpreter: String,
}

/// What was compared on one spec, and what disagreed.
#[derive(Debug, Default)]
pub struct Report {
    pub frames: usize,
    pub encodes: usize,
    pub captures: usize,
    /// The first few disagreements (see [`MAX_KEPT`]).
    pub found: Vec<Disagreement>,
    /// Every disagreement, kept or not.
    pub disagreements: usize,
    /// Of those, where both refuse for different reasons.
    pub class_only: usize,
    /// How many of each signature.
    pub signatures: std::collections::BTreeMap<String, usize>,
    /// Replies whose checksum takes in their request's bytes that both engines accepted,
    /// decoded as the reply to that request.
    pub over_request: usize,
}

/// Disagreements kept per spec: the first of each signature, up to this many.
pub const MAX_KEPT: usize = 6;

impl Report {
    fn record(&mut self, d: Disagreement) {
        self.disagreements += 1;
        if d.class_only {
            self.class_only += 1;
        }
        let n = self.signatures.entry(d.signature.clone()).or_default();
        *n += 1;
        if *n == 1 && self.found.len() < MAX_KEPT {
            self.found.push(d);
        }
    }
}

/// A few words for what an engine said, for signatures.
fn gist<E: fmt::Debug>(s: &Said<E>, class: impl Fn(&E) -> &'static str) -> String {
    match s {
        Said::Accepted(_) => "accepts".into(),
        Said::Refused(e) => format!("refuses ({})", class(e)),
        Said::Panicked(_) => "panics".into(),
    }
}

thread_local! {
    static PANIC: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Panics are caught and recorded, not printed: install once per process.
pub fn quiet_panics() {
    std::panic::set_hook(Box::new(|info| {
        let msg = info.to_string();
        PANIC.with(|p| *p.borrow_mut() = msg);
    }));
}

/// `f`'s value, or the message it panicked with.
pub fn caught<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|_| PANIC.with(|p| p.borrow().clone()))
}

/// A frame one engine accepted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Accepted {
    pub name: String,
    pub address: u8,
    pub values: Values,
    /// What that engine's encoder writes back for it.
    pub reencoded: Result<Vec<u8>, String>,
}

/// What one engine made of a frame.
#[derive(Debug, Clone)]
pub enum Said<E> {
    Accepted(Accepted),
    Refused(E),
    Panicked(String),
}

/// The interpreter's refusal: its error, or `None` where it decoded a response the command
/// does not list (`decode_reply` in generated code refuses it as not a reply).
pub type InterpRefusal = Option<InterpError>;

/// A refusal's class, shared by both engines' errors.
fn class(g: &DecodeError) -> &'static str {
    match g {
        DecodeError::Truncated { .. } => "truncated",
        DecodeError::BadStart { .. } => "bad start",
        DecodeError::BadEnd { .. } => "bad end",
        DecodeError::ChecksumMismatch { .. } => "checksum",
        DecodeError::UnknownCommand { .. } | DecodeError::UnknownResponse { .. } => "unknown code",
        DecodeError::WrongLength { .. } => "wrong length",
        DecodeError::LengthMismatch { .. } => "length field",
        DecodeError::InvalidValue { .. }
        | DecodeError::NotEqual { .. }
        | DecodeError::NotBcd { .. }
        | DecodeError::NotFollowing { .. } => "invalid value",
        DecodeError::Ambiguous { .. } => "ambiguous",
        DecodeError::NotAReply { .. } => "not a reply",
        DecodeError::TooLong { .. } => "too long",
        DecodeError::OutOfRange { .. } => "out of range",
        DecodeError::BadAddress { .. } => "bad address",
        DecodeError::BroadcastNotAccepted { .. } => "broadcast",
        DecodeError::BadCount { .. }
        | DecodeError::ByteCount { .. }
        | DecodeError::BadWidth { .. } => "bad count",
        DecodeError::BadEscape { .. } => "bad escape",
        DecodeError::NeedlessLong { .. } => "needless long form",
        DecodeError::NoTerminator { .. } => "no terminator",
        DecodeError::EndInside { .. } => "end inside",
        DecodeError::NeedsRequest { .. } => "needs the request",
    }
}

fn interp_class(i: &InterpRefusal) -> &'static str {
    match i {
        None => "not a reply",
        Some(e) => match e {
            InterpError::Truncated { .. } => "truncated",
            InterpError::BadStart { .. } => "bad start",
            InterpError::BadEnd { .. } => "bad end",
            InterpError::ChecksumMismatch { .. } => "checksum",
            InterpError::UnknownCode { .. } => "unknown code",
            InterpError::WrongLength { .. } => "wrong length",
            InterpError::LengthMismatch { .. } => "length field",
            InterpError::ConstantMismatch { .. }
            | InterpError::NotEqual { .. }
            | InterpError::NotBcd { .. }
            | InterpError::NotFollowing { .. } => "invalid value",
            InterpError::Ambiguous { .. } => "ambiguous",
            InterpError::NotAnAnswer { .. } => "not a reply",
            InterpError::TooLong { .. } => "too long",
            InterpError::OutOfRange { .. } => "out of range",
            InterpError::BadAddress { .. } => "bad address",
            InterpError::BroadcastNotAccepted { .. } => "broadcast",
            InterpError::BadCount { .. }
            | InterpError::ByteCount { .. }
            | InterpError::BadWidth { .. } => "bad count",
            InterpError::BadEscape { .. } => "bad escape",
            InterpError::NeedlessLong { .. } => "needless long form",
            InterpError::NoTerminator { .. } => "no terminator",
            InterpError::EndInside { .. } => "end inside",
            InterpError::NeedsRequest { .. } => "needs the request",
        },
    }
}

/// Whether the two engines refuse a frame alike: in the same words (the CLI prints the same
/// line whichever engine decoded the frame).
pub fn same_error(g: &DecodeError, i: &InterpRefusal) -> bool {
    match i {
        Some(e) => g.to_string() == e.to_string(),
        None => matches!(g, DecodeError::NotAReply { .. }),
    }
}

/// A generated encoder's refusal: from `from_fields` (a value the typed message cannot hold)
/// or from `encode`.
#[derive(Debug, Clone)]
pub enum GenEncodeError {
    Fields(busspec_runtime::FieldError),
    Encode(EncodeError),
}

fn encode_class(g: &GenEncodeError) -> &'static str {
    use busspec_runtime::FieldError as F;
    match g {
        GenEncodeError::Fields(F::OutOfRange { .. }) => "out of range",
        GenEncodeError::Fields(F::TooMany { .. }) => "count",
        GenEncodeError::Fields(F::TextLength { .. }) => "text length",
        GenEncodeError::Fields(F::Missing { .. }) => "missing",
        GenEncodeError::Fields(F::WrongKind { .. }) => "kind",
        GenEncodeError::Fields(F::UnknownMessage) => "unknown message",
        GenEncodeError::Encode(EncodeError::OutOfRange { .. }) => "out of range",
        GenEncodeError::Encode(EncodeError::NotInRange { .. }) => "not in range",
        GenEncodeError::Encode(EncodeError::WrongCount { .. }) => "count",
        GenEncodeError::Encode(EncodeError::BadAddress { .. }) => "bad address",
        GenEncodeError::Encode(EncodeError::Unaddressed { .. }) => "unaddressed",
        GenEncodeError::Encode(EncodeError::BroadcastNotAccepted { .. }) => "broadcast",
        GenEncodeError::Encode(EncodeError::BufferTooSmall { .. }) => "buffer",
        GenEncodeError::Encode(EncodeError::HoldsTerminator { .. }) => "holds its terminator",
        GenEncodeError::Encode(EncodeError::HoldsEnd { .. }) => "holds the end bytes",
        GenEncodeError::Encode(EncodeError::NeedsRequest { .. }) => "needs the request",
        GenEncodeError::Encode(EncodeError::Optional { .. }) => "optional",
        #[allow(unreachable_patterns)]
        GenEncodeError::Encode(_) => "other",
    }
}

fn interp_encode_class(i: &interp::EncodeError) -> &'static str {
    use interp::EncodeError as E;
    match i {
        E::OutOfRange { .. } => "out of range",
        E::NotInRange { .. } => "not in range",
        E::WrongCount { .. } => "count",
        E::WrongTextLength { .. } => "text length",
        E::MissingValue { .. } => "missing",
        E::NotText { .. } | E::NotNumber { .. } | E::NotList { .. } => "kind",
        E::UnknownValue { .. } => "unknown value",
        E::BadAddress { .. } => "bad address",
        E::Unaddressed { .. } => "unaddressed",
        E::BroadcastNotAccepted { .. } => "broadcast",
        E::Fixed { .. } => "fixed",
        E::Inconsistent { .. } => "inconsistent",
        E::Optional { .. } => "optional",
        E::HoldsTerminator { .. } => "holds its terminator",
        E::HoldsEnd { .. } => "holds the end bytes",
        E::NeedsRequest { .. } => "needs the request",
    }
}

/// Whether the two encoders refuse alike. Where the generated `from_fields` accepted the
/// values (each present, of its kind, within its Rust type, a list within its capacity), both
/// name the same fault of the same field: the generated `encode` checks in the interpreter's
/// order (the address, then each list's count and elements, then the fields in frame order, a
/// list of a fixed count its count first). A refusal of `from_fields` is a typed check the
/// interpreter has no counterpart for (its values are untyped), so there only both refusing
/// is compared.
pub fn same_encode_error(g: &GenEncodeError, i: &interp::EncodeError) -> bool {
    match g {
        GenEncodeError::Fields(_) => true,
        GenEncodeError::Encode(e) => {
            encode_class(g) == interp_encode_class(i)
                && gen_encode_field(e) == interp_encode_field(i)
        }
    }
}

/// The field a generated encoder's refusal names, if any.
fn gen_encode_field(e: &EncodeError) -> Option<&str> {
    match e {
        EncodeError::OutOfRange { field }
        | EncodeError::NotInRange { field, .. }
        | EncodeError::WrongCount { field, .. }
        | EncodeError::Optional { field, .. }
        | EncodeError::HoldsTerminator { field, .. }
        | EncodeError::HoldsEnd { field, .. } => Some(field),
        _ => None,
    }
}

/// The field the interpreter's refusal names, if any.
fn interp_encode_field(e: &interp::EncodeError) -> Option<&str> {
    use interp::EncodeError as E;
    match e {
        E::OutOfRange { field, .. }
        | E::NotInRange { field, .. }
        | E::WrongCount { field, .. }
        | E::Optional { field, .. }
        | E::HoldsTerminator { field, .. }
        | E::HoldsEnd { field, .. } => Some(field),
        _ => None,
    }
}

/// How a frame is decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Request,
    Response,
    /// As the reply to the request `asks[i]`.
    Reply(usize),
}

/// A request frame both engines decode, for decoding replies to it.
struct Ask<P: Protocol> {
    command: usize,
    wire: Vec<u8>,
    generated: P::Request,
    interp: interp::Frame<'static>,
}

/// A generated module's borrowed views (`RequestView::decode`, `ResponseView::decode` and
/// `decode_reply`), each made owned (`to_owned`) with its address; `None` where the generator
/// made no view of a direction. Where given, every frame the generated code decodes is also
/// made into a view, which must accept and refuse as the owned decode does and hold its
/// message: a view that does not is a panic of the generated side (a disagreement).
pub struct ViewFns<P: Protocol> {
    pub request: Option<ViewRequest<P>>,
    pub response: Option<ViewResponse<P>>,
}

/// A request view made owned: [`ViewFns::request`].
pub type ViewRequest<P> = fn(&[u8]) -> Result<(u8, <P as Protocol>::Request), DecodeError>;
/// A response view (as the reply to the request where given) made owned:
/// [`ViewFns::response`].
pub type ViewResponse<P> = fn(
    &[u8],
    Option<&<P as Protocol>::Request>,
) -> Result<(u8, <P as Protocol>::Response), DecodeError>;

impl<P: Protocol> ViewFns<P> {
    /// No views.
    pub fn none() -> Self {
        ViewFns {
            request: None,
            response: None,
        }
    }
}

/// The view agrees with the owned decode: both accept with the same address, message and raw
/// values (as `visit` gives them: a NaN is its bits), or both refuse with the same error;
/// panics where they do not.
fn same_as_view<M: Message + fmt::Debug>(
    owned: &Result<busspec_runtime::Decoded<M>, DecodeError>,
    view: Option<Result<(u8, M), DecodeError>>,
) {
    let Some(view) = view else { return };
    let raw = |m: &M| (m.name(), visit_values(|f| m.visit(f)));
    match (owned, &view) {
        (Ok(o), Ok((a, m))) if o.address == *a && raw(&o.message) == raw(m) => {}
        (Err(o), Err(v)) if o == v => {}
        _ => panic!("the view disagrees with the owned decode: view {view:?}, owned {owned:?}"),
    }
}

/// Everything one spec's comparison needs.
pub struct Run<'p, P: Protocol> {
    p: &'p ir::Protocol,
    asks: Vec<Ask<P>>,
    /// The ask the last random frame, a reply whose checksum takes in its request's bytes,
    /// was made over.
    over: Option<usize>,
    rng: fastrand::Rng,
    pub report: Report,
    views: ViewFns<P>,
}

impl<E: fmt::Debug> fmt::Display for Said<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Said::Accepted(a) => {
                write!(
                    f,
                    "accepted {} from 0x{:02X} {:?}",
                    a.name, a.address, a.values
                )?;
                match &a.reencoded {
                    Ok(w) => write!(f, ", writes back {}", interp::format_hex(w)),
                    Err(e) => write!(f, ", does not write back: {e}"),
                }
            }
            Said::Refused(e) => write!(f, "refused: {e:?}"),
            Said::Panicked(m) => write!(f, "panicked: {m}"),
        }
    }
}

fn pattern_encode<M: Message>(m: &M, address: u8, max: usize) -> Result<Vec<u8>, String> {
    let mut buf = vec![0xA5u8; max];
    m.encode(address, &mut buf)
        .map(|n| buf[..n].to_vec())
        .map_err(|e| e.to_string())
}

/// `raw` as a field value; records lent from `flat`, their raw values record after record
/// (`fields` to a record).
fn field_value<'a>(raw: &'a Raw, flat: &'a [i64], fields: usize) -> FieldValue<'a> {
    match raw {
        Raw::Int(i) => FieldValue::Int(*i),
        Raw::Text(t) => FieldValue::Text(t),
        Raw::List(l) => FieldValue::List(Elements::I64(l)),
        Raw::Records(_) => FieldValue::Records(busspec_runtime::RecordList::Flat {
            values: flat,
            fields,
        }),
    }
}

/// The values the interpreter decoded that an encoder takes back.
fn carried_values(p: &ir::Protocol, f: &interp::Frame) -> Vec<Value<'static>> {
    interp_values(p, f)
        .into_iter()
        .map(|(name, raw)| Value {
            name: name.into(),
            raw,
        })
        .collect()
}

impl<'p, P: Protocol> Run<'p, P> {
    pub fn new(p: &'p ir::Protocol, seed: u64) -> Self {
        let mut run = Run {
            p,
            asks: Vec::new(),
            over: None,
            rng: fastrand::Rng::with_seed(seed),
            report: Report::default(),
            views: ViewFns::none(),
        };
        // A request per command both engines decode: its first example, else encoded from
        // random values.
        for c in 0..p.commands.len() {
            let r = MessageRef {
                direction: Direction::Request,
                index: c,
            };
            let mut tries: Vec<Vec<u8>> = p
                .examples
                .iter()
                .filter(|e| e.message == r)
                .map(|e| e.wire.clone())
                .collect();
            for _ in 0..4 {
                let v = random_values(p, &p.commands[c], &mut run.rng, true);
                let a = run.rng.u8(p.framing.address.min..=p.framing.address.max);
                let a = if p.framing.has_address_in(Direction::Request) {
                    a
                } else {
                    0
                };
                if let Ok(w) = interp::encode(p, r, a, &v) {
                    tries.push(w);
                }
            }
            for wire in tries {
                let g = caught(|| P::decode_request(&wire))
                    .ok()
                    .and_then(|x| x.ok());
                let i = interp::decode(p, Some(Direction::Request), None, &wire).ok();
                if let (Some(g), Some(i)) = (g, i) {
                    if i.message == r {
                        run.asks.push(Ask {
                            command: c,
                            wire,
                            generated: g.message,
                            interp: i.into_owned(),
                        });
                        break;
                    }
                }
            }
        }
        // The requests examples of replies give (a reply whose checksum takes in its
        // request's bytes names its request's frame): asked too, so such a reply is decoded
        // as the reply to the request it was made over.
        for e in &p.examples {
            let Some(wire) = e.request.clone() else {
                continue;
            };
            if run.asks.iter().any(|a| a.wire == wire) {
                continue;
            }
            let g = caught(|| P::decode_request(&wire))
                .ok()
                .and_then(|x| x.ok());
            let i = interp::decode(p, Some(Direction::Request), None, &wire).ok();
            if let (Some(g), Some(i)) = (g, i) {
                run.asks.push(Ask {
                    command: i.message.index,
                    wire,
                    generated: g.message,
                    interp: i.into_owned(),
                });
            }
        }
        run
    }

    fn generated(&self, frame: &[u8], mode: Mode) -> Said<DecodeError> {
        let max = P::MAX_FRAME_LEN.max(frame.len());
        let got = caught(|| match mode {
            Mode::Request => {
                let d = P::decode_request(frame);
                same_as_view(&d, self.views.request.map(|v| v(frame)));
                d.map(|d| Accepted {
                    name: d.message.name().to_owned(),
                    address: d.address,
                    values: visit_values(|f| d.message.visit(f)),
                    reencoded: pattern_encode(&d.message, d.address, max),
                })
            }
            Mode::Response | Mode::Reply(_) => {
                let (d, request) = match mode {
                    Mode::Reply(k) => {
                        let ask = &self.asks[k];
                        // The view has the request's values, not its bytes: as `decode_reply`.
                        same_as_view(
                            &P::decode_reply(frame, &ask.generated),
                            self.views.response.map(|v| v(frame, Some(&ask.generated))),
                        );
                        // With the request's bytes, which a reply's checksum may take in.
                        let covered = P::Request::covered(&ask.wire);
                        let d = P::Response::decode_as_reply_over(
                            frame,
                            Some(&ask.generated),
                            Some(covered),
                        )
                        .inspect(|d| {
                            assert!(
                                d.message.answers(&ask.generated),
                                "decode_reply gave a response that does not answer"
                            )
                        });
                        (d, Some(&ask.wire))
                    }
                    _ => {
                        let d = P::decode_response(frame);
                        same_as_view(&d, self.views.response.map(|v| v(frame, None)));
                        (d, None)
                    }
                };
                d.map(|d| Accepted {
                    name: d.message.name().to_owned(),
                    address: d.address,
                    values: visit_values(|f| d.message.visit(f)),
                    reencoded: match request {
                        Some(w) => {
                            let mut buf = vec![0xA5u8; max];
                            P::encode_reply(&d.message, d.address, w, &mut buf)
                                .map(|n| buf[..n].to_vec())
                                .map_err(|e| e.to_string())
                        }
                        None => pattern_encode(&d.message, d.address, max),
                    },
                })
            }
        });
        match got {
            Ok(Ok(a)) => Said::Accepted(a),
            Ok(Err(e)) => Said::Refused(e),
            Err(m) => Said::Panicked(m),
        }
    }

    fn interpreted(&self, frame: &[u8], mode: Mode) -> Said<InterpRefusal> {
        let p = self.p;
        let got = caught(|| {
            let decoded = match mode {
                Mode::Request => interp::decode(p, Some(Direction::Request), None, frame),
                Mode::Response => interp::decode(p, Some(Direction::Response), None, frame),
                Mode::Reply(k) => {
                    let ask = &self.asks[k];
                    interp::decode_reply_with(p, &ask.interp, Some(&ask.wire), frame)
                }
            };
            let decoded = match (decoded, mode) {
                (Ok(f), Mode::Reply(k))
                    if !p.commands[self.asks[k].command]
                        .responses
                        .iter()
                        .any(|(r, _)| *r == f.message.index) =>
                {
                    Err(None)
                }
                (Ok(f), _) => Ok(f),
                (Err(e), _) => Err(Some(e)),
            };
            decoded.map(|f| Accepted {
                name: p.message(f.message).name.clone(),
                address: f.address,
                values: interp_values(p, &f),
                reencoded: interp::encode_with(
                    p,
                    f.message,
                    f.address,
                    &carried_values(p, &f),
                    match mode {
                        Mode::Reply(k) => p.checksum_span(&self.asks[k].wire),
                        _ => None,
                    },
                )
                .map_err(|e| e.to_string()),
            })
        });
        match got {
            Ok(Ok(a)) => Said::Accepted(a),
            Ok(Err(e)) => Said::Refused(e),
            Err(m) => Said::Panicked(m),
        }
    }

    fn mode_text(&self, mode: Mode) -> String {
        match mode {
            Mode::Request => "decoded as a request".into(),
            Mode::Response => "decoded as a response".into(),
            Mode::Reply(k) => {
                let a = &self.asks[k];
                format!(
                    "decoded as the reply to {} ({})",
                    self.p.commands[a.command].name,
                    interp::format_hex(&a.wire)
                )
            }
        }
    }

    /// One frame, one way, through both engines.
    fn decode(&mut self, frame: &[u8], mode: Mode) {
        self.report.frames += 1;
        let g = self.generated(frame, mode);
        let i = self.interpreted(frame, mode);
        // What an encoder writes back: the frame itself, but beside payload truncation
        // (`framing.truncation`) a frame that came with trailing zeros goes back stripped.
        let back: std::borrow::Cow<[u8]> = match busspec_model::long::canonical(self.p, frame) {
            Ok(c) if self.p.framing.truncation.is_some() => std::borrow::Cow::Owned(
                busspec_model::truncate::travel(self.p, c.frame.into_owned()),
            ),
            _ => std::borrow::Cow::Borrowed(frame),
        };
        let frame_back: &[u8] = &back;
        if let (Said::Accepted(a), Mode::Reply(_)) = (&i, mode) {
            let over = self
                .p
                .responses
                .iter()
                .any(|m| m.name == a.name && m.over_request.is_some());
            self.report.over_request += usize::from(over);
        }
        let agree = match (&g, &i) {
            (Said::Accepted(a), Said::Accepted(b)) => {
                a.name == b.name
                    && a.address == b.address
                    && a.values == b.values
                    && a.reencoded.as_deref() == Ok(frame_back)
                    && b.reencoded.as_deref() == Ok(frame_back)
            }
            (Said::Refused(a), Said::Refused(b)) => same_error(a, b),
            _ => false,
        };
        if !agree {
            let panicked = matches!(g, Said::Panicked(_)) || matches!(i, Said::Panicked(_));
            let how = self.mode_text(mode);
            let kind = if panicked { "panic" } else { "decode" };
            let mut signature = format!(
                "{kind}: generated {}, interpreter {}",
                gist(&g, class),
                gist(&i, interp_class)
            );
            if let (Said::Accepted(a), Said::Accepted(b)) = (&g, &i) {
                let what = if a.name != b.name {
                    "another message"
                } else if a.address != b.address {
                    "another address"
                } else if a.values != b.values {
                    "other values"
                } else if a.reencoded.as_deref() != Ok(frame_back) {
                    "the generated encoder writes it back otherwise"
                } else {
                    "the interpreter's encoder writes it back otherwise"
                };
                signature.push_str(&format!(": {what}"));
            }
            let class_only = matches!((&g, &i), (Said::Refused(_), Said::Refused(_)));
            self.report.record(Disagreement {
                kind,
                signature,
                class_only,
                how,
                input: interp::format_hex(frame),
                generated: g.to_string(),
                interpreter: i.to_string(),
            });
        }
    }

    /// One frame through both engines' weakest acceptance test (`Framing::checksum_ok`, which
    /// the checksum-only soak master and the fuzz bodies take as the rule).
    fn checksum_ok(&mut self, frame: &[u8]) {
        let g = catch_unwind(|| P::checksum_ok(frame));
        let i = catch_unwind(AssertUnwindSafe(|| interp::checksum_ok(self.p, frame)));
        if g.as_ref().ok() == i.as_ref().ok() && g.is_ok() {
            return;
        }
        let say = |r: &std::thread::Result<bool>| match r {
            Ok(true) => "passes".to_owned(),
            Ok(false) => "fails".to_owned(),
            Err(_) => "panics".to_owned(),
        };
        let kind = if g.is_err() || i.is_err() {
            "panic"
        } else {
            "checksum_ok"
        };
        self.report.record(Disagreement {
            kind,
            signature: format!(
                "checksum_ok: the frame {} the generated test, {} the interpreter's",
                say(&g),
                say(&i)
            ),
            class_only: false,
            how: "checked by its checksum alone".into(),
            input: interp::format_hex(frame),
            generated: say(&g),
            interpreter: say(&i),
        });
    }

    /// One frame every way: as request, as response, and as the reply to each request (all
    /// of them, or `replies` drawn at random).
    fn decode_all_ways(&mut self, frame: &[u8], replies: Option<usize>) {
        self.checksum_ok(frame);
        self.decode(frame, Mode::Request);
        self.decode(frame, Mode::Response);
        let n = self.asks.len();
        match replies {
            None => (0..n).for_each(|k| self.decode(frame, Mode::Reply(k))),
            Some(r) if n > 0 => {
                for _ in 0..r {
                    let k = self.rng.usize(..n);
                    self.decode(frame, Mode::Reply(k));
                }
            }
            _ => {}
        }
    }

    /// `values` as message `r` for `address`, through both encoders.
    fn encode(&mut self, r: MessageRef, address: u8, values: &[Value]) {
        self.report.encodes += 1;
        let p = self.p;
        let name = p.message(r).name.as_str();
        let flats: Vec<Vec<i64>> = values
            .iter()
            .map(|v| match &v.raw {
                Raw::Records(r) => r.concat(),
                _ => Vec::new(),
            })
            .collect();
        let m = p.message(r);
        let lookup = |n: &str| {
            values
                .iter()
                .zip(&flats)
                .find(|(v, _)| v.name == n)
                .map(|(v, flat)| {
                    let fields = m
                        .fields
                        .iter()
                        .find(|f| f.name == n)
                        .map_or(0, |f| f.record.len());
                    field_value(&v.raw, flat, fields)
                })
        };
        let max = P::MAX_FRAME_LEN;
        let g = caught(|| -> Result<Vec<u8>, GenEncodeError> {
            let mut buf = vec![0u8; max];
            let n = match r.direction {
                Direction::Request => P::Request::from_fields(name, lookup)
                    .map_err(GenEncodeError::Fields)?
                    .encode(address, &mut buf),
                Direction::Response => P::Response::from_fields(name, lookup)
                    .map_err(GenEncodeError::Fields)?
                    .encode(address, &mut buf),
            }
            .map_err(GenEncodeError::Encode)?;
            Ok(buf[..n].to_vec())
        });
        let i = caught(|| interp::encode(p, r, address, values));
        let agree = match (&g, &i) {
            (Ok(Ok(a)), Ok(Ok(b))) => a == b,
            (Ok(Err(a)), Ok(Err(b))) => same_encode_error(a, b),
            _ => false,
        };
        if !agree {
            let show_g = match &g {
                Ok(Ok(w)) => format!("writes {}", interp::format_hex(w)),
                Ok(Err(e)) => format!("refuses: {e:?}"),
                Err(m) => format!("panicked: {m}"),
            };
            let show_i = match &i {
                Ok(Ok(w)) => format!("writes {}", interp::format_hex(w)),
                Ok(Err(e)) => format!("refuses: {e:?}"),
                Err(m) => format!("panicked: {m}"),
            };
            let input: Vec<String> = values
                .iter()
                .map(|v| format!("{}: {:?}", v.name, v.raw))
                .collect();
            let kind = if g.is_err() || i.is_err() {
                "panic"
            } else {
                "encode"
            };
            let word = |r: &Result<Result<Vec<u8>, String>, String>| match r {
                Ok(Ok(_)) => "writes".to_owned(),
                Ok(Err(c)) => format!("refuses ({c})"),
                Err(_) => "panics".to_owned(),
            };
            let gw = word(
                &g.as_ref()
                    .map(|r| {
                        r.as_ref()
                            .map(|_| Vec::new())
                            .map_err(|e| encode_class(e).to_owned())
                    })
                    .map_err(|e| e.clone()),
            );
            let iw = word(
                &i.as_ref()
                    .map(|r| {
                        r.as_ref()
                            .map(|_| Vec::new())
                            .map_err(|e| interp_encode_class(e).to_owned())
                    })
                    .map_err(|e| e.clone()),
            );
            let mut signature = format!("{kind}: generated {gw}, interpreter {iw}");
            if gw == "writes" && iw == "writes" {
                signature.push_str(": other bytes");
            }
            let class_only = matches!((&g, &i), (Ok(Err(_)), Ok(Err(_))));
            self.report.record(Disagreement {
                kind,
                signature,
                class_only,
                how: format!("{name} encoded for address 0x{address:02X}"),
                input: format!("{{{}}}", input.join(", ")),
                generated: show_g,
                interpreter: show_i,
            });
        }
    }

    /// `capture` through both stream decoders in `direction`, cut into `chunks`.
    fn stream(&mut self, capture: &[u8], direction: Option<Direction>) {
        self.report.captures += 1;
        let p = self.p;
        let chunks = events::chunks(self.rng.u8(..), capture.len(), 2 * P::MAX_FRAME_LEN);
        let sd = direction.map(|d| match d {
            Direction::Request => StreamDirection::Request,
            Direction::Response => StreamDirection::Response,
        });
        let g = caught(|| seen::<P>(&stream_events::<P>(sd, capture, &chunks)));
        let i = caught(|| events::interp_events(p, direction, capture, &chunks));
        if let (Ok(a), Ok(b)) = (&g, &i) {
            if a == b {
                return;
            }
        }
        let show = |r: &Result<Vec<Seen>, String>| match r {
            Ok(ev) => {
                let all: Vec<String> = ev.iter().map(|e| format!("{e:?}")).collect();
                all.join("; ")
            }
            Err(m) => format!("panicked: {m}"),
        };
        // The first event that differs, for a readable report.
        let first = match (&g, &i) {
            (Ok(a), Ok(b)) => {
                let k = a.iter().zip(b).take_while(|(x, y)| x == y).count();
                format!(" (events differ from #{k})")
            }
            _ => String::new(),
        };
        let cut: Vec<String> = chunks.iter().map(|c| c.to_string()).collect();
        let kind = if g.is_err() || i.is_err() {
            "panic"
        } else {
            "stream"
        };
        let signature = match (&g, &i) {
            (Ok(a), Ok(b)) => {
                let k = a.iter().zip(b).take_while(|(x, y)| x == y).count();
                let word = |e: Option<&Seen>| match e {
                    Some(Seen::Frame { .. }) => "a frame",
                    Some(Seen::Ambiguous { .. }) => "an ambiguous frame",
                    Some(Seen::Skipped { .. }) => "skipped bytes",
                    Some(Seen::OutOfSpec { .. }) => "an out-of-spec frame",
                    None => "nothing",
                };
                format!(
                    "stream: generated sees {}, interpreter {}",
                    word(a.get(k)),
                    word(b.get(k))
                )
            }
            _ => "panic: in a stream decoder".to_owned(),
        };
        self.report.record(Disagreement {
            kind,
            signature,
            class_only: false,
            how: format!(
                "stream of {}, pushed in chunks [{}]{first}",
                direction.map_or("both directions", |d| d.as_str()),
                cut.join(", ")
            ),
            input: interp::format_hex(capture),
            generated: show(&g),
            interpreter: show(&i),
        });
    }

    fn random_address(&mut self) -> u8 {
        let a = &self.p.framing.address;
        match self.rng.u8(..10) {
            0 => a.broadcast.unwrap_or(a.min),
            1 => a.host.unwrap_or(a.max),
            2 => self.rng.u8(..),
            _ => self.rng.u8(a.min..=a.max),
        }
    }

    /// A frame of message `r` from random values, through the interpreter of the spec
    /// without ranges or address rules, so it may break them.
    fn random_frame(&mut self, lenient: &ir::Protocol, r: MessageRef) -> Option<Vec<u8>> {
        let m = self.p.message(r);
        let strict = self.rng.bool();
        let values = random_values(self.p, m, &mut self.rng, strict);
        let a = self.random_address();
        // A reply whose checksum takes in its request's bytes: over a request drawn from
        // the asks (the reply to it, decoded as such, checks: `self.over`).
        self.over = None;
        let covered = match m.over_request {
            Some(_) if !self.asks.is_empty() => {
                let k = self.rng.usize(..self.asks.len());
                self.over = Some(k);
                self.p.checksum_span(&self.asks[k].wire)
            }
            _ => None,
        };
        interp::encode_with(lenient, r, a, &values, covered).ok()
    }

    /// Runs every comparison.
    pub fn all(&mut self, budget: Budget) {
        let p = self.p;
        let lenient = lenient(p);
        let all: Vec<MessageRef> = [Direction::Request, Direction::Response]
            .into_iter()
            .flat_map(|d| {
                (0..p.messages(d).len()).map(move |index| MessageRef {
                    direction: d,
                    index,
                })
            })
            .collect();

        // Examples, their mutations and every prefix.
        let mut valid: Vec<Vec<u8>> = p.examples.iter().map(|e| e.wire.clone()).collect();
        for e in &p.examples {
            let d = e.message.direction;
            self.decode_all_ways(&e.wire, None);
            for m in mutations(p, d, &e.wire) {
                self.decode_all_ways(&m, Some(2));
            }
            for n in 0..e.wire.len() {
                let f = e.wire[..n].to_vec();
                self.decode(
                    &f,
                    if d == Direction::Request {
                        Mode::Request
                    } else {
                        Mode::Response
                    },
                );
            }
        }
        // Random frames of every message, mutated too.
        for k in 0..budget.random_frames {
            let input = match self.rng.u8(..10) {
                0 => {
                    let max = P::MAX_FRAME_LEN + 2;
                    let n = self.rng.usize(..=max);
                    let mut f: Vec<u8> = (0..n).map(|_| self.rng.u8(..)).collect();
                    if self.rng.bool() {
                        // Each direction's checksum, where they cover from other bytes.
                        let d = if k % 2 == 0 {
                            Direction::Request
                        } else {
                            Direction::Response
                        };
                        reseal_as(p, d, &mut f);
                    }
                    f
                }
                _ => {
                    let r = all[k % all.len()];
                    let Some(mut f) = self.random_frame(&lenient, r) else {
                        continue;
                    };
                    valid.push(f.clone());
                    if self.rng.u8(..3) == 0 {
                        let ms = mutations(p, r.direction, &f);
                        f = ms[self.rng.usize(..ms.len())].clone();
                    } else if self.rng.u8(..4) == 0 {
                        lie_about_count(p, r, &mut f, &mut self.rng);
                    }
                    f
                }
            };
            self.decode_all_ways(&input, Some(1));
            // A reply made over an ask's bytes, as the reply to that ask too.
            if let Some(k) = self.over.take() {
                self.decode(&input, Mode::Reply(k));
            }
        }
        // Encodes: the examples' values, then random ones.
        for e in &p.examples {
            let covered = e.request.as_deref().and_then(|w| p.checksum_span(w));
            let decoded =
                interp::decode_with(p, Some(e.message.direction), e.reply_to, covered, &e.wire);
            if let Ok(f) = decoded {
                let values = carried_values(p, &f);
                self.encode(e.message, f.address, &values);
                let a = self.random_address();
                self.encode(e.message, a, &values);
            }
        }
        for &r in &all {
            for _ in 0..budget.encodes_per_message {
                let strict = self.rng.bool();
                let mut values = random_values(p, p.message(r), &mut self.rng, strict);
                if self.rng.u8(..12) == 0 && !values.is_empty() {
                    let k = self.rng.usize(..values.len());
                    values.remove(k);
                }
                let a = self.random_address();
                self.encode(r, a, &values);
            }
        }
        // Streams: valid frames and noise, in both directions and each alone.
        for _ in 0..budget.captures {
            let mut capture = Vec::new();
            for _ in 0..self.rng.usize(1..=8) {
                match self.rng.u8(..6) {
                    0 => capture.extend((0..self.rng.usize(1..6)).map(|_| self.rng.u8(..))),
                    1 if !valid.is_empty() => {
                        let f = &valid[self.rng.usize(..valid.len())];
                        capture.extend_from_slice(&f[..self.rng.usize(..f.len())]);
                    }
                    _ if !valid.is_empty() => {
                        let f = &valid[self.rng.usize(..valid.len())];
                        // A flag that closes one frame and opens the next, shared by a
                        // sender (HDLC): the frame's own opening flag left out.
                        let shared = p.framing.shared_flag().is_some_and(|flag| {
                            capture.last() == Some(&flag) && f.first() == Some(&flag)
                        });
                        let from = usize::from(shared && self.rng.bool());
                        // Wake-up bytes (DL/T 645): none, as many as a frame may have, or a
                        // few more (the first of which are noise).
                        if let Some(pre) = p.framing.preamble.as_ref().filter(|_| self.rng.bool()) {
                            let k = self.rng.usize(..=usize::from(pre.max) + 2);
                            capture.extend(std::iter::repeat(pre.byte).take(k));
                            capture.extend_from_slice(p.framing.after_preamble(f));
                            continue;
                        }
                        capture.extend_from_slice(&f[from..])
                    }
                    _ => {}
                }
            }
            for d in [None, Some(Direction::Request), Some(Direction::Response)] {
                self.stream(&capture, d);
            }
        }
    }
}

/// `p` with nothing of the strict contract: no ranges, every address allowed, no broadcast
/// rule. Its interpreter writes the frames the strict encoders refuse.
pub fn lenient(p: &ir::Protocol) -> ir::Protocol {
    let mut p = p.clone();
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
}

/// The repeated field's count field set to a nearby or random value (the checksum repaired
/// or not): a count that lies about the frame.
fn lie_about_count(p: &ir::Protocol, r: MessageRef, frame: &mut [u8], rng: &mut fastrand::Rng) {
    let frame = after_preamble(p, frame);
    let m = p.message(r);
    if let Some((_, rep)) = m.repeat() {
        if let Count::Elements(i) | Count::Bytes(i) = rep.count {
            let f = &m.fields[i];
            let at = m.layout.payload + f.offset;
            if let Some(bytes) = frame.get_mut(at..at + f.width) {
                let old = interp::read_uint(bytes, f.byte_order);
                let new = match rng.u8(..3) {
                    0 => old.wrapping_add(1),
                    1 => old.wrapping_sub(1),
                    _ => rng.u64(..),
                };
                interp::write_uint(new, bytes, f.byte_order);
            }
        }
    }
    if p.framing.length.is_some() && rng.bool() {
        // A length field that lies too, or is made to agree with the frame's length.
        let rule = p.framing.length_rule(r.direction);
        if let Some(rule) = rule {
            if let Some(b) = frame.get_mut(rule.at) {
                *b = b.wrapping_add(1);
            }
        }
    }
    if rng.u8(..4) != 0 {
        reseal_as(p, r.direction, frame);
    }
}

/// Compares the engines on generated protocol `P` with `seed`, within `budget`. The spec is
/// `P`'s own text (`Protocol::SOURCE.spec_yaml`), loaded here; a panic anywhere outside the engines
/// (a bug of this harness or a spec that does not load) is reported as a disagreement too.
pub fn compare<P: Protocol>(seed: u64, budget: Budget) -> Report {
    compare_with_views::<P>(seed, budget, ViewFns::none())
}

/// [`compare`], every frame the generated code decodes also made into a view where `views`
/// has one (see [`ViewFns`]).
pub fn compare_with_views<P: Protocol>(seed: u64, budget: Budget, views: ViewFns<P>) -> Report {
    let p = match caught(|| busspec_model::load_str(P::NAME, P::SOURCE.spec_yaml)) {
        Ok(Ok(p)) => p,
        other => {
            let mut r = Report::default();
            r.record(Disagreement {
                kind: "panic",
                signature: "panic: the spec does not load".into(),
                class_only: false,
                how: "loading the spec".into(),
                input: String::new(),
                generated: String::new(),
                interpreter: match other {
                    Ok(Err(d)) => d.to_string(),
                    Err(m) => m,
                    Ok(Ok(_)) => String::new(),
                },
            });
            return r;
        }
    };
    let outcome = caught(|| {
        let mut r = Run::<P>::new(&p, seed);
        r.views = views;
        r.all(budget);
        r.report
    });
    match outcome {
        Ok(r) => r,
        Err(m) => {
            let mut r = Report::default();
            r.record(Disagreement {
                kind: "panic",
                signature: "panic: in the comparison itself".into(),
                class_only: false,
                how: "the comparison itself".into(),
                input: String::new(),
                generated: m,
                interpreter: String::new(),
            });
            r
        }
    }
}

/// The reproduction text for one disagreement: a leading comment with the input and both
/// answers, then the spec.
pub fn reproduction(spec_yaml: &str, seed: u64, d: &Disagreement) -> String {
    let mut out = String::new();
    let comment = |out: &mut String, label: &str, text: &str| {
        for (k, line) in text.lines().enumerate() {
            let l = if k == 0 { label } else { "" };
            out.push_str(&format!("# {l:<12}{line}\n"));
        }
        if text.is_empty() {
            out.push_str(&format!("# {label}\n"));
        }
    };
    out.push_str(&format!(
        "# busspec-difftest disagreement, spec seed {seed}\n# {}\n",
        d.signature
    ));
    comment(&mut out, "how:", &d.how);
    comment(&mut out, "input:", &d.input);
    comment(&mut out, "generated:", &d.generated);
    comment(&mut out, "interpreter:", &d.interpreter);
    out.push_str("#\n");
    out.push_str(spec_yaml);
    out
}
