//! The interpreter: decode and encode any frame straight from the IR, at run time.
//!
//! It is the independent oracle the generated code is tested and fuzzed against, the engine that
//! replays every example during validation, and what the CLI uses for a spec given at run time.
//! It never panics: every index is checked, every length compared before it is used.
//! Where each part of a frame sits is read from the IR ([`crate::ir::Message::layout`],
//! [`crate::ir::Framing::head`]), resolved once by the validator; nothing here lays out a frame.

use std::borrow::Cow;
use std::fmt;

use crate::checksum;
use crate::escape;
use crate::ir::{
    BitField, ByteOrder, Count, Direction, Field, FieldType, Follows, FrameLayout, LengthRule,
    Message, MessageRef, Packed, Protocol,
};
use crate::number::{swap_index, Num, NumKind};

/// A field's raw wire value: an integer (sign-extended where the field is signed) or text bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Raw {
    Int(i64),
    Text(Vec<u8>),
    /// The elements of a repeated field (bits as 0 or 1).
    List(Vec<i64>),
    /// The elements of a repeated record (`type: record`): each record's raw values, one per
    /// field of the record in its order.
    Records(Vec<Vec<i64>>),
}

impl Raw {
    /// How many elements a repeated field's value holds (`None`: not a list).
    pub fn elements(&self) -> Option<usize> {
        match self {
            Raw::List(l) => Some(l.len()),
            Raw::Records(r) => Some(r.len()),
            Raw::Int(_) | Raw::Text(_) => None,
        }
    }
}

/// One named value of a decoded frame; packed words appear as their sub-fields. A decoded
/// frame borrows its names from the spec (`'p`); values given to [`encode`] may own theirs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Value<'p> {
    pub name: Cow<'p, str>,
    pub raw: Raw,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame<'p> {
    pub message: MessageRef,
    pub address: u8,
    pub values: Vec<Value<'p>>,
}

impl Frame<'_> {
    /// The frame with names of its own, borrowing nothing.
    pub fn into_owned(self) -> Frame<'static> {
        Frame {
            message: self.message,
            address: self.address,
            values: self
                .values
                .into_iter()
                .map(|v| Value {
                    name: Cow::Owned(v.name.into_owned()),
                    raw: v.raw,
                })
                .collect(),
        }
    }

    pub fn get(&self, name: &str) -> Option<&Raw> {
        self.values.iter().find(|v| v.name == name).map(|v| &v.raw)
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DecodeError {
    /// Fewer bytes than the shortest frame that could start like this one.
    Truncated { needed: usize, found: usize },
    BadStart {
        offset: usize,
        expected: u8,
        found: u8,
    },
    /// A byte of the end bytes after the checksum is not what the spec says.
    BadEnd {
        offset: usize,
        expected: u8,
        found: u8,
    },
    ChecksumMismatch {
        offset: usize,
        expected: u64,
        found: u64,
        width: u8,
    },
    /// A reply whose checksum (at `offset`) takes in its request's bytes, decoded without
    /// the request: its checksum cannot be checked (`checksum_over_request`).
    NeedsRequest { message: String, offset: usize },
    UnknownCode {
        offset: usize,
        code: Vec<u8>,
        /// The one direction the frame was decoded as, if only one.
        direction: Option<Direction>,
    },
    WrongLength {
        message: String,
        expected: Vec<usize>,
        found: usize,
    },
    ConstantMismatch {
        message: String,
        field: String,
        offset: usize,
        expected: u64,
        found: u64,
    },
    /// A BCD field holds a nibble above 9: its bytes as read, `found`.
    NotBcd {
        message: String,
        field: String,
        offset: usize,
        found: u64,
    },
    NotEqual {
        message: String,
        field: String,
        offset: usize,
        other: String,
        expected: i64,
        found: i64,
    },
    /// Several messages fit the bytes; only the request they answer can tell them apart.
    Ambiguous { candidates: Vec<String> },
    /// More bytes than the protocol's longest frame (of the directions decoded), refused for
    /// its length before anything else.
    TooLong { max: usize, found: usize },
    /// A field's raw value lies outside its spec `range` and is none of its special values.
    OutOfRange {
        message: String,
        field: String,
        offset: usize,
        found: i64,
        min: i64,
        max: i64,
        /// How the three raw values read as numbers (the bits of a `u64` or a float).
        kind: NumKind,
    },
    /// An address outside the device range that is neither the broadcast nor the host address.
    BadAddress {
        offset: usize,
        found: u8,
        min: u8,
        max: u8,
    },
    /// A request to the broadcast address for a command that does not accept broadcast.
    BroadcastNotAccepted {
        message: String,
        code: Vec<u8>,
        address: u8,
    },
    /// The length field disagrees with the frame's length.
    LengthMismatch {
        offset: usize,
        expected: i64,
        found: i64,
    },
    /// A repeated field's count does not fit the frame: `found` elements where `expected`
    /// says how many may stand.
    BadCount {
        message: String,
        field: String,
        offset: usize,
        expected: String,
        found: i64,
    },
    /// The field `field` at `offset` gives each record's last field `found` bytes (`bytes:`),
    /// outside `1..=most`: the frame's records cannot be laid out.
    BadWidth {
        message: String,
        field: String,
        offset: usize,
        found: i64,
        most: usize,
    },
    /// Text up to a terminator (`repeat: {until}`) whose terminator is not among the
    /// `within` bytes from `offset` that the frame's length leaves it.
    NoTerminator {
        message: String,
        field: String,
        offset: usize,
        terminator: u8,
        within: usize,
    },
    /// Where end bytes alone delimit a frame ([`crate::ir::Framing::end_delimited`]), the
    /// list to the end `field` holds the end bytes `end` at `offset`, before the frame's own:
    /// a receiver ends the frame there.
    EndInside {
        message: String,
        field: String,
        offset: usize,
        end: Vec<u8>,
    },
    /// A count field says the elements of `list` take `found` bytes; the frame's length gives
    /// them `expected`.
    ByteCount {
        message: String,
        field: String,
        offset: usize,
        list: String,
        expected: i64,
        found: i64,
    },
    /// A field that follows from another (of the frame or of the request) does not.
    NotFollowing {
        message: String,
        field: String,
        offset: usize,
        rule: String,
        expected: i64,
        found: i64,
    },
    /// A reply the request does not get; `unasked` where `message` is a response the device
    /// sends on its own (`unasked: true`), a frame that came unasked rather than a wrong reply.
    NotAnAnswer {
        message: String,
        request: String,
        unasked: bool,
    },
    /// The escaped bytes break the protocol's escaping (`framing.escaping`); `offset` counts
    /// the bytes as they travel.
    BadEscape { offset: usize, fault: EscapeFault },
    /// A frame in the long form of its length field (`framing.length.long`) whose length the
    /// short form holds (at most `most`): encoders send it short, so strict decoding refuses
    /// it. `offset` is the length field's.
    NeedlessLong {
        offset: usize,
        length: i64,
        most: i64,
    },
}

/// What is wrong with escaped bytes ([`DecodeError::BadEscape`]); the runtime's
/// `EscapeFault` is the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    /// COBS: a 0x01 block ending the frame after a full block (encoding ends with the full one).
    CobsTrailing,
}

impl fmt::Display for EscapeFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EscapeFault::Escape { escape, found } => {
                write!(f, "0x{escape:02X} followed by 0x{found:02X}")
            }
            EscapeFault::Unescaped { found } => write!(f, "0x{found:02X} not escaped"),
            EscapeFault::Stuffing { expected, found } => {
                write!(f, "expected inserted byte 0x{expected:02X}, found ")?;
                match found {
                    Some(b) => write!(f, "0x{b:02X}"),
                    None => write!(f, "the frame's end"),
                }
            }
            EscapeFault::CobsZero => write!(f, "COBS block holds 0x00"),
            EscapeFault::CobsOverrun { code } => {
                write!(f, "COBS block 0x{code:02X} runs past the end byte")
            }
            EscapeFault::CobsEmpty => write!(f, "no COBS block before the end byte"),
            EscapeFault::CobsTrailing => {
                write!(f, "COBS block 0x01 after a full block ends the frame")
            }
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    let mut s = String::from("0x");
    for b in bytes {
        s.push_str(&format!("{b:02X}"));
    }
    s
}

/// `bytes` in hex, a space between: `FF FF FF`.
fn hex_spaced(bytes: &[u8]) -> String {
    let each: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    each.join(" ")
}

fn hex_width(v: u64, bits: u8) -> String {
    let digits = usize::from(bits.div_ceil(4)).max(2);
    format!("0x{v:0digits$X}")
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::Truncated { needed, found } => {
                write!(f, "truncated frame: need at least {needed} bytes, found {found}")
            }
            DecodeError::BadStart { offset, expected, found } => {
                write!(f, "bad start byte at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}")
            }
            DecodeError::BadEnd { offset, expected, found } => {
                write!(f, "bad end byte at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}")
            }
            DecodeError::ChecksumMismatch { offset, expected, found, width } => write!(
                f,
                "checksum mismatch at offset {offset}: expected {}, found {}",
                hex_width(*expected, *width),
                hex_width(*found, *width)
            ),
            DecodeError::NeedsRequest { message, offset } => write!(
                f,
                "{message}'s checksum at offset {offset} takes in its request's bytes: decode it as the reply to its request"
            ),
            DecodeError::UnknownCode {
                offset,
                code,
                direction,
            } => {
                let what = match direction {
                    Some(Direction::Response) => "response",
                    _ => "command",
                };
                write!(f, "unknown {what} code {} at offset {offset}", hex(code))
            }
            DecodeError::WrongLength { message, expected, found } => {
                let exp: Vec<String> = expected.iter().map(|n| n.to_string()).collect();
                write!(f, "wrong length for {message}: expected {} bytes, found {found}", exp.join(" or "))
            }
            DecodeError::ConstantMismatch { message, field, offset, expected, found } => write!(
                f,
                "invalid value for {message}.{field} at offset {offset}: expected 0x{expected:02X}, found 0x{found:02X}"
            ),
            DecodeError::NotBcd { message, field, offset, found } => write!(
                f,
                "invalid value for {message}.{field} at offset {offset}: 0x{found:02X} is not BCD (a digit above 9)"
            ),
            DecodeError::NotEqual { message, field, offset, other, expected, found } => write!(
                f,
                "invalid value for {message}.{field} at offset {offset}: must repeat {other} ({expected}), found {found}"
            ),
            DecodeError::Ambiguous { candidates } => write!(
                f,
                "ambiguous frame: could be {}; decode it together with the request it answers",
                candidates.join(" or ")
            ),
            DecodeError::TooLong { max, found } => write!(
                f,
                "frame too long: {found} bytes, the longest frame has {max}"
            ),
            DecodeError::OutOfRange { message, field, offset, found, min, max, kind } => write!(
                f,
                "{message}.{field} at offset {offset} is {}, outside its range {}..={}",
                Num(*kind, *found),
                Num(*kind, *min),
                Num(*kind, *max)
            ),
            DecodeError::BadAddress { offset, found, min, max } => write!(
                f,
                "address 0x{found:02X} at offset {offset} is outside the device range 0x{min:02X}..=0x{max:02X} and is not the broadcast or host address"
            ),
            DecodeError::BroadcastNotAccepted { message, code, address } => {
                if code.is_empty() {
                    write!(f, "{message} (no code)")?;
                } else {
                    write!(f, "{message} (code {})", hex(code))?;
                }
                write!(f, " does not accept the broadcast address 0x{address:02X}")
            }
            DecodeError::LengthMismatch { offset, expected, found } => write!(
                f,
                "length field at offset {offset} says {found}, the frame's length gives {expected}"
            ),
            DecodeError::BadCount { message, field, offset, expected, found } => write!(
                f,
                "{message}.{field} at offset {offset}: {found} elements, expected {expected}"
            ),
            DecodeError::BadWidth { message, field, offset, found, most } => write!(
                f,
                "{message}.{field} at offset {offset} is {found}: each record's last field takes 1..={most} bytes"
            ),
            DecodeError::NoTerminator { message, field, offset, terminator, within } => write!(
                f,
                "{message}.{field} at offset {offset}: no terminator 0x{terminator:02X} in the {within} bytes the frame's length leaves it"
            ),
            DecodeError::EndInside { message, field, offset, end } => write!(
                f,
                "{message}.{field} at offset {offset}: holds the end bytes {}, which end the frame there",
                hex_spaced(end)
            ),
            DecodeError::ByteCount { message, field, offset, list, expected, found } => write!(
                f,
                "invalid value for {message}.{field} at offset {offset}: must be the bytes of {list} ({expected}), found {found}"
            ),
            DecodeError::NotFollowing { message, field, offset, rule, expected, found } => write!(
                f,
                "invalid value for {message}.{field} at offset {offset}: must be {rule} ({expected}), found {found}"
            ),
            DecodeError::NotAnAnswer { message, request, unasked: false } => {
                write!(f, "{message} is not a reply {request} gets")
            }
            DecodeError::NotAnAnswer { message, request, unasked: true } => {
                write!(f, "{message} is sent unasked, not a reply {request} gets")
            }
            DecodeError::BadEscape { offset, fault } => {
                write!(f, "bad escape at offset {offset}: {fault}")
            }
            DecodeError::NeedlessLong { offset, length, most } => write!(
                f,
                "long length field at offset {offset} says {length}: lengths up to {most} take the short form"
            ),
        }
    }
}

impl std::error::Error for DecodeError {}

#[cfg(feature = "tools")]
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EncodeError {
    MissingValue {
        field: String,
    },
    /// A reply whose checksum takes in its request's bytes, encoded without the request
    /// (`checksum_over_request`).
    NeedsRequest {
        message: String,
    },
    UnknownValue {
        field: String,
    },
    OutOfRange {
        field: String,
        value: i64,
        min: i64,
        max: i64,
    },
    WrongTextLength {
        field: String,
        expected: usize,
        found: usize,
    },
    NotText {
        field: String,
    },
    NotNumber {
        field: String,
    },
    /// A value lies outside its field's spec `range` and is none of its special values.
    NotInRange {
        field: String,
        value: i64,
        min: i64,
        max: i64,
        /// How the three raw values read as numbers.
        kind: NumKind,
    },
    /// An address outside the device range that is neither the broadcast nor the host address.
    BadAddress {
        address: u8,
        min: u8,
        max: u8,
    },
    /// An address other than 0 for a protocol whose frames carry none.
    Unaddressed {
        address: u8,
    },
    /// The command does not accept the broadcast address.
    BroadcastNotAccepted {
        message: String,
        address: u8,
    },
    /// A value was given for a constant or repeated field and differs from what it must be.
    Fixed {
        field: String,
        expected: i64,
        found: i64,
    },
    /// A repeated field takes a list of numbers.
    NotList {
        field: String,
    },
    /// Text up to a terminator (`repeat: {until}`) whose characters hold the terminator (the
    /// `index`th): the frame would end it there.
    HoldsTerminator {
        field: String,
        index: usize,
        terminator: u8,
    },
    /// Where end bytes alone delimit a frame, the list to the end `field` would put the end
    /// bytes `end` at `offset` of the frame, before its own: a receiver would end the frame
    /// there.
    HoldsEnd {
        field: String,
        offset: usize,
        end: Vec<u8>,
    },
    /// A repeated field's list is longer or shorter than the spec allows.
    WrongCount {
        field: String,
        min: usize,
        max: usize,
        found: usize,
    },
    /// The values given do not make a frame the spec accepts (a count field that disagrees
    /// with its list, a field that does not follow its rule): what decoding it says.
    Inconsistent {
        reason: String,
    },
    /// An optional field (`present:`) given where its condition does not hold, or not given
    /// where it does: `condition` in words (`bit 0 of `flags` is set`).
    Optional {
        field: String,
        condition: String,
        given: bool,
    },
}

