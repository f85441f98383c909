//! The sans-IO bus master: every rule of a transaction, and no I/O.
//!
//! [`MasterCore`] turns "send this request to this address" into [`Action`]s — sleep until a
//! time, discard stale input, raise the driver-enable line, write these bytes, lower it, read
//! until a time — and a result once the caller has fed it the bytes it read and the time. A
//! driver is a loop: ask [`MasterCore::poll`] what to do at `now`, do it, feed what was read to
//! [`MasterCore::received`], ask again, until [`Action::Done`]; then
//! [`MasterCore::take_outcome`]. Nothing here allocates or sleeps, so the same core runs
//! under a blocking `std` port, tokio, or `embedded-io(-async)` firmware.
//!
//! The rules (as the `std` master always kept them):
//!
//! - **One request in flight**, and a quiet [`Timing::inter_request_gap`] since the line was
//!   last busy before each send (UB2 §2.1: 10 ms); input that arrived meanwhile is discarded.
//! - **Reply pairing**: bytes are read until they decode as a reply to this request
//!   ([`Protocol::decode_reply`](crate::Protocol::decode_reply): length, checksum, code and the spec's `answers`) from the
//!   address it goes back from ([`Link::reply_address`]), or the line is quiet for
//!   [`Timing::byte_gap`] after the last byte, or [`Timing::reply_timeout`] passes with nothing.
//! - **Safe retries**: a lost or garbled reply, a checksum NAK or a collision is retried up to
//!   [`Timing::attempts`] times only where [`Link::retry_safe`] says sending twice is harmless.
//! - **Settle**: after a timeout (or a collision) the line must be quiet for
//!   [`Timing::settle`] (at most four times that) before the next send, so a late reply is
//!   discarded instead of taken for the next request's answer.
//! - **Broadcasts** the spec leaves unanswered ([`Command::broadcast`](busspec_runtime::Command::broadcast)) finish when sent.
//! - **Commands without a reply** ([`Command::reply`](busspec_runtime::Command::reply): `reply: none`)
//!   finish when sent; where the reply is optional, silence until the timeout finishes the
//!   transaction with no response, and is not retried.
//! - **Freshness counters** ([`Link::freshness_mut`], SD §3.1) are kept per address: every
//!   request that carries one carries the next value; the first one to an address starts from
//!   the device's own view ([`Link::freshness_readout`]), read in a transaction of its own.
//! - **Byte-order check** ([`MasterCore::start_checked`]): before the first movement to an
//!   address, the [`Link::byte_order_probe`] replies must read plausibly in the declared byte
//!   order (erratum ub2-e01), or nothing is sent; forgotten on [`Link::forgets_byte_order_checks`].
//! - **RS485** ([`Line`]): local echo read back and compared, driver-enable timing, turnaround.

use core::fmt;
use core::time::Duration;

use busspec_runtime::{
    DecodeError, EncodeError, FrameBuffer, Framing, Message, Reply as ReplyRule, RequestMessage,
    ResponseMessage,
};

use crate::line::{DriverEnable, Line};
use crate::link::{ByteOrderCheck, Link};

/// Line timing of a master.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timing {
    /// How long to wait for the first byte of a reply.
    pub reply_timeout: Duration,
    /// Quiet time after a byte that ends a reply.
    pub byte_gap: Duration,
    /// Quiet time the line must have after a timeout before the next request goes out.
    pub settle: Duration,
    /// Minimum time between the end of one exchange and the next request.
    pub inter_request_gap: Duration,
    /// Sends of one request at most, where retrying is safe.
    pub attempts: u32,
}

impl Timing {
    /// Defaults for a protocol on its document's line ([`Line::for_protocol`]).
    pub fn for_protocol<P: Link>() -> Timing {
        Timing::for_line::<P>(&Line::for_link::<P>())
    }

    /// Defaults for a protocol on `line`: the response timeout its spec declares
    /// (`transactions.response_timeout_ms`), else one generous for its baud rate; its gap
    /// between frames at the line's baud rate ([`crate::link::inter_request_gap`]).
    pub fn for_line<P: Link>(line: &Line) -> Timing {
        // Where the spec gives no reply time (UB2, SD): UB2 runs at 19,200 baud with a 10 ms
        // command gap; SD at 115,200 baud and 50 frames per second, one exchange every 20 ms.
        let reply_timeout = default_reply_timeout(P::transactions().response_timeout_us, P::baud());
        Timing {
            reply_timeout,
            byte_gap: Duration::from_millis(5),
            settle: reply_timeout,
            inter_request_gap: P::request_gap(line.baud, line.bits_per_byte),
            attempts: 3,
        }
    }
}

