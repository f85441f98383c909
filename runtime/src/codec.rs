//! What generated code uses, under one path: each generated module imports it once as
//! `use ::busspec_runtime::codec as rt;`. A lowercase name cannot clash with a spec name (spec
//! names become `CamelCase` types, variants of `Request`/`Response`, or fields), so a spec may
//! name a unit `option` or a message `ok` and the generated `rt::Option`, `rt::Ok` still mean
//! core's.
//!
//! Beside the re-exports are the small checks every message or frame would otherwise repeat
//! in the generated text. Each is `#[inline]` and takes its constants as arguments or as a
//! named constant of the generated module (a field's [`FieldCheck`]: its offset, range and
//! relation; the module's [`Frame`]: its broadcast address and trailer), so after inlining it
//! compiles to what was written out before. Public only for generated code; they
//! are not part of the runtime's documented API and may change with the generator.

pub use core::fmt::{Debug, Formatter, Result as FmtResult};
pub use core::ops::{Range, RangeInclusive};
pub use core::option::Option::{self, None, Some};
pub use core::result::Result::{self, Err, Ok};

pub use crate::escape::{
    escape as escape_frame, frame_lens as escaped_lens,
    frame_lens_by_direction as escaped_lens_by_direction, unescape as unescape_frame, EscapeKind,
    Escaping,
};
pub use crate::lists::{Lists, Split};
pub use crate::optional::{presence, OptionalAt, Optionals, Present, When};
pub use crate::repeated::{
    encode_packed_in_range, fixed_elements, list, list_bits, list_text, pack, packed_in_range,
    packed_padding, read_bits, records, unpack, write_bits, write_fixed, ByteCount, CountBy,
    CountField, CountLen, Element, RepeatAt, SizedBy,
};
pub use crate::stream::{Candidate, Candidates, LengthField, VarLen, VarLens};
pub use crate::Bits;
pub use crate::CommandKind::{CompletionCheck, Getter, Movement, Reset, Setter};
pub use crate::FieldValue::{Int, List, Records, Text};
pub use crate::LongLength;
pub use crate::ShortForm;
pub use crate::Truncation;
pub use crate::{
    crc, desc, field, field_int, field_text, round, sum8, Ascii, Broadcast, Bus, Command,
    CommandKind, DecodeError, Decoded, Elements, EncodeError, FieldDesc, FieldError, FieldValue,
    Framing, Message, MessageDesc, NumKind, Preamble, Protocol, Record, RecordList, Repeated,
    Reply, RequestMessage, ResponseMessage, Source, Transactions, Transform,
};
pub use crate::{BitsView, ListView};

/// A wire number type: the raw values a whole field of it holds, as a `from_fields` getter
/// gives them (a `u64`'s bits, an `f32`'s zero-extended, an `f64`'s: see `NumKind`).
pub trait Wire: Copy {
    const MIN: i64;
    const MAX: i64;
    /// How its raw value reads as a number.
    const KIND: NumKind = NumKind::Int;
    /// `v`, which lies in `MIN..=MAX`.
    fn from_i64(v: i64) -> Self;
    /// The raw value as `i64` (`as i64`; a float's bits).
    fn to_i64(self) -> i64;
    /// The value as `u64` (`as u64`: sign-extended).
    fn to_u64(self) -> u64;
    /// Whether raw value `raw` lies in `min..=max` (raw values), as the type orders numbers.
    #[inline(always)]
    fn within(raw: i64, min: i64, max: i64) -> bool {
        min <= raw && raw <= max
    }
}

/// A field's raw value as it travels in `FieldValue::Int` (a float's bits).
#[inline(always)]
pub fn raw<T: Wire>(v: T) -> i64 {
    v.to_i64()
}

/// The raw value of an `f32` range bound.
#[inline(always)]
pub fn f32_raw(v: f32) -> i64 {
    i64::from(v.to_bits())
}

/// The raw value of an `f64` range bound.
#[inline(always)]
pub fn f64_raw(v: f64) -> i64 {
    v.to_bits() as i64
}

/// The raw value of a `u64` range bound in generated code (its bits).
#[inline(always)]
pub const fn u64_raw(v: u64) -> i64 {
    v as i64
}

impl Wire for u64 {
    const MIN: i64 = i64::MIN;
    const MAX: i64 = i64::MAX;
    const KIND: NumKind = NumKind::U64;
    #[inline(always)]
    fn from_i64(v: i64) -> Self {
        v as u64
    }
    #[inline(always)]
    fn to_i64(self) -> i64 {
        self as i64
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        self
    }
    #[inline(always)]
    fn within(raw: i64, min: i64, max: i64) -> bool {
        (min as u64) <= (raw as u64) && (raw as u64) <= (max as u64)
    }
}

impl Wire for f32 {
    const MIN: i64 = 0;
    const MAX: i64 = u32::MAX as i64;
    const KIND: NumKind = NumKind::F32;
    #[inline(always)]
    fn from_i64(v: i64) -> Self {
        f32::from_bits(v as u32)
    }
    #[inline(always)]
    fn to_i64(self) -> i64 {
        i64::from(self.to_bits())
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        u64::from(self.to_bits())
    }
    /// A NaN lies in no range.
    #[inline(always)]
    fn within(raw: i64, min: i64, max: i64) -> bool {
        let f = |r: i64| f32::from_bits(r as u32);
        f(min) <= f(raw) && f(raw) <= f(max)
    }
}

impl Wire for f64 {
    const MIN: i64 = i64::MIN;
    const MAX: i64 = i64::MAX;
    const KIND: NumKind = NumKind::F64;
    #[inline(always)]
    fn from_i64(v: i64) -> Self {
        f64::from_bits(v as u64)
    }
    #[inline(always)]
    fn to_i64(self) -> i64 {
        self.to_bits() as i64
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        self.to_bits()
    }
    /// A NaN lies in no range.
    #[inline(always)]
    fn within(raw: i64, min: i64, max: i64) -> bool {
        let f = |r: i64| f64::from_bits(r as u64);
        f(min) <= f(raw) && f(raw) <= f(max)
    }
}

macro_rules! wire {
    ($($t:ty = $min:expr, $max:expr;)*) => {$(
        impl Wire for $t {
            const MIN: i64 = $min;
            const MAX: i64 = $max;
            #[inline(always)]
            fn from_i64(v: i64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_i64(self) -> i64 {
                self as i64
            }
            #[inline(always)]
            fn to_u64(self) -> u64 {
                self as u64
            }
        }
    )*};
}
wire! {
    u8 = 0, u8::MAX as i64;
    i8 = i8::MIN as i64, i8::MAX as i64;
    u16 = 0, u16::MAX as i64;
    i16 = i16::MIN as i64, i16::MAX as i64;
    u32 = 0, u32::MAX as i64;
    i32 = i32::MIN as i64, i32::MAX as i64;
    i64 = i64::MIN, i64::MAX;
}

/// The value of whole integer field `name` from a `from_fields` getter, checked against its
/// wire type `T`.
#[inline]
pub fn get<'v, T: Wire>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<T, FieldError> {
    field_int(name, field(name), T::MIN, T::MAX).map(T::from_i64)
}

/// The value of optional field `name` from a `from_fields` getter (`None`: no value, the
/// field absent), checked against its wire type `T`.
#[inline]
pub fn get_opt<'v, T: Wire>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Option<T>, FieldError> {
    match field(name) {
        None => Ok(None),
        value => field_int(name, value, T::MIN, T::MAX).map(|v| Some(T::from_i64(v))),
    }
}

/// [`field_int`] of an optional field: `None` where no value is given (the field absent).
#[inline]
pub fn field_int_opt(
    name: &'static str,
    value: Option<FieldValue<'_>>,
    min: i64,
    max: i64,
) -> Result<Option<i64>, FieldError> {
    match value {
        None => Ok(None),
        value => field_int(name, value, min, max).map(Some),
    }
}

/// The bytes of ASCII field `name` (exactly `N`) from a `from_fields` getter.
#[inline]
pub fn text<'v, const N: usize>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Ascii<N>, FieldError> {
    field_text(name, field(name))
}

/// What decoding one message gives.
pub type DecodeResult<T> = Result<T, DecodeError>;

/// What encoding one message gives: the frame's length.
pub type EncodeResult = Result<usize, EncodeError>;

/// The framing every frame of a protocol shares, for [`check_frame`].
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Where the start byte is and what it must be, if the protocol has one.
    pub start: Option<(usize, u8)>,
    /// Whether frames carry an address. Where they do not, the one device address is 0.
    pub addressed: bool,
    /// The device addresses, inclusive.
    pub devices: (u8, u8),
    /// Addresses a frame may carry besides the devices': broadcast and host.
    pub broadcast: Option<u8>,
    pub host: Option<u8>,
    /// Checksum bytes at the end of the frame (before [`Self::end`]), and whether they travel
    /// big-endian.
    pub checksum_len: usize,
    pub checksum_be: bool,
    /// The bytes that end every frame after its checksum (none for most protocols), or just
    /// before it where `end_first` (the checksum then covers them).
    pub end: &'static [u8],
    pub end_first: bool,
    /// Where the checksum sits where it comes before the bytes it covers (Septentrio SBF's
    /// CRC at offset 2, before the ID, length and body): it is then the checksum of the bytes
    /// from its `covers_from` to the frame's end, which the module's `frame_sum` takes from
    /// the whole frame. `None`: at the frame's end, over the bytes before it.
    pub lead: Option<usize>,
}

