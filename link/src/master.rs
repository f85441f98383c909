//! The transaction layer: one request in flight, a typed request out, the paired typed response
//! back.
//!
//! A transaction: wait out the protocol's gap since the line was last busy (UB2 §2.1: 10 ms),
//! discard stale input, send, then read until a frame decodes as a reply to this request from
//! this address (`decode_reply` checks length, checksum, code and pairing; the address is
//! checked here), or until the line has been quiet for `byte_gap` after the last byte, or until
//! `reply_timeout` passes with nothing. A garbled reply or none at all is retried, up to
//! `attempts` times, only where [`Link::retry_safe`] says sending twice is harmless — never
//! a movement. After a timeout the master waits until the line has been quiet for `settle`
//! before it sends again, so a reply that comes late is discarded instead of being taken for
//! the answer to the next request.
//!
//! Broadcasts that the spec says go unanswered ([`Protocol::broadcast`]) return at once with no
//! response. A freshness counter ([`Link::freshness_mut`], the SD set point's, §3.1) is kept
//! here, per address: every request that carries one carries the next value, whatever the caller
//! put in it; the first one to an address starts from the device's own view of the counter
//! ([`Link::freshness_readout`], SD §3.12).
//!
//! Before the first movement to an address, [`Master::run_movement`], [`Master::move_to`] and
//! [`Master::start_movement`] read what [`Link::byte_order_probe`] names (UB2: the factory
//! limits) and refuse to move a device whose numbers do not read plausibly in the byte order
//! the spec declares ([`LinkError::ByteOrder`], erratum ub2-e01); the check is kept per address
//! until a reset or a new slave address ([`Link::forgets_byte_order_checks`]).
//!
//! [`Master`] works for any protocol that implements [`Link`]; the long operations of one
//! device family (UB2 movements and C-curve table, SD movements and string readouts) are
//! methods of `Master<Ub2, _, _>` and `Master<Sd, _, _>`.

use std::fmt;
use std::io;
use std::marker::PhantomData;
use std::time::Duration;

use busspec_protocols::sd::{self, Sd};
use busspec_protocols::ub2::{self, Ub2};
use busspec_protocols::{CommandKind, EncodeError, Message, Protocol};

use crate::clock::Clock;
use crate::protocol::{byte_order_source, declared_byte_order, swapped_byte_order};
use crate::protocol::{ByteOrderCheck, Link};
use crate::transport::Transport;

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
    /// Defaults for a protocol: its documented gap, and timeouts generous for its baud rate.
    pub fn for_protocol<P: Link>() -> Timing {
        // The documents give no reply time. UB2 runs at 19,200 baud with a 10 ms command gap;
        // SD at 115,200 baud and 50 frames per second, i.e. one exchange every 20 ms.
        let reply_timeout = if P::BAUD >= 100_000 {
            Duration::from_millis(50)
        } else {
            Duration::from_millis(200)
        };
        Timing {
            reply_timeout,
            byte_gap: Duration::from_millis(5),
            settle: reply_timeout,
            inter_request_gap: P::INTER_REQUEST_GAP,
            attempts: 3,
        }
    }
}