/// The reply timeout of a protocol whose spec declares `response_timeout_us` (or none) and
/// whose document's line runs at `baud`: the declared one, else 50 ms from 100,000 baud and
/// 200 ms below.
pub fn default_reply_timeout(response_timeout_us: Option<u32>, baud: u32) -> Duration {
    match response_timeout_us {
        Some(us) => Duration::from_micros(u64::from(us)),
        None if baud >= 100_000 => Duration::from_millis(50),
        None => Duration::from_millis(200),
    }
}

/// Why received bytes are not the reply to the request in flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rejection {
    /// They do not decode as a reply to it (length, checksum, code, pairing).
    Decode(DecodeError),
    /// A reply to a broadcast from outside the device range.
    NotDevice { from: u8 },
    /// A reply from another address than the request's.
    WrongAddress { from: u8, expected: u8 },
    /// The device reports a checksum error in the request ([`Link::is_checksum_nak`]).
    ChecksumNak,
}

impl fmt::Display for Rejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Rejection::Decode(e) => write!(f, "{e}"),
            Rejection::NotDevice { from } => {
                write!(
                    f,
                    "reply carries address 0x{from:02X}, not a device address"
                )
            }
            Rejection::WrongAddress { from, expected } => write!(
                f,
                "reply comes from address 0x{from:02X}, expected 0x{expected:02X}"
            ),
            Rejection::ChecksumNak => {
                f.write_str("the device reports a checksum error in the request")
            }
        }
    }
}

/// Why an address cannot take a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AddressProblem {
    /// The broadcast address, for a command that does not accept it.
    NoBroadcast,
    /// Neither a device address nor the broadcast address.
    NotDevice,
}

/// A transaction that did not produce a usable reply. `request` is the request the failure
/// happened to (a probe or the freshness readout before the caller's own, where it was one).
#[derive(Debug, Clone, PartialEq)]
pub enum Failure<P: Link> {
    /// The request does not fit its frame.
    Encode {
        request: P::Request,
        source: EncodeError,
    },
    /// The address cannot take this request.
    Address {
        request: P::Request,
        address: u8,
        problem: AddressProblem,
    },
    /// Nothing came back.
    NoReply {
        request: P::Request,
        address: u8,
        attempts: u32,
    },
    /// Bytes came back, but not a reply to this request from this address; the bytes are
    /// [`MasterCore::reply`].
    BadReply {
        request: P::Request,
        address: u8,
        attempts: u32,
        reason: Rejection,
    },
    /// The echo of the request differs from what was sent at `offset`: another transmitter
    /// drove the bus at the same time.
    Collision {
        request: P::Request,
        address: u8,
        attempts: u32,
        offset: usize,
        expected: u8,
        received: u8,
    },
    /// The line echoes ([`Line::echo`]), but only `received` bytes of the request came back.
    NoEcho {
        request: P::Request,
        address: u8,
        attempts: u32,
        received: usize,
    },
    /// A byte-order probe was answered with something else than the probe expects
    /// ([`Link::byte_order_check`] gave `None`); the replies are [`MasterCore::probe_replies`].
    ProbeRefused { request: P::Request, address: u8 },
    /// The device's numbers do not read plausibly in the declared byte order: `request` was
    /// not sent. What was read is [`MasterCore::take_byte_order_check`].
    ByteOrder {
        request: P::Request,
        address: u8,
        /// They read plausibly the other way round.
        swapped_fits: bool,
    },
}

/// A completed transaction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reply<P: Link> {
    /// The reply; `None` for a broadcast that is not answered (or a byte-order check alone).
    pub response: Option<P::Response>,
    /// The address the reply came from (the request's address when there is no reply).
    pub address: u8,
    /// Sends it took (1 = no retry).
    pub attempts: u32,
}

/// What the driver does next.
#[derive(Debug, PartialEq, Eq)]
pub enum Action<'a> {
    /// Wait until this time, then poll again.
    Sleep(Duration),
    /// Discard input received but not read yet, then poll again.
    ClearInput,
    /// Raise the driver-enable line, then poll again.
    EnableDriver,
    /// Write these bytes (and flush, with [`DriverEnable::Flushed`]), then poll again.
    Write(&'a [u8]),
    /// Lower the driver-enable line, then poll again.
    DisableDriver,
    /// Read: feed whatever arrives to [`MasterCore::received`] as it arrives, and poll again
    /// then, or at this time if nothing has.
    Read { until: Duration },
    /// The operation is finished: [`MasterCore::take_outcome`].
    Done,
}

/// Something that happened on the line, for logs and tests; see [`MasterCore::take_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The frame ([`MasterCore::sent`]) goes out: queued with [`Action::Write`].
    Sent { attempt: u32 },
    /// A reply ([`MasterCore::reply`]) was judged: accepted, or rejected for this reason.
    Received {
        attempt: u32,
        rejected: Option<Rejection>,
    },
    /// Nothing came back in time.
    NoReply { attempt: u32 },
    /// Bytes ([`MasterCore::reply`]) thrown away while waiting for the line to settle.
    Discarded,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Idle,
    Gap,
    Enable,
    Write,
    Written {
        started: Duration,
    },
    Drain {
        until: Duration,
    },
    Echo {
        got: usize,
        until: Duration,
    },
    Reply {
        deadline: Duration,
        quiet_until: Option<Duration>,
    },
    Settle {
        limit: Duration,
        quiet_until: Duration,
    },
    Done,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Reading the byte-order probe, this request of it.
    Probe(usize),
    /// Reading the device's freshness counter before the caller's request.
    Freshness,
    /// The caller's request.
    Main,
}

