//! A streaming frame decoder for bus captures: bytes in, in chunks of any size; frames out.
//!
//! [`StreamDecoder`] is sans-IO: it reads nothing and prints nothing. Push the bytes as they come
//! ([`StreamDecoder::push`]) and call [`StreamDecoder::flush`] at the end of the capture (or when
//! the bus has gone quiet for longer than a frame takes); each call returns the [`Event`]s it
//! settled. It never panics, and its buffer never holds more than [`StreamDecoder::capacity`]
//! bytes: the longest frame of the directions it decodes.
//!
//! # The framing rule
//!
//! A sniffer on an RS485 pair sees both directions, noise, and frames cut short, with nothing but
//! the bytes themselves to say where a frame starts. The decoder looks at the bytes at the head
//! of its buffer (the earliest byte not yet accounted for) and asks which messages could start
//! there:
//!
//! 0. A constant whole frame (`frame:`, M-Bus's `E5`) whose bytes the head holds is that
//!    frame, settled at once; while the head holds only the start of one, the decoder waits
//!    (unless flushing). No framed frame begins with a constant frame's first byte
//!    (validated), so no other candidate competes.
//! 1. A message is a *candidate* while every byte already buffered agrees with it: the start byte
//!    (protocols that have one) and its code. Not the address: strict decoding judges it
//!    ([`crate::interp::address_allowed`]), so the stream accepts exactly the addresses
//!    [`crate::interp::decode`] accepts, and reports a frame from any other as out of spec
//!    (rule 4) instead of losing it in the noise.
//!    Every message of the decoded directions is considered, whatever its direction: UB2 setter
//!    requests and their echo ACKs share a code and differ only in length; SD codes are disjoint
//!    per direction.
//! 2. No candidate: the head byte starts no frame. It is dropped as noise and the next byte is
//!    tried (*resynchronisation by one byte*). Consecutive dropped bytes are reported together as
//!    one [`Event::Skipped`] (split every [`MAX_SKIPPED_RUN`] bytes, so memory stays bounded).
//! 3. While any candidate is longer than what is buffered, the decoder waits for more bytes
//!    (unless flushing).
//! 4. Then every candidate length that is complete is tried, **longest first**: the first length
//!    whose bytes checksum and decode (through [`crate::interp::decode`]: code, length,
//!    constants, repeated fields, ranges, address and broadcast rules) is the frame, and that many bytes are consumed. A frame that
//!    checksums but fits several messages that only its request can tell apart (SD 0x22..0x28,
//!    0x38) is paired with the request (see below) or else reported as [`Event::Ambiguous`],
//!    still consuming its bytes. If no length decodes, the longest whose bytes checksum and
//!    fail *only* a rule of the spec — strict decoding refuses them with
//!    [`DecodeError::OutOfRange`], [`DecodeError::BadAddress`] or
//!    [`DecodeError::BroadcastNotAccepted`] ([`breaks_spec`]) — is an [`Event::OutOfSpec`]: the
//!    reason, the values as they decode with those rules lifted ([`decode_lenient`]), and its
//!    bytes consumed, so the decoder never resynchronises inside it. If none, the head byte is
//!    noise (rule 2).
//!
//! A list to the end of a frame that end bytes alone delimit ([`crate::ir::Framing::end_delimited`]:
//! no length field, no checksum) has one length: up to the first end bytes from the list's
//! first byte ([`crate::ir::Message::delimited_list`]), waited for while the buffer holds less
//! than the message's longest frame; none where that is not a whole number of elements within
//! its bounds. Decoding refuses such a list holding them ([`DecodeError::EndInside`]), so no
//! longer length could decode either.
//!
//! Text up to a terminator in a frame without a length field
//! ([`crate::ir::Message::terminated_text`], the message's only list) has one length too: the
//! message's frame with the characters up to the first terminator from the text's first byte,
//! and the terminator; waited for while fewer than its `max` characters and the terminator
//! are buffered from there, none where they hold no terminator or it comes before `min`
//! characters (decoding would refuse every length).
//!
//! Why longest first: when a short and a long message share a code (a UB2 setter request
//! `AA 21 43 00 a s cs` and its ACK `AA 21 43 00 cs`), preferring the short one would misread
//! every request whose first payload byte happens to equal the ACK's checksum — a fixed value
//! (`0x0E` for address 0x21, code 0x4300), so a whole class of requests would always be lost.
//! Preferring the long one errs only when an ACK and the bytes after it checksum as the long
//! message by chance: about one in 256 for UB2's 8-bit sum, and then with plausible start,
//! address and code already matched.
//!
//! Limits, stated plainly:
//! - A short frame sharing its code with a longer one is settled only once the longer one's
//!   length has arrived or [`StreamDecoder::flush`] is called: a live sniffer should flush when
//!   the line goes idle (UB2 requires 10 ms between requests).
//! - The chance misreading above: the long frame then swallows the start of the next frame,
//!   whose remaining bytes are skipped as noise until the decoder resynchronises.
//! - A frame whose checksum passes by chance inside noise is reported as a frame: an 8-bit sum
//!   makes this likelier than a 16-bit CRC does; the start byte, code and address checks
//!   narrow it.
//! - An out-of-spec frame is never reported as a frame: only as [`Event::OutOfSpec`]. Noise whose
//!   start byte and code fit and whose checksum passes by chance can be reported as out of spec
//!   (a random address byte must still checksum), as it could be reported as a frame before.
//! - Decisions depend only on the bytes, never on how they were cut into chunks: the same capture
//!   gives the same events however it is pushed, as long as `flush` is called only at its end.
//!
//! # Shared flags
//!
//! Where one byte both opens and closes every frame ([`crate::ir::Framing::shared_flag`]: HDLC's
//! `7E`, KISS's `C0`), a sender may let the flag that closes a frame open the next one. A frame's
//! closing flag is therefore left at the head after its event: if a frame starts there, the two
//! events share that byte (the later one starts where the earlier one ends, less one); if none
//! does (the next flag follows at once, or the capture ends), it is dropped without being
//! reported as noise, since its frame accounted for it.
//!
//! # Preambles
//!
//! Where wake-up bytes come before a frame ([`crate::ir::Framing::preamble`]: DL/T 645's
//! `FE FE FE FE`), a run of the preamble byte (which starts no frame: it is never a start byte)
//! is held rather than reported as noise. A frame (or an ambiguous or out-of-spec one) that
//! starts right after the run takes the held bytes into its event, whose offset is then the
//! first of them; at most the preamble's `max` are held, so in a longer run the first bytes
//! are noise. Held bytes that open no frame (a byte that is neither a frame nor the preamble
//! byte follows, or the capture ends) are noise after all.
//!
//! # Long length forms
//!
//! Where the start byte chooses the length field's width ([`crate::ir::Framing::long`]: VESC's
//! `02 len …` and `03 lenH lenL …`), both start bytes open a frame: the head byte is noise
//! unless it is one of them, and the frame is as long as the length field of its form says
//! (waiting for that field, then for the frame). A long frame whose length the short form holds
//! is refused by strict decoding ([`DecodeError::NeedlessLong`]) and so is noise here, as a
//! frame with a bad checksum is; the decoder resynchronises on the byte after its start byte.
//!
//! A short form of the frame ([`crate::ir::Framing::form`]: M-Bus's `10 C A CS 16` beside
//! `68 L L 68 …`) is framed the same way: its start byte opens a frame of the short form's one
//! length (a frame with an empty payload), the framing's own start byte one as long as its
//! length field says.
//!
//! # Pairing responses with requests
//!
//! A response that only its request can identify is decoded as the answer to the last request
//! seen since the previous response (a sniffer sees the request just before its reply). A
//! response ends the pairing, since a request gets one reply, but one sent unasked that is not
//! the request's reply (a heartbeat between a request and its reply), which leaves the request
//! waiting for its reply; failing a current request, the
//! default request given to [`StreamDecoder::with_default_request`] is used (for a capture of
//! one direction only). If that still leaves it open, the frame is [`Event::Ambiguous`]. An
//! out-of-spec frame ends the pairing, as an ambiguous one does.
//!
//! Pairing says which response a frame is, never whether it is one: a frame that decodes both
//! as a request and as a response (a Modbus write_single_coil echo; a read_coils request whose
//! starting address has the high byte 0x03, which also reads as a reply with 3 bytes of coils)
//! is [`Event::Ambiguous`] whatever request came before it, since the bytes cannot tell a
//! reply from the master's next request or retry. (`busspec decode --reply-to` on single
//! frames does settle it: there the user says the frames are replies.) The generated stream
//! decoder follows the same rule.

use crate::interp::{self, DecodeError, Frame, Lookup, Raw, Spare, Value};
use crate::ir::{Count, Direction, FrameLayout, Message, MessageRef, Protocol};

/// Consecutive noise bytes beyond this many are reported in more than one [`Event::Skipped`].
pub const MAX_SKIPPED_RUN: usize = 256;

/// The most buffers of each kind [`StreamDecoder::recycle`] keeps.
const SPARE: usize = 4096;

