//! The IR: a spec resolved and checked. Offsets, widths, byte orders, scales, checksum parameters
//! and request→response pairing are all worked out here, so no emitter works anything out again.
//! Each message carries its resolved frame layout ([`Message::layout`]: where start byte, address,
//! code, payload and checksum sit, and the frame's length), and the framing carries the layout of
//! an empty-payload frame for each code length ([`Framing::head`]); the validator computes both
//! once, and every reader takes them from here.
//!
//! Only [`crate::validate`] builds these; holding a [`Protocol`] means every invariant the
//! validator checks holds (references resolve, widths add up, values fit, examples replay).

pub use crate::model::{
    Broadcast, ByteOrder, CommandKind, Computed, Document, FieldType, FrameRate, Parity, Part,
    Reply, ResponseKind,
};
use crate::rational::Rational;

/// The generated stream decoder keeps its candidate frame lengths in a 64-bit set.
pub const MAX_DISTINCT_LENGTHS: usize = 64;

/// The longest constant whole frame (`frame:`), in bytes.
pub const MAX_CONSTANT_FRAME: usize = 16;

#[derive(Debug, Clone)]
pub struct Protocol {
    pub name: String,
    pub title: String,
    pub document: Document,
    pub byte_order: ByteOrder,
    pub printed_byte_order: ByteOrder,
    pub serial: Serial,
    pub framing: Framing,
    pub units: Vec<Unit>,
    pub enums: Vec<Enum>,
    pub flags: Vec<FlagSet>,
    pub commands: Vec<Message>,
    pub responses: Vec<Message>,
    /// Indices into `responses` that every command may get.
    pub common_responses: Vec<usize>,
    pub examples: Vec<Example>,
    pub errata: Vec<Erratum>,
    /// What a bus master needs (`transactions:`, resolved with its defaults).
    pub transactions: crate::transactions::Transactions,
    /// What a device holds and what its commands do (`device:`; every command answers and
    /// changes nothing without it).
    pub device: crate::device::Device,
    /// SHA-256 of the spec text this was loaded from, lowercase hex (what `sha256sum` prints);
    /// empty when the protocol was validated from a model rather than loaded from text.
    pub spec_sha256: String,
}

#[derive(Debug, Clone)]
pub struct Serial {
    pub section: Option<String>,
    pub baud: u32,
    pub data_bits: u8,
    pub parity: Parity,
    pub stop_bits: u8,
    pub inter_frame_gap_ms: Option<u32>,
    pub frame_rate: Option<FrameRate>,
    /// Index into `Protocol::enums`.
    pub baud_rates: Option<usize>,
}

#[derive(Debug, Clone)]
pub struct Framing {
    pub section: Option<String>,
    /// The layout of a request (the one layout where the spec gives one for both directions).
    pub layout: Vec<Part>,
    /// The layout of a response: the same as [`Self::layout`] unless the spec gives a layout
    /// per direction (`framing.layout: {request, response}`, Sensirion SHDLC); see
    /// [`Self::layout_of`].
    pub response_layout: Vec<Part>,
    /// The first start byte of a request (the only one where the protocol has one).
    pub start: Option<u8>,
    /// Every start byte of a request, in order (empty without `start`): `FF FF` for Dynamixel.
    pub sync: Vec<u8>,
    /// Every start byte of a response: the same as [`Self::sync`] unless the protocol's start
    /// bytes differ by direction (MSP: `$M<` and `$M>`), then as many; see [`Self::sync_of`].
    pub response_sync: Vec<u8>,
    /// The bytes that end every frame after its checksum (or just before it, where the layout
    /// says so: [`Framing::end_first`]), in order (empty without `end`): `16` for an M-Bus
    /// frame, `AF` (before the checksum) for Pelco-P. A request's, where the end bytes are
    /// given per direction: see [`Self::end_of`].
    pub end: Vec<u8>,
    /// The end bytes of a response: the same as [`Self::end`] unless the directions' layouts
    /// differ in `end` (responses without start or end bytes beside flagged requests, F.Port's
    /// uplink); see [`Self::end_of`].
    pub response_end: Vec<u8>,
    /// The length field, where the framing has one.
    pub length: Option<LengthField>,
    /// The addresses a frame may carry. A protocol whose frames carry none (the layout has no
    /// `address`) has the one device address 0, which no frame shows: see
    /// [`Framing::has_address`].
    pub address: Address,
    pub request: DirectionFraming,
    pub response: DirectionFraming,
    pub checksum: Checksum,
    /// The layout of a request with an empty payload, indexed by code length (0 to
    /// [`MAX_CODE_LEN`]); see [`Framing::head`].
    pub heads: Vec<FrameLayout>,
    /// The same for a response: [`Self::heads`] unless the layouts differ by direction.
    pub response_heads: Vec<FrameLayout>,
    /// How frames are escaped or stuffed on the wire (`None`: they travel as laid out). Every
    /// offset and length of the IR is the unescaped frame's; [`crate::escape`] turns one into
    /// the other.
    pub escaping: Option<Escaping>,
    /// The header fields every message carries (`framing.header`), `offset` counted from the
    /// layout's `header` part; every message's `fields` begin with copies of them (with a
    /// layout per direction, every message of a direction whose layout has `header`).
    pub header: Vec<Field>,
    /// The header fields of a response: [`Self::header`] unless they are given per direction
    /// (`framing.header: {request, response}`, JBD's BMS); see [`Self::header_of`].
    pub response_header: Vec<Field>,
    /// Wake-up bytes before every frame (`framing.preamble`), outside the frame: no offset,
    /// length or checksum of the IR counts them.
    pub preamble: Option<Preamble>,
    /// A per-byte transform of every payload byte as it travels (`framing.transform`: DL/T
    /// 645's +33H): the IR's constants and values are the bytes before it; the checksum covers
    /// the bytes as they travel.
    pub transform: Option<Transform>,
    /// A long form of the length field that a second start byte announces
    /// (`framing.length.long`: VESC's `03 lenH lenL`). Every offset and length of the IR is
    /// the long layout's, with the first start byte: [`crate::long`] turns a frame as it
    /// travels (either form) into that layout and back.
    pub long: Option<LongForm>,
    /// A short form of the frame (`framing.forms`: M-Bus's `10 C A CS 16` beside its long
    /// `68 L L 68 C A ... CS 16`). Every offset and length of the IR is the layout's own (the
    /// long frame's): [`crate::forms`] turns a short frame into that layout and back.
    pub form: Option<ShortForm>,
    /// Payload truncation (`framing.truncation: trailing_zeros`, MAVLink v2): every offset and
    /// length of the IR is the whole payload's; [`crate::truncate`] pads a truncated frame to
    /// it and strips an encoded one.
    pub truncation: Option<crate::model::Truncation>,
}

/// A short form of the frame (`framing.forms`): the layout without a run of parts (the length
/// field's copies, a second start), opened by its own start byte. A frame with an empty
/// payload travels in it, every other one in the layout's own form; strict decoders refuse a
/// frame with an empty payload in the long form.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShortForm {
    /// The short form's start byte.
    pub start: u8,
    /// The framing's own start byte (the long form's; the one the IR's layout carries).
    pub long_start: u8,
    /// Where the start byte sits.
    pub start_at: usize,
    /// Where the dropped parts sit in the layout.
    pub at: usize,
    /// The dropped parts' bytes in a frame with an empty payload, as the layout holds them
    /// (the length field's copies and the second start byte).
    pub fill: Vec<u8>,
    /// Where the length field sits in the layout.
    pub length_at: usize,
    /// The length field's width.
    pub width: usize,
    /// The length field's value in a frame with an empty payload.
    pub most: i64,
    /// A frame with an empty payload, laid out: the short frame is `fill` shorter.
    pub laid_len: usize,
    /// The parts it drops, as the spec names them.
    pub drops: Vec<Part>,
    pub section: Option<String>,
}

impl ShortForm {
    /// How many bytes the short form lacks.
    pub fn extra(&self) -> usize {
        self.fill.len()
    }

    /// The short frame's length as it travels.
    pub fn short_len(&self) -> usize {
        self.laid_len - self.fill.len()
    }

    /// The form in words, as docs and diff print it.
    pub fn describe(&self) -> String {
        let drops: Vec<&str> = self
            .drops
            .iter()
            .map(|p| match p {
                Part::Length => "length",
                Part::Start => "start",
                _ => "?",
            })
            .collect();
        format!(
            "start 0x{:02X} without [{}] for frames with an empty payload ({} bytes), 0x{:02X} with them for every other",
            self.start,
            drops.join(", "),
            self.short_len(),
            self.long_start
        )
    }
}

/// The long form of a length field (`framing.length.long`): a frame whose start byte is
/// `start` carries the length field in [`LengthField::width`] bytes, a frame with the
/// framing's start byte in `short_width` bytes. Encoders take the long form only for a length
/// the short one cannot hold; strict decoders refuse a long form whose length it could.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LongForm {
    /// The long form's start byte.
    pub start: u8,
    /// The framing's own start byte (the short form's; the one the IR's layout carries).
    pub short_start: u8,
    /// The short form's length width (the spec's `length.width`).
    pub short_width: usize,
    /// The long form's length width (the IR's `length.width`).
    pub width: usize,
    /// Where the start byte and the length field sit (the length field at the same offset in
    /// both forms: the start byte is the only part before it).
    pub start_at: usize,
    pub length_at: usize,
}

impl LongForm {
    /// How many bytes longer the long form's length field is.
    pub fn extra(&self) -> usize {
        self.width - self.short_width
    }

    /// The largest length the short form holds.
    pub fn short_max(&self) -> i64 {
        (1i64 << (8 * self.short_width)) - 1
    }

    /// The form in words, as docs and diff print it.
    pub fn describe(&self) -> String {
        format!(
            "start 0x{:02X} with a {}-byte length, or 0x{:02X} with a {}-byte length for lengths over {}",
            self.short_start,
            self.short_width,
            self.start,
            self.width,
            self.short_max()
        )
    }
}

/// A per-byte transform of the payload (`framing.transform`): every byte of the `payload`
/// part travels transformed; header, code, length, checksum and end bytes do not. Encoders
/// write the fields, transform the payload, then compute the checksum over the bytes as they
/// travel; decoders check the checksum, then undo the transform before reading fields.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transform {
    pub section: Option<String>,
    pub kind: TransformKind,
}

/// What a [`Transform`] does to a byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransformKind {
    /// The byte plus this, mod 256 (DL/T 645's 0x33).
    Add(u8),
    /// The byte XOR this.
    Xor(u8),
}

impl Transform {
    /// A byte as it travels.
    pub fn apply(&self, b: u8) -> u8 {
        match self.kind {
            TransformKind::Add(k) => b.wrapping_add(k),
            TransformKind::Xor(k) => b ^ k,
        }
    }

    /// A byte as it travelled, back to its value.
    pub fn undo(&self, b: u8) -> u8 {
        match self.kind {
            TransformKind::Add(k) => b.wrapping_sub(k),
            TransformKind::Xor(k) => b ^ k,
        }
    }

