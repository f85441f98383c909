//! The runtime every busspec-generated protocol shares: errors, decoded frames, field values,
//! command kinds, checksum helpers, the streaming decoder, and the [`Protocol`] trait each
//! generated module implements, so tools are written once, generic over protocols.
//!
//! Generated code (from `busspec-codegen`, in a build script) refers to this crate by its name,
//! so a crate that includes generated modules depends on `busspec-runtime` too. Nothing here is
//! specific to one protocol.
//!
//! Invariants: `no_std`, no allocation, no `unsafe`, and no input makes encoding or decoding
//! panic — generated decoders check every frame's length before reading any byte, and hand
//! fixed-size arrays to every field access.

#![no_std]
#![forbid(unsafe_code)]

// `arbitrary`'s derive counts recursion in a `std` thread-local, and `arbitrary` needs `std`
// anyway: the feature is for fuzzing and tests, never for a device build.
#[cfg(feature = "arbitrary")]
extern crate std;

/// The CRC implementation generated checksums are built on, re-exported so a crate of
/// generated code needs no dependency of its own on it.
pub use crc;

mod ascii;
pub use ascii::Ascii;

pub mod codec;
pub mod escape;
mod forms;
mod lists;
mod long;
mod optional;
mod protocol;
mod repeated;
pub mod stream;
mod truncate;
mod view;

#[doc(hidden)]
pub use forms::ShortForm;
#[doc(hidden)]
pub use long::LongLength;
pub use protocol::{
    Bus, Command, FrameBuffer, Message, Protocol, ProtocolVisitor, RequestMessage, ResponseMessage,
    Source, Transactions,
};
#[doc(hidden)]
pub use protocol::{Framing, Preamble, Transform};
pub use repeated::{Bits, CapacityError, Element, Repeated};
pub use truncate::Truncation;
pub use view::{BitsView, ListView};

use core::fmt;

/// A decoded frame: the address it carried and its message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
pub struct Decoded<M> {
    pub address: u8,
    pub message: M,
}

/// What a command does, as its spec classifies it (each protocol's `Request::kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CommandKind {
    /// Starts a movement; sending it twice moves twice.
    Movement,
    /// Asks whether a movement is done.
    CompletionCheck,
    /// Sets a value; the device echoes or acknowledges it.
    Setter,
    /// Reads a value.
    Getter,
    /// Resets a counter, a flag or the device.
    Reset,
}

/// Whether a command gets a reply, as its spec says (each protocol's `Request::reply`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Reply {
    /// One of its responses always comes.
    Required,
    /// One of its responses may come, or none.
    Optional,
    /// None ever comes.
    None,
}

impl CommandKind {
    /// Whether a command of this kind may be sent again when its reply is lost or garbled,
    /// with nothing else known about it: reads, completion checks and setters (the same value
    /// set twice is set once); never movements (a second trigger restarts or extends the move)
    /// or resets (the second reply reports the reset state, not the value before it). A spec
    /// says otherwise in `transactions.retry` ([`Command::may_retry`](crate::Command::may_retry)).
    pub const fn safe_to_repeat(self) -> bool {
        matches!(
            self,
            CommandKind::Getter | CommandKind::CompletionCheck | CommandKind::Setter
        )
    }
}

/// How a command treats the broadcast address (each protocol's `Request::broadcast`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Broadcast {
    /// Devices act on it when it is sent to the broadcast address.
    pub accepted: bool,
    /// Devices answer it when it is sent to the broadcast address.
    pub answered: bool,
}

/// How a raw value (an `i64`, as [`FieldValue::Int`] carries it) reads as a number: the value
/// itself for every integer type but `u64`, whose bits it carries (`v as u64`), as it carries
/// an `f32`'s bits zero-extended (`f32::from_bits(v as u32)`) and an `f64`'s
/// (`f64::from_bits(v as u64)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NumKind {
    Int,
    U64,
    F32,
    F64,
}

/// A raw value displayed as its [`NumKind`] reads it, as the JSON contract prints it: an
/// integer in decimal; a finite float as `{:?}` prints it (the shortest text that reads back
/// to the same bits); `inf`, `-inf`; `NaN` for the canonical quiet NaN and `NaN:0x…` (every
/// bit) for any other.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Num(pub NumKind, pub i64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Num(kind, raw) = *self;
        let (nan, canonical, infinite, negative) = match kind {
            NumKind::Int => return write!(f, "{raw}"),
            NumKind::U64 => return write!(f, "{}", raw as u64),
            NumKind::F32 => {
                let v = f32::from_bits(raw as u32);
                (
                    v.is_nan(),
                    raw as u32 == 0x7FC0_0000,
                    v.is_infinite(),
                    v.is_sign_negative(),
                )
            }
            NumKind::F64 => {
                let v = f64::from_bits(raw as u64);
                let canonical = raw as u64 == 0x7FF8_0000_0000_0000;
                (v.is_nan(), canonical, v.is_infinite(), v.is_sign_negative())
            }
        };
        match (nan, canonical, infinite, negative, kind) {
            (true, true, ..) => f.write_str("NaN"),
            (true, false, .., NumKind::F32) => write!(f, "NaN:0x{:08X}", raw as u32),
            (true, false, ..) => write!(f, "NaN:0x{:016X}", raw as u64),
            (_, _, true, false, _) => f.write_str("inf"),
            (_, _, true, true, _) => f.write_str("-inf"),
            (.., NumKind::F32) => write!(f, "{:?}", f32::from_bits(raw as u32)),
            _ => write!(f, "{:?}", f64::from_bits(raw as u64)),
        }
    }
}

