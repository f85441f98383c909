//! The spec model: the YAML file exactly as written, before any checking beyond its shape.
//!
//! Every struct rejects unknown keys, so a misspelt key is an error and never silently ignored.
//! `spec/SCHEMA.md` documents the format for the people who edit it; keep the two in step.

use std::collections::BTreeMap;

// The trait from `serde::de`: serde's root also exports the derive when another crate of the
// build turns on its `derive` feature, and the derive here is serde_derive's.
use serde::de::{Deserialize, Deserializer};
use serde_derive::Deserialize;

/// A number written as decimal text (`"0.01"`, `"360/4096"`) or as a YAML number.
///
/// Kept as text so that `0.01` stays exact: [`crate::rational::Rational`] parses it.
#[derive(Debug, Clone, PartialEq)]
pub struct NumberText(pub String);

impl<'de> Deserialize<'de> for NumberText {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = NumberText;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, or a decimal or fraction as text (\"0.01\", \"360/4096\")")
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<NumberText, E> {
                Ok(NumberText(s.to_owned()))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumberText, E> {
                Ok(NumberText(v.to_string()))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumberText, E> {
                Ok(NumberText(v.to_string()))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumberText, E> {
                // `{}` prints the shortest text that reads back as the same f64: 0.01 -> "0.01".
                Ok(NumberText(format!("{v}")))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    pub protocol: String,
    pub title: String,
    pub document: Document,
    pub byte_order: ByteOrder,
    pub printed_byte_order: ByteOrder,
    pub serial: Serial,
    pub framing: Framing,
    #[serde(default)]
    pub units: Vec<Unit>,
    #[serde(default)]
    pub enums: Vec<EnumDef>,
    #[serde(default)]
    pub flags: Vec<FlagSet>,
    #[serde(default)]
    pub commands: Vec<Command>,
    #[serde(default)]
    pub responses: Vec<Response>,
    #[serde(default)]
    pub common_responses: Vec<String>,
    #[serde(default)]
    pub examples: Vec<Example>,
    #[serde(default)]
    pub errata: Vec<Erratum>,
    /// What a bus master needs: see [`crate::transactions`].
    #[serde(default)]
    pub transactions: Option<crate::transactions::Section>,
    /// What a device holds and what its commands do to it: see [`crate::device`].
    #[serde(default)]
    pub device: Option<crate::device::Section>,
}

/// The keys of [`Spec`], in file order; the loader checks top-level keys against it.
pub const SPEC_KEYS: &[&str] = &[
    "protocol",
    "title",
    "document",
    "byte_order",
    "printed_byte_order",
    "serial",
    "framing",
    "units",
    "enums",
    "flags",
    "commands",
    "responses",
    "common_responses",
    "examples",
    "errata",
    "transactions",
    "device",
];

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Document {
    pub title: String,
    #[serde(default)]
    pub file: Option<String>,
    pub revision: String,
    pub date: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ByteOrder {
    Little,
    Big,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Parity {
    None,
    Even,
    Odd,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Serial {
    #[serde(default)]
    pub section: Option<String>,
    pub baud: u32,
    pub data_bits: u8,
    pub parity: Parity,
    pub stop_bits: u8,
    #[serde(default)]
    pub inter_frame_gap_ms: Option<u32>,
    #[serde(default)]
    pub frame_rate: Option<FrameRate>,
    #[serde(default)]
    pub baud_rates: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameRate {
    pub typical_per_s: u32,
    pub max_per_s: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    Start,
    Address,
    Code,
    Payload,
    Checksum,
    /// A length field (see [`LengthField`]).
    Length,
    /// Constant bytes after the checksum that end every frame (`framing.end`).
    End,
    /// The header fields every message carries (`framing.header`), in their order.
    Header,
}

/// The start of a frame: one byte (`0xAA`) or a sync sequence (`[0xFF, 0xFF]`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StartBytes {
    One(i64),
    Many(Vec<i64>),
}

/// A number is one byte, a list of numbers several; anything else is named as wrong.
impl<'de> Deserialize<'de> for StartBytes {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let v = serde_yaml::Value::deserialize(d)?;
        let wrong = || D::Error::custom("expected a byte (0x7E) or a list of bytes ([0xFF, 0xFF])");
        match v {
            serde_yaml::Value::Number(_) => i64::deserialize(v)
                .map(StartBytes::One)
                .map_err(|_| wrong()),
            serde_yaml::Value::Sequence(_) => Vec::<i64>::deserialize(v)
                .map(StartBytes::Many)
                .map_err(|_| wrong()),
            _ => Err(wrong()),
        }
    }
}

impl StartBytes {
    pub fn bytes(&self) -> Vec<i64> {
        match self {
            StartBytes::One(b) => vec![*b],
            StartBytes::Many(v) => v.clone(),
        }
    }
}

/// `framing.start`: the start bytes every frame begins with, or (MSP's `$M<` and `$M>`) the
/// bytes of each direction, of the same length.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Start {
    Same(StartBytes),
    ByDirection(DirectionStart),
}

/// A mapping is the start bytes by direction (so a misspelt key is named), anything else the
/// bytes of both.
impl<'de> Deserialize<'de> for Start {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let v = serde_yaml::Value::deserialize(d)?;
        if v.is_mapping() {
            DirectionStart::deserialize(v)
                .map(Start::ByDirection)
                .map_err(D::Error::custom)
        } else {
            StartBytes::deserialize(v)
                .map(Start::Same)
                .map_err(|_| D::Error::custom("expected a start byte, a list of start bytes, or `{request: [...], response: [...]}`"))
        }
    }
}

/// `framing.start: {request: ..., response: ...}`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionStart {
    pub request: StartBytes,
    pub response: StartBytes,
}

/// `framing.layout`: one list of parts for both directions, or (Sensirion SHDLC, whose
/// replies carry a state byte that requests lack) a list per direction.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Layout {
    Same(Vec<Part>),
    ByDirection(DirectionLayout),
}

/// `framing.layout: {request: [...], response: [...]}`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionLayout {
    pub request: Vec<Part>,
    pub response: Vec<Part>,
}

/// A mapping is a layout per direction (so a misspelt key is named), anything else the one
/// layout of both.
impl<'de> Deserialize<'de> for Layout {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let v = serde_yaml::Value::deserialize(d)?;
        if v.is_mapping() {
            DirectionLayout::deserialize(v)
                .map(Layout::ByDirection)
                .map_err(D::Error::custom)
        } else {
            Vec::<Part>::deserialize(v)
                .map(Layout::Same)
                .map_err(D::Error::custom)
        }
    }
}