    /// The transform in words, as docs and diff print it: `every payload byte travels plus
    /// 0x33 (mod 256)`.
    pub fn describe(&self) -> String {
        match self.kind {
            TransformKind::Add(k) => {
                format!("every payload byte travels plus 0x{k:02X} (mod 256)")
            }
            TransformKind::Xor(k) => format!("every payload byte travels XOR 0x{k:02X}"),
        }
    }
}

/// A preamble of wake-up bytes (DL/T 645's `FE FE FE FE`): encoders write `send` copies of
/// `byte` before every frame; decoders take 0 to `max` of them before a frame's start byte,
/// which is never `byte`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Preamble {
    pub section: Option<String>,
    pub byte: u8,
    pub send: u8,
    pub max: u8,
}

impl Preamble {
    /// The preamble in words, as docs and diff print it: `0xFE sent 4 times before every
    /// frame; 0 to 4 taken before one`.
    pub fn describe(&self) -> String {
        format!(
            "0x{:02X} sent {} times before every frame; 0 to {} taken before one",
            self.byte, self.send, self.max
        )
    }

    /// How many preamble bytes `wire` begins with, at most `max`: the frame follows them.
    pub fn skip(&self, wire: &[u8]) -> usize {
        wire.iter()
            .take(usize::from(self.max))
            .take_while(|b| **b == self.byte)
            .count()
    }
}

/// Escaping or stuffing, declared once in `framing.escaping`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Escaping {
    pub section: Option<String>,
    /// Where the checksum and the length field are computed.
    pub computed: Computed,
    pub kind: EscapeKind,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EscapeKind {
    /// Between the leading start bytes and the end byte, each byte of `map` travels as
    /// `escape` followed by its replacement (SLIP, KISS, HDLC). `xor`: the mask the spec
    /// gave the replacements by, if it did.
    Bytes {
        escape: u8,
        /// (byte, replacement), in spec order.
        map: Vec<(u8, u8)>,
        xor: Option<u8>,
    },
    /// From `from` through the payload, `byte` is inserted after every occurrence of `after`
    /// (matched left to right on the unstuffed bytes, starting afresh after each one).
    Insert {
        after: Vec<u8>,
        byte: u8,
        from: Part,
    },
    /// Consistent overhead byte stuffing of the bytes between the leading start bytes and the
    /// end byte 0x00.
    Cobs,
}

impl EscapeKind {
    /// The escape byte where it travels doubled (`{byte: 0x10, as: 0x10}`: Garmin's and
    /// TSIP's DLE stuffing), whose frames end in it and a byte no escape stands for (DLE ETX,
    /// `10 03`).
    pub fn doubled(&self) -> Option<u8> {
        match self {
            EscapeKind::Bytes { escape, map, .. } if map.contains(&(*escape, *escape)) => {
                Some(*escape)
            }
            _ => None,
        }
    }

    /// The most bytes `n` unescaped bytes of the escaped region can take on the wire.
    pub fn worst_len(&self, n: usize) -> usize {
        match self {
            EscapeKind::Bytes { .. } => 2 * n,
            EscapeKind::Insert { after, .. } => n + n / after.len().max(1),
            EscapeKind::Cobs => n + 1 + n / 254,
        }
    }
}

/// A length field: `width` bytes in the protocol's byte order, whose value is the number of
/// bytes of the parts it `counts` plus `adjust`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LengthField {
    pub width: usize,
    pub counts: Vec<Part>,
    pub adjust: i64,
}

/// The length field of the frames of one direction, resolved ([`Framing::length_rule`]): at
/// `at`, `width` bytes, holding the frame's length plus `k` where it counts the payload
/// (`grows`), else `k` alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LengthRule {
    pub at: usize,
    /// Where the length field comes again, if the layout repeats it: the same value.
    pub again: Option<usize>,
    pub width: usize,
    pub grows: bool,
    pub k: i64,
    /// The length of a frame with an empty payload: no frame is shorter.
    pub head_len: usize,
}

impl LengthRule {
    /// The value the length field of a frame of `len` bytes holds (`None` for a frame shorter
    /// than any).
    pub fn value(&self, len: usize) -> Option<i64> {
        if len < self.head_len {
            return None;
        }
        Some(if self.grows {
            len as i64 + self.k
        } else {
            self.k
        })
    }
}

/// The longest code a frame can have, in bytes.
pub const MAX_CODE_LEN: usize = 4;

/// The most times a layout holds `header` (NovAtel's OEM header needs three: before the
/// message id, between it and the length, after the length).
pub const MAX_HEADER_PARTS: usize = 4;

/// Byte offsets of the parts of one frame, and its length; resolved by the validator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameLayout {
    /// `None` when the layout has no start byte.
    pub start: Option<usize>,
    /// Where the start bytes come again, where the layout has a second `start` (M-Bus's long
    /// frame `68 L L 68`).
    pub start_again: Option<usize>,
    /// `None` when the framing has no length field.
    pub length: Option<usize>,
    /// Where the length field comes again (it must agree), where the layout has a second
    /// `length`.
    pub length_again: Option<usize>,
    /// `None` when the layout has no address.
    pub address: Option<usize>,
    /// Where each `header` part begins, in layout order (`framing.header`; 0 for a part the
    /// layout does not hold).
    pub headers: [usize; MAX_HEADER_PARTS],
    pub code: usize,
    pub payload: usize,
    /// Where the checksum is: the payload's end (also where frames have none).
    pub checksum: usize,
    /// Bytes in the whole frame.
    pub len: usize,
}

impl FrameLayout {
    /// Where each copy of the start bytes begins, in layout order.
    pub fn starts(&self) -> impl Iterator<Item = usize> {
        [self.start, self.start_again].into_iter().flatten()
    }

    /// Where each copy of the length field begins, in layout order.
    pub fn lengths(&self) -> impl Iterator<Item = usize> {
        [self.length, self.length_again].into_iter().flatten()
    }
}

impl Framing {
    /// Where the start byte, address and code sit in any frame of direction `d` whose code has
    /// `code_len` bytes (the payload taken as empty, so `payload`, `checksum` and `len` are
    /// those of a frame without one). Code lengths are at most [`MAX_CODE_LEN`]; a longer one
    /// gets the layout of the longest.
    pub fn head(&self, d: Direction, code_len: usize) -> FrameLayout {
        let heads = self.heads_of(d);
        heads[code_len.min(heads.len().saturating_sub(1))]
    }

    /// The layouts of a direction's frames with an empty payload, by code length.
    pub fn heads_of(&self, d: Direction) -> &[FrameLayout] {
        match d {
            Direction::Request => &self.heads,
            Direction::Response => &self.response_heads,
        }
    }

    /// The layout of a frame of direction `d`.
    pub fn layout_of(&self, d: Direction) -> &[Part] {
        match d {
            Direction::Request => &self.layout,
            Direction::Response => &self.response_layout,
        }
    }

    /// Whether requests and responses are laid out differently (`framing.layout: {request,
    /// response}`).
    pub fn layout_by_direction(&self) -> bool {
        self.layout != self.response_layout
    }

    /// Whether frames of direction `d` carry the header fields (its layout has `header`).
    pub fn has_header(&self, d: Direction) -> bool {
        !self.header_of(d).is_empty() && self.layout_of(d).contains(&Part::Header)
    }

    /// The header fields of a frame of direction `d` (where its layout has `header`: see
    /// [`Self::has_header`]).
    pub fn header_of(&self, d: Direction) -> &[Field] {
        match d {
            Direction::Request => &self.header,
            Direction::Response => &self.response_header,
        }
    }

    /// Whether the header fields differ by direction (`framing.header: {request, response}`,
    /// each direction's layout with `header`): their names, types or places.
    pub fn header_by_direction(&self) -> bool {
        let key = |f: &Field| (f.name.clone(), f.width, f.signed, f.part, f.offset);
        self.header.len() != self.response_header.len()
            || self
                .header
                .iter()
                .zip(&self.response_header)
                .any(|(a, b)| key(a) != key(b) || a.bits.len() != b.bits.len())
    }

    /// The start bytes of a frame of direction `d`.
    pub fn sync_of(&self, d: Direction) -> &[u8] {
        match d {
            Direction::Request => &self.sync,
            Direction::Response => &self.response_sync,
        }
    }

    /// Whether the start bytes tell a request from a response (they differ by direction).
    pub fn sync_by_direction(&self) -> bool {
        self.sync != self.response_sync
    }

    /// Bytes after the payload: the checksum and the end bytes (a request's; see
    /// [`Self::trailer_len_of`]).
    pub fn trailer_len(&self) -> usize {
        self.trailer_len_of(Direction::Request)
    }

    /// The end bytes of a frame of direction `d` (empty where its layout has no `end`).
    pub fn end_of(&self, d: Direction) -> &[u8] {
        match d {
            Direction::Request => &self.end,
            Direction::Response => &self.response_end,
        }
    }

    /// Whether the end bytes differ by direction (one direction's layout has `end`, the
    /// other's not).
    pub fn end_by_direction(&self) -> bool {
        self.end != self.response_end
    }

    /// Bytes after the payload of a frame of direction `d`: its checksum and end bytes.
    /// A checksum before the payload ([`Checksum::lead`]) is not among them.
    pub fn trailer_len_of(&self, d: Direction) -> usize {
        if self.checksum.lead.is_some() {
            return self.end_of(d).len();
        }
        self.checksum.len() + self.end_of(d).len()
    }

    /// Whether end bytes alone delimit a frame: the framing has end bytes and no length
    /// field, checksum or escaping (Nextion's `FF FF FF`). A receiver can then tell where a
    /// list to the end of the frame stops only by its end bytes, so such a list ends at the
    /// first end bytes after its first byte ([`Message::delimited_list`]).
    pub fn end_delimited(&self) -> bool {
        !self.end.is_empty()
            && self.length.is_none()
            && self.checksum.is_empty()
            && self.escaping.is_none()
    }

    /// Where the end bytes first appear in `bytes` (never without end bytes): where a frame
    /// end bytes alone delimit ends ([`Self::end_delimited`]).
    pub fn first_end(&self, bytes: &[u8]) -> Option<usize> {
        if self.end.is_empty() {
            return None;
        }
        bytes
            .windows(self.end.len())
            .position(|w| w == self.end.as_slice())
    }

    /// The flag of flag framing (HDLC, KISS): one byte that both opens and closes every
    /// escaped frame (`start` and `end` the same single byte, escaping that keeps it out of
    /// the frame between them). A flag that closes one frame may also open the next, as
    /// ISO/IEC 13239 and RFC 1662 allow a sender to share it: both stream decoders then take
    /// a frame's closing flag as the next frame's opening one where the bytes after it make
    /// one, and drop it silently where they do not.
    pub fn shared_flag(&self) -> Option<u8> {
        let escaped = matches!(
            self.escaping.as_ref().map(|e| &e.kind),
            Some(EscapeKind::Bytes { .. } | EscapeKind::Cobs)
        );
        // Every direction's frames between the flags, or requests between them and responses
        // with neither start nor end bytes (F.Port's uplink: stuffed, found by its length
        // between a poll's closing flag and the next frame's opening one).
        let flagged = |l: &[Part]| l.first() == Some(&Part::Start) && l.last() == Some(&Part::End);
        let bare = |l: &[Part]| !l.contains(&Part::Start) && !l.contains(&Part::End);
        let framed = flagged(&self.layout)
            && ((flagged(&self.response_layout) && self.response_sync == self.sync)
                || bare(&self.response_layout));
        match (self.sync.as_slice(), self.end.as_slice()) {
            ([s], [e]) if escaped && framed && s == e => Some(*s),
            _ => None,
        }
    }