/// One field's value as it travels: the raw wire integer (sign-extended where the field is
/// signed; enums, flags and units by their raw value; a `u64`'s or a float's bits, see
/// [`NumKind`]) or an ASCII field's bytes.
/// See each message type's `visit`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FieldValue<'a> {
    Int(i64),
    Text(&'a [u8]),
    /// A repeated field's elements, borrowed from the message (or the caller).
    List(Elements<'a>),
    /// A repeated record's records (`type: record`), each its fields' raw values.
    Records(RecordList<'a>),
}

/// The records of a repeated record, as raw values: a generated message's records (each a
/// [`Record`]), or a caller's raw values one record after the other.
#[derive(Clone, Copy)]
pub enum RecordList<'a> {
    /// Records that lend their raw values (a generated message's `rt::Repeated` of records).
    Table(&'a dyn RecordTable),
    /// Raw values, record after record, `fields` to a record (for callers holding raw values,
    /// as the interpreter does).
    Flat { values: &'a [i64], fields: usize },
}

/// A table of records' raw values: how [`RecordList::Table`] reads them.
pub trait RecordTable {
    /// How many records.
    fn records(&self) -> usize;
    /// How many fields a record has.
    fn fields(&self) -> usize;
    /// The raw value of field `field` of record `record` (0 outside the table).
    fn raw(&self, record: usize, field: usize) -> i64;
}

/// One record of a repeated record in generated code: a `Copy` struct of its fields, as
/// generated for each repeated record. Public only for generated code.
pub trait Record: Copy + Default {
    /// How many fields it has.
    const FIELDS: usize;
    /// The raw wire value of field `field` (0 past the last).
    fn raw(&self, field: usize) -> i64;
    /// The record from the raw values of record `k` of `list`, each checked against its
    /// field's wire limits.
    fn from_raw(list: &RecordList<'_>, k: usize) -> Result<Self, FieldError>;
}

impl RecordList<'_> {
    /// How many records.
    pub fn len(&self) -> usize {
        match self {
            RecordList::Table(t) => t.records(),
            RecordList::Flat { values, fields } => values.len() / (*fields).max(1),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// How many fields each record has.
    pub fn fields(&self) -> usize {
        match self {
            RecordList::Table(t) => t.fields(),
            RecordList::Flat { fields, .. } => *fields,
        }
    }

    /// The raw value of field `field` of record `record`, if both exist.
    pub fn get(&self, record: usize, field: usize) -> Option<i64> {
        if record >= self.len() || field >= self.fields() {
            return None;
        }
        match self {
            RecordList::Table(t) => Some(t.raw(record, field)),
            RecordList::Flat { values, fields } => values.get(record * fields + field).copied(),
        }
    }
}

impl PartialEq for RecordList<'_> {
    fn eq(&self, other: &Self) -> bool {
        let (n, w) = (self.len(), self.fields());
        n == other.len()
            && w == other.fields()
            && (0..n).all(|k| (0..w).all(|j| self.get(k, j) == other.get(k, j)))
    }
}

impl Eq for RecordList<'_> {}

impl core::hash::Hash for RecordList<'_> {
    fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
        let (n, w) = (self.len(), self.fields());
        (n, w).hash(state);
        for k in 0..n {
            for j in 0..w {
                self.get(k, j).hash(state);
            }
        }
    }
}

impl fmt::Debug for RecordList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.fields();
        f.debug_list()
            .entries((0..self.len()).map(|k| Row(self, k, w)))
            .finish()
    }
}

/// One record of a [`RecordList`], for `Debug`.
struct Row<'r, 'a>(&'r RecordList<'a>, usize, usize);

impl fmt::Debug for Row<'_, '_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list()
            .entries((0..self.2).map(|j| self.0.get(self.1, j).unwrap_or(0)))
            .finish()
    }
}

/// The elements of a repeated field, as the message holds them: a slice of its element type
/// (`I64` for callers holding raw values, as the interpreter does), or bits packed eight to a
/// byte, least significant first (`len` of them; the padding bits are zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Elements<'a> {
    U8(&'a [u8]),
    I8(&'a [i8]),
    U16(&'a [u16]),
    I16(&'a [i16]),
    U32(&'a [u32]),
    I32(&'a [i32]),
    I64(&'a [i64]),
    Bits {
        packed: &'a [u8],
        len: usize,
    },
    /// Elements of a type of the spec's (a unit's newtype, an enum), each lent as its raw
    /// value.
    Table(ElementRef<'a>),
}

/// A list whose elements lend their raw values: how [`Elements::Table`] reads them.
pub trait ElementTable {
    /// How many elements.
    fn count(&self) -> usize;
    /// The raw value of element `i` (0 past the last).
    fn raw(&self, i: usize) -> i64;
}

/// An [`ElementTable`] lent to [`Elements::Table`]: compared, hashed and printed by its raw
/// values.
#[derive(Clone, Copy)]
pub struct ElementRef<'a>(pub &'a dyn ElementTable);

impl ElementRef<'_> {
    fn values(&self) -> impl Iterator<Item = i64> + '_ {
        (0..self.0.count()).map(|i| self.0.raw(i))
    }
}

impl PartialEq for ElementRef<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.0.count() == other.0.count() && self.values().eq(other.values())
    }
}

impl Eq for ElementRef<'_> {}

impl core::hash::Hash for ElementRef<'_> {
    fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
        self.0.count().hash(state);
        for v in self.values() {
            v.hash(state);
        }
    }
}

impl fmt::Debug for ElementRef<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.values()).finish()
    }
}