#[cfg(feature = "tools")]
impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EncodeError::MissingValue { field } => write!(f, "no value given for field {field}"),
            EncodeError::NeedsRequest { message } => write!(
                f,
                "{message}'s checksum takes in its request's bytes: encode it as the reply to its request"
            ),
            EncodeError::UnknownValue { field } => write!(
                f,
                "value given for {field}, which the message does not have"
            ),
            EncodeError::OutOfRange {
                field,
                value,
                min,
                max,
            } => {
                write!(
                    f,
                    "{field} = {value} does not fit the field ({min}..={max})"
                )
            }
            EncodeError::WrongTextLength {
                field,
                expected,
                found,
            } => {
                write!(
                    f,
                    "{field} takes exactly {expected} characters, got {found}"
                )
            }
            EncodeError::NotText { field } => write!(f, "{field} takes text"),
            EncodeError::NotNumber { field } => write!(f, "{field} takes a number"),
            EncodeError::Fixed {
                field,
                expected,
                found,
            } => write!(f, "{field} is fixed at {expected} in this message, got {found}"),
            EncodeError::NotInRange {
                field,
                value,
                min,
                max,
                kind,
            } => write!(
                f,
                "{field} = {} is outside its range {}..={}",
                Num(*kind, *value),
                Num(*kind, *min),
                Num(*kind, *max)
            ),
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
                "{message} does not accept the broadcast address 0x{address:02X}"
            ),
            EncodeError::NotList { field } => write!(f, "{field} takes a list of numbers"),
            EncodeError::HoldsTerminator { field, index, terminator } => write!(
                f,
                "{field} holds its terminator 0x{terminator:02X} (character {index}), which would end it there"
            ),
            EncodeError::HoldsEnd { field, offset, end } => write!(
                f,
                "{field} would put the end bytes {} at offset {offset}, which would end the frame there",
                hex_spaced(end)
            ),
            EncodeError::WrongCount { field, min, max, found } => write!(
                f,
                "{field} takes {min}..={max} elements, got {found}"
            ),
            EncodeError::Inconsistent { reason } => {
                write!(f, "the values do not make a valid frame: {reason}")
            }
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
        }
    }
}

#[cfg(feature = "tools")]
impl std::error::Error for EncodeError {}

/// Reads an unsigned integer of `bytes.len()` bytes.
pub fn read_uint(bytes: &[u8], order: ByteOrder) -> u64 {
    let fold = |acc: u64, b: &u8| (acc << 8) | u64::from(*b);
    // The widths most fields have without a loop.
    match (bytes, order) {
        (&[b], _) => u64::from(b),
        (&[a, b], ByteOrder::Big) => u64::from(u16::from_be_bytes([a, b])),
        (&[a, b], ByteOrder::Little) => u64::from(u16::from_le_bytes([a, b])),
        (_, ByteOrder::Big) => bytes.iter().fold(0, fold),
        (_, ByteOrder::Little) => bytes.iter().rev().fold(0, fold),
    }
}

/// Writes the low `out.len()` bytes of `v`.
pub fn write_uint(v: u64, out: &mut [u8], order: ByteOrder) {
    let n = out.len();
    for (i, slot) in out.iter_mut().enumerate() {
        let shift = 8 * match order {
            ByteOrder::Big => n - 1 - i,
            ByteOrder::Little => i,
        };
        *slot = if shift < 64 { (v >> shift) as u8 } else { 0 };
    }
}

/// A whole number field's bits from its bytes: [`read_uint`], its 16-bit words put back in
/// order first where they travel swapped.
pub fn read_number(f: &Field, bytes: &[u8]) -> u64 {
    let n = bytes.len();
    if !f.word_swapped || !(n == 4 || n == 8) {
        return read_uint(bytes, f.byte_order);
    }
    let mut b = [0u8; 8];
    for (i, slot) in b[..n].iter_mut().enumerate() {
        *slot = bytes[swap_index(i, n)];
    }
    read_uint(&b[..n], f.byte_order)
}

/// Writes a whole number field's bits: [`write_uint`], then its 16-bit words swapped where
/// the field says.
pub fn write_number(f: &Field, v: u64, out: &mut [u8]) {
    let n = out.len();
    if !f.word_swapped || !(n == 4 || n == 8) {
        return write_uint(v, out, f.byte_order);
    }
    let mut b = [0u8; 8];
    write_uint(v, &mut b[..n], f.byte_order);
    for (i, byte) in b[..n].iter().enumerate() {
        out[swap_index(i, n)] = *byte;
    }
}

pub(crate) fn sign_extend(v: u64, bits: u32) -> i64 {
    if bits == 0 || bits >= 64 {
        return v as i64;
    }
    let shift = 64 - bits;
    ((v << shift) as i64) >> shift
}

fn bit_value(container: u64, b: &BitField) -> i64 {
    let w = u32::from(b.width());
    let mask = if w >= 64 { u64::MAX } else { (1u64 << w) - 1 };
    let v = (container >> b.lsb) & mask;
    if b.signed {
        sign_extend(v, w)
    } else {
        v as i64
    }
}

/// The inclusive range of raw values a field of `bits` bits can hold.
pub fn raw_limits(bits: u32, signed: bool) -> (i64, i64) {
    match (signed, bits) {
        (_, 0) => (0, 0),
        (true, b) if b >= 64 => (i64::MIN, i64::MAX),
        (false, b) if b >= 63 => (0, i64::MAX),
        (true, b) => (-(1i64 << (b - 1)), (1i64 << (b - 1)) - 1),
        (false, b) => (0, (1i64 << b) - 1),
    }
}

/// Whether a frame may carry `address`: one in the device range, the broadcast address or the
/// host address (where the spec has them). Whether a command accepts the broadcast address is
/// [`broadcast_refused`].
pub fn address_allowed(p: &Protocol, address: u8) -> bool {
    let a = &p.framing.address;
    (a.min..=a.max).contains(&address) || a.broadcast == Some(address) || a.host == Some(address)
}

/// Whether `m` is a request for a command that does not accept the broadcast address and
/// `address` is that address.
pub fn broadcast_refused(p: &Protocol, m: &Message, address: u8) -> bool {
    m.direction == Direction::Request
        && p.framing.address.broadcast == Some(address)
        && !m.broadcast.as_ref().is_some_and(|b| b.accepted)
}

/// The spec range of a whole field (`bits` `None`) or a packed sub-field, and whether `raw`
/// lies outside it and is none of the field's special values: `Some((min, max))` if so.
pub fn range_violation(f: &Field, bits: Option<&BitField>, raw: i64) -> Option<(i64, i64)> {
    let (min, max) = match bits {
        Some(b) => b.range,
        None => f.range,
    }?;
    // The special values only for a value outside the range: most are inside.
    let special = || bits.is_none() && f.special.iter().any(|s| s.value == raw);
    let outside = match bits {
        Some(_) => !(min..=max).contains(&raw),
        None => f.outside(raw, (min, max)),
    };
    (outside && !special()).then_some((min, max))
}

/// What [`decode`] derives from the spec for the directions it decodes, before it looks at a
/// frame: no allocation, so a single decode pays only a pass over the messages.
#[derive(Debug, Clone, Copy)]
struct Limits {
    directions: &'static [Direction],
    longest_frame: usize,
    shortest: usize,
    /// The shortest frame with a checksum: a frame no message without one
    /// (`checksum: none`) is must be this long.
    shortest_checked: usize,
    min_code: usize,
    /// The length field of each direction decoded (in the order of `directions`), where the
    /// framing has one.
    length_rules: [Option<LengthRule>; 2],
}

impl Limits {
    fn of(p: &Protocol, direction: Option<Direction>) -> Limits {
        let directions: &'static [Direction] = match direction {
            Some(Direction::Request) => &[Direction::Request],
            Some(Direction::Response) => &[Direction::Response],
            None => &[Direction::Request, Direction::Response],
        };
        // One pass over the messages: the longest and shortest frames, and the shortest with
        // a checksum (the same where every message has one).
        let (mut longest_frame, mut shortest, mut checked) = (0, usize::MAX, usize::MAX);
        for m in directions.iter().flat_map(|d| p.framed(*d)) {
            let min = m.min_len();
            longest_frame = longest_frame.max(m.max_len);
            shortest = shortest.min(min);
            if !m.unchecked {
                checked = checked.min(min);
            }
        }
        Limits {
            directions,
            longest_frame,
            shortest: if shortest == usize::MAX { 0 } else { shortest },
            shortest_checked: match (checked, shortest) {
                // No message at all.
                (usize::MAX, usize::MAX) => 0,
                // Every message without a checksum.
                (usize::MAX, _) => shortest_head(p, directions),
                (checked, _) => checked,
            },
            min_code: directions
                .iter()
                .flat_map(|d| p.framing.direction(*d).code_lengths.iter().copied())
                .min()
                .unwrap_or(1),
            length_rules: [
                directions.first().and_then(|d| p.framing.length_rule(*d)),
                directions.get(1).and_then(|d| p.framing.length_rule(*d)),
            ],
        }
    }
}

/// The shortest head of a frame with a checksum of `directions` (its parts before the payload,
/// the checksum and the end bytes), as the generated frame checks take it: the shortest frame
/// with a checksum where every message of them travels without one (`checksum: none`).
fn shortest_head(p: &Protocol, directions: &[Direction]) -> usize {
    directions
        .iter()
        .map(|&d| {
            let code = p.framing.direction(d).code_lengths.iter().min();
            p.framing.head(d, code.copied().unwrap_or(0)).len
        })
        .min()
        .unwrap_or(0)
}

/// [`decode`] with everything it derives from the spec computed once, for decoding many
/// frames of one protocol (the stream decoder): the limits, and the messages of each frame
/// length in the order `decode` tries them. Decodes exactly as [`decode`] does, errors
/// included; build it from the protocol it decodes.
#[derive(Debug, Clone)]
pub struct Lookup {
    limits: Limits,
    /// The frame checksum, table-driven.
    checksum: checksum::Prepared,
    /// `by_len[n]`: the messages whose frames are `n` bytes long, by where their code sits
    /// and its first byte.
    by_len: Vec<Vec<ByFirst>>,
}

/// Messages of one frame length whose code sits at `code_at`, by the code's first byte: those
/// with first byte `b` are `refs[starts[b]..starts[b + 1]]`; `starts[256]` is `refs.len()`.
/// Messages without a code are `codeless`.
#[derive(Debug, Clone)]
struct ByFirst {
    code_at: usize,
    starts: Vec<usize>,
    refs: Vec<MessageRef>,
    codeless: Vec<MessageRef>,
}

impl ByFirst {
    /// The messages whose code's first byte is the byte of `wire` where it sits.
    fn get(&self, wire: &[u8]) -> &[MessageRef] {
        let (from, to) = match wire.get(self.code_at) {
            Some(&b) => (self.starts[usize::from(b)], self.starts[usize::from(b) + 1]),
            None => (0, 0),
        };
        self.refs.get(from..to).unwrap_or_default()
    }

    fn codeless(&self) -> &[MessageRef] {
        &self.codeless
    }
}

impl Lookup {
    /// The lookup of `p` for `direction` (`None`: both).
    pub fn new(p: &Protocol, direction: Option<Direction>) -> Lookup {
        let limits = Limits::of(p, direction);
        // (frame length, code offset, first code byte or 256 for none, message), sorted.
        let mut all = Vec::new();
        for &direction in limits.directions {
            for (index, m) in p.framed(direction).iter().enumerate() {
                let first = m.code.first().map_or(256, |&b| usize::from(b));
                let r = MessageRef { direction, index };
                // A variable message under every length it can have (`decode_in` checks
                // which its frame has).
                let lens = if m.is_variable() {
                    m.layout.len..=m.max_len
                } else {
                    let len = p.frame_len(m);
                    len..=len
                };
                for len in lens {
                    all.push((len, m.layout.code, first, r));
                }
            }
        }
        all.sort_by_key(|&(len, at, first, r)| (len, at, first, r.direction as u8, r.index));
        let mut by_len: Vec<Vec<ByFirst>> = vec![Vec::new(); limits.longest_frame + 1];
        for (len, at, first, r) in all {
            let Some(groups) = by_len.get_mut(len) else {
                continue;
            };
            if groups.last().map_or(true, |g: &ByFirst| g.code_at != at) {
                groups.push(ByFirst {
                    code_at: at,
                    starts: vec![0; 257],
                    refs: Vec::new(),
                    codeless: Vec::new(),
                });
            }
            if let Some(g) = groups.last_mut() {
                if first == 256 {
                    g.codeless.push(r);
                    continue;
                }
                g.refs.push(r);
                // Messages sorted by first byte: every later byte starts after this one.
                for s in g.starts.iter_mut().skip(first + 1) {
                    *s = g.refs.len();
                }
            }
        }
        Lookup {
            limits,
            checksum: checksum::Prepared::new(&p.framing.checksum.algorithm),
            by_len,
        }
    }

    /// Decodes a frame of `p` (the protocol the lookup was built from) as [`decode`] does.
    pub fn decode<'p>(
        &self,
        p: &'p Protocol,
        reply_to: Option<usize>,
        wire: &[u8],
    ) -> Result<Frame<'p>, DecodeError> {
        decode_in(
            p,
            self.limits,
            Some(self),
            (reply_to, false),
            None,
            wire,
            &mut Spare::default(),
        )
    }

    /// [`Self::decode`] with the bytes the request's checksum covers ([`decode_with`]).
    pub fn decode_with<'p>(
        &self,
        p: &'p Protocol,
        reply_to: Option<usize>,
        covered: Option<&[u8]>,
        wire: &[u8],
    ) -> Result<Frame<'p>, DecodeError> {
        decode_in(
            p,
            self.limits,
            Some(self),
            (reply_to, false),
            covered,
            wire,
            &mut Spare::default(),
        )
    }

    /// Decodes a frame as the stream decoder pairs a response with the request before it:
    /// as [`decode`] without `request`, and where that is [`DecodeError::Ambiguous`], as with
    /// `request` if that settles it; otherwise the ambiguity without it. The same as decoding
    /// twice, with the fields decoded once.
    pub fn decode_paired<'p>(
        &self,
        p: &'p Protocol,
        request: Option<usize>,
        wire: &[u8],
    ) -> Result<Frame<'p>, DecodeError> {
        self.decode_paired_reusing(p, request, None, wire, &mut Spare::default())
    }

    /// [`Self::decode_paired`] in `spare`'s memory: the frame's values built in
    /// [`Spare::values`] (taken from it only when a frame decodes), for a caller that gives
    /// back the frames it is done with, and the decode's own lists kept there.
    /// `covered`: the bytes the request's checksum covers ([`crate::ir::Protocol::checksum_span`] of its
    /// frame), which the checksum of a reply that takes them in runs over first.
    pub fn decode_paired_reusing<'p>(
        &self,
        p: &'p Protocol,
        request: Option<usize>,
        covered: Option<&[u8]>,
        wire: &[u8],
        spare: &mut Spare<'p>,
    ) -> Result<Frame<'p>, DecodeError> {
        decode_in(
            p,
            self.limits,
            Some(self),
            (request, true),
            covered,
            wire,
            spare,
        )
    }
}

/// Memory a caller decoding many frames lends to [`Lookup::decode_paired_reusing`], so that a
/// decode allocates nothing once it has grown.
#[derive(Debug, Clone, Default)]
pub struct Spare<'p> {
    /// Where the next decoded frame's values are built; taken by the frame (left empty,
    /// without capacity) when one decodes.
    pub values: Vec<Value<'p>>,
    /// The messages whose fields a frame fits, where several share its code and length.
    fitting: Vec<MessageRef>,
}

/// Decodes a frame. `direction` limits the search; `reply_to` (a command index) settles
/// responses that only the request they answer can tell apart. To decode many frames of one
/// protocol, build a [`Lookup`] once.
pub fn decode<'p>(
    p: &'p Protocol,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    decode_with(p, direction, reply_to, None, wire)
}