impl Layout {
    /// The layout of a direction (the one layout where it is given once).
    pub fn of(&self, request: bool) -> &Vec<Part> {
        match self {
            Layout::Same(l) => l,
            Layout::ByDirection(d) if request => &d.request,
            Layout::ByDirection(d) => &d.response,
        }
    }
}

/// The validator reads a layout as a list where it is one (a layout per direction is split
/// into two plain framings before anything reads it so): the request's otherwise.
impl std::ops::Deref for Layout {
    type Target = Vec<Part>;
    fn deref(&self) -> &Vec<Part> {
        self.of(true)
    }
}

/// A length field in the framing: its width and which parts of the frame it counts.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LengthField {
    /// Bytes: 1 or 2 (in the protocol's byte order).
    pub width: i64,
    /// The parts whose bytes it counts (`[code, payload, checksum]`).
    pub counts: Vec<Part>,
    /// Added to the count of those bytes (optional, default 0).
    #[serde(default)]
    pub adjust: Option<i64>,
    /// A second, wider form of the length field that a second start byte announces (VESC's
    /// `03 lenH lenL`), sent only where the length does not fit `width`; optional.
    #[serde(default)]
    pub long: Option<LongLength>,
}

/// The long form of a length field (`framing.length.long`): frames starting with `start`
/// carry a length field of `width` bytes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LongLength {
    pub start: i64,
    pub width: i64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Framing {
    #[serde(default)]
    pub section: Option<String>,
    pub layout: Layout,
    #[serde(default)]
    pub start: Option<Start>,
    #[serde(default)]
    pub length: Option<LengthField>,
    /// The bytes that end every frame, after the checksum; required iff the layout has `end`.
    #[serde(default)]
    pub end: Option<StartBytes>,
    /// Required iff the layout has `address`.
    #[serde(default)]
    pub address: Option<Address>,
    pub request: DirectionFraming,
    pub response: DirectionFraming,
    /// Required iff the layout has `checksum`.
    #[serde(default)]
    pub checksum: Option<Checksum>,
    /// Escaping or stuffing applied to every frame on the wire (optional).
    #[serde(default)]
    pub escaping: Option<Escaping>,
    /// Fields every message carries, where the layout's `header` part places them (MAVLink's
    /// sequence, system and component bytes); required iff the layout has `header`. With a
    /// layout per direction, a list per direction (`{request: [...], response: [...]}`, JBD's
    /// BMS: a request's state, a reply's status).
    #[serde(default)]
    pub header: Option<Header>,
    /// Wake-up bytes sent before every frame (DL/T 645's `FE FE FE FE`), optional.
    #[serde(default)]
    pub preamble: Option<Preamble>,
    /// A per-byte transform of the payload (DL/T 645's +33H on every data byte), optional.
    #[serde(default)]
    pub transform: Option<Transform>,
    /// Other forms of the frame, each told apart by its start byte (M-Bus's short frame
    /// `10 C A CS 16` beside the long `68 L L 68 ...`), optional.
    #[serde(default)]
    pub forms: Vec<Form>,
    /// Payload truncation (MAVLink v2's trailing zeros), optional.
    #[serde(default)]
    pub truncation: Option<Truncation>,
}