impl Elements<'_> {
    /// How many elements.
    pub fn len(&self) -> usize {
        match self {
            Elements::U8(s) => s.len(),
            Elements::I8(s) => s.len(),
            Elements::U16(s) => s.len(),
            Elements::I16(s) => s.len(),
            Elements::U32(s) => s.len(),
            Elements::I32(s) => s.len(),
            Elements::I64(s) => s.len(),
            Elements::Bits { len, .. } => *len,
            Elements::Table(t) => t.0.count(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Element `i` as a raw value (sign-extended; a bit as 0 or 1).
    pub fn get(&self, i: usize) -> Option<i64> {
        match self {
            Elements::U8(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::I8(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::U16(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::I16(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::U32(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::I32(s) => s.get(i).map(|&v| i64::from(v)),
            Elements::I64(s) => s.get(i).copied(),
            Elements::Bits { packed, len } if i < *len => {
                packed.get(i / 8).map(|b| i64::from(b >> (i % 8) & 1))
            }
            Elements::Bits { .. } => None,
            Elements::Table(t) => (i < t.0.count()).then(|| t.0.raw(i)),
        }
    }

    /// The elements as raw values, in order.
    pub fn iter(&self) -> impl Iterator<Item = i64> + '_ {
        (0..self.len()).filter_map(move |i| self.get(i))
    }
}

/// Which kind of [`FieldValue`] a field takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueKind {
    /// [`FieldValue::Int`]: every field but ASCII text.
    Int,
    /// [`FieldValue::Text`]: an ASCII field.
    Text,
    /// [`FieldValue::List`]: a repeated field.
    List,
    /// [`FieldValue::Records`]: a repeated record.
    Records,
}

/// Why a message could not be built from field values ([`Message::from_fields`]), and where.
/// The field is named as the spec names it, as [`Message::visit`] reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FieldError {
    /// No message of this type (request or response) has the name given.
    UnknownMessage,
    /// The getter gave no value for a field the message has.
    Missing { field: &'static str },
    /// The value does not fit the field's wire type (`300` for a `u8`, `16` for a 4-bit
    /// sub-field); the field holds `min..=max`.
    OutOfRange {
        field: &'static str,
        value: i64,
        min: i64,
        max: i64,
    },
    /// Text of another length than the ASCII field's: it takes exactly `expected` bytes, as both
    /// encoders do (neither pads).
    TextLength {
        field: &'static str,
        expected: usize,
        found: usize,
    },
    /// More elements than the repeated field holds (the spec's `max`).
    TooMany {
        field: &'static str,
        found: usize,
        max: usize,
    },
    /// A value of the wrong kind (text for a number field, a number for an ASCII field, a
    /// list for either, or anything but a list for a repeated field); the field takes
    /// `expected`.
    WrongKind {
        field: &'static str,
        expected: ValueKind,
    },
}

impl fmt::Display for FieldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            FieldError::UnknownMessage => f.write_str("no message of this direction has that name"),
            FieldError::Missing { field } => write!(f, "no value given for field {field}"),
            FieldError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(
                f,
                "{field} = {value} does not fit the field ({min}..={max})"
            ),
            FieldError::TextLength {
                field,
                expected,
                found,
            } => write!(
                f,
                "{field} takes exactly {expected} characters, got {found}"
            ),
            FieldError::WrongKind {
                field,
                expected: ValueKind::Int,
            } => write!(f, "{field} takes a number"),
            FieldError::WrongKind {
                field,
                expected: ValueKind::Text,
            } => write!(f, "{field} takes text"),
            FieldError::WrongKind {
                field,
                expected: ValueKind::List,
            } => write!(f, "{field} takes a list of numbers"),
            FieldError::WrongKind {
                field,
                expected: ValueKind::Records,
            } => write!(f, "{field} takes a list of records"),
            FieldError::TooMany { field, found, max } => {
                write!(f, "{field} holds at most {max} elements, got {found}")
            }
        }
    }
}

impl core::error::Error for FieldError {}

/// The raw value of integer field `field` from a [`Message::from_fields`] getter's answer,
/// checked against the field's wire limits `min..=max`. Public only for generated code.
#[doc(hidden)]
#[inline]
pub fn field_int(
    field: &'static str,
    value: Option<FieldValue<'_>>,
    min: i64,
    max: i64,
) -> Result<i64, FieldError> {
    match value {
        Some(FieldValue::Int(value)) if (min..=max).contains(&value) => Ok(value),
        Some(FieldValue::Int(value)) => Err(FieldError::OutOfRange {
            field,
            value,
            min,
            max,
        }),
        Some(FieldValue::Text(_) | FieldValue::List(_) | FieldValue::Records(_)) => {
            Err(FieldError::WrongKind {
                field,
                expected: ValueKind::Int,
            })
        }
        None => Err(FieldError::Missing { field }),
    }
}

/// The bytes of ASCII field `field` (exactly `N`) from a [`Message::from_fields`] getter's
/// answer. Public only for generated code.
#[doc(hidden)]
#[inline]
pub fn field_text<const N: usize>(
    field: &'static str,
    value: Option<FieldValue<'_>>,
) -> Result<Ascii<N>, FieldError> {
    match value {
        Some(FieldValue::Text(text)) => {
            text.try_into()
                .map(Ascii)
                .map_err(|_| FieldError::TextLength {
                    field,
                    expected: N,
                    found: text.len(),
                })
        }
        Some(FieldValue::Int(_) | FieldValue::List(_) | FieldValue::Records(_)) => {
            Err(FieldError::WrongKind {
                field,
                expected: ValueKind::Text,
            })
        }
        None => Err(FieldError::Missing { field }),
    }
}

/// A message as errors name it: its spec name, its code and the frame lengths of its code. Each
/// generated module has one per message, the constant `DESC` of the message's struct in its
/// `request` or `response` module (`modbus::request::ReadCoils::DESC`), which refusals point
/// at: building one stores a
/// reference, not the name, code and lengths, and [`DecodeError`]'s `Display` reads them here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MessageDesc {
    /// The message's name in the spec.
    pub name: &'static str,
    /// Its code as the frame holds it (big-endian, `code_len` bytes; 0 bytes: it has none).
    pub code: u32,
    /// The code's length in bytes.
    pub code_len: u8,
    /// The frame lengths of the messages with its code, sorted (for one of variable length,
    /// its shortest); empty where the refusing engine does not say them (the interpreter's
    /// errors carried over by the CLI).
    pub lengths: &'static [usize],
}

impl MessageDesc {
    /// A descriptor for message `name` with `code` (`code_len` bytes) and the frame `lengths`
    /// of its code.
    pub const fn new(
        name: &'static str,
        code: u32,
        code_len: u8,
        lengths: &'static [usize],
    ) -> Self {
        MessageDesc {
            name,
            code,
            code_len,
            lengths,
        }
    }
}

/// A field (a sub-field, a repeated field) as refusals name it: its message's name and its
/// own. Each generated module has one for each field its decoders refuse, a `const` beside its
/// message's [`MessageDesc`], both constants of the message's struct
/// (`request::ReadCoils::QUANTITY_DESC`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FieldDesc {
    /// The name of the message holding it, in the spec.
    pub message: &'static str,
    /// Its name in the spec.
    pub name: &'static str,
}

