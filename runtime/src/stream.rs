//! The streaming decoder: bytes of a bus in chunks of any size, frames out. `no_std`, no
//! allocation, sans-IO.
//!
//! Each protocol module has its own `StreamDecoder` (this type with the protocol's codec and a
//! buffer of exactly its longest frame) and `Event`. Feed bytes with [`StreamDecoder::push`]
//! (it takes what fits and says how many) and take events with [`StreamDecoder::poll`] until it
//! returns `None`; at the end of a capture, or when the line has gone idle for longer than a
//! frame takes, call [`StreamDecoder::finish`] until it returns `None`.
//! [`StreamDecoder::feed`] wraps that loop in an iterator.
//!
//! # The framing rule
//!
//! The decoder looks at the earliest byte not yet accounted for and asks which messages could
//! start there (their *candidates*, [`Framing::candidates`](crate::Framing::candidates)): those whose start byte and code
//! agree with every byte buffered so far. The address is not part of it: a frame from an
//! address the spec does not allow is still a frame on the wire, and a sniffer must see it.
//! No candidate: the byte is noise; it is dropped and the next one tried, and consecutive
//! dropped bytes are reported as one [`Event::Skipped`] (split every [`MAX_SKIPPED_RUN`]
//! bytes). A candidate's length is fixed by its message (one of
//! [`Framing::FRAME_LENGTHS`](crate::Framing::FRAME_LENGTHS)) or, for a variable-length message, given by its length or count
//! field once that is buffered ([`Framing::variable_candidates`](crate::Framing::variable_candidates)), or where end bytes alone delimit
//! the frame (no length field, no checksum) up to their first appearance from its list's
//! first byte ([`CountBy::Delimited`](crate::codec::CountBy::Delimited)); a field that gives a length
//! no frame of the message can have makes it no candidate, so a length that lies drops one
//! byte and the decoder resynchronises. While a candidate is longer than what is buffered, or
//! its length or count field has not arrived, the decoder waits. Then every complete candidate
//! length is tried, **longest first**; the first that checksums and decodes
//! strictly (ranges, address and broadcast rules included) is the frame. If none does, the
//! longest that checksums and fails *only* a rule of the spec (its error is one that
//! [`breaks_spec`] names: a value out of its range, an address outside the allowed ones, a
//! broadcast the command does not accept) is an [`Event::OutOfSpec`]: reported at its offset
//! with the reason, its bytes consumed, so resynchronisation never steps into it. A frame that
//! checksums is never noise, and never a valid frame unless it is one. Noise whose checksum
//! passes by chance with a start byte and code that fit can be reported as out of spec,
//! exactly as it could before be reported as a frame. This is the rule of busspec's
//! interpreter stream decoder (`busspec_model::stream`), whose module documentation gives the
//! reasons and the limits; the two are tested against each other.
//!
//! A response only its request can identify (SD 0x22..0x28, 0x38) is decoded as the answer to
//! the last request seen since the previous response (a response sent unasked that is not
//! that request's reply leaves it waiting), or else to the default request
//! ([`StreamDecoder::with_default_request`]); failing both it is an [`Event::Ambiguous`].
//! Pairing says which response a frame is, never whether it is one: a frame that decodes as a
//! request and as a response (a Modbus echo) is an [`Event::Ambiguous`] whatever request came
//! before it (it may be the master's next request or retry), as in the interpreter's.
//!
//! Where one flag byte opens and closes every frame and a sender may share it between two
//! ([`Framing::SHARED_FLAG`](crate::Framing::SHARED_FLAG): HDLC, KISS), a frame's closing flag
//! stays at the head as the next frame's possible opening one: the two events then share that
//! byte, and a flag that opens nothing is dropped without being noise.
//!
//! Where wake-up bytes come before a frame ([`Framing::PREAMBLE`](crate::Framing::PREAMBLE):
//! DL/T 645's `FE FE FE FE`), a run of the preamble byte is held rather than reported as noise:
//! the frame that follows it takes the last `max` of them into its event (its offset at the
//! first of them), and those that open no frame are noise after all (a byte that is neither a
//! frame nor the preamble byte follows them, more than `max` come in a row, or the capture
//! ends).
//!
//! Decisions depend only on the bytes, never on how they were cut into chunks, as long as
//! `finish` is called only at the end.

use crate::{DecodeError, Decoded, FrameBuffer, Protocol, RequestMessage, ResponseMessage};

/// Consecutive noise bytes beyond this many are reported in more than one [`Event::Skipped`].
pub const MAX_SKIPPED_RUN: u64 = 256;

/// Which way a frame travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Direction {
    /// Master to device.
    Request,
    /// Device to master.
    Response,
}

/// The messages that could start at the head of the buffer, as sets of frame lengths: bit `i`
/// stands for [`Framing::FRAME_LENGTHS`](crate::Framing::FRAME_LENGTHS)`[i]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Candidates {
    pub requests: u64,
    pub responses: u64,
}

/// The frames that could start at the head of a whole window, where the start byte and code
/// fix at most two of them (one length of each direction, or two lengths of one):
/// [`Framing::candidate`](crate::Framing::candidate), a faster route to the decision [`Framing::candidates`](crate::Framing::candidates) gives (the
/// stream decoder's fast path asks it first, and the candidates only where it says
/// [`Candidate::MANY`]).
///
/// Two bytes, the longer frame in the low one: each 0 for none, else the frame's length
/// (below 127) with bit 7 set for a response. `0xFFFF`: not fixed, ask the candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Candidate(pub u16);

impl Candidate {
    /// No message agrees with the head: its byte is noise.
    pub const NONE: Candidate = Candidate(0);
    /// Not fixed by the head's start byte and code (more than two frames, a length of both
    /// directions, or a head too short): [`Framing::candidates`](crate::Framing::candidates) says which.
    pub const MANY: Candidate = Candidate(0xFFFF);

    /// From a [`Candidates`] mask over `lengths` (the protocol's [`Framing::FRAME_LENGTHS`](crate::Framing::FRAME_LENGTHS),
    /// longest first): what the generated tables hold, computed when they are generated.
    pub fn of(c: Candidates, lengths: &[usize]) -> Candidate {
        let mut slots = 0u16;
        let mut n = 0;
        for (i, &len) in lengths.iter().enumerate().take(64) {
            let (q, r) = (c.requests >> i & 1 != 0, c.responses >> i & 1 != 0);
            if q && r || (q || r) && (n == 2 || len == 0 || len >= 127) {
                return Candidate::MANY;
            }
            if q || r {
                slots |= u16::from(len as u8 | if r { 0x80 } else { 0 }) << (8 * n);
                n += 1;
            }
        }
        Candidate(slots)
    }
}

/// The length of a variable-length frame (one whose length a length field or a repeated
/// field's count gives, so [`Framing::FRAME_LENGTHS`](crate::Framing::FRAME_LENGTHS) does not list it) that could start at
/// the head of the buffer, for one direction: see [`Framing::variable_candidates`](crate::Framing::variable_candidates).
///
/// A `u32` with two reserved values rather than an `Option<Option<usize>>`: it costs one
/// register, and [`VarLens::NONE`] is one compare against zero on the decoder's path for
/// protocols without variable frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct VarLen(u32);