/// How a sender shortens a payload (`framing.truncation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Truncation {
    /// The payload's trailing zero bytes stripped, at least one byte kept; a receiver pads a
    /// shorter payload with zeros up to its message's length (MAVLink v2).
    TrailingZeros,
}

/// Another form of the frame (`framing.forms`): the layout without the parts it drops, opened
/// by a start byte of its own; a frame with an empty payload travels in it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Form {
    #[serde(default)]
    pub section: Option<String>,
    pub start: i64,
    pub drops: Vec<Part>,
}

/// A per-byte transform of every payload byte as it travels: exactly one of `add` (the byte
/// plus it, mod 256: DL/T 645's 0x33) or `xor`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    #[serde(default)]
    pub section: Option<String>,
    #[serde(default)]
    pub add: Option<i64>,
    #[serde(default)]
    pub xor: Option<i64>,
}

/// A preamble: `send` copies of `byte` written before every frame, 0 to `max` (default
/// `send`) of them accepted before one.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preamble {
    #[serde(default)]
    pub section: Option<String>,
    pub byte: i64,
    pub send: i64,
    #[serde(default)]
    pub max: Option<i64>,
}

/// How frames are escaped or stuffed on the wire: exactly one of `escape` (with `xor` and
/// `bytes`, or `map`), `insert` (with `after` and `from`) or `cobs`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Escaping {
    #[serde(default)]
    pub section: Option<String>,
    /// Where the checksum and the length field are computed: on the frame before escaping or
    /// on the bytes as they travel.
    pub computed: Computed,
    /// The escape byte (SLIP, KISS, HDLC): each byte of `bytes` (or `map`) travels as the
    /// escape byte followed by its replacement.
    #[serde(default)]
    pub escape: Option<i64>,
    /// With `escape` and `bytes`: the replacement is the byte XOR this mask (HDLC: 0x20).
    #[serde(default)]
    pub xor: Option<i64>,
    #[serde(default)]
    pub bytes: Option<Vec<i64>>,
    /// With `escape`: each escaped byte and the byte that stands for it (SLIP: C0 as DC).
    #[serde(default)]
    pub map: Option<Vec<EscapeMap>>,
    /// The byte inserted after every occurrence of `after` (Dynamixel 2.0: FD after FF FF FD).
    #[serde(default)]
    pub insert: Option<i64>,
    #[serde(default)]
    pub after: Option<StartBytes>,
    /// With `insert`: the first part stuffed; stuffing runs through the payload.
    #[serde(default)]
    pub from: Option<Part>,
    /// Consistent overhead byte stuffing (`cobs: true`).
    #[serde(default)]
    pub cobs: Option<bool>,
}