impl Frame {
    /// Where the checksum and the end bytes of a frame of `len` bytes start, for a frame at
    /// least as long as both.
    #[inline(always)]
    const fn trailer(&self, len: usize) -> (usize, usize) {
        if let Some(at) = self.lead {
            return (at, len - self.end.len());
        }
        let at = len - self.checksum_len - self.end.len();
        if self.end_first {
            (at + self.end.len(), at)
        } else {
            (at, at + self.checksum_len)
        }
    }

    /// Writes the end bytes and the checksum (`sum` of the bytes before it) of the `len`-byte
    /// frame in `buf`, in the order the frame has them (the checksum covers end bytes before
    /// it). Where frames carry no checksum nor end bytes, nothing.
    #[inline(always)]
    pub fn seal(&self, buf: &mut [u8], len: usize, sum: impl FnOnce(&[u8]) -> u32) {
        if let Some(at) = self.lead {
            seal_lead(buf, len, sum, at, self);
        } else if self.end.is_empty() {
            seal(buf, len, sum, self.checksum_len, self.checksum_be);
        } else {
            seal_end(buf, len, sum, self);
        }
    }

    /// A refusal of the broadcast address by a command (`message`) that does not accept it,
    /// in a decoded frame addressed to `address` (`FRAME.no_broadcast(frame[0], &Self::DESC)`).
    #[inline(always)]
    pub fn no_broadcast(
        &self,
        address: u8,
        message: &'static MessageDesc,
    ) -> Result<(), DecodeError> {
        match self.broadcast {
            Some(b) if b == address => Err(DecodeError::BroadcastNotAccepted {
                message,
                address: b,
            }),
            _ => Ok(()),
        }
    }

    /// [`Frame::no_broadcast`] for an encoder.
    #[inline(always)]
    pub fn encode_broadcast(
        &self,
        address: u8,
        message: &'static MessageDesc,
    ) -> Result<(), EncodeError> {
        match self.broadcast {
            Some(b) if b == address => Err(EncodeError::BroadcastNotAccepted { message, address }),
            _ => Ok(()),
        }
    }

    /// Whether `frame` ends in the checksum (`checksum` of the bytes before it, at least one)
    /// and the end bytes, and nothing else: `FRAME.checksum_ok(frame, frame_sum)`.
    #[inline(always)]
    pub fn checksum_ok(&self, frame: &[u8], checksum: impl FnOnce(&[u8]) -> u32) -> bool {
        // A checksum before the bytes it covers: a frame at least as long as its end.
        let holds = |at: usize| frame.len() >= at + self.checksum_len;
        match frame.len().checked_sub(self.checksum_len + self.end.len()) {
            Some(n) if n > 0 && self.lead.map_or(true, holds) => {
                check_sum(frame, n, self, checksum)
            }
            _ => false,
        }
    }

    /// Whether a frame may carry `address`: a device's, the broadcast or the host address.
    #[inline(always)]
    pub const fn address_ok(&self, address: u8) -> bool {
        (self.devices.0 <= address && address <= self.devices.1)
            || matches!(self.broadcast, Some(b) if b == address)
            || matches!(self.host, Some(h) if h == address)
    }
}

/// The checksum at the end of `frame` (from `at`) and the one computed over the bytes before
/// it: `(found, expected)`.
#[inline(always)]
fn sums<T>(frame: &[u8], at: usize, f: &Frame, checksum: impl FnOnce(&[u8]) -> T) -> (u32, T) {
    if f.lead.is_some() {
        // Before the bytes it covers: the frame to its end bytes goes to `checksum`, which
        // takes the covered ones from it.
        let found = frame.get(at..at + f.checksum_len).unwrap_or(&[]);
        let body = frame
            .get(..frame.len().saturating_sub(f.end.len()))
            .unwrap_or(frame);
        return (uint(found, !f.checksum_be) as u32, checksum(body));
    }
    let (body, tail) = frame.split_at(at);
    let tail = tail.get(..f.checksum_len).unwrap_or(tail);
    let found = uint(tail, !f.checksum_be) as u32;
    (found, checksum(body))
}

/// Whether `frame` ends in the checksum of its first `at` bytes and the end bytes, and nothing
/// else.
#[inline(always)]
fn check_sum(frame: &[u8], at: usize, f: &Frame, checksum: impl FnOnce(&[u8]) -> u32) -> bool {
    if frame.len() != at + f.checksum_len + f.end.len() {
        return false;
    }
    let (sum_at, end_at) = f.trailer(frame.len());
    if frame.get(end_at..end_at + f.end.len()) != Some(f.end) {
        return false;
    }
    let (found, expected) = sums(frame, sum_at, f, checksum);
    found == expected
}

/// The checks every frame of a direction passes before its code is looked at, in this order:
/// no longer than `max`, the start byte, at least `min` bytes, the end bytes, the checksum
/// (`checksum` of the bytes before it, compared as an unsigned integer), the address (at
/// `address_at`). Returns the address (0 where frames carry none; `address_at` is then not
/// looked at).
#[inline(always)]
pub fn check_frame(
    frame: &[u8],
    min: usize,
    max: usize,
    address_at: usize,
    f: &Frame,
    checksum: impl FnOnce(&[u8]) -> u32,
) -> Result<u8, DecodeError> {
    check_frame_with(frame, min, max, address_at, f, |b| Ok(checksum(b)))
}

/// [`check_frame`] with a checksum that may refuse the frame instead of computing it: a reply
/// whose checksum takes in its request's bytes, decoded without them
/// ([`DecodeError::NeedsRequest`], in the checksum's place in the order).
#[inline(always)]
pub fn check_frame_with(
    frame: &[u8],
    min: usize,
    max: usize,
    address_at: usize,
    f: &Frame,
    checksum: impl FnOnce(&[u8]) -> Result<u32, DecodeError>,
) -> Result<u8, DecodeError> {
    let len = frame.len();
    if len > max {
        return Err(DecodeError::TooLong { max, found: len });
    }
    if let Some((at, expected)) = f.start {
        if let Some(&found) = frame.get(at) {
            if found != expected {
                return Err(DecodeError::BadStart {
                    offset: at,
                    expected,
                    found,
                });
            }
        }
    }
    if len < min || (f.addressed && min <= address_at) || min < f.checksum_len + f.end.len() {
        return Err(DecodeError::Truncated {
            needed: min,
            found: len,
        });
    }
    let (at, end_at) = f.trailer(len);
    if let Some(e) = check_end(frame, end_at, f.end) {
        return Err(e);
    }
    let (found, expected) = sums(frame, at, f, checksum);
    let expected = expected?;
    if found != expected {
        return Err(DecodeError::ChecksumMismatch {
            offset: at,
            expected,
            found,
            width: f.checksum_len as u8,
        });
    }
    if !f.addressed {
        return Ok(0);
    }
    let address = frame[address_at];
    if !f.address_ok(address) {
        return Err(DecodeError::BadAddress {
            offset: address_at,
            found: address,
            min: f.devices.0,
            max: f.devices.1,
        });
    }
    Ok(address)
}

/// The checks every frame of a direction passes before its code is read, with the numbers
/// they take named: each generated module's `CHECKS`, or `REQUEST_CHECKS` and
/// `RESPONSE_CHECKS` where the directions' differ.
#[derive(Debug, Clone, Copy)]
pub struct FrameChecks {
    /// Sync sequences checked first, each at its offset (where one is longer than the start
    /// byte, differs by direction or comes twice): [`check_sync`].
    pub sync: &'static [(usize, &'static [u8])],
    /// What every frame of the direction shares: start byte, addresses, checksum, end bytes.
    pub frame: &'static Frame,
    /// The direction's shortest and longest frame, in bytes.
    pub min: usize,
    pub max: usize,
    /// The address's offset (not looked at where frames carry none).
    pub address_at: usize,
}

impl FrameChecks {
    /// [`check_frame`] with these numbers: the frame's address, or why the frame is refused.
    #[inline(always)]
    pub fn check(
        &self,
        frame: &[u8],
        checksum: impl FnOnce(&[u8]) -> u32,
    ) -> Result<u8, DecodeError> {
        self.check_syncs(frame)?;
        check_frame(
            frame,
            self.min,
            self.max,
            self.address_at,
            self.frame,
            checksum,
        )
    }

