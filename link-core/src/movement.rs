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

/// A driver's error as the movement loop words and weighs it: shared by a driver's blocking
/// and async kinds ([`Drive::Error`], [`DriveAsync::Error`]).
pub trait MovementError<P: Link>: Sized {
    /// Whether an optional request that failed with this may be passed over: a failure of the
    /// line, not of the port.
    fn skippable(&self) -> bool;
    /// `request`, whose answer the movement needs, went to `address` and nothing answers there.
    fn unanswered(address: u8, request: P::Request) -> Self;
    /// The movement stopped: refused, or not done in time.
    fn stopped(address: u8, e: MoveError<P>) -> Self;
}

/// What a blocking driver lends [`run`]: its transactions, its time and its waits, and its
/// error ([`MovementError`]). Each driver implements it once (the embedded-io driver here,
/// `busspec-link`'s `std` master), and its `run_movement` is [`run`].
pub trait Drive<P: Link> {
    /// What the driver's movement ends in besides a report.
    type Error: MovementError<P>;
    /// Time since the driver's epoch.
    fn now(&mut self) -> Duration;
    /// The byte-order check before the first movement to `address`, for `trigger`
    /// ([`crate::MasterCore::start_byte_order_check`]).
    fn check_byte_order(&mut self, address: u8, trigger: P::Request) -> Result<(), Self::Error>;
    /// One transaction: the reply, or `None` where the request went unanswered (a broadcast).
    fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, Self::Error>;
    /// Waits until `until` (driver time).
    fn sleep_until(&mut self, until: Duration);
}

/// [`Drive`] for an async driver: the same, with the transactions and waits awaited. Each
/// async driver implements it once (the embedded-io-async driver here, `busspec-link`'s tokio
/// driver), and its `run_movement` is [`run_async`].
// The futures are the drivers' own: a tokio driver's are `Send`, an embedded one's need not be,
// and a caller that names a concrete driver sees which.
#[allow(async_fn_in_trait)]
pub trait DriveAsync<P: Link> {
    /// See [`Drive::Error`].
    type Error: MovementError<P>;
    /// See [`Drive::now`].
    fn now(&mut self) -> Duration;
    /// See [`Drive::check_byte_order`].
    async fn check_byte_order(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<(), Self::Error>;
    /// See [`Drive::transact`].
    async fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, Self::Error>;
    /// See [`Drive::sleep_until`].
    async fn sleep_until(&mut self, until: Duration);
}

/// Runs `movement` to its end on a blocking driver: the byte-order check before its trigger,
/// then its transactions and sleeps; `progress` hears where the device is in between. The
/// movement loop of every blocking driver.
///
/// [`run_async`] is the same loop with `.await` after each transaction and wait: Rust has no
/// way yet to write one body for both (`async` closures and keyword generics are not in the
/// crate's Rust 1.81), so the two are kept line for line alike.
pub fn run<P: Link, D: Drive<P>, M: Movement<P>>(
    driver: &mut D,
    address: u8,
    mut movement: M,
    mut progress: impl FnMut(Moving),
) -> Result<MoveReport<P::Response>, D::Error> {
    let trigger = movement
        .trigger()
        .map_err(|e| D::Error::stopped(address, e))?;
    driver.check_byte_order(address, trigger)?;
    let mut step = movement.next(driver.now());
    loop {
        step = match step {
            Step::Ask { request, optional } => match driver.transact(address, request) {
                Ok(Some(r)) => movement.answered(driver.now(), Some(r)),
                Ok(None) if optional => movement.answered(driver.now(), None),
                Ok(None) => return Err(D::Error::unanswered(address, request)),
                Err(e) if optional && e.skippable() => movement.answered(driver.now(), None),
                Err(e) => return Err(e),
            },
            Step::Sleep {
                until,
                progress: moving,
            } => {
                if let Some(m) = moving {
                    progress(m);
                }
                driver.sleep_until(until);
                movement.next(driver.now())
            }
            Step::Done(report) => return Ok(report),
            Step::Failed(e) => return Err(D::Error::stopped(address, e)),
        }
    }
}

/// [`run`] on an async driver.
pub async fn run_async<P: Link, D: DriveAsync<P>, M: Movement<P>>(
    driver: &mut D,
    address: u8,
    mut movement: M,
    mut progress: impl FnMut(Moving),
) -> Result<MoveReport<P::Response>, D::Error> {
    let trigger = movement
        .trigger()
        .map_err(|e| D::Error::stopped(address, e))?;
    driver.check_byte_order(address, trigger).await?;
    let mut step = movement.next(driver.now());
    loop {
        step = match step {
            Step::Ask { request, optional } => match driver.transact(address, request).await {
                Ok(Some(r)) => movement.answered(driver.now(), Some(r)),
                Ok(None) if optional => movement.answered(driver.now(), None),
                Ok(None) => return Err(D::Error::unanswered(address, request)),
                Err(e) if optional && e.skippable() => movement.answered(driver.now(), None),
                Err(e) => return Err(e),
            },
            Step::Sleep {
                until,
                progress: moving,
            } => {
                if let Some(m) = moving {
                    progress(m);
                }
                driver.sleep_until(until).await;
                movement.next(driver.now())
            }
            Step::Done(report) => return Ok(report),
            Step::Failed(e) => return Err(D::Error::stopped(address, e)),
        }
    }
}
