//! The traits every generated protocol implements: [`Protocol`] for the protocol as a whole
//! (its constants, its codec, its framing), [`Message`] for its `Request` and `Response` types.
//!
//! Each generated module has a unit type named after the protocol (`ub2::Ub2`, `sd::Sd`) that
//! implements [`Protocol`]; a transport, a sniffer or a test written against the trait works
//! for every protocol, built in or brought by a user's build script.

use core::fmt::Debug;
use core::ops::RangeInclusive;

use crate::stream::{Candidate, Candidates, VarLens};
use crate::{
    Broadcast, CommandKind, DecodeError, Decoded, EncodeError, FieldError, FieldValue, Reply,
};

/// One message type of a protocol (its `Request` or its `Response`): every variant is one
/// message of the spec.
pub trait Message: Copy + Debug + PartialEq + Send + Sync + 'static {
    /// The message's name in the spec (`go_to_capacitance`).
    fn name(&self) -> &'static str;
    /// The message's code bytes, as they travel.
    fn code(&self) -> &'static [u8];
    /// The length of the message's frame, in bytes.
    fn frame_len(&self) -> usize;
    /// Calls `f` with each field's spec name and raw value, in frame order.
    fn visit<F: FnMut(&'static str, FieldValue<'_>)>(&self, f: F);
    /// Writes the frame to `address` into `buf` and returns its length.
    fn encode(&self, address: u8, buf: &mut [u8]) -> Result<usize, EncodeError>;
    /// The message called `name` in the spec, from its field values: `field` is asked once for
    /// each field [`Self::visit`] reports, by the same spec name, and answers with the same raw
    /// wire value `visit` gives (an integer that fits the field's wire type, sign-extended
    /// where it is signed; an ASCII field's bytes, exactly its length), or `None` if it has
    /// none. Constant and repeated fields are not asked for: [`Self::encode`] writes them.
    ///
    /// For every message `m`, `from_fields(m.name(), |f| the value m.visit gave for f)` is
    /// `Ok(m)`. Enums and flags take any raw value (unlisted ones as `Unknown`, unnamed bits
    /// kept); a value is checked only against its wire type, as the encoders check it.
    fn from_fields<'v, F: FnMut(&'static str) -> Option<FieldValue<'v>>>(
        name: &str,
        field: F,
    ) -> Result<Self, FieldError>;
}

/// A protocol's `Request` type: what the spec says of each command beyond its frame.
pub trait RequestMessage: Message {
    /// What the spec says of this request beyond its frame: its kind, the broadcast address,
    /// its reply, whether a master may send it again.
    fn command(&self) -> Command;
    /// The bytes of the request frame `frame` (as it travelled) its checksum covers: what the
    /// checksum of a reply that takes in its request's bytes (`checksum_over_request`) runs
    /// over first. Empty for a protocol with no such reply and for a frame too short to hold a
    /// checksum.
    #[inline]
    fn covered(frame: &[u8]) -> &[u8] {
        let _ = frame;
        &[]
    }
}

/// A protocol's `Response` type, the reply to requests of type `Q`: which requests it
/// answers, whether it is a refusal, and its decoding as the reply to a request.
pub trait ResponseMessage<Q>: Message {
    /// Whether the spec lets `request` get this response.
    fn answers(&self, request: &Q) -> bool;
    /// Whether this response is a refusal: the spec marks it `kind: nak`.
    fn is_nak(&self) -> bool;
    /// Whether the device sends this response on its own (`unasked: true`), not only as a
    /// reply: heard after a request that does not list it ([`Self::answers`] is `false`), it
    /// is not that request's reply, and the master sets it aside and keeps waiting. `false`
    /// for a protocol with no such response.
    #[inline]
    fn is_unasked(&self) -> bool {
        false
    }
    /// Whether any response of the protocol is sent unasked ([`Self::is_unasked`]): where
    /// none is, a master need not look for one in what it receives.
    const HAS_UNASKED: bool = false;
    /// Decodes `frame` as a response, the reply to `request` where one is given (only the
    /// responses it may get); a response only its request tells apart is
    /// [`DecodeError::Ambiguous`] without one. What [`Protocol::decode_response`] and
    /// [`Protocol::decode_reply`] call, and the stream decoder.
    fn decode_as_reply(frame: &[u8], request: Option<&Q>) -> Result<Decoded<Self>, DecodeError>;
    /// [`Self::decode_as_reply`] with the bytes the request's checksum covers
    /// ([`RequestMessage::covered`]), which the checksum of a reply that takes in its
    /// request's bytes runs over first; without them such a reply is
    /// [`DecodeError::NeedsRequest`]. Protocols with no such reply decode as without them.
    #[inline]
    fn decode_as_reply_over(
        frame: &[u8],
        request: Option<&Q>,
        covered: Option<&[u8]>,
    ) -> Result<Decoded<Self>, DecodeError> {
        let _ = covered;
        Self::decode_as_reply(frame, request)
    }
    /// Writes this response to `address` into `buf` as the reply to a request whose checksum
    /// covered `covered`: as [`Message::encode`], and the checksum of a reply that takes in
    /// its request's bytes over them.
    #[inline]
    fn encode_reply_over(
        &self,
        address: u8,
        covered: &[u8],
        buf: &mut [u8],
    ) -> Result<usize, EncodeError> {
        let _ = covered;
        self.encode(address, buf)
    }
}