/// A transaction that did not produce a usable reply, with what and where.
#[derive(Debug)]
pub enum LinkError {
    /// The transport failed.
    Io { context: String, source: io::Error },
    /// The request does not fit its frame.
    Encode {
        request: &'static str,
        source: EncodeError,
    },
    /// The address is neither a device address nor a broadcast this command accepts.
    Address {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        reason: String,
    },
    /// Nothing came back.
    NoReply {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        attempts: u32,
        timeout: Duration,
    },
    /// Bytes came back, but not a reply to this request from this address.
    BadReply {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        attempts: u32,
        reason: String,
        bytes: Vec<u8>,
    },
    /// The device answered, but not with what the operation needs (a NAK, an unexpected reply).
    Refused {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        response: &'static str,
        detail: String,
    },
    /// The device's numbers do not read plausibly in the byte order the spec declares: the
    /// movement was not sent ([`Link::byte_order_probe`]).
    ByteOrder {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        check: Box<ByteOrderCheck>,
        /// The spec's `byte_order` line (`spec/ub2.yaml:8: byte_order: little`).
        source: String,
        /// The declared byte order and the other one, as words.
        declared: &'static str,
        other: &'static str,
    },
    /// A movement did not finish within the time allowed.
    MovementTimeout {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        waited: Duration,
    },
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

fn plural(n: u32) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Io { context, source } => write!(f, "{context}: {source}"),
            LinkError::Encode { request, source } => write!(f, "cannot encode {request}: {source}"),
            LinkError::Address {
                protocol,
                request,
                address,
                reason,
            } => write!(f, "{protocol} {request} to address 0x{address:02X}: {reason}"),
            LinkError::NoReply {
                protocol,
                request,
                address,
                attempts,
                timeout,
            } => write!(
                f,
                "{protocol} {request} to address 0x{address:02X}: no reply within {} ms ({attempts} attempt{})",
                timeout.as_millis(),
                plural(*attempts)
            ),
            LinkError::BadReply {
                protocol,
                request,
                address,
                attempts,
                reason,
                bytes,
            } => write!(
                f,
                "{protocol} {request} to address 0x{address:02X}: no valid reply ({attempts} attempt{}); last reply {}: {reason}",
                plural(*attempts),
                if bytes.is_empty() { "empty".to_owned() } else { hex(bytes) }
            ),
            LinkError::Refused {
                protocol,
                request,
                address,
                response,
                detail,
            } => write!(
                f,
                "{protocol} {request} to address 0x{address:02X}: device answered {response}: {detail}"
            ),
            LinkError::ByteOrder {
                protocol,
                request,
                address,
                check,
                source,
                declared,
                other,
            } => {
                write!(
                    f,
                    "{protocol} {request} to address 0x{address:02X}: not sent: the device read \
                     {}, implausible {declared} ({}) as the spec declares ({source}); ",
                    check.read, check.rule
                )?;
                if check.swapped_fits {
                    write!(
                        f,
                        "read {other} they are {}, plausible: the device sends its numbers \
                         {other}, as the document's examples print them, not as its text says \
                         (erratum {}); it would read the target the wrong way round and run \
                         elsewhere",
                        check.swapped, check.erratum
                    )
                } else {
                    write!(
                        f,
                        "read {other} they are {}, implausible too: neither byte order fits \
                         (erratum {}); is this the device the spec describes?",
                        check.swapped, check.erratum
                    )
                }
            }
            LinkError::MovementTimeout {
                protocol,
                request,
                address,
                waited,
            } => write!(
                f,
                "{protocol} {request} at address 0x{address:02X}: movement not completed after {:.1} s",
                waited.as_secs_f64()
            ),
        }
    }
}

impl std::error::Error for LinkError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LinkError::Io { source, .. } => Some(source),
            LinkError::Encode { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// A completed transaction.
#[derive(Debug, Clone, PartialEq)]
pub struct Exchange<R> {
    /// The reply; `None` for a broadcast that is not answered.
    pub response: Option<R>,
    /// The address the reply came from (the request's address for an unanswered broadcast).
    pub address: u8,
    /// Sends it took (1 = no retry).
    pub attempts: u32,
    /// The reply frame as received.
    pub frame: Vec<u8>,
    /// The request as sent (with the freshness counter the master filled in).
    pub sent: Vec<u8>,
}

/// What happened on the line, for logs, the demo and the soak.
#[derive(Debug, Clone, Copy)]
pub enum TraceEvent<'a> {
    Sent {
        attempt: u32,
        bytes: &'a [u8],
    },
    Received {
        attempt: u32,
        bytes: &'a [u8],
        /// `None` when accepted, else why not.
        rejected: Option<&'a str>,
    },
    NoReply {
        attempt: u32,
    },
    /// Bytes thrown away while waiting for the line to settle.
    Discarded {
        bytes: &'a [u8],
    },
}

