//! A protocol read at run time (`talk --spec`, `soak --spec`): the interpreter behind the
//! runtime's `Protocol` and link-core's `Link`, so that the one master (`MasterCore`, every
//! transaction rule) runs a spec no build has seen.
//!
//! The spec is installed once per process ([`install`]) and kept for its life. A message is
//! its frame, at most [`CAP`] bytes, copied (the runtime's messages are `Copy`), decoded and
//! encoded by the interpreter whenever its values are needed. The `Protocol` constants are
//! placeholders; what the master reads of the spec (name, baud rate, `transactions:`, device
//! and broadcast addresses, request gap) comes from the installed spec through `Link`'s
//! methods. Stream framing (`candidates`) is not offered: the master frames replies by
//! decoding them, and `decode --stream --spec` has the interpreter's own stream decoder.

use std::borrow::Cow;
use std::collections::HashSet;
use std::fmt;
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

use busspec_link::Link;
use busspec_model::interp::{self, Raw, Value};
use busspec_model::ir::{Direction, MessageKind, MessageRef};
use busspec_model::Protocol as Spec;
use busspec_runtime::stream::Candidates;
use busspec_runtime::{
    Broadcast, Bus, Command, CommandKind, CountRule, DecodeError, Decoded, Elements, EncodeError,
    EscapeFault, FieldDesc, FieldError, FieldValue, Framing, Message, MessageDesc, MessageNames,
    NumKind, Protocol, Reply, RequestMessage, ResponseMessage, Source, Transactions,
};

/// The most bytes a frame of a spec read at run time may take.
pub const CAP: usize = 1024;

static SPEC: OnceLock<&'static Spec> = OnceLock::new();

/// Keeps `spec` for the life of the process as the protocol [`Interpreted`] stands for. A spec
/// whose longest frame is over [`CAP`] bytes is refused, and so is a second spec.
pub fn install(spec: Spec) -> Result<&'static Spec, String> {
    let longest = spec
        .commands
        .iter()
        .chain(&spec.responses)
        .map(|m| m.max_len)
        .max()
        .unwrap_or(0);
    if longest > CAP {
        return Err(format!(
            "error: {}: frames of up to {longest} bytes; a spec read at run time may have {CAP} at most (generate its crate instead)",
            spec.name
        ));
    }
    if let Some(p) = SPEC.get() {
        return if p.spec_sha256 == spec.spec_sha256 {
            Ok(p)
        } else {
            Err("error: one spec read at run time per process".to_owned())
        };
    }
    let leaked: &'static Spec = Box::leak(Box::new(spec));
    Ok(SPEC.get_or_init(|| leaked))
}

/// The installed spec. Every [`Interpreted`] value is made from it, so it is there whenever
/// one exists; before [`install`], the empty name.
fn spec() -> Option<&'static Spec> {
    SPEC.get().copied()
}

/// Text with the life of the process: spec names are `&'static` already (the spec is); other
/// texts an error carries are kept once each.
fn keep(s: &str) -> &'static str {
    static KEPT: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let set = KEPT.get_or_init(|| Mutex::new(HashSet::new()));
    let mut set = match set.lock() {
        Ok(g) => g,
        Err(poisoned) => poisoned.into_inner(),
    };
    if let Some(k) = set.get(s) {
        return k;
    }
    let k: &'static str = Box::leak(s.to_owned().into_boxed_str());
    set.insert(k);
    k
}

/// A message's descriptor with the life of the process, kept once each, as the runtime's
/// errors point at one: its name, its code (`code_len` bytes) and no lengths.
fn keep_message(name: &str, code: u32, code_len: u8) -> &'static MessageDesc {
    static KEPT: OnceLock<Mutex<HashSet<&'static MessageDesc>>> = OnceLock::new();
    let set = KEPT.get_or_init(|| Mutex::new(HashSet::new()));
    let mut set = match set.lock() {
        Ok(g) => g,
        Err(poisoned) => poisoned.into_inner(),
    };
    let d = MessageDesc::new(keep(name), code, code_len, &[]);
    if let Some(k) = set.get(&d) {
        return k;
    }
    let k: &'static MessageDesc = Box::leak(Box::new(d));
    set.insert(k);
    k
}