/// What the decoder found in the capture. Offsets count bytes from the first byte ever pushed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event<'p> {
    /// A frame that checksummed and decoded.
    Frame {
        offset: u64,
        bytes: Vec<u8>,
        frame: Frame<'p>,
    },
    /// A frame that checksummed but fits several messages only its request could tell apart,
    /// with no request to pair it with. Its bytes are consumed.
    Ambiguous {
        offset: u64,
        bytes: Vec<u8>,
        candidates: Vec<String>,
    },
    /// Bytes that start no frame.
    Skipped { offset: u64, bytes: Vec<u8> },
    /// A frame whose start byte, code, length and checksum fit, but that breaks a rule of the
    /// spec: `reason` is the strict decoder's error ([`breaks_spec`]; where the frame could be
    /// either, the first refusal both ways, as `interp::decode` says it); `frame` its values with the spec's rules lifted, where they
    /// decode so ([`decode_lenient`]; not when the frame is ambiguous without them). Its bytes
    /// are consumed.
    OutOfSpec {
        offset: u64,
        bytes: Vec<u8>,
        reason: DecodeError,
        frame: Option<Frame<'p>>,
    },
}

impl Event<'_> {
    /// Offset of the event's first byte in the capture.
    pub fn offset(&self) -> u64 {
        match self {
            Event::Frame { offset, .. }
            | Event::Ambiguous { offset, .. }
            | Event::OutOfSpec { offset, .. }
            | Event::Skipped { offset, .. } => *offset,
        }
    }

    /// The bytes the event accounts for.
    pub fn bytes(&self) -> &[u8] {
        match self {
            Event::Frame { bytes, .. }
            | Event::Ambiguous { bytes, .. }
            | Event::OutOfSpec { bytes, .. }
            | Event::Skipped { bytes, .. } => bytes,
        }
    }
}

/// One message as the framing rule sees it.
#[derive(Debug, Clone)]
struct Shape {
    message: MessageRef,
    code: Vec<u8>,
    /// The frame's length: fixed, or for a variable message that of a frame with no elements
    /// (its lengths are [`lens`]').
    len: usize,
    variable: bool,
    at: FrameLayout,
}

/// The lengths a message's frame can have, as far as the buffered bytes tell.
enum Lens {
    /// The length depends on bytes not yet buffered (a length or count field).
    Need,
    /// Any of these (none: the bytes say the frame is longer than the message allows).
    Are(Vec<usize>),
}

/// The frame lengths message `m` could have given the bytes at the head of the buffer: its
/// fixed length; the length its length field or count field gives; for a repeat to the end of
/// the frame, every whole number of elements between its bounds.
fn lens_of(p: &Protocol, m: &Message, buf: &[u8]) -> Lens {
    // A truncated payload (`framing.truncation`): its length field gives the frame's length,
    // one payload byte up to the message's whole (fixed: validated).
    if p.framing.truncation.is_some() {
        let (Some(l), Some(at)) = (&p.framing.length, m.layout.length) else {
            return Lens::Are(Vec::new());
        };
        let Some(bytes) = buf.get(at..at + l.width) else {
            return Lens::Need;
        };
        let v = interp::read_uint(bytes, p.byte_order) as i64;
        let base = interp::length_for(p, m.direction, m.layout.len).unwrap_or(0);
        let ok = usize::try_from(m.layout.len as i64 + (v - base))
            .ok()
            .filter(|n| crate::truncate::lens(m.layout.len, m.payload_len).contains(n));
        return Lens::Are(ok.into_iter().collect());
    }
    let repeat = m.repeat();
    if repeat.is_none() && !m.has_optional() {
        return Lens::Are(vec![m.layout.len]);
    }
    // A variable-length message whose length or count field gives its length is told apart
    // by the constants that lead its payload too, as by its code
    // (`Message::leading_constants`): wait for them, and none where one differs. One whose
    // elements run to the end without a length field has its lengths listed, as a fixed
    // message's, by its code alone (unless end bytes alone delimit it).
    // One that end bytes alone delimit is told apart by its leading constants too.
    let listed = p.framing.length.is_none()
        && repeat.is_some_and(|(_, r)| r.count == Count::ToEnd)
        && m.delimited_list(&p.framing).is_none();
    let lead = if listed {
        Vec::new()
    } else {
        m.leading_constants()
    };
    // As they travel (`framing.transform`).
    let lead: Vec<u8> = match &p.framing.transform {
        Some(t) => lead.iter().map(|&b| t.apply(b)).collect(),
        None => lead,
    };
    let at = m.layout.payload;
    for (i, &b) in lead.iter().enumerate() {
        match buf.get(at + i) {
            Some(&x) if x != b => return Lens::Are(Vec::new()),
            Some(_) => {}
            None => return Lens::Need,
        }
    }
    // Within the frames the message can have: with the fewest elements to the most.
    let within = |len: i64| -> Lens {
        let ok = usize::try_from(len)
            .ok()
            .filter(|l| (m.min_len()..=m.max_len).contains(l));
        Lens::Are(ok.into_iter().collect())
    };
    if let (Some(l), Some(at)) = (&p.framing.length, m.layout.length) {
        let Some(bytes) = buf.get(at..at + l.width) else {
            return Lens::Need;
        };
        let v = interp::read_uint(bytes, p.byte_order) as i64;
        let base = interp::length_for(p, m.direction, m.layout.len).unwrap_or(0);
        return within(m.layout.len as i64 + (v - base));
    }
    // Optional fields have a length field (validated): only a list is left to read.
    let Some((f, r)) = repeat else {
        return Lens::Are(Vec::new());
    };
    match r.count {
        Count::Elements(_) | Count::Bytes(_) | Count::Fixed(_) => {
            // Each list's count field, read where the lists before it put it (a list to the
            // end beside others has a length field: validated).
            let mut tail = 0usize;
            let mut lists: Vec<(usize, usize)> = Vec::new();
            for (li, lf, lr) in m.repeats() {
                let n = match lr.count {
                    // Records of a fixed count: that many, no field to read.
                    Count::Fixed(n) => n,
                    Count::Elements(c) | Count::Bytes(c) => {
                        let cf = &m.fields[c];
                        let shift: usize = lists.iter().filter(|l| l.0 < c).map(|l| l.1).sum();
                        let at = m
                            .layout
                            .payload
                            .saturating_add(cf.offset)
                            .saturating_add(shift);
                        let Some(bytes) = buf.get(at..at.saturating_add(cf.width)) else {
                            return Lens::Need;
                        };
                        let v = interp::read_uint(bytes, cf.byte_order);
                        usize::try_from(v).unwrap_or(usize::MAX)
                    }
                    // Text up to a terminator is here only with a length field (validated).
                    Count::ToEnd | Count::Until(_) => continue,
                };
                let len = match lr.count {
                    Count::Elements(_) | Count::Fixed(_) => lf.elements_len(n),
                    _ => n,
                };
                // Several lists, or fields after one: each list's count must fit its own
                // bounds in whole elements (as the generated `Lists::frame_len` checks).
                let whole = lf.ty == crate::ir::FieldType::Bit || len % lf.width.max(1) == 0;
                if !m.tail_repeat()
                    && (len < lf.elements_len(lr.min) || len > lf.elements_len(lr.max) || !whole)
                {
                    return Lens::Are(Vec::new());
                }
                tail = tail.saturating_add(len);
                if m.layout.len.saturating_add(tail) > m.max_len {
                    return Lens::Are(Vec::new());
                }
                lists.push((li, len));
            }
            within(m.layout.len.saturating_add(tail) as i64)
        }
        // Text up to a terminator without a length field (the message's only list:
        // validated): the frame ends at its first terminator from the text's first byte, its
        // characters and the terminator at most `max` + 1 bytes.
        Count::Until(t) => {
            let at = f.frame_at(&m.layout);
            let most = at.saturating_add(r.max).saturating_add(1);
            let seen = buf.get(at..buf.len().min(most)).unwrap_or(&[]);
            match seen.iter().position(|&b| b == t) {
                Some(n) if n >= r.min => within(m.layout.len.saturating_add(n + 1) as i64),
                Some(_) => Lens::Are(Vec::new()),
                None if buf.len() >= most => Lens::Are(Vec::new()),
                None => Lens::Need,
            }
        }
        Count::ToEnd => {
            let step = if f.ty == crate::ir::FieldType::Bit {
                1
            } else {
                f.width.max(1)
            };
            // End bytes alone delimit the frame: it ends at their first appearance from the
            // list's first byte on, within the longest frame of the message.
            if let Some((_, at)) = m.delimited_list(&p.framing) {
                let end = &p.framing.end;
                let seen = buf.get(at..buf.len().min(m.max_len)).unwrap_or(&[]);
                // Fields after the list sit between it and the end bytes.
                let len = |i: usize| at + i + end.len();
                return match p.framing.first_end(seen) {
                    Some(i) if len(i) >= m.layout.len && (len(i) - m.layout.len) % step == 0 => {
                        within(len(i) as i64)
                    }
                    Some(_) => Lens::Are(Vec::new()),
                    None if buf.len() >= m.max_len => Lens::Are(Vec::new()),
                    None => Lens::Need,
                };
            }
            Lens::Are(
                (m.layout.len..=m.max_len)
                    .filter(|l| (l - m.layout.len) % step == 0)
                    .collect(),
            )
        }
    }
}

/// The messages whose code sits at one offset, by the bytes of their code: the only ones that
/// can agree with the buffered bytes there.
#[derive(Debug, Clone)]
struct ByCode {
    code_at: usize,
    codes: CodeNode,
}