/// [`decode`] with the bytes the request's checksum covers (`covered`, [`crate::ir::Protocol::checksum_span`]
/// of its frame): the checksum of a reply that takes in its request's bytes
/// (`checksum_over_request`) runs over them first; without them such a reply is refused
/// ([`DecodeError::NeedsRequest`]).
pub fn decode_with<'p>(
    p: &'p Protocol,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    let limits = Limits::of(p, direction);
    decode_in(
        p,
        limits,
        None,
        (reply_to, false),
        covered,
        wire,
        &mut Spare::default(),
    )
}

/// The decode every entry point shares: `wire` unescaped (where the framing escapes), decoded
/// by [`decode_plain`], and an error located on the bytes as they travelled.
fn decode_in<'p>(
    p: &'p Protocol,
    limits: Limits,
    lookup: Option<&Lookup>,
    reply_to: (Option<usize>, bool),
    covered: Option<&[u8]>,
    wire: &[u8],
    spare: &mut Spare<'p>,
) -> Result<Frame<'p>, DecodeError> {
    // A constant whole frame is its bytes exactly; no framed frame begins as one does.
    for &d in limits.directions {
        if let Some(message) = p.constant_of(d, wire) {
            return Ok(constant_frame(message));
        }
    }
    // Offsets count from the frame's first byte, after any preamble.
    let wire = p.framing.after_preamble(wire);
    // Where the end bytes (and so the escaped bytes) differ by direction (responses without
    // start or end bytes beside flagged requests), a frame is unescaped and decoded as each
    // direction on its own: the one it decodes as, ambiguous where it decodes both ways, else
    // refused for the reason that got further (the first direction's on a tie).
    let d = match limits.directions {
        [d] => *d,
        [a, b] if p.framing.end_by_direction() => {
            let mut one = |d: Direction| {
                decode_in(
                    p,
                    Limits::of(p, Some(d)),
                    lookup,
                    reply_to,
                    covered,
                    wire,
                    spare,
                )
            };
            return match (one(*a), one(*b)) {
                (Ok(x), Ok(y)) => Err(DecodeError::Ambiguous {
                    candidates: vec![
                        p.message(x.message).name.clone(),
                        p.message(y.message).name.clone(),
                    ],
                }),
                (Ok(x), Err(_)) | (Err(_), Ok(x)) => Ok(x),
                // A direction refused at its start bytes, then one refused at an escape, got
                // less far than one whose frame unescaped and was checked.
                (Err(e0), Err(e1)) => {
                    let rank = |e: &DecodeError| match e {
                        DecodeError::BadStart { .. } => 0,
                        DecodeError::BadEscape { .. } => 1,
                        e => 2 + progress(e),
                    };
                    Err(if rank(&e1) > rank(&e0) { e1 } else { e0 })
                }
            };
        }
        _ => Direction::Request,
    };
    let un = escape::unescape_as(p, d, wire)?;
    // A frame of either form of a length field the start byte chooses, in the IR's layout.
    let c = crate::long::canonical(p, &un.frame)?;
    decode_plain(p, limits, lookup, (reply_to, covered), &c.frame, spare)
        .map_err(|e| un.locate(c.locate(e)))
}

/// Decodes an unescaped frame.
fn decode_plain<'p>(
    p: &'p Protocol,
    limits: Limits,
    lookup: Option<&Lookup>,
    (reply_to, covered): ((Option<usize>, bool), Option<&[u8]>),
    wire: &[u8],
    spare: &mut Spare<'p>,
) -> Result<Frame<'p>, DecodeError> {
    let Limits {
        directions,
        longest_frame,
        shortest_checked,
        min_code,
        ..
    } = limits;
    if wire.len() > longest_frame {
        return Err(DecodeError::TooLong {
            max: longest_frame,
            found: wire.len(),
        });
    }
    let d0 = directions.first().copied().unwrap_or(Direction::Request);
    let first = p.framing.head(d0, min_code);
    // Decoded both ways, a frame of the second direction has its parts where that
    // direction's layout puts them (`framing.layout: {request, response}`).
    let second = match directions {
        [_, b] => p.framing.head(*b, min_code),
        _ => first,
    };
    // Start bytes that differ by direction (or sit where each direction's layout puts them)
    // tell the frame's direction.
    let (sync0, sync1) = match directions {
        [a, b] if p.framing.sync_by_direction() || p.framing.layout_by_direction() => {
            let (x, y) = (
                check_sync(p, *a, &first, wire),
                check_sync(p, *b, &second, wire),
            );
            if let (Err(e), Err(_)) = (&x, &y) {
                return Err(e.clone());
            }
            (x.is_ok(), y.is_ok())
        }
        _ => {
            check_sync(p, d0, &first, wire)?;
            (true, true)
        }
    };
    // A message without a checksum (`checksum: none`), by its code and length: it has none
    // to check, and may be shorter than any frame with one.
    let unchecked = p.unchecked(directions, wire).is_some();
    if !unchecked && wire.len() < shortest_checked.max(first.len.min(second.len)) {
        return Err(DecodeError::Truncated {
            needed: shortest_checked,
            found: wire.len(),
        });
    }
    // Each direction's end bytes are the same wherever a frame is decoded both ways (where
    // they differ, `decode_in` decodes it as each direction on its own).
    check_end(p, d0, wire)?;
    // A direction refused for its checksum or address alone is set aside with its refusal:
    // where the other is refused too, the refusal that got further is reported
    // ([`progress`], the first direction's on a tie), as the generated stream decoder, which
    // decodes each direction on its own, reports it.
    let mut set_aside: Option<(bool, DecodeError)> = None;
    let (sync0, sync1) = match p.over_request(directions, wire) {
        _ if unchecked => (sync0, sync1),
        // A reply whose checksum takes in its request's bytes, by its code and length, whose
        // code and length a request may have too (RoboClaw's code-less replies): decoded both
        // ways, each direction is checked by its own rule.
        Some((m, from)) if directions.len() == 2 && p.request_fits(wire) => {
            let over = check_over_request(p, m, from, covered, wire);
            let own = check_checksum(p, Direction::Request, lookup.map(|l| &l.checksum), wire);
            let (x, y) = if directions[0] == Direction::Response {
                (over, own)
            } else {
                (own, over)
            };
            set_aside_refused(sync0, sync1, x, y, &mut set_aside)?
        }
        // A reply whose checksum takes in its request's bytes, by its code and length.
        Some((m, from)) => {
            check_over_request(p, m, from, covered, wire)?;
            (sync0, sync1)
        }
        // Each direction's checksum covers from its own first byte (`covers_from: {request,
        // response}`): decoded both ways, each direction is checked at its own.
        None if directions.len() == 2 && p.framing.checksum.covers_by_direction() => {
            let prepared = lookup.map(|l| &l.checksum);
            let (x, y) = (
                check_checksum(p, directions[0], prepared, wire),
                check_checksum(p, directions[1], prepared, wire),
            );
            set_aside_refused(sync0, sync1, x, y, &mut set_aside)?
        }
        None => {
            check_checksum(p, d0, lookup.map(|l| &l.checksum), wire)?;
            (sync0, sync1)
        }
    };
    // Where the address sits (or whether frames carry one) differs by direction, each
    // direction the frame may be is checked at its own; it is refused where none agrees.
    let (sync0, sync1) = if first.address != second.address && set_aside.is_none() {
        let (x, y) = (
            check_address(p, first.address, wire),
            check_address(p, second.address, wire),
        );
        set_aside_refused(sync0, sync1, x, y, &mut set_aside)?
    } else if first.address != second.address {
        // One direction is set aside for its checksum: the other's address decides.
        let (kept, at) = if sync0 {
            (true, first.address)
        } else {
            (false, second.address)
        };
        if let Err(e) = check_address(p, at, wire) {
            let Some((first_set_aside, a)) = set_aside.take() else {
                return Err(e);
            };
            // Both refused: the refusal that got further, the first direction's on a tie.
            let (e0, e1) = if first_set_aside { (a, e) } else { (e, a) };
            return Err(if progress(&e1) > progress(&e0) {
                e1
            } else {
                e0
            });
        }
        (sync0 && kept, sync1 && !kept)
    } else {
        if let Err(e) = check_address(p, first.address, wire) {
            // The first direction set aside for its checksum got as far: its refusal.
            return Err(match set_aside.take() {
                Some((true, a)) if progress(&a) >= progress(&e) => a,
                _ => e,
            });
        }
        (sync0, sync1)
    };
    let decoded = decode_kept(
        p,
        limits,
        lookup,
        reply_to,
        wire,
        spare,
        (sync0, sync1, unchecked),
    );
    match (decoded, set_aside) {
        // A frame the other direction's messages share is ambiguous, not refused.
        (Err(e @ DecodeError::Ambiguous { .. }), _) => Err(e),
        (Err(e), Some((true, a))) => Err(if progress(&e) > progress(&a) { e } else { a }),
        (Err(e), Some((false, a))) => Err(if progress(&a) > progress(&e) { a } else { e }),
        (decoded, _) => decoded,
    }
}

/// The directions `(sync0, sync1)` still kept after a check made for each (`x` the first's,
/// `y` the second's): a kept direction refused is set aside with its refusal (where none is
/// yet); where both are refused, the first kept one's refusal.
fn set_aside_refused(
    sync0: bool,
    sync1: bool,
    x: Result<(), DecodeError>,
    y: Result<(), DecodeError>,
    set_aside: &mut Option<(bool, DecodeError)>,
) -> Result<(bool, bool), DecodeError> {
    match (sync0 && x.is_ok(), sync1 && y.is_ok()) {
        (false, false) => {
            if sync0 {
                x?;
            }
            y?;
            Ok((false, false))
        }
        kept => {
            if let (true, Err(e)) = (sync0, x) {
                *set_aside = Some((true, e));
            } else if let (true, Err(e)) = (sync1, y) {
                *set_aside = Some((false, e));
            }
            Ok(kept)
        }
    }
}

/// How far a frame decoded as one direction got before `e`: the order of the runtime's
/// `DecodeError::progress` (0, no message of the direction has its code, its length field or
/// its length; 1, too short; 2, a code whose messages have other lengths or counts; 3, a
/// message's own refusal).
fn progress(e: &DecodeError) -> u8 {
    match e {
        DecodeError::UnknownCode { .. }
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

/// [`decode_plain`] after the checks every frame takes (length, start, end, checksum,
/// address), of the directions `(sync0, sync1)` still kept.
fn decode_kept<'p>(
    p: &'p Protocol,
    limits: Limits,
    lookup: Option<&Lookup>,
    reply_to: (Option<usize>, bool),
    wire: &[u8],
    spare: &mut Spare<'p>,
    (sync0, sync1, unchecked): (bool, bool, bool),
) -> Result<Frame<'p>, DecodeError> {
    let Limits {
        directions,
        shortest,
        min_code,
        length_rules: [rule0, rule1],
        ..
    } = limits;
    let d0 = directions.first().copied().unwrap_or(Direction::Request);
    // The checksum covers the payload as it travelled; the fields are read with its transform
    // undone (`framing.transform`).
    let plain = p.framing.untransformed(wire);
    let wire: &[u8] = &plain;
    // Decoded both ways where the directions' length fields differ (each after a code of its
    // own length), the frame is of a direction whose length field it agrees with.
    let (keep0, keep1) = match directions {
        [_, _] if rule0 != rule1 => {
            let (a, b) = (
                check_length_rule(p, rule0, wire),
                check_length_rule(p, rule1, wire),
            );
            if let (Err(e), Err(_)) = (&a, &b) {
                return Err(e.clone());
            }
            (a.is_ok(), b.is_ok())
        }
        _ => {
            check_length_rule(p, rule0, wire)?;
            (true, true)
        }
    };
    let (keep0, keep1) = (keep0 && sync0, keep1 && sync1);
    let kept = |d: Direction| {
        if Some(&d) == directions.first() {
            keep0
        } else {
            keep1
        }
    };

    // A frame without a checksum (`checksum: none`) has its code up to its end.
    let clen = |d: Direction| {
        if unchecked {
            0
        } else {
            p.framing.trailer_len_of(d)
        }
    };
    let code_fits = |r: &MessageRef| {
        let m = p.message(*r);
        let o = m.layout;
        // Byte by byte: a code is a byte or two, shorter than a call to compare slices. It
        // lies before the checksum: a checksum byte is no code byte.
        kept(r.direction)
            && o.code + m.code.len() + clen(r.direction) <= wire.len()
            && (m.code.iter().enumerate()).all(|(i, c)| wire.get(o.code + i) == Some(c))
    };
    // In the lookup, a variable message stands under every length it can have: its frame
    // must have one its length or count field agrees with.
    let looked_up = |r: &MessageRef| {
        let m = p.message(*r);
        code_fits(r) && (!m.is_variable() || fits_len(p, m, wire))
    };
    // The messages of this length whose code fits, in the order of the scan below: when
    // there are any, they are what the scan would find.
    if let Some(groups) = lookup.and_then(|l| l.by_len.get(wire.len())) {
        // One group holds the coded messages (by direction) before the code-less ones: the
        // order of `coded_first` where the frame is decoded one way or nothing is code-less.
        let one_way = directions.len() == 1;
        if let [g] = groups.as_slice() {
            if one_way || g.codeless.is_empty() {
                let fits = |r: &MessageRef| looked_up(r);
                let mut found = g
                    .get(wire)
                    .iter()
                    .chain(g.codeless())
                    .copied()
                    .filter(fits)
                    .peekable();
                if found.peek().is_some() {
                    return decide(p, found, shortest, reply_to, wire, spare);
                }
            }
        }
        let mut by_len: Vec<MessageRef> = Vec::new();
        for g in groups {
            by_len.extend(
                g.get(wire)
                    .iter()
                    .chain(g.codeless())
                    .filter(|r| looked_up(r)),
            );
        }
        if groups.len() > 1 || !one_way {
            by_len.sort_by_key(|r| coded_first(p, r));
        }
        if !by_len.is_empty() {
            return decide(p, by_len, shortest, reply_to, wire, spare);
        }
    }

    // Messages whose code matches the bytes where the code sits, in the order they are tried.
    let mut by_code: Vec<MessageRef> = Vec::new();
    for &direction in directions {
        for index in 0..p.framed(direction).len() {
            let r = MessageRef { direction, index };
            if code_fits(&r) {
                by_code.push(r);
            }
        }
    }
    by_code.sort_by_key(|r| coded_first(p, r));
    if by_code.is_empty() {
        let o = p.framing.head(d0, min_code);
        let longest = directions
            .iter()
            .flat_map(|d| p.framing.direction(*d).code_lengths.iter().copied())
            .max()
            .unwrap_or(1);
        let end = (o.code + longest).min(wire.len().saturating_sub(clen(d0)));
        let code = wire.get(o.code..end.max(o.code)).unwrap_or(&[]).to_vec();
        return Err(DecodeError::UnknownCode {
            offset: o.code,
            code,
            direction: match directions {
                [d] => Some(*d),
                _ => None,
            },
        });
    }
    let by_len: Vec<MessageRef> = by_code
        .iter()
        .copied()
        .filter(|r| fits_len(p, p.message(*r), wire))
        .collect();
    if by_len.is_empty() {
        // A message with a repeated field that could be this long: say what in it disagrees.
        let counted = by_code.iter().find_map(|r| {
            let m = p.message(*r);
            // Too long for its bounds too: the count says what is wrong.
            let fits = m.is_variable() && wire.len() >= m.layout.len;
            fits.then(|| element_count(p, m, wire).err()).flatten()
        });
        if let Some(e) = counted {
            return Err(e);
        }
        let mut expected: Vec<usize> = by_code.iter().map(|r| p.frame_len(p.message(*r))).collect();
        expected.sort_unstable();
        expected.dedup();
        let name = p.message(by_code[0]).name.clone();
        if expected.iter().all(|&n| n > wire.len()) {
            return Err(DecodeError::Truncated {
                needed: expected[0],
                found: wire.len(),
            });
        }
        return Err(DecodeError::WrongLength {
            message: name,
            expected,
            found: wire.len(),
        });
    }
    decide(p, by_len, shortest, reply_to, wire, spare)
}