/// A field's descriptor with the life of the process, kept once each, as the runtime's
/// errors point at one: field `field` of message `message`.
fn keep_field(message: &str, field: &str) -> &'static FieldDesc {
    static KEPT: OnceLock<Mutex<HashSet<&'static FieldDesc>>> = OnceLock::new();
    let set = KEPT.get_or_init(|| Mutex::new(HashSet::new()));
    let mut set = match set.lock() {
        Ok(g) => g,
        Err(poisoned) => poisoned.into_inner(),
    };
    let d = FieldDesc::new(keep(message), keep(field));
    if let Some(k) = set.get(&d) {
        return k;
    }
    let k: &'static FieldDesc = Box::leak(Box::new(d));
    set.insert(k);
    k
}

/// The installed spec's end bytes (`framing.end`), with the life of the process.
fn end_bytes() -> &'static [u8] {
    spec().map_or(&[], |p| p.framing.end.as_slice())
}

fn name_of(c: Cow<'static, str>) -> &'static str {
    match c {
        Cow::Borrowed(s) => s,
        Cow::Owned(s) => keep(&s),
    }
}

/// The protocol of the installed spec.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Interpreted;

/// A message of the installed spec: a command (`RESPONSE` false) or a response, as its frame.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Frame<const RESPONSE: bool> {
    index: u16,
    len: u16,
    bytes: [u8; CAP],
}

impl<const R: bool> Frame<R> {
    fn direction() -> Direction {
        if R {
            Direction::Response
        } else {
            Direction::Request
        }
    }

    fn r(&self) -> MessageRef {
        MessageRef {
            direction: Self::direction(),
            index: usize::from(self.index),
        }
    }

    fn wire(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }

    fn from_wire(index: usize, wire: &[u8]) -> Option<Self> {
        if wire.len() > CAP {
            return None;
        }
        let mut bytes = [0u8; CAP];
        bytes[..wire.len()].copy_from_slice(wire);
        Some(Frame {
            index: u16::try_from(index).ok()?,
            len: wire.len() as u16,
            bytes,
        })
    }

    fn values(&self) -> Vec<Value<'static>> {
        let Some(p) = spec() else {
            return Vec::new();
        };
        interp::decode_as_kept(p, self.r(), self.wire())
            .map(|f| f.values)
            .unwrap_or_default()
    }

    fn message(&self) -> Option<&'static busspec_model::ir::Message> {
        spec().map(|p| p.message(self.r()))
    }
}

impl<const R: bool> fmt::Debug for Frame<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}({})",
            self.name(),
            busspec_model::interp::format_hex(self.wire())
        )
    }
}