/// The receive buffer's default size in bytes, [`MasterCore`]'s `CAP` where a type does not
/// name one. Any one frame of a protocol must fit the buffer (a protocol whose frames may be
/// longer does not build: [`MasterCore::new`]); reading stops at four frames' worth or when it
/// is full. 1024 bytes hold Dynamixel 2.0's longest status packet (256 bytes cut its packets of
/// 246 data bytes and more into "no valid reply") and the longest frame a spec read at run
/// time may have.
pub const RX: usize = 1024;

/// The sans-IO master for protocol `P`, with a receive buffer of `CAP` bytes; see the module
/// docs.
///
/// `CAP` defaults to [`RX`]. Firmware whose protocol has short frames takes less RAM with a
/// smaller one, and a protocol whose frames are longer than 1024 bytes needs a larger one:
///
/// ```
/// # use busspec_link_core::MasterCore;
/// # use busspec_devices::Sd;
/// // SD's frames are 6 bytes: 32 bytes hold four of them and more.
/// let core = MasterCore::<Sd, 32>::new();
/// assert!(!core.busy());
/// ```
///
/// A `CAP` below the protocol's longest frame does not build:
///
/// ```compile_fail
/// # use busspec_link_core::MasterCore;
/// # use busspec_devices::Sd;
/// let core = MasterCore::<Sd, 4>::new();
/// ```
pub struct MasterCore<P: Link, const CAP: usize = RX> {
    timing: Timing,
    line: Line,
    /// When the line was last busy (a send or a received byte), if ever.
    last_activity: Option<Duration>,
    /// Last freshness counter sent, per address.
    freshness: [Option<u8>; 256],
    /// Addresses that passed the byte-order check, one bit each.
    checked: [u32; 8],
    state: State,
    phase: Phase,
    /// The caller's request and its address.
    target: Option<(u8, P::Request)>,
    probe_only: bool,
    probe_replies: heapless::Vec<P::Response, 4>,
    passed: Option<ByteOrderCheck>,
    // The transaction in flight.
    address: u8,
    request: Option<P::Request>,
    broadcast: bool,
    expects_reply: bool,
    /// The spec says the reply may not come (`reply: optional`): silence ends the transaction
    /// with no response, not with a failure.
    reply_optional: bool,
    allowed: u32,
    attempt: u32,
    frame: P::Buffer,
    frame_len: usize,
    rx: [u8; CAP],
    rx_len: usize,
    /// Frames set aside while waiting for a reply: responses sent unasked that the request
    /// does not get ([`Self::unasked_seen`]).
    unasked: u32,
    last_error: Option<Failure<P>>,
    outcome: Option<Result<Reply<P>, Failure<P>>>,
    events: heapless::Deque<Event, 4>,
}

impl<P: Link, const CAP: usize> Default for MasterCore<P, CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<P: Link, const CAP: usize> MasterCore<P, CAP> {
    /// Every frame of `P` fits the receive buffer.
    const FRAME_FITS: () = assert!(
        P::MAX_FRAME_LEN <= CAP,
        "a frame of this protocol is longer than the master's receive buffer (MasterCore's CAP, link_core::master::RX by default)"
    );

    /// A master with the protocol's [`Timing`] and [`Line`].
    pub fn new() -> Self {
        // Refused at build time for a protocol whose frames the buffer cannot hold.
        #[allow(clippy::let_unit_value)]
        let () = Self::FRAME_FITS;
        MasterCore {
            timing: Timing::for_protocol::<P>(),
            line: Line::for_link::<P>(),
            last_activity: None,
            freshness: [None; 256],
            checked: [0; 8],
            state: State::Idle,
            phase: Phase::Main,
            target: None,
            probe_only: false,
            probe_replies: heapless::Vec::new(),
            passed: None,
            address: 0,
            request: None,
            broadcast: false,
            expects_reply: true,
            reply_optional: false,
            allowed: 1,
            attempt: 0,
            frame: P::Buffer::ZERO,
            frame_len: 0,
            rx: [0; CAP],
            rx_len: 0,
            unasked: 0,
            last_error: None,
            outcome: None,
            events: heapless::Deque::new(),
        }
    }

    pub fn timing(&self) -> Timing {
        self.timing
    }

    pub fn set_timing(&mut self, timing: Timing) {
        self.timing = timing;
    }

    pub fn line(&self) -> Line {
        self.line
    }