/// The order messages whose code fits a frame are tried in, and the first refusal among them
/// reported: by direction, then the messages the frame's code names before the code-less ones
/// (the empty code fits every frame, so a coded message's refusal says more), then spec order.
/// The generated `dispatch` tries them in this order too.
fn coded_first(p: &Protocol, r: &MessageRef) -> (u8, bool, usize) {
    (r.direction as u8, p.message(*r).code.is_empty(), r.index)
}

/// The frame among the messages of the frame's code and length (`by_len`, not empty) whose
/// fields decode, settled by `reply_to` where several do.
///
/// `paired`: as the stream decoder pairs a response with the request before it, a `reply_to`
/// that settles nothing leaves the frame ambiguous among every candidate (otherwise among
/// those answering `reply_to`, or an error if none does).
fn decide<'p>(
    p: &'p Protocol,
    by_len: impl IntoIterator<Item = MessageRef>,
    shortest: usize,
    (reply_to, paired): (Option<usize>, bool),
    wire: &[u8],
    spare: &mut Spare<'p>,
) -> Result<Frame<'p>, DecodeError> {
    let mut by_len = by_len.into_iter();
    let first = by_len.next();
    let second = by_len.next();
    // One message of this code and length (the common case): it fits or its misfit is the
    // error, as below, without a list.
    if let (Some(r), None) = (first, second) {
        let m = p.message(r);
        return match misfit(p, m, wire) {
            None => Ok(Frame {
                message: r,
                address: address_in(m.layout, wire),
                values: values_of(p, m, wire, std::mem::take(&mut spare.values)),
            }),
            Some(misfit) => Err(misfit.error(m)),
        };
    }
    let answers = |cmd: usize, r: &MessageRef| {
        r.direction == Direction::Response && p.commands.get(cmd).is_some_and(|c| c.gets(r.index))
    };
    // Decoded as the reply to a request, the responses only the request tells apart that it
    // does not get are set aside: one that fits is not the request's reply, and one that does
    // not fit is reported only where nothing else is.
    let aside = |r: &MessageRef| match reply_to {
        Some(cmd) if !paired => p.message(*r).needs_request && !answers(cmd, r),
        _ => false,
    };
    // The messages whose fields fit; their values are built for the one chosen.
    let fitting = &mut spare.fitting;
    fitting.clear();
    let mut first_err = None;
    let (mut refused, mut aside_err) = (None, None);
    for r in first.into_iter().chain(second).chain(by_len) {
        let misfit = misfit(p, p.message(r), wire);
        match (misfit, aside(&r)) {
            (None, false) => fitting.push(r),
            (Some(misfit), false) => {
                first_err.get_or_insert((r, misfit));
            }
            (None, true) => {
                refused.get_or_insert(r);
            }
            (Some(misfit), true) => {
                aside_err.get_or_insert((r, misfit));
            }
        }
    }
    // A stream's pairing says which response a frame is, never whether it is one: a frame that
    // is a request and a response too (a Modbus echo, a read_coils request that reads as a
    // 3-byte reply) stays ambiguous whatever request came before (it may be the master's
    // retry). The rule of both stream decoders (their module docs).
    let both_ways = fitting.iter().any(|r| r.direction == Direction::Request)
        && fitting.iter().any(|r| r.direction == Direction::Response);
    if paired && both_ways {
        return Err(DecodeError::Ambiguous {
            candidates: fitting.iter().map(|r| p.message(*r).name.clone()).collect(),
        });
    }
    if fitting.len() > 1 {
        if let Some(cmd) = reply_to {
            let answers = |r: &MessageRef| answers(cmd, r);
            if paired && fitting.iter().filter(|r| answers(r)).count() != 1 {
                // Not settled by the request: the ambiguity without it.
                return Err(DecodeError::Ambiguous {
                    candidates: fitting.iter().map(|r| p.message(*r).name.clone()).collect(),
                });
            }
            if !fitting.iter().any(answers) {
                // The frame is one of several replies, none of them the request's.
                return Err(DecodeError::NotAnAnswer {
                    message: p.message(fitting[0]).name.clone(),
                    unasked: p.message(fitting[0]).unasked,
                    request: p
                        .commands
                        .get(cmd)
                        .map(|c| c.name.clone())
                        .unwrap_or_default(),
                });
            }
            fitting.retain(answers);
        }
    }
    match fitting.len() {
        // The first misfit's error, built only now that it is reported; else a set-aside
        // response that fits (not the request's), else a set-aside one's misfit.
        0 => Err(match (first_err, refused, aside_err) {
            (Some((r, misfit)), _, _) => misfit.error(p.message(r)),
            (None, Some(r), _) => DecodeError::NotAnAnswer {
                message: p.message(r).name.clone(),
                unasked: p.message(r).unasked,
                request: reply_to
                    .and_then(|c| p.commands.get(c))
                    .map(|c| c.name.clone())
                    .unwrap_or_default(),
            },
            (None, None, Some((r, misfit))) => misfit.error(p.message(r)),
            (None, None, None) => DecodeError::Truncated {
                needed: shortest,
                found: wire.len(),
            },
        }),
        1 => {
            let message = fitting[0];
            let m = p.message(message);
            let o = m.layout;
            Ok(Frame {
                message,
                address: address_in(o, wire),
                values: values_of(p, m, wire, std::mem::take(&mut spare.values)),
            })
        }
        _ => Err(DecodeError::Ambiguous {
            candidates: fitting.iter().map(|r| p.message(*r).name.clone()).collect(),
        }),
    }
}

/// Decodes `wire` as the given message, reporting the first thing that does not fit it.
pub fn decode_as<'p>(
    p: &'p Protocol,
    r: MessageRef,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    decode_as_in(p, r, Over::Check(None), wire)
}

/// [`decode_as`] of a reply with the bytes its request's checksum covers (`covered`,
/// [`crate::ir::Protocol::checksum_span`]): the checksum of a reply that takes them in runs over them
/// first ([`DecodeError::NeedsRequest`] without them).
pub fn decode_as_reply<'p>(
    p: &'p Protocol,
    r: MessageRef,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    decode_as_in(p, r, Over::Check(covered), wire)
}

/// [`decode_as`] of a frame already decoded as that message, whose checksum, where it takes in
/// its request's bytes (`checksum_over_request`), was checked with them then: it is not
/// checked again (every other check is made).
pub fn decode_as_kept<'p>(
    p: &'p Protocol,
    r: MessageRef,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    decode_as_in(p, r, Over::Checked, wire)
}

/// How [`decode_as_unescaped`] takes the checksum of a reply that takes in its request's
/// bytes.
#[derive(Clone, Copy)]
enum Over<'r> {
    /// Over these bytes of the request's (none: refused, [`DecodeError::NeedsRequest`]).
    Check(Option<&'r [u8]>),
    /// Checked before: not again.
    Checked,
}

fn decode_as_in<'p>(
    p: &'p Protocol,
    r: MessageRef,
    over: Over,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    let un = escape::unescape_as(p, r.direction, p.framing.after_preamble(wire))?;
    let c = crate::long::canonical(p, &un.frame)?;
    decode_as_unescaped(p, r, over, &c.frame).map_err(|e| un.locate(c.locate(e)))
}

/// A constant whole frame, decoded: no address, no values.
pub fn constant_frame<'p>(message: MessageRef) -> Frame<'p> {
    Frame {
        message,
        address: 0,
        values: Vec::new(),
    }
}

/// [`decode_as`] of an unescaped frame.
fn decode_as_unescaped<'p>(
    p: &'p Protocol,
    r: MessageRef,
    over: Over,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    let m = p.message(r);
    if let Some(bytes) = &m.frame {
        return match wire.len().cmp(&bytes.len()) {
            _ if wire == &bytes[..] => Ok(constant_frame(r)),
            std::cmp::Ordering::Less => Err(DecodeError::Truncated {
                needed: bytes.len(),
                found: wire.len(),
            }),
            std::cmp::Ordering::Greater => Err(DecodeError::WrongLength {
                message: m.name.clone(),
                expected: vec![bytes.len()],
                found: wire.len(),
            }),
            std::cmp::Ordering::Equal => Err(DecodeError::UnknownCode {
                offset: 0,
                code: wire.to_vec(),
                direction: Some(m.direction),
            }),
        };
    }
    let len = p.frame_len(m);
    let o = m.layout;
    check_sync(p, r.direction, &o, wire)?;
    if wire.len() < len {
        return Err(DecodeError::Truncated {
            needed: len,
            found: wire.len(),
        });
    }
    if wire.len() > m.max_len {
        return Err(DecodeError::WrongLength {
            message: m.name.clone(),
            expected: vec![len],
            found: wire.len(),
        });
    }
    if wire.get(o.code..o.code + m.code.len()) != Some(&m.code[..]) {
        return Err(DecodeError::UnknownCode {
            offset: o.code,
            code: wire[o.code..o.code + m.code.len()].to_vec(),
            direction: Some(m.direction),
        });
    }
    check_end(p, m.direction, wire)?;
    match (m.over_request, over) {
        _ if m.unchecked => {}
        (Some(from), Over::Check(covered)) => check_over_request(p, m, from, covered, wire)?,
        (Some(_), Over::Checked) => {}
        (None, _) => check_checksum(p, m.direction, None, wire)?,
    }
    check_address(p, o.address, wire)?;
    let plain = p.framing.untransformed(wire);
    let wire: &[u8] = &plain;
    check_length_field(p, &[m.direction], wire)?;
    element_count(p, m, wire)?;
    let values = decode_fields(p, m, wire)?;
    Ok(Frame {
        message: r,
        address: address_in(o, wire),
        values,
    })
}

/// Refuses a frame of direction `d` whose checksum is wrong (over the bytes from where that
/// direction's checksum covers from); `prepared` is the protocol's checksum made once (else it
/// is computed from its parameters).
pub(crate) fn check_checksum(
    p: &Protocol,
    d: Direction,
    prepared: Option<&checksum::Prepared>,
    wire: &[u8],
) -> Result<(), DecodeError> {
    let c = &p.framing.checksum;
    let needed = p.framing.sealed_len_of(d);
    if wire.len() < needed {
        return Err(DecodeError::Truncated {
            needed,
            found: wire.len(),
        });
    }
    let at = p.framing.checksum_at_of(d, wire.len());
    // Bytes on both sides of it (HerkuleX's): both spans, in order.
    let around;
    let covered = if p.framing.covers_around() {
        around = p.framing.covered_bytes_of(d, wire);
        &around[..]
    } else {
        wire.get(p.framing.covered_of(d, wire.len())).unwrap_or(&[])
    };
    // The prepared tables know no extra byte.
    let expected = match prepared {
        Some(prepared) if c.extra.is_none() => prepared.compute(covered),
        _ => c.compute(covered),
    };
    let found = read_uint(&wire[at..at + c.len()], c.byte_order);
    if expected != found {
        return Err(DecodeError::ChecksumMismatch {
            offset: at,
            expected,
            found,
            width: c.width,
        });
    }
    Ok(())
}

/// Refuses a frame of reply `m`, whose checksum takes in its request's bytes (`covered`, the
/// bytes the request's checksum covers) and then its own from `from`, where that checksum is
/// wrong, or where there is no request to check it with.
fn check_over_request(
    p: &Protocol,
    m: &Message,
    from: usize,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<(), DecodeError> {
    let c = &p.framing.checksum;
    let at = p.framing.checksum_at_of(m.direction, wire.len());
    let Some(request) = covered else {
        return Err(DecodeError::NeedsRequest {
            message: m.name.clone(),
            offset: at,
        });
    };
    let expected = c.compute_after(request, wire.get(from..at).unwrap_or(&[]));
    let found = read_uint(&wire[at..at + c.len()], c.byte_order);
    if expected != found {
        return Err(DecodeError::ChecksumMismatch {
            offset: at,
            expected,
            found,
            width: c.width,
        });
    }
    Ok(())
}

/// Whether `wire` ends in the checksum of the bytes it covers and the end bytes, and nothing
/// else, as the generated `Framing::checksum_ok` decides: the weakest acceptance test, which
/// knows no message. A frame without a checksum (`checksum: none`) passes; any other must lay
/// out (a long or short form's; a short length field widened, no longer than the longest
/// frame), is taken after its preamble, unescaped (and then no longer than the longest frame),
/// and must hold at least one byte before its checksum. Where
/// the directions' checksums cover from different bytes or their frames end apart, a frame
/// passes that is either direction's. A reply whose checksum takes in its request's bytes is
/// taken over its own bytes alone, which it fails.
pub fn checksum_ok(p: &Protocol, wire: &[u8]) -> bool {
    let both = [Direction::Request, Direction::Response];
    if p.unchecked(&both, wire).is_some() {
        return true;
    }
    let f = &p.framing;
    // A frame of a long or short form is laid out first, which refuses a long frame whose
    // length the short form holds.
    if f.long.is_some() || f.form.is_some() {
        // Generated code widens a short frame's length field into a buffer of the longest
        // frame's length.
        match crate::long::canonical(p, wire) {
            Ok(laid) if laid.short.is_none() || laid.frame.len() <= p.longest_wire() => {}
            _ => return false,
        }
    }
    let directions: &[Direction] = if f.checksum.covers_by_direction() || f.end_by_direction() {
        &both
    } else {
        &both[..1]
    };
    directions.iter().any(|&d| {
        let Ok(plain) = escape::unescape_as(p, d, f.after_preamble(wire)) else {
            return false;
        };
        let frame = &plain.frame[..];
        // At least one byte besides the checksum and end bytes, all where they sit; generated
        // code unescapes into a buffer of the longest frame's length.
        if frame.len() <= f.checksum.len() + f.end_of(d).len()
            || frame.len() < f.sealed_len_of(d)
            || f.escaping.is_some() && frame.len() > p.longest_frame()
        {
            return false;
        }
        let mut copy = frame.to_vec();
        reseal_as(p, d, &mut copy);
        copy == frame
    })
}

/// Writes into `frame` (of any message's length) its checksum, over the bytes it covers, and
/// the end bytes after it; nothing into a frame shorter than those.
///
/// A frame of a length field the start byte chooses (`framing.length.long`) is taken as it
/// travels: one with the short start byte covered from where its checksum starts in the short
/// form. Where each direction's checksum covers from its own byte (`covers_from: {request,
/// response}`), a request's: [`reseal_as`] says the direction.
pub fn reseal(p: &Protocol, frame: &mut [u8]) {
    reseal_as(p, Direction::Request, frame);
}

/// [`reseal`] of a frame of direction `d`: its checksum over the bytes from where that
/// direction's checksum covers from.
pub fn reseal_as(p: &Protocol, d: Direction, frame: &mut [u8]) {
    // A frame without a checksum (`checksum: none`) has none to write.
    if p.unchecked(&[Direction::Request, Direction::Response], frame)
        .is_some()
    {
        return;
    }
    // A short frame (`framing.forms`): covered from where its checksum starts in it.
    if let Some(f) = p
        .framing
        .form
        .as_ref()
        .filter(|_| crate::forms::is_short(p, frame))
    {
        return reseal_from(p, d, frame, f.extra());
    }
    let short = p
        .framing
        .long
        .filter(|l| frame.get(l.start_at) == Some(&l.short_start));
    reseal_from(p, d, frame, short.map_or(0, |l| l.extra()));
}

/// [`reseal_as`] of a frame whose checksum covers from `back` bytes before where the IR's
/// layout says (0: a frame as the IR lays it out).
fn reseal_from(p: &Protocol, d: Direction, frame: &mut [u8], back: usize) {
    let (c, f) = (&p.framing.checksum, &p.framing);
    if frame.len() < f.sealed_len_of(d) {
        return;
    }
    let (at, end) = (
        f.checksum_at_of(d, frame.len()),
        f.end_at_of(d, frame.len()),
    );
    let bytes = f.end_of(d);
    frame[end..end + bytes.len()].copy_from_slice(bytes);
    let sum = if f.covers_around() {
        // Bytes on both sides of it (HerkuleX's): both spans, in order.
        c.compute(&f.covered_bytes_of(d, frame))
    } else {
        let covered = f.covered_of(d, frame.len());
        let from = covered.start.saturating_sub(back);
        c.compute(frame.get(from..covered.end).unwrap_or(&[]))
    };
    write_uint(sum, &mut frame[at..at + c.len()], c.byte_order);
}

/// Refuses a frame that does not end in the end bytes (the first that differs); the frame is
/// at least as long as the shortest.
fn check_end(p: &Protocol, d: Direction, wire: &[u8]) -> Result<(), DecodeError> {
    let end = p.framing.end_of(d);
    let from = p.framing.end_at_of(d, wire.len());
    for (i, (&found, &expected)) in wire[from..].iter().zip(end).enumerate() {
        if found != expected {
            return Err(DecodeError::BadEnd {
                offset: from + i,
                expected,
                found,
            });
        }
    }
    Ok(())
}

/// Refuses a frame whose start bytes, at each place layout `o` has them (in layout order),
/// are not the sync sequence of direction `d`.
fn check_sync(p: &Protocol, d: Direction, o: &FrameLayout, wire: &[u8]) -> Result<(), DecodeError> {
    for at in o.starts() {
        for (i, &expected) in p.framing.sync_of(d).iter().enumerate() {
            if let Some(&found) = wire.get(at + i) {
                if found != expected {
                    return Err(DecodeError::BadStart {
                        offset: at + i,
                        expected,
                        found,
                    });
                }
            }
        }
    }
    Ok(())
}

/// The value the length field of a frame of `len` bytes must hold (every message of a
/// protocol with a length field has its length field at the same offset and counts the same
/// parts; only the payload varies, so the value follows from the frame's length).
pub fn length_for(p: &Protocol, d: Direction, len: usize) -> Option<i64> {
    p.framing.length_rule(d)?.value(len)
}

/// Refuses a frame whose length field disagrees with its length.
fn check_length_field(
    p: &Protocol,
    directions: &[Direction],
    wire: &[u8],
) -> Result<(), DecodeError> {
    let rule = directions.first().and_then(|d| p.framing.length_rule(*d));
    check_length_rule(p, rule, wire)
}

/// [`check_length_field`] with the rule of the first direction decoded already found.
fn check_length_rule(
    p: &Protocol,
    rule: Option<LengthRule>,
    wire: &[u8],
) -> Result<(), DecodeError> {
    let Some(rule) = rule else {
        return Ok(());
    };
    let expected = rule.value(wire.len()).unwrap_or(-1);
    for at in [Some(rule.at), rule.again].into_iter().flatten() {
        let found = read_uint(wire.get(at..at + rule.width).unwrap_or(&[]), p.byte_order) as i64;
        if found != expected {
            return Err(DecodeError::LengthMismatch {
                offset: at,
                expected,
                found,
            });
        }
    }
    Ok(())
}

/// Whether `wire` has a length message `m` can have: its fixed length, or for a message with
/// a repeated field, a whole number of elements that its count (if any) agrees with.
pub fn fits_len(p: &Protocol, m: &Message, wire: &[u8]) -> bool {
    if m.is_variable() {
        element_count(p, m, wire).is_ok()
    } else {
        wire.len() == m.layout.len
    }
}

/// The number of elements of `m`'s first repeated field in `wire` (0 if it has none), every
/// list checked as [`shape`] checks them.
pub fn element_count(p: &Protocol, m: &Message, wire: &[u8]) -> Result<usize, DecodeError> {
    Ok(shape(p, m, wire)?.lists.first().map_or(0, |l| l.1))
}

/// Where the parts of a variable message sit in one frame: each repeated field's element
/// count and the bytes its elements take, in wire order. A field sits at its `offset` plus
/// the bytes of the lists before it ([`Shape::shift`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Shape {
    /// (field index, elements, bytes) of each repeated field.
    pub lists: Vec<(usize, usize, usize)>,
}