    #[inline(always)]
    fn check_syncs(&self, frame: &[u8]) -> Result<(), DecodeError> {
        // One sync sequence (the common case) is checked without a loop over them.
        match self.sync {
            [] => Ok(()),
            &[(at, sync)] => check_sync(frame, self.max, at, sync),
            many => {
                for &(at, sync) in many {
                    check_sync(frame, self.max, at, sync)?;
                }
                Ok(())
            }
        }
    }

    /// [`check_frame_with`] with these numbers: a checksum that may refuse the frame.
    #[inline(always)]
    pub fn check_with(
        &self,
        frame: &[u8],
        checksum: impl FnOnce(&[u8]) -> Result<u32, DecodeError>,
    ) -> Result<u8, DecodeError> {
        self.check_syncs(frame)?;
        check_frame_with(
            frame,
            self.min,
            self.max,
            self.address_at,
            self.frame,
            checksum,
        )
    }

    /// The checks of a frame that travels without a checksum (`checksum: none`), found by its
    /// code and length: every check but the checksum and the shortest frame.
    #[inline(always)]
    pub fn check_unsummed(&self, frame: &[u8]) -> Result<u8, DecodeError> {
        self.check_syncs(frame)?;
        let unsummed = Frame {
            checksum_len: 0,
            ..*self.frame
        };
        check_frame(
            frame,
            frame.len(),
            self.max,
            self.address_at,
            &unsummed,
            |_| 0,
        )
    }
}

/// The code: `n` bytes from `at`, big-endian (as codes are written). The caller has checked
/// that `frame` is long enough.
#[inline(always)]
pub fn code(frame: &[u8], at: usize, n: usize) -> u32 {
    uint(&frame[at..at + n], false) as u32
}

/// The frame as the fixed-size array of `message`, whose code matched, or why not: too short
/// for it, or another length (its `lengths`: every length of a message with this code, `[N]`
/// where it is the only one).
#[inline(always)]
pub fn fixed<'f, const N: usize>(
    frame: &'f [u8],
    message: &'static MessageDesc,
) -> Result<&'f [u8; N], DecodeError> {
    frame.try_into().map_err(|_| wrong_length(frame, message))
}

/// The refusal of a frame whose code is known but whose length is none of `message`'s
/// `lengths` (sorted, the lengths of the messages with its code, `message` the first tried):
/// truncated where every one is longer, as the interpreter reports it.
#[cold]
pub fn wrong_length(frame: &[u8], message: &'static MessageDesc) -> DecodeError {
    match message.lengths.first() {
        Some(&needed) if needed > frame.len() => DecodeError::Truncated {
            needed,
            found: frame.len(),
        },
        _ => DecodeError::WrongLength {
            message,
            found: frame.len(),
            less: 0,
        },
    }
}

/// The refusal of a reply `request` does not get: `message` decoded from the frame, but the
/// spec does not list it among the request's responses.
#[cold]
pub fn not_a_reply(message: &'static str, request: &'static str) -> DecodeError {
    not_a_reply_unasked(message, request, false)
}

/// [`not_a_reply`] where the protocol has responses sent unasked: `unasked` says whether
/// `message` is one (`unasked: true`), worded as such.
#[cold]
pub fn not_a_reply_unasked(
    message: &'static str,
    request: &'static str,
    unasked: bool,
) -> DecodeError {
    DecodeError::NotAReply {
        message,
        request,
        unasked,
    }
}

/// Where the code of a direction's frames sits (each generated module's `REQUEST_CODE` and
/// `RESPONSE_CODE`): from `at`, at most `longest` bytes, before a trailer (checksum and end
/// bytes) of `trailer` bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CodeAt {
    pub at: usize,
    pub longest: usize,
    pub trailer: usize,
    /// The direction is the responses' (an unknown code is [`DecodeError::UnknownResponse`]).
    pub response: bool,
}

impl CodeAt {
    /// The error for a code no message of the direction has: its `longest` bytes from `at`,
    /// or as many as lie before the trailer.
    #[inline]
    pub fn unknown(&self, frame: &[u8]) -> DecodeError {
        let n = frame
            .len()
            .saturating_sub(self.at + self.trailer)
            .min(self.longest);
        let code = frame
            .iter()
            .skip(self.at)
            .take(n)
            .fold(0u32, |a, b| (a << 8) | u32::from(*b));
        let (offset, len) = (self.at, n as u8);
        if self.response {
            DecodeError::UnknownResponse { offset, code, len }
        } else {
            DecodeError::UnknownCommand { offset, code, len }
        }
    }
}

/// The messages sharing one code, tried in spec order: the first that has the frame's length
/// and decodes is the message. Where only the request tells some apart ([`Self::ambiguous`]
/// candidates), a request settles which one the frame is, and decoding without one must find
/// exactly one of them. Each candidate is a no-op once one has settled the frame. Whether a
/// request gets the message is checked after, as the interpreter checks it.
#[derive(Debug)]
pub struct Group<'f, T> {
    frame: &'f [u8],
    code: u32,
    /// The name of the request the frame answers, where one was given.
    request: Option<&'static str>,
    found: Option<T>,
    /// The ambiguous candidates that decoded, without a request: two or more make the frame
    /// ambiguous.
    decoded: crate::MessageNames,
    /// The first ambiguous candidate that decoded but the request does not get.
    refused: Option<&'static str>,
    /// The first error of an ambiguous candidate the request does not get.
    aside: Option<DecodeError>,
    /// The first error of a variable-length candidate whose count does not fit the frame.
    count: Option<DecodeError>,
    /// The first refused candidate's error, in spec order (the interpreter reports the same).
    first: Option<DecodeError>,
    done: Option<DecodeResult<T>>,
}

impl<'f, T> Group<'f, T> {
    #[inline(always)]
    pub fn new(frame: &'f [u8], code: u32, request: Option<&'static str>) -> Self {
        Group {
            frame,
            code,
            request,
            found: None,
            decoded: crate::MessageNames::default(),
            refused: None,
            aside: None,
            count: None,
            first: None,
            done: None,
        }
    }

    /// The candidate's message if it has the frame's length and decodes.
    #[inline(always)]
    fn try_one<const N: usize>(
        &mut self,
        decode: impl FnOnce(&[u8; N]) -> DecodeResult<T>,
    ) -> Option<T> {
        if self.done.is_some() {
            return None;
        }
        let frame: &[u8; N] = self.frame.try_into().ok()?;
        match decode(frame) {
            Ok(m) => Some(m),
            Err(e) => {
                self.first.get_or_insert(e);
                None
            }
        }
    }

    /// Tries one candidate; the first that decodes settles the frame.
    #[inline(always)]
    pub fn attempt<const N: usize>(&mut self, decode: impl FnOnce(&[u8; N]) -> DecodeResult<T>) {
        if let Some(m) = self.try_one(decode) {
            self.done = Some(Ok(m));
        }
    }

    /// [`Self::attempt`] for a message of variable length whose repeated field `repeat` is:
    /// the frame is split into its fixed part, the elements' bytes and their number, which
    /// `decode` takes. A frame whose count does not fit is not one of its lengths: its error
    /// is said only where no candidate has the frame's length (as the interpreter says it).
    #[inline(always)]
    pub fn attempt_split<const AT: usize>(
        &mut self,
        repeat: &RepeatAt,
        decode: impl FnOnce(&'f [u8; AT], &'f [u8], usize) -> DecodeResult<T>,
    ) {
        if let Some(m) = self.try_split(repeat, decode) {
            self.done = Some(Ok(m));
        }
    }

    /// [`Self::ambiguous`] for a message of variable length, as [`Self::attempt_split`].
    #[inline(always)]
    pub fn ambiguous_split<const AT: usize>(
        &mut self,
        admitted: bool,
        message: &'static MessageDesc,
        repeat: &RepeatAt,
        decode: impl FnOnce(&'f [u8; AT], &'f [u8], usize) -> DecodeResult<T>,
    ) {
        if self.set_aside(admitted) {
            if let Some((frame, elements, n)) = self.split(repeat) {
                let r = decode(frame, elements, n);
                self.aside(r.map(|_| ()), message);
            }
        } else if let Some(m) = self.try_split(repeat, decode) {
            self.settle_ambiguous(m, message);
        }
    }

    /// The frame split by `repeat` ([`RepeatAt::split`]); `None` where it is shorter than the
    /// message's shortest frame, or its count does not fit (kept as the count's error).
    #[inline(always)]
    fn split<const AT: usize>(
        &mut self,
        repeat: &RepeatAt,
    ) -> Option<(&'f [u8; AT], &'f [u8], usize)> {
        if self.done.is_some() || self.frame.len() < repeat.base {
            return None;
        }
        repeat
            .split::<AT>(self.frame)
            .map_err(|e| {
                self.count.get_or_insert(e);
            })
            .ok()
    }