/// A frame buffer: `[u8; N]` for any `N`, with its all-zero value ([`Protocol::Buffer`]).
pub trait FrameBuffer: AsRef<[u8]> + AsMut<[u8]> + Copy + Debug {
    /// The all-zero buffer.
    const ZERO: Self;
}

impl<const N: usize> FrameBuffer for [u8; N] {
    const ZERO: Self = [0; N];
}

/// A protocol generated from a busspec spec: its types, where it came from, its bus, and its
/// codec.
///
/// Implemented by the unit type each generated module declares. All methods are associated
/// functions (no `self`): a protocol is a type, not a value. Its face is what a user calls:
/// the two message types and a buffer, four constants, the decoders and the reply's encoder.
/// What the spec says of a message beyond its frame is the message's own
/// ([`RequestMessage::command`], [`ResponseMessage::answers`], [`ResponseMessage::is_nak`]);
/// what the stream decoder asks of a protocol (frame lengths, the candidates a head leaves,
/// the checksum test) is [`Framing`], a supertrait no user needs to name.
pub trait Protocol: Framing + Copy + Debug + Default + Send + Sync + 'static {
    /// Master to device.
    type Request: RequestMessage;
    /// Device to master.
    type Response: ResponseMessage<Self::Request>;
    /// A buffer of exactly [`Self::MAX_FRAME_LEN`] bytes (`[u8; MAX_FRAME_LEN]`;
    /// [`FrameBuffer::ZERO`] is the empty one).
    type Buffer: FrameBuffer;

    /// The protocol's name in the spec (`ub2`).
    const NAME: &'static str;
    /// The document the spec transcribes, and the spec the code was generated from.
    const SOURCE: Source;
    /// The bus the document puts its devices on: baud rate, gaps, addresses, transaction
    /// timing.
    const BUS: Bus;
    /// The longest frame in either direction: a buffer this long holds any frame.
    const MAX_FRAME_LEN: usize;

    /// Decodes a request frame.
    fn decode_request(frame: &[u8]) -> Result<Decoded<Self::Request>, DecodeError>;
    /// Decodes a response frame on its own; a response only its request identifies is
    /// [`DecodeError::Ambiguous`].
    #[inline]
    fn decode_response(frame: &[u8]) -> Result<Decoded<Self::Response>, DecodeError> {
        Self::Response::decode_as_reply(frame, None)
    }
    /// [`Self::decode_request`]'s answer, where the stream decoder's candidate table
    /// ([`Framing::candidate`]) gave the frame's length: generated code decodes each of the
    /// direction's fixed lengths through a copy of the decoder of its own, which checks a
    /// frame of constant length (UB2's stream: fewer instructions a frame than the decoder
    /// that takes any length). The default is [`Self::decode_request`]. The stream decoder's,
    /// not a user's: hidden from the protocol's face.
    #[doc(hidden)]
    #[inline]
    fn decode_request_fixed(frame: &[u8]) -> Result<Decoded<Self::Request>, DecodeError> {
        Self::decode_request(frame)
    }
    /// [`Self::decode_response`]'s answer, as [`Self::decode_request_fixed`] gives
    /// [`Self::decode_request`]'s.
    #[doc(hidden)]
    #[inline]
    fn decode_response_fixed(frame: &[u8]) -> Result<Decoded<Self::Response>, DecodeError> {
        Self::decode_response(frame)
    }
    /// Decodes a frame as the reply to `request`: only the responses `request` may get.
    #[inline]
    fn decode_reply(
        frame: &[u8],
        request: &Self::Request,
    ) -> Result<Decoded<Self::Response>, DecodeError> {
        Self::Response::decode_as_reply(frame, Some(request))
    }
    /// Decodes `frame` as the reply to the request frame `request_frame` (as it travelled):
    /// as [`Self::decode_reply`], and the checksum of a reply that takes in its request's
    /// bytes (`checksum_over_request`: Pelco D's general response) is checked over them,
    /// where [`Self::decode_reply`] refuses such a reply with
    /// [`DecodeError::NeedsRequest`]. A `request_frame` that does not decode as a request is
    /// refused with its own error.
    #[inline]
    fn decode_reply_to(
        frame: &[u8],
        request_frame: &[u8],
    ) -> Result<Decoded<Self::Response>, DecodeError> {
        let request = Self::decode_request(request_frame)?;
        Self::Response::decode_as_reply_over(
            frame,
            Some(&request.message),
            Some(Self::Request::covered(request_frame)),
        )
    }
    /// Writes `response` to `address` into `buf` as the reply to the request frame
    /// `request_frame` (as it travelled), and returns its length: as
    /// [`Message::encode`], and the checksum of a reply that takes in its request's bytes
    /// over them, where [`Message::encode`] refuses such a reply with
    /// [`EncodeError::NeedsRequest`].
    #[inline]
    fn encode_reply(
        response: &Self::Response,
        address: u8,
        request_frame: &[u8],
        buf: &mut [u8],
    ) -> Result<usize, EncodeError> {
        response.encode_reply_over(address, Self::Request::covered(request_frame), buf)
    }
}