impl Shape {
    /// How much further than its `offset` field `i` sits: the bytes of the lists before it.
    pub fn shift(&self, i: usize) -> usize {
        self.lists.iter().filter(|l| l.0 < i).map(|l| l.2).sum()
    }

    /// The payload offset of field `i` of `m` in this frame.
    pub fn at(&self, m: &Message, i: usize) -> usize {
        m.fields.get(i).map_or(0, |f| f.offset) + self.shift(i)
    }

    /// The number of elements of repeated field `i` (0 for any other).
    pub fn count(&self, i: usize) -> usize {
        self.lists.iter().find(|l| l.0 == i).map_or(0, |l| l.1)
    }

    /// Whether field `i` of `m` is on the wire in this frame: every field but an optional one
    /// whose condition does not hold (an optional field stands in [`Self::lists`] as one
    /// element where it is present, none where not).
    pub fn present(&self, m: &Message, i: usize) -> bool {
        m.fields.get(i).is_some_and(|f| f.present.is_none()) || self.count(i) == 1
    }
}

/// The [`Shape`] of `wire` as a frame of `m`: each list's elements, in wire order, from its
/// count field (read where the lists before it put it) or, for a list to the end, from what
/// the frame's length leaves; each checked against its element size, the bytes the frame has
/// left and its bounds. The last list takes exactly what is left.
pub fn shape(p: &Protocol, m: &Message, wire: &[u8]) -> Result<Shape, DecodeError> {
    let mut out = Shape::default();
    if m.has_optional() {
        // Optional fields (never beside a list): each present or not by its condition, and
        // the frame exactly as long as those present make it.
        let payload = payload_of(p, m, wire);
        let mut len = m.layout.len;
        for (i, f, _) in m.optionals() {
            let on = m.present_in(i, payload);
            let bytes = if on { f.width } else { 0 };
            len += bytes;
            out.lists.push((i, usize::from(on), bytes));
        }
        if wire.len() != len {
            return Err(DecodeError::WrongLength {
                message: m.name.clone(),
                expected: vec![len],
                found: wire.len(),
            });
        }
        return Ok(out);
    }
    let lists: Vec<(usize, &Field, &crate::ir::Repeat)> = m.repeats().collect();
    let Some(&(_, first, first_r)) = lists.first() else {
        return Ok(out);
    };
    let mut rest = wire
        .len()
        .checked_sub(m.layout.len)
        .ok_or_else(|| DecodeError::BadCount {
            message: m.name.clone(),
            field: first.name.clone(),
            offset: m.layout.payload + first.offset,
            expected: format!("at least {}", first_r.min),
            found: 0,
        })?;
    let mut shift = 0usize;
    for (k, &(fi, f, r)) in lists.iter().enumerate() {
        let last = k + 1 == lists.len();
        // A record whose last field's bytes an earlier field gives: as wide as it says.
        let sized;
        let f = match f.record_bytes_from() {
            Some(wi) => {
                let c = &m.fields[wi];
                let o = m.layout.payload + c.offset + out.shift(wi);
                let v = read_uint(wire.get(o..o + c.width).unwrap_or(&[]), c.byte_order) as i64;
                let most = f.record.last().map_or(1, |g| g.width) as i64;
                if !(1..=most).contains(&v) {
                    return Err(DecodeError::BadWidth {
                        message: m.name.clone(),
                        field: c.name.clone(),
                        offset: o,
                        found: v,
                        most: most as usize,
                    });
                }
                sized = f.record_in_frame(v as usize);
                &*sized
            }
            None => f,
        };
        let at = f.frame_at(&m.layout) + shift;
        let bad = |expected: String, found: i64| DecodeError::BadCount {
            message: m.name.clone(),
            field: f.name.clone(),
            offset: at,
            expected,
            found,
        };
        let bits = f.ty == FieldType::Bit;
        let per_byte = |bytes: usize| {
            if bits {
                bytes * 8
            } else {
                bytes / f.width.max(1)
            }
        };
        let count_value = |i: usize| -> i64 {
            let c = &m.fields[i];
            let o = m.layout.payload + c.offset + out.shift(i);
            read_uint(wire.get(o..o + c.width).unwrap_or(&[]), c.byte_order) as i64
        };
        let n = match r.count {
            // Characters up to the first terminator among the bytes the frame leaves; the
            // terminator travels after them.
            Count::Until(t) => wire
                .get(at..at.saturating_add(rest))
                .and_then(|b| b.iter().position(|&x| x == t))
                .ok_or_else(|| DecodeError::NoTerminator {
                    message: m.name.clone(),
                    field: f.name.clone(),
                    offset: at,
                    terminator: t,
                    within: rest,
                })
                .and_then(|n| {
                    // The last list takes exactly what the frame's length leaves.
                    if last && n + 1 != rest {
                        return Err(bad(format!("{} by the frame's length", rest - 1), n as i64));
                    }
                    Ok(n)
                })?,
            Count::ToEnd => {
                // End bytes alone delimit the frame: they must first appear where its own sit.
                if m.delimited_list(&p.framing).is_some() {
                    let end = &p.framing.end;
                    let first = wire.get(at..).and_then(|list| p.framing.first_end(list));
                    // Before the frame's own (fields may sit after the list).
                    let own = wire.len().saturating_sub(end.len());
                    if let Some(i) = first.filter(|&i| at + i < own) {
                        return Err(DecodeError::EndInside {
                            message: m.name.clone(),
                            field: f.name.clone(),
                            offset: at + i,
                            end: end.clone(),
                        });
                    }
                }
                if !bits && rest % f.width.max(1) != 0 {
                    return Err(bad(format!("whole {}-byte elements", f.width), rest as i64));
                }
                per_byte(rest)
            }
            Count::Elements(_) | Count::Fixed(_) => {
                // A fixed count as a count field saying that many would.
                let v = match r.count {
                    Count::Elements(i) => count_value(i),
                    _ => r.max as i64,
                };
                let n = usize::try_from(v).unwrap_or(usize::MAX);
                if last && f.elements_len(n) != rest {
                    return Err(bad(
                        format!("{} by the frame's length", rest / f.width.max(1)),
                        v,
                    ));
                }
                if !last && f.elements_len(n) > rest {
                    return Err(bad(
                        format!("at most {} by the frame's length", rest / f.width.max(1)),
                        v,
                    ));
                }
                n
            }
            Count::Bytes(i) => {
                let v = count_value(i);
                if last {
                    if usize::try_from(v).ok() != Some(rest)
                        || (!bits && rest % f.width.max(1) != 0)
                    {
                        return Err(DecodeError::ByteCount {
                            message: m.name.clone(),
                            field: m.fields[i].name.clone(),
                            offset: m.layout.payload + m.fields[i].offset + out.shift(i),
                            list: f.name.clone(),
                            expected: rest as i64,
                            found: v,
                        });
                    }
                    per_byte(rest)
                } else {
                    let bytes = usize::try_from(v).unwrap_or(usize::MAX);
                    if !bits && bytes % f.width.max(1) != 0 {
                        return Err(bad(format!("whole {}-byte elements", f.width), v));
                    }
                    if bytes > rest {
                        return Err(bad(
                            format!("at most {} by the frame's length", per_byte(rest)),
                            per_byte(bytes) as i64,
                        ));
                    }
                    per_byte(bytes)
                }
            }
        };
        // Bits come eight to a byte: the bound applies to the bytes they fill.
        let (lo, hi) = if bits {
            (r.min.div_ceil(8) * 8, r.max.div_ceil(8) * 8)
        } else {
            (r.min, r.max)
        };
        if n < lo || n > hi {
            return Err(bad(format!("{}..={}", r.min, r.max), n as i64));
        }
        let bytes = f.elements_len(n);
        rest -= bytes;
        shift += bytes;
        out.lists.push((fi, n, bytes));
    }
    Ok(out)
}

/// A repeated record's field index, the record as the frame sizes it, and its records.
#[cfg(feature = "tools")]
type SizedRecords<'f, 'v> = (usize, Cow<'f, Field>, &'v [Vec<i64>]);

/// Repeated record `f` of `m` as a frame has it: its last field as many bytes wide as the
/// field it takes them from says (`value` gives that field's value by name; one clamped to
/// 1..=the type's width, the values outside refused where they are read), or as it is.
pub fn record_sized<'f>(
    m: &Message,
    f: &'f Field,
    value: impl Fn(&str) -> Option<i64>,
) -> Cow<'f, Field> {
    match (f.record_bytes_from(), f.record.last()) {
        (Some(wi), Some(g)) => {
            let v = m.fields.get(wi).and_then(|c| value(&c.name)).unwrap_or(1);
            f.record_in_frame(v.clamp(1, g.width as i64) as usize)
        }
        _ => Cow::Borrowed(f),
    }
}

/// [`record_sized`] for a frame's payload as [`Shape`] places its fields.
fn record_in_payload<'f>(m: &Message, f: &'f Field, payload: &[u8], sh: &Shape) -> Cow<'f, Field> {
    record_sized(m, f, |name| {
        let i = m.fields.iter().position(|c| c.name == name)?;
        let c = &m.fields[i];
        let at = sh.at(m, i);
        Some(int_of(c, payload, at).1)
    })
}

/// The address a frame carries at `o.address`: 0 where frames carry none (or the frame is too
/// short to hold it).
fn address_in(o: FrameLayout, wire: &[u8]) -> u8 {
    o.address.and_then(|at| wire.get(at).copied()).unwrap_or(0)
}

/// Refuses an address no frame may carry ([`address_allowed`]); nothing where frames carry
/// none.
fn check_address(p: &Protocol, at: Option<usize>, wire: &[u8]) -> Result<(), DecodeError> {
    let Some(at) = at else { return Ok(()) };
    let found = wire.get(at).copied().unwrap_or(0);
    if address_allowed(p, found) {
        return Ok(());
    }
    let a = &p.framing.address;
    Err(DecodeError::BadAddress {
        offset: at,
        found,
        min: a.min,
        max: a.max,
    })
}

/// Field values of a frame already known to have the message's length and an allowed address:
/// constants, repeated fields, ranges and the broadcast rule checked.
fn decode_fields<'p>(
    p: &Protocol,
    m: &'p Message,
    wire: &[u8],
) -> Result<Vec<Value<'p>>, DecodeError> {
    fields_of(p, m, wire).map_err(|misfit| misfit.error(m))
}

/// Why a frame's fields do not fit a message: what [`decode_fields`] reports, held without
/// allocating until it is reported, since [`decide`] tries every message of a code and
/// length and reports only the first failure.
#[derive(Debug, Clone, Copy)]
enum Misfit {
    Broadcast {
        address: u8,
    },
    NotBcd {
        field: usize,
        offset: usize,
        found: u64,
    },
    Constant {
        field: usize,
        bit: Option<usize>,
        offset: usize,
        expected: u64,
        found: u64,
    },
    NotEqual {
        field: usize,
        other: usize,
        offset: usize,
        expected: i64,
        found: i64,
    },
    Range {
        field: usize,
        bit: Option<usize>,
        offset: usize,
        found: i64,
        min: i64,
        max: i64,
        kind: NumKind,
    },
    /// A field that follows another of its frame (`follows: {field}`) does not.
    NotFollowing {
        field: usize,
        offset: usize,
        expected: i64,
        found: i64,
    },
}