    /// [`Self::attempt`] for a message with several lists or fields after one ([`Lists`]):
    /// `decode` takes the frame taken apart ([`Lists::split`]).
    #[inline(always)]
    pub fn attempt_lists<const BASE: usize, const K: usize>(
        &mut self,
        lists: &Lists,
        decode: impl FnOnce(&Split<'f, BASE, K>) -> DecodeResult<T>,
    ) {
        if let Some(m) = self.try_lists(lists, decode) {
            self.done = Some(Ok(m));
        }
    }

    /// [`Self::ambiguous`] for a message with [`Lists`], as [`Self::attempt_lists`].
    #[inline(always)]
    pub fn ambiguous_lists<const BASE: usize, const K: usize>(
        &mut self,
        admitted: bool,
        message: &'static MessageDesc,
        lists: &Lists,
        decode: impl FnOnce(&Split<'f, BASE, K>) -> DecodeResult<T>,
    ) {
        if self.set_aside(admitted) {
            if let Some(s) = self.split_lists::<BASE, K>(lists) {
                let r = decode(&s);
                self.aside(r.map(|_| ()), message);
            }
        } else if let Some(m) = self.try_lists(lists, decode) {
            self.settle_ambiguous(m, message);
        }
    }

    /// The frame taken apart by `lists`; `None` where it is shorter than the message's
    /// shortest frame, or a count does not fit (kept as the count's error).
    #[inline(always)]
    fn split_lists<const BASE: usize, const K: usize>(
        &mut self,
        lists: &Lists,
    ) -> Option<Split<'f, BASE, K>> {
        if self.done.is_some() || self.frame.len() < lists.base {
            return None;
        }
        lists
            .split::<BASE, K>(self.frame)
            .map_err(|e| {
                self.count.get_or_insert(e);
            })
            .ok()
    }

    /// [`Self::try_one`] for a message with [`Lists`].
    #[inline(always)]
    fn try_lists<const BASE: usize, const K: usize>(
        &mut self,
        lists: &Lists,
        decode: impl FnOnce(&Split<'f, BASE, K>) -> DecodeResult<T>,
    ) -> Option<T> {
        let s = self.split_lists::<BASE, K>(lists)?;
        decode(&s)
            .map_err(|e| {
                self.first.get_or_insert(e);
            })
            .ok()
    }

    /// [`Self::try_one`] for a message of variable length.
    #[inline(always)]
    fn try_split<const AT: usize>(
        &mut self,
        repeat: &RepeatAt,
        decode: impl FnOnce(&'f [u8; AT], &'f [u8], usize) -> DecodeResult<T>,
    ) -> Option<T> {
        let (frame, elements, n) = self.split(repeat)?;
        decode(frame, elements, n)
            .map_err(|e| {
                self.first.get_or_insert(e);
            })
            .ok()
    }

    /// Whether a candidate only the request tells apart is set aside: the request does not
    /// get it. It is still decoded, to say so where nothing else fits.
    #[inline(always)]
    fn set_aside(&self, admitted: bool) -> bool {
        self.request.is_some() && !admitted && self.done.is_none()
    }

    /// A set-aside candidate `message` decoded to `r`.
    #[inline(always)]
    fn aside(&mut self, r: DecodeResult<()>, message: &'static MessageDesc) {
        match r {
            Ok(()) => {
                self.refused.get_or_insert(message.name);
            }
            Err(e) => {
                self.aside.get_or_insert(e);
            }
        }
    }

    /// Tries a candidate `message` that shares code and length with another only the request
    /// tells apart (`admitted`: the request gets it).
    #[inline(always)]
    pub fn ambiguous<const N: usize>(
        &mut self,
        admitted: bool,
        message: &'static MessageDesc,
        decode: impl FnOnce(&[u8; N]) -> DecodeResult<T>,
    ) {
        if self.set_aside(admitted) {
            if let Ok(frame) = <&[u8; N]>::try_from(self.frame) {
                let r = decode(frame);
                self.aside(r.map(|_| ()), message);
            }
            return;
        }
        let Some(m) = self.try_one(decode) else {
            return;
        };
        self.settle_ambiguous(m, message);
    }

    /// An ambiguous candidate's message that decoded (one the request gets, where there is a
    /// request): a request settles the frame; without one it is kept and named, and the others
    /// are still tried, so that an ambiguous frame names every message it decodes as.
    #[inline(always)]
    fn settle_ambiguous(&mut self, m: T, message: &'static MessageDesc) {
        if self.request.is_some() {
            self.done = Some(Ok(m));
            return;
        }
        self.decoded.push(message);
        if self.found.is_none() {
            self.found = Some(m);
        }
    }

    /// What the group decodes to: the candidate that settled it, else the one ambiguous
    /// candidate that decoded, the first refused candidate's error, a set-aside candidate that
    /// decoded (not the request's reply), a set-aside candidate's error, a count that does not
    /// fit, or a wrong length ([`wrong_length`]: `message`, the first
    /// candidate, its `lengths` every candidate's, sorted).
    #[inline(always)]
    pub fn end(self, message: &'static MessageDesc) -> DecodeResult<T> {
        if self.decoded.messages().len() > 1 {
            return Err(DecodeError::Ambiguous {
                code: self.code,
                candidates: self.decoded,
            });
        }
        if let Some(r) = self.done {
            return r;
        }
        if let Some(m) = self.found {
            return Ok(m);
        }
        Err(match (self.first, self.refused, self.request, self.aside) {
            (Some(e), ..) => e,
            (None, Some(refused), Some(request), _) => not_a_reply(refused, request),
            (None, _, _, Some(e)) => e,
            _ => match self.count {
                Some(e) => e,
                None => wrong_length(self.frame, message),
            },
        })
    }
}

/// The bytes a message fixes at its start, as the stream decoder tells its variable-length
/// messages apart: its code at `code_at`, and the constants that lead its payload at `lead_at`
/// (what tells code-less messages apart).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fixed {
    pub code_at: usize,
    pub code: &'static [u8],
    pub lead_at: usize,
    pub lead: &'static [u8],
}

impl Fixed {
    /// Whether `head` agrees with every byte fixed: `None` while some are not buffered yet.
    #[inline(always)]
    pub fn agrees(&self, head: &[u8]) -> Option<bool> {
        match (
            code_agrees(head, self.code_at, self.code),
            code_agrees(head, self.lead_at, self.lead),
        ) {
            (Some(false), _) | (_, Some(false)) => Some(false),
            (Some(true), Some(true)) => Some(true),
            _ => None,
        }
    }
}

/// Whether the code bytes `code` at `at` agree with `head` (the bytes buffered from a possible
/// frame start): `None` while some are not buffered yet.
#[inline]
pub fn code_agrees(head: &[u8], at: usize, code: &[u8]) -> Option<bool> {
    let mut all = true;
    for (i, &c) in code.iter().enumerate() {
        match head.get(at + i) {
            Some(&b) if b != c => return Some(false),
            Some(_) => {}
            None => all = false,
        }
    }
    all.then_some(true)
}

/// The variable-length candidate of one direction of a protocol whose length field gives
/// every frame's length: the length `field` gives, within the shortest and longest frame of
/// the variable-length messages (`(code offset, code, shortest, longest)`) whose code agrees
/// with `head` or is not buffered yet; none if no such message agrees.
#[inline(always)]
pub fn var_by_length(head: &[u8], shapes: &[(Fixed, usize, usize)], field: LengthField) -> VarLen {
    let (mut min, mut max) = (usize::MAX, 0);
    for &(fixed, lo, hi) in shapes {
        if fixed.agrees(head) != Some(false) {
            min = min.min(lo);
            max = max.max(hi);
        }
    }
    if min > max {
        return VarLen::NONE;
    }
    VarLen::of(LengthField { min, max, ..field }.frame_len(head))
}

/// The variable-length candidate of one direction whose variable-length messages are counted
/// by a field (`(the bytes it fixes, how its count gives its length)`, the latter
/// [`RepeatAt::count_len`] in a `const`): the length the count field of the first whose fixed
/// bytes agree with `head` gives; [`VarLen::NEED_MORE`] while some are not buffered yet.
#[inline(always)]
pub fn var_by_count(head: &[u8], shapes: &[(Fixed, CountLen)]) -> VarLen {
    // Written out rather than through `first_agreeing`: its closure was not inlined, so
    // every head paid a call and a count read generic over the repeat (Modbus: 62
    // instructions where a count field agreed); inlined, each shape's constants fold.
    let mut wait = false;
    for (fixed, r) in shapes {
        match fixed.agrees(head) {
            Some(true) => return VarLen::of(r.frame_len(head)),
            Some(false) => {}
            None => wait = true,
        }
    }
    if wait {
        VarLen::NEED_MORE
    } else {
        VarLen::NONE
    }
}

/// How a variable-length message counted by fields gives its frame's length: one repeated
/// field, or [`Lists`].
#[derive(Debug, Clone, Copy)]
pub enum Counted {
    One(RepeatAt),
    Many(Lists),
}

/// [`var_by_count`] for a direction with messages counted by several fields ([`Counted`]).
#[inline(always)]
pub fn var_by_counts(head: &[u8], shapes: &[(Fixed, Counted)]) -> VarLen {
    first_agreeing(head, shapes, |c| match c {
        Counted::One(r) => r.frame_len(head),
        Counted::Many(l) => l.frame_len(head),
    })
}

/// The length `len` gives for the first shape whose fixed bytes agree with `head`;
/// [`VarLen::NEED_MORE`] while some are not buffered yet.
#[inline(always)]
fn first_agreeing<S>(
    head: &[u8],
    shapes: &[(Fixed, S)],
    len: impl Fn(&S) -> Option<usize>,
) -> VarLen {
    let mut wait = false;
    for (fixed, s) in shapes {
        match fixed.agrees(head) {
            Some(true) => return VarLen::of(len(s)),
            Some(false) => {}
            None => wait = true,
        }
    }
    if wait {
        VarLen::NEED_MORE
    } else {
        VarLen::NONE
    }
}

/// What a generated message checks of one field, as a named constant beside its
/// [`FieldDesc`] (`request::ReadCoils::QUANTITY_CHECK`): the field a refusal names, where it
/// sits, the values its spec admits, and the relation it follows. Built in a `const`
/// (`rt::check(&Self::QUANTITY_DESC, 4).range(1, 2000)`), handed to [`in_range`],
/// [`encode_in_range`] and [`following`], whose `#[inline(always)]` bodies read it as the
/// constants it holds: the check compiles to immediates, and only `field` is left in the
/// error a refusal returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldCheck {
    /// The field (or sub-field) refusals name.
    pub field: &'static FieldDesc,
    /// Its offset in the frame, as refusals give it: a whole field's first byte (a sub-field's
    /// field's), in a frame whose lists are empty and whose optional fields are all present;
    /// [`FieldCheck::at`] where a frame's lists or optional fields move it.
    pub at: usize,
    /// The spec range its raw values lie in (`range:`); its wire type's limits where it has
    /// none.
    pub range: Bounds,
    /// The `special:` values admitted outside `range`.
    pub special: &'static [i64],
    /// `follows:`: the field must be `ceil(base × multiply / divide)`, `base` the field it
    /// follows.
    pub multiply: u64,
    pub divide: u64,
    /// The relation as refusals word it (`"ceil(quantity / 8)"`).
    pub rule: &'static str,
}