    pub fn set_line(&mut self, line: Line) {
        self.line = line;
    }

    /// Whether an operation is under way (started and not yet taken).
    pub fn busy(&self) -> bool {
        !matches!(self.state, State::Idle)
    }

    /// The request frame last written.
    pub fn sent(&self) -> &[u8] {
        &self.frame.as_ref()[..self.frame_len]
    }

    /// The bytes last received: the reply being read or judged, or bytes discarded.
    /// How many frames the master has set aside since it was made: while waiting for a reply,
    /// a frame that decodes as a response the device sends unasked (`unasked: true`,
    /// [`ResponseMessage::is_unasked`]) and that the
    /// request in flight does not get is not the reply and not a failure: its bytes are
    /// dropped, this count goes up, and the master keeps waiting within the same timeout.
    pub fn unasked_seen(&self) -> u32 {
        self.unasked
    }

    pub fn reply(&self) -> &[u8] {
        &self.rx[..self.rx_len.min(CAP)]
    }

    /// The address and request of the operation last started.
    pub fn target(&self) -> Option<(u8, P::Request)> {
        self.target
    }

    /// The replies to the byte-order probe read by the last checked start.
    pub fn probe_replies(&self) -> &[P::Response] {
        &self.probe_replies
    }

    /// What the byte-order check of the last operation read, if it made one: passed when the
    /// operation went on, failed with [`Failure::ByteOrder`].
    pub fn take_byte_order_check(&mut self) -> Option<ByteOrderCheck> {
        self.passed.take()
    }

    /// What happened since the last call, oldest first; take them after every input (a
    /// poll or received bytes), while [`MasterCore::sent`] and [`MasterCore::reply`] still
    /// hold the bytes they speak of.
    pub fn take_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    fn event(&mut self, e: Event) {
        // At most two events follow one input; a driver that never takes them loses the oldest.
        if self.events.is_full() {
            self.events.pop_front();
        }
        let _ = self.events.push_back(e);
    }

    /// The result, once [`Action::Done`]; the core is idle again afterwards.
    pub fn take_outcome(&mut self) -> Option<Result<Reply<P>, Failure<P>>> {
        let o = self.outcome.take();
        if o.is_some() {
            self.state = State::Idle;
        }
        o
    }

    // Freshness counters.

    /// `v` modulo [`Link::FRESHNESS_MODULUS`].
    fn wrap(v: u16) -> u8 {
        // The remainder is below the modulus, at most 256: it fits.
        (v % P::FRESHNESS_MODULUS.max(1)) as u8
    }

    /// Forgets the freshness counter of `address`, so the next request that carries one
    /// re-reads it.
    pub fn forget_freshness(&mut self, address: u8) {
        self.freshness[usize::from(address)] = None;
    }

    /// Sets the last freshness counter sent to `address`, e.g. when another master sent before.
    pub fn set_freshness(&mut self, address: u8, last: u8) {
        self.freshness[usize::from(address)] = Some(Self::wrap(u16::from(last)));
    }

    /// The freshness counter the next request to `address` that carries one will carry, if known.
    pub fn next_freshness_value(&self, address: u8) -> Option<u8> {
        self.freshness[usize::from(address)].map(|v| Self::wrap(u16::from(v) + 1))
    }

    fn before_zero() -> u8 {
        Self::wrap(P::FRESHNESS_MODULUS.max(1) - 1)
    }

    // Byte-order checks.

    /// Whether `address` passed the byte-order check (and has not been forgotten since).
    pub fn byte_order_checked(&self, address: u8) -> bool {
        self.checked[usize::from(address / 32)] & (1 << (address % 32)) != 0
    }

    /// Forgets every byte-order check, so the next movement to each address checks again.
    pub fn forget_byte_order_checks(&mut self) {
        self.checked = [0; 8];
    }

    // Starting an operation.

    /// Starts one transaction: `request` to `address`. Panics never; a start while busy
    /// abandons the operation under way.
    pub fn start(&mut self, address: u8, request: P::Request) {
        self.begin(address, request, false, false);
    }

    /// Starts `request` to `address` after the byte-order check [`Link::byte_order_probe`]
    /// makes before the first movement to an address (none for a broadcast, or once passed).
    pub fn start_checked(&mut self, address: u8, request: P::Request) {
        self.begin(address, request, true, false);
    }

    /// Runs only the byte-order check for `request` to `address`: finishes with no response
    /// when it passes (or is not needed), and never sends `request`.
    pub fn start_byte_order_check(&mut self, address: u8, request: P::Request) {
        self.begin(address, request, true, true);
    }