impl Misfit {
    fn error(self, m: &Message) -> DecodeError {
        let name = |field: usize, bit: Option<usize>| {
            let f = m.fields.get(field);
            match bit {
                // A record's field `b`: `blocks.position`.
                Some(b) if f.is_some_and(Field::is_record) => f.map(|f| f.record_field_name(b)),
                Some(b) => f.and_then(|f| f.bits.get(b)).map(|b| b.name.clone()),
                None => f.map(|f| f.name.clone()),
            }
            .unwrap_or_default()
        };
        match self {
            Misfit::Broadcast { address } => DecodeError::BroadcastNotAccepted {
                message: m.name.clone(),
                code: m.code.clone(),
                address,
            },
            Misfit::Constant {
                field,
                bit,
                offset,
                expected,
                found,
            } => DecodeError::ConstantMismatch {
                message: m.name.clone(),
                field: name(field, bit),
                offset,
                expected,
                found,
            },
            Misfit::NotBcd {
                field,
                offset,
                found,
            } => DecodeError::NotBcd {
                message: m.name.clone(),
                field: name(field, None),
                offset,
                found,
            },
            Misfit::NotEqual {
                field,
                other,
                offset,
                expected,
                found,
            } => DecodeError::NotEqual {
                message: m.name.clone(),
                field: name(field, None),
                offset,
                other: name(other, None),
                expected,
                found,
            },
            Misfit::Range {
                field,
                bit,
                offset,
                found,
                min,
                max,
                kind,
            } => DecodeError::OutOfRange {
                message: m.name.clone(),
                field: name(field, bit),
                offset,
                found,
                min,
                max,
                kind,
            },
            Misfit::NotFollowing {
                field,
                offset,
                expected,
                found,
            } => DecodeError::NotFollowing {
                message: m.name.clone(),
                field: name(field, None),
                offset,
                rule: match m.fields.get(field).and_then(|f| f.follows.as_ref()) {
                    Some(Follows::Field(_, rel) | Follows::Request(rel)) => {
                        rel.describe(&rel.field)
                    }
                    None => String::new(),
                },
                expected,
                found,
            },
        }
    }
}

/// A whole field's value: unsigned as read, and as the field's type reads it (0 for text).
/// A BCD field's value is the number its digits give (0 where one is above 9: [`misfit`]
/// refuses those through [`bcd_of`] before any value is taken).
fn int_of(f: &Field, payload: &[u8], at: usize) -> (u64, i64) {
    bcd_of(f, payload, at).unwrap_or_default()
}

/// [`int_of`], or a BCD field's bytes as read where a digit is above 9.
fn bcd_of(f: &Field, payload: &[u8], at: usize) -> Result<(u64, i64), u64> {
    if f.is_ascii() {
        return Ok((0, 0));
    }
    let bytes = payload.get(at..at + f.width).unwrap_or(&[]);
    let unsigned = read_number(f, bytes);
    if f.bcd {
        let v = crate::number::from_bcd(unsigned).ok_or(unsigned)?;
        return Ok((v, v as i64));
    }
    let v = if f.signed {
        sign_extend(unsigned, 8 * f.width as u32)
    } else {
        unsigned as i64
    };
    Ok((unsigned, v))
}

/// [`decode_fields`], failing with a [`Misfit`]: the fields are checked first
/// ([`misfit`]), and their values built only for a message they fit ([`values_of`]).
fn fields_of<'p>(p: &Protocol, m: &'p Message, wire: &[u8]) -> Result<Vec<Value<'p>>, Misfit> {
    match misfit(p, m, wire) {
        Some(misfit) => Err(misfit),
        None => Ok(values_of(p, m, wire, Vec::new())),
    }
}

/// A variable message's payload runs to the checksum.
fn payload_of<'w>(p: &Protocol, m: &Message, wire: &'w [u8]) -> &'w [u8] {
    let end = wire.len().saturating_sub(trailer_of(p, m));
    wire.get(m.layout.payload..end).unwrap_or(&[])
}

/// The bytes after message `m`'s payload: the framing's checksum and end bytes, none where
/// it travels without a checksum (`checksum: none`, validated without end bytes).
pub fn trailer_of(p: &Protocol, m: &Message) -> usize {
    if m.unchecked {
        0
    } else {
        p.framing.trailer_len_of(m.direction)
    }
}

/// The first thing in the frame's fields that does not fit message `m`, if any: broadcast,
/// constants, fields that follow or equal others, repeated elements and ranges.
fn misfit(p: &Protocol, m: &Message, wire: &[u8]) -> Option<Misfit> {
    let o = m.layout;
    let address = address_in(o, wire);
    if broadcast_refused(p, m, address) {
        return Some(Misfit::Broadcast { address });
    }
    let payload = payload_of(p, m, wire);
    let sh = shape(p, m, wire).unwrap_or_default();
    let pos = |i: usize| sh.at(m, i);
    for (i, f) in m.fields.iter().enumerate() {
        if !sh.present(m, i) {
            continue;
        }
        if f.is_record() {
            let f = &*record_in_payload(m, f, payload, &sh);
            let at = o.payload + pos(i);
            let bytes = list_bytes(f, payload, pos(i), &sh, i);
            for (k, rec) in bytes.chunks_exact(f.width.max(1)).enumerate() {
                for (j, g) in f.record.iter().enumerate() {
                    let v = int_of(g, rec, g.offset).1;
                    if let Some((min, max)) = range_violation(g, None, v) {
                        return Some(Misfit::Range {
                            field: i,
                            bit: Some(j),
                            offset: at + k * f.width + g.offset,
                            found: v,
                            min,
                            max,
                            kind: NumKind::Int,
                        });
                    }
                }
            }
            continue;
        }
        if f.repeat.is_some() {
            let at = o.payload + pos(i);
            // The offset of the element out of range (bits: of the field).
            let step = if f.ty == FieldType::Bit { 0 } else { f.width };
            let elements = list_at(f, payload, pos(i), &sh, i);
            for (k, v) in elements.into_iter().enumerate() {
                if let Some((min, max)) = range_violation(f, None, v) {
                    return Some(Misfit::Range {
                        field: i,
                        bit: None,
                        offset: at + k * step,
                        found: v,
                        min,
                        max,
                        kind: f.num_kind(),
                    });
                }
            }
            continue;
        }
        if f.is_ascii() {
            continue;
        }
        let at = o.payload + pos(i);
        // A header field (a plain integer, maybe with sub-fields) is read from the frame's
        // header; every other from the payload.
        let (src, rel, at) = if f.header {
            (wire, f.frame_at(&o), f.frame_at(&o))
        } else {
            (payload, pos(i), at)
        };
        if let Some(pk) = &f.packed {
            let bytes = payload.get(pos(i)..pos(i) + f.width).unwrap_or(&[]);
            if !pk.padding_clear(bytes) {
                return Some(Misfit::Constant {
                    field: i,
                    bit: None,
                    offset: at + f.width - 1,
                    expected: 0,
                    found: u64::from(packed_padding(pk, bytes)),
                });
            }
            for (k, v) in f.packed_elements(bytes).into_iter().enumerate() {
                if let Some((min, max)) = range_violation(f, None, v) {
                    return Some(Misfit::Range {
                        field: i,
                        bit: None,
                        offset: at + k * pk.bits as usize / 8,
                        found: v,
                        min,
                        max,
                        kind: f.num_kind(),
                    });
                }
            }
            continue;
        }
        let (unsigned, v) = match bcd_of(f, src, rel) {
            Ok(v) => v,
            Err(found) => {
                return Some(Misfit::NotBcd {
                    field: i,
                    offset: at,
                    found,
                })
            }
        };
        if let Some(c) = f.constant {
            if unsigned != c {
                return Some(Misfit::Constant {
                    field: i,
                    bit: None,
                    offset: at,
                    expected: c,
                    found: unsigned,
                });
            }
        }
        if let Some(Follows::Field(other, rel)) = &f.follows {
            let expected = rel.apply(
                m.fields
                    .get(*other)
                    .map_or(0, |e| int_of(e, payload, pos(*other)).1),
            );
            if v != expected {
                return Some(Misfit::NotFollowing {
                    field: i,
                    offset: at,
                    expected,
                    found: v,
                });
            }
        }
        if let Some(other) = f.equals {
            let expected = m
                .fields
                .get(other)
                .map_or(0, |e| int_of(e, payload, pos(other)).1);
            if v != expected {
                return Some(Misfit::NotEqual {
                    field: i,
                    other,
                    offset: at,
                    expected,
                    found: v,
                });
            }
        }
        if f.bits.is_empty() {
            if let Some((min, max)) = range_violation(f, None, v) {
                return Some(Misfit::Range {
                    field: i,
                    bit: None,
                    offset: at,
                    found: v,
                    min,
                    max,
                    kind: f.num_kind(),
                });
            }
        }
        for (k, b) in f.bits.iter().enumerate() {
            let bv = bit_value(unsigned, b);
            if let Some(c) = b.constant {
                if bv as u64 != c {
                    return Some(Misfit::Constant {
                        field: i,
                        bit: Some(k),
                        offset: at,
                        expected: c,
                        found: bv as u64,
                    });
                }
            }
            if let Some((min, max)) = range_violation(f, Some(b), bv) {
                return Some(Misfit::Range {
                    field: i,
                    bit: Some(k),
                    offset: at,
                    found: bv,
                    min,
                    max,
                    kind: NumKind::Int,
                });
            }
        }
    }
    None
}

/// The values of a frame that fits message `m` ([`misfit`] found nothing), in `values`'s
/// memory (emptied first).
fn values_of<'p>(
    p: &Protocol,
    m: &'p Message,
    wire: &[u8],
    mut values: Vec<Value<'p>>,
) -> Vec<Value<'p>> {
    let payload = payload_of(p, m, wire);
    let sh = shape(p, m, wire).unwrap_or_default();
    values.clear();
    values.reserve(m.fields.len());
    for (i, f) in m.fields.iter().enumerate() {
        if !sh.present(m, i) {
            continue;
        }
        let at = sh.at(m, i);
        if f.is_record() {
            let sized = record_in_payload(m, f, payload, &sh);
            values.push(Value {
                name: Cow::Borrowed(&f.name),
                raw: Raw::Records(read_records(&sized, list_bytes(f, payload, at, &sh, i))),
            });
            continue;
        }
        if f.repeat.is_some() {
            let list = list_at(f, payload, at, &sh, i);
            // Counted text: its characters are the list's bytes.
            let raw = if f.is_ascii() {
                Raw::Text(list.into_iter().map(|b| b as u8).collect())
            } else {
                Raw::List(list)
            };
            values.push(Value {
                name: Cow::Borrowed(&f.name),
                raw,
            });
            continue;
        }
        if f.is_ascii() {
            let bytes = payload.get(at..at + f.width).unwrap_or(&[]);
            values.push(Value {
                name: Cow::Borrowed(&f.name),
                raw: Raw::Text(bytes.to_vec()),
            });
            continue;
        }
        if f.packed.is_some() {
            let bytes = payload.get(at..at + f.width).unwrap_or(&[]);
            values.push(Value {
                name: Cow::Borrowed(&f.name),
                raw: Raw::List(f.packed_elements(bytes)),
            });
            continue;
        }
        let (unsigned, v) = if f.header {
            int_of(f, wire, f.frame_at(&m.layout))
        } else {
            int_of(f, payload, at)
        };
        if f.bits.is_empty() {
            values.push(Value {
                name: Cow::Borrowed(&f.name),
                raw: Raw::Int(v),
            });
        }
        for b in &f.bits {
            values.push(Value {
                name: Cow::Borrowed(&b.name),
                raw: Raw::Int(bit_value(unsigned, b)),
            });
        }
    }
    values
}

/// The elements of repeated field `i` (`f`), from payload offset `at`, as many bytes as the
/// frame's [`Shape`] gives it (to the payload's end for a message that has none).
fn list_at(f: &Field, payload: &[u8], at: usize, sh: &Shape, i: usize) -> Vec<i64> {
    read_elements(f, list_bytes(f, payload, at, sh, i))
}

/// The bytes of repeated field `i`'s elements, from payload offset `at`: as many as the
/// frame's [`Shape`] gives it (to the payload's end for a message that has none).
fn list_bytes<'w>(f: &Field, payload: &'w [u8], at: usize, sh: &Shape, i: usize) -> &'w [u8] {
    let bytes = payload.get(at..).unwrap_or(&[]);
    match sh.lists.iter().find(|l| l.0 == i) {
        // Text up to a terminator: its characters, not the terminator after them.
        Some(l) if f.terminator().is_some() => bytes.get(..l.1).unwrap_or(bytes),
        Some(l) => bytes.get(..l.2).unwrap_or(bytes),
        None => bytes,
    }
}

/// The records of a repeated record from the bytes of its elements: each record's fields'
/// raw values, as whole fields read (signed ones sign-extended).
fn read_records(f: &Field, bytes: &[u8]) -> Vec<Vec<i64>> {
    bytes
        .chunks_exact(f.width.max(1))
        .map(|rec| {
            f.record
                .iter()
                .map(|g| int_of(g, rec, g.offset).1)
                .collect()
        })
        .collect()
}

/// The bits of a packed field's last byte that no element takes (0 in a valid frame).
fn packed_padding(pk: &Packed, bytes: &[u8]) -> u8 {
    let pad = 8 * pk.bytes() - pk.count * pk.bits as usize;
    let last = bytes.get(pk.bytes().wrapping_sub(1)).copied().unwrap_or(0);
    let mask = if pad == 0 {
        0
    } else if pk.lsb_first {
        0xFFu8 << (8 - pad)
    } else {
        0xFFu8 >> (8 - pad)
    };
    last & mask
}

/// The elements of a repeated field from the bytes where they start (to the payload's end).
fn read_elements(f: &Field, bytes: &[u8]) -> Vec<i64> {
    if f.ty == FieldType::Bit {
        return bytes
            .iter()
            .flat_map(|b| (0..8).map(move |i| i64::from((b >> i) & 1)))
            .collect();
    }
    let w = f.width.max(1);
    bytes
        .chunks_exact(w)
        .map(|c| {
            // Its words in their order (`word_order`, 32- and 64-bit elements).
            let u = read_number(f, c);
            if f.signed {
                sign_extend(u, 8 * w as u32)
            } else {
                u as i64
            }
        })
        .collect()
}

/// Decodes a reply as the answer to `request` (a decoded request frame): the reply must be one
/// the request gets, and every field that follows from the request (Modbus: byte count =
/// 2 × quantity) and every element count taken from it must agree.
#[cfg(feature = "tools")]
pub fn decode_reply<'p>(
    p: &'p Protocol,
    request: &Frame,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    decode_reply_with(p, request, None, wire)
}

/// [`decode_reply`] with the request's frame as it travelled (`request_wire`), whose bytes
/// the checksum of a reply that takes them in runs over first (`checksum_over_request`);
/// without it such a reply is refused ([`DecodeError::NeedsRequest`]).
#[cfg(feature = "tools")]
pub fn decode_reply_with<'p>(
    p: &'p Protocol,
    request: &Frame,
    request_wire: Option<&[u8]>,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    let covered = request_wire.and_then(|w| p.checksum_span(w));
    decode_reply_over(p, request, covered, wire)
}

/// [`decode_reply_with`] with the bytes the request's checksum covers (`covered`,
/// [`crate::ir::Protocol::checksum_span`] of its frame) rather than its frame.
#[cfg(feature = "tools")]
pub fn decode_reply_over<'p>(
    p: &'p Protocol,
    request: &Frame,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<Frame<'p>, DecodeError> {
    let frame = decode_with(
        p,
        Some(Direction::Response),
        Some(request.message.index),
        covered,
        wire,
    )?;
    // Its offsets are the IR's layout's: on the frame as it travelled (a long length form).
    answers(p, request, &frame).map_err(|e| crate::long::locate_on(p, wire, e))?;
    Ok(frame)
}