/// A preamble of wake-up bytes (`framing.preamble`): `send` copies of `byte` are written
/// before every frame, and 0 to `max` of them are taken before one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Preamble {
    pub byte: u8,
    pub send: u8,
    pub max: u8,
}

impl Preamble {
    /// `frame` after its preamble bytes (0 to `max` of them).
    #[inline]
    pub fn skip<'f>(&self, frame: &'f [u8]) -> &'f [u8] {
        let n = frame
            .iter()
            .take(usize::from(self.max))
            .take_while(|b| **b == self.byte)
            .count();
        frame.get(n..).unwrap_or_default()
    }

    /// Writes the `send` preamble bytes at the start of `buf`: how many, or
    /// [`EncodeError::BufferTooSmall`](crate::EncodeError::BufferTooSmall).
    #[inline]
    pub fn put(&self, buf: &mut [u8]) -> Result<usize, crate::EncodeError> {
        let n = usize::from(self.send);
        let available = buf.len();
        let out = buf.get_mut(..n).ok_or(crate::EncodeError::BufferTooSmall {
            needed: n,
            available,
        })?;
        out.fill(self.byte);
        Ok(n)
    }
}

/// A per-byte transform of every payload byte as it travels (`framing.transform`: DL/T 645's
/// +33H). Encoders write the fields, transform the payload, then compute the checksum over the
/// bytes as they travel; decoders check the checksum, then undo the transform before reading
/// fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transform {
    /// The byte plus this, mod 256.
    Add(u8),
    /// The byte XOR this.
    Xor(u8),
}

impl Transform {
    /// A byte as it travels.
    #[inline(always)]
    pub const fn apply(self, b: u8) -> u8 {
        match self {
            Transform::Add(k) => b.wrapping_add(k),
            Transform::Xor(k) => b ^ k,
        }
    }

    /// A byte as it travelled, back to its value.
    #[inline(always)]
    pub const fn undo(self, b: u8) -> u8 {
        match self {
            Transform::Add(k) => b.wrapping_sub(k),
            Transform::Xor(k) => b ^ k,
        }
    }

    /// Transforms the payload of the frame of `len` bytes in `buf`, from `at` to the last
    /// `trailer` bytes (checksum and end bytes), in place: as it travels.
    #[inline]
    pub fn put(self, buf: &mut [u8], len: usize, at: usize, trailer: usize) {
        let end = len.saturating_sub(trailer);
        if let Some(payload) = buf.get_mut(at..end) {
            for b in payload {
                *b = self.apply(*b);
            }
        }
    }