impl FieldDesc {
    /// A descriptor for field `name` of message `message`.
    pub const fn new(message: &'static str, name: &'static str) -> Self {
        FieldDesc { message, name }
    }
}

/// [`MessageDesc::new`], short enough that a generated message's `DESC` stays one line:
/// `rt::desc(Self::NAME, 0x03, 1, &[8])`.
pub const fn desc(
    name: &'static str,
    code: u32,
    code_len: u8,
    lengths: &'static [usize],
) -> MessageDesc {
    MessageDesc::new(name, code, code_len, lengths)
}

/// [`FieldDesc::new`], short enough that a generated field descriptor stays one line:
/// `rt::field(Self::NAME, "quantity")`.
pub const fn field(message: &'static str, name: &'static str) -> FieldDesc {
    FieldDesc::new(message, name)
}

impl fmt::Display for FieldDesc {
    /// `message.field`, as refusals name a field.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.message, self.name)
    }
}

/// Why a frame did not decode, and where.
///
/// A refusal names the message it concerns by its [`MessageDesc`] (a `&'static` constant of
/// the generated module, `request::ReadCoils::DESC`), not by its name and numbers: building one
/// stores a reference, and the error stays small; a field by its [`FieldDesc`]
/// (`request::ReadCoils::QUANTITY_DESC`). Match on the descriptor's fields
/// (`DecodeError::WrongLength { message, .. } if message.name == "read_coils"`) or compare it
/// with the constant (`message == &request::ReadCoils::DESC`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DecodeError {
    /// Fewer bytes than the shortest frame that could start like this one.
    Truncated { needed: usize, found: usize },
    /// A start byte (at `offset`, within the sync sequence) is not the protocol's.
    BadStart {
        offset: usize,
        expected: u8,
        found: u8,
    },
    /// A byte of the end bytes after the checksum (at `offset`) is not the protocol's.
    BadEnd {
        offset: usize,
        expected: u8,
        found: u8,
    },
    /// The checksum at `offset` is not what the bytes before it give; `width` is its length in
    /// bytes (both values are printed at that width, as the frame holds them).
    ChecksumMismatch {
        offset: usize,
        expected: u32,
        found: u32,
        width: u8,
    },
    /// A reply whose checksum (at `offset`) takes in its request's bytes, decoded without
    /// them (`checksum_over_request`): its checksum cannot be checked. Decode it with
    /// [`crate::Protocol::decode_reply_to`].
    NeedsRequest {
        message: &'static MessageDesc,
        offset: usize,
    },
    /// No message of this direction has this code: the `len` bytes at `offset`.
    UnknownCommand { offset: usize, code: u32, len: u8 },
    /// No response has this code (a frame decoded as a response only).
    UnknownResponse { offset: usize, code: u32, len: u8 },
    /// The code is known but the frame's length is none of the lengths its messages have
    /// (`message`: the first of them; the lengths: its `lengths`).
    WrongLength {
        message: &'static MessageDesc,
        found: usize,
        /// How much shorter than `expected` says each length is as the frame travelled: 0 but
        /// for a frame that travelled in the short form of a length field the start byte
        /// chooses (`framing.length.long`), whose `expected` are the lengths laid out in the
        /// long form's width.
        less: usize,
    },
    /// A constant field (or constant bits of one) holds another value.
    InvalidValue {
        field: &'static FieldDesc,
        offset: usize,
        expected: u64,
        found: u64,
    },
    /// A BCD field (`encoding: bcd`) holds a nibble above 9: its bytes as read, `found`.
    NotBcd {
        field: &'static FieldDesc,
        offset: usize,
        found: u64,
    },
    /// A field that repeats another (`equals`) holds another value than that field.
    NotEqual {
        field: &'static FieldDesc,
        offset: usize,
        other: &'static str,
        expected: i64,
        found: i64,
    },
    /// A field that follows from another (of the frame or of the request) does not: it must
    /// be `expected`, by `rule`.
    NotFollowing {
        field: &'static FieldDesc,
        offset: usize,
        rule: &'static str,
        expected: i64,
        found: i64,
    },
    /// The count field `field` at `offset` says the elements of `list` (of the same message)
    /// take `found` bytes; the frame's length gives them `expected`.
    ByteCount {
        list: &'static FieldDesc,
        field: &'static str,
        offset: usize,
        expected: i64,
        found: i64,
    },
    /// The length field at `offset` says `found`; the frame's length gives `expected`.
    LengthMismatch {
        offset: usize,
        expected: i64,
        found: i64,
    },
    /// Several responses share this code and length, and `candidates` all decode from the
    /// frame; decode it with `decode_reply`.
    Ambiguous { code: u32, candidates: MessageNames },
    /// The frame is a valid response `message`, but not one the spec lists for `request`;
    /// `unasked` where `message` is one the device sends on its own (`unasked: true`), a frame
    /// that came unasked rather than a wrong reply.
    NotAReply {
        message: &'static str,
        request: &'static str,
        unasked: bool,
    },
    /// More bytes than the protocol's longest frame (of the direction decoded): refused for
    /// its length before anything else is looked at.
    TooLong { max: usize, found: usize },
    /// A field's raw value lies outside the `range` the spec gives it (and is none of its
    /// special values); `offset` is where the field (or the word holding the sub-field) starts.
    OutOfRange {
        field: &'static FieldDesc,
        offset: usize,
        found: i64,
        min: i64,
        max: i64,
        /// How the three raw values read as numbers (the bits of a `u64` or a float).
        kind: NumKind,
    },
    /// The address at `offset` is outside the device range `min..=max` and is neither the
    /// broadcast address nor the host address (where the protocol has them).
    BadAddress {
        offset: usize,
        found: u8,
        min: u8,
        max: u8,
    },
    /// A request to the broadcast address `address` for a command (`message`, its code
    /// there) the spec says does not accept broadcast.
    BroadcastNotAccepted {
        message: &'static MessageDesc,
        address: u8,
    },
    /// The repeated field `field`, whose elements start at `offset`, cannot have what this
    /// frame gives it: `found` (elements, or bytes where they are not whole elements) against
    /// what it must be.
    BadCount {
        field: &'static FieldDesc,
        offset: usize,
        found: i64,
        expected: CountRule,
    },
    /// The bytes as they travel break the protocol's escaping (`framing.escaping`) at
    /// `offset` (counted in the escaped bytes).
    BadEscape { offset: usize, fault: EscapeFault },
    /// A frame in the long form of its length field (`framing.length.long`: VESC's `03 lenH
    /// lenL`) whose length the short form holds (at most `most`): encoders send it short, so
    /// decoding refuses it. `offset` is the length field's.
    NeedlessLong {
        offset: usize,
        length: i64,
        most: i64,
    },
    /// Text up to a terminator (`repeat: {until}`) whose terminator is not among the
    /// `within` bytes from `offset` that the frame's length leaves it.
    NoTerminator {
        field: &'static FieldDesc,
        offset: usize,
        terminator: u8,
        within: usize,
    },
    /// The field `field` at `offset` gives each record's last field `found` bytes
    /// (`bytes:` in the spec), outside `1..=most`: the records of `list` (of the same
    /// message) cannot be laid out.
    BadWidth {
        list: &'static FieldDesc,
        field: &'static str,
        offset: usize,
        found: i64,
        most: usize,
    },
    /// Where end bytes alone delimit a frame (no length field, no checksum: Nextion's
    /// `FF FF FF`), the list to the end `field` holds the end bytes `end` at `offset`, before
    /// the frame's own: a receiver ends the frame there.
    EndInside {
        field: &'static FieldDesc,
        offset: usize,
        end: &'static [u8],
    },
}