/// Whether `reply` answers `request`: a response the command lists, whose fields that follow
/// from the request do.
pub fn answers(p: &Protocol, request: &Frame, reply: &Frame) -> Result<(), DecodeError> {
    let cmd = p.message(request.message);
    let m = p.message(reply.message);
    if request.message.direction != Direction::Request
        || reply.message.direction != Direction::Response
        || !cmd.gets(reply.message.index)
    {
        return Err(DecodeError::NotAnAnswer {
            message: m.name.clone(),
            request: cmd.name.clone(),
            unasked: reply.message.direction == Direction::Response && m.unasked,
        });
    }
    let req_int = |name: &str| match request.get(name) {
        Some(Raw::Int(v)) => Some(*v),
        _ => None,
    };
    // A field sits further than its offset by the bytes of the lists before it.
    let mut shift = 0usize;
    for f in &m.fields {
        let at = f.frame_at(&m.layout) + shift;
        let f = &*record_sized(m, f, |name| match reply.get(name) {
            Some(Raw::Int(v)) => Some(*v),
            _ => None,
        });
        if let (Some(_), Some(n)) = (&f.repeat, reply.get(&f.name).and_then(Raw::elements)) {
            shift += f.elements_len(n);
        }
        if let Some(Follows::Request(rel)) = &f.follows {
            let (Some(base), Some(Raw::Int(found))) = (req_int(&rel.field), reply.get(&f.name))
            else {
                continue;
            };
            let expected = rel.apply(base);
            if *found != expected {
                return Err(DecodeError::NotFollowing {
                    message: m.name.clone(),
                    field: f.name.clone(),
                    offset: at,
                    rule: format!("{} of the request", rel.describe(&rel.field)),
                    expected,
                    found: *found,
                });
            }
        }
        if let Some(rel) = f.repeat.as_ref().and_then(|r| r.request.as_ref()) {
            let (Some(base), Some(found)) = (
                req_int(&rel.field),
                reply.get(&f.name).and_then(Raw::elements),
            ) else {
                continue;
            };
            let expected = rel.apply(base);
            let same = match usize::try_from(expected) {
                Ok(n) => f.elements_len(n) == f.elements_len(found),
                Err(_) => false,
            };
            if !same {
                return Err(DecodeError::BadCount {
                    message: m.name.clone(),
                    field: f.name.clone(),
                    offset: at,
                    expected: format!("{expected} ({} of the request)", rel.describe(&rel.field)),
                    found: found as i64,
                });
            }
        }
    }
    Ok(())
}

/// Encodes a message for `address` from named raw values. Constants and repeated fields fill
/// themselves in and need no value; every other leaf must be given exactly once.
#[cfg(feature = "tools")]
pub fn encode(
    p: &Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
) -> Result<Vec<u8>, EncodeError> {
    encode_with(p, r, address, values, None)
}

/// [`encode`] of a reply with the bytes its request's checksum covers (`covered`,
/// [`crate::ir::Protocol::checksum_span`] of the request's frame): the checksum of a reply that takes
/// them in runs over them first (`checksum_over_request`); without them such a reply is
/// refused ([`EncodeError::NeedsRequest`]). Other messages ignore them.
#[cfg(feature = "tools")]
pub fn encode_with(
    p: &Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
    covered: Option<&[u8]>,
) -> Result<Vec<u8>, EncodeError> {
    let m = p.message(r);
    // Counted text (`type: ascii` with `repeat`) is encoded as the list of its bytes.
    if m.fields.iter().any(Field::is_counted_text) {
        let mut given = values.to_vec();
        for v in &mut given {
            let Some(f) = m.fields.iter().find(|f| f.name == v.name) else {
                continue;
            };
            if !f.is_counted_text() {
                continue;
            }
            match &v.raw {
                Raw::Text(t) => v.raw = Raw::List(t.iter().map(|&b| i64::from(b)).collect()),
                _ => {
                    return Err(EncodeError::NotText {
                        field: f.name.clone(),
                    })
                }
            }
        }
        return encode_values(p, r, address, &given, covered);
    }
    encode_values(p, r, address, values, covered)
}

#[cfg(feature = "tools")]
fn encode_values(
    p: &Protocol,
    r: MessageRef,
    address: u8,
    values: &[Value],
    covered: Option<&[u8]>,
) -> Result<Vec<u8>, EncodeError> {
    let m = p.message(r);
    // A constant whole frame carries no address: its bytes, whatever address is given.
    if let Some(bytes) = &m.frame {
        if let Some(v) = values.first() {
            return Err(EncodeError::UnknownValue {
                field: v.name.to_string(),
            });
        }
        return Ok(bytes.clone());
    }
    let a = &p.framing.address;
    if !p.framing.has_address_in(m.direction) && address != 0 {
        return Err(EncodeError::Unaddressed { address });
    }
    if p.framing.has_address_in(m.direction) && !address_allowed(p, address) {
        return Err(EncodeError::BadAddress {
            address,
            min: a.min,
            max: a.max,
        });
    }
    if broadcast_refused(p, m, address) {
        return Err(EncodeError::BroadcastNotAccepted {
            message: m.name.clone(),
            address,
        });
    }
    for v in values {
        if !m.leaves().any(|l| l.name() == v.name) {
            return Err(EncodeError::UnknownValue {
                field: v.name.to_string(),
            });
        }
    }
    let lookup = |name: &str| values.iter().find(|v| v.name == name).map(|v| &v.raw);
    let int = |name: &str| match lookup(name) {
        Some(Raw::Int(i)) => Ok(*i),
        Some(Raw::Text(_) | Raw::List(_) | Raw::Records(_)) => Err(EncodeError::NotNumber {
            field: name.to_owned(),
        }),
        None => Err(EncodeError::MissingValue {
            field: name.to_owned(),
        }),
    };
    let o = m.layout;
    // The repeated fields' elements, checked against their bounds and their element type, and
    // the value of each count field.
    let mut lists: Vec<(usize, &[i64])> = Vec::new();
    let mut records: Vec<SizedRecords> = Vec::new();
    let mut counts: Vec<(usize, i64)> = Vec::new();
    for (fi, f, r) in m.repeats() {
        if f.is_record() {
            // Its last field as wide as the field it takes its bytes from says, 1 up to its type's.
            if let (Some(wi), Some(g)) = (f.record_bytes_from(), f.record.last()) {
                let c = &m.fields[wi];
                let v = int(&c.name)?;
                if !(1..=g.width as i64).contains(&v) {
                    return Err(EncodeError::NotInRange {
                        field: c.name.clone(),
                        value: v,
                        min: 1,
                        max: g.width as i64,
                        kind: NumKind::Int,
                    });
                }
            }
            let f = record_sized(m, f, |name| int(name).ok());
            let recs = record_list(&f, r, lookup(&f.name))?;
            match r.count {
                Count::Elements(i) => counts.push((i, recs.len() as i64)),
                Count::Bytes(i) => counts.push((i, f.elements_len(recs.len()) as i64)),
                Count::ToEnd | Count::Until(_) | Count::Fixed(_) => {}
            }
            records.push((fi, f, recs));
            continue;
        }
        let list: &[i64] = match lookup(&f.name) {
            Some(Raw::List(l)) => l,
            Some(_) => {
                return Err(EncodeError::NotList {
                    field: f.name.clone(),
                })
            }
            None => {
                return Err(EncodeError::MissingValue {
                    field: f.name.clone(),
                })
            }
        };
        // Text up to a terminator must not hold it: the frame would end the text there.
        if let Some(t0) = f.terminator() {
            if let Some(index) = list.iter().position(|&b| b == i64::from(t0)) {
                return Err(EncodeError::HoldsTerminator {
                    field: f.name.clone(),
                    index,
                    terminator: t0,
                });
            }
        }
        // Bits come eight to a byte: decode reads whole bytes, so a bound counts the bytes.
        let (lo, hi) = if f.ty == FieldType::Bit {
            (r.min, r.max.div_ceil(8) * 8)
        } else {
            (r.min, r.max)
        };
        if list.len() < lo || list.len() > hi {
            return Err(EncodeError::WrongCount {
                field: f.name.clone(),
                min: lo,
                max: hi,
                found: list.len(),
            });
        }
        let (lo, hi) = if f.ty == FieldType::Bit {
            (0, 1)
        } else {
            f.raw_span()
        };
        for &v in list {
            if let Some((min, max)) = range_violation(f, None, v) {
                return Err(EncodeError::NotInRange {
                    field: f.name.clone(),
                    value: v,
                    min,
                    max,
                    kind: f.num_kind(),
                });
            }
            if v < lo || v > hi {
                return Err(EncodeError::OutOfRange {
                    field: f.name.clone(),
                    value: v,
                    min: lo,
                    max: hi,
                });
            }
        }
        match r.count {
            Count::Elements(i) => counts.push((i, list.len() as i64)),
            Count::Bytes(i) => counts.push((i, f.elements_len(list.len()) as i64)),
            Count::ToEnd | Count::Until(_) | Count::Fixed(_) => {}
        }
        lists.push((fi, list));
    }
    let list_of = |i: usize| lists.iter().find(|l| l.0 == i).map_or(&[][..], |l| l.1);
    let records_of = |i: usize| records.iter().find(|l| l.0 == i).map(|l| (&*l.1, l.2));
    // Optional fields take their bytes where a value is given for them (the loop below
    // refuses one given where its condition does not hold, or missing where it does).
    let optional: usize = m
        .optionals()
        .filter(|(_, f, _)| lookup(&f.name).is_some())
        .map(|(_, f, _)| f.width)
        .sum();
    let tail: usize = lists
        .iter()
        .map(|&(i, l)| m.fields[i].elements_len(l.len()))
        .chain(records.iter().map(|(_, f, l)| f.elements_len(l.len())))
        .sum::<usize>()
        + optional;
    let mut out = vec![0u8; p.frame_len(m) + tail];
    for at in o.starts() {
        for (i, s) in p.framing.sync_of(m.direction).iter().enumerate() {
            out[at + i] = *s;
        }
    }
    if let Some(at) = o.address {
        out[at] = address;
    }
    out[o.code..o.code + m.code.len()].copy_from_slice(&m.code);
    if let Some(l) = &p.framing.length {
        let v = length_for(p, m.direction, out.len()).unwrap_or(0);
        for at in o.lengths() {
            write_uint(v as u64, &mut out[at..at + l.width], p.byte_order);
        }
    }
    // Each field's value as decode reads it (signed fields sign-extended): what a field that
    // follows it is computed from.
    let mut ints: Vec<i64> = Vec::with_capacity(m.fields.len());
    let mut shift = 0usize;
    for (i, f) in m.fields.iter().enumerate() {
        let at = f.frame_at(&o) + shift;
        if let Some(c) = &f.present {
            // Its condition reads a field before it, encoded already.
            let on = c.holds(ints.get(c.field).copied().unwrap_or(0));
            let given = lookup(&f.name).is_some();
            if on != given {
                let of = m.fields.get(c.field).map_or("", |g| g.name.as_str());
                return Err(EncodeError::Optional {
                    field: f.name.clone(),
                    condition: c.describe(of),
                    given,
                });
            }
            if !on {
                ints.push(0);
                continue;
            }
            shift += f.width;
        }
        if f.is_record() {
            let (f, recs) = records_of(i).unwrap_or((f, &[]));
            shift += f.elements_len(recs.len());
            for (k, rec) in recs.iter().enumerate() {
                for (g, &v) in f.record.iter().zip(rec) {
                    let s = at + k * f.width + g.offset;
                    write_uint(v as u64, &mut out[s..s + g.width], g.byte_order);
                }
            }
            ints.push(0);
            continue;
        }
        if f.repeat.is_some() {
            let list = list_of(i);
            shift += f.elements_len(list.len());
            if f.ty == FieldType::Bit {
                for (k, &v) in list.iter().enumerate() {
                    out[at + k / 8] |= ((v & 1) as u8) << (k % 8);
                }
            } else {
                for (k, &v) in list.iter().enumerate() {
                    let s = at + k * f.width;
                    write_number(f, v as u64, &mut out[s..s + f.width]);
                }
                if let Some(t) = f.terminator() {
                    out[at + list.len()] = t;
                }
            }
            ints.push(0);
            continue;
        }
        let slot = &mut out[at..at + f.width];
        let computed = match &f.follows {
            Some(Follows::Field(other, rel)) => {
                Some(rel.apply(ints.get(*other).copied().unwrap_or(0)))
            }
            _ => counts
                .iter()
                .find(|(c, _)| *c == i && lookup(&f.name).is_none())
                .map(|&(_, n)| n),
        };
        if let Some(v) = computed {
            if let Some(Raw::Int(given)) = lookup(&f.name) {
                if *given != v {
                    return Err(EncodeError::Fixed {
                        field: f.name.clone(),
                        expected: v,
                        found: *given,
                    });
                }
            }
            let (min, max) = f.raw_span();
            if v < min || v > max {
                return Err(EncodeError::OutOfRange {
                    field: f.name.clone(),
                    value: v,
                    min,
                    max,
                });
            }
            write_uint(v as u64, slot, f.byte_order);
            ints.push(v);
            continue;
        }
        if let Some(pk) = &f.packed {
            let list = match lookup(&f.name) {
                Some(Raw::List(l)) => l,
                Some(_) => {
                    return Err(EncodeError::NotList {
                        field: f.name.clone(),
                    })
                }
                None => {
                    return Err(EncodeError::MissingValue {
                        field: f.name.clone(),
                    })
                }
            };
            if list.len() != pk.count {
                return Err(EncodeError::WrongCount {
                    field: f.name.clone(),
                    min: pk.count,
                    max: pk.count,
                    found: list.len(),
                });
            }
            for &v in list {
                if let Some((min, max)) = range_violation(f, None, v) {
                    return Err(EncodeError::NotInRange {
                        field: f.name.clone(),
                        value: v,
                        min,
                        max,
                        kind: f.num_kind(),
                    });
                }
                let (lo, hi) = f.packed_span();
                if v < lo || v > hi {
                    return Err(EncodeError::OutOfRange {
                        field: f.name.clone(),
                        value: v,
                        min: lo,
                        max: hi,
                    });
                }
            }
            f.write_packed(list, slot);
            ints.push(0);
            continue;
        }
        if f.is_ascii() {
            let text = match lookup(&f.name) {
                Some(Raw::Text(t)) => t,
                Some(Raw::Int(_) | Raw::List(_) | Raw::Records(_)) => {
                    return Err(EncodeError::NotText {
                        field: f.name.clone(),
                    })
                }
                None => {
                    return Err(EncodeError::MissingValue {
                        field: f.name.clone(),
                    })
                }
            };
            if text.len() != f.width {
                return Err(EncodeError::WrongTextLength {
                    field: f.name.clone(),
                    expected: f.width,
                    found: text.len(),
                });
            }
            slot.copy_from_slice(text);
            ints.push(0);
            continue;
        }
        let word: u64 = if let Some(c) = f
            .constant
            .or_else(|| f.equals.and_then(|o| ints.get(o).map(|&v| v as u64)))
        {
            // Constants and repeats fill themselves in; a value given for one must agree.
            let expected = if f.signed {
                sign_extend(c, 8 * f.width as u32)
            } else {
                c as i64
            };
            if let Some(Raw::Int(given)) = lookup(&f.name) {
                if *given != expected {
                    return Err(EncodeError::Fixed {
                        field: f.name.clone(),
                        expected,
                        found: *given,
                    });
                }
            }
            c
        } else if !f.bits.is_empty() {
            let mut word = 0u64;
            for b in &f.bits {
                let v = match (b.constant, lookup(&b.name)) {
                    (Some(c), Some(Raw::Int(given))) if *given != c as i64 => {
                        return Err(EncodeError::Fixed {
                            field: b.name.clone(),
                            expected: c as i64,
                            found: *given,
                        });
                    }
                    (Some(c), _) => c as i64,
                    (None, _) => int(&b.name)?,
                };
                if let Some((min, max)) = range_violation(f, Some(b), v) {
                    return Err(EncodeError::NotInRange {
                        field: b.name.clone(),
                        value: v,
                        min,
                        max,
                        kind: NumKind::Int,
                    });
                }
                let (min, max) = raw_limits(u32::from(b.width()), b.signed);
                if v < min || v > max {
                    return Err(EncodeError::OutOfRange {
                        field: b.name.clone(),
                        value: v,
                        min,
                        max,
                    });
                }
                let mask = (1u64 << b.width()) - 1;
                word |= ((v as u64) & mask) << b.lsb;
            }
            word
        } else {
            let v = int(&f.name)?;
            if let Some((min, max)) = range_violation(f, None, v) {
                return Err(EncodeError::NotInRange {
                    field: f.name.clone(),
                    value: v,
                    min,
                    max,
                    kind: f.num_kind(),
                });
            }
            let (min, max) = f.raw_span();
            if v < min || v > max {
                return Err(EncodeError::OutOfRange {
                    field: f.name.clone(),
                    value: v,
                    min,
                    max,
                });
            }
            let bits = 8 * f.width as u32;
            (v as u64)
                & if bits >= 64 {
                    u64::MAX
                } else {
                    (1u64 << bits) - 1
                }
        };
        let bits = 8 * f.width as u32;
        if f.bcd {
            // In range (0..=10^(2 × width) - 1, checked above): its digits, and its value as
            // decode reads it.
            write_number(f, crate::number::to_bcd(word), slot);
            ints.push(word as i64);
            continue;
        }
        write_number(f, word, slot);
        ints.push(if f.signed {
            sign_extend(word, bits)
        } else {
            word as i64
        });
    }
    for (_, f, recs) in &records {
        check_records(f, recs)?;
    }
    // The payload as it travels (`framing.transform`), then the checksum over it.
    p.framing.transform_in_place(&mut out);
    if !m.unchecked {
        reseal_from(p, m.direction, &mut out, 0);
    }
    if let Some(from) = m.over_request {
        let Some(request) = covered else {
            return Err(EncodeError::NeedsRequest {
                message: m.name.clone(),
            });
        };
        let c = &p.framing.checksum;
        let at = p.framing.checksum_at_of(m.direction, out.len());
        let sum = c.compute_after(request, out.get(from..at).unwrap_or(&[]));
        write_uint(sum, &mut out[at..at + c.len()], c.byte_order);
    }
    // End bytes alone delimit the frame: its list to the end must not show them before its
    // own (a receiver would end the frame there).
    if let Some((f, at)) = m.delimited_list(&p.framing) {
        let end = &p.framing.end;
        let own = out.len().saturating_sub(end.len());
        let first = out.get(at..).and_then(|list| p.framing.first_end(list));
        if let Some(i) = first.filter(|&i| at + i < own) {
            return Err(EncodeError::HoldsEnd {
                field: f.name.clone(),
                offset: at + i,
                end: end.clone(),
            });
        }
    }
    if m.is_variable() {
        // A count field given a value, or one that follows another, may disagree with the
        // list: what encode writes, decode must accept.
        decode_as_unescaped(p, r, Over::Check(covered), &out).map_err(|e| {
            EncodeError::Inconsistent {
                reason: e.to_string(),
            }
        })?;
    }
    if p.framing.escaping.is_some() {
        return Ok(escape::escape_as(p, r.direction, &out));
    }
    // Short where the length fits the short form, long otherwise (`framing.length.long`).
    let mut out = crate::long::travel(p, out);
    if let Some(pre) = &p.framing.preamble {
        // The wake-up bytes, then the frame.
        out.splice(
            0..0,
            std::iter::repeat(pre.byte).take(usize::from(pre.send)),
        );
    }
    Ok(out)
}