impl<const R: bool> Message for Frame<R> {
    fn name(&self) -> &'static str {
        self.message().map_or("", |m| m.name.as_str())
    }

    fn code(&self) -> &'static [u8] {
        self.message().map_or(&[], |m| m.code.as_slice())
    }

    fn frame_len(&self) -> usize {
        usize::from(self.len)
    }

    fn visit<F: FnMut(&'static str, FieldValue<'_>)>(&self, mut f: F) {
        for Value { name, raw } in self.values() {
            let name = name_of(name);
            match &raw {
                Raw::Int(i) => f(name, FieldValue::Int(*i)),
                Raw::Text(t) => f(name, FieldValue::Text(t)),
                Raw::List(l) => f(name, FieldValue::List(Elements::I64(l))),
                Raw::Records(r) => f(
                    name,
                    FieldValue::Records(busspec_runtime::RecordList::Flat {
                        values: &r.concat(),
                        fields: r.first().map_or(0, Vec::len),
                    }),
                ),
            }
        }
    }

    fn encode(&self, address: u8, buf: &mut [u8]) -> Result<usize, EncodeError> {
        let Some(p) = spec() else {
            return Err(EncodeError::OutOfRange { field: "" });
        };
        let wire = interp::encode(p, self.r(), address, &self.values()).map_err(encode_error)?;
        let available = buf.len();
        let out = buf
            .get_mut(..wire.len())
            .ok_or(EncodeError::BufferTooSmall {
                needed: wire.len(),
                available,
            })?;
        out.copy_from_slice(&wire);
        Ok(wire.len())
    }

    fn from_fields<'v, F: FnMut(&'static str) -> Option<FieldValue<'v>>>(
        name: &str,
        mut field: F,
    ) -> Result<Self, FieldError> {
        let p = spec().ok_or(FieldError::UnknownMessage)?;
        let list = if R { &p.responses } else { &p.commands };
        let index = list
            .iter()
            .position(|m| m.name == name)
            .ok_or(FieldError::UnknownMessage)?;
        let m = &list[index];
        let mut values = Vec::new();
        for leaf in m.leaves() {
            if let busspec_model::ir::Leaf::Field(i, _) = leaf {
                if m.is_derived(i) {
                    continue;
                }
            }
            if let busspec_model::ir::Leaf::Bits(_, _, b) = leaf {
                if b.constant.is_some() {
                    continue;
                }
            }
            let n: &'static str = match leaf {
                busspec_model::ir::Leaf::Field(_, f) => f.name.as_str(),
                busspec_model::ir::Leaf::Bits(_, _, b) => b.name.as_str(),
            };
            let raw = match field(n).ok_or(FieldError::Missing { field: n })? {
                FieldValue::Int(i) => Raw::Int(i),
                FieldValue::Text(t) => Raw::Text(t.to_vec()),
                FieldValue::List(e) => Raw::List((0..e.len()).filter_map(|k| e.get(k)).collect()),
                FieldValue::Records(l) => Raw::Records(
                    (0..l.len())
                        .map(|k| (0..l.fields()).map(|j| l.get(k, j).unwrap_or(0)).collect())
                        .collect(),
                ),
            };
            values.push(Value {
                name: Cow::Borrowed(n),
                raw,
            });
        }
        let address = first_address(p);
        let r = MessageRef {
            direction: Self::direction(),
            index,
        };
        // A reply whose checksum takes in its request's bytes is kept with its checksum over
        // its own: [`Protocol::encode_reply`] writes it over the request's, and its
        // `encode` refuses it.
        let wire = interp::encode_with(p, r, address, &values, Some(&[])).map_err(|_| {
            FieldError::Missing {
                field: "(the values do not encode)",
            }
        })?;
        Self::from_wire(index, &wire).ok_or(FieldError::UnknownMessage)
    }
}

/// An address a frame of `p` may carry: its default or first device address (0 without one).
fn first_address(p: &Spec) -> u8 {
    if !p.framing.has_address() {
        return 0;
    }
    let a = &p.framing.address;
    a.default.unwrap_or(a.min)
}

