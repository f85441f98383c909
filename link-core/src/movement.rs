//! Movements polled to completion, as a sequence of transactions: sans-IO like the master.
//!
//! A movement says what to do next ([`Step`]): ask a request (one transaction of the
//! master; a driver runs it and hands back the response), sleep until a time, or stop with a
//! report or a refusal. The movements of particular devices are theirs: `busspec-devices` has
//! the UB2 movement (trigger, completion check, position reads) and the SD move (set point,
//! position reads).
//!
//! A driver runs one so: [`Movement::trigger`] names the trigger, for the byte-order check
//! the master makes before a first movement ([`crate::MasterCore::start_byte_order_check`]);
//! then [`Movement::next`] and [`Movement::answered`] until [`Step::Done`] or
//! [`Step::Failed`].

use core::time::Duration;

use crate::link::Link;

/// Where a movement is, for display: `position` in the protocol's unit (UB2 full steps, SD
/// degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moving {
    pub elapsed: Duration,
    pub position: f64,
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

/// Why a movement stopped without a report.
#[derive(Debug, Clone, PartialEq)]
pub enum MoveError<P: Link> {
    /// The request is not a movement trigger with a completion check.
    NotATrigger { request: P::Request },
    /// The device answered `request` with `response`, which the movement cannot go on with.
    Refused {
        request: P::Request,
        response: P::Response,
        detail: &'static str,
    },
    /// Not done within the limit.
    Timeout {
        request: P::Request,
        waited: Duration,
    },
}

/// What a movement needs done next.
#[derive(Debug, Clone, PartialEq)]
pub enum Step<P: Link> {
    /// Run this transaction and hand its response to [`Movement::answered`]. An `optional`
    /// one may fail (hand back `None`); any other failure ends the movement.
    Ask {
        request: P::Request,
        optional: bool,
    },
    /// Report `progress` if any, wait until `until`, then [`Movement::next`].
    Sleep {
        until: Duration,
        progress: Option<Moving>,
    },
    Done(MoveReport<P::Response>),
    Failed(MoveError<P>),
}

/// A movement as a sequence of transactions.
pub trait Movement<P: Link> {
    /// The request that starts the movement, to check the byte order for before it is sent.
    fn trigger(&self) -> Result<P::Request, MoveError<P>>;
    /// The first step (the trigger), or the next one after a sleep.
    fn next(&mut self, now: Duration) -> Step<P>;
    /// The response to the last [`Step::Ask`] (`None`: an optional one failed).
    fn answered(&mut self, now: Duration, response: Option<P::Response>) -> Step<P>;
}