/// Shapes (indices into the decoder's shapes) by their code, a byte per level: a node stands
/// for the code bytes on the path to it.
#[derive(Debug, Clone, Default)]
struct CodeNode {
    /// The shapes whose code is exactly the bytes on the path.
    ends: Vec<usize>,
    /// Every shape whose code starts with the bytes on the path (`ends` included).
    all: Vec<usize>,
    /// The node after each next byte (256 of them), or empty where no code is longer.
    next: Vec<CodeNode>,
}

impl CodeNode {
    fn insert(&mut self, code: &[u8], shape: usize) {
        self.all.push(shape);
        let Some((&b, rest)) = code.split_first() else {
            self.ends.push(shape);
            return;
        };
        if self.next.is_empty() {
            self.next = vec![CodeNode::default(); 256];
        }
        self.next[usize::from(b)].insert(rest, shape);
    }

    /// Appends to `out` the shapes whose code agrees with `bytes`, the buffered bytes from
    /// where the code sits: those whose code the bytes start with, and those whose code starts
    /// with all the bytes there are.
    fn agreeing(&self, bytes: &[u8], out: &mut Vec<usize>) {
        let mut node = self;
        for &b in bytes {
            // Most nodes end no code (and the copy of an empty list is a call all the same).
            if !node.ends.is_empty() {
                out.extend_from_slice(&node.ends);
            }
            match node.next.get(usize::from(b)) {
                Some(next) => node = next,
                None => return,
            }
        }
        out.extend_from_slice(&node.all);
    }
}

/// What the head of the buffer holds, for a protocol with escaping.
enum Escaped {
    /// Frame lengths to try (complete).
    Try,
    /// The head byte starts no frame.
    Drop,
    /// A frame may start here, not yet complete.
    NeedMore,
}

/// What the head of the buffer holds as constant whole frames go.
enum Constant {
    /// This constant frame, this long.
    Found(MessageRef, usize),
    /// The start of one, not yet complete.
    Wait,
    None,
}

/// The constant whole frames of the directions decoded (`None`: both).
fn constants(
    p: &Protocol,
    direction: Option<Direction>,
) -> impl Iterator<Item = (MessageRef, &[u8])> {
    [Direction::Request, Direction::Response]
        .into_iter()
        .filter(move |d| direction.map_or(true, |want| want == *d))
        .flat_map(move |d| {
            p.constants(d).map(move |(index, f)| {
                (
                    MessageRef {
                        direction: d,
                        index,
                    },
                    f,
                )
            })
        })
}

/// What one step of the framing rule did.
enum Step {
    Progress,
    NeedMore,
}

/// Splits a byte stream into frames of one protocol. See the module docs for the rule.
#[derive(Debug, Clone)]
pub struct StreamDecoder<'p> {
    p: &'p Protocol,
    direction: Option<Direction>,
    shapes: Vec<Shape>,
    /// The shapes grouped by where their code sits, then by its first byte; made once.
    by_code: Vec<ByCode>,
    /// Shapes without a code: candidates wherever their start byte agrees.
    codeless: Vec<usize>,
    /// The decoding `interp::decode` does for this protocol and direction, prepared once.
    lookup: Lookup,
    /// Decoding both ways, the lookups of one direction each: a length only one direction's
    /// candidates have is decoded as that direction alone, as the generated stream decoder
    /// decodes it.
    one_way: Option<[Lookup; 2]>,
    /// Per length in `lens`, the directions whose candidates have it (bit 0 requests, bit 1
    /// responses).
    dirs: Vec<u8>,
    /// Candidate shapes and lengths of one step, kept for their memory.
    candidates: Vec<usize>,
    lens: Vec<usize>,
    /// The shortest frame the decoder decodes.
    shortest: usize,
    capacity: usize,
    /// Bytes not yet accounted for; `buf[0]` is at capture offset `head`.
    buf: Vec<u8>,
    head: u64,
    /// Noise not yet reported; its first byte is at capture offset `noise_at`.
    noise: Vec<u8>,
    noise_at: u64,
    /// The flag of flag framing ([`crate::ir::Framing::shared_flag`]), if the protocol has one.
    shared_flag: Option<u8>,
    /// Whether any reply's checksum takes in its request's bytes: the stream keeps them.
    over_request: bool,
    /// Whether `buf[0]` is the closing flag of the frame just reported, kept as the next
    /// frame's possible opening one: if it opens none, it is dropped without being noise.
    held_flag: bool,
    /// The preamble's byte and the most a frame takes ([`crate::ir::Framing::preamble`]).
    preamble: Option<(u8, usize)>,
    /// Preamble bytes held just before `buf[0]`, the first at capture offset `preamble_at`:
    /// the next frame's if one starts at `buf[0]`, else noise.
    preamble_at: u64,
    preamble_len: usize,
    /// Command index of the last request seen since the previous response.
    last_request: Option<usize>,
    /// That request's frame: a reply it settles must also agree with its values (a READ's
    /// reply holds as many bytes as it asked for), as the generated stream decoder checks
    /// `decode_reply` against the request it keeps; a reply that does not is decoded alone.
    last_frame: Option<Frame<'p>>,
    /// The bytes that request's checksum covers, which the checksum of a reply that takes in
    /// its request's bytes runs over first (`checksum_over_request`).
    last_covered: Vec<u8>,
    default_request: Option<usize>,
    /// The spec with its rules lifted ([`relaxed`]), made at the first out-of-spec frame.
    relaxed: Option<Box<Protocol>>,
    /// Empty buffers of events given back ([`Self::recycle`]), for the next events' bytes and
    /// values.
    spare_bytes: Vec<Vec<u8>>,
    spare_values: Vec<Vec<Value<'p>>>,
    /// The memory the lookup decodes in.
    spare: Spare<'p>,
}

impl<'p> StreamDecoder<'p> {
    /// A decoder for `direction` (`None`: both, as a sniffer sees them).
    pub fn new(p: &'p Protocol, direction: Option<Direction>) -> StreamDecoder<'p> {
        let mut shapes = Vec::new();
        for d in [Direction::Request, Direction::Response] {
            if direction.is_some_and(|want| want != d) {
                continue;
            }
            for (index, m) in p.framed(d).iter().enumerate() {
                shapes.push(Shape {
                    message: MessageRef {
                        direction: d,
                        index,
                    },
                    code: m.code.clone(),
                    len: p.frame_len(m),
                    // A truncating framing's frames are as long as their length field says.
                    variable: m.is_variable() || p.framing.truncation.is_some(),
                    at: m.layout,
                });
            }
        }
        // Escaped frames take up to their worst case on the wire.
        let capacity = p
            .framing
            .wire_len(
                shapes
                    .iter()
                    .map(|s| p.message(s.message).max_len)
                    .max()
                    .unwrap_or(0),
            )
            .max(
                constants(p, direction)
                    .map(|(_, f)| f.len())
                    .max()
                    .unwrap_or(0),
            )
            .max(1);
        let shortest = shapes.iter().map(|s| s.len).min().unwrap_or(1).max(1);
        let mut by_code: Vec<ByCode> = Vec::new();
        let mut codeless = Vec::new();
        for (i, s) in shapes.iter().enumerate() {
            if s.code.is_empty() {
                codeless.push(i);
                continue;
            }
            let group = match by_code.iter().position(|g| g.code_at == s.at.code) {
                Some(g) => g,
                None => {
                    by_code.push(ByCode {
                        code_at: s.at.code,
                        codes: CodeNode::default(),
                    });
                    by_code.len() - 1
                }
            };
            by_code[group].codes.insert(&s.code, i);
        }
        StreamDecoder {
            p,
            direction,
            shapes,
            by_code,
            codeless,
            lookup: Lookup::new(p, direction),
            one_way: direction.is_none().then(|| {
                [
                    Lookup::new(p, Some(Direction::Request)),
                    Lookup::new(p, Some(Direction::Response)),
                ]
            }),
            dirs: Vec::new(),
            candidates: Vec::new(),
            lens: Vec::new(),
            shortest,
            capacity,
            buf: Vec::with_capacity(capacity),
            head: 0,
            noise: Vec::new(),
            noise_at: 0,
            shared_flag: p.framing.shared_flag(),
            over_request: p.has_over_request(),
            held_flag: false,
            preamble: p
                .framing
                .preamble
                .as_ref()
                .map(|pre| (pre.byte, usize::from(pre.max))),
            preamble_at: 0,
            preamble_len: 0,
            last_request: None,
            last_frame: None,
            last_covered: Vec::new(),
            default_request: None,
            relaxed: None,
            spare_bytes: Vec::new(),
            spare_values: Vec::new(),
            spare: Spare::default(),
        }
    }

    /// The request (a command index) to pair ambiguous responses with when no request has been
    /// seen since the previous response: for captures of the device's side only.
    pub fn with_default_request(mut self, command: Option<usize>) -> StreamDecoder<'p> {
        self.default_request = command.filter(|&c| c < self.p.commands.len());
        self
    }

    /// The most bytes the decoder ever buffers: the longest frame it decodes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Bytes pushed so far and settled (reported, or noise waiting to be reported).
    pub fn settled(&self) -> u64 {
        self.head
    }