    /// `wire` after its preamble bytes (0 to the preamble's `max`): the frame. All of `wire`
    /// where the framing has no preamble.
    pub fn after_preamble<'w>(&self, wire: &'w [u8]) -> &'w [u8] {
        match &self.preamble {
            Some(pre) => &wire[pre.skip(wire)..],
            None => wire,
        }
    }

    /// The length a frame of direction `d` laid out in `len` bytes has as it travels: as long
    /// in the long form of a length field the start byte chooses (`framing.length.long`)
    /// where its length field's value needs it, shorter by the bytes the short field lacks
    /// otherwise; `len` without a long form.
    pub fn travelled_len(&self, d: Direction, len: usize) -> usize {
        if let Some(f) = &self.form {
            return if len == f.laid_len {
                f.short_len()
            } else {
                len
            };
        }
        let (Some(l), Some(rule)) = (self.long, self.length_rule(d)) else {
            return len;
        };
        match rule.value(len) {
            Some(v) if v > l.short_max() => len,
            _ => len.saturating_sub(l.extra()),
        }
    }

    /// Where the checksum starts as a frame travels in the short form of a length field the
    /// start byte chooses (`framing.length.long`): where it starts laid out, less the bytes the
    /// short field lacks (the checksum covers no byte before the length field's end:
    /// validated). `checksum.covers_from` without a long form.
    pub fn short_covers_from(&self) -> usize {
        let from = self.checksum.covers_from;
        match self.long {
            Some(l) if from >= l.length_at + l.width => from - l.extra(),
            _ => from,
        }
    }

    /// The bytes of a frame of `len` bytes (after any preamble, unescaped) that travel
    /// transformed (`framing.transform`): its payload, from where the payload begins (every
    /// code has one length: validated) to the checksum and end bytes. Empty without a
    /// transform.
    pub fn transformed(&self, len: usize) -> std::ops::Range<usize> {
        if self.transform.is_none() {
            return 0..0;
        }
        let code_len = self.request.code_lengths.first().copied().unwrap_or(0);
        let at = self.head(Direction::Request, code_len).payload;
        let end = len.saturating_sub(self.trailer_len()).max(at);
        at..end
    }

    /// `frame` with its payload's transform undone (`framing.transform`), where the framing
    /// has one; `frame` itself otherwise.
    pub fn untransformed<'f>(&self, frame: &'f [u8]) -> std::borrow::Cow<'f, [u8]> {
        match &self.transform {
            Some(t) => {
                let mut plain = frame.to_vec();
                let range = self.transformed(frame.len());
                for b in plain.get_mut(range).unwrap_or_default() {
                    *b = t.undo(*b);
                }
                std::borrow::Cow::Owned(plain)
            }
            None => std::borrow::Cow::Borrowed(frame),
        }
    }

    /// Transforms `frame`'s payload in place, as it travels (`framing.transform`); nothing
    /// without one.
    pub fn transform_in_place(&self, frame: &mut [u8]) {
        if let Some(t) = &self.transform {
            let range = self.transformed(frame.len());
            for b in frame.get_mut(range).unwrap_or_default() {
                *b = t.apply(*b);
            }
        }
    }

    /// Whether the end bytes come before the checksum (which then covers them: Pelco-P's
    /// ETX), rather than after it.
    pub fn end_first(&self) -> bool {
        self.end_first_of(Direction::Request)
    }

    /// [`Self::end_first`] of a frame of direction `d`, by its own layout.
    pub fn end_first_of(&self, d: Direction) -> bool {
        let layout = self.layout_of(d);
        let at = |p: Part| layout.iter().position(|x| *x == p);
        matches!((at(Part::End), at(Part::Checksum)), (Some(e), Some(c)) if e < c)
    }

    /// Where the checksum of a request of `len` bytes starts; its end bytes start at
    /// [`Self::end_at`]. See [`Self::checksum_at_of`].
    pub fn checksum_at(&self, len: usize) -> usize {
        self.checksum_at_of(Direction::Request, len)
    }

    /// The fewest bytes a frame of direction `d` takes to hold its checksum and end bytes
    /// where they sit: its trailer, or a checksum before the payload up to its own end.
    pub fn sealed_len_of(&self, d: Direction) -> usize {
        let lead = self.checksum.lead.map_or(0, |at| at + self.checksum.len());
        self.trailer_len_of(d).max(lead)
    }

    /// Where the checksum of a frame of direction `d` and `len` bytes starts.
    /// Where it sits before the payload ([`Checksum::lead`]), there whatever the length.
    pub fn checksum_at_of(&self, d: Direction, len: usize) -> usize {
        if let Some(at) = self.checksum.lead {
            return at;
        }
        let after = if self.end_first_of(d) {
            0
        } else {
            self.end_of(d).len()
        };
        len.saturating_sub(self.checksum.len() + after)
    }

    /// The bytes a request frame with a checksum covers, as it travelled (after any
    /// preamble); [`Protocol::checksum_span`] of any request. `None` for a frame too short to
    /// hold a checksum.
    fn checksum_span_of<'w>(&self, request: &'w [u8]) -> Option<&'w [u8]> {
        let w = self.after_preamble(request);
        if w.len() < self.trailer_len() {
            return None;
        }
        w.get(self.covered_of(Direction::Request, w.len()))
    }

    /// The bytes a frame of direction `d` and `len` bytes has its checksum over: from its
    /// `covers_from` up to the checksum, or, where the checksum comes before the payload
    /// ([`Checksum::lead`]), from `covers_from` (after it) to the frame's end bytes. Empty
    /// (start past end) for a frame too short to hold them.
    /// Where it covers bytes on both sides of itself (HerkuleX's, from the size byte before
    /// it), the bytes before it: the rest are [`Self::covered_after_of`].
    pub fn covered_of(&self, d: Direction, len: usize) -> std::ops::Range<usize> {
        let from = self.checksum.covers_from_of(d);
        let to = match self.checksum.lead {
            Some(at) if from < at => at,
            Some(_) => len.saturating_sub(self.end_of(d).len()),
            None => self.checksum_at_of(d, len),
        };
        from..to
    }

    /// Whether the checksum covers bytes on both sides of itself: it comes before the payload
    /// and covers from a part before it (HerkuleX's, from the size byte), skipping its own
    /// bytes, to the frame's end.
    pub fn covers_around(&self) -> bool {
        self.checksum.lead.is_some_and(|at| {
            self.checksum
                .covers_from
                .min(self.checksum.response_covers_from)
                < at
        })
    }

    /// The bytes a checksum that covers bytes on both sides of itself ([`Self::covers_around`])
    /// covers after itself in a frame of direction `d` and `len` bytes: from its end to the
    /// frame's end bytes (empty, start past end, for a frame too short). Empty otherwise.
    pub fn covered_after_of(&self, d: Direction, len: usize) -> std::ops::Range<usize> {
        match self.checksum.lead {
            Some(at) if self.checksum.covers_from_of(d) < at => {
                at + self.checksum.len()..len.saturating_sub(self.end_of(d).len())
            }
            _ => 0..0,
        }
    }

    /// Every byte a frame of direction `d` (`wire`, as it travelled) has its checksum over, in
    /// order: [`Self::covered_of`] then [`Self::covered_after_of`] (spans past the frame
    /// contribute nothing).
    pub fn covered_bytes_of(&self, d: Direction, wire: &[u8]) -> Vec<u8> {
        let mut v = wire
            .get(self.covered_of(d, wire.len()))
            .unwrap_or(&[])
            .to_vec();
        v.extend_from_slice(
            wire.get(self.covered_after_of(d, wire.len()))
                .unwrap_or(&[]),
        );
        v
    }

    /// Where the end bytes of a request of `len` bytes start; see [`Self::end_at_of`].
    pub fn end_at(&self, len: usize) -> usize {
        self.end_at_of(Direction::Request, len)
    }

    /// Where the end bytes of a frame of direction `d` and `len` bytes start.
    pub fn end_at_of(&self, d: Direction, len: usize) -> usize {
        if self.end_first_of(d) {
            len.saturating_sub(self.trailer_len_of(d))
        } else {
            len.saturating_sub(self.end_of(d).len())
        }
    }

    /// Bytes of the header fields a request carries (0 without `framing.header`); see
    /// [`Self::header_len_of`].
    pub fn header_len(&self) -> usize {
        self.header_len_of(Direction::Request)
    }

    /// Bytes of the header fields a frame of direction `d` carries where its layout has
    /// `header`: of every `header` part.
    pub fn header_len_of(&self, d: Direction) -> usize {
        self.header_of(d).iter().map(|f| f.width).sum()
    }

    /// Bytes of the `header` part `part` (counted from 0 in layout order) of a frame of
    /// direction `d`.
    pub fn header_part_len_of(&self, d: Direction, part: usize) -> usize {
        self.header_of(d)
            .iter()
            .filter(|f| f.part == part)
            .map(|f| f.width)
            .sum()
    }

    /// Bytes of each part of direction `d`'s layout, in its order, for a code of `code_len`
    /// bytes and a payload of `payload` (each `header` its own part's fields).
    pub fn part_lens_of(
        &self,
        d: Direction,
        code_len: usize,
        payload: usize,
    ) -> impl Iterator<Item = (Part, usize)> + '_ {
        let mut headers = 0;
        self.layout_of(d).iter().map(move |&p| {
            let len = match p {
                Part::Start => self.sync.len(),
                Part::Address => 1,
                Part::Length => self.length.as_ref().map_or(0, |l| l.width),
                Part::Code => code_len,
                Part::Payload => payload,
                Part::Checksum => self.checksum.len(),
                Part::End => self.end.len(),
                Part::Header => {
                    headers += 1;
                    self.header_part_len_of(d, headers - 1)
                }
            };
            (p, len)
        })
    }

    /// Whether frames carry an address (the layout has `address`; with a layout per
    /// direction, either direction's).
    pub fn has_address(&self) -> bool {
        self.layout.contains(&Part::Address) || self.response_layout.contains(&Part::Address)
    }

    /// Whether frames of direction `d` carry an address (its layout has `address`): a frame of
    /// a direction without one carries address 0, which it does not show.
    pub fn has_address_in(&self, d: Direction) -> bool {
        self.layout_of(d).contains(&Part::Address)
    }

    /// Bytes in a frame of direction `d` besides code and payload: start, address, checksum.
    pub fn overhead(&self, d: Direction) -> usize {
        self.part_lens_of(d, 0, 0).map(|(_, n)| n).sum()
    }

    /// Where the length field of a frame of direction `d` sits and how its value follows from
    /// the frame's length, if the framing has one: the one derivation the interpreter
    /// ([`crate::interp::length_for`]) and the generated code (its check in `decode`, its value
    /// in `encode`) share. Every message of a direction has the field at the same offset (its
    /// code lengths are one, validated) and only the payload varies.
    pub fn length_rule(&self, d: Direction) -> Option<LengthRule> {
        let l = self.length.as_ref()?;
        let code_len = self.direction(d).code_lengths.first().copied().unwrap_or(0);
        let head = self.head(d, code_len);
        let at = head.length?;
        let base = self.length_value_of(d, l, code_len, 0);
        let grows = l.counts.contains(&Part::Payload);
        Some(LengthRule {
            at,
            again: head.length_again,
            width: l.width,
            grows,
            k: if grows { base - head.len as i64 } else { base },
            head_len: head.len,
        })
    }

    /// The value a length field holds for a frame with this code length and payload: every
    /// part it counts (each time the layout holds it), plus its adjustment. With a layout per
    /// direction every part it counts is in both (validated), once each.
    pub fn length_value(&self, l: &LengthField, code_len: usize, payload: usize) -> i64 {
        self.length_value_of(Direction::Request, l, code_len, payload)
    }

    /// [`Self::length_value`] of a frame of direction `d`: its own header fields counted
    /// where they differ by direction (`framing.header: {request, response}`).
    pub fn length_value_of(
        &self,
        d: Direction,
        l: &LengthField,
        code_len: usize,
        payload: usize,
    ) -> i64 {
        // Each counted part as often as direction `d`'s layout holds it (its own header
        // fields where they differ by direction).
        let bytes: usize = self
            .part_lens_of(d, code_len, payload)
            .filter(|(p, _)| l.counts.contains(p))
            .map(|(p, n)| if p == Part::Length { l.width } else { n })
            .sum();
        bytes as i64 + l.adjust
    }

    /// The bytes of a frame of `len` bytes (escaped or not) that escaping applies to,
    /// `from..to`; `None` where there is no escaping or the frame is too short to hold its
    /// fixed bytes around them. A request's: see [`Self::escaped_region_of`].
    pub fn escaped_region(&self, len: usize) -> Option<(usize, usize)> {
        self.escaped_region_of(Direction::Request, len)
    }

    /// [`Self::escaped_region`] of a frame of direction `d`: between its own leading start
    /// bytes (none where its layout does not begin with `start`) and its own end bytes
    /// (none where its layout has no `end`: escaped to its last byte, framed by its length
    /// field).
    pub fn escaped_region_of(&self, d: Direction, len: usize) -> Option<(usize, usize)> {
        let e = self.escaping.as_ref()?;
        let (from, tail) = match &e.kind {
            EscapeKind::Bytes { .. } | EscapeKind::Cobs => {
                let lead = if self.layout_of(d).first() == Some(&Part::Start) {
                    self.sync_of(d).len()
                } else {
                    0
                };
                (lead, self.end_of(d).len())
            }
            EscapeKind::Insert { from, .. } => {
                let h = self.head(d, 0);
                let at = match from {
                    Part::Start => h.start,
                    Part::Address => h.address,
                    Part::Length => h.length,
                    Part::Code => Some(h.code),
                    _ => None,
                };
                (at?, self.trailer_len_of(d))
            }
        };
        let to = len.checked_sub(tail)?;
        (from <= to).then_some((from, to))
    }

    /// Where the escaped bytes of any frame lie: from this offset to this many bytes before
    /// the frame's end (`None` without escaping).
    pub fn escaped_bounds(&self) -> Option<(usize, usize)> {
        self.escaped_bounds_of(Direction::Request)
    }

    /// [`Self::escaped_bounds`] of a frame of direction `d` ([`Self::escaped_region_of`]).
    pub fn escaped_bounds_of(&self, d: Direction) -> Option<(usize, usize)> {
        let probe = self.head(d, 0).len + 64;
        let (from, to) = self.escaped_region_of(d, probe)?;
        Some((from, probe - to))
    }

    /// How far before a request's end its checksum starts; see [`Self::checksum_from_end_of`].
    pub fn checksum_from_end(&self) -> usize {
        self.checksum_from_end_of(Direction::Request)
    }

    /// How far before the end of a frame of direction `d` its checksum starts.
    pub fn checksum_from_end_of(&self, d: Direction) -> usize {
        let probe = self.trailer_len_of(d);
        probe - self.checksum_at_of(d, probe)
    }

    /// The longest a frame of `len` unescaped bytes can be on the wire.
    pub fn wire_len(&self, len: usize) -> usize {
        match (&self.escaping, self.escaped_region(len)) {
            (Some(e), Some((from, to))) => len - (to - from) + e.kind.worst_len(to - from),
            _ => len,
        }
    }

    pub fn direction(&self, d: Direction) -> &DirectionFraming {
        match d {
            Direction::Request => &self.request,
            Direction::Response => &self.response,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Address {
    pub host: Option<u8>,
    pub min: u8,
    pub max: u8,
    pub broadcast: Option<u8>,
    pub default: Option<u8>,
}

#[derive(Debug, Clone)]
pub struct DirectionFraming {
    pub code_lengths: Vec<usize>,
    pub payload_min: usize,
    pub payload_max: usize,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ChecksumAlgorithm {
    /// 8-bit sum of every byte, modulo 256.
    Sum8,
    /// The 8-bit sum inverted (ones' complement).
    Sum8OnesComplement,
    /// The 8-bit sum negated (two's complement).
    Sum8TwosComplement,
    /// The 8-bit sum with each carry added back in (end-around carry), inverted: FrSky's S.Port
    /// and F.Port checksum (`sum8_end_around`).
    Sum8EndAround,
    /// 8-bit XOR of every byte.
    Xor8,
    /// 16-bit sum of every byte, modulo 65536.
    Sum16,
    /// The 16-bit sum inverted (ones' complement).
    Sum16OnesComplement,
    /// The 16-bit sum negated (two's complement).
    Sum16TwosComplement,
    /// Two 8-bit running sums modulo 256 (u-blox UBX): `b << 8 | a`.
    Fletcher8,
    /// Fletcher-16: two running sums modulo 255, `b << 8 | a`.
    Fletcher16,
    Crc(CrcParams),
    /// Another algorithm's value kept to the bits of a mask (`sum8` & 0x7F).
    Masked(Box<ChecksumAlgorithm>, u64),
    /// An 8-bit sum or XOR (masked or not) followed by its complement kept to the mask
    /// (`complement: true`, HerkuleX's CS1 and CS2): the value `v << 8 | (!v & mask)`, two
    /// bytes, `v` first.
    Complemented(Box<ChecksumAlgorithm>, u64),
    /// No checksum: the layout has none (width 0).
    None,
}

impl ChecksumAlgorithm {
    /// The algorithm as the spec names it (`sum8`, `sum16 & 0x7F`, `crc`; `none`).
    pub fn name(&self) -> String {
        match self {
            ChecksumAlgorithm::Sum8 => "sum8".to_owned(),
            ChecksumAlgorithm::Sum8OnesComplement => "sum8_ones_complement".to_owned(),
            ChecksumAlgorithm::Sum8TwosComplement => "sum8_twos_complement".to_owned(),
            ChecksumAlgorithm::Sum8EndAround => "sum8_end_around".to_owned(),
            ChecksumAlgorithm::Xor8 => "xor8".to_owned(),
            ChecksumAlgorithm::Sum16 => "sum16".to_owned(),
            ChecksumAlgorithm::Sum16OnesComplement => "sum16_ones_complement".to_owned(),
            ChecksumAlgorithm::Sum16TwosComplement => "sum16_twos_complement".to_owned(),
            ChecksumAlgorithm::Fletcher8 => "fletcher8".to_owned(),
            ChecksumAlgorithm::Fletcher16 => "fletcher16".to_owned(),
            ChecksumAlgorithm::Crc(_) => "crc".to_owned(),
            ChecksumAlgorithm::Masked(a, mask) => format!("{} & 0x{mask:X}", a.name()),
            ChecksumAlgorithm::Complemented(a, _) => format!("{}, then its complement", a.name()),
            ChecksumAlgorithm::None => "none".to_owned(),
        }
    }
}

/// A CRC in the catalogue's (Rocksoft) parameter model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CrcParams {
    pub width: u8,
    pub poly: u64,
    pub init: u64,
    pub refin: bool,
    pub refout: bool,
    pub xorout: u64,
}

#[derive(Debug, Clone)]
pub struct Checksum {
    pub algorithm: ChecksumAlgorithm,
    /// Width in bits: 8, 16, 24 (a CRC) or 32; 0 where the frames carry no checksum.
    pub width: u8,
    pub byte_order: ByteOrder,
    pub catalogue: Option<String>,
    pub check: u64,
    /// Offset of the first byte a request's checksum covers (it covers every byte from there
    /// up to itself): 0 unless the spec says `covers_from`.
    pub covers_from: usize,
    /// The same for a response: [`Self::covers_from`] unless a layout per direction puts the
    /// first covered byte elsewhere (`covers_from: {request: code, response: header}`, JBD's
    /// BMS; SHDLC's length field at offset 3 in requests, 4 in replies); see
    /// [`Self::covers_from_of`].
    pub response_covers_from: usize,
    /// A byte of each message's own the checksum takes after the bytes it covers (MAVLink's
    /// CRC_EXTRA), found by the code the covered bytes hold.
    pub extra: Option<ChecksumExtra>,
    /// Where the checksum sits where the layout places it before the payload (Septentrio
    /// SBF's CRC at offset 2, after the `$@` sync and before the ID, length and body it
    /// covers): it then covers from `covers_from` (after it) to the frame's end. `None`, the
    /// checksum at the frame's end, covering the bytes before it.
    pub lead: Option<usize>,
}

/// Each message's extra checksum byte, by its code (`framing.checksum.extra: per_message`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChecksumExtra {
    /// Where the code sits in the covered bytes (every code has one length).
    pub code_at: usize,
    /// Each code and its byte, in message order, each code once.
    pub by_code: Vec<(Vec<u8>, u8)>,
}

impl ChecksumExtra {
    /// The extra byte of the message whose code `covered` holds; `None` for a code no message
    /// has (such a frame is checked without one).
    pub fn of(&self, covered: &[u8]) -> Option<u8> {
        self.by_code.iter().find_map(|(code, x)| {
            (covered.get(self.code_at..self.code_at + code.len()) == Some(code)).then_some(*x)
        })
    }
}

impl Checksum {
    /// The checksum of the frame bytes it covers: its algorithm over them, and over the
    /// message's extra byte after them where it takes one.
    pub fn compute(&self, covered: &[u8]) -> u64 {
        match self.extra.as_ref().and_then(|e| e.of(covered)) {
            Some(x) => {
                let mut with = Vec::with_capacity(covered.len() + 1);
                with.extend_from_slice(covered);
                with.push(x);
                crate::checksum::compute(&self.algorithm, &with)
            }
            None => crate::checksum::compute(&self.algorithm, covered),
        }
    }

    /// The checksum of a reply that takes in its request's bytes: over `request` (the bytes
    /// the request's checksum covers), then over the reply's own `covered` bytes.
    pub fn compute_after(&self, request: &[u8], covered: &[u8]) -> u64 {
        let mut all = Vec::with_capacity(request.len() + covered.len());
        all.extend_from_slice(request);
        all.extend_from_slice(covered);
        self.compute(&all)
    }

    /// No checksum: frames whose layout has none.
    pub fn none(byte_order: ByteOrder) -> Checksum {
        Checksum {
            algorithm: ChecksumAlgorithm::None,
            width: 0,
            byte_order,
            catalogue: None,
            check: 0,
            covers_from: 0,
            response_covers_from: 0,
            extra: None,
            lead: None,
        }
    }

    /// Offset of the first byte a frame of direction `d`'s checksum covers.
    pub fn covers_from_of(&self, d: Direction) -> usize {
        match d {
            Direction::Request => self.covers_from,
            Direction::Response => self.response_covers_from,
        }
    }

    /// Whether a request's checksum covers from another offset than a response's.
    pub fn covers_by_direction(&self) -> bool {
        self.covers_from != self.response_covers_from
    }

    /// Bytes the checksum takes in the frame.
    pub fn len(&self) -> usize {
        usize::from(self.width / 8)
    }

    /// Whether the frames carry no checksum.
    pub fn is_empty(&self) -> bool {
        self.width == 0
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    Request,
    Response,
}

impl Direction {
    pub fn as_str(self) -> &'static str {
        match self {
            Direction::Request => "request",
            Direction::Response => "response",
        }
    }
}

#[derive(Debug, Clone)]
pub struct Unit {
    pub name: String,
    pub symbol: String,
    pub scale: Rational,
    pub offset: Rational,
    pub doc: String,
}

impl Unit {
    /// `raw * scale + offset`.
    pub fn physical(&self, raw: i64) -> Rational {
        // Scales and offsets are parsed with at most 18 digits, so this cannot overflow i128.
        let r = Rational::int(i128::from(raw));
        r.times(self.scale)
            .and_then(|v| v.plus(self.offset))
            .unwrap_or(Rational::ZERO)
    }

    /// The raw value whose physical value is `v`, if there is an exact one.
    pub fn raw_exact(&self, v: Rational) -> Option<i128> {
        let r = v.minus(self.offset)?.over(self.scale)?;
        r.is_integer().then_some(r.num)
    }
}

#[derive(Debug, Clone)]
pub struct Enum {
    pub name: String,
    pub section: Option<String>,
    pub doc: String,
    pub values: Vec<EnumValue>,
}

#[derive(Debug, Clone)]
pub struct EnumValue {
    pub value: u64,
    pub name: String,
    pub doc: String,
}

#[derive(Debug, Clone)]
pub struct FlagSet {
    pub name: String,
    pub section: Option<String>,
    pub doc: String,
    pub bits: Vec<Flag>,
}

#[derive(Debug, Clone)]
pub struct Flag {
    pub bit: u8,
    pub name: String,
    pub doc: String,
}

#[derive(Debug, Clone)]
pub enum MessageKind {
    Command(CommandKind),
    Response(ResponseKind),
}

#[derive(Debug, Clone)]
pub struct Message {
    pub name: String,
    pub title: String,
    pub section: String,
    pub doc: String,
    pub direction: Direction,
    pub kind: MessageKind,
    pub code: Vec<u8>,
    pub fields: Vec<Field>,
    /// Payload bytes (sum of field widths).
    pub payload_len: usize,
    /// Where each part of this message's frame sits, and the frame's length.
    pub layout: FrameLayout,
    /// Commands: every response it may get (its own, then the common ones), as indices into
    /// `Protocol::responses`, each with what it means for this command where the spec says.
    pub responses: Vec<(usize, Option<String>)>,
    /// Whether a command gets a reply (`Required` for a response).
    pub reply: Reply,
    /// Responses: the commands that may get it, as indices into `Protocol::commands`.
    pub answers: Vec<usize>,
    pub broadcast: Option<Broadcast>,
    pub needs_request: bool,
    /// Responses: the code is each answered command's code with these bits set.
    pub code_from_request: Option<u8>,
    /// The longest frame of this message: `layout.len` unless it has a repeated field, whose
    /// elements `layout` leaves out (a frame with none).
    pub max_len: usize,
    /// The byte its checksum takes after the covered bytes (`checksum_extra`), where the
    /// framing's checksum takes one.
    pub checksum_extra: Option<u8>,
    /// Responses whose checksum takes in their request's bytes (`checksum_over_request`):
    /// the offset in this message's frame from which it covers its own bytes, after the
    /// bytes the request's checksum covers ([`Protocol::checksum_span`]).
    pub over_request: Option<usize>,
    /// Whether its frames travel without the framing's checksum (`checksum: none`): its
    /// `layout` ends where the checksum would begin (`layout.checksum == layout.len`), and
    /// no engine computes or checks one. Such a message has one length and is found by its
    /// code and length before any checksum is checked ([`Protocol::unchecked`]).
    pub unchecked: bool,
    /// A constant whole frame (`frame:`, responses only): the message is these bytes and
    /// nothing else, outside the framing (M-Bus's single character `E5`). It has no code,
    /// fields, address or checksum; its `layout.len` and `max_len` are the bytes' length. Such
    /// messages come after every framed one of their direction ([`Protocol::framed`]).
    pub frame: Option<Vec<u8>>,
    /// Responses: the device sends it on its own (`unasked: true`), not only as a reply;
    /// `answers` may then be empty (sent unasked only). A frame of it heard after a request
    /// that does not list it is not that request's reply: the stream decoders report it on
    /// its own, and the master sets it aside and keeps waiting.
    pub unasked: bool,
}

impl Message {
    /// Its first repeated field, if it has one (the only one where [`Self::tail_repeat`]).
    pub fn repeat(&self) -> Option<(&Field, &Repeat)> {
        self.repeats().next().map(|(_, f, r)| (f, r))
    }

    /// Every repeated field (index, field, repeat), in wire order.
    pub fn repeats(&self) -> impl Iterator<Item = (usize, &Field, &Repeat)> {
        self.fields
            .iter()
            .enumerate()
            .filter_map(|(i, f)| f.repeat.as_ref().map(|r| (i, f, r)))
    }

    /// Where end bytes alone delimit the frame ([`Framing::end_delimited`]), its list to the
    /// end of the frame and the list's offset in the frame: the list ends at the first end
    /// bytes from that offset on (a frame whose list holds them earlier is refused, by decode
    /// and encode alike, and both stream decoders end the frame there).
    pub fn delimited_list(&self, framing: &Framing) -> Option<(&Field, usize)> {
        let (f, r) = self.repeat()?;
        (framing.end_delimited() && r.count == Count::ToEnd && !self.has_optional())
            .then(|| (f, f.frame_at(&self.layout)))
    }

    /// Where the framing has no length field, its text up to a terminator (`repeat: {until}`,
    /// the message's only list: validated), the text's offset in the frame and its
    /// terminator: the frame ends at the first terminator from the text's first byte, within
    /// its `max` characters and the terminator, then the fields after the text and the trailer.
    /// Both stream decoders frame it so: `layout.len` + the characters + 1.
    pub fn terminated_text(&self, framing: &Framing) -> Option<(&Field, usize, u8)> {
        if framing.length.is_some() {
            return None;
        }
        let (f, _) = self.repeat()?;
        let t = f.terminator()?;
        Some((f, f.frame_at(&self.layout), t))
    }

    /// Whether its one variable part, if any, is a single repeated field ending the payload:
    /// every field keeps a fixed offset. A message with fields after a list, or with several
    /// lists, places each field after a list by the lists before it.
    pub fn tail_repeat(&self) -> bool {
        match self.repeats().count() {
            0 => true,
            1 => self.fields.last().is_some_and(|f| f.repeat.is_some()),
            _ => false,
        }
    }

    /// Where field `i` sits, as docs and diff print it: its payload offset (`5`), or for a
    /// field after a list, its distance from the end of the last list before it
    /// (`` `values` + 2 ``).
    pub fn place(&self, i: usize) -> String {
        let Some(f) = self.fields.get(i) else {
            return String::new();
        };
        match self.fields[..i].iter().rev().find(|g| g.repeat.is_some()) {
            _ if f.header => f.header_place(),
            // After the optional fields before it that are present.
            _ if f.present.is_some() && self.fields[..i].iter().any(|g| g.present.is_some()) => {
                format!("{} + earlier optional", f.offset)
            }
            Some(l) => format!("`{}` + {}", l.name, f.offset - l.offset),
            None => f.offset.to_string(),
        }
    }

    /// The repeated field (index) whose elements or bytes field `i` counts, if any.
    pub fn counted_by(&self, i: usize) -> Option<(usize, &Field, &Repeat)> {
        self.repeats()
            .find(|(_, _, r)| matches!(r.count, Count::Elements(c) | Count::Bytes(c) if c == i))
    }

    /// The bytes of the constants that lead its payload (whole fields, one after the other from
    /// the payload's first byte): with its code, what tells a variable-length message apart in
    /// a stream before its length or count is read (both stream decoders).
    pub fn leading_constants(&self) -> Vec<u8> {
        let mut lead = Vec::new();
        for f in self.fields.iter().filter(|f| !f.header) {
            match f.constant {
                Some(c) if f.bits.is_empty() && f.repeat.is_none() && lead.len() == f.offset => {
                    let mut bytes = vec![0u8; f.width];
                    crate::interp::write_uint(c, &mut bytes, f.byte_order);
                    lead.extend(bytes);
                }
                _ => break,
            }
        }
        lead
    }

    /// Its shortest frame: with the fewest elements its repeated fields may have (and no
    /// optional field).
    pub fn min_len(&self) -> usize {
        self.layout.len
            + self
                .repeats()
                .map(|(_, f, r)| match f.record_bytes_from() {
                    Some(_) => r.min.saturating_mul(f.min_element_width()),
                    None => f.elements_len(r.min),
                })
                .sum::<usize>()
    }

    /// A command: whether it may get response `index` (of `Protocol::responses`): its own
    /// responses and the common ones.
    pub fn gets(&self, index: usize) -> bool {
        self.responses.iter().any(|(i, _)| *i == index)
    }

    /// Whether its frames vary in length: a repeated field, or optional fields.
    pub fn is_variable(&self) -> bool {
        self.repeat().is_some() || self.has_optional()
    }

    /// Whether it has optional fields (`present:`).
    pub fn has_optional(&self) -> bool {
        self.fields.iter().any(|f| f.present.is_some())
    }

    /// Every optional field (index, field, its condition), in wire order.
    pub fn optionals(&self) -> impl Iterator<Item = (usize, &Field, &Presence)> {
        self.fields
            .iter()
            .enumerate()
            .filter_map(|(i, f)| f.present.as_ref().map(|c| (i, f, c)))
    }

    /// Whether optional field `i` is on the wire in a frame whose payload is `payload` (its
    /// condition's field read where it sits; a field without `present` always is). Optional
    /// fields follow every other field, and the fields their conditions read sit at fixed
    /// offsets before them.
    pub fn present_in(&self, i: usize, payload: &[u8]) -> bool {
        let Some(c) = self.fields.get(i).and_then(|f| f.present.as_ref()) else {
            return true;
        };
        let Some(g) = self.fields.get(c.field) else {
            return false;
        };
        let bytes = payload.get(g.offset..g.offset + g.width).unwrap_or(&[]);
        c.holds(crate::interp::read_uint(bytes, g.byte_order) as i64)
    }

    /// The field (index) that counts the elements or bytes of its first repeated field, if any.
    pub fn count_field(&self) -> Option<usize> {
        self.repeat()?.1.count.field()
    }

    /// Whether field `i` is filled in from the rest of the frame: a constant, a repeat of
    /// another field (`equals`), a value following another field of the frame, or the count of
    /// the repeated field (the list's length gives it). Encoders compute it, decoders check
    /// it, and generated messages do not carry it.
    pub fn is_derived(&self, i: usize) -> bool {
        self.fields.get(i).is_some_and(|f| {
            f.constant.is_some()
                || f.equals.is_some()
                || matches!(f.follows, Some(Follows::Field(..)))
                || self.counted_by(i).is_some()
        })
    }

    /// The frame lengths a stream decoder lists for this message beforehand: its length, or
    /// for a repeat to the end of the frame without a length field every length a whole number
    /// of elements gives; none where a length or count field gives each frame's length (the
    /// stream decoder reads it from the frame), where end bytes alone delimit the frame, or
    /// where the frame is escaped (its end byte or length field frames it).
    pub fn listed_lengths(&self, framing: &Framing) -> Vec<usize> {
        if self.has_optional() {
            // A length field gives each frame's length (the validator requires one).
            return Vec::new();
        }
        let Some((f, r)) = self.repeat() else {
            return vec![self.layout.len];
        };
        // End bytes alone delimit it: the stream decoder finds them in the frame. Escaped
        // frames are framed by their end byte or length field as they unescape
        // (`rt::escaped_lens`), so a KISS data frame of up to 1024 bytes lists no lengths.
        if framing.length.is_some()
            || r.count != Count::ToEnd
            || framing.end_delimited()
            || framing.escaping.is_some()
        {
            return Vec::new();
        }
        let step = if f.ty == FieldType::Bit {
            1
        } else {
            f.width.max(1)
        };
        (self.layout.len..=self.max_len)
            .filter(|l| (l - self.layout.len) % step == 0)
            .collect()
    }

    /// The code as written in the spec: `0x2000`.
    pub fn code_hex(&self) -> String {
        let mut s = String::from("0x");
        for b in &self.code {
            s.push_str(&format!("{b:02X}"));
        }
        s
    }

    /// Every named value of the payload, packed sub-fields flattened, in wire order.
    pub fn leaves(&self) -> impl Iterator<Item = Leaf<'_>> {
        self.fields.iter().enumerate().flat_map(|(i, f)| {
            let own = (f.bits.is_empty()).then_some(Leaf::Field(i, f));
            let bits = f.bits.iter().map(move |b| Leaf::Bits(i, f, b));
            own.into_iter().chain(bits)
        })
    }
}