/// Where a checksum and a length field are computed, relative to escaping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Computed {
    /// On the frame before escaping (SLIP, KISS, HDLC, COBS).
    Unescaped,
    /// On the bytes as they travel (Dynamixel 2.0: the length counts the stuffed bytes and the
    /// CRC covers them).
    Escaped,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EscapeMap {
    pub byte: i64,
    #[serde(rename = "as")]
    pub replacement: i64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Address {
    #[serde(default)]
    pub host: Option<i64>,
    pub devices: Range,
    #[serde(default)]
    pub broadcast: Option<i64>,
    #[serde(default)]
    pub default: Option<i64>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub min: i64,
    pub max: i64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionFraming {
    pub code_lengths: Vec<i64>,
    pub payload: Range,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChecksumAlgorithm {
    Sum8,
    /// The 8-bit sum, inverted (ones' complement): `!sum`.
    Sum8OnesComplement,
    /// The 8-bit sum, negated (two's complement): `-sum`, so all bytes sum to zero.
    Sum8TwosComplement,
    /// FrSky's S.Port and F.Port checksum: an 8-bit sum in which each carry out of the top bit
    /// is added back in (end-around carry: `s += byte; s = (s & 0xFF) + (s >> 8)`), sent
    /// inverted (`0xFF - s`). Not `sum8_ones_complement`, which inverts the plain sum.
    Sum8EndAround,
    /// 8-bit XOR of every byte.
    Xor8,
    /// Modbus ASCII's longitudinal redundancy check: the 8-bit sum negated, the same as
    /// `sum8_twos_complement` (which the IR, docs and diff call it).
    Lrc,
    /// 16-bit sum of every byte, modulo 65536.
    Sum16,
    /// The 16-bit sum, inverted (ones' complement): `!sum`.
    Sum16OnesComplement,
    /// The 16-bit sum, negated (two's complement): `-sum`, so the bytes and the checksum's
    /// value sum to zero modulo 65536 (the JBD battery management protocol's).
    Sum16TwosComplement,
    /// Two 8-bit running sums modulo 256 (`a += byte; b += a`), u-blox UBX's 8-bit Fletcher:
    /// the value `b << 8 | a`, so `byte_order: little` sends `a` first.
    Fletcher8,
    /// Fletcher-16: two running sums modulo 255, the value `b << 8 | a`.
    Fletcher16,
    Crc,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checksum {
    pub algorithm: ChecksumAlgorithm,
    pub width: i64,
    #[serde(default)]
    pub byte_order: Option<ByteOrder>,
    #[serde(default)]
    pub poly: Option<i64>,
    #[serde(default)]
    pub init: Option<i64>,
    #[serde(default)]
    pub refin: Option<bool>,
    #[serde(default)]
    pub refout: Option<bool>,
    #[serde(default)]
    pub xorout: Option<i64>,
    #[serde(default)]
    pub catalogue: Option<String>,
    pub check: i64,
    /// A sum or XOR kept to these bits (`0x7F`: the sum's low seven bits).
    #[serde(default)]
    pub mask: Option<i64>,
    /// Followed by its complement (HerkuleX's CS1, CS2): the checksum takes two bytes, its
    /// 8-bit value and then that value's bitwise complement, both kept to `mask`. 8-bit sums
    /// and XOR only.
    #[serde(default)]
    pub complement: Option<bool>,
    /// The first part of the frame the checksum covers (default: the first part); it covers
    /// every byte from there up to itself. With a layout per direction, a part per direction
    /// (`{request: code, response: header}`, JBD's BMS).
    #[serde(default)]
    pub covers_from: Option<CoversFrom>,
    /// A byte of each message's own the checksum takes after the bytes it covers (MAVLink's
    /// CRC_EXTRA): `per_message`, each message giving its `checksum_extra`.
    #[serde(default)]
    pub extra: Option<ChecksumExtra>,
}

/// `framing.header`: the header fields of every direction whose layout has `header`, or (a
/// layout per direction) the fields of each direction.
#[derive(Debug, Clone)]
pub enum Header {
    Same(Vec<Field>),
    ByDirection(DirectionHeader),
}

/// `framing.header: {request: [...], response: [...]}`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionHeader {
    pub request: Vec<Field>,
    pub response: Vec<Field>,
}

/// A mapping is the fields per direction (so a misspelt key is named), a list the fields of
/// both; read through the deserializer's own sequence and map, so an error inside a field
/// keeps its path.
impl<'de> Deserialize<'de> for Header {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Header;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a list of header fields, or `{request: [...], response: [...]}`")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Header, A::Error> {
                let mut out = Vec::new();
                while let Some(f) = seq.next_element::<Field>()? {
                    out.push(f);
                }
                Ok(Header::Same(out))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Header, A::Error> {
                DirectionHeader::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(Header::ByDirection)
            }
        }
        d.deserialize_any(V)
    }
}

impl Header {
    /// The header fields of a direction (the one list where it is given once).
    pub fn of(&self, request: bool) -> &Vec<Field> {
        match self {
            Header::Same(l) => l,
            Header::ByDirection(d) if request => &d.request,
            Header::ByDirection(d) => &d.response,
        }
    }
}

/// `framing.checksum.covers_from`: the part the checksum of every frame covers from, or (a
/// layout per direction) the part of each direction's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoversFrom {
    Same(Part),
    ByDirection(DirectionPart),
}

/// `framing.checksum.covers_from: {request: ..., response: ...}`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionPart {
    pub request: Part,
    pub response: Part,
}

impl CoversFrom {
    /// The part a direction's checksum covers from.
    pub fn of(&self, request: bool) -> Part {
        match self {
            CoversFrom::Same(p) => *p,
            CoversFrom::ByDirection(d) if request => d.request,
            CoversFrom::ByDirection(d) => d.response,
        }
    }
}

/// A mapping is a part per direction (so a misspelt key is named), anything else the part of
/// both.
impl<'de> Deserialize<'de> for CoversFrom {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let v = serde_yaml::Value::deserialize(d)?;
        if v.is_mapping() {
            DirectionPart::deserialize(v)
                .map(CoversFrom::ByDirection)
                .map_err(D::Error::custom)
        } else if v.is_string() {
            Part::deserialize(v)
                .map(CoversFrom::Same)
                .map_err(D::Error::custom)
        } else {
            Err(D::Error::custom(
                "expected a part of the layout (`code`) or a part per direction (`{request: code, response: header}`)",
            ))
        }
    }
}

