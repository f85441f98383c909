//! What a bus master adds to a protocol beyond its spec: the [`Link`] extension trait.
//!
//! Everything the spec says — names, codes, encoding, decoding, which responses a request may
//! get, each command's kind and broadcast rules, which responses are NAKs, the checksum, the
//! line constants — comes from [`busspec_runtime::Protocol`] and [`busspec_runtime::Message`],
//! which the generated protocol types (`busspec_protocols::ub2::Ub2`, `busspec_protocols::sd::Sd`)
//! implement. [`Link`] holds only what a master decides on top: which commands are safe to send
//! twice, where a reply comes from, which NAK means "try again", the SD freshness counter, the
//! quiet time between requests, and the one place the master reads a NAK differently from the
//! spec ([`Link::nak_approves`]), and the readings that tell whether a device sends its numbers
//! in the byte order the spec declares ([`Link::byte_order_probe`]).

use core::fmt::Write;
use core::time::Duration;

use busspec_runtime::{CommandKind, Protocol, RequestMessage, ResponseMessage};

/// The quiet time between two requests of protocol `P` on a line of `baud` and
/// `character_bits` a character: the longest of the document's gap between frames
/// ([`Bus::inter_frame_gap_ms`](busspec_runtime::Bus::inter_frame_gap_ms)), the gap its `transactions:` section declares in
/// character times at this baud rate ([`busspec_runtime::Transactions::gap_us_at`]; it replaces
/// the millisecond gap, which is the same gap at the document's baud rate), and the period of
/// its highest frame rate.
pub const fn inter_request_gap<P: Protocol>(baud: u32, character_bits: u32) -> Duration {
    let gap_us = match P::BUS.transactions.gap_us_at(baud, character_bits) {
        Some(us) => us,
        None => match P::BUS.inter_frame_gap_ms {
            Some(g) => g as u64 * 1000,
            None => 0,
        },
    };
    let period_us = match P::BUS.max_frames_per_s {
        Some(r) if r > 0 => 1000u64.div_ceil(r as u64) * 1000,
        _ => 0,
    };
    Duration::from_micros(if gap_us > period_us {
        gap_us
    } else {
        period_us
    })
}

/// What a byte-order probe read ([`Link::byte_order_probe`]), judged both ways: as the spec
/// declares the numbers travel, and byte-swapped.
///
/// The texts are fixed-capacity strings ([`Text`]), so the check allocates nothing and fits a
/// `no_std` master.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ByteOrderCheck {
    /// What was read, in the declared byte order (`factory limits 50.00..=500.00 pF`).
    pub read: Text,
    /// The same bytes read the other way round.
    pub swapped: Text,
    /// What a plausible reading is (`inside 0.01..=10000.00 pF, lower below upper`).
    pub rule: Text,
    /// The reading is plausible in the declared byte order.
    pub declared_fits: bool,
    /// The reading is plausible byte-swapped.
    pub swapped_fits: bool,
    /// The erratum of the spec that records the doubt about the byte order (`ub2-e01`).
    pub erratum: &'static str,
}

/// A short text of at most 96 bytes (longer text is cut at the last character that fits).
pub type Text = heapless::String<96>;

/// Formats `args` into a [`Text`], cut where it is full.
pub fn text(args: core::fmt::Arguments<'_>) -> Text {
    struct Cut(Text);
    impl Write for Cut {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for c in s.chars() {
                if self.0.push(c).is_err() {
                    break;
                }
            }
            Ok(())
        }
    }
    let mut t = Cut(Text::new());
    let _ = t.write_fmt(args);
    t.0
}

/// The spec's `byte_order:` line: its line number (from 1) and its text without the comment
/// (`byte_order: little`), if the spec has one at the top level.
pub fn spec_byte_order_line<P: Protocol>() -> Option<(usize, &'static str)> {
    P::SOURCE
        .spec_yaml
        .lines()
        .enumerate()
        .find_map(|(i, line)| {
            line.starts_with("byte_order:")
                .then(|| (i + 1, line.split('#').next().unwrap_or(line).trim_end()))
        })
}

/// The byte order the spec declares, as a word (`little-endian`), from its `byte_order:` line.
pub fn declared_byte_order<P: Protocol>() -> &'static str {
    match spec_byte_order_line::<P>().map(|(_, l)| l.trim_start_matches("byte_order:").trim()) {
        Some("big") => "big-endian",
        Some("little") => "little-endian",
        _ => "in the declared byte order",
    }
}