/// A spec range's bounds as the spec writes them: integers (a `u64`'s as its bits,
/// [`u64_raw`]) or floats, compared as raw values ([`Wire::within`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bounds {
    Int(i64, i64),
    F32(f32, f32),
    F64(f64, f64),
}

impl Bounds {
    /// The bounds as raw values, as refusals give them.
    #[inline(always)]
    pub fn raw(self) -> (i64, i64) {
        match self {
            Bounds::Int(min, max) => (min, max),
            Bounds::F32(min, max) => (f32_raw(min), f32_raw(max)),
            Bounds::F64(min, max) => (f64_raw(min), f64_raw(max)),
        }
    }
}

/// A [`FieldCheck`] of `field` at offset `at` that admits any value, for the builder methods
/// to fill in.
pub const fn check(field: &'static FieldDesc, at: usize) -> FieldCheck {
    FieldCheck {
        field,
        at,
        range: Bounds::Int(i64::MIN, i64::MAX),
        special: &[],
        multiply: 1,
        divide: 1,
        rule: "",
    }
}

impl FieldCheck {
    /// The field at offset `at`: where a frame's lists or optional fields move it
    /// (`&Self::FLAGS_CHECK.at(4 + s.shift(1))`).
    #[inline(always)]
    pub const fn at(self, at: usize) -> Self {
        FieldCheck { at, ..self }
    }

    /// Its spec range `min..=max` (raw values).
    pub const fn range(self, min: i64, max: i64) -> Self {
        FieldCheck {
            range: Bounds::Int(min, max),
            ..self
        }
    }

    /// Its spec range, of an `f32` field.
    pub const fn range_f32(self, min: f32, max: f32) -> Self {
        FieldCheck {
            range: Bounds::F32(min, max),
            ..self
        }
    }

    /// Its spec range, of an `f64` field.
    pub const fn range_f64(self, min: f64, max: f64) -> Self {
        FieldCheck {
            range: Bounds::F64(min, max),
            ..self
        }
    }

    /// The `special` values it admits outside its range.
    pub const fn or(self, special: &'static [i64]) -> Self {
        FieldCheck { special, ..self }
    }

    /// The field must be `ceil(base × multiply / divide)` of the field it follows, the
    /// relation `rule` words.
    pub const fn follows(self, multiply: u64, divide: u64, rule: &'static str) -> Self {
        FieldCheck {
            multiply,
            divide,
            rule,
            ..self
        }
    }
}

/// A decoded field checked against its spec range and special values (`check`).
#[inline(always)]
pub fn in_range<T: Wire>(check: &FieldCheck, raw: T) -> Result<(), DecodeError> {
    let raw = raw.to_i64();
    let (min, max) = check.range.raw();
    if T::within(raw, min, max) || is_special(raw, check.special) {
        return Ok(());
    }
    Err(DecodeError::OutOfRange {
        field: check.field,
        offset: check.at,
        found: raw,
        min,
        max,
        kind: T::KIND,
    })
}

/// Whether `raw` is one of the `special` values. One or two (the common case) are compared
/// as such: `contains` stayed a loop over the table at `opt-level = "s"`.
#[inline(always)]
fn is_special(raw: i64, special: &[i64]) -> bool {
    match *special {
        [] => false,
        [a] => raw == a,
        [a, b] => raw == a || raw == b,
        ref more => more.contains(&raw),
    }
}

/// A decoded constant field (or constant bits of one, `found` already shifted down) that must
/// be `expected`.
#[inline(always)]
pub fn equal<T: Wire>(
    field: &'static FieldDesc,
    offset: usize,
    found: T,
    expected: u64,
) -> Result<(), DecodeError> {
    let found = found.to_u64();
    if found != expected {
        return Err(DecodeError::InvalidValue {
            field,
            offset,
            expected,
            found,
        });
    }
    Ok(())
}

/// A decoded field that must repeat field `other` of its frame (`equals`).
#[inline(always)]
pub fn same<T: Wire + PartialEq>(
    field: &'static FieldDesc,
    offset: usize,
    found: T,
    other: &'static str,
    repeated: T,
) -> Result<(), DecodeError> {
    if found != repeated {
        return Err(DecodeError::NotEqual {
            field,
            offset,
            other,
            expected: repeated.to_i64(),
            found: found.to_i64(),
        });
    }
    Ok(())
}

/// The address an encoder may write: a device's, the broadcast or the host address; 0 alone
/// where frames carry none.
#[inline(always)]
pub fn encode_address(address: u8, f: &Frame) -> Result<(), EncodeError> {
    if !f.addressed && address != 0 {
        return Err(EncodeError::Unaddressed { address });
    }
    if f.address_ok(address) {
        return Ok(());
    }
    Err(EncodeError::BadAddress {
        address,
        min: f.devices.0,
        max: f.devices.1,
    })
}

/// A value to encode checked against its field's spec range and special values (`check`, the
/// decoder's).
#[inline(always)]
pub fn encode_in_range<T: Wire>(check: &FieldCheck, raw: T) -> Result<(), EncodeError> {
    let raw = raw.to_i64();
    let (min, max) = check.range.raw();
    if T::within(raw, min, max) || is_special(raw, check.special) {
        return Ok(());
    }
    Err(EncodeError::NotInRange {
        field: check.field.name,
        value: raw,
        min,
        max,
        kind: T::KIND,
    })
}

/// A typed value that may hold more than its field's wire type, checked to fit it.
#[inline(always)]
pub fn fits<T: Wire>(field: &'static str, raw: T, min: i64, max: i64) -> Result<i64, EncodeError> {
    let raw = raw.to_i64();
    if (min..=max).contains(&raw) {
        return Ok(raw);
    }
    Err(EncodeError::OutOfRange { field })
}

/// Writes a constant whole frame (`frame:` in the spec, M-Bus's `E5`) into `buf`: its length,
/// or [`EncodeError::BufferTooSmall`].
#[inline]
pub fn put_frame(buf: &mut [u8], frame: &[u8]) -> Result<usize, EncodeError> {
    let available = buf.len();
    let out = buf
        .get_mut(..frame.len())
        .ok_or(EncodeError::BufferTooSmall {
            needed: frame.len(),
            available,
        })?;
    out.copy_from_slice(frame);
    Ok(frame.len())
}

/// The first `N` bytes of `buf`, for a frame of `N` bytes, with `head` (the bytes known before
/// any field: start, address, code, constants) written at its start.
#[inline(always)]
pub fn frame_mut<'b, const N: usize>(
    buf: &'b mut [u8],
    head: &[u8],
) -> Result<&'b mut [u8; N], EncodeError> {
    let available = buf.len();
    let out: &mut [u8; N] =
        buf.get_mut(..N)
            .and_then(|s| s.try_into().ok())
            .ok_or(EncodeError::BufferTooSmall {
                needed: N,
                available,
            })?;
    out[..head.len()].copy_from_slice(head);
    Ok(out)
}