    /// Feeds bytes; returns what they settled. Bytes that might still start a frame stay
    /// buffered until more arrive or [`StreamDecoder::flush`] is called.
    pub fn push(&mut self, data: &[u8]) -> Vec<Event<'p>> {
        let mut out = Vec::new();
        self.push_into(data, &mut out);
        out
    }

    /// Takes back events the caller is done with (leaving `events` empty), to build the next
    /// ones in their memory: an event's bytes and a frame's values are otherwise allocated per
    /// event and freed by the caller.
    pub fn recycle(&mut self, events: &mut Vec<Event<'p>>) {
        // Taken out in place: an event is large (an out-of-spec one holds its error).
        for e in events.iter_mut() {
            let (bytes, values) = match e {
                Event::Frame { bytes, frame, .. } => (bytes, Some(&mut frame.values)),
                Event::Ambiguous { bytes, .. }
                | Event::Skipped { bytes, .. }
                | Event::OutOfSpec { bytes, .. } => (bytes, None),
            };
            if self.spare_bytes.len() < SPARE {
                let mut bytes = std::mem::take(bytes);
                bytes.clear();
                self.spare_bytes.push(bytes);
            }
            if let Some(values) = values.filter(|_| self.spare_values.len() < SPARE) {
                let mut values = std::mem::take(values);
                values.clear();
                self.spare_values.push(values);
            }
        }
        events.clear();
    }

    /// [`Self::push`], appending the events to `out` (for a caller that reuses one list).
    pub fn push_into(&mut self, mut data: &[u8], out: &mut Vec<Event<'p>>) {
        // As many events as frames of the shortest length fit (noise runs come between them).
        out.reserve(data.len() / self.shortest + 1);
        while !data.is_empty() {
            let room = self.capacity.saturating_sub(self.buf.len()).max(1);
            let n = room.min(data.len());
            self.buf.extend_from_slice(&data[..n]);
            data = &data[n..];
            // A full buffer settles something at every step (no frame is longer), and settles
            // it as the same bytes with fewer buffered would: so steps wait for a full buffer
            // while bytes remain, instead of waiting at every shorter one.
            while self.buf.len() >= self.capacity {
                if let Step::NeedMore = self.step(false, out) {
                    break;
                }
            }
        }
        self.drain(false, out);
    }

    /// Settles everything buffered, as at the end of a capture or after an idle gap: complete
    /// frames are decoded with the candidates that fit, the rest is noise. The decoder stays
    /// usable; offsets continue.
    pub fn flush(&mut self) -> Vec<Event<'p>> {
        let mut out = Vec::new();
        self.drain(true, &mut out);
        self.release_preamble();
        self.report_noise(&mut out);
        out
    }

    fn drain(&mut self, flushing: bool, out: &mut Vec<Event<'p>>) {
        while let Step::Progress = self.step(flushing, out) {}
    }

    /// Applies the framing rule once at the head of the buffer.
    fn step(&mut self, flushing: bool, out: &mut Vec<Event<'p>>) -> Step {
        if self.buf.is_empty() {
            return Step::NeedMore;
        }
        // The lengths of the candidates (rule 1) that are complete; whether there is any
        // candidate, and any longer than what is buffered.
        // Rule 0: a constant whole frame at the head is settled as soon as its bytes are there.
        match self.constant_at(flushing) {
            Constant::Found(message, len) => {
                let mut bytes = self.spare_bytes.pop().unwrap_or_default();
                bytes.extend_from_slice(&self.buf[..len]);
                let offset = self.head;
                self.report_noise(out);
                self.consume(len);
                if !self.unasked_aside(&interp::constant_frame(message)) {
                    self.pair(message);
                    self.last_frame = None;
                }
                out.push(Event::Frame {
                    offset,
                    bytes,
                    frame: interp::constant_frame(message),
                });
                return Step::Progress;
            }
            Constant::Wait => return Step::NeedMore,
            Constant::None => {}
        }
        let mut lens = std::mem::take(&mut self.lens);
        lens.clear();
        let mut dirs = std::mem::take(&mut self.dirs);
        dirs.clear();
        let forms = self.p.framing.long.is_some() || self.p.framing.form.is_some();
        if self.p.framing.escaping.is_some() || forms {
            let found = if forms {
                self.long_lens(flushing, &mut lens, &mut dirs)
            } else {
                self.escaped_lens(flushing, &mut lens, &mut dirs)
            };
            return match found {
                Escaped::Try => self.try_lens(lens, dirs, out),
                Escaped::Drop => {
                    (self.lens, self.dirs) = (lens, dirs);
                    self.drop_byte(out);
                    Step::Progress
                }
                Escaped::NeedMore => {
                    (self.lens, self.dirs) = (lens, dirs);
                    Step::NeedMore
                }
            };
        }
        let mut candidates = std::mem::take(&mut self.candidates);
        self.find_candidates(&mut candidates);
        let (mut live, mut longer) = (false, false);
        for &i in &candidates {
            let s = &self.shapes[i];
            if !self.agrees(s) {
                continue;
            }
            live = true;
            let dir = match s.message.direction {
                Direction::Request => 1,
                Direction::Response => 2,
            };
            if s.variable {
                // Its lengths, as far as the buffered length or count field tells.
                match lens_of(self.p, self.p.message(s.message), &self.buf) {
                    Lens::Need => longer |= !flushing,
                    Lens::Are(all) => {
                        for l in all {
                            if l > self.buf.len() {
                                longer = true;
                            } else {
                                lens.push(l);
                                dirs.push(dir);
                            }
                        }
                    }
                }
            } else if s.len > self.buf.len() {
                longer = true;
            } else {
                lens.push(s.len);
                dirs.push(dir);
            }
        }
        self.candidates = candidates;
        if !live || (!flushing && longer) {
            self.lens = lens;
            self.dirs = dirs;
            if !live {
                self.drop_byte(out);
                return Step::Progress;
            }
            return Step::NeedMore;
        }
        self.try_lens(lens, dirs, out)
    }

    /// Rule 4: tries the complete candidate lengths `lens` (each with the directions in
    /// `dirs` that have it), longest first.
    fn try_lens(
        &mut self,
        mut lens: Vec<usize>,
        mut dirs: Vec<u8>,
        out: &mut Vec<Event<'p>>,
    ) -> Step {
        if lens.len() > 1 {
            // Longest first, each with the directions of every candidate that has it.
            let mut by_len: Vec<(usize, u8)> =
                lens.iter().copied().zip(dirs.iter().copied()).collect();
            by_len.sort_unstable_by_key(|&(l, _)| std::cmp::Reverse(l));
            lens.clear();
            dirs.clear();
            for (l, d) in by_len {
                match lens.last() {
                    Some(&last) if last == l => {
                        if let Some(m) = dirs.last_mut() {
                            *m |= d;
                        }
                    }
                    _ => {
                        lens.push(l);
                        dirs.push(d);
                    }
                }
            }
        }
        let mut out_of_spec: Option<(usize, DecodeError)> = None;
        let mut found = false;
        for (&len, &dir) in lens.iter().zip(&dirs) {
            match self.try_frame(len, dir, out) {
                Ok(()) => {
                    found = true;
                    break;
                }
                Err(Some(reason)) if out_of_spec.is_none() => out_of_spec = Some((len, reason)),
                Err(_) => {}
            }
        }
        self.lens = lens;
        self.dirs = dirs;
        if found {
            return Step::Progress;
        }
        if let Some((len, reason)) = out_of_spec {
            let (offset, mut bytes) = self.with_preamble();
            bytes.extend_from_slice(self.buf.get(..len).unwrap_or_default());
            let relaxed = self
                .relaxed
                .get_or_insert_with(|| Box::new(relaxed(self.p)));
            let frame = decode_lenient(self.p, relaxed, self.direction, None, &bytes)
                .ok()
                .map(|(frame, _)| frame.into_owned());
            self.last_request = None;
            self.report_noise(out);
            out.push(Event::OutOfSpec {
                offset,
                bytes,
                reason,
                frame,
            });
            self.consume_frame(len);
            return Step::Progress;
        }
        self.drop_byte(out);
        Step::Progress
    }

    /// The frame lengths at the head of the buffer of a protocol with escaping (see the
    /// module docs, "Escaped frames"), in `lens`: up to the first end byte after the start
    /// bytes (byte escaping, COBS), or as the length field of stuffed frames says.
    fn escaped_lens(&self, flushing: bool, lens: &mut Vec<usize>, dirs: &mut Vec<u8>) -> Escaped {
        if !self.p.framing.end_by_direction() {
            return self.escaped_lens_of(None, flushing, lens, dirs);
        }
        // Requests between their flags, responses (without start or end bytes) by their
        // length field: each direction's lengths by its own framing; a direction still
        // waiting for bytes makes the head wait, as the generated stream decoder's
        // candidates of both directions do (`rt::escaped_lens_by_direction`).
        let mut waiting = false;
        for d in [Direction::Request, Direction::Response] {
            if !self.looks_for(None, d) {
                continue;
            }
            let (mut l, mut k) = (Vec::new(), Vec::new());
            match self.escaped_lens_of(Some(d), flushing, &mut l, &mut k) {
                Escaped::Try => {
                    lens.extend(l);
                    dirs.extend(k);
                }
                Escaped::NeedMore => waiting = true,
                Escaped::Drop => {}
            }
        }
        if waiting {
            lens.clear();
            dirs.clear();
            return Escaped::NeedMore;
        }
        if lens.is_empty() {
            return Escaped::Drop;
        }
        Escaped::Try
    }

    /// Whether frames of direction `d` are looked for: the decoder's direction (both where it
    /// has none) and `only` (both: `None`) take it.
    fn looks_for(&self, only: Option<Direction>, d: Direction) -> bool {
        only.map_or(true, |o| o == d) && self.direction.map_or(true, |want| want == d)
    }

    /// [`Self::escaped_lens`] of the directions `only` names (both: `None`), by its framing
    /// (where they differ, [`crate::ir::Framing::end_by_direction`], one direction at a time).
    fn escaped_lens_of(
        &self,
        only: Option<Direction>,
        flushing: bool,
        lens: &mut Vec<usize>,
        dirs: &mut Vec<u8>,
    ) -> Escaped {
        let (p, buf) = (self.p, &self.buf);
        let f = &p.framing;
        let d0 = only.unwrap_or(Direction::Request);
        let wanted = |d: Direction| self.looks_for(only, d);
        let head = f.head(d0, 0);
        if let Some(at) = head.start {
            for (i, &b) in f.sync_of(d0).iter().enumerate() {
                if buf.get(at + i).is_some_and(|&x| x != b) {
                    return Escaped::Drop;
                }
            }
        }
        let complete = |len: usize| len <= buf.len();
        let wait = if flushing || buf.len() >= self.capacity {
            Escaped::Drop
        } else {
            Escaped::NeedMore
        };
        let insert = matches!(
            f.escaping.as_ref().map(|e| &e.kind),
            Some(crate::ir::EscapeKind::Insert { .. })
        );
        let lead = if f.layout_of(d0).first() == Some(&crate::ir::Part::Start) {
            f.sync_of(d0).len()
        } else {
            0
        };
        if !insert && f.end_of(d0).is_empty() {
            return self.escaped_lens_by_length(lead, only, flushing, lens, dirs);
        }
        if !insert {
            let len = match crate::escape::frame_end(f, d0, buf, lead) {
                None => return wait,
                Some(None) => return Escaped::Drop,
                Some(Some(len)) => len,
            };
            // Each direction whose frames can be as long unescaped (none where the escapes
            // are bad): the generated stream decoder's candidates (`rt::escaped_lens`).
            let Ok(plain) = crate::escape::unescape_bytes_of(f, d0, &buf[..len]) else {
                return Escaped::Drop;
            };
            let mut dir = 0;
            for (d, bit) in [(Direction::Request, 1), (Direction::Response, 2)] {
                let fits = p
                    .frame_len_bounds(d)
                    .is_some_and(|(lo, hi)| (lo..=hi).contains(&plain.len()));
                if fits && wanted(d) {
                    dir |= bit;
                }
            }
            if dir == 0 {
                return Escaped::Drop;
            }
            lens.push(len);
            dirs.push(dir);
            return Escaped::Try;
        }
        // Stuffed frames: the length field counts the stuffed bytes.
        let (Some(l), Some(at)) = (&f.length, head.length) else {
            return Escaped::Drop;
        };
        let Some(bytes) = buf.get(at..at + l.width) else {
            return wait;
        };
        let v = interp::read_uint(bytes, p.byte_order) as i64;
        for d in [Direction::Request, Direction::Response] {
            if self.direction.is_some_and(|want| want != d) {
                continue;
            }
            let Some(rule) = f.length_rule(d) else {
                continue;
            };
            let len = if rule.grows { v - rule.k } else { continue };
            let ok = usize::try_from(len)
                .ok()
                .filter(|&n| n >= rule.head_len && n <= self.capacity);
            if let Some(n) = ok {
                // Each length with the directions whose rule gives it (try_lens merges them).
                lens.push(n);
                dirs.push(match d {
                    Direction::Request => 1,
                    Direction::Response => 2,
                });
            }
        }
        if lens.is_empty() {
            return Escaped::Drop;
        }
        if lens.iter().any(|&n| !complete(n)) {
            if !flushing {
                lens.clear();
                dirs.clear();
                return Escaped::NeedMore;
            }
            let keep: Vec<(usize, u8)> = (lens.iter().copied().zip(dirs.iter().copied()))
                .filter(|&(n, _)| complete(n))
                .collect();
            lens.clear();
            dirs.clear();
            for (n, d) in keep {
                lens.push(n);
                dirs.push(d);
            }
            if lens.is_empty() {
                return Escaped::Drop;
            }
        }
        Escaped::Try
    }

    /// The frame lengths at the head of the buffer of a protocol whose start byte chooses its
    /// length field's width (`framing.length.long`; see the module docs, "Long length
    /// forms"), in `lens`: as the length field of the form the head byte starts says, on the
    /// wire.
    fn long_lens(&self, flushing: bool, lens: &mut Vec<usize>, dirs: &mut Vec<u8>) -> Escaped {
        let (p, buf) = (self.p, &self.buf);
        let wait = flushing || buf.len() >= self.capacity;
        let (v, extra) = match crate::long::wire_len(p, buf) {
            None => return Escaped::Drop,
            Some(None) if wait => return Escaped::Drop,
            Some(None) => return Escaped::NeedMore,
            Some(Some(found)) => found,
        };
        let mut longer = false;
        for (d, bit) in [(Direction::Request, 1u8), (Direction::Response, 2)] {
            if self.direction.is_some_and(|want| want != d) {
                continue;
            }
            let Some(rule) = p.framing.length_rule(d).filter(|r| r.grows) else {
                continue;
            };
            let fits = |n: usize| {
                n >= rule.head_len
                    && p.frame_len_bounds(d)
                        .is_some_and(|(lo, hi)| (lo..=hi).contains(&n))
            };
            // The length in the IR's layout, less the bytes the short form's field lacks.
            let Some(n) = usize::try_from(v - rule.k).ok().filter(|&n| fits(n)) else {
                continue;
            };
            let n = n - extra;
            if n > buf.len() {
                longer = true;
            } else {
                lens.push(n);
                dirs.push(bit);
            }
        }
        if longer && !wait {
            lens.clear();
            dirs.clear();
            return Escaped::NeedMore;
        }
        if lens.is_empty() {
            return Escaped::Drop;
        }
        Escaped::Try
    }

    /// [`Self::escaped_lens`] for byte escaping without an end byte (XBee API mode 2): the
    /// frame's length comes from its length field, read as the bytes after the start bytes
    /// unescape, and the frame runs on until that many bytes have unescaped.
    fn escaped_lens_by_length(
        &self,
        lead: usize,
        only: Option<Direction>,
        flushing: bool,
        lens: &mut Vec<usize>,
        dirs: &mut Vec<u8>,
    ) -> Escaped {
        let (p, buf) = (self.p, &self.buf);
        let f = &p.framing;
        let wait = if flushing || buf.len() >= self.capacity {
            Escaped::Drop
        } else {
            Escaped::NeedMore
        };
        let d0 = only.unwrap_or(Direction::Request);
        let (Some(l), Some(at)) = (&f.length, f.head(d0, 0).length) else {
            return Escaped::Drop;
        };
        // `ends[n]`: where the first `n` unescaped bytes end on the wire (from `lead` on);
        // `plain` the bytes.
        let mut plain: Vec<u8> = buf.get(..lead).unwrap_or_default().to_vec();
        let mut ends: Vec<usize> = (0..=plain.len()).collect();
        let mut i = lead;
        let need = |n: usize, plain: &mut Vec<u8>, ends: &mut Vec<usize>, i: &mut usize| {
            while plain.len() < n {
                match crate::escape::unescape_one(f, buf, *i) {
                    Some(Ok((b, next))) => {
                        plain.push(b);
                        ends.push(next);
                        *i = next;
                    }
                    Some(Err(())) => return Some(false),
                    None => return None,
                }
            }
            Some(true)
        };
        match need(at + l.width, &mut plain, &mut ends, &mut i) {
            Some(true) => {}
            Some(false) => return Escaped::Drop,
            None => return wait,
        }
        let v = interp::read_uint(&plain[at..at + l.width], p.byte_order) as i64;
        let mut waiting = false;
        for (d, bit) in [(Direction::Request, 1u8), (Direction::Response, 2)] {
            if !self.looks_for(only, d) {
                continue;
            }
            let Some(rule) = f.length_rule(d).filter(|r| r.grows) else {
                continue;
            };
            let fits = |n: usize| {
                p.frame_len_bounds(d)
                    .is_some_and(|(lo, hi)| (lo..=hi).contains(&n))
            };
            let n = usize::try_from(v - rule.k).ok();
            // No frame ends before its length field.
            let Some(n) = n.filter(|&n| fits(n) && n >= at + l.width) else {
                continue;
            };
            match need(n, &mut plain, &mut ends, &mut i) {
                Some(true) => {
                    lens.push(ends[n]);
                    dirs.push(bit);
                }
                Some(false) => {}
                None => waiting = true,
            }
        }
        if waiting && !matches!(wait, Escaped::Drop) {
            lens.clear();
            dirs.clear();
            return Escaped::NeedMore;
        }
        if lens.is_empty() {
            return Escaped::Drop;
        }
        Escaped::Try
    }

    /// Whether the buffer begins with a constant whole frame of a direction decoded, or is (not
    /// flushing) the start of one still incomplete.
    fn constant_at(&self, flushing: bool) -> Constant {
        let mut wait = false;
        for (r, f) in constants(self.p, self.direction) {
            if self.buf.starts_with(f) {
                return Constant::Found(r, f.len());
            }
            wait |= !flushing && f.starts_with(&self.buf);
        }
        if wait {
            Constant::Wait
        } else {
            Constant::None
        }
    }

    /// The shapes that can agree with the buffer (indices into `shapes`), in `out` (cleared
    /// first): those whose code agrees with the bytes buffered where it sits, and the codeless
    /// ones. [`Self::agrees`] decides.
    fn find_candidates(&self, out: &mut Vec<usize>) {
        out.clear();
        for g in &self.by_code {
            let bytes = self.buf.get(g.code_at..).unwrap_or_default();
            g.codes.agreeing(bytes, out);
        }
        if !self.codeless.is_empty() {
            out.extend_from_slice(&self.codeless);
        }
    }

    /// Whether the buffered bytes agree with a message so far, for a shape
    /// [`Self::find_candidates`] found (whose code agrees): its start bytes.
    fn agrees(&self, s: &Shape) -> bool {
        let buf = &self.buf;
        if let Some(at) = s.at.start {
            let sync = self.p.framing.sync_of(s.message.direction);
            for (i, &start) in sync.iter().enumerate() {
                if buf.get(at + i).is_some_and(|&b| b != start) {
                    return false;
                }
            }
        }
        true
    }

    /// If the first `len` buffered bytes are a frame, reports it (after the noise before it)
    /// and consumes them; otherwise `Err` with the reason if they break only a rule of the
    /// spec ([`breaks_spec`]), `Err(None)` if they are no frame at all.
    fn try_frame(
        &mut self,
        len: usize,
        dir: u8,
        out: &mut Vec<Event<'p>>,
    ) -> Result<(), Option<DecodeError>> {
        let Some(wire) = self.buf.get(..len) else {
            return Err(None);
        };
        let request = self.last_request.or(self.default_request);
        self.spare.values = self.spare_values.pop().unwrap_or_default();
        let lookup = match (&self.one_way, dir) {
            (Some([requests, _]), 1) => requests,
            (Some([_, responses]), 2) => responses,
            _ => &self.lookup,
        };
        // A default request has no bytes: a reply whose checksum takes in its request's
        // bytes is not checked against it.
        let covered = self.last_request.map(|_| &self.last_covered[..]);
        let mut decoded =
            lookup.decode_paired_reusing(self.p, request, covered, wire, &mut self.spare);
        if let (Ok(f), Some(q), Some(_)) = (&decoded, &self.last_frame, self.last_request) {
            if f.message.direction == Direction::Response && interp::answers(self.p, q, f).is_err()
            {
                decoded =
                    lookup.decode_paired_reusing(self.p, None, covered, wire, &mut self.spare);
            }
        }
        let values = std::mem::take(&mut self.spare.values);
        if values.capacity() > 0 {
            // Not taken: no frame decoded.
            self.spare_values.push(values);
        }
        let found = match decoded {
            Ok(frame) => Ok(frame),
            Err(DecodeError::Ambiguous { candidates }) => Err(candidates),
            Err(e) => return Err(Some(e).filter(breaks_spec)),
        };
        let mut bytes = self.spare_bytes.pop().unwrap_or_default();
        let offset = match self.preamble {
            Some((byte, _)) if self.preamble_len > 0 => {
                let n = std::mem::take(&mut self.preamble_len);
                bytes.extend(std::iter::repeat(byte).take(n));
                self.preamble_at
            }
            _ => self.head,
        };
        bytes.extend_from_slice(wire);
        self.report_noise(out);
        self.consume_frame(len);
        out.push(match found {
            Ok(frame) => {
                if !self.unasked_aside(&frame) {
                    self.pair(frame.message);
                    self.last_frame = self.last_request.map(|_| frame.clone());
                    if self.last_request.is_some() && self.over_request {
                        self.last_covered.clear();
                        let span = self.p.checksum_span(&bytes).unwrap_or(&[]);
                        self.last_covered.extend_from_slice(span);
                    }
                }
                Event::Frame {
                    offset,
                    bytes,
                    frame,
                }
            }
            Err(candidates) => {
                self.last_request = None;
                Event::Ambiguous {
                    offset,
                    bytes,
                    candidates,
                }
            }
        });
        Ok(())
    }

    /// Whether `frame` is a response sent unasked (`unasked: true`) that is not the reply to
    /// the request before it: it leaves the pairing as it was, that request still waiting for
    /// its reply.
    fn unasked_aside(&self, frame: &Frame<'p>) -> bool {
        let r = frame.message;
        if r.direction != Direction::Response || !self.p.message(r).unasked {
            return false;
        }
        let Some(q) = self.last_request else {
            return false;
        };
        match &self.last_frame {
            Some(request) => interp::answers(self.p, request, frame).is_err(),
            // A constant request frame: nothing of it for a reply to follow.
            None => !self.p.commands[q].gets(r.index),
        }
    }

    fn pair(&mut self, r: MessageRef) {
        self.last_request = match r.direction {
            Direction::Request => Some(r.index),
            Direction::Response => None,
        };
    }

    fn consume(&mut self, len: usize) {
        let n = len.min(self.buf.len());
        self.buf.drain(..n);
        self.head += n as u64;
    }

    /// Consumes a frame of `len` bytes that was reported, all but its closing flag where the
    /// framing shares flags: that byte may open the next frame too.
    fn consume_frame(&mut self, len: usize) {
        let keep = len > 1
            && self.shared_flag.is_some()
            && self.buf.get(len - 1) == self.shared_flag.as_ref();
        self.consume(len - usize::from(keep));
        self.held_flag = keep;
    }

    fn drop_byte(&mut self, out: &mut Vec<Event<'p>>) {
        let Some(&b) = self.buf.first() else {
            return;
        };
        if std::mem::take(&mut self.held_flag) {
            // The closing flag of the frame before, which opens no frame: reported with it.
            self.consume(1);
            return;
        }
        if let Some((byte, max)) = self.preamble {
            if b == byte {
                if self.preamble_len >= max {
                    // More in a row than a frame takes: the first of them is noise.
                    if self.noise.is_empty() {
                        self.noise_at = self.preamble_at;
                    }
                    self.noise.push(byte);
                    self.preamble_at += 1;
                    self.preamble_len -= 1;
                }
                if self.preamble_len == 0 {
                    self.preamble_at = self.head;
                }
                self.preamble_len += 1;
                self.consume(1);
                if self.noise.len() >= MAX_SKIPPED_RUN {
                    self.report_noise(out);
                }
                return;
            }
            self.release_preamble();
        }
        if self.noise.is_empty() {
            self.noise_at = self.head;
        }
        self.noise.push(b);
        self.consume(1);
        if self.noise.len() >= MAX_SKIPPED_RUN {
            self.report_noise(out);
        }
    }

    /// The offset of a frame at the head, and its event's bytes so far: the preamble bytes
    /// held before it, which it takes.
    fn with_preamble(&mut self) -> (u64, Vec<u8>) {
        let mut bytes = self.spare_bytes.pop().unwrap_or_default();
        match self.preamble {
            Some((byte, _)) if self.preamble_len > 0 => {
                bytes.extend(std::iter::repeat(byte).take(std::mem::take(&mut self.preamble_len)));
                (self.preamble_at, bytes)
            }
            _ => (self.head, bytes),
        }
    }

    /// The preamble bytes held, which open no frame: noise.
    fn release_preamble(&mut self) {
        if let Some((byte, _)) = self.preamble.filter(|_| self.preamble_len > 0) {
            if self.noise.is_empty() {
                self.noise_at = self.preamble_at;
            }
            let n = std::mem::take(&mut self.preamble_len);
            self.noise.extend(std::iter::repeat(byte).take(n));
        }
    }

    fn report_noise(&mut self, out: &mut Vec<Event<'p>>) {
        if !self.noise.is_empty() {
            out.push(Event::Skipped {
                offset: self.noise_at,
                bytes: std::mem::take(&mut self.noise),
            });
        }
    }
}