/// The other byte order than the declared one, as a word.
pub fn swapped_byte_order<P: Protocol>() -> &'static str {
    match declared_byte_order::<P>() {
        "big-endian" => "little-endian",
        "little-endian" => "big-endian (most significant byte first)",
        _ => "byte-swapped",
    }
}

/// Any generated protocol `P` with the master's rules of its spec alone: its [`Protocol`] is
/// `P`'s, item for item (the same `Request` and `Response` types), and its [`Link`] takes every
/// default, which the spec drives (timing, retries, broadcasts, refusals). How a master talks
/// to a protocol no crate has written rules for: `Master<Plain<modbus::Modbus>, ..>`.
///
/// A protocol with rules of its own (UB2's byte-order probe, SD's freshness counter) is a type
/// of its own in the crate that holds them, as `busspec-devices` does.
pub struct Plain<P>(core::marker::PhantomData<P>);

impl<P> Clone for Plain<P> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<P> Copy for Plain<P> {}
impl<P> Default for Plain<P> {
    fn default() -> Self {
        Plain(core::marker::PhantomData)
    }
}
impl<P: Protocol> core::fmt::Debug for Plain<P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Plain<{}>", P::NAME)
    }
}

impl<P: Protocol> Protocol for Plain<P> {
    type Request = P::Request;
    type Response = P::Response;
    type Buffer = P::Buffer;
    const NAME: &'static str = P::NAME;
    const SOURCE: busspec_runtime::Source = P::SOURCE;
    const BUS: busspec_runtime::Bus = P::BUS;
    const MAX_FRAME_LEN: usize = P::MAX_FRAME_LEN;
    fn decode_request(
        frame: &[u8],
    ) -> Result<busspec_runtime::Decoded<Self::Request>, busspec_runtime::DecodeError> {
        P::decode_request(frame)
    }
    fn decode_request_fixed(
        frame: &[u8],
    ) -> Result<busspec_runtime::Decoded<Self::Request>, busspec_runtime::DecodeError> {
        P::decode_request_fixed(frame)
    }
    fn decode_response_fixed(
        frame: &[u8],
    ) -> Result<busspec_runtime::Decoded<Self::Response>, busspec_runtime::DecodeError> {
        P::decode_response_fixed(frame)
    }
}

impl<P: Protocol> busspec_runtime::Framing for Plain<P> {
    const MAX_REQUEST_LEN: usize = P::MAX_REQUEST_LEN;
    const MAX_RESPONSE_LEN: usize = P::MAX_RESPONSE_LEN;
    const FRAME_LENGTHS: &'static [usize] = P::FRAME_LENGTHS;
    const SHARED_FLAG: Option<u8> = P::SHARED_FLAG;
    const PREAMBLE: Option<busspec_runtime::Preamble> = P::PREAMBLE;
    const TRANSFORM: Option<busspec_runtime::Transform> = P::TRANSFORM;
    const LONG: Option<busspec_runtime::LongLength> = P::LONG;
    const OVER_REQUEST: bool = P::OVER_REQUEST;
    type Span = P::Span;
    const EMPTY_SPAN: Self::Span = P::EMPTY_SPAN;
    fn candidates(head: &[u8]) -> busspec_runtime::stream::Candidates {
        P::candidates(head)
    }
    fn candidate(head: &[u8]) -> busspec_runtime::stream::Candidate {
        P::candidate(head)
    }
    fn variable_candidates(head: &[u8]) -> busspec_runtime::stream::VarLens {
        P::variable_candidates(head)
    }
    fn checksum_ok(frame: &[u8]) -> bool {
        P::checksum_ok(frame)
    }
}

impl<P: Protocol> Link for Plain<P> {}

/// One protocol as a bus master sees it: the generated [`Protocol`] plus the master's own rules.
pub trait Link: Protocol {
    /// The quiet time between two requests at the document's baud rate and character bits
    /// ([`inter_request_gap`]): UB2 §2.1 demands 10 ms; SD §1 allows at most 100 frames per
    /// second, i.e. one every 10 ms; Modbus t3.5 is 2.005 ms at 19,200 baud, 8E1.
    const INTER_REQUEST_GAP: Duration =
        inter_request_gap::<Self>(Self::BUS.baud, Self::BUS.transactions.character_bits);