/// `out`, a frame [`frame_mut`] took before the encoder's match, with `head` written at its
/// start.
#[inline(always)]
pub fn head<'b, const N: usize>(out: &'b mut [u8; N], head: &[u8]) -> &'b mut [u8; N] {
    out[..head.len()].copy_from_slice(head);
    out
}

/// The first `len` bytes of `buf`, for a frame of variable length, with `head` written at its
/// start (as [`frame_mut`]).
#[inline(always)]
pub fn frame_mut_len<'b>(
    buf: &'b mut [u8],
    len: usize,
    head: &[u8],
) -> Result<&'b mut [u8], EncodeError> {
    let available = buf.len();
    let out = buf.get_mut(..len).ok_or(EncodeError::BufferTooSmall {
        needed: len,
        available,
    })?;
    out[..head.len()].copy_from_slice(head);
    Ok(out)
}

/// [`seal_sum8`] for a frame of variable length.
#[inline(always)]
pub fn seal_sum8_len(out: &mut [u8]) -> usize {
    let n = out.len();
    if let Some((last, body)) = out.split_last_mut() {
        *last = crate::sum8_bytes(body);
    }
    n
}

/// Writes a sum-8 into the last byte of `out`, over every byte before it; returns the frame
/// length. Inlined into each message's encoder, where it folds the constant header bytes.
#[inline(always)]
pub fn seal_sum8<const N: usize>(out: &mut [u8; N]) -> usize {
    let sum = crate::sum8_bytes(&out[..N - 1]);
    out[N - 1] = sum;
    N
}

/// [`seal_sum8`] where the generator knows the sum of the first `from` bytes (`head`: its
/// constants added to the address): only the bytes after them are summed here, none for a
/// frame without fields.
#[inline(always)]
pub fn seal_sum8_head<const N: usize>(out: &mut [u8; N], from: usize, head: u8) -> usize {
    // A field of one or two bytes is added as such rather than by a loop (`opt-level = "s"`).
    let rest = match out[from..N - 1] {
        [] => 0,
        [a] => a,
        [a, b] => a.wrapping_add(b),
        ref rest => crate::sum8_bytes(rest),
    };
    let sum = head.wrapping_add(rest);
    out[N - 1] = sum;
    N
}

/// The first byte of the frame's `end.len()` bytes from `from` that is not `end`'s, as an
/// error.
#[inline(always)]
fn check_end(frame: &[u8], from: usize, end: &[u8]) -> Option<DecodeError> {
    let (i, (&found, &expected)) = frame
        .get(from..)?
        .iter()
        .zip(end)
        .enumerate()
        .find(|(_, (a, b))| a != b)?;
    Some(DecodeError::BadEnd {
        offset: from + i,
        expected,
        found,
    })
}

/// The bytes of `frame` its checksum covers, from `from` up to the checksum (as `f` places
/// it): what the checksum of a reply that takes in its request's bytes runs over first.
/// Empty for a frame too short to hold its checksum and end bytes.
#[inline]
pub fn span<'f>(frame: &'f [u8], from: usize, f: &Frame) -> &'f [u8] {
    if frame.len() < f.checksum_len + f.end.len() {
        return &[];
    }
    let (at, end_at) = f.trailer(frame.len());
    // A checksum before the bytes it covers covers them to the frame's end bytes.
    let to = if f.lead.is_some() { end_at } else { at };
    frame.get(from..to).unwrap_or(&[])
}

/// Writes the checksum that sits at `at`, before the bytes it covers (`sum` of the frame up to
/// its end bytes, from which it takes them), and the end bytes, of the `len`-byte frame in
/// `buf`.
#[inline(always)]
fn seal_lead(buf: &mut [u8], len: usize, sum: impl FnOnce(&[u8]) -> u32, at: usize, f: &Frame) {
    let end_at = len - f.end.len();
    buf[end_at..len].copy_from_slice(f.end);
    let s = sum(&buf[..end_at]);
    let n = f.checksum_len;
    if f.checksum_be {
        buf[at..at + n].copy_from_slice(&s.to_be_bytes()[4 - n..]);
    } else {
        buf[at..at + n].copy_from_slice(&s.to_le_bytes()[..n]);
    }
}

/// [`seal`] for a protocol whose frames have end bytes: the end bytes and the checksum of the
/// `len`-byte frame in `buf`, in the order `f` has them (the checksum covers end bytes before
/// it).
#[inline(always)]
pub fn seal_end(buf: &mut [u8], len: usize, sum: impl FnOnce(&[u8]) -> u32, f: &Frame) {
    let (at, end_at) = f.trailer(len);
    buf[end_at..end_at + f.end.len()].copy_from_slice(f.end);
    seal(buf, at + f.checksum_len, sum, f.checksum_len, f.checksum_be);
}

/// Writes the `checksum` of the first `len - n` bytes of `buf` into its last `n` bytes.
#[inline(always)]
pub fn seal(buf: &mut [u8], len: usize, sum: impl FnOnce(&[u8]) -> u32, n: usize, be: bool) {
    let at = len - n;
    let s = sum(&buf[..at]);
    // Copied rather than shifted a byte at a time, which stayed a loop at `opt-level = "s"`.
    if be {
        buf[at..len].copy_from_slice(&s.to_be_bytes()[4 - n..]);
    } else {
        buf[at..len].copy_from_slice(&s.to_le_bytes()[..n]);
    }
}

/// 8-bit XOR of `bytes` (the `xor8` checksum).
#[inline]
pub fn xor8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, b| s ^ *b)
}

/// The 16-bit sum of `bytes`, modulo 65536 (`sum16`).
#[inline]
pub fn sum16(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0u16, |s, b| s.wrapping_add(u16::from(*b)))
}

/// Two 8-bit running sums modulo 256, `b << 8 | a` (`fletcher8`: u-blox UBX's checksum, sent
/// low byte first: `a`, then `b`).
#[inline]
pub fn fletcher8(bytes: &[u8]) -> u16 {
    let (a, b) = bytes.iter().fold((0u8, 0u8), |(a, b), x| {
        let a = a.wrapping_add(*x);
        (a, b.wrapping_add(a))
    });
    u16::from(b) << 8 | u16::from(a)
}

/// Fletcher-16: two running sums modulo 255, `b << 8 | a` (`fletcher16`).
#[inline]
pub fn fletcher16(bytes: &[u8]) -> u16 {
    let (a, b) = bytes.iter().fold((0u16, 0u16), |(a, b), x| {
        let a = (a + u16::from(*x)) % 255;
        (a, (b + a) % 255)
    });
    b << 8 | a
}

/// The 8-bit sum of `bytes` inverted (`sum8_ones_complement`: Dynamixel's checksum).
#[inline]
pub fn sum8_ones(bytes: &[u8]) -> u8 {
    !sum8(bytes)
}

/// The 8-bit sum of `bytes` negated (`sum8_twos_complement`).
#[inline]
pub fn sum8_twos(bytes: &[u8]) -> u8 {
    sum8(bytes).wrapping_neg()
}

/// The 8-bit sum of `bytes` with each carry out of bit 7 added back in (end-around carry),
/// inverted: `0xFF` less it (`sum8_end_around`: FrSky's S.Port and F.Port checksum).
#[inline]
pub fn sum8_end_around(bytes: &[u8]) -> u8 {
    let s = bytes.iter().fold(0u16, |s, b| {
        let s = s + u16::from(*b);
        (s & 0xFF) + (s >> 8)
    });
    0xFF - s as u8
}

/// The bytes of `frame` (the frame before its checksum) that a checksum covering from offset
/// `from` on covers: none when the frame is that short.
#[inline]
pub fn covered(frame: &[u8], from: usize) -> &[u8] {
    frame.get(from..).unwrap_or(&[])
}

/// Checks every byte of a multi-byte sync sequence `sync` at `at` that `frame` holds (the first
/// is also [`Frame::start`]'s): the error names the first that differs.
#[inline]
pub fn check_sync(frame: &[u8], max: usize, at: usize, sync: &[u8]) -> Result<(), DecodeError> {
    // A frame too long for the protocol is refused for its length before its bytes are read,
    // as `check_frame` and the interpreter refuse it.
    if frame.len() > max {
        return Err(DecodeError::TooLong {
            max,
            found: frame.len(),
        });
    }
    for (i, &expected) in sync.iter().enumerate() {
        if let Some(&found) = frame.get(at + i) {
            if found != expected {
                return Err(DecodeError::BadStart {
                    offset: at + i,
                    expected,
                    found,
                });
            }
        }
    }
    Ok(())
}