/// A named value of a message: a whole field, or a packed sub-field of one.
#[derive(Debug, Clone, Copy)]
pub enum Leaf<'a> {
    Field(usize, &'a Field),
    Bits(usize, &'a Field, &'a BitField),
}

impl Leaf<'_> {
    pub fn name(&self) -> &str {
        match self {
            Leaf::Field(_, f) => &f.name,
            Leaf::Bits(_, _, b) => &b.name,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Field {
    pub name: String,
    pub doc: String,
    pub ty: FieldType,
    /// Offset in the payload, bytes; for a header field ([`Self::header`]), in its `header`
    /// part ([`Self::part`]).
    pub offset: usize,
    /// A header field (`framing.header`): it sits in the frame's header, at the layout's
    /// `header` part plus `offset`, not in the payload. Header fields come first in a
    /// message's fields.
    pub header: bool,
    /// A header field's `header` part, counted from 0 in layout order (a layout may hold
    /// `header` up to [`MAX_HEADER_PARTS`] times); 0 for every other field.
    pub part: usize,
    /// Width on the wire, bytes.
    pub width: usize,
    pub signed: bool,
    /// The protocol's byte order, resolved here so emitters need not look it up.
    pub byte_order: ByteOrder,
    /// `word_order: swapped` (32- and 64-bit numbers only): the 16-bit words travel in the
    /// opposite order, byte `i` of the number in `byte_order` at [`crate::number::swap_index`].
    pub word_swapped: bool,
    /// `encoding: bcd` (unsigned fields of 1 to 4 bytes): two decimal digits a byte; the raw
    /// value is the decimal number (bytes `12 34` read big-endian are 1234), within
    /// `0..=10^(2 × width) - 1`, which [`Self::range`] always holds.
    pub bcd: bool,
    pub unit: Option<usize>,
    pub range: Option<(i64, i64)>,
    pub constant: Option<u64>,
    pub enumeration: Option<usize>,
    pub flags: Option<usize>,
    /// Index of an earlier field of the same message this one repeats.
    pub equals: Option<usize>,
    pub special: Vec<Special>,
    pub bits: Vec<BitField>,
    /// A repeated field: `width` is one element's (bytes; a bit element is 1 and packs eight to
    /// a byte), `offset` where the first sits when every earlier list is empty. Every field's
    /// `offset` is so counted: a field after lists sits further by the bytes their elements
    /// take (`interp::Shape`).
    pub repeat: Option<Repeat>,
    /// Packed elements (`packed:`): `width` is the bytes they take together; the elements
    /// have the field's type (`elem_width` bytes, unsigned), each `bits` wide.
    pub packed: Option<Packed>,
    /// The value follows from another field (of this frame or of the request).
    pub follows: Option<Follows>,
    /// A repeated record (`type: record`): its fields, each of a fixed width, `offset` counted
    /// from the record's first byte; `width` is their sum (one element's bytes). Empty for
    /// every other field.
    pub record: Vec<Field>,
    /// A record's last field whose bytes an earlier field of the message gives (`bytes:`):
    /// that field's index. Its `width` is its type's (the most it takes); in a frame it takes
    /// the named field's value, 1 up to that. The record's `width` counts it at its most.
    pub bytes_from: Option<usize>,
    /// An optional field (`present:`): on the wire only where its condition holds. Optional
    /// fields end the payload; `offset` is where the field sits when no optional field before
    /// it is on the wire (the optional fields before it on the wire shift it by their widths,
    /// as lists shift the fields after them: `interp::Shape`).
    pub present: Option<Presence>,
}

/// When an optional field is on the wire: a condition on an earlier field of its message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Presence {
    /// The field (index in the message's fields) whose raw value says.
    pub field: usize,
    pub when: PresentWhen,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PresentWhen {
    /// That bit (0 = least significant) of the field is set.
    Bit(u32),
    /// The field holds this raw value.
    Equals(i64),
}

impl Presence {
    /// Whether the field is present when the field it depends on holds `raw`.
    pub fn holds(&self, raw: i64) -> bool {
        match self.when {
            PresentWhen::Bit(b) => b < 64 && (raw as u64) >> b & 1 == 1,
            PresentWhen::Equals(v) => raw == v,
        }
    }

    /// The condition in words, with the name of the field it reads: `bit 0 of flags is set`,
    /// `kind = 2`.
    pub fn describe(&self, of: &str) -> String {
        match self.when {
            PresentWhen::Bit(b) => format!("bit {b} of `{of}` is set"),
            PresentWhen::Equals(v) => format!("`{of}` = {v}"),
        }
    }
}

/// A fixed number of elements, each `bits` wide, packed into one bit stream (CRSF's 16 × 11-bit
/// RC channels in 22 bytes). The bits after the last element, up to the byte's end, are 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packed {
    pub count: usize,
    pub bits: u32,
    /// `bit_order: lsb_first` (else `msb_first`).
    pub lsb_first: bool,
    /// The element type's width, bytes (1, 2 or 4; a list of a fixed count's, whose elements
    /// take whole bytes, 1 to 8).
    pub elem_width: usize,
}

impl Packed {
    /// Whether each element takes whole bytes of its type (`bits` its type's width): a plain
    /// array, as `repeat: {count: 4}` writes one, each element in the protocol's byte order.
    pub fn whole(&self) -> bool {
        self.bits as usize == 8 * self.elem_width
    }

    /// The bytes `count` elements take.
    pub fn bytes(&self) -> usize {
        (self.count * self.bits as usize).div_ceil(8)
    }

    /// The largest element (unsigned, of `bits` bits; all of `i64` for 64).
    pub fn max(&self) -> i64 {
        if self.bits >= 63 {
            i64::MAX
        } else {
            (1i64 << self.bits) - 1
        }
    }

    /// The elements packed in `bytes` (at most [`Self::bytes`] of them are read; missing ones
    /// read as 0).
    pub fn read(&self, bytes: &[u8]) -> Vec<i64> {
        (0..self.count)
            .map(|k| {
                let mut v = 0i64;
                for j in 0..self.bits as usize {
                    let (bit, at) = if self.lsb_first {
                        (j, k * self.bits as usize + j)
                    } else {
                        (self.bits as usize - 1 - j, k * self.bits as usize + j)
                    };
                    let b = bytes.get(at / 8).copied().unwrap_or(0);
                    let set = if self.lsb_first {
                        b >> (at % 8) & 1
                    } else {
                        b >> (7 - at % 8) & 1
                    };
                    v |= i64::from(set) << bit;
                }
                v
            })
            .collect()
    }

    /// Whether the padding bits after the last element are all 0.
    pub fn padding_clear(&self, bytes: &[u8]) -> bool {
        let used = self.count * self.bits as usize;
        (used..8 * self.bytes()).all(|at| {
            let b = bytes.get(at / 8).copied().unwrap_or(0);
            let set = if self.lsb_first {
                b >> (at % 8) & 1
            } else {
                b >> (7 - at % 8) & 1
            };
            set == 0
        })
    }

    /// Writes `items` (each within `0..=max`, at most `count`) into `out` (zeroed, at least
    /// [`Self::bytes`] long).
    pub fn write(&self, items: &[i64], out: &mut [u8]) {
        for (k, &v) in items.iter().enumerate().take(self.count) {
            for j in 0..self.bits as usize {
                let (bit, at) = if self.lsb_first {
                    (j, k * self.bits as usize + j)
                } else {
                    (self.bits as usize - 1 - j, k * self.bits as usize + j)
                };
                if v >> bit & 1 == 1 {
                    if let Some(b) = out.get_mut(at / 8) {
                        *b |= if self.lsb_first {
                            1 << (at % 8)
                        } else {
                            0x80 >> (at % 8)
                        };
                    }
                }
            }
        }
    }
}

/// How many elements a repeated field has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// The value of an earlier field (index) is the number of elements.
    Elements(usize),
    /// The value of an earlier field (index) is the number of bytes they take.
    Bytes(usize),
    /// As many as fit before the checksum.
    ToEnd,
    /// Characters up to the first terminator byte (this one), which travels after them: text
    /// (`type: ascii`) with `repeat: {until: 0x00}`.
    Until(u8),
    /// Exactly this many, always (`repeat: {count: 3}` on records, UBX's fixed blocks): no
    /// field counts them (`min` and `max` are this). A list of a fixed count of numbers is
    /// packed elements instead ([`Field::fixed_count`]).
    Fixed(usize),
}