impl VarLen {
    /// No variable-length candidate: no such message agrees with the head, or its length or
    /// count field says a length no frame of it can have (the `Some(0)` of
    /// [`crate::codec::RepeatAt::frame_len`] and [`LengthField::frame_len`]).
    pub const NONE: VarLen = VarLen(0);
    /// A variable-length message agrees with the head but its length or count field has not
    /// been buffered yet: the decoder waits for more bytes (unless it is settling what is
    /// buffered, when the candidate counts for nothing).
    pub const NEED_MORE: VarLen = VarLen(u32::MAX);

    /// A frame of `len` bytes (0: [`Self::NONE`]). A length the decoder's buffer cannot hold
    /// (beyond [`Protocol::MAX_FRAME_LEN`]) is never complete, so it never becomes a frame: the
    /// head byte is then dropped as noise once the buffer is full or settled.
    #[inline]
    pub const fn len(len: usize) -> VarLen {
        if len >= u32::MAX as usize {
            VarLen(u32::MAX - 1)
        } else {
            VarLen(len as u32)
        }
    }

    /// From the answer of [`crate::codec::RepeatAt::frame_len`] or [`LengthField::frame_len`]:
    /// `None` (the field not yet buffered) is [`Self::NEED_MORE`], `Some(0)` (a length no
    /// frame of the message has) is [`Self::NONE`], `Some(n)` a frame of `n` bytes.
    #[inline]
    pub const fn of(frame_len: Option<usize>) -> VarLen {
        match frame_len {
            Some(n) => VarLen::len(n),
            None => VarLen::NEED_MORE,
        }
    }

    /// The candidate's length, once known (`None` for [`Self::NONE`] and [`Self::NEED_MORE`]).
    #[inline]
    pub const fn get(self) -> Option<usize> {
        match self.0 {
            0 | u32::MAX => None,
            n => Some(n as usize),
        }
    }

    /// Whether the decoder must wait for the candidate's length or count field.
    #[inline]
    pub const fn needs_more(self) -> bool {
        self.0 == u32::MAX
    }

    /// Whether there is no variable-length candidate.
    #[inline]
    pub const fn is_none(self) -> bool {
        self.0 == 0
    }
}

/// The variable-length candidates at the head of the buffer: at most one per direction
/// ([`Framing::variable_candidates`](crate::Framing::variable_candidates)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct VarLens {
    pub requests: VarLen,
    pub responses: VarLen,
}

impl VarLens {
    /// Neither direction has one: what every protocol without variable-length frames says.
    pub const NONE: VarLens = VarLens {
        requests: VarLen::NONE,
        responses: VarLen::NONE,
    };
}

/// A frame's length field, as the stream decoder reads it from the bytes buffered from a
/// possible frame start: where it sits and what a frame's length is from its value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LengthField {
    /// Its offset in the frame.
    pub at: usize,
    /// Its width, bytes (1 or 2).
    pub width: usize,
    /// Least significant byte first.
    pub le: bool,
    /// The frame's length less the field's value: the bytes the field does not count, less
    /// its adjustment (may be negative).
    pub excess: isize,
    /// The shortest and longest frame the messages that agree with the head can have.
    pub min: usize,
    pub max: usize,
}

impl LengthField {
    /// The length of the frame that starts `head`, once its length field has arrived (`None`
    /// before); a value that gives a length outside `min..=max` gives `Some(0)`, which no frame
    /// has: the stream decoder then drops a byte and resynchronises. Feed it to [`VarLen::of`].
    #[inline]
    pub fn frame_len(&self, head: &[u8]) -> Option<usize> {
        let b = head.get(self.at..self.at.checked_add(self.width)?)?;
        let len = isize::try_from(crate::codec::uint(b, self.le))
            .ok()
            .and_then(|v| v.checked_add(self.excess))
            .and_then(|l| usize::try_from(l).ok())
            .filter(|l| (self.min..=self.max).contains(l));
        Some(len.unwrap_or(0))
    }
}

/// What the decoder found. Offsets count bytes from the first byte ever pushed.
///
/// `repr(u8)`: every variant then has its offset and length at the same place, so
/// [`Event::offset`] and [`Event::len`] are one load each rather than a jump on the variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Event<Q, R> {
    /// A request frame of `len` bytes at `offset`.
    Request {
        offset: u64,
        len: usize,
        frame: Decoded<Q>,
    },
    /// A response frame of `len` bytes at `offset`.
    Response {
        offset: u64,
        len: usize,
        frame: Decoded<R>,
    },
    /// A frame that checksums and decodes as more than one message, and no request settles it.
    Ambiguous { offset: u64, len: usize, code: u32 },
    /// `len` bytes at `offset` that start no frame.
    Skipped { offset: u64, len: u64 },
    /// A frame of `len` bytes at `offset` whose start byte, code, length and checksum fit, but
    /// that breaks a rule of the spec: `reason` is the strict decoder's error, one that
    /// [`breaks_spec`] names (where the frame could be either, the one that got further,
    /// [`DecodeError::progress`], the request's on a tie). Its bytes are
    /// consumed; it ends request pairing as an ambiguous frame does.
    OutOfSpec {
        offset: u64,
        len: usize,
        reason: DecodeError,
    },
}

/// The next candidate length of the framing rule's walk, longest first: the fixed ones left in
/// `rest` (bit i for [`Framing::FRAME_LENGTHS`](crate::Framing::FRAME_LENGTHS)`[i]`) and the variable ones `lq` and `lr` (0
/// for none), each length once with every direction that has it (`(length, as a request, as a
/// response)`), taken out of the walk; `None` when none is left. The one walk of
/// `Core::advance` and the fast path.
#[inline(always)]
fn next_length<C: Protocol>(
    rest: &mut u64,
    lq: &mut usize,
    lr: &mut usize,
    requests: u64,
    responses: u64,
) -> Option<(usize, bool, bool)> {
    let i = rest.trailing_zeros() as usize;
    let fixed = C::FRAME_LENGTHS.get(i).copied().unwrap_or(0);
    let len = fixed.max(*lq).max(*lr);
    if len == 0 {
        return None;
    }
    let bit = if fixed == len { 1u64 << i } else { 0 };
    *rest &= !bit;
    let request = requests & bit != 0 || *lq == len;
    let response = responses & bit != 0 || *lr == len;
    if *lq == len {
        *lq = 0;
    }
    if *lr == len {
        *lr = 0;
    }
    Some((len, request, response))
}

/// The code of an [`Event::Ambiguous`] frame that decodes as a request and as a response: its
/// bytes folded into a `u32` (each shifting the ones before it left by 8), which leaves its last
/// four bytes, most significant first.
#[inline(always)]
fn both_ways_code(frame: &[u8]) -> u32 {
    frame
        .get(frame.len().saturating_sub(4)..)
        .unwrap_or_default()
        .iter()
        .fold(0u32, |a, b| a << 8 | u32::from(*b))
}