    /// `frame` copied into `plain` (at least as long) with its payload's transform undone,
    /// from `at` to the last `trailer` bytes: the copy.
    #[inline]
    pub fn undo_into<'b>(
        self,
        frame: &[u8],
        at: usize,
        trailer: usize,
        plain: &'b mut [u8],
    ) -> &'b [u8] {
        let len = frame.len();
        let Some(out) = plain.get_mut(..len) else {
            return &[];
        };
        out.copy_from_slice(frame);
        if let Some(payload) = out.get_mut(at..len.saturating_sub(trailer)) {
            for b in payload {
                *b = self.undo(*b);
            }
        }
        out
    }
}

/// What the stream decoder asks of a protocol to find frames in a stream: implemented by the
/// generated code, beside [`Protocol`]; a tool that only decodes, encodes or talks never names
/// it.
#[doc(hidden)]
pub trait Framing {
    /// The longest request frame, in bytes.
    const MAX_REQUEST_LEN: usize;
    /// The longest response frame, in bytes.
    const MAX_RESPONSE_LEN: usize;
    /// Every distinct frame length, longest first (at most 64).
    const FRAME_LENGTHS: &'static [usize];
    /// The flag of flag framing (HDLC's `7E`, KISS's `C0`: one byte that opens and closes
    /// every escaped frame), which a sender may share between two frames: the stream decoder
    /// then keeps a frame's closing flag as the next frame's possible opening one. `None`
    /// (the default) for every other framing.
    const SHARED_FLAG: Option<u8> = None;
    /// The wake-up bytes sent before every frame (DL/T 645's `FE FE FE FE`), which the stream
    /// decoder counts into the frame they precede. `None` (the default) for every other
    /// framing.
    const PREAMBLE: Option<Preamble> = None;
    /// The per-byte transform of every payload byte (DL/T 645's +33H), which the generated
    /// candidate tables already apply to the constants they compare. `None` (the default) for
    /// every other framing.
    const TRANSFORM: Option<Transform> = None;
    /// The long form of a length field whose width the start byte chooses (VESC's `03 lenH
    /// lenL`), by which the generated `variable_candidates` frames both forms. `None` (the
    /// default) for every other framing.
    const LONG: Option<crate::LongLength> = None;
    /// Whether a reply's checksum takes in its request's bytes (`checksum_over_request`):
    /// the stream decoder then keeps the bytes each request's checksum covers
    /// ([`RequestMessage::covered`]) in a [`Self::Span`] for the reply after it.
    const OVER_REQUEST: bool = false;
    /// Whether a response's decoding may depend on the request before it: some response only
    /// its request tells apart from another (`needs_request`), or [`Self::OVER_REQUEST`].
    /// Where not (`false`, generated for such a protocol), a frame decodes as the reply to any
    /// request exactly as it decodes on its own, or is refused as the reply and decodes on its
    /// own all the same, so the stream decoder neither keeps the last request nor asks it.
    /// `true` (the default) pairs every response.
    const REPLY_BY_REQUEST: bool = true;
    /// Room for those bytes: `[u8; MAX_REQUEST_LEN]` where [`Self::OVER_REQUEST`], else
    /// `[u8; 0]`.
    type Span: AsRef<[u8]> + AsMut<[u8]> + Copy + core::fmt::Debug;
    /// An all-zero [`Self::Span`].
    const EMPTY_SPAN: Self::Span;

    /// The messages whose start byte and code agree with `head`, the bytes buffered from a
    /// possible frame start (possibly fewer than a whole frame): the stream decoder's framing
    /// rule. The address is not looked at: strict decoding judges it, and a frame from an
    /// address the spec does not allow is reported as out of spec, not skipped.
    fn candidates(head: &[u8]) -> Candidates;

    /// [`Self::candidates`] for a head of at least `MAX_FRAME_LEN` bytes, where its
    /// start byte and code leave at most two frames ([`Candidate::of`] of the candidates):
    /// the same decision in one table lookup, which the stream decoder's fast path takes
    /// first. [`Candidate::MANY`] (the default) wherever the candidates must be asked.
    #[inline]
    fn candidate(head: &[u8]) -> Candidate {
        let _ = head;
        Candidate::MANY
    }