/// Whether `e` says a frame breaks a rule of the spec rather than its framing: a value outside
/// its range, an address outside the allowed ones, a broadcast the command does not accept.
/// The same errors as the runtime's `stream::breaks_spec`.
pub fn breaks_spec(e: &DecodeError) -> bool {
    matches!(
        e,
        DecodeError::OutOfRange { .. }
            | DecodeError::BadAddress { .. }
            | DecodeError::BroadcastNotAccepted { .. }
    )
}

/// `p` with the rules strict decoding enforces beyond the framing lifted: no field or
/// sub-field has a `range`, every address is a device address, and there is no broadcast
/// address (so no command refuses it). For [`decode_lenient`]; make it once per spec.
pub fn relaxed(p: &Protocol) -> Protocol {
    let mut r = p.clone();
    for m in r.commands.iter_mut().chain(r.responses.iter_mut()) {
        for f in &mut m.fields {
            f.range = None;
            for b in &mut f.bits {
                b.range = None;
            }
            for g in &mut f.record {
                g.range = None;
            }
        }
    }
    let a = &mut r.framing.address;
    a.min = u8::MIN;
    a.max = u8::MAX;
    a.broadcast = None;
    a.host = None;
    r
}

/// Decodes a frame as [`interp::decode`] does with the spec's ranges, address limits and
/// broadcast rules lifted (`relaxed` is [`relaxed`]`(p)`), and lists every rule of `p` the
/// frame breaks, in the order strict decoding checks them (address, broadcast, then fields in
/// frame order): so the first is the error strict decoding gives, and the list is empty for a
/// frame strict decoding accepts. Framing, codes, lengths, constants and repeated fields are
/// checked as ever: their errors are returned.
pub fn decode_lenient<'r>(
    p: &Protocol,
    relaxed: &'r Protocol,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    wire: &[u8],
) -> Result<(Frame<'r>, Vec<DecodeError>), DecodeError> {
    let frame = interp::decode(relaxed, direction, reply_to, wire)?;
    // Offsets as the frame travelled (a short form's or a long length form's short frame).
    let violations = violations(p, &frame)
        .into_iter()
        .map(|e| crate::long::locate_on(p, wire, e))
        .collect();
    Ok((frame, violations))
}