/// `bytes` in hex, a space between: `FF FF FF`.
struct HexBytes(&'static [u8]);

impl fmt::Display for HexBytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, b) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

/// What is wrong with escaped bytes ([`DecodeError::BadEscape`]), as the interpreter's
/// `EscapeFault` says it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EscapeFault {
    /// The escape byte followed by a byte that stands for none (the end byte included).
    Escape { escape: u8, found: u8 },
    /// A byte that travels escaped, found as it is.
    Unescaped { found: u8 },
    /// A stuffing pattern not followed by its inserted byte (`None`: the frame ends).
    Stuffing { expected: u8, found: Option<u8> },
    /// COBS: a 0x00 among the encoded bytes.
    CobsZero,
    /// COBS: a block longer than the bytes before the end byte.
    CobsOverrun { code: u8 },
    /// COBS: no block before the end byte.
    CobsEmpty,
    /// COBS: a 0x01 block ending the frame after a full block.
    CobsTrailing,
}

impl fmt::Display for EscapeFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            EscapeFault::Escape { escape, found } => {
                write!(f, "0x{escape:02X} followed by 0x{found:02X}")
            }
            EscapeFault::Unescaped { found } => write!(f, "0x{found:02X} not escaped"),
            EscapeFault::Stuffing { expected, found } => {
                write!(f, "expected inserted byte 0x{expected:02X}, found ")?;
                match found {
                    Some(b) => write!(f, "0x{b:02X}"),
                    None => f.write_str("the frame's end"),
                }
            }
            EscapeFault::CobsZero => f.write_str("COBS block holds 0x00"),
            EscapeFault::CobsOverrun { code } => {
                write!(f, "COBS block 0x{code:02X} runs past the end byte")
            }
            EscapeFault::CobsEmpty => f.write_str("no COBS block before the end byte"),
            EscapeFault::CobsTrailing => {
                f.write_str("COBS block 0x01 after a full block ends the frame")
            }
        }
    }
}

/// The messages an ambiguous frame decodes as, in spec order (the first four: no spec has more
/// than two responses only the request tells apart), by their descriptors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MessageNames {
    messages: [&'static MessageDesc; 4],
    len: u8,
}

/// What an empty slot of [`MessageNames`] holds.
static NO_MESSAGE: MessageDesc = MessageDesc::new("", 0, 0, &[]);

impl Default for MessageNames {
    fn default() -> Self {
        MessageNames {
            messages: [&NO_MESSAGE; 4],
            len: 0,
        }
    }
}

impl MessageNames {
    /// `messages`, the first four of them.
    pub fn from_slice(messages: &[&'static MessageDesc]) -> Self {
        let mut c = MessageNames::default();
        for m in messages {
            c.push(m);
        }
        c
    }

    /// Adds `message` (dropped past the fourth).
    #[inline]
    pub fn push(&mut self, message: &'static MessageDesc) {
        if let Some(slot) = self.messages.get_mut(usize::from(self.len)) {
            *slot = message;
            self.len += 1;
        }
    }

    /// The messages, in spec order. Inlined: `rt::Group::end` asks how many on every frame
    /// of a group, which a call cost.
    #[inline]
    pub fn messages(&self) -> &[&'static MessageDesc] {
        &self.messages[..usize::from(self.len)]
    }

    /// Their names, in spec order.
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.messages().iter().map(|m| m.name)
    }
}

impl fmt::Display for MessageNames {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, n) in self.names().enumerate() {
            if i > 0 {
                f.write_str(" or ")?;
            }
            f.write_str(n)?;
        }
        Ok(())
    }
}

/// What a repeated field's count must be, as [`DecodeError::BadCount`] says it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CountRule {
    /// Whole elements of this many bytes.
    Whole(usize),
    /// This many, as the frame's length gives them (the count field says otherwise).
    ByLength(usize),
    /// At most this many, as the bytes the frame's length leaves a list before another.
    AtMost(usize),
    /// Between the spec's bounds.
    Between(usize, usize),
    /// As many as follow from the request (`rule`, the relation's words).
    Request(i64, &'static str),
    /// The rule in the words of an engine that states it as text (the interpreter behind a
    /// spec read at run time).
    Stated(&'static str),
}

impl fmt::Display for CountRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            CountRule::Whole(w) => write!(f, "whole {w}-byte elements"),
            CountRule::ByLength(n) => write!(f, "{n} by the frame's length"),
            CountRule::AtMost(n) => write!(f, "at most {n} by the frame's length"),
            CountRule::Between(min, max) => write!(f, "{min}..={max}"),
            CountRule::Request(n, rule) => write!(f, "{n} ({rule} of the request)"),
            CountRule::Stated(rule) => f.write_str(rule),
        }
    }
}