    fn begin(&mut self, address: u8, request: P::Request, check: bool, probe_only: bool) {
        self.outcome = None;
        self.events.clear();
        self.passed = None;
        self.probe_replies.clear();
        self.target = Some((address, request));
        self.probe_only = probe_only;
        let probe = P::byte_order_probe();
        let needs_check = check
            && !probe.is_empty()
            && Some(address) != P::broadcast_address()
            && !self.byte_order_checked(address);
        if needs_check {
            self.phase = Phase::Probe(0);
            self.transact(address, probe[0]);
        } else {
            self.checked_go_on(address, request);
        }
    }

    /// The byte-order check passed or was not needed: send `request`, unless only the check
    /// was asked for.
    fn checked_go_on(&mut self, address: u8, request: P::Request) {
        if self.probe_only {
            self.finish(Ok(Reply {
                response: None,
                address,
                attempts: 0,
            }));
        } else {
            self.phase = Phase::Main;
            self.transact(address, request);
        }
    }

    fn finish(&mut self, result: Result<Reply<P>, Failure<P>>) {
        self.outcome = Some(result);
        self.state = State::Done;
    }

    /// Starts one transaction of the operation: address checks, freshness, encoding.
    fn transact(&mut self, address: u8, mut request: P::Request) {
        let broadcast = match Self::check_address(&request, address) {
            Ok(b) => b,
            Err(problem) => {
                return self.finish(Err(Failure::Address {
                    request,
                    address,
                    problem,
                }))
            }
        };
        if P::forgets_byte_order_checks(&request) {
            self.forget_byte_order_checks();
        }
        if P::freshness_mut(&mut request).is_some() {
            let last = match self.freshness[usize::from(address)] {
                Some(v) => Some(v),
                None if Some(address) == P::broadcast_address() => Some(Self::before_zero()),
                None => match P::freshness_readout() {
                    Some(readout) => {
                        // Read the device's view first; `request` waits in `target`.
                        self.phase = Phase::Freshness;
                        return self.transact(address, readout);
                    }
                    None => Some(Self::before_zero()),
                },
            };
            if let Some(last) = last {
                let next = Self::wrap(u16::from(last) + 1);
                self.freshness[usize::from(address)] = Some(next);
                if let Some(f) = P::freshness_mut(&mut request) {
                    *f = next;
                }
            }
        }
        let buf = self.frame.as_mut();
        match request.encode(address, buf) {
            Ok(n) => self.frame_len = n,
            Err(source) => return self.finish(Err(Failure::Encode { request, source })),
        }
        self.address = address;
        self.request = Some(request);
        self.broadcast = broadcast;
        // A command the spec says gets no reply is done once sent, like a broadcast nobody
        // answers; one whose reply is optional is done when none comes.
        let rule = request.command().reply;
        self.expects_reply =
            rule != ReplyRule::None && (!broadcast || request.command().broadcast.answered);
        self.reply_optional = rule == ReplyRule::Optional;
        self.allowed = if P::retry_safe(&request) {
            self.timing.attempts.max(1)
        } else {
            1
        };
        self.attempt = 1;
        self.last_error = None;
        self.rx_len = 0;
        self.state = State::Gap;
    }

    fn check_address(request: &P::Request, address: u8) -> Result<bool, AddressProblem> {
        if Some(address) == P::broadcast_address() {
            return if request.command().broadcast.accepted {
                Ok(true)
            } else {
                Err(AddressProblem::NoBroadcast)
            };
        }
        if !P::device_addresses().contains(&address) {
            return Err(AddressProblem::NotDevice);
        }
        Ok(false)
    }

    /// A transaction of the operation ended: go on to the next, or finish.
    fn transaction_done(&mut self, result: Result<Reply<P>, Failure<P>>) {
        let Some((address, target)) = self.target else {
            return self.finish(result);
        };
        match (self.phase, result) {
            (_, Err(e)) => self.finish(Err(e)),
            (Phase::Main, Ok(r)) => self.finish(Ok(r)),
            (Phase::Freshness, Ok(r)) => {
                let last = r
                    .response
                    .as_ref()
                    .and_then(P::freshness_from_reply)
                    .map_or(Self::before_zero(), |v| Self::wrap(u16::from(v)));
                self.freshness[usize::from(address)] = Some(last);
                self.phase = Phase::Main;
                self.transact(address, target);
            }
            (Phase::Probe(i), Ok(r)) => {
                let probe = P::byte_order_probe();
                let Some(response) = r.response else {
                    return self.finish(Err(Failure::ProbeRefused {
                        request: target,
                        address,
                    }));
                };
                // The probe has at most four requests (a Vec of four).
                let _ = self.probe_replies.push(response);
                if let Some(next) = probe.get(i + 1) {
                    self.phase = Phase::Probe(i + 1);
                    return self.transact(address, *next);
                }
                match P::byte_order_check(&self.probe_replies) {
                    None => self.finish(Err(Failure::ProbeRefused {
                        request: target,
                        address,
                    })),
                    Some(check) if !check.declared_fits => {
                        let swapped_fits = check.swapped_fits;
                        self.passed = Some(check);
                        self.finish(Err(Failure::ByteOrder {
                            request: target,
                            address,
                            swapped_fits,
                        }))
                    }
                    Some(check) => {
                        self.checked[usize::from(address / 32)] |= 1 << (address % 32);
                        self.passed = Some(check);
                        self.checked_go_on(address, target);
                    }
                }
            }
        }
    }