/// A BCD field's value (`encoding: bcd`) from its bytes as read, `raw` (each 4 bits a digit,
/// the high ones the more significant): refused where a digit is above 9.
#[inline]
pub fn bcd(field: &'static FieldDesc, offset: usize, raw: u64) -> Result<u64, DecodeError> {
    let mut v = 0u64;
    let mut i = 16;
    while i > 0 {
        i -= 1;
        let d = (raw >> (4 * i)) & 0xF;
        if d > 9 {
            return Err(DecodeError::NotBcd {
                field,
                offset,
                found: raw,
            });
        }
        v = v * 10 + d;
    }
    Ok(v)
}

/// `v` (at most 16 decimal digits) as binary-coded decimal: [`bcd`]'s inverse.
#[inline]
pub fn to_bcd(mut v: u64) -> u64 {
    let mut out = 0u64;
    let mut i = 0;
    while i < 16 {
        out |= (v % 10) << (4 * i);
        v /= 10;
        i += 1;
    }
    out
}

/// A 24-bit unsigned integer from its three wire bytes (`le`: least significant first).
#[inline(always)]
pub fn u24(b: [u8; 3], le: bool) -> u32 {
    if le {
        u32::from_le_bytes([b[0], b[1], b[2], 0])
    } else {
        u32::from_be_bytes([0, b[0], b[1], b[2]])
    }
}

/// A 24-bit signed integer from its three wire bytes, sign-extended.
#[inline(always)]
pub fn i24(b: [u8; 3], le: bool) -> i32 {
    ((u24(b, le) << 8) as i32) >> 8
}

/// The three wire bytes of a 24-bit integer held in the low bits of `v` (two's complement for a
/// negative one; the caller has checked its range).
#[inline(always)]
pub fn bytes24(v: u32, le: bool) -> [u8; 3] {
    let b = v.to_le_bytes();
    if le {
        [b[0], b[1], b[2]]
    } else {
        [b[2], b[1], b[0]]
    }
}

/// `ceil(base × multiply / divide)`: the value of a field that follows another (`follows`),
/// saturating at the ends of `i64`.
#[inline(always)]
pub fn follows(base: i64, multiply: u64, divide: u64) -> i64 {
    let n = base as i128 * multiply as i128;
    let d = divide.max(1) as i128;
    let q = if n >= 0 { (n + d - 1) / d } else { n / d };
    q.clamp(i64::MIN as i128, i64::MAX as i128) as i64
}

/// A decoded field that follows another (of its frame, or of the request a reply answers): it
/// must be `ceil(base × multiply / divide)`, the relation `check` gives.
#[inline(always)]
pub fn following<T: Wire>(check: &FieldCheck, found: T, base: i64) -> Result<(), DecodeError> {
    let expected = follows(base, check.multiply, check.divide);
    if found.to_i64() != expected {
        return Err(DecodeError::NotFollowing {
            field: check.field,
            offset: check.at,
            rule: check.rule,
            expected,
            found: found.to_i64(),
        });
    }
    Ok(())
}

/// The integer the bytes of a record's last field hold where another field gives their number
/// (1 to 4; `signed`: sign-extended from their width).
#[inline]
pub fn sized_int(bytes: &[u8], le: bool, signed: bool) -> i64 {
    let v = uint(bytes, le);
    let bits = 8 * bytes.len() as u32;
    if signed && (1..64).contains(&bits) && v >> (bits - 1) & 1 == 1 {
        (v as i64) - (1i64 << bits)
    } else {
        v as i64
    }
}

/// Writes `v` into all of `out` (`le`: least significant byte first), a record's last field
/// as many bytes wide as another field says: [`EncodeError::OutOfRange`] where it does not fit
/// them (`signed`: as a signed integer of that width).
#[inline]
pub fn write_sized(
    field: &'static str,
    v: i64,
    signed: bool,
    le: bool,
    out: &mut [u8],
) -> Result<(), EncodeError> {
    let bits = 8 * out.len() as u32;
    let (lo, hi) = if signed {
        (-(1i64 << (bits - 1)), (1i64 << (bits - 1)) - 1)
    } else {
        (0, (1i64 << bits) - 1)
    };
    if bits == 0 || bits > 32 || v < lo || v > hi {
        return Err(EncodeError::OutOfRange { field });
    }
    let n = out.len();
    for (i, b) in out.iter_mut().enumerate() {
        let k = if le { i } else { n - 1 - i };
        *b = (v >> (8 * k)) as u8;
    }
    Ok(())
}

/// The unsigned integer `bytes` hold (`le`: least significant byte first): a code, checksum,
/// length, count or element field of up to 8 bytes. The common widths (1, 2 and 4 bytes) are
/// written out, so a constant width compiles to one load: at `opt-level = "s"` a fold alone
/// stayed a loop in every decoder.
#[inline(always)]
pub fn uint(bytes: &[u8], le: bool) -> u64 {
    let fold = |a: u64, b: &u8| (a << 8) | u64::from(*b);
    match *bytes {
        [a] => u64::from(a),
        [a, b] if le => u64::from(u16::from_le_bytes([a, b])),
        [a, b] => u64::from(u16::from_be_bytes([a, b])),
        [a, b, c, d] if le => u64::from(u32::from_le_bytes([a, b, c, d])),
        [a, b, c, d] => u64::from(u32::from_be_bytes([a, b, c, d])),
        _ if le => bytes.iter().rev().fold(0, fold),
        _ => bytes.iter().fold(0, fold),
    }
}

/// The integer `bytes` hold, as [`uint`] reads it, sign-extended from its width where `signed`
/// (a list element's raw value, as `FieldValue` carries it).
#[inline(always)]
pub fn int(bytes: &[u8], le: bool, signed: bool) -> i64 {
    let u = uint(bytes, le);
    let bits = 8 * bytes.len() as u32;
    if signed && bits < 64 {
        ((u << (64 - bits)) as i64) >> (64 - bits)
    } else {
        u as i64
    }
}

/// A frame's length field (`framing.length`) as decode checks it and encode writes it
/// ([`crate::stream::LengthField`] is how the stream decoder reads it): `width` bytes at `at` (`le`: least significant
/// byte first) holding `frame.len() + k` where it counts the payload (`grows`), else `k`. Each
/// generated module names its own (`LENGTH`, or one for each direction where they differ;
/// `…_AGAIN` where the layout repeats the field).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameLength {
    pub at: usize,
    pub width: usize,
    pub le: bool,
    pub grows: bool,
    pub k: i64,
}

impl FrameLength {
    /// The value the field holds in a frame of `len` bytes.
    #[inline(always)]
    const fn value(&self, len: usize) -> i64 {
        if self.grows {
            len as i64 + self.k
        } else {
            self.k
        }
    }

    /// Checks the field of `frame`: a frame whose field disagrees with its length is refused
    /// with the field's offset and value.
    #[inline]
    pub fn check(&self, frame: &[u8]) -> Result<(), DecodeError> {
        let bytes = frame.get(self.at..self.at + self.width).unwrap_or(&[]);
        let found = uint(bytes, self.le) as i64;
        let expected = self.value(frame.len());
        if found != expected {
            return Err(DecodeError::LengthMismatch {
                offset: self.at,
                expected,
                found,
            });
        }
        Ok(())
    }

    /// Writes the field of `out`, a whole frame; the inverse of [`Self::check`]. A length the
    /// field cannot hold is [`EncodeError::OutOfRange`] of `length`.
    #[inline]
    pub fn put(&self, out: &mut [u8]) -> Result<(), EncodeError> {
        let v = self.value(out.len());
        let fits = u32::try_from(self.width)
            .ok()
            .and_then(|w| 1i64.checked_shl(8 * w))
            .map_or(true, |limit| v < limit);
        let slot = out.get_mut(self.at..self.at + self.width);
        let (Some(slot), true, true) = (slot, v >= 0, fits) else {
            return Err(EncodeError::OutOfRange { field: "length" });
        };
        let n = slot.len();
        for (i, b) in slot.iter_mut().enumerate() {
            let shift = if self.le { 8 * i } else { 8 * (n - 1 - i) };
            *b = (v >> shift) as u8;
        }
        Ok(())
    }
}

#[cfg(test)]
mod lang_tests {
    use super::*;

    #[test]
    fn sums_of_the_newer_checksums() {
        // Dynamixel PING of ID 1: FF FF 01 02 01, checksum over 01 02 01 is !4 = 0xFB.
        assert_eq!(sum8_ones(&[0x01, 0x02, 0x01]), 0xFB);
        assert_eq!(sum8_twos(&[0x01, 0x02, 0x01]), 0xFC);
        // FrSky's: no carry, the plain sum inverted; FF + 01 carries (0x00 + 1, inverted FE,
        // where the plain sum's is FF); "123456789" gives 0x21 (the plain sum's 0x22).
        assert_eq!(sum8_end_around(&[]), 0xFF);
        assert_eq!(sum8_end_around(&[0x08, 0x01]), 0xF6);
        assert_eq!(sum8_end_around(&[0xFF, 0x01]), 0xFE);
        assert_eq!(sum8_end_around(&[0xFF, 0xFF, 0xFF]), 0x00);
        assert_eq!(sum8_end_around(b"123456789"), 0x21);
        assert_eq!(sum8_ones(b"123456789"), 0x22);
        assert_eq!(xor8(&[0x0F, 0xF0, 0x01]), 0xFE);
        assert_eq!(covered(&[1, 2, 3], 2), &[3]);
        assert_eq!(covered(&[1], 2), &[] as &[u8]);
    }