    /// The protocol's name, its document's baud rate, its `transactions:` section, its device
    /// and broadcast addresses: what the master reads of the spec's line constants. The
    /// [`Protocol`] constants by default; a protocol whose spec is read at run time (the CLI's
    /// `talk --spec`) answers from it instead, its constants being placeholders.
    fn name() -> &'static str {
        Self::NAME
    }
    /// See [`Link::name`].
    fn baud() -> u32 {
        Self::BUS.baud
    }
    /// See [`Link::name`].
    fn transactions() -> busspec_runtime::Transactions {
        Self::BUS.transactions
    }
    /// See [`Link::name`].
    fn device_addresses() -> core::ops::RangeInclusive<u8> {
        Self::BUS.device_addresses
    }
    /// See [`Link::name`].
    fn broadcast_address() -> Option<u8> {
        Self::BUS.broadcast_address
    }

    /// Whether replies carry the device's address (`Bus::replies_addressed`): where they do
    /// not, a reply is taken as from the device asked.
    fn replies_addressed() -> bool {
        Self::BUS.replies_addressed
    }
    /// The quiet time between two requests on a line of `baud` and `character_bits`
    /// ([`inter_request_gap`] by default).
    fn request_gap(baud: u32, character_bits: u32) -> Duration {
        inter_request_gap::<Self>(baud, character_bits)
    }

    /// Whether sending `r` twice does no more than sending it once, so a lost or garbled reply
    /// may be answered by sending it again: what the spec declares ([`Command::may_retry`](busspec_runtime::Command::may_retry):
    /// its `transactions.retry`, by default by kind). A protocol's rules may add commands the
    /// spec cannot tell about.
    fn retry_safe(r: &Self::Request) -> bool {
        r.command().may_retry
    }

    /// The address the reply to `r`, sent to `address`, comes from.
    fn reply_address(_r: &Self::Request, address: u8) -> u8 {
        address
    }

    /// A reply that says the device saw a corrupted request (UB2 NAK 0x92): a line failure
    /// worth a retry, not the device's answer.
    fn is_checksum_nak(_r: &Self::Response) -> bool {
        false
    }

    /// Whether `response`, which the spec marks `kind: nak` ([`busspec_runtime::ResponseMessage::is_nak`]), means to
    /// `request` that the command was carried out after all. The one place the master reads a
    /// NAK differently from the spec; `false` unless a protocol says otherwise.
    fn nak_approves(_request: &Self::Request, _response: &Self::Response) -> bool {
        false
    }

    /// Whether `response` refuses `request`: a NAK the spec declares ([`busspec_runtime::ResponseMessage::is_nak`])
    /// that does not, to this request, approve it ([`Link::nak_approves`]).
    fn is_refusal(request: &Self::Request, response: &Self::Response) -> bool {
        response.is_nak() && !Self::nak_approves(request, response)
    }

    /// How many values the freshness counter takes: the master counts modulo this, from 0
    /// (1 to 256; a whole byte by default).
    const FRESHNESS_MODULUS: u16 = 256;
    /// The freshness counter a request carries, if it carries one (SD set point, §3.1).
    fn freshness_mut(_r: &mut Self::Request) -> Option<&mut u8> {
        None
    }
    /// The request that reads the device's view of the host's freshness counter (SD §3.12).
    fn freshness_readout() -> Option<Self::Request> {
        None
    }
    /// The host's freshness counter as the reply to [`Link::freshness_readout`] carries it (the
    /// master takes it modulo [`Link::FRESHNESS_MODULUS`]).
    fn freshness_from_reply(_r: &Self::Response) -> Option<u8> {
        None
    }

    /// Requests whose replies carry multi-byte numbers with a range the master knows, read
    /// before the first movement to an address to make sure the device sends its numbers in
    /// the byte order the spec declares: a device that reads the target the other way round
    /// runs somewhere else entirely. None by default: no check.
    fn byte_order_probe() -> &'static [Self::Request] {
        &[]
    }

    /// The replies to [`Link::byte_order_probe`], in its order, judged both ways; `None` if
    /// they are not the replies the probe expects (a NAK, another reply).
    fn byte_order_check(_replies: &[Self::Response]) -> Option<ByteOrderCheck> {
        None
    }

    /// Whether sending `r` makes the master forget which addresses passed the byte-order check:
    /// a reset, or a command that moves a device to another address (another device may then
    /// answer where a checked one did). A reset by default.
    fn forgets_byte_order_checks(r: &Self::Request) -> bool {
        r.command().kind == CommandKind::Reset
    }
}