    /// The variable-length messages (a length field or a repeated field's count gives their
    /// length, so [`Self::FRAME_LENGTHS`] does not list it) whose start byte and code agree
    /// with `head`: for each direction, the length of the frame the head's length or count
    /// field gives ([`VarLen::of`](crate::stream::VarLen::of) of [`crate::codec::RepeatAt::frame_len`] or
    /// [`crate::stream::LengthField::frame_len`]), [`VarLen::NEED_MORE`](crate::stream::VarLen::NEED_MORE) while that field
    /// has not been buffered, [`VarLen::NONE`](crate::stream::VarLen::NONE) if no such message agrees or the field gives a
    /// length none of them can have (the decoder then drops the head byte unless a fixed-length
    /// candidate is a frame: resynchronisation).
    ///
    /// At most one per direction: where several variable-length messages of one direction
    /// agree with a head, their length must come from the same field (a length field does), or
    /// the protocol lists those lengths in [`Self::FRAME_LENGTHS`] instead (so must a repeat
    /// to the end of the frame without a length field: every whole number of elements is a
    /// length). The default, for protocols whose every frame length is in
    /// [`Self::FRAME_LENGTHS`], is [`VarLens::NONE`]; it costs the decoder nothing.
    #[inline]
    fn variable_candidates(head: &[u8]) -> VarLens {
        let _ = head;
        VarLens::NONE
    }

    /// Whether [`Self::request_decodes`] or [`Self::response_decodes`] answers through a
    /// borrowed view (generated where a direction has one), cheaper than the owned decoding:
    /// the stream decoder then asks them first of a frame that may be either direction, and
    /// decodes the value only of the one direction that decodes. `false` by default: each
    /// direction decoded once.
    const VIEWS: bool = false;

    /// Whether `frame` decodes as a request: [`Protocol::decode_request`]'s answer without
    /// its value (`Ok(())` where it decodes, else the same error). The stream decoder asks it
    /// where a frame may be either direction, and the answer alone settles it wherever it
    /// decodes both ways (ambiguous); generated code answers through its borrowed view where
    /// the direction has one, which checks all the owned decoder checks and copies no list.
    #[inline]
    fn request_decodes(frame: &[u8]) -> Result<(), DecodeError>
    where
        Self: Protocol,
    {
        Self::decode_request(frame).map(|_| ())
    }

    /// Whether `frame` may decode as a request as far as what follows its framing says (its
    /// code, constants, lengths, the ranges of its fields, the broadcast rule), its checksum
    /// not computed: `false` only where [`Self::request_decodes`] fails whatever its framing.
    /// The stream decoder asks it of a request candidate longer than another candidate, which
    /// it then tries first (a short Modbus coil reply is not tried as an 8-byte request through
    /// a whole decode). Generated code answers through the request view's `dispatch` where the
    /// framing checks leave it nothing to rely on; `true` (no claim) otherwise.
    #[inline]
    fn request_may_decode(frame: &[u8]) -> bool {
        let _ = frame;
        true
    }

    /// [`ResponseMessage::decode_as_reply_over`]'s answer without its value, as
    /// [`Self::request_decodes`] gives [`Protocol::decode_request`]'s.
    #[inline]
    fn response_decodes(
        frame: &[u8],
        request: Option<&<Self as Protocol>::Request>,
        covered: Option<&[u8]>,
    ) -> Result<(), DecodeError>
    where
        Self: Protocol,
    {
        <Self as Protocol>::Response::decode_as_reply_over(frame, request, covered).map(|_| ())
    }

    /// Whether `frame` decodes as a request (`Ok`, else the request's error, as
    /// [`Self::request_decodes`] gives it) and then also as a response on its own (`Ok(true)`
    /// where [`Self::response_decodes`] without a request decodes it or finds it ambiguous):
    /// what the stream decoder asks of a frame both directions may be, where no response needs
    /// its request ([`Self::REPLY_BY_REQUEST`] and [`Self::OVER_REQUEST`] are `false`).
    /// Generated code checks the framing once where both directions check it alike (the same
    /// start, length, address, checksum and length field), then each direction's code.
    #[inline]
    fn decodes_both_ways(frame: &[u8]) -> Result<bool, DecodeError>
    where
        Self: Protocol,
    {
        Self::request_decodes(frame)?;
        Ok(matches!(
            Self::response_decodes(frame, None, None),
            Ok(()) | Err(DecodeError::Ambiguous { .. })
        ))
    }

    /// Whether `frame` ends in the checksum of the bytes it covers, and nothing else: the
    /// weakest acceptance test (a frame shorter than a checksum fails it). It knows no
    /// request: a reply whose checksum takes in its request's bytes (`checksum_over_request`)
    /// is taken over its own bytes alone here, which such a reply fails.
    fn checksum_ok(frame: &[u8]) -> bool;
}