/// Where a checksum's extra byte comes from (`framing.checksum.extra`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChecksumExtra {
    /// Each message's `checksum_extra`.
    PerMessage,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unit {
    pub name: String,
    pub symbol: String,
    pub scale: NumberText,
    #[serde(default)]
    pub offset: Option<NumberText>,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnumDef {
    pub name: String,
    #[serde(default)]
    pub section: Option<String>,
    #[serde(default)]
    pub doc: Option<String>,
    pub values: Vec<EnumValue>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnumValue {
    pub value: i64,
    pub name: String,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlagSet {
    pub name: String,
    #[serde(default)]
    pub section: Option<String>,
    #[serde(default)]
    pub doc: Option<String>,
    pub bits: Vec<Flag>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flag {
    pub bit: i64,
    pub name: String,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CommandKind {
    Movement,
    CompletionCheck,
    Setter,
    Getter,
    Reset,
}

/// Whether a command gets a reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Reply {
    /// One of its `responses` always comes (the default).
    #[default]
    Required,
    /// One of its `responses` may come, or none.
    Optional,
    /// None ever comes: it lists no `responses` (Pelco-P, a broadcast-only command).
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResponseKind {
    Ack,
    Nak,
    Data,
    Echo,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Broadcast {
    pub accepted: bool,
    pub answered: bool,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Command {
    pub name: String,
    pub title: String,
    pub section: String,
    pub kind: CommandKind,
    pub code: String,
    #[serde(default)]
    pub doc: Option<String>,
    #[serde(default)]
    pub fields: Vec<Field>,
    #[serde(default)]
    pub responses: Vec<String>,
    /// Whether a reply comes: `required` (default), `optional` or `none`.
    #[serde(default)]
    pub reply: Reply,
    #[serde(default)]
    pub response_meanings: OpenMap,
    #[serde(default)]
    pub broadcast: Option<Broadcast>,
    /// The byte the checksum takes after the frame's covered bytes, where
    /// `framing.checksum.extra` is `per_message`.
    #[serde(default)]
    pub checksum_extra: Option<i64>,
    /// `checksum: none`: this command's frames travel without the framing's checksum.
    #[serde(default)]
    pub checksum: Option<MessageChecksum>,
    /// Values this command's header fields (`framing.header`) always hold, by name: JBD's
    /// BMS sends every read with the state byte `0xA5`, every write with `0x5A`.
    #[serde(default)]
    pub header: BTreeMap<String, i64>,
}

/// A message's own `checksum:` (`none`: its frames travel without the framing's checksum,
/// as RoboClaw's read commands are sent as address and command alone).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MessageChecksum {
    /// No checksum: the frame ends where the framing's checksum would begin.
    None,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Response {
    pub name: String,
    pub title: String,
    pub section: String,
    pub kind: ResponseKind,
    /// Its code; required unless the response is a constant whole frame (`frame`).
    #[serde(default)]
    pub code: Option<String>,
    /// A constant whole frame (hex bytes, `"E5"`): the response is these bytes and nothing
    /// else, outside the framing (M-Bus's single character); no code, fields or checksum.
    #[serde(default)]
    pub frame: Option<String>,
    #[serde(default)]
    pub doc: Option<String>,
    #[serde(default)]
    pub fields: Vec<Field>,
    #[serde(default)]
    pub needs_request: bool,
    /// The device sends this frame on its own (`unasked: true`), not only (or not at all) as
    /// the reply to a request: a KISS TNC's received data frames, a GNSS receiver's periodic
    /// output. Such a response need not be listed by any command.
    #[serde(default)]
    pub unasked: bool,
    /// The reply's code derives from the request's: for every command that lists it, its
    /// code is the command's code with these bits set (Modbus exceptions: `0x80`).
    #[serde(default)]
    pub code_from_request: Option<CodeFromRequest>,
    /// As [`Command::checksum_extra`].
    #[serde(default)]
    pub checksum_extra: Option<i64>,
    /// The reply's checksum takes in its request's bytes: it runs over the bytes the
    /// request's checksum covers, then over the reply's own from `covers_from` (Pelco D's
    /// general response: the request's sum plus the alarm byte).
    #[serde(default)]
    pub checksum_over_request: Option<OverRequest>,
    /// As [`Command::checksum`].
    #[serde(default)]
    pub checksum: Option<MessageChecksum>,
    /// As [`Command::header`].
    #[serde(default)]
    pub header: BTreeMap<String, i64>,
}

/// A reply's `checksum_over_request`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OverRequest {
    /// The first part of the reply its checksum covers after the request's bytes.
    pub covers_from: Part,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CodeFromRequest {
    pub or: i64,
}

/// A number field's 16-bit word order (`word_order`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WordOrder {
    /// As the protocol's `byte_order` puts the whole number (the default).
    Normal,
    /// The 16-bit words in the opposite order, each word's bytes in the protocol's byte order.
    Swapped,
}

/// A number field's `encoding`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Encoding {
    /// Binary (the default).
    Binary,
    /// Binary-coded decimal: each byte two decimal digits, the high nibble the more
    /// significant; the bytes in the field's byte order. Its raw value is the decimal number.
    Bcd,
}

/// A field's `range`: raw wire integers, or numbers (decimals allowed) for a float field.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldRange {
    pub min: Bound,
    pub max: Bound,
}

/// One end of a field's range as written: an integer (up to `u64::MAX`) or a decimal.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Bound {
    Int(i64),
    Uint(u64),
    Float(f64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldType {
    U8,
    U16,
    U32,
    I8,
    I16,
    I32,
    U24,
    I24,
    /// 64-bit integers: a `u64` travels as its bits in an `i64` (`FieldValue::Int`, the
    /// interpreter's `Raw::Int`), so values above `i64::MAX` read as negative there.
    U64,
    I64,
    /// IEEE-754 binary32 and binary64; their raw value is their bits.
    F32,
    F64,
    Ascii,
    /// One bit; only as the element of a `repeat` (coils), packed least significant bit first.
    Bit,
    /// A named group of fixed-width fields (`fields`); only as the element of a `repeat`
    /// (Dynamixel SYNC_WRITE's blocks, register/value pairs).
    Record,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Field {
    pub name: String,
    #[serde(rename = "type")]
    pub ty: FieldType,
    #[serde(default)]
    pub length: Option<i64>,
    /// The order of a 32- or 64-bit number's 16-bit words (Modbus registers): `swapped` sends
    /// them in the opposite order to the protocol's `byte_order`, each word's bytes in it.
    #[serde(default)]
    pub word_order: Option<WordOrder>,
    /// How the number's bytes hold it: `bcd` (two decimal digits a byte, as meters send
    /// readings and addresses). The default is binary.
    #[serde(default)]
    pub encoding: Option<Encoding>,
    #[serde(default)]
    pub unit: Option<String>,
    #[serde(default)]
    pub range: Option<FieldRange>,
    #[serde(default)]
    pub value: Option<i64>,
    #[serde(default, rename = "enum")]
    pub enum_: Option<String>,
    #[serde(default)]
    pub flags: Option<String>,
    #[serde(default)]
    pub equals: Option<String>,
    #[serde(default)]
    pub special: Vec<Special>,
    #[serde(default)]
    pub bits: Vec<BitField>,
    #[serde(default)]
    pub repeat: Option<Repeat>,
    /// A fixed number of elements of the field's type, each `bits` wide, packed across bytes.
    #[serde(default)]
    pub packed: Option<Packed>,
    #[serde(default)]
    pub follows: Option<Follows>,
    /// A record's fields (`type: record`), each of a fixed width, in wire order.
    #[serde(default)]
    pub fields: Vec<Field>,
    /// A record's last field only: its bytes on the wire are the value of this earlier field
    /// of the message (Dynamixel SYNC_WRITE's `data_length`), 1 up to its type's width.
    #[serde(default)]
    pub bytes: Option<String>,
    /// An optional field: on the wire only when an earlier field says so (`present: {field:
    /// flags, bit: 0}` or `present: {field: kind, equals: 2}`).
    #[serde(default)]
    pub present: Option<Present>,
    /// A header field only (`framing.header`), where the layout holds `header` more than once:
    /// the `header` it sits in, counted from 1 (NovAtel's OEM header: fields before the
    /// message id, between it and the length, and after the length). 1 where not given.
    #[serde(default)]
    pub part: Option<i64>,
    #[serde(default)]
    pub doc: Option<String>,
}

impl Field {
    /// Whether the field sets the key `key` as written in YAML (`encoding` only where it is
    /// `bcd`, the default being binary); `false` for a key it does not know.
    pub fn sets(&self, key: &str) -> bool {
        match key {
            "length" => self.length.is_some(),
            "word_order" => self.word_order.is_some(),
            "encoding" => self.encoding == Some(Encoding::Bcd),
            "unit" => self.unit.is_some(),
            "range" => self.range.is_some(),
            "value" => self.value.is_some(),
            "enum" => self.enum_.is_some(),
            "flags" => self.flags.is_some(),
            "equals" => self.equals.is_some(),
            "special" => !self.special.is_empty(),
            "bits" => !self.bits.is_empty(),
            "repeat" => self.repeat.is_some(),
            "packed" => self.packed.is_some(),
            "follows" => self.follows.is_some(),
            "fields" => !self.fields.is_empty(),
            "bytes" => self.bytes.is_some(),
            "present" => self.present.is_some(),
            "part" => self.part.is_some(),
            // The validator's own key lists name only these: a misspelt one is its bug.
            _ => {
                debug_assert!(false, "`{key}` is no key of a field");
                false
            }
        }
    }
}

/// `present: {field: flags, bit: 3}` (the field is on the wire when bit 3 of the earlier
/// field `flags` is set) or `present: {field: kind, equals: 2}` (when `kind` is 2): exactly one
/// of `bit` and `equals`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Present {
    pub field: String,
    #[serde(default)]
    pub bit: Option<i64>,
    #[serde(default)]
    pub equals: Option<i64>,
}

/// `packed: {count: 16, bits: 11, bit_order: lsb_first}`: `count` elements of `bits` bits each,
/// one after the other in a bit stream that fills bytes in `bit_order` (CRSF's RC channels).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Packed {
    pub count: i64,
    pub bits: i64,
    pub bit_order: BitOrder,
}

/// How a packed bit stream fills its bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BitOrder {
    /// Bit 0 of the stream is bit 0 (least significant) of the first byte, and each element's
    /// least significant bit comes first (a little-endian integer of all the bytes).
    LsbFirst,
    /// Bit 0 of the stream is bit 7 of the first byte, and each element's most significant bit
    /// comes first (a big-endian integer of all the bytes).
    MsbFirst,
}

/// A repeated field: `count` elements of the field's type.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Repeat {
    /// An earlier field of the message holding the count, or `end`: to the end of the payload,
    /// or a number: that many elements always (`count: 5`, kept here as its digits). Empty
    /// (absent) where `until` ends the list instead.
    #[serde(default, deserialize_with = "count_text")]
    pub count: String,
    /// Text that ends at a terminator byte (`until: 0x00`, a C string): the characters run up
    /// to the first such byte, which travels after them and is no character.
    #[serde(default)]
    pub until: Option<i64>,
    /// What `count` counts: `elements` (default) or `bytes`.
    #[serde(default)]
    pub of: Option<CountOf>,
    /// The fewest elements a frame carries (default 0).
    #[serde(default)]
    pub min: Option<i64>,
    /// The most elements a frame may carry; required but where `count` is a number.
    #[serde(default)]
    pub max: Option<i64>,
    /// In a reply: the element count follows from a field of the request.
    #[serde(default)]
    pub request: Option<Relation>,
}

/// `repeat.count` as text: a field's name, `end`, or a number's digits (`count: 5`).
fn count_text<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    struct V;
    impl serde::de::Visitor<'_> for V {
        type Value = String;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an earlier field's name, `end`, or a number of elements")
        }
        fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<String, E> {
            Ok(s.to_owned())
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<String, E> {
            Ok(v.to_string())
        }
    }
    d.deserialize_any(V)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CountOf {
    Elements,
    Bytes,
}

/// `ceil(field × multiply / divide)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Relation {
    pub field: String,
    #[serde(default)]
    pub multiply: Option<i64>,
    #[serde(default)]
    pub divide: Option<i64>,
}

