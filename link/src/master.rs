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
//! Broadcasts that the spec says go unanswered ([`busspec_runtime::Command::broadcast`]) return at once with no
//! response. A freshness counter ([`Link::freshness_mut`], the SD set point's, §3.1) is kept
//! here, per address: every request that carries one carries the next value, whatever the caller
//! put in it; the first one to an address starts from the device's own view of the counter
//! ([`Link::freshness_readout`], SD §3.12).
//!
//! Before the first movement to an address, [`Master::run_to_end`] (and so the device
//! movements of `busspec-devices`) and [`Master::start_movement`] read what [`Link::byte_order_probe`] names (UB2: the factory
//! limits) and refuse to move a device whose numbers do not read plausibly in the byte order
//! the spec declares ([`LinkError::ByteOrder`], erratum ub2-e01); the check is kept per address
//! until a reset or a new slave address ([`Link::forgets_byte_order_checks`]).
//!
//! [`Master`] works for any protocol that implements [`Link`] and names none; the long
//! operations of one device family (UB2 movements and C-curve table, SD movements and string
//! readouts) are `busspec-devices`', on top of [`Master::ask`] and [`Master::run_to_end`].

use std::fmt;
use std::io;
use std::time::Duration;

use busspec_link_core::master::{Action, AddressProblem, Event, Failure, MasterCore, Reply, RX};
pub use busspec_link_core::master::{Rejection, Timing};
pub use busspec_link_core::movement::MoveReport;
use busspec_link_core::movement::{self, Drive, MoveError, Movement, MovementError};
use busspec_link_core::Line;

use busspec_runtime::{EncodeError, Message};