impl DecodeError {
    /// How far a frame decoded as one direction got before this error: 0, no message of the
    /// direction has its code, its length field (the direction's own) or its length (longer
    /// than the direction's longest: an escaped stream tries every frame both ways); 1, too short; 2, a
    /// code whose messages have other lengths or counts; 3, a message's own refusal. A frame
    /// decoded both ways is refused for the reason that got further (the request's on a tie),
    /// as the interpreter, which decodes both ways at once, refuses it.
    pub fn progress(&self) -> u8 {
        match self {
            DecodeError::UnknownCommand { .. }
            | DecodeError::UnknownResponse { .. }
            | DecodeError::LengthMismatch { .. }
            | DecodeError::TooLong { .. } => 0,
            DecodeError::Truncated { .. } => 1,
            DecodeError::WrongLength { .. }
            | DecodeError::BadCount { .. }
            | DecodeError::BadWidth { .. }
            | DecodeError::NoTerminator { .. }
            | DecodeError::ByteCount { .. } => 2,
            _ => 3,
        }
    }
}

/// `v` in hex as `len` bytes (`0x0009` for a two-byte code), as the frame holds them (`0x`
/// where it holds none).
fn hex(f: &mut fmt::Formatter<'_>, v: u32, len: u8) -> fmt::Result {
    if len == 0 {
        return f.write_str("0x");
    }
    let digits = 2 * usize::from(len);
    write!(f, "0x{v:0digits$X}")
}

/// The wording of every error is the interpreter's (`busspec_model::interp::DecodeError`):
/// the CLI prints the same line for the same refusal whichever engine decoded the frame.
impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DecodeError::Truncated { needed, found } => write!(
                f,
                "truncated frame: need at least {needed} bytes, found {found}"
            ),
            DecodeError::BadEnd {
                offset,
                expected,
                found,
            } => {
                write!(
                    f,
                    "bad end byte at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}"
                )
            }
            DecodeError::BadStart {
                offset,
                expected,
                found,
            } => {
                write!(
                    f,
                    "bad start byte at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}"
                )
            }
            DecodeError::ChecksumMismatch {
                offset,
                expected,
                found,
                width,
            } => {
                write!(f, "checksum mismatch at offset {offset}: expected ")?;
                hex(f, expected, width)?;
                f.write_str(", found ")?;
                hex(f, found, width)
            }
            DecodeError::NeedsRequest { message, offset } => write!(
                f,
                "{}'s checksum at offset {offset} takes in its request's bytes: decode it as the reply to its request",
                message.name
            ),
            DecodeError::UnknownCommand { offset, code, len } => {
                f.write_str("unknown command code ")?;
                hex(f, code, len)?;
                write!(f, " at offset {offset}")
            }
            DecodeError::UnknownResponse { offset, code, len } => {
                f.write_str("unknown response code ")?;
                hex(f, code, len)?;
                write!(f, " at offset {offset}")
            }
            DecodeError::WrongLength {
                message,
                found,
                less,
            } => {
                write!(f, "wrong length for {}: expected ", message.name)?;
                for (i, n) in message.lengths.iter().enumerate() {
                    if i > 0 {
                        f.write_str(" or ")?;
                    }
                    write!(f, "{}", n.saturating_sub(less))?;
                }
                write!(f, " bytes, found {found}")
            }
            DecodeError::InvalidValue {
                field,
                offset,
                expected,
                found,
            } => write!(
                f,
                "invalid value for {field} at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}"
            ),
            DecodeError::NotBcd {
                field,
                offset,
                found,
            } => write!(
                f,
                "invalid value for {field} at offset {offset}: 0x{found:02X} is not BCD (a digit above 9)"
            ),
            DecodeError::NotEqual {
                field,
                offset,
                other,
                expected,
                found,
            } => write!(
                f,
                "invalid value for {field} at offset {offset}: must repeat {other} ({expected}), found {found}"
            ),
            DecodeError::NotFollowing {
                field,
                offset,
                rule,
                expected,
                found,
            } => write!(
                f,
                "invalid value for {field} at offset {offset}: must be {rule} ({expected}), found {found}"
            ),
            DecodeError::ByteCount {
                list,
                field,
                offset,
                expected,
                found,
            } => write!(
                f,
                "invalid value for {}.{field} at offset {offset}: must be the bytes of {} ({expected}), found {found}",
                list.message, list.name
            ),
            DecodeError::LengthMismatch {
                offset,
                expected,
                found,
            } => write!(
                f,
                "length field at offset {offset} says {found}, the frame's length gives {expected}"
            ),
            DecodeError::Ambiguous { candidates, .. } => write!(
                f,
                "ambiguous frame: could be {candidates}; decode it together with the request it answers"
            ),
            DecodeError::NotAReply {
                message,
                request,
                unasked: false,
            } => write!(f, "{message} is not a reply {request} gets"),
            DecodeError::NotAReply {
                message,
                request,
                unasked: true,
            } => write!(f, "{message} is sent unasked, not a reply {request} gets"),
            DecodeError::TooLong { max, found } => write!(
                f,
                "frame too long: {found} bytes, the longest frame has {max}"
            ),
            DecodeError::OutOfRange {
                field,
                offset,
                found,
                min,
                max,
                kind,
            } => write!(
                f,
                "{field} at offset {offset} is {}, outside its range {}..={}",
                Num(kind, found),
                Num(kind, min),
                Num(kind, max)
            ),
            DecodeError::BadAddress {
                offset,
                found,
                min,
                max,
            } => write!(
                f,
                "address 0x{found:02X} at offset {offset} is outside the device range 0x{min:02X}..=0x{max:02X} and is not the broadcast or host address"
            ),
            DecodeError::BroadcastNotAccepted { message, address } => {
                let MessageDesc {
                    name,
                    code,
                    code_len,
                    ..
                } = *message;
                if code_len == 0 {
                    write!(f, "{name} (no code)")?;
                } else {
                    write!(f, "{name} (code ")?;
                    hex(f, code, code_len)?;
                    f.write_str(")")?;
                }
                write!(f, " does not accept the broadcast address 0x{address:02X}")
            }
            DecodeError::BadCount {
                field,
                offset,
                found,
                expected,
            } => write!(
                f,
                "{field} at offset {offset}: {found} elements, expected {expected}"
            ),
            DecodeError::BadEscape { offset, fault } => {
                write!(f, "bad escape at offset {offset}: {fault}")
            }
            DecodeError::NoTerminator {
                field,
                offset,
                terminator,
                within,
            } => write!(
                f,
                "{field} at offset {offset}: no terminator 0x{terminator:02X} in the {within} bytes the frame's length leaves it"
            ),
            DecodeError::EndInside { field, offset, end } => write!(
                f,
                "{field} at offset {offset}: holds the end bytes {}, which end the frame there",
                HexBytes(end)
            ),
            DecodeError::NeedlessLong {
                offset,
                length,
                most,
            } => write!(
                f,
                "long length field at offset {offset} says {length}: lengths up to {most} take the short form"
            ),
            DecodeError::BadWidth {
                list,
                field,
                offset,
                found,
                most,
            } => write!(
                f,
                "{}.{field} at offset {offset} is {found}: each record's last field takes 1..={most} bytes",
                list.message
            ),
        }
    }
}