/// The interpreter's decode error as the runtime's, in the same words where the runtime has
/// them.
fn decode_error(e: interp::DecodeError) -> DecodeError {
    use interp::DecodeError as I;
    let code = |c: &[u8]| {
        c.iter()
            .take(4)
            .fold(0u32, |acc, b| acc << 8 | u32::from(*b))
    };
    match e {
        I::Truncated { needed, found } => DecodeError::Truncated { needed, found },
        I::BadStart {
            offset,
            expected,
            found,
        } => DecodeError::BadStart {
            offset,
            expected,
            found,
        },
        I::BadEnd {
            offset,
            expected,
            found,
        } => DecodeError::BadEnd {
            offset,
            expected,
            found,
        },
        I::ChecksumMismatch {
            offset,
            expected,
            found,
            width,
        } => DecodeError::ChecksumMismatch {
            offset,
            expected: expected as u32,
            found: found as u32,
            width,
        },
        I::NeedsRequest { message, offset } => DecodeError::NeedsRequest {
            message: keep_message(&message, 0, 0),
            offset,
        },
        I::UnknownCode {
            offset,
            code: c,
            direction,
        } => {
            let (code, len) = (code(&c), c.len() as u8);
            if direction == Some(Direction::Response) {
                DecodeError::UnknownResponse { offset, code, len }
            } else {
                DecodeError::UnknownCommand { offset, code, len }
            }
        }
        I::WrongLength { message, found, .. } => DecodeError::WrongLength {
            message: keep_message(&message, 0, 0),
            found,
            less: 0,
        },
        I::ConstantMismatch {
            message,
            field,
            offset,
            expected,
            found,
        } => DecodeError::InvalidValue {
            field: keep_field(&message, &field),
            offset,
            expected,
            found,
        },
        I::NotBcd {
            message,
            field,
            offset,
            found,
        } => DecodeError::NotBcd {
            field: keep_field(&message, &field),
            offset,
            found,
        },
        I::NotEqual {
            message,
            field,
            offset,
            other,
            expected,
            found,
        } => DecodeError::NotEqual {
            field: keep_field(&message, &field),
            offset,
            other: keep(&other),
            expected,
            found,
        },
        I::Ambiguous { candidates } => DecodeError::Ambiguous {
            code: 0,
            candidates: MessageNames::from_slice(
                &candidates
                    .iter()
                    .map(|c| keep_message(c, 0, 0))
                    .collect::<Vec<_>>(),
            ),
        },
        I::TooLong { max, found } => DecodeError::TooLong { max, found },
        I::OutOfRange {
            message,
            field,
            offset,
            found,
            min,
            max,
            kind,
        } => DecodeError::OutOfRange {
            field: keep_field(&message, &field),
            offset,
            found,
            min,
            max,
            kind: num_kind(kind),
        },
        I::BadAddress {
            offset,
            found,
            min,
            max,
        } => DecodeError::BadAddress {
            offset,
            found,
            min,
            max,
        },
        I::BroadcastNotAccepted {
            message,
            code: c,
            address,
        } => DecodeError::BroadcastNotAccepted {
            message: keep_message(&message, code(&c), c.len() as u8),
            address,
        },
        I::LengthMismatch {
            offset,
            expected,
            found,
        } => DecodeError::LengthMismatch {
            offset,
            expected,
            found,
        },
        I::ByteCount {
            message,
            field,
            offset,
            list,
            expected,
            found,
        } => DecodeError::ByteCount {
            list: keep_field(&message, &list),
            field: keep(&field),
            offset,
            expected,
            found,
        },
        I::NotFollowing {
            message,
            field,
            offset,
            rule,
            expected,
            found,
        } => DecodeError::NotFollowing {
            field: keep_field(&message, &field),
            offset,
            rule: keep(&rule),
            expected,
            found,
        },
        I::NotAnAnswer {
            message,
            request,
            unasked,
        } => DecodeError::NotAReply {
            message: keep(&message),
            request: keep(&request),
            unasked,
        },
        I::BadEscape { offset, fault } => DecodeError::BadEscape {
            offset,
            fault: escape_fault(fault),
        },
        I::NeedlessLong {
            offset,
            length,
            most,
        } => DecodeError::NeedlessLong {
            offset,
            length,
            most,
        },
        I::NoTerminator {
            message,
            field,
            offset,
            terminator,
            within,
        } => DecodeError::NoTerminator {
            field: keep_field(&message, &field),
            offset,
            terminator,
            within,
        },
        I::EndInside {
            message,
            field,
            offset,
            ..
        } => DecodeError::EndInside {
            field: keep_field(&message, &field),
            offset,
            end: end_bytes(),
        },
        I::BadWidth {
            message,
            field,
            offset,
            found,
            most,
        } => DecodeError::BadWidth {
            // The interpreter names the message, not the list: what the words say.
            list: keep_field(&message, ""),
            field: keep(&field),
            offset,
            found,
            most,
        },
        // The interpreter states the rule as text: kept in its words.
        I::BadCount {
            message,
            field,
            offset,
            expected,
            found,
        } => DecodeError::BadCount {
            field: keep_field(&message, &field),
            offset,
            found,
            expected: CountRule::Stated(keep(&expected)),
        },
    }
}