use crate::clock::Clock;
use crate::protocol::{byte_order_source, declared_byte_order, swapped_byte_order};
use crate::protocol::{ByteOrderCheck, Link};
use crate::transport::Transport;

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
    /// The line echoes what the master sends, and the echo differed from the request at
    /// `offset`: another transmitter drove the bus at the same time.
    Collision {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        attempts: u32,
        sent: Vec<u8>,
        offset: usize,
        expected: u8,
        received: u8,
    },
    /// The line is set to echo, but only `received` bytes of the request came back.
    NoEcho {
        protocol: &'static str,
        request: &'static str,
        address: u8,
        attempts: u32,
        sent: Vec<u8>,
        received: usize,
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
            LinkError::Collision {
                protocol,
                request,
                address,
                attempts,
                sent,
                offset,
                expected,
                received,
            } => write!(
                f,
                "{protocol} {request} to address 0x{address:02X}: collision on the bus ({attempts} attempt{}): the echo of {} differs at offset {offset}: expected 0x{expected:02X}, received 0x{received:02X}",
                plural(*attempts),
                hex(sent)
            ),
            LinkError::NoEcho {
                protocol,
                request,
                address,
                attempts,
                sent,
                received,
            } => write!(
                f,
                "{protocol} {request} to address 0x{address:02X}: the line echoes, but only {received} of the {} bytes of {} came back ({attempts} attempt{})",
                sent.len(),
                hex(sent),
                plural(*attempts)
            ),
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

impl LinkError {
    /// [`LinkError::Refused`] for a request whose answer is needed, sent where nothing answers
    /// it (a broadcast the spec leaves unanswered).
    pub fn unanswered<P: Link>(request: &P::Request, address: u8) -> LinkError {
        LinkError::Refused {
            protocol: P::name(),
            request: request.name(),
            address,
            response: "nothing",
            detail: "a broadcast of this command is not answered".to_owned(),
        }
    }

    /// [`LinkError::Refused`]: the device answered `request` to `address` with `response`,
    /// which the operation cannot go on with, and `detail` says why.
    pub fn refused<P: Link>(
        request: &P::Request,
        address: u8,
        response: &P::Response,
        detail: &str,
    ) -> LinkError {
        LinkError::Refused {
            protocol: P::name(),
            request: request.name(),
            address,
            response: response.name(),
            detail: detail.to_owned(),
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

/// A bus master for protocol `P` over transport `T`, timed by clock `C`: the blocking `std`
/// driver of [`MasterCore`], which keeps every rule; this loop only does what it says. `CAP` is
/// the receive buffer in bytes ([`MasterCore`]; 1024 by default).
pub struct Master<P: Link, T: Transport, C: Clock, const CAP: usize = RX> {
    transport: T,
    clock: C,
    core: MasterCore<P, CAP>,
    /// The byte-order check that passed, per address ([`Link::byte_order_probe`]); valid while
    /// the core still counts the address as checked.
    byte_order: Vec<Option<ByteOrderCheck>>,
    observer: Option<Observer>,
}

impl<P: Link, T: Transport, C: Clock, const CAP: usize> Master<P, T, C, CAP> {
    pub fn new(transport: T, clock: C) -> Self {
        Master {
            transport,
            clock,
            core: MasterCore::new(),
            byte_order: vec![None; 256],
            observer: None,
        }
    }

    pub fn with_timing(mut self, timing: Timing) -> Self {
        self.core.set_timing(timing);
        self
    }

    /// The port's line: baud rate, frame bits and RS485 habits (echo, driver enable,
    /// turnaround).
    pub fn with_line(mut self, line: Line) -> Self {
        self.core.set_line(line);
        self
    }

    pub fn timing(&self) -> Timing {
        self.core.timing()
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

    /// Forgets the freshness counter of `address`, so the next request that carries one
    /// re-reads it.
    pub fn forget_freshness(&mut self, address: u8) {
        self.core.forget_freshness(address);
    }

    /// Sets the last freshness counter sent to `address`, e.g. when another master sent before.
    pub fn set_freshness(&mut self, address: u8, last: u8) {
        self.core.set_freshness(address, last);
    }

    /// The freshness counter the next request to `address` that carries one will carry, if known.
    pub fn next_freshness_value(&self, address: u8) -> Option<u8> {
        self.core.next_freshness_value(address)
    }

    /// The byte-order check `address` passed, if it has been checked (and not forgotten since).
    pub fn byte_order_checked(&self, address: u8) -> Option<&ByteOrderCheck> {
        if self.core.byte_order_checked(address) {
            self.byte_order[usize::from(address)].as_ref()
        } else {
            None
        }
    }

    /// Forgets every byte-order check, so the next movement to each address checks again.
    pub fn forget_byte_order_checks(&mut self) {
        self.core.forget_byte_order_checks();
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
        // The core decides whether a check is due (a probe, not a broadcast, not yet checked)
        // and finishes at once when it is not.
        self.core.start_byte_order_check(address, *request);
        self.run()?;
        Ok(self.byte_order_checked(address))
    }

    /// Runs the core's operation to its end: the blocking driver loop.
    fn run(&mut self) -> Result<Reply<P>, LinkError> {
        let mut chunk = [0u8; 64];
        loop {
            let now = self.clock.now();
            let io = |context: &str, source: io::Error| LinkError::Io {
                context: format!("{} {context}", P::name()),
                source,
            };
            match self.core.poll(now) {
                Action::Done => break,
                Action::Sleep(t) => self.clock.sleep_until(t),
                Action::ClearInput => self
                    .transport
                    .clear_input()
                    .map_err(|e| io("clear input", e))?,
                Action::EnableDriver => self
                    .transport
                    .set_driver_enable(true)
                    .map_err(|e| io("raise driver enable", e))?,
                Action::DisableDriver => self
                    .transport
                    .set_driver_enable(false)
                    .map_err(|e| io("lower driver enable", e))?,
                Action::Write(bytes) => self.transport.write(bytes).map_err(|e| io("write", e))?,
                Action::Read { until } => {
                    let n = self
                        .transport
                        .read(&mut chunk, until.saturating_sub(now))
                        .map_err(|e| io("read", e))?;
                    if n > 0 {
                        self.core.received(&chunk[..n], self.clock.now());
                    }
                }
            }
            self.trace_events();
        }
        self.trace_events();
        match self.core.take_outcome() {
            Some(Ok(reply)) => {
                let check = self.core.take_byte_order_check();
                if let (Some(check), Some((address, _))) = (check, self.core.target()) {
                    self.byte_order[usize::from(address)] = Some(check);
                }
                Ok(reply)
            }
            Some(Err(failure)) => Err(link_error(&mut self.core, failure)),
            None => unreachable!("the core says Done only with an outcome"),
        }
    }

    fn trace_events(&mut self) {
        while let Some(event) = self.core.take_event() {
            self.trace(event);
        }
    }

    fn trace(&mut self, event: Event) {
        let Some(f) = self.observer.as_mut() else {
            return;
        };
        match event {
            Event::Sent { attempt } => f(&TraceEvent::Sent {
                attempt,
                bytes: self.core.sent(),
            }),
            Event::Received { attempt, rejected } => {
                let reason = rejected.map(|r| r.to_string());
                f(&TraceEvent::Received {
                    attempt,
                    bytes: self.core.reply(),
                    rejected: reason.as_deref(),
                })
            }
            Event::NoReply { attempt } => f(&TraceEvent::NoReply { attempt }),
            Event::Discarded => f(&TraceEvent::Discarded {
                bytes: self.core.reply(),
            }),
        }
    }

    /// Sends `request` to `address` and returns the paired reply.
    pub fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Exchange<P::Response>, LinkError> {
        self.core.start(address, request);
        let reply = self.run()?;
        Ok(exchange(&self.core, reply))
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
        self.core.start_checked(address, trigger);
        let reply = self.run()?;
        Ok(exchange(&self.core, reply))
    }

    /// Like [`Master::transact`] for a request that must be answered: the response itself.
    pub fn ask(&mut self, address: u8, request: P::Request) -> Result<P::Response, LinkError> {
        let ex = self.transact(address, request)?;
        ex.response
            .ok_or_else(|| LinkError::unanswered::<P>(&request, address))
    }

    /// Runs a movement to its end ([`Movement`]): the byte-order check before its trigger
    /// ([`Master::check_byte_order`]), then its transactions and sleeps, reporting progress
    /// (the core's movement loop, [`movement::run`]).
    pub fn run_to_end<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<MoveReport<P::Response>, LinkError> {
        movement::run(&mut Steps(self), address, movement, |m| {
            progress(Progress::Moving {
                elapsed: m.elapsed,
                position: m.position,
            })
        })
    }
}

/// The master as the movement loop borrows it ([`Drive`]).
struct Steps<'a, P: Link, T: Transport, C: Clock, const CAP: usize>(&'a mut Master<P, T, C, CAP>);

impl<P: Link, T: Transport, C: Clock, const CAP: usize> Drive<P> for Steps<'_, P, T, C, CAP> {
    type Error = LinkError;

    fn now(&mut self) -> Duration {
        self.0.clock.now()
    }

    fn check_byte_order(&mut self, address: u8, trigger: P::Request) -> Result<(), LinkError> {
        self.0.check_byte_order(address, &trigger).map(|_| ())
    }

    fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, LinkError> {
        Ok(self.0.transact(address, request)?.response)
    }

    fn sleep_until(&mut self, until: Duration) {
        self.0.clock.sleep_until(until)
    }
}

impl<P: Link> MovementError<P> for LinkError {
    /// Any failure: a position read that fails is only a position not shown.
    fn skippable(&self) -> bool {
        true
    }

    fn unanswered(address: u8, request: P::Request) -> LinkError {
        LinkError::unanswered::<P>(&request, address)
    }

    fn stopped(address: u8, e: MoveError<P>) -> LinkError {
        move_error(address, e)
    }
}

/// The core's failure as a [`LinkError`], with names and texts (every driver reports through it).
pub(crate) fn link_error<P: Link, const CAP: usize>(
    core: &mut MasterCore<P, CAP>,
    failure: Failure<P>,
) -> LinkError {
    let timeout = core.timing().reply_timeout;
    match failure {
        Failure::Encode { request, source } => LinkError::Encode {
            request: request.name(),
            source,
        },
        Failure::Address {
            request,
            address,
            problem,
        } => LinkError::Address {
            protocol: P::name(),
            request: request.name(),
            address,
            reason: match problem {
                AddressProblem::NoBroadcast => {
                    "this command does not accept the broadcast address".to_owned()
                }
                AddressProblem::NotDevice => format!(
                    "not a device address (0x{:02X}..=0x{:02X}{})",
                    P::device_addresses().start(),
                    P::device_addresses().end(),
                    match P::broadcast_address() {
                        Some(b) => format!(", or broadcast 0x{b:02X}"),
                        None => String::new(),
                    }
                ),
            },
        },
        Failure::NoReply {
            request,
            address,
            attempts,
        } => LinkError::NoReply {
            protocol: P::name(),
            request: request.name(),
            address,
            attempts,
            timeout,
        },
        Failure::BadReply {
            request,
            address,
            attempts,
            reason,
        } => LinkError::BadReply {
            protocol: P::name(),
            request: request.name(),
            address,
            attempts,
            reason: reason.to_string(),
            bytes: core.reply().to_vec(),
        },
        Failure::Collision {
            request,
            address,
            attempts,
            offset,
            expected,
            received,
        } => LinkError::Collision {
            protocol: P::name(),
            request: request.name(),
            address,
            attempts,
            sent: core.sent().to_vec(),
            offset,
            expected,
            received,
        },
        Failure::NoEcho {
            request,
            address,
            attempts,
            received,
        } => LinkError::NoEcho {
            protocol: P::name(),
            request: request.name(),
            address,
            attempts,
            sent: core.sent().to_vec(),
            received,
        },
        Failure::ProbeRefused { request, address } => {
            let replies = core.probe_replies();
            let names: Vec<&str> = replies.iter().map(Message::name).collect();
            LinkError::Refused {
                protocol: P::name(),
                request: request.name(),
                address,
                response: replies.first().map_or("nothing", Message::name),
                detail: format!(
                    "not sent: the byte-order check before the first movement read {} \
                     to {}",
                    names.join(", "),
                    P::byte_order_probe()
                        .iter()
                        .map(Message::name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }
        }
        Failure::ByteOrder {
            request,
            address,
            swapped_fits,
        } => {
            let check = core
                .take_byte_order_check()
                .unwrap_or_else(|| ByteOrderCheck {
                    read: Default::default(),
                    swapped: Default::default(),
                    rule: Default::default(),
                    declared_fits: false,
                    swapped_fits,
                    erratum: "",
                });
            LinkError::ByteOrder {
                protocol: P::name(),
                request: request.name(),
                address,
                check: Box::new(check),
                source: byte_order_source::<P>(),
                declared: declared_byte_order::<P>(),
                other: swapped_byte_order::<P>(),
            }
        }
    }
}

/// A movement's stop as a [`LinkError`] (every driver reports through it).
fn move_error<P: Link>(address: u8, e: MoveError<P>) -> LinkError {
    match e {
        MoveError::NotATrigger { request } => LinkError::Refused {
            protocol: P::name(),
            request: request.name(),
            address,
            response: "nothing",
            detail: "not a movement trigger with a completion check".to_owned(),
        },
        MoveError::Refused {
            request,
            response,
            detail,
        } => LinkError::Refused {
            protocol: P::name(),
            request: request.name(),
            address,
            response: response.name(),
            detail: detail.to_owned(),
        },
        MoveError::Timeout { request, waited } => LinkError::MovementTimeout {
            protocol: P::name(),
            request: request.name(),
            address,
            waited,
        },
    }
}

/// A completed transaction of the core as an [`Exchange`].
pub(crate) fn exchange<P: Link, const CAP: usize>(
    core: &MasterCore<P, CAP>,
    reply: Reply<P>,
) -> Exchange<P::Response> {
    Exchange {
        response: reply.response,
        address: reply.address,
        attempts: reply.attempts,
        frame: if reply.response.is_some() {
            core.reply().to_vec()
        } else {
            Vec::new()
        },
        sent: core.sent().to_vec(),
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