impl core::error::Error for DecodeError {}

/// Why a message did not encode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EncodeError {
    /// The buffer is shorter than the frame; `MAX_FRAME_LEN` of each protocol always suffices.
    BufferTooSmall { needed: usize, available: usize },
    /// A reply whose checksum takes in its request's bytes, encoded without them
    /// (`checksum_over_request`): encode it with [`crate::Protocol::encode_reply`].
    NeedsRequest { message: &'static str },
    /// A typed value does not fit the wire field it goes into.
    OutOfRange { field: &'static str },
    /// A value lies outside the `range` the spec gives its field (and is none of its special
    /// values): the frame would be one the spec forbids.
    NotInRange {
        field: &'static str,
        value: i64,
        min: i64,
        max: i64,
        /// How the three raw values read as numbers.
        kind: NumKind,
    },
    /// A list holds `found` elements (records, characters), outside the `min..=max` its
    /// spec allows.
    WrongCount {
        field: &'static str,
        min: usize,
        max: usize,
        found: usize,
    },
    /// The address is outside the device range `min..=max` and is neither the broadcast
    /// address nor the host address (where the protocol has them).
    BadAddress { address: u8, min: u8, max: u8 },
    /// An address other than 0 for a protocol whose frames carry none.
    Unaddressed { address: u8 },
    /// The command does not accept the broadcast address `address`, says the spec.
    BroadcastNotAccepted {
        message: &'static MessageDesc,
        address: u8,
    },
    /// An optional field (`present:` in the spec) given where its condition does not hold
    /// (`given`), or not given where it does: `condition` in words (``bit 0 of `flags` is
    /// set``).
    Optional {
        field: &'static str,
        condition: &'static str,
        given: bool,
    },
    /// Text up to a terminator (`repeat: {until}`) whose characters hold the terminator (the
    /// `index`th): the frame would end it there.
    HoldsTerminator {
        field: &'static str,
        index: usize,
        terminator: u8,
    },
    /// Where end bytes alone delimit a frame, the list to the end `field` would put the end
    /// bytes `end` at `offset` of the frame, before its own: a receiver would end the frame
    /// there.
    HoldsEnd {
        field: &'static str,
        offset: usize,
        end: &'static [u8],
    },
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            EncodeError::BufferTooSmall { needed, available } => {
                write!(
                    f,
                    "buffer too small: the frame needs {needed} bytes, the buffer has {available}"
                )
            }
            EncodeError::OutOfRange { field } => {
                write!(f, "value of {field} does not fit its wire field")
            }
            EncodeError::NeedsRequest { message } => write!(
                f,
                "{message}'s checksum takes in its request's bytes: encode it as the reply to its request"
            ),
            EncodeError::NotInRange {
                field,
                value,
                min,
                max,
                kind,
            } => write!(
                f,
                "{field} = {} is outside its range {}..={}",
                Num(kind, value),
                Num(kind, min),
                Num(kind, max)
            ),
            EncodeError::WrongCount {
                field,
                min,
                max,
                found,
            } => write!(f, "{field} takes {min}..={max} elements, got {found}"),
            EncodeError::BadAddress { address, min, max } => write!(
                f,
                "address 0x{address:02X} is outside the device range 0x{min:02X}..=0x{max:02X} and is not the broadcast or host address"
            ),
            EncodeError::Unaddressed { address } => write!(
                f,
                "the protocol's frames carry no address: give address 0, not 0x{address:02X}"
            ),
            EncodeError::BroadcastNotAccepted { message, address } => write!(
                f,
                "{} does not accept the broadcast address 0x{address:02X}",
                message.name
            ),
            EncodeError::Optional {
                field,
                condition,
                given: true,
            } => write!(
                f,
                "value given for {field}, which is present only when {condition}"
            ),
            EncodeError::Optional {
                field,
                condition,
                given: false,
            } => write!(
                f,
                "no value given for field {field}, which is present when {condition}"
            ),
            EncodeError::HoldsTerminator {
                field,
                index,
                terminator,
            } => write!(
                f,
                "{field} holds its terminator 0x{terminator:02X} (character {index}), which would end it there"
            ),
            EncodeError::HoldsEnd { field, offset, end } => write!(
                f,
                "{field} would put the end bytes {} at offset {offset}, which would end the frame there",
                HexBytes(end)
            ),
        }
    }
}

impl core::error::Error for EncodeError {}

