//! What the `embedded-io` and `embedded-io-async` drivers share: the driver itself (its
//! parts and their builders; [`Blocking`] or [`Async`] decides which traits its UART and delay
//! need and which `transact` it has), a time source, the error type, a stand-in for a missing
//! driver-enable pin, and how long to wait between looks at the UART.

use core::fmt;
use core::marker::PhantomData;
use core::time::Duration;

use embedded_hal::digital::{ErrorKind, ErrorType, OutputPin};

use crate::line::Line;
use crate::link::Link;
use crate::master::{Failure, MasterCore, Timing, RX};
use crate::movement::{MoveError, MovementError};

/// A monotonic time source: time since any fixed epoch (a free-running timer).
pub trait Now {
    fn now(&self) -> Duration;
}

impl<N: Now + ?Sized> Now for &N {
    fn now(&self) -> Duration {
        (**self).now()
    }
}

/// No driver-enable line (the transceiver switches by itself, or the line is full duplex).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoPin;

impl ErrorType for NoPin {
    type Error = core::convert::Infallible;
}

impl OutputPin for NoPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// What a driver's transaction can end in besides a reply.
#[derive(Debug, Clone, PartialEq)]
pub enum Error<P: Link, E> {
    /// The UART failed.
    Io(E),
    /// The driver-enable pin failed.
    Pin(ErrorKind),
    /// The transaction failed by the master's rules.
    Link(Failure<P>),
    /// A movement stopped: refused, or not done in time.
    Move(MoveError<P>),
    /// A movement's request went to the broadcast address, which does not answer.
    Unanswered,
}

impl<P: Link, E: fmt::Debug> fmt::Display for Error<P, E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io(e) => write!(f, "{} UART: {e:?}", P::NAME),
            Error::Pin(e) => write!(f, "{} driver-enable pin: {e:?}", P::NAME),
            Error::Link(e) => write!(f, "{} transaction: {e:?}", P::NAME),
            Error::Move(e) => write!(f, "{} movement: {e:?}", P::NAME),
            Error::Unanswered => write!(f, "{} movement: a broadcast is not answered", P::NAME),
        }
    }
}

impl<P: Link, E> MovementError<P> for Error<P, E> {
    /// A transaction the master's rules failed (no reply, a bad one); not the UART's or the pin's.
    fn skippable(&self) -> bool {
        matches!(self, Error::Link(_))
    }

    fn unanswered(_address: u8, _request: P::Request) -> Self {
        Error::Unanswered
    }

    fn stopped(_address: u8, e: MoveError<P>) -> Self {
        Error::Move(e)
    }
}

/// How long to wait before looking at the UART again: one byte time, or what is left.
pub(crate) fn tick(line: &Line, left: Duration) -> u32 {
    let byte = line.tx_time(1).max(Duration::from_micros(10));
    u32::try_from(left.min(byte).as_nanos())
        .unwrap_or(u32::MAX)
        .max(1)
}

/// Nanoseconds to wait, at most `u32::MAX` (about 4.3 s) at a time.
pub(crate) fn nanos(left: Duration) -> u32 {
    u32::try_from(left.as_nanos()).unwrap_or(u32::MAX).max(1)
}

/// The blocking kind of [`Driver`]: `embedded-io` and `embedded-hal` (`crate::blocking`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Blocking;

/// The async kind of [`Driver`]: `embedded-io-async` and `embedded-hal-async`
/// (`crate::nonblocking`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Async;

/// A master for protocol `P` on the UART `U`, timed by `N` and `D`, with the driver-enable
/// pin `DE`; `M` is [`Blocking`] or [`Async`] (use `blocking::Driver` or
/// `nonblocking::Driver`); `CAP` is its core's receive buffer in bytes ([`MasterCore`]).
pub struct Driver<P: Link, U, N, D, DE, M, const CAP: usize = RX> {
    pub(crate) core: MasterCore<P, CAP>,
    pub(crate) uart: U,
    pub(crate) now: N,
    pub(crate) delay: D,
    pub(crate) de: DE,
    _kind: PhantomData<M>,
}

impl<P: Link, U, N: Now, D, M, const CAP: usize> Driver<P, U, N, D, NoPin, M, CAP> {
    /// A driver with the protocol's timing and line, and no driver-enable pin.
    pub fn new(uart: U, now: N, delay: D) -> Self {
        Driver {
            core: MasterCore::new(),
            uart,
            now,
            delay,
            de: NoPin,
            _kind: PhantomData,
        }
    }
}

impl<P: Link, U, N: Now, D, DE, M, const CAP: usize> Driver<P, U, N, D, DE, M, CAP> {
    /// Drives `pin` as the transceiver's driver-enable line; set [`Line::driver_enable`] too.
    pub fn with_driver_enable<E: OutputPin>(self, pin: E) -> Driver<P, U, N, D, E, M, CAP> {
        Driver {
            core: self.core,
            uart: self.uart,
            now: self.now,
            delay: self.delay,
            de: pin,
            _kind: PhantomData,
        }
    }

    pub fn with_timing(mut self, timing: Timing) -> Self {
        self.core.set_timing(timing);
        self
    }

    pub fn with_line(mut self, line: Line) -> Self {
        self.core.set_line(line);
        self
    }

    /// The sans-IO core: freshness counters, byte-order checks, the last frames.
    pub fn core(&self) -> &MasterCore<P, CAP> {
        &self.core
    }

    pub fn core_mut(&mut self) -> &mut MasterCore<P, CAP> {
        &mut self.core
    }

    /// The UART, the time source, the delay and the pin back.
    pub fn release(self) -> (U, N, D, DE) {
        (self.uart, self.now, self.delay, self.de)
    }
}