/// A field whose value follows from another: an earlier field of the same frame (`field`) or,
/// in a reply, a field of the request (`request`); `ceil(value × multiply / divide)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Follows {
    #[serde(default)]
    pub field: Option<String>,
    #[serde(default)]
    pub request: Option<String>,
    #[serde(default)]
    pub multiply: Option<i64>,
    #[serde(default)]
    pub divide: Option<i64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Special {
    pub value: i64,
    pub name: String,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BitField {
    pub name: String,
    pub msb: i64,
    pub lsb: i64,
    #[serde(default)]
    pub signed: bool,
    #[serde(default)]
    pub unit: Option<String>,
    #[serde(default)]
    pub range: Option<Range>,
    #[serde(default)]
    pub value: Option<i64>,
    #[serde(default)]
    pub doc: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Example {
    pub section: String,
    pub message: String,
    #[serde(default)]
    pub reply_to: Option<String>,
    /// The request frame a reply example answers (hex, as example text is written), where
    /// the reply's checksum takes in its request's bytes (`checksum_over_request`).
    #[serde(default)]
    pub request: Option<String>,
    #[serde(default)]
    pub printed: Option<String>,
    #[serde(default)]
    pub derived: Option<String>,
    #[serde(default)]
    pub comment: Option<String>,
    #[serde(default)]
    pub values: OpenMap,
    #[serde(default)]
    pub erratum: Option<String>,
    #[serde(default)]
    pub corrected: Option<String>,
}

/// A value where the format leaves the shape open (example values, response meanings), kept as
/// written so that the validator can say what it expected and what it found.
#[derive(Debug, Clone, PartialEq)]
pub enum OpenValue {
    Null,
    Bool(bool),
    /// A YAML number, as decimal text (integers exactly; floats as `{}` prints them).
    Number(String),
    String(String),
    List(Vec<OpenValue>),
    Map(OpenMap),
    /// A value with a YAML tag (`!name value`); the tag itself is not kept.
    Tagged(Box<OpenValue>),
}

impl OpenValue {
    /// The text, if this is a string (a tagged one too).
    pub fn as_str(&self) -> Option<&str> {
        match self {
            OpenValue::String(s) => Some(s),
            OpenValue::Tagged(v) => v.as_str(),
            _ => None,
        }
    }

    /// What kind of value this is, for messages: "a number", "a list", ...
    pub fn kind(&self) -> &'static str {
        match self {
            OpenValue::Null => "nothing",
            OpenValue::Bool(_) => "a boolean",
            OpenValue::Number(_) => "a number",
            OpenValue::String(_) => "a string",
            OpenValue::List(_) => "a list",
            OpenValue::Map(_) => "a mapping",
            OpenValue::Tagged(_) => "a tagged value",
        }
    }
}

impl<'de> Deserialize<'de> for OpenValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = OpenValue;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("any YAML value")
            }
            fn visit_unit<E: serde::de::Error>(self) -> Result<OpenValue, E> {
                Ok(OpenValue::Null)
            }
            fn visit_none<E: serde::de::Error>(self) -> Result<OpenValue, E> {
                Ok(OpenValue::Null)
            }
            fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<OpenValue, D::Error> {
                OpenValue::deserialize(d)
            }
            fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<OpenValue, E> {
                Ok(OpenValue::Bool(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<OpenValue, E> {
                Ok(OpenValue::Number(v.to_string()))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<OpenValue, E> {
                Ok(OpenValue::Number(v.to_string()))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<OpenValue, E> {
                Ok(OpenValue::Number(format!("{v}")))
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<OpenValue, E> {
                Ok(OpenValue::String(s.to_owned()))
            }
            fn visit_string<E: serde::de::Error>(self, s: String) -> Result<OpenValue, E> {
                Ok(OpenValue::String(s))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<OpenValue, A::Error> {
                let mut items = Vec::new();
                while let Some(item) = seq.next_element()? {
                    items.push(item);
                }
                Ok(OpenValue::List(items))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<OpenValue, A::Error> {
                entries(map).map(|e| OpenValue::Map(OpenMap(e)))
            }
            fn visit_enum<A: serde::de::EnumAccess<'de>>(
                self,
                data: A,
            ) -> Result<OpenValue, A::Error> {
                use serde::de::VariantAccess;
                let (_tag, contents): (String, _) = data.variant()?;
                Ok(OpenValue::Tagged(Box::new(contents.newtype_variant()?)))
            }
        }
        d.deserialize_any(V)
    }
}

/// A mapping where the format leaves the keys open, entries in file order. Absent or empty
/// (`~`) reads as no entries. Duplicate keys never get here: the loader's YAML parser rejects
/// them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OpenMap(pub Vec<(OpenValue, OpenValue)>);

impl OpenMap {
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn iter(&self) -> std::slice::Iter<'_, (OpenValue, OpenValue)> {
        self.0.iter()
    }
}

impl<'a> IntoIterator for &'a OpenMap {
    type Item = &'a (OpenValue, OpenValue);
    type IntoIter = std::slice::Iter<'a, (OpenValue, OpenValue)>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

fn entries<'de, A: serde::de::MapAccess<'de>>(
    mut map: A,
) -> Result<Vec<(OpenValue, OpenValue)>, A::Error> {
    let mut out = Vec::new();
    while let Some(key) = map.next_key::<OpenValue>()? {
        let value = map.next_value()?;
        out.push((key, value));
    }
    Ok(out)
}

impl<'de> Deserialize<'de> for OpenMap {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = OpenMap;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a YAML mapping")
            }
            fn visit_unit<E: serde::de::Error>(self) -> Result<OpenMap, E> {
                Ok(OpenMap::default())
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<OpenMap, A::Error> {
                entries(map).map(OpenMap)
            }
        }
        d.deserialize_map(V)
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Erratum {
    pub id: String,
    pub section: String,
    pub says: String,
    pub decision: String,
    pub why: String,
}