/// 8-bit sum of `bytes`, modulo 256.
///
/// Frames are short, and the length of the one being decoded is known only at run time: up to
/// 8 bytes the sum is a chain of adds, each behind a test of the length, which the compiler
/// unrolls in full (about three instructions a byte). A loop over a run-time length is unrolled
/// by eight with a remainder loop, about four instructions a byte plus a dozen to set up: UB2
/// decode took 103.5 instructions per frame that way, 98.5 with the chain, and 101.4 with a
/// second chain for bytes 9 to 16 (`benches/icount.sh`).
#[inline]
pub fn sum8(bytes: &[u8]) -> u8 {
    if bytes.len() <= 8 {
        return sum8_upto8(bytes);
    }
    sum8_bytes(bytes)
}

/// [`sum8`] of at most 8 bytes, as a chain the compiler unrolls.
#[inline(always)]
fn sum8_upto8(bytes: &[u8]) -> u8 {
    let mut s = 0u8;
    for i in 0..8 {
        let Some(b) = bytes.get(i) else { break };
        s = s.wrapping_add(*b);
    }
    s
}

/// [`sum8`] as a plain loop: for long inputs, and for a length known at compile time (the
/// encoders' `seal_sum8`, where it folds into the bytes written before it).
#[inline]
pub(crate) fn sum8_bytes(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b))
}

/// `x` rounded to the nearest integer, ties away from zero; `None` if not finite or beyond `i64`.
/// (`f64::round` lives in std; this crate is `no_std`.) Public only for generated code.
#[doc(hidden)]
pub fn round(x: f64) -> Option<i64> {
    if !x.is_finite() || x.abs() >= 9.0e18 {
        return None;
    }
    let t = x as i64; // truncates toward zero
    let frac = x - t as f64;
    Some(if frac >= 0.5 {
        t + 1
    } else if frac <= -0.5 {
        t - 1
    } else {
        t
    })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::{sum8, sum8_bytes, DecodeError, EncodeError, FieldDesc, MessageDesc};
    use std::string::ToString;

    static READ: MessageDesc = MessageDesc::new("read", 0x4072, 2, &[6, 8]);
    static PING: MessageDesc = MessageDesc::new("ping", 0, 0, &[4]);

    /// A refusal is a few words: the names and numbers the spec fixes are in the `&'static`
    /// descriptors it points at, so a `Result` carrying one stays small to build and to move
    /// (88 bytes on a 64-bit target before the descriptors, 56 now: the largest variant is
    /// `BadCount`, whose `CountRule` carries a relation's words).
    #[test]
    fn a_decode_error_is_small() {
        let size = core::mem::size_of::<DecodeError>();
        assert!(size <= 56, "DecodeError is {size} bytes");
        assert!(core::mem::size_of::<super::MessageNames>() <= 40);
    }

    static QUANTITY: FieldDesc = FieldDesc::new("read_coils", "quantity");
    static VALUES: FieldDesc = FieldDesc::new("write", "values");

    /// A refusal that points at a field's descriptor names the field as `message.field`, and
    /// one about a list's count field names the list's message and the list.
    #[test]
    fn field_refusals_read_their_descriptor() {
        let e = DecodeError::OutOfRange {
            field: &QUANTITY,
            offset: 4,
            found: 0,
            min: 1,
            max: 2000,
            kind: super::NumKind::Int,
        };
        assert_eq!(
            e.to_string(),
            "read_coils.quantity at offset 4 is 0, outside its range 1..=2000"
        );
        let e = DecodeError::ByteCount {
            list: &VALUES,
            field: "byte_count",
            offset: 6,
            expected: 4,
            found: 6,
        };
        assert_eq!(
            e.to_string(),
            "invalid value for write.byte_count at offset 6: must be the bytes of values (4), found 6"
        );
        let e = DecodeError::BadWidth {
            list: &VALUES,
            field: "data_length",
            offset: 7,
            found: 0,
            most: 4,
        };
        assert_eq!(
            e.to_string(),
            "write.data_length at offset 7 is 0: each record's last field takes 1..=4 bytes"
        );
    }

    /// A refusal that points at a message's descriptor says what the descriptor holds, in the
    /// interpreter's words: every length of the code, the code at its width.
    #[test]
    fn refusals_read_their_descriptor() {
        let e = DecodeError::WrongLength {
            message: &READ,
            found: 7,
            less: 0,
        };
        assert_eq!(
            e.to_string(),
            "wrong length for read: expected 6 or 8 bytes, found 7"
        );
        let e = DecodeError::BroadcastNotAccepted {
            message: &READ,
            address: 0,
        };
        assert_eq!(
            e.to_string(),
            "read (code 0x4072) does not accept the broadcast address 0x00"
        );
        let e = DecodeError::BroadcastNotAccepted {
            message: &PING,
            address: 0xFE,
        };
        assert_eq!(
            e.to_string(),
            "ping (no code) does not accept the broadcast address 0xFE"
        );
        let e = EncodeError::BroadcastNotAccepted {
            message: &PING,
            address: 0xFE,
        };
        assert_eq!(
            e.to_string(),
            "ping does not accept the broadcast address 0xFE"
        );
    }

    /// The chain for short inputs and the loop for long ones sum alike, at every length up to
    /// 40, for bytes that carry on every add (all 0xFF), none and a mix.
    #[test]
    fn sum8_chain_equals_loop() {
        let mut mixed = [0u8; 40];
        for (i, b) in mixed.iter_mut().enumerate() {
            *b = (i as u8).wrapping_mul(97).wrapping_add(13);
        }
        for bytes in [[0xFFu8; 40], [0u8; 40], mixed] {
            for start in 0..3 {
                for end in start..=bytes.len() {
                    let s = &bytes[start..end];
                    assert_eq!(sum8(s), sum8_bytes(s), "bytes {start}..{end} of {bytes:?}");
                }
            }
        }
        assert_eq!(sum8(&[0xFF; 8]), 0xF8);
        assert_eq!(sum8(&[0x80, 0x80, 0x01, 0x02, 0x03]), 0x06);
    }
}