/// Whether `e` says a frame breaks a rule of the spec rather than its framing: a value outside
/// its range, an address outside the allowed ones, a broadcast the command does not accept.
/// A frame whose strict decoding fails with such an error (and whose checksum passed) is an
/// [`Event::OutOfSpec`] in a stream.
pub fn breaks_spec(e: &DecodeError) -> bool {
    matches!(
        e,
        DecodeError::OutOfRange { .. }
            | DecodeError::BadAddress { .. }
            | DecodeError::BroadcastNotAccepted { .. }
    )
}

impl<Q, R> Event<Q, R> {
    /// Where the event's bytes start in the stream.
    pub fn offset(&self) -> u64 {
        match *self {
            Event::Request { offset, .. }
            | Event::Response { offset, .. }
            | Event::Ambiguous { offset, .. }
            | Event::OutOfSpec { offset, .. }
            | Event::Skipped { offset, .. } => offset,
        }
    }

    /// How many bytes of the stream the event accounts for.
    pub fn len(&self) -> u64 {
        match *self {
            Event::Request { len, .. }
            | Event::Response { len, .. }
            | Event::Ambiguous { len, .. }
            | Event::OutOfSpec { len, .. } => len as u64,
            Event::Skipped { len, .. } => len,
        }
    }

    /// Whether the event accounts for no bytes (never true of an event the decoder returns).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A streaming decoder for protocol `C`, with a buffer of `C::Buffer` (generated protocols:
/// exactly the longest frame; each protocol module names the decoder `StreamDecoder`). A
/// shorter buffer cannot stall it: a full buffer settles as at the end of a capture.
pub struct StreamDecoder<C: Protocol> {
    /// Bytes pushed and not yet settled; `buf[0]` is at stream offset `core.head`.
    buf: C::Buffer,
    len: usize,
    core: Core<C>,
}

/// Everything but the buffer: what the framing rule has seen so far. Kept apart so the rule
/// can run on the buffer or, in [`Feed`], straight on the caller's bytes.
struct Core<C: Protocol> {
    /// Stream offset of the first unsettled byte.
    head: u64,
    /// All ones for a decoded direction, zero for the other: masks the candidates.
    requests: u64,
    responses: u64,
    last_request: Option<C::Request>,
    /// The bytes that request's checksum covers (the first `span_len` of `span`), where a
    /// reply's checksum may take them in ([`Framing::OVER_REQUEST`]).
    span: C::Span,
    span_len: usize,
    default_request: Option<C::Request>,
    noise_at: u64,
    noise_len: u64,
    pending: Option<Event<C::Request, C::Response>>,
    /// Whether the byte at `head` is the closing flag of the frame just settled, kept as the
    /// next frame's possible opening one ([`Framing::SHARED_FLAG`]): if it opens none, it is
    /// dropped without being noise.
    held_flag: bool,
    /// Preamble bytes ([`Framing::PREAMBLE`]) held just before `head`, the first at
    /// `preamble_at`: the next frame's if one starts at `head`, else noise.
    preamble_at: u64,
    preamble_len: u8,
}

impl<C: Protocol> Clone for Core<C> {
    fn clone(&self) -> Self {
        Core { ..*self }
    }
}

/// What one step of the framing rule reported and the state it left
/// ([`StreamDecoder::fast_and_full`]).
#[doc(hidden)]
#[derive(Debug, Clone, PartialEq)]
pub struct RuleOutcome<Q, R> {
    pub event: Option<Event<Q, R>>,
    pub pending: Option<Event<Q, R>>,
    pub head: u64,
    pub noise_at: u64,
    pub noise_len: u64,
    pub last_request: Option<Q>,
}

impl<C: Protocol> Default for StreamDecoder<C> {
    fn default() -> Self {
        Self::new(None)
    }
}

impl<C: Protocol> StreamDecoder<C> {
    /// A decoder for frames of one direction (a master that knows what it expects), or of both
    /// (`None`: a sniffer on a shared bus).
    pub fn new(direction: Option<Direction>) -> Self {
        StreamDecoder {
            buf: <C::Buffer as FrameBuffer>::ZERO,
            len: 0,
            core: Core {
                head: 0,
                requests: if direction == Some(Direction::Response) {
                    0
                } else {
                    u64::MAX
                },
                responses: if direction == Some(Direction::Request) {
                    0
                } else {
                    u64::MAX
                },
                last_request: None,
                span: C::EMPTY_SPAN,
                span_len: 0,
                default_request: None,
                noise_at: 0,
                noise_len: 0,
                pending: None,
                held_flag: false,
                preamble_at: 0,
                preamble_len: 0,
            },
        }
    }

    /// Responses that only their request identifies are decoded as answers to `request` when
    /// no request precedes them in the stream (a capture of the device's side only).
    pub fn with_default_request(mut self, request: Option<C::Request>) -> Self {
        self.core.default_request = request;
        self
    }

    /// Stream offset of the next byte [`Self::push`] will take.
    pub fn position(&self) -> u64 {
        self.core.head + self.len as u64
    }

    /// Bytes buffered and not yet settled.
    pub fn buffered(&self) -> usize {
        self.len
    }

    /// Takes as many bytes of `data` as the buffer has room for and returns how many; call
    /// [`Self::poll`] until it returns `None` to make room again.
    pub fn push(&mut self, data: &[u8]) -> usize {
        let n = (self.buf.as_ref().len() - self.len).min(data.len());
        self.buf.as_mut()[self.len..self.len + n].copy_from_slice(&data[..n]);
        self.len += n;
        n
    }

    /// The next event the buffered bytes settle, or `None` when more bytes are needed.
    pub fn poll(&mut self) -> Option<Event<C::Request, C::Response>> {
        self.step(false)
    }

    /// Settles what is buffered, as at the end of a capture or after an idle line: complete
    /// frames are decoded, the rest is noise. Call until it returns `None`; the decoder then
    /// stays usable and offsets continue.
    pub fn finish(&mut self) -> Option<Event<C::Request, C::Response>> {
        self.step(true)
    }

    /// The fast path and the full rule each applied once, from this decoder's state with
    /// `noise` bytes of noise before the head (up to [`MAX_SKIPPED_RUN`]), to `window` taken
    /// as a whole window of the caller's bytes (as [`Feed`] takes it; `window.len()` must be
    /// the buffer's capacity): `None` where the fast path leaves the head to the full rule,
    /// otherwise what each reports and leaves behind. For the tests that hold the two equal;
    /// the buffered bytes play no part.
    #[doc(hidden)]
    pub fn fast_and_full(
        &self,
        window: &[u8],
        noise: u64,
    ) -> Option<[RuleOutcome<C::Request, C::Response>; 2]> {
        if window.len() != self.buf.as_ref().len() {
            return None;
        }
        let mut core = self.core.clone();
        core.noise_len = noise.min(MAX_SKIPPED_RUN);
        core.noise_at = core.head.saturating_sub(core.noise_len);
        let mut full = core.clone();
        let mut slow = false;
        let fast = core.fast_step(window, &mut slow);
        if slow {
            return None;
        }
        let full_event = full.full_step(window);
        Some([core.outcome(fast), full.outcome(full_event)])
    }

    /// Pushes all of `data`, yielding each event as it is settled. Bytes the iterator has not
    /// reached when it is dropped are not consumed: see [`Feed::remaining`].
    pub fn feed<'a, 'd>(&'a mut self, data: &'d [u8]) -> Feed<'a, 'd, C> {
        Feed {
            base: self.position(),
            decoder: self,
            input: data,
        }
    }

