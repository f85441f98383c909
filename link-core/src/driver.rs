//! What the `embedded-io` and `embedded-io-async` drivers share: a time source, the error
//! type, a stand-in for a missing driver-enable pin, and how long to wait between looks at
//! the UART.

use core::fmt;
use core::time::Duration;

use embedded_hal::digital::{ErrorKind, ErrorType, OutputPin};

use crate::line::Line;
use crate::link::Link;
use crate::master::Failure;
use crate::movement::MoveError;

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