    // Running it.

    /// What to do at `now`.
    pub fn poll(&mut self, now: Duration) -> Action<'_> {
        loop {
            match self.state {
                State::Idle | State::Done => return Action::Done,
                State::Gap => {
                    if let Some(t) = self.last_activity {
                        let ready = t + self.timing.inter_request_gap;
                        if now < ready {
                            return Action::Sleep(ready);
                        }
                    }
                    self.state = State::Enable;
                    return Action::ClearInput;
                }
                State::Enable => {
                    self.state = State::Write;
                    if self.line.driver_enable.is_some() {
                        return Action::EnableDriver;
                    }
                }
                State::Write => {
                    self.state = State::Written { started: now };
                    self.event(Event::Sent {
                        attempt: self.attempt,
                    });
                    return Action::Write(&self.frame.as_ref()[..self.frame_len]);
                }
                State::Written { started } => match self.line.driver_enable {
                    Some(DriverEnable::Computed) => {
                        let until = started + self.line.tx_time(self.frame_len);
                        self.state = State::Drain { until };
                    }
                    Some(DriverEnable::Flushed) => {
                        self.state = State::Drain { until: now };
                    }
                    None => {
                        self.listen(now);
                        continue;
                    }
                },
                State::Drain { until } => {
                    if now < until {
                        return Action::Sleep(until);
                    }
                    self.listen(now);
                    return Action::DisableDriver;
                }
                State::Echo { got, until } => {
                    if now < until {
                        return Action::Read { until };
                    }
                    self.fail_and_settle(
                        now,
                        Failure::NoEcho {
                            request: self.current(),
                            address: self.address,
                            attempts: self.attempt,
                            received: got,
                        },
                    );
                }
                State::Reply {
                    deadline,
                    quiet_until,
                } => match quiet_until {
                    None if now < deadline => return Action::Read { until: deadline },
                    None if self.reply_optional => {
                        self.event(Event::NoReply {
                            attempt: self.attempt,
                        });
                        let reply = Reply {
                            response: None,
                            address: self.address,
                            attempts: self.attempt,
                        };
                        self.transaction_done(Ok(reply));
                    }
                    None => {
                        self.event(Event::NoReply {
                            attempt: self.attempt,
                        });
                        self.fail_and_settle(
                            now,
                            Failure::NoReply {
                                request: self.current(),
                                address: self.address,
                                attempts: self.attempt,
                            },
                        );
                    }
                    Some(q) if now < q => return Action::Read { until: q },
                    Some(_) => self.judge_quiet(deadline),
                },
                State::Settle { quiet_until, .. } => {
                    if now < quiet_until {
                        return Action::Read { until: quiet_until };
                    }
                    self.next_attempt();
                }
            }
        }
    }

    fn current(&self) -> P::Request {
        match self.request {
            Some(r) => r,
            None => match self.target {
                Some((_, r)) => r,
                None => unreachable!("a transaction runs only after a start"),
            },
        }
    }

    /// The frame has left: read the echo, or the reply, or finish a broadcast.
    fn listen(&mut self, now: Duration) {
        self.last_activity = Some(now);
        self.rx_len = 0;
        if self.line.echo {
            self.state = State::Echo {
                got: 0,
                until: now + self.timing.reply_timeout,
            };
        } else {
            self.await_reply(now);
        }
    }

    fn await_reply(&mut self, now: Duration) {
        if !self.expects_reply {
            // The devices turn around before they take the next request (Modbus serial
            // 2.4.1's turnaround delay): the line counts as busy until then.
            self.last_activity = Some(now + self.line.turnaround);
            let reply = Reply {
                response: None,
                address: self.address,
                attempts: self.attempt,
            };
            return self.transaction_done(Ok(reply));
        }
        self.rx_len = 0;
        self.state = State::Reply {
            deadline: now + self.line.turnaround + self.timing.reply_timeout,
            quiet_until: None,
        };
    }

    fn fail_and_settle(&mut self, now: Duration, failure: Failure<P>) {
        self.last_error = Some(failure);
        self.state = State::Settle {
            limit: now + 4 * self.timing.settle,
            quiet_until: now + self.timing.settle,
        };
    }

    fn next_attempt(&mut self) {
        if self.attempt < self.allowed {
            self.attempt += 1;
            self.state = State::Gap;
        } else {
            let e = self.last_error.take().unwrap_or(Failure::NoReply {
                request: self.current(),
                address: self.address,
                attempts: self.attempt,
            });
            self.transaction_done(Err(e));
        }
    }

    /// Decodes the received bytes as the reply to the request in flight.
    fn accept(&self) -> Result<(u8, P::Response), Rejection> {
        self.accept_bytes(self.reply())
    }

    /// Decodes `bytes` (the received bytes or a tail of them) as the reply to the request in
    /// flight.
    fn accept_bytes(&self, bytes: &[u8]) -> Result<(u8, P::Response), Rejection> {
        let request = self.current();
        // With the request's frame as sent, which a reply's checksum may take in.
        let covered = P::Request::covered(self.sent());
        let reply = P::Response::decode_as_reply_over(bytes, Some(&request), Some(covered))
            .map_err(Rejection::Decode)?;
        let (from, response) = (reply.address, reply.message);
        // Replies without an address (RoboClaw's): from the device asked.
        if !P::replies_addressed() {
            return Ok((self.address, response));
        }
        if self.broadcast {
            if !P::device_addresses().contains(&from) {
                return Err(Rejection::NotDevice { from });
            }
        } else {
            let expected = P::reply_address(&request, self.address);
            if from != expected {
                return Err(Rejection::WrongAddress { from, expected });
            }
        }
        Ok((from, response))
    }

    fn judge_verdict(&mut self, verdict: Result<(u8, P::Response), Rejection>) {
        let (request, address, attempt) = (self.current(), self.address, self.attempt);
        match verdict {
            Ok((from, response)) => {
                self.event(Event::Received {
                    attempt,
                    rejected: None,
                });
                // The request arrived damaged: a line failure, not the device's answer.
                if P::is_checksum_nak(&response) {
                    self.last_error = Some(Failure::BadReply {
                        request,
                        address,
                        attempts: attempt,
                        reason: Rejection::ChecksumNak,
                    });
                    return self.next_attempt();
                }
                self.transaction_done(Ok(Reply {
                    response: Some(response),
                    address: from,
                    attempts: attempt,
                }));
            }
            Err(reason) => {
                self.event(Event::Received {
                    attempt,
                    rejected: Some(reason),
                });
                self.last_error = Some(Failure::BadReply {
                    request,
                    address,
                    attempts: attempt,
                    reason,
                });
                self.next_attempt();
            }
        }
    }

    /// The line went quiet after the bytes read: they are judged as the reply, once any
    /// unasked frames at their head are set aside (where only those came, the master keeps
    /// waiting until `deadline`).
    fn judge_quiet(&mut self, deadline: Duration) {
        let mut verdict = self.accept();
        while verdict.is_err() && self.set_aside_unasked(true) {
            if self.rx_len == 0 {
                self.state = State::Reply {
                    deadline,
                    quiet_until: None,
                };
                return;
            }
            verdict = self.accept();
        }
        self.judge_verdict(verdict);
    }

    /// Sets aside a frame at the head of the received bytes that decodes as a response sent
    /// unasked the request in flight does not get: its bytes dropped, counted
    /// ([`Self::unasked_seen`]). `false` where there is none (or the protocol has no unasked
    /// response, or the bytes overflowed the buffer).
    ///
    /// A head whose start byte and code admit a longer response frame (a list that runs to
    /// the frame's end without a length field or end bytes) may be a frame cut short, its
    /// last byte a checksum by chance: only the line's quiet time ends such a frame. Before it
    /// (`quiet` false) the shortest head that decodes is set aside only where no longer
    /// response frame can start with it, else nothing is (the bytes wait for the quiet gap);
    /// once the line is quiet, the bytes are split into unasked frames followed by the reply
    /// where they can be ([`Self::reply_after_unasked`]), and the first of those frames is set
    /// aside, else the longest head that decodes. So a reply that came in the same gap is not
    /// swallowed by a longer unasked frame whose checksum its bytes happen to match, however
    /// many unasked frames to their end come before it.
    fn set_aside_unasked(&mut self, quiet: bool) -> bool {
        if !<P::Response as ResponseMessage<P::Request>>::HAS_UNASKED || self.rx_len > CAP {
            return false;
        }
        let request = self.current();
        let unasked = |head: &[u8]| {
            P::Response::decode_as_reply(head, None)
                .is_ok_and(|d| d.message.is_unasked() && !d.message.answers(&request))
        };
        let found = if quiet {
            let longest = || (1..=self.rx_len).rev().find(|&n| unasked(&self.rx[..n]));
            match self.reply_after_unasked(&unasked) {
                // The first unasked frame: the longest head from whose end the reply is reached.
                Some(reply) => (1..=reply)
                    .rev()
                    .find(|&n| unasked(&self.rx[..n]) && self.unasked_reach(n, reply, &unasked)),
                None => longest(),
            }
        } else {
            match (1..=self.rx_len).find(|&n| unasked(&self.rx[..n])) {
                Some(n) if !self.longer_response_may_start(n) => Some(n),
                _ => None,
            }
        };
        let Some(n) = found else {
            return false;
        };
        self.rx.copy_within(n..self.rx_len, 0);
        self.rx_len -= n;
        self.unasked = self.unasked.saturating_add(1);
        true
    }

    /// Where the reply begins in the received bytes when they are unasked frames (each one
    /// `unasked` accepts) followed by the reply: the latest such offset, so the fewest bytes are
    /// taken as the reply. `None` where no split of the bytes ends in the reply.
    fn reply_after_unasked(&self, unasked: &impl Fn(&[u8]) -> bool) -> Option<usize> {
        let mut reach = [false; CAP];
        self.unasked_walk(0, &mut reach, unasked);
        (1..self.rx_len)
            .rev()
            .find(|&p| reach[p - 1] && self.accept_bytes(&self.rx[p..self.rx_len]).is_ok())
    }

    /// Whether the received bytes from offset `from` to `to` are unasked frames back to back.
    fn unasked_reach(&self, from: usize, to: usize, unasked: &impl Fn(&[u8]) -> bool) -> bool {
        if from == to {
            return true;
        }
        let mut reach = [false; CAP];
        self.unasked_walk(from, &mut reach, unasked);
        reach[to - 1]
    }

    /// Marks in `reach` (offset `p` at index `p - 1`) every offset of the received bytes that
    /// unasked frames back to back lead to from `from`. Each frame is at most the protocol's
    /// longest, so the walk costs at most that many decodes an offset reached.
    fn unasked_walk(&self, from: usize, reach: &mut [bool; CAP], unasked: &impl Fn(&[u8]) -> bool) {
        let len = self.rx_len.min(CAP);
        for pos in from..len {
            if pos != from && !reach[pos - 1] {
                continue;
            }
            for n in 1..=P::MAX_FRAME_LEN.min(len - pos) {
                if !reach[pos + n - 1] && unasked(&self.rx[pos..pos + n]) {
                    reach[pos + n - 1] = true;
                }
            }
        }
    }

    /// Whether a response frame longer than `n` bytes may begin with the received bytes (its
    /// start byte and code agree with theirs: [`Framing::candidates`]).
    fn longer_response_may_start(&self, n: usize) -> bool {
        let responses = <P as Framing>::candidates(&self.rx[..self.rx_len]).responses;
        <P as Framing>::FRAME_LENGTHS
            .iter()
            .take(64)
            .enumerate()
            .any(|(i, &len)| responses >> i & 1 != 0 && len > n)
    }

    fn store(&mut self, bytes: &[u8]) {
        let start = self.rx_len.min(CAP);
        let n = bytes.len().min(CAP - start);
        self.rx[start..start + n].copy_from_slice(&bytes[..n]);
        self.rx_len += bytes.len();
    }

    /// Bytes read at `now`; then poll again.
    pub fn received(&mut self, bytes: &[u8], now: Duration) {
        if bytes.is_empty() {
            return;
        }
        match self.state {
            State::Echo { got, until } => {
                self.last_activity = Some(now);
                let sent = &self.frame.as_ref()[got..self.frame_len];
                let n = bytes.len().min(sent.len());
                if let Some(i) = (0..n).find(|&i| bytes[i] != sent[i]) {
                    let failure = Failure::Collision {
                        request: self.current(),
                        address: self.address,
                        attempts: self.attempt,
                        offset: got + i,
                        expected: sent[i],
                        received: bytes[i],
                    };
                    return self.fail_and_settle(now, failure);
                }
                if got + n < self.frame_len {
                    self.state = State::Echo {
                        got: got + n,
                        until,
                    };
                    return;
                }
                self.await_reply(now);
                self.received(&bytes[n..], now);
            }
            State::Reply { deadline, .. } => {
                self.last_activity = Some(now);
                self.store(bytes);
                self.state = State::Reply {
                    deadline,
                    quiet_until: Some(now + self.timing.byte_gap),
                };
                let mut verdict = self.accept();
                while verdict.is_err() && self.set_aside_unasked(false) {
                    if self.rx_len == 0 {
                        // Only unasked frames so far: keep waiting for the reply.
                        self.state = State::Reply {
                            deadline,
                            quiet_until: None,
                        };
                        return;
                    }
                    verdict = self.accept();
                }
                // A babbling line cannot keep us here: a reply is never longer than this.
                if verdict.is_ok() || self.rx_len >= 4 * P::MAX_FRAME_LEN {
                    self.judge_verdict(verdict);
                }
            }
            State::Settle { limit, .. } => {
                self.last_activity = Some(now);
                self.rx_len = 0;
                self.store(bytes);
                self.event(Event::Discarded);
                if now >= limit {
                    self.next_attempt();
                } else {
                    self.state = State::Settle {
                        limit,
                        quiet_until: now + self.timing.settle,
                    };
                }
            }
            // Bytes while not reading (a driver that reads ahead): line activity, nothing more.
            _ => self.last_activity = Some(now),
        }
    }
}