/// The records given for repeated record `f` (repeat `r`): as many as the repeat allows, each
/// with one value for each of the record's fields (their ranges: [`check_records`]).
#[cfg(feature = "tools")]
fn record_list<'v>(
    f: &Field,
    r: &crate::ir::Repeat,
    given: Option<&'v Raw>,
) -> Result<&'v [Vec<i64>], EncodeError> {
    let recs: &[Vec<i64>] = match given {
        Some(Raw::Records(l)) => l,
        Some(_) => {
            return Err(EncodeError::NotList {
                field: f.name.clone(),
            })
        }
        None => {
            return Err(EncodeError::MissingValue {
                field: f.name.clone(),
            })
        }
    };
    if recs.len() < r.min || recs.len() > r.max {
        return Err(EncodeError::WrongCount {
            field: f.name.clone(),
            min: r.min,
            max: r.max,
            found: recs.len(),
        });
    }
    for rec in recs {
        if rec.len() > f.record.len() {
            return Err(EncodeError::UnknownValue {
                field: format!("{}[{}]", f.name, f.record.len()),
            });
        }
        if rec.len() < f.record.len() {
            return Err(EncodeError::MissingValue {
                field: f.record_field_name(rec.len()),
            });
        }
    }
    Ok(recs)
}

/// Each field of each record of `f` within its range and its wire type: checked once the
/// fields at their places are, as generated code writes (and checks) records last.
#[cfg(feature = "tools")]
fn check_records(f: &Field, recs: &[Vec<i64>]) -> Result<(), EncodeError> {
    for rec in recs {
        for (j, (g, &v)) in f.record.iter().zip(rec).enumerate() {
            let name = f.record_field_name(j);
            if let Some((min, max)) = range_violation(g, None, v) {
                return Err(EncodeError::NotInRange {
                    field: name,
                    value: v,
                    min,
                    max,
                    kind: NumKind::Int,
                });
            }
            let (min, max) = g.raw_span();
            if v < min || v > max {
                return Err(EncodeError::OutOfRange {
                    field: name,
                    value: v,
                    min,
                    max,
                });
            }
        }
    }
    Ok(())
}

/// Reorders a frame between the document's printed byte order and the wire's: every multi-byte
/// number field (and the checksum) is reversed when the two orders differ. `text` must already
/// have the message's frame length.
pub fn printed_to_wire(p: &Protocol, m: &Message, printed: &[u8]) -> Vec<u8> {
    reorder(p, m, printed, p.printed_byte_order)
}

/// The reordering of [`printed_to_wire`] (and back), `order` the order `text`'s count fields
/// are read in.
fn reorder(p: &Protocol, m: &Message, text: &[u8], order: ByteOrder) -> Vec<u8> {
    let mut wire = text.to_vec();
    // Beside payload truncation (`framing.truncation`) example text is the bytes as they
    // travel: a truncated frame is shorter than the layout that places its parts, and the
    // printed byte order is the wire's (validated).
    if p.framing.truncation.is_some() {
        return wire;
    }
    // Values that place fields (a presence condition, a count, a record's width) are read
    // as the fields hold them: with the payload's transform undone. Reversing a field's bytes
    // commutes with a per-byte transform, so the reordering itself works on `text` as it is.
    let text = &*p.framing.untransformed(text);
    let o = m.layout;
    let flip = |order: ByteOrder| order != p.printed_byte_order;
    let end = wire.len().saturating_sub(trailer_of(p, m));
    // Fields in wire order, each list's elements counted as decode counts them: by its count
    // field, already reordered, or to what the fixed fields after it leave.
    let mut shifts: Vec<usize> = Vec::with_capacity(m.fields.len());
    let mut shift = 0usize;
    for (i, f) in m.fields.iter().enumerate() {
        shifts.push(shift);
        let at = f.frame_at(&o) + shift;
        if let Some(c) = &f.present {
            // An optional field: where its condition holds (on a field before it, always on
            // the wire), it sits after the optional fields before it that are present.
            let v = m.fields.get(c.field).map_or(0, |cf| {
                let cat = o.payload + cf.offset;
                text.get(cat..cat + cf.width)
                    .map_or(0, |b| read_uint(b, order))
            });
            if !c.holds(v as i64) {
                continue;
            }
            shift += f.width;
        }
        let f = &*record_sized(m, f, |name| {
            let c = m.fields.iter().position(|c| c.name == name)?;
            let cf = &m.fields[c];
            let cat = o.payload + cf.offset + shifts.get(c).copied().unwrap_or(0);
            text.get(cat..cat + cf.width)
                .map(|b| read_uint(b, order) as i64)
        });
        let n = match &f.repeat {
            Some(r) => {
                let fixed_after: usize = m.fields[i + 1..]
                    .iter()
                    .filter(|g| g.repeat.is_none())
                    .map(|g| g.width)
                    .sum();
                let fit = f.elements_from(end.saturating_sub(at).saturating_sub(fixed_after));
                let n = match r.count {
                    Count::ToEnd => fit,
                    Count::Fixed(n) => n.min(fit),
                    // Characters up to the first terminator (the terminator's byte follows).
                    Count::Until(t) => text
                        .get(at..end)
                        .and_then(|b| b.iter().position(|&x| x == t))
                        .unwrap_or(0),
                    Count::Elements(c) | Count::Bytes(c) => {
                        let cf = &m.fields[c];
                        let cat = o.payload + cf.offset + shifts.get(c).copied().unwrap_or(0);
                        let v = text
                            .get(cat..cat + cf.width)
                            .map_or(0, |b| read_uint(b, order));
                        let v = usize::try_from(v).unwrap_or(usize::MAX);
                        match r.count {
                            Count::Bytes(_) => f.elements_from(v),
                            _ => v,
                        }
                        .min(fit)
                    }
                };
                shift += f.elements_len(n);
                n
            }
            None => 1,
        };
        if f.is_record() {
            for k in 0..n {
                for g in f
                    .record
                    .iter()
                    .filter(|g| g.width > 1 && flip(g.byte_order))
                {
                    let s = at + k * f.width + g.offset;
                    if let Some(s) = wire.get_mut(s..s + g.width) {
                        s.reverse();
                    }
                }
            }
            continue;
        }
        if f.is_ascii() || f.packed.is_some() || f.width < 2 || !flip(f.byte_order) {
            continue;
        }
        for k in 0..n {
            let s = at + k * f.width;
            if let Some(s) = wire.get_mut(s..s + f.width) {
                s.reverse();
            }
        }
    }
    let c = &p.framing.checksum;
    let at = p.framing.checksum_at_of(m.direction, wire.len());
    // A checksum followed by its complement is two bytes, each printed as it travels.
    let bytes = matches!(c.algorithm, crate::ir::ChecksumAlgorithm::Complemented(..));
    if c.len() > 1 && flip(c.byte_order) && !m.unchecked && !bytes {
        if let Some(s) = wire.get_mut(at..at + c.len()) {
            s.reverse();
        }
    }
    if let Some(l) = &p.framing.length {
        for at in o.lengths() {
            if l.width > 1 && flip(p.byte_order) {
                if let Some(s) = wire.get_mut(at..at + l.width) {
                    s.reverse();
                }
            }
        }
    }
    wire
}

/// The same reordering the other way. An escaped frame (`framing.escaping`) is reordered
/// unescaped and escaped again, byte for byte, as example text is read back; the preamble
/// bytes before a frame (`framing.preamble`) are kept as they are.
#[cfg(feature = "tools")]
pub fn wire_to_printed(p: &Protocol, m: &Message, wire: &[u8]) -> Vec<u8> {
    let frame = p.framing.after_preamble(wire);
    let mut out = wire[..wire.len() - frame.len()].to_vec();
    let wire = frame;
    out.extend(
        match escape::unescape_bytes_of(&p.framing, m.direction, wire) {
            Ok(plain) if p.framing.escaping.is_some() => escape::escape_bytes_of(
                &p.framing,
                m.direction,
                &reorder(p, m, &plain, p.byte_order),
            ),
            _ => reorder(p, m, wire, p.byte_order),
        },
    );
    out
}

/// Parses frame text as people write it: hex digits with optional `0x` prefixes, spaces,
/// commas, colons, dashes. `"0x AA21 2000 0000 3A98 BD"` is nine bytes. An error names the
/// first character that is none of these by its place in `text`, counted in characters
/// from 1.
pub fn parse_hex(text: &str) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::with_capacity(text.len() / 2);
    // The first digit of a byte, until its second comes.
    let mut high: Option<u8> = None;
    let mut digits = 0usize;
    let mut chars = text.chars().enumerate().peekable();
    while let Some((i, ch)) = chars.next() {
        if ch == '0' && matches!(chars.peek(), Some((_, 'x' | 'X'))) {
            chars.next();
            continue;
        }
        match ch.to_digit(16) {
            Some(d) => {
                digits += 1;
                match high.take() {
                    Some(h) => bytes.push((h << 4) | d as u8),
                    None => high = Some(d as u8),
                }
            }
            None if matches!(ch, ' ' | '\t' | ',' | ':' | '-' | '_' | '\n' | '\r') => {}
            None => return Err(format!("`{ch}` at character {} is not a hex digit", i + 1)),
        }
    }
    if digits == 0 {
        return Err("no hex digits".to_owned());
    }
    if high.is_some() {
        return Err(format!("odd number of hex digits ({digits})"));
    }
    Ok(bytes)
}

/// Uppercase hex, bytes separated by spaces: `AA 21 50 1B`.
#[cfg(feature = "tools")]
pub fn format_hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A message's leaf names paired with the field that holds each.
pub fn leaf_field<'a>(m: &'a Message, name: &str) -> Option<(&'a Field, Option<&'a BitField>)> {
    m.fields.iter().find_map(|f| {
        if f.bits.is_empty() {
            (f.name == name).then_some((f, None))
        } else {
            f.bits.iter().find(|b| b.name == name).map(|b| (f, Some(b)))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `read_uint` reads every width of either byte order as the plain loop over its bytes
    /// does (widths 1 and 2 have a path of their own).
    #[test]
    fn read_uint_reads_every_width_in_both_orders() {
        let bytes: Vec<u8> = (0..8u8)
            .map(|i| 0x81u8.wrapping_mul(i + 3) ^ 0x5A)
            .collect();
        for width in 0..=8 {
            let b = &bytes[..width];
            let big = b.iter().fold(0u64, |acc, &x| (acc << 8) | u64::from(x));
            let little = b
                .iter()
                .rev()
                .fold(0u64, |acc, &x| (acc << 8) | u64::from(x));
            assert_eq!(read_uint(b, ByteOrder::Big), big, "width {width}, big");
            assert_eq!(
                read_uint(b, ByteOrder::Little),
                little,
                "width {width}, little"
            );
        }
        assert_eq!(read_uint(&[0x12, 0x34], ByteOrder::Big), 0x1234);
        assert_eq!(read_uint(&[0x12, 0x34], ByteOrder::Little), 0x3412);
        assert_eq!(read_uint(&[0xFE], ByteOrder::Little), 0xFE);
    }

    /// A character that is not a hex digit is named with its place in the text as given,
    /// counted in characters from 1, also after `0x` prefixes.
    #[test]
    fn parse_hex_names_the_place_in_the_text_as_given() {
        for (text, at) in [
            ("AA2G", 4),
            ("0xAA 0xZZ", 8),
            ("0XAA,0xBB;", 10),
            ("0x0x0xA?", 8),
            ("é0xAA", 1),
            ("0xAA é", 6),
        ] {
            let err = parse_hex(text).expect_err(text);
            assert!(
                err.ends_with(&format!("at character {at} is not a hex digit")),
                "{text}: {err}"
            );
        }
        assert_eq!(
            parse_hex("0xAA 0X21, 50:1b-0x0F"),
            Ok(vec![0xAA, 0x21, 0x50, 0x1B, 0x0F])
        );
        assert_eq!(parse_hex("A0xB"), Ok(vec![0xAB]));
        assert_eq!(parse_hex(" 0x "), Err("no hex digits".to_owned()));
        assert_eq!(
            parse_hex("AA 2"),
            Err("odd number of hex digits (3)".to_owned())
        );
    }
}