impl Count {
    /// The earlier field (index) whose value counts the elements or bytes, if one does.
    pub fn field(&self) -> Option<usize> {
        match *self {
            Count::Elements(i) | Count::Bytes(i) => Some(i),
            Count::ToEnd | Count::Until(_) | Count::Fixed(_) => None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Repeat {
    pub count: Count,
    /// The fewest elements.
    pub min: usize,
    /// The most elements.
    pub max: usize,
    /// In a reply: the element count is this relation applied to a field of the request.
    pub request: Option<Relation>,
}

/// `ceil(value × multiply / divide)` of a named field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Relation {
    pub field: String,
    pub multiply: u64,
    pub divide: u64,
}

impl Relation {
    pub fn apply(&self, v: i64) -> i64 {
        let n = i128::from(v) * i128::from(self.multiply);
        let d = i128::from(self.divide.max(1));
        let q = if n >= 0 { (n + d - 1) / d } else { n / d };
        q.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
    }

    /// `value`, `2 × quantity`, `ceil(quantity / 8)`.
    pub fn describe(&self, of: &str) -> String {
        match (self.multiply, self.divide) {
            (1, 1) => of.to_owned(),
            (m, 1) => format!("{m} × {of}"),
            (1, d) => format!("ceil({of} / {d})"),
            (m, d) => format!("ceil({m} × {of} / {d})"),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Follows {
    /// An earlier field of the same frame (index).
    Field(usize, Relation),
    /// A field of the request this frame answers (by name).
    Request(Relation),
}

impl Field {
    /// Where the field (its first element, for a list before which every list is empty) sits
    /// in a frame laid out as `o`: in the header or in the payload.
    pub fn frame_at(&self, o: &FrameLayout) -> usize {
        if self.header {
            o.headers[self.part] + self.offset
        } else {
            o.payload + self.offset
        }
    }

    /// Where a header field sits, as docs and diff print it: `header + 2`, or `header part 3
    /// + 2` past the layout's first `header` (`framing.header`'s `part`).
    pub fn header_place(&self) -> String {
        match self.part {
            0 => format!("header + {}", self.offset),
            k => format!("header part {} + {}", k + 1, self.offset),
        }
    }

    /// Its constant as decode reads it: sign-extended where the field is signed.
    pub fn constant_value(&self) -> Option<i64> {
        let c = self.constant?;
        let bits = 8 * self.width as u32;
        Some(if self.signed && bits < 64 && c >> (bits - 1) & 1 == 1 {
            (c as i64) - (1i64 << bits)
        } else {
            c as i64
        })
    }

    /// Bytes `n` elements of a repeated field take.
    pub fn elements_len(&self, n: usize) -> usize {
        if self.ty == FieldType::Bit {
            n.div_ceil(8)
        } else if self.terminator().is_some() {
            // Characters and the terminator after them.
            n.saturating_add(1)
        } else {
            n.saturating_mul(self.width)
        }
    }

    /// The byte that ends text with `repeat: {until}` ([`Count::Until`]).
    pub fn terminator(&self) -> Option<u8> {
        match self.repeat.as_ref()?.count {
            Count::Until(t) => Some(t),
            _ => None,
        }
    }

    /// The whole elements of a repeated field that `bytes` bytes hold.
    pub fn elements_from(&self, bytes: usize) -> usize {
        if self.ty == FieldType::Bit {
            bytes.saturating_mul(8)
        } else {
            bytes / self.width.max(1)
        }
    }

    pub fn is_ascii(&self) -> bool {
        self.ty == FieldType::Ascii
    }

    /// Its packed elements where they are a list of a fixed count (`repeat: {count: N}`):
    /// elements of whole bytes ([`Packed::whole`]) in its byte order (the bit order the byte
    /// order). Packed elements of whole bytes in the other bit order (`packed: {count: 3, bits:
    /// 16, bit_order: lsb_first}` in a big-endian protocol) are not: each element's bytes
    /// travel reversed, as [`Packed::read`] reads them.
    pub fn fixed_count(&self) -> Option<&Packed> {
        self.packed.as_ref().filter(|pk| {
            pk.whole()
                && (pk.elem_width == 1 || pk.lsb_first == (self.byte_order == ByteOrder::Little))
        })
    }

    /// One of its packed elements as a field of its own (its type's width, not packed): how a
    /// list of a fixed count reads and writes each element. Itself where it is not packed.
    pub fn element(&self) -> std::borrow::Cow<'_, Field> {
        match &self.packed {
            Some(pk) => {
                let mut e = self.clone();
                e.width = pk.elem_width;
                e.packed = None;
                std::borrow::Cow::Owned(e)
            }
            None => std::borrow::Cow::Borrowed(self),
        }
    }

    /// The elements of a packed field from its bytes (missing ones read as 0): elements of
    /// whole bytes ([`Packed::whole`]) each as a field of its type reads ([`Self::element`]:
    /// sign-extended, its words in their order) where they are a list of a fixed count
    /// ([`Self::fixed_count`]), others as [`Packed::read`] reads them.
    pub fn packed_elements(&self, bytes: &[u8]) -> Vec<i64> {
        let Some(pk) = &self.packed else {
            return Vec::new();
        };
        if self.fixed_count().is_none() {
            return pk.read(bytes);
        }
        let e = self.element();
        let w = pk.elem_width.max(1);
        (0..pk.count)
            .map(|k| {
                let mut chunk = [0u8; 8];
                let n = w.min(8);
                for (j, slot) in chunk[..n].iter_mut().enumerate() {
                    *slot = bytes.get(k * w + j).copied().unwrap_or(0);
                }
                let u = crate::interp::read_number(&e, &chunk[..n]);
                if e.signed {
                    crate::interp::sign_extend(u, 8 * n as u32)
                } else {
                    u as i64
                }
            })
            .collect()
    }

    /// The raw values one of its packed elements holds: its type's ([`Self::raw_span`]) for a
    /// list of a fixed count ([`Self::fixed_count`]), else `0..=` [`Packed::max`].
    pub fn packed_span(&self) -> (i64, i64) {
        match &self.packed {
            Some(_) if self.fixed_count().is_some() => self.element().raw_span(),
            Some(pk) => (0, pk.max()),
            None => self.raw_span(),
        }
    }

    /// Writes packed elements `items` (each within [`Self::packed_span`], at most its count)
    /// into `out` (zeroed, at least its width long).
    pub fn write_packed(&self, items: &[i64], out: &mut [u8]) {
        let Some(pk) = &self.packed else {
            return;
        };
        if self.fixed_count().is_none() {
            return pk.write(items, out);
        }
        let e = self.element();
        for (v, chunk) in items
            .iter()
            .zip(out.chunks_exact_mut(pk.elem_width.max(1)))
            .take(pk.count)
        {
            crate::interp::write_number(&e, *v as u64, chunk);
        }
    }

    /// Whether its value is a list: a repeated field (not counted text) or packed elements.
    pub fn is_list(&self) -> bool {
        (self.repeat.is_some() && !self.is_ascii()) || self.packed.is_some()
    }

    /// Text a count field counts (`type: ascii` with `repeat`): on the wire one byte a
    /// character, framed as a list of bytes is; its value is text ([`Self::is_ascii`]).
    pub fn is_counted_text(&self) -> bool {
        self.is_ascii() && self.repeat.is_some()
    }

    /// Whether it is a repeated record (`type: record`), whose elements are groups of fields.
    pub fn is_record(&self) -> bool {
        self.ty == FieldType::Record
    }

    /// A repeated record whose last field's bytes an earlier field gives (`bytes:`): that
    /// field's index in the message.
    pub fn record_bytes_from(&self) -> Option<usize> {
        self.record.last().and_then(|g| g.bytes_from)
    }

    /// The narrowest a record element can be: its width with its last field at one byte
    /// where an earlier field gives that field's bytes (else its width).
    pub fn min_element_width(&self) -> usize {
        match (self.record_bytes_from(), self.record.last()) {
            (Some(_), Some(g)) => self.width - g.width + 1,
            _ => self.width,
        }
    }

    /// This repeated record as one frame has it, its last field `bytes` wide where an earlier
    /// field gives that (`bytes:`); the record as it is otherwise.
    pub fn record_in_frame(&self, bytes: usize) -> std::borrow::Cow<'_, Field> {
        match (self.record_bytes_from(), self.record.last()) {
            (Some(_), Some(g)) => {
                let mut f = self.clone();
                f.width = self.width - g.width + bytes;
                if let Some(last) = f.record.last_mut() {
                    last.width = bytes;
                }
                std::borrow::Cow::Owned(f)
            }
            _ => std::borrow::Cow::Borrowed(self),
        }
    }

    /// The name a record's field `j` goes by in errors: `blocks.position`.
    pub fn record_field_name(&self, j: usize) -> String {
        match self.record.get(j) {
            Some(r) => format!("{}.{}", self.name, r.name),
            None => self.name.clone(),
        }
    }

    /// How its raw value reads as a number.
    pub fn num_kind(&self) -> crate::number::NumKind {
        crate::number::NumKind::of(self.ty)
    }

    pub fn is_float(&self) -> bool {
        matches!(self.ty, FieldType::F32 | FieldType::F64)
    }

    /// A 64-bit integer or a float: never a count, a length or a value another follows.
    pub fn is_wide(&self) -> bool {
        matches!(
            self.ty,
            FieldType::U64 | FieldType::I64 | FieldType::F32 | FieldType::F64
        )
    }

    /// The raw values the field's type holds (all of `i64` for 64-bit types, whose raw value
    /// is their bits; an `f32`'s bits zero-extended).
    pub fn raw_span(&self) -> (i64, i64) {
        match self.width {
            8 => (i64::MIN, i64::MAX),
            w => crate::interp::raw_limits(8 * w as u32, self.signed),
        }
    }

    /// Whether `raw` lies outside the field's spec range, compared as its type compares.
    pub fn outside(&self, raw: i64, (min, max): (i64, i64)) -> bool {
        !self.num_kind().within(raw, min, max)
    }
}

#[derive(Debug, Clone)]
pub struct Special {
    pub value: i64,
    pub name: String,
    pub doc: String,
}

#[derive(Debug, Clone)]
pub struct BitField {
    pub name: String,
    pub doc: String,
    pub msb: u8,
    pub lsb: u8,
    pub signed: bool,
    pub unit: Option<usize>,
    pub range: Option<(i64, i64)>,
    pub constant: Option<u64>,
}

impl BitField {
    pub fn width(&self) -> u8 {
        self.msb - self.lsb + 1
    }
}

#[derive(Debug, Clone)]
pub struct Example {
    pub section: String,
    /// The message it shows.
    pub message: MessageRef,
    /// The request a response example answers.
    pub reply_to: Option<usize>,
    /// That request's frame as it travels, where the example gives it (`request`): the bytes
    /// a reply's checksum that takes them in runs over first.
    pub request: Option<Vec<u8>>,
    /// Verbatim from the document, or `None` for a derived example.
    pub printed: Option<String>,
    /// Our own frame text for a derived example.
    pub derived: Option<String>,
    pub comment: Option<String>,
    /// Stated values, as written in the spec (physical units, names for enums).
    pub values: Vec<(String, StatedValue)>,
    /// Index into `Protocol::errata`.
    pub erratum: Option<usize>,
    pub corrected: Option<String>,
    /// The bytes on the wire this example stands for (byte order applied).
    pub wire: Vec<u8>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MessageRef {
    pub direction: Direction,
    pub index: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub enum StatedValue {
    Number(Rational),
    Name(String),
    Names(Vec<String>),
    /// The elements of a repeated field.
    Numbers(Vec<Rational>),
    /// The records of a repeated record: each record's stated values by field name.
    Records(Vec<Vec<(String, StatedValue)>>),
    /// A number with more digits than a rational holds, as written: a 64-bit integer or a
    /// float reads it as its type; any other field refuses it for `why`.
    Exact {
        text: String,
        why: String,
    },
}

#[derive(Debug, Clone)]
pub struct Erratum {
    pub id: String,
    pub section: String,
    pub says: String,
    pub decision: String,
    pub why: String,
}

impl Protocol {
    /// What the code generator cannot emit yet, one line each (empty: it can emit all of it).
    /// It emits every construct of the language: sync sequences, every checksum and its
    /// coverage, 24-bit integers, a length field, values that follow another field or the
    /// request, codes derived from the request's, code-less messages, repeated fields and
    /// optional fields (variable-length frames). It refuses, by name, repeats to the end of the frame without a
    /// length field whose frame lengths (every whole number of elements) would make more than
    /// [`MAX_DISTINCT_LENGTHS`] in all: its stream decoder lists such lengths
    /// beforehand. The interpreter (`--spec`) serves those.
    pub fn generator_gaps(&self) -> Vec<String> {
        let mut gaps = Vec::new();
        let mut lengths: Vec<usize> = self
            .commands
            .iter()
            .chain(&self.responses)
            .flat_map(|m| m.listed_lengths(&self.framing))
            .collect();
        lengths.sort_unstable();
        lengths.dedup();
        // With several lists, or fields after one, what a reply takes from its request is
        // emitted for the first list and the fields before it.
        for m in self.commands.iter().chain(&self.responses) {
            if m.tail_repeat() {
                continue;
            }
            let first = m.repeats().next().map(|(i, _, _)| i);
            for (i, f) in m.fields.iter().enumerate() {
                let later = |l: usize| first.is_some_and(|first| l > first);
                let by_request = matches!(f.follows, Some(Follows::Request(_)))
                    && (later(i) || m.counted_by(i).is_some_and(|(l, _, _)| later(l)));
                let list_by_request =
                    f.repeat.as_ref().is_some_and(|r| r.request.is_some()) && later(i);
                if by_request || list_by_request {
                    gaps.push(format!(
                        "`{}.{}`: a value taken from the request after the message's first repeated field (the interpreter serves it: `busspec decode --spec`)",
                        m.name, f.name
                    ));
                }
            }
        }
        for r in &self.responses {
            let rels = r
                .fields
                .iter()
                .filter_map(|f| match (&f.follows, &f.repeat) {
                    (Some(Follows::Request(rel)), _) => Some(rel),
                    (_, Some(rep)) => rep.request.as_ref(),
                    _ => None,
                });
            for rel in rels {
                for cmd in r.answers.iter().filter_map(|&c| self.commands.get(c)) {
                    let Some(i) = cmd.fields.iter().position(|f| f.name == rel.field) else {
                        continue;
                    };
                    let first = cmd.repeats().next().map(|(l, _, _)| l);
                    if cmd.counted_by(i).is_some_and(|(l, _, _)| Some(l) != first) {
                        gaps.push(format!(
                            "`{}`: a reply's count taken from `{}.{}`, the count of a repeated field after the first (the interpreter serves it: `busspec decode --spec`)",
                            r.name, cmd.name, rel.field
                        ));
                    }
                }
            }
        }
        let max = MAX_DISTINCT_LENGTHS;
        if lengths.len() > max {
            for m in self.commands.iter().chain(&self.responses) {
                if m.listed_lengths(&self.framing).len() > 1 {
                    let f = m.repeat().map_or("", |(f, _)| f.name.as_str());
                    gaps.push(format!(
                        "`{}.{f}`: a repeat to the end of the frame without a length field (the frame lengths to list, {} in all, are more than the {max} the generated stream decoder tracks)",
                        m.name,
                        lengths.len()
                    ));
                }
            }
        }
        gaps
    }

    pub fn message(&self, r: MessageRef) -> &Message {
        match r.direction {
            Direction::Request => &self.commands[r.index],
            Direction::Response => &self.responses[r.index],
        }
    }

    pub fn messages(&self, d: Direction) -> &[Message] {
        match d {
            Direction::Request => &self.commands,
            Direction::Response => &self.responses,
        }
    }

    /// The messages of direction `d` that follow the framing: every one but the constant
    /// whole frames (`frame:`), which come after them, so an index into this slice is an index
    /// into [`Self::messages`].
    pub fn framed(&self, d: Direction) -> &[Message] {
        let all = self.messages(d);
        let constants = all.iter().rev().take_while(|m| m.frame.is_some()).count();
        &all[..all.len() - constants]
    }

    /// The reply whose checksum takes in its request's bytes that a frame of `wire`'s length
    /// and code is, among `directions` (validated: no message of another checksum rule
    /// shares a code and a length with one), and where its checksum takes up its own bytes.
    pub fn over_request(&self, directions: &[Direction], wire: &[u8]) -> Option<(&Message, usize)> {
        if !directions.contains(&Direction::Response) {
            return None;
        }
        self.framed(Direction::Response).iter().find_map(|m| {
            let from = m.over_request?;
            let fits = (m.layout.len..=m.max_len).contains(&wire.len())
                && wire.get(m.layout.code..m.layout.code + m.code.len()) == Some(&m.code[..]);
            fits.then_some((m, from))
        })
    }

    /// The message without a checksum (`checksum: none`) that a frame of `wire`'s length and
    /// code is, among `directions` (validated: no message with a checksum can have its code
    /// and length).
    pub fn unchecked(&self, directions: &[Direction], wire: &[u8]) -> Option<&Message> {
        directions.iter().find_map(|&d| {
            self.framed(d).iter().find(|m| {
                m.unchecked
                    && wire.len() == m.layout.len
                    && wire.get(m.layout.code..m.layout.code + m.code.len()) == Some(&m.code[..])
            })
        })
    }

    /// Whether any message travels without the framing's checksum (`checksum: none`).
    pub fn has_unchecked(&self) -> bool {
        self.commands
            .iter()
            .chain(&self.responses)
            .any(|m| m.unchecked)
    }

    /// The bytes a request's checksum covers, which a reply whose checksum takes in its
    /// request's bytes (`checksum_over_request`) takes first: from the checksum's first
    /// covered part to the checksum, or to the frame's end where the request travels without
    /// one (`checksum: none`). `None` for a frame shorter than the framing's trailer.
    pub fn checksum_span<'w>(&self, request: &'w [u8]) -> Option<&'w [u8]> {
        let w = self.framing.after_preamble(request);
        if self.unchecked(&[Direction::Request], w).is_some() {
            return w.get(self.framing.checksum.covers_from..);
        }
        self.framing.checksum_span_of(request)
    }

    /// Whether a request could be a frame of `wire`'s length and code: some request's code
    /// sits where that request's layout puts it, and its lengths take `wire`'s.
    pub fn request_fits(&self, wire: &[u8]) -> bool {
        self.framed(Direction::Request).iter().any(|m| {
            (m.min_len()..=m.max_len).contains(&wire.len())
                && wire.get(m.layout.code..m.layout.code + m.code.len()) == Some(&m.code[..])
        })
    }

    /// Whether any reply's checksum takes in its request's bytes.
    pub fn has_over_request(&self) -> bool {
        self.responses.iter().any(|m| m.over_request.is_some())
    }

    /// The constant whole frames of direction `d` (`frame:`), with their indices in
    /// [`Self::messages`].
    pub fn constants(&self, d: Direction) -> impl Iterator<Item = (usize, &[u8])> {
        let all = self.messages(d);
        let from = self.framed(d).len();
        (from..all.len()).filter_map(move |i| all[i].frame.as_deref().map(|f| (i, f)))
    }

    /// The constant whole frame of direction `d` that `wire` is, byte for byte, if any.
    pub fn constant_of(&self, d: Direction, wire: &[u8]) -> Option<MessageRef> {
        self.constants(d)
            .find(|(_, f)| *f == wire)
            .map(|(index, _)| MessageRef {
                direction: d,
                index,
            })
    }

    /// Frame length of a message, in bytes (its resolved [`Message::layout`]).
    pub fn frame_len(&self, m: &Message) -> usize {
        m.layout.len
    }

    /// The longest frame in a direction.
    pub fn max_frame_len(&self, d: Direction) -> usize {
        self.messages(d)
            .iter()
            .map(|m| m.max_len)
            .max()
            .unwrap_or(0)
    }

    /// The shortest and longest frame of a direction (`None`: it has no message). An escaped
    /// stream decodes a frame as a direction only where its unescaped length lies between them.
    pub fn frame_len_bounds(&self, d: Direction) -> Option<(usize, usize)> {
        let ms = self.messages(d);
        let lo = ms.iter().map(|m| m.min_len()).min()?;
        Some((lo, self.max_frame_len(d)))
    }

    /// The longest frame of either direction before escaping: what generated code unescapes
    /// into (`UNESCAPED_LEN`).
    pub fn longest_frame(&self) -> usize {
        self.max_frame_len(Direction::Request)
            .max(self.max_frame_len(Direction::Response))
    }

    /// The longest frame of either direction as it travels (generated `MAX_FRAME_LEN`: what
    /// generated code lays a frame out into).
    pub fn longest_wire(&self) -> usize {
        self.max_wire_len(Direction::Request)
            .max(self.max_wire_len(Direction::Response))
    }

    /// The longest frame in a direction as it travels: escaped at worst, after the preamble
    /// an encoder sends.
    pub fn max_wire_len(&self, d: Direction) -> usize {
        let preamble = self.framing.preamble.as_ref().map_or(0, |pre| pre.send);
        self.framing.wire_len(self.max_frame_len(d)) + usize::from(preamble)
    }

    /// Finds a command or response by name.
    pub fn find(&self, name: &str) -> Option<MessageRef> {
        self.find_in(name, Direction::Request)
            .or_else(|| self.find_in(name, Direction::Response))
    }

    /// The message of direction `d` named `name` (commands and responses share one name space,
    /// so a name is never found in both).
    pub fn find_in(&self, name: &str, d: Direction) -> Option<MessageRef> {
        self.messages(d)
            .iter()
            .position(|m| m.name == name)
            .map(|index| MessageRef {
                direction: d,
                index,
            })
    }
}