/// Where a protocol's code came from ([`Protocol::SOURCE`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Source {
    /// The vendor document the spec transcribes.
    pub document: &'static str,
    /// The document's revision.
    pub revision: &'static str,
    /// SHA-256 of the spec the code was generated from (with the files it includes),
    /// lowercase hex.
    pub spec_sha256: &'static str,
    /// The spec's text, as the code was generated from it: tools that need more than the
    /// codec (names of units, documentation, the interpreter) load it with `busspec-model`.
    /// Costs nothing in a binary that does not use it.
    pub spec_yaml: &'static str,
}

/// The bus a protocol's document puts its devices on ([`Protocol::BUS`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Bus {
    /// The document's baud rate.
    pub baud: u32,
    /// The quiet time the document demands between frames, in milliseconds, if it says.
    pub inter_frame_gap_ms: Option<u32>,
    /// The most frames per second the document allows, if it says.
    pub max_frames_per_s: Option<u32>,
    /// Device addresses, inclusive.
    pub device_addresses: RangeInclusive<u8>,
    /// The broadcast address, if the protocol has one.
    pub broadcast_address: Option<u8>,
    /// The host's own address, if the spec gives one: a frame may carry it besides the device
    /// range and the broadcast address.
    pub host_address: Option<u8>,
    /// Whether replies carry the device's address (with a layout per direction, requests
    /// alone may: RoboClaw's replies carry none, and a master takes them as from the device
    /// it asked).
    pub replies_addressed: bool,
    /// What a bus master needs that the spec declares in its `transactions:` section
    /// ([`Transactions::UNDECLARED`] for a spec without one).
    pub transactions: Transactions,
}

/// What a spec says of one command beyond its frame ([`RequestMessage::command`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Command {
    /// What the command does, as the spec classifies it.
    pub kind: CommandKind,
    /// How the command treats the broadcast address.
    pub broadcast: Broadcast,
    /// Whether it gets a reply (`reply`; required unless the spec says).
    pub reply: Reply,
    /// Whether a master may send it again when its reply is lost or garbled: the spec's
    /// `transactions.retry`, by default [`CommandKind::safe_to_repeat`] of its kind.
    pub may_retry: bool,
}

/// The timing a spec's `transactions:` section declares for a bus master. Durations are in
/// microseconds; `None` where the spec does not say (the master keeps its own default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transactions {
    /// How long a device may take to start its reply.
    pub response_timeout_us: Option<u32>,
    /// A device's turnaround: the time before its reply may start, and after a broadcast it
    /// does not answer, before it takes the next request.
    pub turnaround_us: Option<u32>,
    /// The quiet time between frames in tenths of a character time (35 for Modbus's t3.5), at
    /// the line's baud rate; [`Bus::inter_frame_gap_ms`] is the same gap at the document's.
    pub gap_tenths_of_character: Option<u32>,
    /// The gap is never shorter than this (Modbus: 1750 µs above 19,200 baud).
    pub gap_at_least_us: u32,
    /// Bits one character takes on the line: start, data, parity and stop bits.
    pub character_bits: u32,
}

impl Transactions {
    /// A spec without the section: nothing declared, 8N1 characters.
    pub const UNDECLARED: Transactions = Transactions {
        response_timeout_us: None,
        turnaround_us: None,
        gap_tenths_of_character: None,
        gap_at_least_us: 0,
        character_bits: 10,
    };

    /// The declared gap in character times at `baud` (and `character_bits` a character),
    /// rounded up to the microsecond and never below [`Self::gap_at_least_us`]; `None` where
    /// the gap is not declared in character times.
    pub const fn gap_us_at(&self, baud: u32, character_bits: u32) -> Option<u64> {
        let Some(tenths) = self.gap_tenths_of_character else {
            return None;
        };
        let baud = if baud == 0 { 1 } else { baud as u64 };
        let us = (tenths as u64 * character_bits as u64 * 1_000_000).div_ceil(10 * baud);
        let floor = self.gap_at_least_us as u64;
        Some(if us > floor { us } else { floor })
    }
}

/// Something to do with a protocol chosen at run time, by name: see each protocols crate's
/// `with_protocol`. The trait has associated types, so it cannot be a `dyn` object; a visitor
/// is how a tool turns a name into a type.
pub trait ProtocolVisitor {
    type Output;
    fn visit<P: Protocol>(self) -> Self::Output;
}