    fn step(&mut self, flushing: bool) -> Option<Event<C::Request, C::Response>> {
        loop {
            if self.core.pending.is_some() {
                return self.core.pending.take();
            }
            if self.len == 0 {
                return if flushing {
                    self.core.release_preamble();
                    self.core.take_noise()
                } else {
                    None
                };
            }
            // A full buffer cannot wait for more (only a buffer shorter than the longest frame,
            // which no protocol module declares, fills up while waiting): settle what is there.
            let step = self.core.advance(
                &self.buf.as_ref()[..self.len],
                flushing || self.len == self.buf.as_ref().len(),
            );
            match step {
                Step::Wait => return None,
                Step::Frame(n, len, found) => {
                    self.consume(n);
                    return Some(self.core.frame_event(n, len, found));
                }
                Step::Settled(n) => {
                    self.consume(n);
                    if let Some(ev) = self.core.report() {
                        return Some(ev);
                    }
                }
            }
        }
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.as_mut().copy_within(n..self.len, 0);
        self.len -= n;
    }
}

/// What a frame decoded as, before it becomes an [`Event`]: small, so it travels in registers
/// and the event is written once, where the caller returns it.
enum Found<Q, R> {
    Request(Decoded<Q>),
    Response(Decoded<R>),
    Ambiguous(u32),
}

/// How [`Core::fast_with`] ended where it did not hand a frame's event on.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FastEnd {
    /// A frame: its event went to `emit`.
    Frame,
    /// A byte of noise, counted.
    Noise,
    /// Not the simple case: nothing changed, the full rule decides.
    Slow,
}

/// What one application of the framing rule did.
enum Step<Q, R> {
    /// A candidate is longer than the window and more bytes may come.
    Wait,
    /// A frame: the bytes settled (`head` is past them: all of the frame's but a shared
    /// closing flag, [`Framing::SHARED_FLAG`]), its length, what it decoded as.
    Frame(usize, usize, Found<Q, R>),
    /// That many bytes settled with what they report, if anything, left to
    /// [`Core::report`]: a byte of noise, or an out-of-spec frame (in `pending`).
    Settled(usize),
}

impl<C: Protocol> Core<C> {
    /// Applies the framing rule once to `window`, the unsettled bytes from `head` on (only the
    /// first `MAX_FRAME_LEN` matter, and all of them are there unless the window ends the
    /// buffered bytes; `flushing`: no more will come before a decision).
    #[inline(always)]
    fn advance(&mut self, window: &[u8], flushing: bool) -> Step<C::Request, C::Response> {
        let c = C::candidates(window);
        let v = C::variable_candidates(window);
        let requests = c.requests & self.requests;
        let responses = c.responses & self.responses;
        let var_q = if self.requests != 0 {
            v.requests
        } else {
            VarLen::NONE
        };
        let var_r = if self.responses != 0 {
            v.responses
        } else {
            VarLen::NONE
        };
        let live = requests | responses;
        if live != 0 || !var_q.is_none() || !var_r.is_none() {
            // Bit i is LENGTHS[i], longest first: a live candidate longer than the window is
            // one whose bit lies below the first length that fits (none when the longest does,
            // as in every whole window).
            let longer = if C::FRAME_LENGTHS
                .first()
                .map_or(true, |&l| l <= window.len())
            {
                0
            } else {
                let fits = C::FRAME_LENGTHS
                    .iter()
                    .position(|&l| l <= window.len())
                    .unwrap_or(64);
                if fits >= 64 {
                    u64::MAX
                } else {
                    (1u64 << fits) - 1
                }
            };
            // A variable-length candidate whose length is known and complete; one still
            // waiting for its length or count field, or longer than the window, waits.
            let complete = |v: VarLen| v.get().filter(|&l| l <= window.len()).unwrap_or(0);
            let (mut lq, mut lr) = (complete(var_q), complete(var_r));
            let waits = |v: VarLen| v.needs_more() || v.get().is_some_and(|l| l > window.len());
            if !flushing && (live & longer != 0 || waits(var_q) || waits(var_r)) {
                return Step::Wait;
            }
            let mut rest = live & !longer;
            // The longest length that checksums and breaks only a rule of the spec, and why:
            // reported if no length is a frame.
            let mut out_of_spec: Option<(usize, DecodeError)> = None;
            while let Some((len, request, response)) =
                next_length::<C>(&mut rest, &mut lq, &mut lr, requests, responses)
            {
                let Some(frame) = window.get(..len) else {
                    break;
                };
                if let Some(found) = self.try_frame(frame, request, response, &mut out_of_spec) {
                    let n = self.pass(window, len);
                    return Step::Frame(n, len, found);
                }
            }
            if let Some((len, reason)) = out_of_spec {
                self.last_request = None;
                let (offset, whole) = self.with_preamble(self.head, len);
                self.pending = Some(Event::OutOfSpec {
                    offset,
                    len: whole,
                    reason,
                });
                return Step::Settled(self.pass(window, len));
            }
        }
        // The head byte starts no frame.
        self.noise_byte(window);
        Step::Settled(1)
    }

    /// The event of a frame of `len` bytes that [`Self::advance`] found and settled (`settled`
    /// of them), after any noise before it (then the frame waits in `pending`).
    #[inline(always)]
    fn frame_event(
        &mut self,
        settled: usize,
        len: usize,
        found: Found<C::Request, C::Response>,
    ) -> Event<C::Request, C::Response> {
        let (offset, len) = self.with_preamble(self.head - settled as u64, len);
        let ev = match found {
            Found::Request(frame) => Event::Request { offset, len, frame },
            Found::Response(frame) => Event::Response { offset, len, frame },
            Found::Ambiguous(code) => Event::Ambiguous { offset, len, code },
        };
        if self.noise_len > 0 {
            self.pending = Some(ev);
            return Event::Skipped {
                offset: self.noise_at,
                len: core::mem::take(&mut self.noise_len),
            };
        }
        ev
    }

    /// What bytes settled as [`Step::Settled`] report: a run of noise once it is
    /// [`MAX_SKIPPED_RUN`] long or a frame follows it, then the frame in `pending`.
    #[inline(always)]
    fn report(&mut self) -> Option<Event<C::Request, C::Response>> {
        if self.noise_len >= MAX_SKIPPED_RUN || (self.noise_len > 0 && self.pending.is_some()) {
            return self.take_noise();
        }
        self.pending.take()
    }