/// The interpreter's escaping fault as the runtime's (the same words).
fn escape_fault(f: interp::EscapeFault) -> EscapeFault {
    use interp::EscapeFault as I;
    match f {
        I::Escape { escape, found } => EscapeFault::Escape { escape, found },
        I::Unescaped { found } => EscapeFault::Unescaped { found },
        I::Stuffing { expected, found } => EscapeFault::Stuffing { expected, found },
        I::CobsZero => EscapeFault::CobsZero,
        I::CobsOverrun { code } => EscapeFault::CobsOverrun { code },
        I::CobsEmpty => EscapeFault::CobsEmpty,
        I::CobsTrailing => EscapeFault::CobsTrailing,
    }
}

/// The interpreter's kind of number as the runtime's.
fn num_kind(k: busspec_model::number::NumKind) -> NumKind {
    use busspec_model::number::NumKind as K;
    match k {
        K::Int => NumKind::Int,
        K::U64 => NumKind::U64,
        K::F32 => NumKind::F32,
        K::F64 => NumKind::F64,
    }
}

/// The interpreter's encode error as the runtime's.
fn encode_error(e: interp::EncodeError) -> EncodeError {
    use interp::EncodeError as I;
    match e {
        I::BadAddress { address, min, max } => EncodeError::BadAddress { address, min, max },
        I::NeedsRequest { message } => EncodeError::NeedsRequest {
            message: keep(&message),
        },
        I::Unaddressed { address } => EncodeError::Unaddressed { address },
        I::BroadcastNotAccepted { message, address } => EncodeError::BroadcastNotAccepted {
            message: keep_message(&message, 0, 0),
            address,
        },
        I::NotInRange {
            field,
            value,
            min,
            max,
            kind,
        } => EncodeError::NotInRange {
            field: keep(&field),
            value,
            min,
            max,
            kind: num_kind(kind),
        },
        I::Optional {
            field,
            condition,
            given,
        } => EncodeError::Optional {
            field: keep(&field),
            condition: keep(&condition),
            given,
        },
        I::HoldsTerminator {
            field,
            index,
            terminator,
        } => EncodeError::HoldsTerminator {
            field: keep(&field),
            index,
            terminator,
        },
        I::WrongCount {
            field,
            min,
            max,
            found,
        } => EncodeError::WrongCount {
            field: keep(&field),
            min,
            max,
            found,
        },
        I::HoldsEnd { field, offset, .. } => EncodeError::HoldsEnd {
            field: keep(&field),
            offset,
            end: end_bytes(),
        },
        other => EncodeError::OutOfRange {
            field: keep(&other.to_string()),
        },
    }
}

fn decoded<const R: bool>(
    f: interp::Frame<'static>,
    wire: &[u8],
) -> Result<Decoded<Frame<R>>, DecodeError> {
    let message = Frame::<R>::from_wire(f.message.index, wire).ok_or(DecodeError::TooLong {
        max: CAP,
        found: wire.len(),
    })?;
    Ok(Decoded {
        address: f.address,
        message,
    })
}

impl Protocol for Interpreted {
    type Request = Frame<false>;
    type Response = Frame<true>;
    type Buffer = [u8; CAP];

    const NAME: &'static str = "spec";
    const SOURCE: Source = Source {
        document: "",
        revision: "",
        spec_sha256: "",
        spec_yaml: "",
    };
    const BUS: Bus = Bus {
        baud: 9600,
        inter_frame_gap_ms: None,
        max_frames_per_s: None,
        device_addresses: 0..=255,
        broadcast_address: None,
        host_address: None,
        replies_addressed: true,
        transactions: Transactions::UNDECLARED,
    };
    const MAX_FRAME_LEN: usize = CAP;

    fn decode_request(frame: &[u8]) -> Result<Decoded<Self::Request>, DecodeError> {
        let p = spec().ok_or(DecodeError::Truncated {
            needed: 1,
            found: 0,
        })?;
        let f = interp::decode(p, Some(Direction::Request), None, frame).map_err(decode_error)?;
        decoded(f, frame)
    }
}