type Observer = Box<dyn FnMut(&TraceEvent<'_>)>;

/// A bus master for protocol `P` over transport `T`, timed by clock `C`.
pub struct Master<P: Link, T: Transport, C: Clock> {
    transport: T,
    clock: C,
    timing: Timing,
    /// When the line was last busy (our send or a received byte), if ever.
    last_activity: Option<Duration>,
    /// Last freshness counter sent, per address.
    freshness: [Option<u8>; 256],
    /// The byte-order check that passed, per address ([`Link::byte_order_probe`]).
    byte_order: Vec<Option<ByteOrderCheck>>,
    observer: Option<Observer>,
    _protocol: PhantomData<P>,
}

impl<P: Link, T: Transport, C: Clock> Master<P, T, C> {
    pub fn new(transport: T, clock: C) -> Self {
        Master {
            transport,
            clock,
            timing: Timing::for_protocol::<P>(),
            last_activity: None,
            freshness: [None; 256],
            byte_order: vec![None; 256],
            observer: None,
            _protocol: PhantomData,
        }
    }

    pub fn with_timing(mut self, timing: Timing) -> Self {
        self.timing = timing;
        self
    }

    pub fn timing(&self) -> Timing {
        self.timing
    }

    pub fn clock(&self) -> &C {
        &self.clock
    }

    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Calls `f` for every send, reply, timeout and discarded byte run.
    pub fn observe(&mut self, f: impl FnMut(&TraceEvent<'_>) + 'static) {
        self.observer = Some(Box::new(f));
    }

    fn trace(&mut self, e: TraceEvent<'_>) {
        if let Some(f) = self.observer.as_mut() {
            f(&e);
        }
    }

    fn io(&self, context: &str, source: io::Error) -> LinkError {
        LinkError::Io {
            context: format!("{} {context}", P::NAME),
            source,
        }
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

    /// `v` modulo [`Link::FRESHNESS_MODULUS`].
    fn wrap(v: u16) -> u8 {
        // The remainder is below the modulus, at most 256: it fits.
        (v % P::FRESHNESS_MODULUS.max(1)) as u8
    }

    /// The freshness counter the next request to `address` that carries one carries.
    fn next_freshness(&mut self, address: u8) -> Result<u8, LinkError> {
        // The value before 0: with nothing known, counting starts at 0.
        let before_zero = Self::wrap(P::FRESHNESS_MODULUS.max(1) - 1);
        let last = match self.freshness[usize::from(address)] {
            Some(v) => v,
            None if Some(address) == P::BROADCAST_ADDRESS => before_zero,
            None => match P::freshness_readout() {
                Some(readout) => {
                    let ex = self.transact(address, readout)?;
                    ex.response
                        .as_ref()
                        .and_then(P::freshness_from_reply)
                        .unwrap_or(before_zero)
                }
                None => before_zero,
            },
        };
        let next = Self::wrap(u16::from(last) + 1);
        self.freshness[usize::from(address)] = Some(next);
        Ok(next)
    }

    /// The byte-order check `address` passed, if it has been checked (and not forgotten since).
    pub fn byte_order_checked(&self, address: u8) -> Option<&ByteOrderCheck> {
        self.byte_order[usize::from(address)].as_ref()
    }

    /// Forgets every byte-order check, so the next movement to each address checks again.
    pub fn forget_byte_order_checks(&mut self) {
        self.byte_order.iter_mut().for_each(|c| *c = None);
    }

    /// Makes sure `address` sends its numbers in the byte order the spec declares, before a
    /// movement `request` goes to it: reads [`Link::byte_order_probe`] once per address and
    /// keeps the result. `Ok(None)` when the protocol has no probe or `address` is a broadcast
    /// (which cannot be read back); `Ok(Some(check))` when the readings fit the declared byte
    /// order; [`LinkError::ByteOrder`] when they do not (whether or not they fit swapped), or
    /// [`LinkError::Refused`] when the device does not answer the probe as expected.
    pub fn check_byte_order(
        &mut self,
        address: u8,
        request: &P::Request,
    ) -> Result<Option<&ByteOrderCheck>, LinkError> {
        let probe = P::byte_order_probe();
        if probe.is_empty() || Some(address) == P::BROADCAST_ADDRESS {
            return Ok(None);
        }
        if self.byte_order[usize::from(address)].is_none() {
            let mut replies = Vec::with_capacity(probe.len());
            for q in &probe {
                replies.push(self.ask(address, *q)?);
            }
            let Some(check) = P::byte_order_check(&replies) else {
                let names: Vec<&str> = replies.iter().map(Message::name).collect();
                return Err(LinkError::Refused {
                    protocol: P::NAME,
                    request: request.name(),
                    address,
                    response: replies.first().map_or("nothing", Message::name),
                    detail: format!(
                        "not sent: the byte-order check before the first movement read {} \
                         to {}",
                        names.join(", "),
                        probe
                            .iter()
                            .map(Message::name)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                });
            };
            if !check.declared_fits {
                return Err(LinkError::ByteOrder {
                    protocol: P::NAME,
                    request: request.name(),
                    address,
                    check: Box::new(check),
                    source: byte_order_source::<P>(),
                    declared: declared_byte_order::<P>(),
                    other: swapped_byte_order::<P>(),
                });
            }
            self.byte_order[usize::from(address)] = Some(check);
        }
        Ok(self.byte_order[usize::from(address)].as_ref())
    }

    fn check_address(&self, request: &P::Request, address: u8) -> Result<bool, LinkError> {
        let broadcast = P::broadcast(request);
        let err = |reason: String| LinkError::Address {
            protocol: P::NAME,
            request: request.name(),
            address,
            reason,
        };
        if Some(address) == P::BROADCAST_ADDRESS {
            if !broadcast.accepted {
                return Err(err(
                    "this command does not accept the broadcast address".to_owned()
                ));
            }
            return Ok(true);
        }
        if !P::DEVICE_ADDRESSES.contains(&address) {
            return Err(err(format!(
                "not a device address (0x{:02X}..=0x{:02X}{})",
                P::DEVICE_ADDRESSES.start(),
                P::DEVICE_ADDRESSES.end(),
                match P::BROADCAST_ADDRESS {
                    Some(b) => format!(", or broadcast 0x{b:02X}"),
                    None => String::new(),
                }
            )));
        }
        Ok(false)
    }

    /// Decodes `bytes` as the reply to `request` sent to `address`.
    fn accept(
        bytes: &[u8],
        request: &P::Request,
        address: u8,
        broadcast: bool,
    ) -> Result<P::Response, String> {
        let reply = P::decode_reply(bytes, request).map_err(|e| e.to_string())?;
        let (from, response) = (reply.address, reply.message);
        if broadcast {
            if !P::DEVICE_ADDRESSES.contains(&from) {
                return Err(format!(
                    "reply carries address 0x{from:02X}, not a device address"
                ));
            }
        } else if from != P::reply_address(request, address) {
            return Err(format!(
                "reply comes from address 0x{from:02X}, expected 0x{:02X}",
                P::reply_address(request, address)
            ));
        }
        Ok(response)
    }

    /// Reads one reply: until it decodes, or the line goes quiet after some bytes, or the
    /// reply timeout passes with none. Returns what arrived (empty on timeout).
    fn read_reply(
        &mut self,
        request: &P::Request,
        address: u8,
        broadcast: bool,
    ) -> Result<Vec<u8>, LinkError> {
        let start = self.clock.now();
        let deadline = start + self.timing.reply_timeout;
        let mut got = Vec::new();
        let mut chunk = [0u8; 64];
        // A babbling line cannot keep us here: a reply is never longer than this.
        let cap = 4 * P::MAX_FRAME_LEN;
        loop {
            let now = self.clock.now();
            let wait = if got.is_empty() {
                if now >= deadline {
                    break;
                }
                deadline - now
            } else {
                self.timing.byte_gap
            };
            let n = self
                .transport
                .read(&mut chunk, wait)
                .map_err(|e| self.io("read", e))?;
            if n == 0 {
                if !got.is_empty() {
                    break;
                }
                continue;
            }
            self.last_activity = Some(self.clock.now());
            got.extend_from_slice(&chunk[..n]);
            if got.len() >= cap || Self::accept(&got, request, address, broadcast).is_ok() {
                break;
            }
        }
        Ok(got)
    }

    /// Waits until the line has been quiet for `settle`, discarding what arrives (bounded).
    fn settle(&mut self) -> Result<(), LinkError> {
        let limit = self.clock.now() + 4 * self.timing.settle;
        let mut chunk = [0u8; 64];
        while self.clock.now() < limit {
            let n = self
                .transport
                .read(&mut chunk, self.timing.settle)
                .map_err(|e| self.io("read", e))?;
            if n == 0 {
                break;
            }
            self.last_activity = Some(self.clock.now());
            let bytes = chunk[..n].to_vec();
            self.trace(TraceEvent::Discarded { bytes: &bytes });
        }
        Ok(())
    }

    /// Sends `request` to `address` and returns the paired reply.
    pub fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Exchange<P::Response>, LinkError> {
        let broadcast = self.check_address(&request, address)?;
        if P::forgets_byte_order_checks(&request) {
            self.forget_byte_order_checks();
        }
        let answered = P::broadcast(&request).answered;
        let mut request = request;
        if P::freshness_mut(&mut request).is_some() {
            let next = self.next_freshness(address)?;
            if let Some(f) = P::freshness_mut(&mut request) {
                *f = next;
            }
        }
        let name = request.name();
        let mut frame = vec![0u8; P::MAX_FRAME_LEN];
        let len = request
            .encode(address, &mut frame)
            .map_err(|source| LinkError::Encode {
                request: name,
                source,
            })?;
        frame.truncate(len);
        let expects_reply = !broadcast || answered;
        let allowed = if P::retry_safe(&request) {
            self.timing.attempts.max(1)
        } else {
            1
        };
        let mut last_error = None;
        for attempt in 1..=allowed {
            if let Some(t) = self.last_activity {
                self.clock.sleep_until(t + self.timing.inter_request_gap);
            }
            self.transport
                .clear_input()
                .map_err(|e| self.io("clear input", e))?;
            self.transport
                .write(&frame)
                .map_err(|e| self.io("write", e))?;
            self.last_activity = Some(self.clock.now());
            self.trace(TraceEvent::Sent {
                attempt,
                bytes: &frame,
            });
            if !expects_reply {
                return Ok(Exchange {
                    response: None,
                    address,
                    attempts: attempt,
                    frame: Vec::new(),
                    sent: frame,
                });
            }
            let got = self.read_reply(&request, address, broadcast)?;
            if got.is_empty() {
                self.trace(TraceEvent::NoReply { attempt });
                last_error = Some(LinkError::NoReply {
                    protocol: P::NAME,
                    request: name,
                    address,
                    attempts: attempt,
                    timeout: self.timing.reply_timeout,
                });
                self.settle()?;
                continue;
            }
            match Self::accept(&got, &request, address, broadcast) {
                Ok(response) => {
                    self.trace(TraceEvent::Received {
                        attempt,
                        bytes: &got,
                        rejected: None,
                    });
                    // The request arrived damaged: a line failure, not the device's answer.
                    if P::is_checksum_nak(&response) {
                        last_error = Some(LinkError::BadReply {
                            protocol: P::NAME,
                            request: name,
                            address,
                            attempts: attempt,
                            reason: "the device reports a checksum error in the request".to_owned(),
                            bytes: got,
                        });
                        continue;
                    }
                    let from = P::decode_reply(&got, &request)
                        .map(|d| d.address)
                        .unwrap_or(address);
                    return Ok(Exchange {
                        response: Some(response),
                        address: from,
                        attempts: attempt,
                        frame: got,
                        sent: frame,
                    });
                }
                Err(reason) => {
                    self.trace(TraceEvent::Received {
                        attempt,
                        bytes: &got,
                        rejected: Some(&reason),
                    });
                    last_error = Some(LinkError::BadReply {
                        protocol: P::NAME,
                        request: name,
                        address,
                        attempts: attempt,
                        reason,
                        bytes: got,
                    });
                }
            }
        }
        Err(last_error.unwrap_or(LinkError::NoReply {
            protocol: P::NAME,
            request: name,
            address,
            attempts: allowed,
            timeout: self.timing.reply_timeout,
        }))
    }

    /// Sends a movement trigger, after the byte-order check [`Master::check_byte_order`] makes
    /// before the first movement to an address: the way to start a movement. (Plain
    /// [`Master::transact`] sends what it is given: the transaction layer, which the soak
    /// and the tests drive directly.)
    pub fn start_movement(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<Exchange<P::Response>, LinkError> {
        self.check_byte_order(address, &trigger)?;
        self.transact(address, trigger)
    }

    /// Like [`Master::transact`] for a request that must be answered: the response itself.
    pub fn ask(&mut self, address: u8, request: P::Request) -> Result<P::Response, LinkError> {
        let ex = self.transact(address, request)?;
        ex.response.ok_or(LinkError::Refused {
            protocol: P::NAME,
            request: request.name(),
            address,
            response: "nothing",
            detail: "a broadcast of this command is not answered".to_owned(),
        })
    }

    fn refused(
        request: &P::Request,
        address: u8,
        response: &P::Response,
        detail: &str,
    ) -> LinkError {
        LinkError::Refused {
            protocol: P::NAME,
            request: request.name(),
            address,
            response: response.name(),
            detail: detail.to_owned(),
        }
    }
}

/// Progress of a long operation, for display.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Progress {
    /// A movement is under way; `position` in the protocol's position unit (UB2 full steps,
    /// SD degrees).
    Moving { elapsed: Duration, position: f64 },
    /// `done` items of a table or string read so far.
    Read { done: usize },
}

/// How a movement ended.
#[derive(Debug, Clone, PartialEq)]
pub struct MoveReport<R> {
    /// The trigger's reply.
    pub started: R,
    /// The final completion reply.
    pub finished: Option<R>,
    /// The target lay outside the customer limits; the device ran to the limit (UB2 0x93).
    pub clipped: bool,
    /// Micro-steps lost on the way (UB2 0x5400).
    pub lost_micro_steps: Option<u32>,
    /// Completion checks sent.
    pub polls: u32,
    pub elapsed: Duration,
}

/// One row of the UB2 C-curve table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CCurvePoint {
    pub index: u16,
    pub full_steps: u16,
    pub capacitance: ub2::Capacitance,
}

/// The completion check that goes with a UB2 movement trigger: same first code byte, second
/// byte 0x01 (§4.x.2). Built as a frame and decoded, so it is whatever the spec says it is.
pub fn ub2_completion_check(trigger: &ub2::Request) -> Option<ub2::Request> {
    let code = trigger.code();
    if code.len() != 2 || code[1] != 0x00 {
        return None;
    }
    let address = *Ub2::DEVICE_ADDRESSES.start();
    let mut frame = [0xAA, address, code[0], 0x01, 0];
    frame[4] = ub2::checksum(&frame[..4]);
    match Ub2::decode_request(&frame) {
        Ok(d) if Ub2::kind(&d.message) == CommandKind::CompletionCheck => Some(d.message),
        _ => None,
    }
}

impl<T: Transport, C: Clock> Master<Ub2, T, C> {
    /// Triggers a movement and polls its completion check every `poll_every` until it is done,
    /// reporting the full-step position in between. Fails if the device refuses the trigger,
    /// says the movement was not triggered, or is not done within `limit`.
    pub fn run_movement(
        &mut self,
        address: u8,
        trigger: ub2::Request,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<ub2::Response>, LinkError> {
        let check = ub2_completion_check(&trigger).ok_or_else(|| LinkError::Refused {
            protocol: Ub2::NAME,
            request: trigger.name(),
            address,
            response: "nothing",
            detail: "not a movement trigger with a completion check".to_owned(),
        })?;
        // Before the first movement to this address: does the device read numbers as the
        // spec says (ub2-e01)? Nothing moves if not.
        self.check_byte_order(address, &trigger)?;
        let start = self.clock.now();
        let started = self.ask(address, trigger)?;
        let clipped = match started {
            ub2::Response::MovementStarted => false,
            // 0x93: approved, the cap runs to the customer limit (§7.2; `Link::nak_approves`).
            r if Ub2::nak_approves(&trigger, &r) => true,
            other => {
                return Err(Self::refused(
                    &trigger,
                    address,
                    &other,
                    "the movement did not start",
                ))
            }
        };
        let mut polls = 0;
        loop {
            let reply = self.ask(address, check)?;
            polls += 1;
            let elapsed = self.clock.now() - start;
            let lost = match reply {
                ub2::Response::MovementCompleted => None,
                ub2::Response::MovementCompletedWithStepLoss { lost_micro_steps } => {
                    Some(lost_micro_steps)
                }
                ub2::Response::MovementNotCompleted => {
                    if elapsed >= limit {
                        return Err(LinkError::MovementTimeout {
                            protocol: Ub2::NAME,
                            request: trigger.name(),
                            address,
                            waited: elapsed,
                        });
                    }
                    if let Ok(ub2::Response::ActualFullStepPosition { full_steps }) =
                        self.ask(address, ub2::Request::GetActualFullStepPosition)
                    {
                        progress(Progress::Moving {
                            elapsed,
                            position: f64::from(full_steps),
                        });
                    }
                    self.clock.sleep(poll_every);
                    continue;
                }
                other => {
                    return Err(Self::refused(
                        &check,
                        address,
                        &other,
                        "while waiting for the movement to complete",
                    ))
                }
            };
            return Ok(MoveReport {
                started,
                finished: Some(reply),
                clipped,
                lost_micro_steps: lost,
                polls,
                elapsed,
            });
        }
    }

    /// Reads the whole C-curve table (§6.7): entries from index 0 until the device answers
    /// "index out of range" (0x94), at most 500.
    pub fn read_c_curve(
        &mut self,
        address: u8,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<CCurvePoint>, LinkError> {
        const MAX_ENTRIES: u16 = 500;
        let mut table = Vec::new();
        for index in 0..MAX_ENTRIES {
            let request = ub2::Request::GetCCurveIndexedFullStepCapacitance { index };
            match self.ask(address, request)? {
                ub2::Response::CCurveEntry {
                    index: got,
                    full_steps,
                    capacitance,
                } if got == index => table.push(CCurvePoint {
                    index,
                    full_steps,
                    capacitance,
                }),
                ub2::Response::CCurveEntry { index: got, .. } => {
                    return Err(LinkError::BadReply {
                        protocol: Ub2::NAME,
                        request: request.name(),
                        address,
                        attempts: 1,
                        reason: format!("entry {got} came back for index {index}"),
                        bytes: Vec::new(),
                    })
                }
                ub2::Response::NakIndexOutOfRange => break,
                other => {
                    return Err(Self::refused(
                        &request,
                        address,
                        &other,
                        "reading the C-curve table",
                    ))
                }
            }
            progress(Progress::Read { done: table.len() });
        }
        Ok(table)
    }
}

/// The four SD string readouts (§3.20-§3.23).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdString {
    SerialNumber,
    ProductDescription,
    SoftwareRevision,
    HardwareRevision,
}

impl SdString {
    pub const ALL: [SdString; 4] = [
        SdString::SerialNumber,
        SdString::ProductDescription,
        SdString::SoftwareRevision,
        SdString::HardwareRevision,
    ];

    /// The request for byte `byte_number` of this string.
    pub fn request(self, byte_number: u8) -> sd::Request {
        match self {
            SdString::SerialNumber => sd::Request::ReadElectronicSerialNumber { byte_number },
            SdString::ProductDescription => sd::Request::ReadProductDescription { byte_number },
            SdString::SoftwareRevision => sd::Request::ReadSoftwareRevision { byte_number },
            SdString::HardwareRevision => sd::Request::ReadHardwareRevision { byte_number },
        }
    }

    /// The character and the string length a reply carries.
    pub fn character(response: &sd::Response) -> Option<(u8, u8)> {
        match *response {
            sd::Response::ElectronicSerialNumberCharacter {
                character,
                string_length,
            }
            | sd::Response::ProductDescriptionCharacter {
                character,
                string_length,
            }
            | sd::Response::SoftwareRevisionCharacter {
                character,
                string_length,
            }
            | sd::Response::HardwareRevisionCharacter {
                character,
                string_length,
            } => Some((character, string_length)),
            _ => None,
        }
    }

    /// The readout this request belongs to.
    pub fn of(request: &sd::Request) -> Option<SdString> {
        SdString::ALL
            .into_iter()
            .find(|s| s.request(0).name() == request.name())
    }
}

impl<T: Transport, C: Clock> Master<Sd, T, C> {
    /// Reads a whole string, one character per transaction: byte 0 gives the length, then the
    /// rest. Every reply must agree on the length.
    pub fn read_string(
        &mut self,
        address: u8,
        which: SdString,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Vec<u8>, LinkError> {
        let mut text = Vec::new();
        let mut length = None;
        let mut byte = 0u8;
        while length.map_or(true, |n| usize::from(byte) < usize::from(n)) && byte < 0x20 {
            let request = which.request(byte);
            let response = self.ask(address, request)?;
            let Some((c, n)) = SdString::character(&response) else {
                return Err(Self::refused(
                    &request,
                    address,
                    &response,
                    "expected a string character",
                ));
            };
            if n > 0x20 {
                return Err(Self::refused(
                    &request,
                    address,
                    &response,
                    &format!("string length {n} exceeds 32"),
                ));
            }
            match length {
                None => length = Some(n),
                Some(l) if l != n => {
                    return Err(Self::refused(
                        &request,
                        address,
                        &response,
                        &format!("string length changed from {l} to {n} while reading"),
                    ))
                }
                Some(_) => {}
            }
            if n == 0 {
                break;
            }
            text.push(c);
            byte += 1;
            progress(Progress::Read { done: text.len() });
        }
        Ok(text)
    }

    /// Sends a set point and polls the actual position every `poll_every` until it equals the
    /// target, or `limit` passes.
    pub fn move_to(
        &mut self,
        address: u8,
        target: sd::Angle,
        poll_every: Duration,
        limit: Duration,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<sd::Response>, LinkError> {
        let start = self.clock.now();
        let request = sd::Request::SetPoint {
            freshness: 0,
            position: target,
        };
        // SD has no byte-order probe (`Link::byte_order_probe`): this checks nothing today.
        self.check_byte_order(address, &request)?;
        let started = self.ask(address, request)?;
        let mut polls = 0;
        loop {
            let reply = self.ask(address, sd::Request::ReadActualPosition)?;
            polls += 1;
            let elapsed = self.clock.now() - start;
            let sd::Response::ActualPosition { position } = reply else {
                return Err(Self::refused(
                    &sd::Request::ReadActualPosition,
                    address,
                    &reply,
                    "expected the actual position",
                ));
            };
            if position == target {
                return Ok(MoveReport {
                    started,
                    finished: Some(reply),
                    clipped: false,
                    lost_micro_steps: None,
                    polls,
                    elapsed,
                });
            }
            if elapsed >= limit {
                return Err(LinkError::MovementTimeout {
                    protocol: Sd::NAME,
                    request: request.name(),
                    address,
                    waited: elapsed,
                });
            }
            progress(Progress::Moving {
                elapsed,
                position: position.value(),
            });
            self.clock.sleep(poll_every);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::SimClock;
    use crate::sim::sd::SdSim;
    use crate::sim::ub2::Ub2Sim;
    use crate::sim::{BusConfig, SimBus};

    /// The freshness counter wraps at the protocol's modulus: SD's 4 bits, a whole byte where a
    /// protocol does not say.
    #[test]
    fn the_freshness_counter_wraps_at_the_protocols_modulus() {
        let clock = SimClock::new();
        let bus = SimBus::new(clock.clone(), BusConfig::new(Sd::BAUD), vec![SdSim::new(1)]);
        let mut m: Master<Sd, _, _> = Master::new(bus, clock);
        m.set_freshness(1, 0x0F);
        assert_eq!(m.next_freshness_value(1), Some(0));
        m.set_freshness(1, 0x1E);
        assert_eq!(m.next_freshness_value(1), Some(0x0F));
        let clock = SimClock::new();
        let bus = SimBus::new(
            clock.clone(),
            BusConfig::new(Ub2::BAUD),
            vec![Ub2Sim::new(0x21)],
        );
        let mut m: Master<Ub2, _, _> = Master::new(bus, clock);
        m.set_freshness(0x21, 0x0F);
        assert_eq!(m.next_freshness_value(0x21), Some(0x10));
        m.set_freshness(0x21, 0xFF);
        assert_eq!(m.next_freshness_value(0x21), Some(0));
    }
}