    /// What `frame` (the bytes at `head`) is if it is a frame (pairing updated); otherwise
    /// `None`, and if it breaks only a rule of the spec ([`breaks_spec`]: where both directions
    /// are candidates, the error that got further, [`DecodeError::progress`], the request's on
    /// a tie, as the interpreter decoding both ways at once refuses it) and no longer length
    /// did, its length and the reason in `out_of_spec`.
    #[inline(always)]
    fn try_frame(
        &mut self,
        frame: &[u8],
        request: bool,
        response: bool,
        out_of_spec: &mut Option<(usize, DecodeError)>,
    ) -> Option<Found<C::Request, C::Response>> {
        let mut why: Option<DecodeError> = None;
        let as_request = if request {
            match C::decode_request(frame) {
                Ok(d) => Some(d),
                Err(e) => {
                    why = Some(e);
                    None
                }
            }
        } else {
            None
        };
        let as_response = if response {
            match self.response(frame) {
                Ok(d) => Some(Ok(d)),
                Err(DecodeError::Ambiguous { code, .. }) => Some(Err(code)),
                Err(e) => {
                    // The reason that got further ([`DecodeError::progress`]).
                    if why.as_ref().map_or(true, |q| e.progress() > q.progress()) {
                        why = Some(e);
                    }
                    None
                }
            }
        } else {
            None
        };
        let found = match (as_request, as_response) {
            (Some(request), None) => {
                self.remember(Some(request.message));
                self.keep_span(frame);
                Found::Request(request)
            }
            (None, Some(Ok(frame))) => {
                self.last_request = self.kept_after(&frame.message);
                Found::Response(frame)
            }
            (None, Some(Err(code))) => {
                self.last_request = None;
                Found::Ambiguous(code)
            }
            (Some(_), Some(_)) => {
                self.last_request = None;
                Found::Ambiguous(both_ways_code(frame))
            }
            (None, None) => {
                if out_of_spec.is_none() {
                    if let Some(e) = why.filter(breaks_spec) {
                        *out_of_spec = Some((frame.len(), e));
                    }
                }
                return None;
            }
        };
        Some(found)
    }

    /// `frame` decoded as a response by the rule: on its own, and where that is ambiguous, as
    /// the reply to the request before it (or the default request). Asked as the reply first,
    /// which settles it in one decoding where a reply follows its request: a response that
    /// decodes as the reply is the one message that decodes on its own too, or one of those
    /// that make it ambiguous, the one the request settles (messages sharing code and length
    /// differ in a constant unless only the request tells them apart).
    #[inline(always)]
    fn response(&self, frame: &[u8]) -> Result<Decoded<C::Response>, DecodeError> {
        if C::OVER_REQUEST {
            // Not the reply: on its own, its checksum still over the request's bytes (a reply
            // that checksums over them and breaks a rule of the spec is out of spec, as the
            // interpreter's stream says).
            let covered = self.covered();
            if let Some(r) = self.last_request.as_ref().or(self.default_request.as_ref()) {
                return match C::Response::decode_as_reply_over(frame, Some(r), covered) {
                    Ok(d) => Ok(d),
                    Err(_) => C::Response::decode_as_reply_over(frame, None, covered),
                };
            }
            return C::Response::decode_as_reply_over(frame, None, covered);
        }
        // Where the reply to any request decodes as on its own (`Framing::REPLY_BY_REQUEST`),
        // no request is kept, and a default one is not asked.
        let paired = if C::REPLY_BY_REQUEST {
            self.last_request.as_ref().or(self.default_request.as_ref())
        } else {
            None
        };
        if let Some(r) = paired {
            return match C::Response::decode_as_reply(frame, Some(r)) {
                Ok(d) => Ok(d),
                Err(_) => Self::not_the_reply(frame),
            };
        }
        C::Response::decode_as_reply(frame, None)
    }

    /// Whether [`Self::response`] decodes `frame` (`Ok(())`, else the same error), by the
    /// same route, without the value
    /// ([`Framing::response_decodes`](crate::Framing::response_decodes)).
    #[inline(always)]
    fn response_decodes(&self, frame: &[u8]) -> Result<(), DecodeError> {
        if !C::REPLY_BY_REQUEST && !C::OVER_REQUEST {
            return C::response_decodes(frame, None, None);
        }
        let covered = if C::OVER_REQUEST {
            self.covered()
        } else {
            None
        };
        if let Some(r) = self.last_request.as_ref().or(self.default_request.as_ref()) {
            return match C::response_decodes(frame, Some(r), covered) {
                Ok(()) => Ok(()),
                Err(_) => C::response_decodes(frame, None, covered),
            };
        }
        C::response_decodes(frame, None, covered)
    }

    /// The request a response leaves for the next one to pair with: none, since a request gets
    /// one reply, but where the response is sent unasked and is not the reply to the request
    /// before it (a heartbeat between a request and its reply), which leaves that request
    /// waiting. Decided at compile time where no response is sent unasked.
    #[inline(always)]
    fn kept_after(&self, response: &C::Response) -> Option<C::Request> {
        if !<C::Response as ResponseMessage<C::Request>>::HAS_UNASKED {
            return None;
        }
        match self.last_request {
            Some(q) if response.is_unasked() && !response.answers(&q) => Some(q),
            _ => None,
        }
    }

    /// The request the next response pairs with, after a frame (`None` after any but a
    /// request, or an unasked response that is not its reply: [`Self::kept_after`]); not kept where no response's decoding depends on it
    /// ([`Framing::REPLY_BY_REQUEST`](crate::Framing::REPLY_BY_REQUEST)), which saves copying
    /// every request (Modbus: a request is 250 bytes).
    #[inline(always)]
    fn remember(&mut self, request: Option<C::Request>) {
        if C::REPLY_BY_REQUEST || C::OVER_REQUEST {
            self.last_request = request;
        }
    }

    /// Whether `frame`, of both directions' candidates at one length, decodes as a request
    /// (`Ok`, else the request's error) and then also as a response ([`Self::response`]
    /// decodes it or finds it ambiguous: `Ok(true)`, a frame ambiguous both ways), asked
    /// without the values ([`Framing::request_decodes`](crate::Framing::request_decodes),
    /// [`Self::response_decodes`]).
    #[inline(always)]
    fn decodes_both_ways(&self, frame: &[u8]) -> Result<bool, DecodeError> {
        if !C::REPLY_BY_REQUEST && !C::OVER_REQUEST {
            // No request asked: the protocol's answer, its framing checked once where both
            // directions check it alike.
            return C::decodes_both_ways(frame);
        }
        C::request_decodes(frame)?;
        Ok(matches!(
            self.response_decodes(frame),
            Ok(()) | Err(DecodeError::Ambiguous { .. })
        ))
    }

    /// [`Self::decodes_both_ways`] out of line, where no view answers (the checks are the
    /// owned decoders): UB2's loop compiled worse with them in it (156.0 -> 157.9
    /// instructions a frame).
    #[inline(never)]
    fn decodes_both_ways_apart(&self, frame: &[u8]) -> Result<bool, DecodeError> {
        self.decodes_both_ways(frame)
    }

    /// Keeps the bytes request `frame`'s checksum covers, where a reply's checksum may take
    /// them in ([`Framing::OVER_REQUEST`]; nothing for any other protocol).
    #[inline(always)]
    fn keep_span(&mut self, frame: &[u8]) {
        if C::OVER_REQUEST {
            let span = C::Request::covered(frame);
            let room = self.span.as_mut();
            self.span_len = span.len().min(room.len());
            room[..self.span_len].copy_from_slice(&span[..self.span_len]);
        }
    }

    /// The bytes the last request's checksum covered, where a request came before (a default
    /// request has none).
    #[inline(always)]
    fn covered(&self) -> Option<&[u8]> {
        self.last_request
            .map(|_| &self.span.as_ref()[..self.span_len])
    }