/// Every rule of `p` that `frame` (decoded with the rules lifted) breaks, as the errors strict
/// decoding gives, in the order it checks them.
pub fn violations(p: &Protocol, frame: &Frame) -> Vec<DecodeError> {
    let m = p.message(frame.message);
    let at = m.layout;
    let a = &p.framing.address;
    let mut out = Vec::new();
    if !interp::address_allowed(p, frame.address) {
        out.push(DecodeError::BadAddress {
            offset: at.address.unwrap_or(0),
            found: frame.address,
            min: a.min,
            max: a.max,
        });
    }
    if interp::broadcast_refused(p, m, frame.address) {
        out.push(DecodeError::BroadcastNotAccepted {
            message: m.name.clone(),
            code: m.code.clone(),
            address: frame.address,
        });
    }
    // A field sits further than its offset by the bytes of the lists before it.
    let mut shift = 0usize;
    for f in &m.fields {
        let offset = f.frame_at(&at) + shift;
        // A record whose last field's bytes a field gives: as wide as the frame says.
        let f = &*interp::record_sized(m, f, |name| match frame.get(name) {
            Some(Raw::Int(v)) => Some(*v),
            _ => None,
        });
        if let (Some(_), Some(n)) = (&f.repeat, frame.get(&f.name).and_then(Raw::elements)) {
            shift += f.elements_len(n);
        }
        // Every record's fields in order, each outside its range where strict decoding
        // stops: the first such is the error strict decoding gives.
        if let Some(Raw::Records(recs)) = frame.get(&f.name) {
            for (k, rec) in recs.iter().enumerate() {
                for (j, (g, &v)) in f.record.iter().zip(rec).enumerate() {
                    if let Some((min, max)) = interp::range_violation(g, None, v) {
                        out.push(DecodeError::OutOfRange {
                            message: m.name.clone(),
                            field: f.record_field_name(j),
                            offset: offset + k * f.width + g.offset,
                            found: v,
                            min,
                            max,
                            kind: crate::number::NumKind::Int,
                        });
                    }
                }
            }
            continue;
        }
        let leaves: Vec<(&str, Option<&crate::ir::BitField>)> = if f.bits.is_empty() {
            vec![(f.name.as_str(), None)]
        } else {
            f.bits.iter().map(|b| (b.name.as_str(), Some(b))).collect()
        };
        for (name, bits) in leaves {
            let values: &[i64] = match frame.get(name) {
                Some(Raw::Int(v)) => std::slice::from_ref(v),
                Some(Raw::List(l)) => l,
                _ => continue,
            };
            // The first element of a repeated field outside its range, at its own offset, as
            // strict decoding says.
            let Some((k, v, (min, max))) = values
                .iter()
                .enumerate()
                .find_map(|(k, v)| interp::range_violation(f, bits, *v).map(|r| (k, v, r)))
            else {
                continue;
            };
            let step = if f.repeat.is_some() && f.ty != crate::ir::FieldType::Bit {
                f.width
            } else {
                0
            };
            // A packed element sits in the byte where its first bit does.
            let step_bits = f.packed.map_or(8 * step, |pk| pk.bits as usize);
            out.push(DecodeError::OutOfRange {
                message: m.name.clone(),
                field: name.to_owned(),
                offset: offset + k * step_bits / 8,
                found: *v,
                min,
                max,
                kind: if bits.is_some() {
                    crate::number::NumKind::Int
                } else {
                    f.num_kind()
                },
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Example;
    use crate::load_str;

    fn ub2() -> Protocol {
        load_str("ub2.yaml", include_str!("../../spec/ub2.yaml")).unwrap_or_else(|d| panic!("{d}"))
    }

    fn sd() -> Protocol {
        load_str("sd.yaml", include_str!("../../spec/sd.yaml")).unwrap_or_else(|d| panic!("{d}"))
    }

    fn run<'p>(p: &'p Protocol, chunks: &[&[u8]]) -> Vec<Event<'p>> {
        let mut d = StreamDecoder::new(p, None);
        let mut events = Vec::new();
        for c in chunks {
            events.extend(d.push(c));
            assert!(d.buf.len() <= d.capacity(), "buffer over capacity");
        }
        events.extend(d.flush());
        events
    }

    /// Every example frame that decodes without its request, in spec order, with noise
    /// between some of them, and what the decoder should report.
    fn capture(p: &Protocol, noise: &[&[u8]]) -> (Vec<u8>, Vec<(u64, String)>) {
        let mut bytes = Vec::new();
        let mut expected = Vec::new();
        let usable: Vec<&Example> = p
            .examples
            .iter()
            .filter(|e| !p.message(e.message).needs_request)
            .collect();
        for (i, e) in usable.iter().enumerate() {
            if let Some(n) = noise.get(i % (noise.len() + 3)) {
                expected.push((bytes.len() as u64, format!("skip {}", n.len())));
                bytes.extend_from_slice(n);
            }
            expected.push((bytes.len() as u64, p.message(e.message).name.clone()));
            bytes.extend_from_slice(&e.wire);
        }
        (bytes, expected)
    }

    fn summary(p: &Protocol, events: &[Event]) -> Vec<(u64, String)> {
        events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                Event::Skipped { offset, bytes } => (*offset, format!("skip {}", bytes.len())),
                Event::OutOfSpec { offset, frame, .. } => (
                    *offset,
                    format!(
                        "out of spec {}",
                        frame
                            .as_ref()
                            .map_or("?", |f| p.message(f.message).name.as_str())
                    ),
                ),
                Event::Ambiguous {
                    offset, candidates, ..
                } => (*offset, format!("ambiguous {}", candidates.join("|"))),
            })
            .collect()
    }

    #[test]
    fn ub2_examples_with_noise_frame_exactly() {
        let p = ub2();
        let (bytes, expected) = capture(&p, &[&[0x00], &[0xFF, 0x13, 0x55], &[0xAA]]);
        let events = run(&p, &[&bytes]);
        assert_eq!(summary(&p, &events), expected);
        // Every byte is accounted for exactly once, in order.
        let mut at = 0u64;
        for e in &events {
            assert_eq!(e.offset(), at);
            at += e.bytes().len() as u64;
        }
        assert_eq!(at, bytes.len() as u64);
    }

    #[test]
    fn sd_examples_with_noise_frame_exactly() {
        let p = sd();
        let (bytes, expected) = capture(&p, &[&[0x00], &[0xFF, 0xEE], &[0x01, 0x02, 0x03]]);
        assert_eq!(summary(&p, &run(&p, &[&bytes])), expected);
    }

    #[test]
    fn every_cut_into_two_chunks_gives_the_same_events() {
        for p in [ub2(), sd()] {
            let (bytes, _) = capture(&p, &[&[0x00, 0xAA], &[0xFF]]);
            let bytes = &bytes[..bytes.len().min(400)];
            let whole = run(&p, &[bytes]);
            for cut in 0..=bytes.len() {
                let (a, b) = bytes.split_at(cut);
                assert_eq!(run(&p, &[a, b]), whole, "{}: cut at {cut}", p.name);
            }
            let singles: Vec<&[u8]> = bytes.chunks(1).collect();
            assert_eq!(run(&p, &singles), whole, "{}: byte by byte", p.name);
        }
    }

    #[test]
    fn setter_request_and_its_echo_share_a_code() {
        let p = ub2();
        // set_acceleration_speed_index for 0x21 with acceleration index 0x0E, the ACK's own
        // checksum: the longest-first rule still reads the request, then its ACK.
        let req = interp::parse_hex("AA21 4300 0E05 ").unwrap();
        let mut req = req;
        let sum = req.iter().fold(0u8, |a, b| a.wrapping_add(*b));
        req.push(sum);
        let ack = interp::parse_hex("AA21 4300 0E").unwrap();
        let mut bytes = req.clone();
        bytes.extend_from_slice(&ack);
        bytes.extend_from_slice(&interp::parse_hex("AA21 1000 DB").unwrap());
        let events = run(&p, &[&bytes]);
        assert_eq!(
            summary(&p, &events),
            vec![
                (0, "set_acceleration_speed_index".to_owned()),
                (7, "set_acceleration_speed_index_ack".to_owned()),
                (12, "reference_run".to_owned()),
            ]
        );
        // An ACK at the very end settles on flush, not before.
        let mut d = StreamDecoder::new(&p, None);
        assert!(d.push(&ack).is_empty());
        assert_eq!(
            summary(&p, &d.flush()),
            vec![(0, "set_acceleration_speed_index_ack".to_owned())]
        );
    }

    #[test]
    fn ambiguous_responses_pair_with_the_request_before_them() {
        let p = sd();
        let example = |name: &str| {
            p.examples
                .iter()
                .find(|e| p.message(e.message).name == name)
                .unwrap_or_else(|| panic!("no example of {name}"))
                .wire
                .clone()
        };
        let reply = example("total_runtime_min_sec");
        let mut bytes = example("read_total_runtime_min_sec");
        bytes.extend_from_slice(&reply);
        // The same reply again, with no request before it: ambiguous.
        bytes.extend_from_slice(&reply);
        let events = run(&p, &[&bytes]);
        assert_eq!(
            summary(&p, &events),
            vec![
                (0, "read_total_runtime_min_sec".to_owned()),
                (6, "total_runtime_min_sec".to_owned()),
                (
                    12,
                    "ambiguous total_runtime_hours|total_runtime_min_sec".to_owned()
                ),
            ]
        );
        // A default request settles replies of a device-side capture.
        let hours = p
            .commands
            .iter()
            .position(|c| c.name == "read_total_runtime_hours");
        let mut d = StreamDecoder::new(&p, Some(Direction::Response)).with_default_request(hours);
        let mut events = d.push(&reply);
        events.extend(d.flush());
        assert_eq!(
            summary(&p, &events),
            vec![(0, "total_runtime_hours".to_owned())]
        );
    }

    #[test]
    fn long_noise_is_reported_in_bounded_runs_and_never_panics() {
        let p = ub2();
        let noise = vec![0x55u8; MAX_SKIPPED_RUN * 2 + 7];
        let events = run(&p, &[&noise]);
        let lens: Vec<usize> = events.iter().map(|e| e.bytes().len()).collect();
        assert_eq!(lens, vec![MAX_SKIPPED_RUN, MAX_SKIPPED_RUN, 7]);
        // Arbitrary bytes, including truncated frames and lone start bytes.
        let mut x: u32 = 12345;
        let junk: Vec<u8> = (0..5000)
            .map(|_| {
                x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                if x % 7 == 0 {
                    0xAA
                } else {
                    (x >> 16) as u8
                }
            })
            .collect();
        for p in [ub2(), sd()] {
            let events = run(&p, &[&junk]);
            let total: usize = events.iter().map(|e| e.bytes().len()).sum();
            assert_eq!(total, junk.len());
        }
    }

    #[test]
    fn out_of_spec_frames_are_reported_with_reason_and_values() {
        let p = sd();
        // Set point to 0x20 (outside 0x01..=0x1E), then a valid set point, then a serial-number
        // character with string length 75 (0x00..=0x20), cut into two chunks mid-frame.
        let bytes =
            interp::parse_hex("76 20 00 00 BA B0 76 05 32 00 14 74 10 01 4B 4B FB 8A").unwrap();
        let events = run(&p, &[&bytes[..8], &bytes[8..]]);
        assert_eq!(
            summary(&p, &events),
            vec![
                (0, "out of spec set_point".to_owned()),
                (6, "set_point".to_owned()),
                (
                    12,
                    "out of spec electronic_serial_number_character".to_owned()
                ),
            ]
        );
        let Event::OutOfSpec { reason, frame, .. } = &events[0] else {
            panic!("{events:?}");
        };
        assert!(matches!(
            reason,
            DecodeError::BadAddress { found: 0x20, .. }
        ));
        assert_eq!(frame.as_ref().map(|f| f.address), Some(0x20));
        let Event::OutOfSpec { reason, frame, .. } = &events[2] else {
            panic!("{events:?}");
        };
        assert!(
            matches!(reason, DecodeError::OutOfRange { field, found: 75, min: 0, max: 32, .. } if field == "string_length"),
            "{reason}"
        );
        assert_eq!(
            frame.as_ref().and_then(|f| f.get("string_length")),
            Some(&Raw::Int(75))
        );
    }

    #[test]
    fn lenient_decoding_lists_every_broken_rule_in_strict_order() {
        let p = sd();
        let lifted = relaxed(&p);
        let read = p
            .commands
            .iter()
            .position(|c| c.name == "read_electronic_serial_number")
            .unwrap();
        let r = MessageRef {
            direction: Direction::Request,
            index: read,
        };
        let values = [interp::Value {
            name: "byte_number".into(),
            raw: Raw::Int(37),
        }];
        // Strict encoding refuses both the address and the value; lifted, it writes the frame.
        assert!(interp::encode(&p, r, 0x20, &values).is_err());
        let wire = interp::encode(&lifted, r, 0x20, &values).unwrap();
        let strict = interp::decode(&p, None, None, &wire).unwrap_err();
        let (frame, violations) = decode_lenient(&p, &lifted, None, None, &wire).unwrap();
        assert_eq!(frame.message, r);
        assert_eq!(violations.first(), Some(&strict));
        assert!(matches!(
            violations[..],
            [
                DecodeError::BadAddress { found: 0x20, .. },
                DecodeError::OutOfRange { found: 37, .. }
            ]
        ));
        // A frame strict decoding accepts breaks nothing; one that does not checksum is refused.
        let good = interp::encode(
            &p,
            r,
            0x05,
            &[interp::Value {
                name: "byte_number".into(),
                raw: Raw::Int(3),
            }],
        )
        .unwrap();
        assert_eq!(
            decode_lenient(&p, &lifted, None, None, &good).unwrap().1,
            vec![]
        );
        let mut bad = wire.clone();
        bad[5] ^= 1;
        assert!(matches!(
            decode_lenient(&p, &lifted, None, None, &bad),
            Err(DecodeError::ChecksumMismatch { .. })
        ));
    }

    #[test]
    fn code_trie_finds_exactly_the_codes_that_agree() {
        // Codes of one and two bytes, one a prefix of others, as UB2 and Modbus have them.
        let codes: [&[u8]; 5] = [
            &[0x40],
            &[0x40, 0x72],
            &[0x40, 0x73],
            &[0x41, 0x72],
            &[0x07],
        ];
        let mut root = CodeNode::default();
        for (i, c) in codes.iter().enumerate() {
            root.insert(c, i);
        }
        // What `agrees` says of each code, for buffers cut anywhere.
        let agrees = |bytes: &[u8], code: &[u8]| code.iter().zip(bytes).all(|(c, b)| c == b);
        for bytes in [
            &[][..],
            &[0x40],
            &[0x40, 0x72],
            &[0x40, 0x72, 0x00],
            &[0x40, 0x00],
            &[0x41],
            &[0x41, 0x73],
            &[0x07, 0x40],
            &[0x99, 0x40],
        ] {
            let mut found = Vec::new();
            root.agreeing(bytes, &mut found);
            found.sort_unstable();
            let want: Vec<usize> = (0..codes.len())
                .filter(|&i| agrees(bytes, codes[i]))
                .collect();
            assert_eq!(found, want, "bytes {bytes:02X?}");
        }
    }

    #[test]
    fn truncated_frame_then_good_frame_resynchronises() {
        let p = ub2();
        // go_to_capacitance cut after 5 bytes, then a whole reference_run.
        let mut bytes = interp::parse_hex("AA21 2000 00").unwrap();
        bytes.extend_from_slice(&interp::parse_hex("AA21 1000 DB").unwrap());
        let events = run(&p, &[&bytes]);
        assert_eq!(
            summary(&p, &events),
            vec![(0, "skip 5".to_owned()), (5, "reference_run".to_owned())]
        );
    }

    /// Events given back with `recycle` lend their memory to the next ones and change nothing
    /// the decoder reports: the same events as without, over every example (lists and text
    /// included) with noise, out-of-spec and ambiguous frames, however the capture is cut.
    #[test]
    fn recycled_events_change_nothing() {
        let specs = [
            ("ub2.yaml", include_str!("../../spec/ub2.yaml")),
            ("sd.yaml", include_str!("../../spec/sd.yaml")),
            ("modbus.yaml", include_str!("../../spec/modbus.yaml")),
            ("dynamixel.yaml", include_str!("../../spec/dynamixel.yaml")),
        ];
        for (name, text) in specs {
            let p = load_str(name, text).unwrap_or_else(|d| panic!("{d}"));
            let mut bytes = Vec::new();
            for (i, e) in p.examples.iter().enumerate() {
                bytes.extend_from_slice(&e.wire);
                if i % 3 == 0 {
                    bytes.extend_from_slice(&[0x00, 0xFF, 0x13]);
                }
            }
            // Every frame again with a byte changed, for out-of-spec and broken frames.
            for (i, e) in p.examples.iter().enumerate() {
                let mut wire = e.wire.clone();
                let at = i % wire.len();
                wire[at] = wire[at].wrapping_add(1);
                bytes.extend_from_slice(&wire);
            }
            for cut in [1, 5, 64, bytes.len()] {
                let mut plain = StreamDecoder::new(&p, None);
                let mut expected = Vec::new();
                let mut reused = StreamDecoder::new(&p, None);
                let (mut got, mut events) = (Vec::new(), Vec::new());
                for chunk in bytes.chunks(cut) {
                    expected.extend(plain.push(chunk));
                    reused.recycle(&mut events);
                    assert!(events.is_empty());
                    reused.push_into(chunk, &mut events);
                    got.extend(events.iter().cloned());
                }
                expected.extend(plain.flush());
                got.extend(reused.flush());
                assert!(expected.len() > p.examples.len(), "{name}: too few events");
                assert_eq!(got, expected, "{name}, pieces of {cut}");
                reused.recycle(&mut events);
                assert!(
                    !reused.spare_bytes.is_empty() && !reused.spare_values.is_empty(),
                    "{name}: nothing was given back"
                );
            }
        }
    }
}