impl RequestMessage for Frame<false> {
    fn command(&self) -> Command {
        let m = self.message();
        let kind = match m.map(|m| &m.kind) {
            Some(MessageKind::Command(k)) => match *k {
                busspec_model::ir::CommandKind::Movement => CommandKind::Movement,
                busspec_model::ir::CommandKind::CompletionCheck => CommandKind::CompletionCheck,
                busspec_model::ir::CommandKind::Setter => CommandKind::Setter,
                busspec_model::ir::CommandKind::Getter => CommandKind::Getter,
                busspec_model::ir::CommandKind::Reset => CommandKind::Reset,
            },
            _ => CommandKind::Getter,
        };
        let broadcast = match m.and_then(|m| m.broadcast.as_ref()) {
            Some(b) => Broadcast {
                accepted: b.accepted,
                answered: b.answered,
            },
            None => Broadcast {
                accepted: false,
                answered: false,
            },
        };
        let reply = match m.map(|m| m.reply) {
            Some(busspec_model::ir::Reply::Optional) => Reply::Optional,
            Some(busspec_model::ir::Reply::None) => Reply::None,
            _ => Reply::Required,
        };
        let may_retry = match (spec(), m) {
            (Some(p), Some(m)) => p.transactions.retry_safe(m),
            _ => false,
        };
        Command {
            kind,
            broadcast,
            reply,
            may_retry,
        }
    }

    fn covered(frame: &[u8]) -> &[u8] {
        spec()
            .and_then(|p| p.checksum_span(frame))
            .unwrap_or_default()
    }
}

impl ResponseMessage<Frame<false>> for Frame<true> {
    fn answers(&self, request: &Frame<false>) -> bool {
        let Some(p) = spec() else {
            return false;
        };
        match (
            interp::decode_as(p, request.r(), request.wire()),
            interp::decode_as_kept(p, self.r(), self.wire()),
        ) {
            (Ok(q), Ok(r)) => interp::answers(p, &q, &r).is_ok(),
            _ => false,
        }
    }

    fn is_nak(&self) -> bool {
        matches!(
            self.message().map(|m| &m.kind),
            Some(&MessageKind::Response(busspec_model::ir::ResponseKind::Nak))
        )
    }

    /// As the reply to `request` (a response it gets, whose fields that follow from it do),
    /// its checksum over the request's bytes where it takes them in: an interpreted request
    /// keeps its frame.
    fn decode_as_reply(
        frame: &[u8],
        request: Option<&Frame<false>>,
    ) -> Result<Decoded<Self>, DecodeError> {
        let covered = request.map(|q| Frame::<false>::covered(q.wire()));
        Self::decode_as_reply_over(frame, request, covered)
    }

    fn decode_as_reply_over(
        frame: &[u8],
        request: Option<&Frame<false>>,
        covered: Option<&[u8]>,
    ) -> Result<Decoded<Self>, DecodeError> {
        let p = spec().ok_or(DecodeError::Truncated {
            needed: 1,
            found: 0,
        })?;
        let f = match request {
            Some(request) => {
                let req =
                    interp::decode_as(p, request.r(), request.wire()).map_err(decode_error)?;
                interp::decode_reply_over(p, &req, covered, frame).map_err(decode_error)?
            }
            None => interp::decode_with(p, Some(Direction::Response), None, covered, frame)
                .map_err(decode_error)?,
        };
        decoded(f, frame)
    }

    fn encode_reply_over(
        &self,
        address: u8,
        covered: &[u8],
        buf: &mut [u8],
    ) -> Result<usize, EncodeError> {
        let Some(p) = spec() else {
            return Err(EncodeError::OutOfRange { field: "" });
        };
        let wire = interp::encode_with(p, self.r(), address, &self.values(), Some(covered))
            .map_err(encode_error)?;
        let available = buf.len();
        let out = buf
            .get_mut(..wire.len())
            .ok_or(EncodeError::BufferTooSmall {
                needed: wire.len(),
                available,
            })?;
        out.copy_from_slice(&wire);
        Ok(wire.len())
    }
}

impl Framing for Interpreted {
    const MAX_REQUEST_LEN: usize = CAP;
    const MAX_RESPONSE_LEN: usize = CAP;
    const FRAME_LENGTHS: &'static [usize] = &[];
    type Span = [u8; 0];
    const EMPTY_SPAN: [u8; 0] = [];