    /// `frame` on its own, where it did not decode as the reply: out of line and cold, so
    /// the decoder's loop keeps `frame` across the reply's decoding on the stack, not in a
    /// register it would free by moving five others around the call (SD: 5 instructions a
    /// frame).
    #[cold]
    #[inline(never)]
    fn not_the_reply(frame: &[u8]) -> Result<Decoded<C::Response>, DecodeError> {
        C::Response::decode_as_reply(frame, None)
    }

    /// The framing rule at the head of a whole window (`window.len()` the buffer's capacity,
    /// settled as when flushing) where it is simple, which is almost always: no candidate
    /// waiting for its length or count field, and the longest candidate length that decodes
    /// before any breaks only a rule of the spec (fixed and variable lengths alike, of one
    /// direction or both). Returns its event, or `None` with `head`
    /// past a byte of noise (counted, not reported); sets `slow` and changes nothing where
    /// the case is not simple, for [`Self::advance`] to decide.
    #[inline(always)]
    fn fast(&mut self, window: &[u8], slow: &mut bool) -> Option<Event<C::Request, C::Response>> {
        let mut end = FastEnd::Frame;
        let both_ways = self.requests & self.responses != 0;
        let ev = self.fast_with(window, both_ways, &mut end, None, |_, _, ev| Some(ev));
        *slow = end == FastEnd::Slow;
        ev
    }

    /// [`Self::fast`] with its frame's event handed to `emit` (with this state and `acc`)
    /// where it is made, rather than returned: [`Feed`]'s `fold` passes each event straight
    /// to its caller's closure this way, with no merge of the three kinds of event into one
    /// value. Returns what `emit` returned, or `acc` where there was no frame. `both_ways`:
    /// whether the decoder looks for both directions (`requests & responses != 0`, fixed when
    /// it is made), which a loop can read once (UB2: 146.4 -> 145.4 instructions a frame).
    #[inline(always)]
    fn fast_with<T>(
        &mut self,
        window: &[u8],
        both_ways: bool,
        end: &mut FastEnd,
        acc: T,
        emit: impl FnOnce(&mut Self, T, Event<C::Request, C::Response>) -> T,
    ) -> T {
        // A frame settled: the request it leaves for the next response to pair with, the
        // head past it, its event handed to `emit`.
        macro_rules! settle {
            ($last:expr, $len:expr, $event:expr) => {{
                self.remember($last);
                self.pass(window, $len);
                return emit(self, acc, $event);
            }};
        }
        // The case left to the full rule.
        macro_rules! slow {
            () => {{
                *end = FastEnd::Slow;
                return acc;
            }};
        }
        // One frame tried: returns with its event, or where it leaves the case to the full
        // rule; goes on where it is not a frame.
        // `$fixed`: the frame's length is one the candidate table gave, which generated code
        // decodes through a copy of the decoder for that length
        // (`Protocol::decode_request_fixed`, the same answer).
        macro_rules! try_frame {
            ($frame:expr, $request:expr, $defer:expr) => {
                try_frame!($frame, $request, $defer, false)
            };
            ($frame:expr, $request:expr, $defer:expr, $fixed:expr) => {
                let Some(frame) = $frame else { slow!() };
                let (offset, len) = (self.head, frame.len());
                if $request {
                    let decoded = if $fixed {
                        C::decode_request_fixed(frame)
                    } else {
                        C::decode_request(frame)
                    };
                    match decoded {
                        Ok(d) => {
                            self.keep_span(frame);
                            settle!(
                                Some(d.message),
                                len,
                                Event::Request {
                                    offset,
                                    len,
                                    frame: d
                                }
                            )
                        }
                        Err(e) if breaks_spec(&e) => {
                            slow!()
                        }
                        Err(_) => {}
                    }
                } else {
                    // `$defer`: a response that is not the reply to the request before it
                    // goes to the full rule (rare), so the frame need not outlive the reply's
                    // decoding. Where one frame length is the route (SD: 129.1 -> 127.6
                    // instructions a frame); UB2's route compiles worse with it (148.4 ->
                    // 153.3), so there the frame is decoded on its own out of line.
                    let reply = if $fixed && !(C::REPLY_BY_REQUEST || C::OVER_REQUEST) {
                        C::decode_response_fixed(frame)
                    } else if !$defer || !(C::REPLY_BY_REQUEST || C::OVER_REQUEST) {
                        self.response(frame)
                    } else {
                        match self.last_request.as_ref().or(self.default_request.as_ref()) {
                            Some(r) => {
                                match C::Response::decode_as_reply_over(
                                    frame,
                                    Some(r),
                                    self.covered(),
                                ) {
                                    Ok(d) => Ok(d),
                                    Err(_) => slow!(),
                                }
                            }
                            None => C::Response::decode_as_reply(frame, None),
                        }
                    };
                    match reply {
                        Ok(frame) => settle!(
                            self.kept_after(&frame.message),
                            len,
                            Event::Response { offset, len, frame }
                        ),
                        Err(DecodeError::Ambiguous { code, .. }) => {
                            settle!(None, len, Event::Ambiguous { offset, len, code })
                        }
                        Err(e) if breaks_spec(&e) => {
                            slow!()
                        }
                        Err(_) => {}
                    }
                }
            };
        }
        // A reply whose checksum takes in its request's bytes needs them kept: the full
        // rule's case.
        // A frame after preamble bytes takes them into its event: the full rule's case.
        if let Some(pre) = C::PREAMBLE {
            if self.preamble_len > 0 && window.first() != Some(&pre.byte) {
                slow!()
            }
        }
        // Where the head fixes its frames (and the decoder looks for both directions, with no
        // variable-length candidate), they are tried in turn: no mask to build or walk.
        let one = C::candidate(window);
        if one != Candidate::MANY && both_ways && C::variable_candidates(window) == VarLens::NONE {
            let mut slots = one.0;
            while slots != 0 {
                let (len, request) = (usize::from(slots & 0x7F), slots & 0x80 == 0);
                slots >>= 8;
                try_frame!(window.get(..len), request, false, true);
            }
            self.noise_byte(window);
            *end = FastEnd::Noise;
            return acc;
        }
        let c = C::candidates(window);
        let v = C::variable_candidates(window);
        let requests = c.requests & self.requests;
        let responses = c.responses & self.responses;
        let var = (
            if self.requests != 0 {
                v.requests
            } else {
                VarLen::NONE
            },
            if self.responses != 0 {
                v.responses
            } else {
                VarLen::NONE
            },
        );
        let no_var = var == (VarLen::NONE, VarLen::NONE);
        // With one frame length (a constant), the candidates say only which direction a frame
        // is (bit 0 of each mask): decided here once, the frame's length the constant, no mask
        // walked. Variable-length candidates and candidates of both directions take the walk
        // below.
        if let [len] = C::FRAME_LENGTHS {
            let (q, r) = (requests & 1 != 0, responses & 1 != 0);
            if no_var && !(q && r) {
                if q || r {
                    try_frame!(window.get(..*len), q, true);
                }
                self.noise_byte(window);
                *end = FastEnd::Noise;
                return acc;
            }
        }
        // The walk of `advance` on a whole window (settled as when flushing): every candidate
        // length longest first, the fixed ones of the mask and the variable ones, each tried
        // once with every direction that has it; a variable length the window cannot hold is
        // no candidate. Its one case left to the full rule: a length that checksums and breaks
        // only a rule of the spec, which the rule reports unless a shorter one is a frame.
        if var.0.needs_more() || var.1.needs_more() {
            slow!()
        }
        let complete = |v: VarLen| v.get().filter(|&l| l <= window.len()).unwrap_or(0);
        let (mut lq, mut lr) = (complete(var.0), complete(var.1));
        let mut rest = requests | responses;
        // Whether a request candidate was passed over for the shorter ones, its checks past
        // the framing failing (`Framing::request_may_decode`): not a frame, so a shorter one
        // that is a frame is the rule's answer; but its checksum was not asked, so where no
        // shorter one is a frame it may be out of spec: the full rule's case.
        let mut passed_over = false;
        while let Some((len, request, response)) =
            next_length::<C>(&mut rest, &mut lq, &mut lr, requests, responses)
        {
            if !(request && response) {
                // A short Modbus coil reply is not decoded whole as the 8-byte request its
                // bytes and the next frame's first start (its checksum computed to fail).
                if request && (rest != 0 || lq != 0 || lr != 0) {
                    if let Some(frame) = window.get(..len) {
                        if !C::request_may_decode(frame) {
                            passed_over = true;
                            continue;
                        }
                    }
                }
                try_frame!(window.get(..len), request, false);
                continue;
            }
            // Both directions at one length (a Modbus echo, a Dynamixel instruction that also
            // reads as a status packet): `try_frame`'s decision, each event written where it
            // is made. Whether each direction decodes is asked first, without the value
            // (`Framing::request_decodes`, `response_decodes`: a view's check, no list
            // copied), which settles a frame that decodes both ways; the value is decoded
            // only for the one direction that decodes.
            let Some(frame) = window.get(..len) else {
                slow!()
            };
            let offset = self.head;
            let both = if C::VIEWS {
                self.decodes_both_ways(frame)
            } else {
                self.decodes_both_ways_apart(frame)
            };
            match both {
                Ok(true) => {
                    let code = both_ways_code(frame);
                    settle!(None, len, Event::Ambiguous { offset, len, code });
                }
                Ok(false) => match C::decode_request(frame) {
                    Ok(d) => {
                        self.keep_span(frame);
                        settle!(
                            Some(d.message),
                            len,
                            Event::Request {
                                offset,
                                len,
                                frame: d
                            }
                        );
                    }
                    // Never: the check and the decoding agree.
                    Err(_) => slow!(),
                },
                Err(q) => match self.response(frame) {
                    Ok(frame) => settle!(
                        self.kept_after(&frame.message),
                        len,
                        Event::Response { offset, len, frame }
                    ),
                    Err(DecodeError::Ambiguous { code, .. }) => {
                        settle!(None, len, Event::Ambiguous { offset, len, code })
                    }
                    Err(r) => {
                        let why = if r.progress() > q.progress() { r } else { q };
                        if breaks_spec(&why) {
                            slow!()
                        }
                    }
                },
            }
        }
        if passed_over {
            slow!()
        }
        self.noise_byte(window);
        *end = FastEnd::Noise;
        acc
    }