    #[test]
    fn twenty_four_bit_integers_round_trip_and_sign_extend() {
        assert_eq!(u24([0x01, 0x02, 0x03], true), 0x030201);
        assert_eq!(u24([0x01, 0x02, 0x03], false), 0x010203);
        assert_eq!(i24([0xFF, 0xFF, 0xFF], true), -1);
        assert_eq!(i24([0x80, 0x00, 0x00], false), -0x80_0000);
        assert_eq!(bytes24((-2i32) as u32, true), [0xFE, 0xFF, 0xFF]);
        assert_eq!(bytes24(0x010203, false), [0x01, 0x02, 0x03]);
    }

    #[test]
    fn a_following_value_is_the_rounded_up_relation() {
        assert_eq!(follows(10, 2, 1), 20);
        assert_eq!(follows(9, 1, 8), 2);
        assert_eq!(follows(16, 1, 8), 2);
        assert_eq!(follows(i64::MAX, 2, 1), i64::MAX);
        static N: FieldDesc = FieldDesc::new("m", "n");
        const K: FieldCheck = check(&N, 3).follows(2, 1, "2 × k");
        assert_eq!(following(&K, 4u8, 2), Ok(()));
        let e = following(&K, 5u8, 2).unwrap_err();
        assert_eq!(
            e,
            DecodeError::NotFollowing {
                field: &N,
                offset: 3,
                rule: "2 × k",
                expected: 4,
                found: 5
            }
        );
    }

    #[test]
    fn a_length_field_must_count_the_frame() {
        let field = |at, width, le, grows, k| FrameLength {
            at,
            width,
            le,
            grows,
            k,
        };
        // FF FF id len code p p ck: len counts code, payload and checksum (4 = 8 - 4).
        let mut f = [0xFF, 0xFF, 1, 4, 3, 9, 9, 0];
        assert_eq!(field(3, 1, true, true, -4).check(&f), Ok(()));
        assert_eq!(
            field(3, 1, true, true, -3).check(&f),
            Err(DecodeError::LengthMismatch {
                offset: 3,
                expected: 5,
                found: 4
            })
        );
        assert_eq!(
            field(1, 2, false, false, 0x102).check(&[0, 1, 2, 0]),
            Ok(())
        );
        assert_eq!(field(1, 2, true, false, 0x102).check(&[0, 2, 1, 0]), Ok(()));
        assert!(field(1, 2, true, false, 0x102).check(&[0, 2]).is_err());
        // `put` writes what `check` accepts, and refuses what the field cannot hold.
        f[3] = 0;
        assert_eq!(field(3, 1, true, true, -4).put(&mut f), Ok(()));
        assert_eq!(f[3], 4);
        let mut g = [0u8; 4];
        assert_eq!(field(1, 2, true, false, 0x102).put(&mut g), Ok(()));
        assert_eq!(g, [0, 2, 1, 0]);
        assert_eq!(
            field(3, 1, true, true, 300).put(&mut f),
            Err(EncodeError::OutOfRange { field: "length" })
        );
        assert_eq!(
            field(3, 1, true, true, -9).put(&mut f),
            Err(EncodeError::OutOfRange { field: "length" })
        );
    }

    /// The frame's trailing checksum as `check_sum` reads it, for each width and order.
    fn found(frame: &[u8], n: usize, be: bool) -> u32 {
        let f = Frame {
            start: None,
            addressed: true,
            devices: (0, 0),
            broadcast: None,
            host: None,
            checksum_len: n,
            checksum_be: be,
            end: &[],
            end_first: false,
            lead: None,
        };
        sums(frame, frame.len() - n, &f, |_| 0).0
    }

    /// A checksum before the bytes it covers (SBF's CRC at offset 2): `seal` writes it there
    /// over the bytes from the `frame_sum`'s offset to the end, and the frame checks read it
    /// there; a byte changed after it is a mismatch at its offset.
    #[test]
    fn a_checksum_before_the_bytes_it_covers_is_sealed_and_checked_where_it_sits() {
        let f = Frame {
            start: Some((0, 0x24)),
            addressed: false,
            devices: (0, 0),
            broadcast: None,
            host: None,
            checksum_len: 2,
            checksum_be: false,
            end: &[],
            end_first: false,
            lead: Some(2),
        };
        // A sum-16 of the bytes from offset 4 on, standing in for the CRC.
        let sum = |b: &[u8]| b[4..].iter().map(|&x| u32::from(x)).sum::<u32>();
        let mut buf = [0x24, 0x40, 0, 0, 0x21, 0x17, 0x08, 0x00, 0xAA];
        f.seal(&mut buf, 8, sum);
        assert_eq!(buf, [0x24, 0x40, 0x40, 0x00, 0x21, 0x17, 0x08, 0x00, 0xAA]);
        let frame = &buf[..8];
        assert!(f.checksum_ok(frame, sum));
        assert_eq!(check_frame(frame, 8, 8, 0, &f, sum), Ok(0));
        assert_eq!(span(frame, 4, &f), &frame[4..]);
        let mut bad = [0u8; 8];
        bad.copy_from_slice(frame);
        bad[7] = 1;
        assert!(!f.checksum_ok(&bad, sum));
        assert_eq!(
            check_frame(&bad, 8, 8, 0, &f, sum),
            Err(DecodeError::ChecksumMismatch {
                offset: 2,
                expected: 0x41,
                found: 0x40,
                width: 2
            })
        );
    }

    #[test]
    fn codes_and_checksums_read_as_written_in_every_width_and_order() {
        let f = [0x10, 0x21, 0x32, 0x43, 0x54, 0x65];
        assert_eq!(code(&f, 1, 1), 0x21);
        assert_eq!(code(&f, 1, 2), 0x2132);
        assert_eq!(code(&f, 1, 3), 0x21_3243);
        assert_eq!(code(&f, 1, 4), 0x2132_4354);
        let widths = [
            (1, 0x65, 0x65),
            (2, 0x5465, 0x6554),
            (3, 0x43_5465, 0x65_5443),
        ];
        for (n, be, le) in widths.into_iter().chain([(4, 0x3243_5465, 0x6554_4332)]) {
            assert_eq!(found(&f, n, true), be, "{n} bytes, big-endian");
            assert_eq!(found(&f, n, false), le, "{n} bytes, little-endian");
            // `seal` writes what `sums` reads back.
            for order in [true, false] {
                let mut g = f;
                seal(&mut g, f.len(), |_| if order { be } else { le }, n, order);
                assert_eq!(g, f, "{n} bytes, big-endian {order}");
            }
        }
    }

    /// A frame of `N` bytes sealed by `seal_sum8` and by `seal_sum8_head` from each head
    /// length, with the head's sum given.
    fn sealed_alike<const N: usize>() {
        let mut frame = [0u8; N];
        for (i, b) in frame.iter_mut().enumerate() {
            *b = 0x31u8.wrapping_mul(i as u8 + 7);
        }
        let mut whole = frame;
        assert_eq!(seal_sum8(&mut whole), N);
        for from in 0..N {
            let mut sealed = frame;
            let head = crate::sum8_bytes(&frame[..from]);
            assert_eq!(seal_sum8_head(&mut sealed, from, head), N);
            assert_eq!(sealed, whole, "{N} bytes from {from}");
        }
    }

    #[test]
    fn a_sum_8_sealed_from_a_known_head_is_the_sum_of_the_frame() {
        // The rest after the head: none, one, two and more bytes.
        sealed_alike::<2>();
        sealed_alike::<4>();
        sealed_alike::<5>();
        sealed_alike::<9>();
        sealed_alike::<16>();
    }

    #[test]
    fn a_sync_sequence_names_the_byte_that_differs() {
        assert_eq!(check_sync(&[0xFF, 0xFF, 1], 9, 0, &[0xFF, 0xFF]), Ok(()));
        assert_eq!(check_sync(&[0xFF], 9, 0, &[0xFF, 0xFF]), Ok(()));
        assert_eq!(
            check_sync(&[0xFF, 0x01, 0, 0], 3, 0, &[0xFF, 0xFF]),
            Err(DecodeError::TooLong { max: 3, found: 4 })
        );
        assert_eq!(
            check_sync(&[0xFF, 0x01], 9, 0, &[0xFF, 0xFF]),
            Err(DecodeError::BadStart {
                offset: 1,
                expected: 0xFF,
                found: 0x01
            })
        );
    }
}