    fn checksum_ok(frame: &[u8]) -> bool {
        let Some(p) = spec() else {
            return false;
        };
        // As the generated check: a frame without a checksum (`checksum: none`) has none to
        // fail; any other, at least one byte before the checksum and end bytes, and those
        // what the bytes before them give.
        let both = [Direction::Request, Direction::Response];
        if p.unchecked(&both, frame).is_some() {
            return true;
        }
        // (A checksum before the bytes it covers: at least as far as its own end.)
        let (c, f) = (&p.framing.checksum, &p.framing);
        if frame.len() <= c.len() + f.end.len() || frame.len() < c.lead.map_or(0, |at| at + c.len())
        {
            return false;
        }
        let mut copy = frame.to_vec();
        interp::reseal(p, &mut copy);
        copy == frame
    }

    fn candidates(_head: &[u8]) -> Candidates {
        Candidates::default()
    }
}

impl Link for Interpreted {
    fn name() -> &'static str {
        spec().map_or("spec", |p| p.name.as_str())
    }

    fn baud() -> u32 {
        spec().map_or(Self::BUS.baud, |p| p.serial.baud)
    }

    fn transactions() -> Transactions {
        let Some(p) = spec() else {
            return Transactions::UNDECLARED;
        };
        let t = &p.transactions;
        Transactions {
            response_timeout_us: t.response_timeout_us,
            turnaround_us: t.turnaround_us,
            gap_tenths_of_character: t.gap.map(|g| g.tenths),
            gap_at_least_us: t.gap.map_or(0, |g| g.at_least_us),
            character_bits: t.character_bits,
        }
    }

    fn device_addresses() -> core::ops::RangeInclusive<u8> {
        match spec() {
            Some(p) if p.framing.has_address() => p.framing.address.min..=p.framing.address.max,
            _ => 0..=0,
        }
    }

    fn broadcast_address() -> Option<u8> {
        spec().and_then(|p| p.framing.address.broadcast)
    }

    fn replies_addressed() -> bool {
        spec().map_or(true, |p| p.framing.has_address_in(Direction::Response))
    }

    fn request_gap(baud: u32, character_bits: u32) -> Duration {
        let Some(p) = spec() else {
            return Duration::ZERO;
        };
        let gap_us = Self::transactions()
            .gap_us_at(baud, character_bits)
            .or_else(|| p.serial.inter_frame_gap_ms.map(|ms| u64::from(ms) * 1000))
            .unwrap_or(0);
        let period_us = match p.serial.frame_rate.as_ref().map(|r| r.max_per_s) {
            Some(r) if r > 0 => 1000u64.div_ceil(u64::from(r)) * 1000,
            _ => 0,
        };
        Duration::from_micros(gap_us.max(period_us))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A list whose count does not fit its frame is refused as the interpreter refuses it:
    /// the same error, in the same words (it was a wrong length, its number the count).
    #[test]
    fn a_count_that_does_not_fit_is_refused_in_the_interpreters_words() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("spec/dynamixel2.yaml");
        let spec = busspec_model::load_file(&path).expect("dynamixel2.yaml loads");
        let spec = install(spec).expect("the one spec of this process");
        // SYNC WRITE of 2 data bytes a device (3-byte blocks), with 4 bytes of blocks.
        let mut frame = vec![
            0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x0B, 0x00, 0x83, 0x74, 0x00, 0x02, 0x00, 0x01, 0x10,
            0x00, 0x02, 0x00, 0x00,
        ];
        interp::reseal(spec, &mut frame);
        let theirs = interp::decode(spec, Some(Direction::Request), None, &frame)
            .expect_err("the interpreter refuses the count");
        assert!(
            matches!(theirs, interp::DecodeError::BadCount { .. }),
            "{theirs:?}"
        );
        let ours = Interpreted::decode_request(&frame).expect_err("refused here too");
        assert!(
            matches!(ours, DecodeError::BadCount { offset: 12, .. }),
            "{ours:?}"
        );
        assert_eq!(ours.to_string(), theirs.to_string());
    }
}