    /// [`Self::fast`] and what it leaves to report: its frame, after the noise before it (then
    /// the frame waits in `pending`), or a run of noise [`MAX_SKIPPED_RUN`] long. The step
    /// [`Feed`] takes at a whole window in the caller's bytes (written out there, where it
    /// costs less); [`Self::full_step`] is the full rule's, and the two agree wherever this
    /// one does not set `slow` ([`StreamDecoder::fast_and_full`]).
    #[inline(always)]
    fn fast_step(
        &mut self,
        window: &[u8],
        slow: &mut bool,
    ) -> Option<Event<C::Request, C::Response>> {
        let ev = self.fast(window, slow);
        if let Some(ev) = ev {
            if self.noise_len > 0 {
                self.pending = Some(ev);
                return self.take_noise();
            }
            return Some(ev);
        }
        if self.noise_len >= MAX_SKIPPED_RUN {
            return self.take_noise();
        }
        None
    }

    /// The full rule at the head of a whole window (`window.len()` the buffer's capacity),
    /// which settles at least one byte: what it reports, if anything yet.
    #[inline(always)]
    fn full_step(&mut self, window: &[u8]) -> Option<Event<C::Request, C::Response>> {
        match self.advance(window, true) {
            Step::Frame(n, len, found) => Some(self.frame_event(n, len, found)),
            Step::Settled(_) => self.report(),
            // Not when flushing.
            Step::Wait => None,
        }
    }

    fn outcome(
        self,
        event: Option<Event<C::Request, C::Response>>,
    ) -> RuleOutcome<C::Request, C::Response> {
        RuleOutcome {
            event,
            pending: self.pending,
            head: self.head,
            noise_at: self.noise_at,
            noise_len: self.noise_len,
            last_request: self.last_request,
        }
    }

    /// Settles the `len` bytes of a frame (or out-of-spec frame) at the head of `window`: all
    /// but its last byte where that is a shared flag ([`Framing::SHARED_FLAG`]), which stays
    /// at the head as the next frame's possible opening flag. Returns how many were settled.
    #[inline(always)]
    fn pass(&mut self, window: &[u8], len: usize) -> usize {
        let n = match C::SHARED_FLAG {
            Some(flag) => {
                let keep = len > 1 && window.get(len - 1) == Some(&flag);
                self.held_flag = keep;
                len - usize::from(keep)
            }
            None => len,
        };
        self.head += n as u64;
        n
    }

    /// The event's offset and length of a frame of `len` bytes at `offset` (the head), with
    /// the preamble bytes held before it, which it takes ([`Framing::PREAMBLE`]).
    #[inline(always)]
    fn with_preamble(&mut self, offset: u64, len: usize) -> (u64, usize) {
        if C::PREAMBLE.is_some() && self.preamble_len > 0 {
            let held = core::mem::take(&mut self.preamble_len);
            return (self.preamble_at, len + usize::from(held));
        }
        (offset, len)
    }

    /// The preamble bytes held, which open no frame: noise.
    #[inline(always)]
    fn release_preamble(&mut self) {
        if C::PREAMBLE.is_some() && self.preamble_len > 0 {
            if self.noise_len == 0 {
                self.noise_at = self.preamble_at;
            }
            self.noise_len += u64::from(core::mem::take(&mut self.preamble_len));
        }
    }

    /// The head byte (`window[0]`) starts no frame: one more byte of noise (but a held
    /// closing flag, which its frame accounted for, and a preamble byte, held for the frame
    /// that may follow).
    #[inline(always)]
    fn noise_byte(&mut self, window: &[u8]) {
        if C::SHARED_FLAG.is_some() && core::mem::take(&mut self.held_flag) {
            self.head += 1;
            return;
        }
        if let Some(pre) = C::PREAMBLE {
            if window.first() == Some(&pre.byte) {
                if self.preamble_len >= pre.max {
                    // More in a row than a frame takes: the first of them is noise.
                    if self.noise_len == 0 {
                        self.noise_at = self.preamble_at;
                    }
                    self.noise_len += 1;
                    self.preamble_at += 1;
                    self.preamble_len -= 1;
                }
                if self.preamble_len == 0 {
                    self.preamble_at = self.head;
                }
                self.preamble_len += 1;
                self.head += 1;
                return;
            }
            self.release_preamble();
        }
        if self.noise_len == 0 {
            self.noise_at = self.head;
        }
        self.noise_len += 1;
        self.head += 1;
    }

    fn take_noise(&mut self) -> Option<Event<C::Request, C::Response>> {
        if self.noise_len == 0 {
            return None;
        }
        let ev = Event::Skipped {
            offset: self.noise_at,
            len: self.noise_len,
        };
        self.noise_len = 0;
        Some(ev)
    }
}

/// The iterator [`StreamDecoder::feed`] returns.
///
/// Where nothing is buffered and a whole longest frame of the caller's bytes lies ahead, it
/// applies the framing rule to those bytes in place instead of copying them through the
/// buffer: the same decisions (the rule only ever looks at the next `MAX_FRAME_LEN` bytes),
/// without copying every byte in and shifting it out again, which cost about as much as
/// decoding the frame. A frame's event is written once, where `next` returns it.
///
/// `for_each` (and `fold`, `count`) is the faster way to take the events: the fast step then
/// runs in the iterator's own loop and hands each event to the closure where it is made,
/// without re-entering `next` for every event.
pub struct Feed<'a, 'd, C: Protocol> {
    decoder: &'a mut StreamDecoder<C>,
    input: &'d [u8],
    /// The stream offset of `input[0]`: `input[..at]`, `at` the decoder's
    /// [`StreamDecoder::position`] less this, has been pushed or settled in place. Kept as
    /// this rather than `at` so that settling a frame in place moves one count, `head`.
    base: u64,
}

impl<'d, C: Protocol> Feed<'_, 'd, C> {
    /// The bytes not yet pushed into the decoder.
    pub fn remaining(&self) -> &'d [u8] {
        self.input.get(self.at()..).unwrap_or_default()
    }

    /// How many bytes of the input have been pushed or settled in place.
    #[inline(always)]
    fn at(&self) -> usize {
        (self.decoder.position() - self.base) as usize
    }
}

impl<C: Protocol> Iterator for Feed<'_, '_, C> {
    type Item = Event<C::Request, C::Response>;

    // Inlined into the caller's loop, the event is built where the caller uses it.
    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let d = &mut *self.decoder;
            let cap = d.buf.as_ref().len();
            if d.len == 0 && d.core.pending.is_none() {
                // Heads in place, while the simple case holds (`Core::fast`).
                // What `Core::fast_step` does, written out: returning the frame's event
                // here and the noise's there keeps the event out of a merge (14 instructions
                // a frame more).
                loop {
                    let at = (d.core.head - self.base) as usize;
                    let Some(window) = self.input.get(at..at + cap) else {
                        break;
                    };
                    let mut slow = false;
                    let ev = d.core.fast(window, &mut slow);
                    if slow {
                        break;
                    }
                    if let Some(ev) = ev {
                        if d.core.noise_len > 0 {
                            d.core.pending = Some(ev);
                            return d.core.take_noise();
                        }
                        return Some(ev);
                    }
                    if d.core.noise_len >= MAX_SKIPPED_RUN {
                        return d.core.take_noise();
                    }
                }
            }
            if let Some(ev) = self.next_slow() {
                return ev;
            }
        }
    }

    /// The events one by one to `f`, as [`Self::next`] returns them, without going through
    /// `next` for each: the fast step runs in this loop and hands each frame's event straight
    /// to `f` where it is made (and the noise before it first, rather than holding the frame
    /// in `pending`), so the decoder's state stays in this loop and no event is merged with
    /// another kind before `f` gets it. What `for_each` and `count` use; as fast as the
    /// decoder gets.
    #[inline]
    fn fold<B, F>(mut self, init: B, mut f: F) -> B
    where
        F: FnMut(B, Self::Item) -> B,
    {
        let mut acc = init;
        loop {
            let d = &mut *self.decoder;
            let cap = d.buf.as_ref().len();
            if d.len == 0 && d.core.pending.is_none() {
                let both_ways = d.core.requests & d.core.responses != 0;
                loop {
                    let at = (d.core.head - self.base) as usize;
                    let Some(window) = self.input.get(at..at + cap) else {
                        break;
                    };
                    let mut end = FastEnd::Frame;
                    acc = d
                        .core
                        .fast_with(window, both_ways, &mut end, acc, |core, acc, ev| {
                            let acc = match core.take_noise() {
                                Some(noise) => f(acc, noise),
                                None => acc,
                            };
                            f(acc, ev)
                        });
                    match end {
                        FastEnd::Frame => {}
                        FastEnd::Noise => {
                            if d.core.noise_len >= MAX_SKIPPED_RUN {
                                if let Some(noise) = d.core.take_noise() {
                                    acc = f(acc, noise);
                                }
                            }
                        }
                        FastEnd::Slow => break,
                    }
                }
            }
            match self.next_slow() {
                Some(Some(ev)) => acc = f(acc, ev),
                Some(None) => return acc,
                None => {}
            }
        }
    }
}

impl<C: Protocol> Feed<'_, '_, C> {
    /// [`Iterator::next`] where the simple case does not hold: the framing rule in full, until
    /// it reports an event or the end of the input (`Some`), or has settled bytes in place
    /// without one (`None`: the simple case may hold again).
    #[inline(never)]
    fn next_slow(&mut self) -> Option<Option<Event<C::Request, C::Response>>> {
        loop {
            let at = self.at();
            let d = &mut *self.decoder;
            if d.core.pending.is_some() {
                return Some(d.core.pending.take());
            }
            // Buffered bytes that all came from this input are still there, right before
            // `at` (the buffer holds the last bytes pushed): give them back to the input
            // (`at` moves back with `len`).
            let cap = d.buf.as_ref().len();
            if d.len > 0 && d.len <= at && self.input.len() - (at - d.len) >= cap {
                d.len = 0;
                continue;
            }
            if d.len == 0 {
                // A whole buffer's worth of bytes: as in `step`, a full window settles.
                if let Some(window) = self.input.get(at..at + cap) {
                    return d.core.full_step(window).map(Some);
                }
            }
            if let Some(ev) = d.poll() {
                return Some(Some(ev));
            }
            let rest = self.input.get(at..).unwrap_or_default();
            if rest.is_empty() {
                return Some(None);
            }
            d.push(rest);
        }
    }
}

#[cfg(test)]
mod tests {
    /// The last four bytes are what folding every byte into a `u32` leaves, as the code of an
    /// ambiguous frame was computed before.
    #[test]
    fn both_ways_code_is_the_fold_of_every_byte() {
        let bytes: [u8; 9] = [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99];
        for n in 0..=bytes.len() {
            let frame = &bytes[..n];
            let fold = frame
                .iter()
                .fold(0u32, |a, b| a.wrapping_shl(8) | u32::from(*b));
            assert_eq!(super::both_ways_code(frame), fold, "{n} bytes");
        }
    }
}
