//! The blocking `embedded-io` driver (feature `embedded-io`): [`MasterCore`](crate::MasterCore) over a UART that
//! implements [`Read`] + [`Write`] + [`ReadReady`], timed by a [`Now`] and an
//! `embedded-hal` [`DelayNs`], with an optional driver-enable [`OutputPin`].
//!
//! A read never blocks past its deadline: the driver looks at [`ReadReady`] and waits one byte
//! time (or what is left) in between, so it needs no UART timeout support.

use core::time::Duration;
use embedded_hal::delay::DelayNs;

use embedded_hal::digital::{Error as _, OutputPin};
use embedded_io::{Read, ReadReady, Write};

use crate::driver::{nanos, tick, Blocking, Error, NoPin, Now};
use crate::link::Link;
use crate::master::{Action, Reply, RX};
use crate::movement::{run, Drive, MoveReport, Movement, Moving};

/// A blocking master for protocol `P` on the UART `U` (builders: [`crate::driver::Driver`]).
pub type Driver<P, U, N, D, DE = NoPin, const CAP: usize = RX> =
    crate::driver::Driver<P, U, N, D, DE, Blocking, CAP>;

impl<P: Link, U, N, D, DE, const CAP: usize> Driver<P, U, N, D, DE, CAP>
where
    U: Read + Write + ReadReady,
    N: Now,
    D: DelayNs,
    DE: OutputPin,
{
    /// Sends `request` to `address` and returns the paired reply.
    pub fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Reply<P>, Error<P, U::Error>> {
        self.core.start(address, request);
        self.run()
    }

    /// Sends a movement trigger after the byte-order check before a first movement.
    pub fn start_movement(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<Reply<P>, Error<P, U::Error>> {
        self.core.start_checked(address, trigger);
        self.run()
    }

    /// Runs a movement to its end: the byte-order check before its trigger, then its
    /// transactions and sleeps; `progress` hears where the device is in between
    /// ([`run`]).
    pub fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
        progress: impl FnMut(Moving),
    ) -> Result<MoveReport<P::Response>, Error<P, U::Error>> {
        run(&mut Steps(self), address, movement, progress)
    }

    fn run(&mut self) -> Result<Reply<P>, Error<P, U::Error>> {
        let mut chunk = [0u8; 64];
        loop {
            let now = self.now.now();
            let line = self.core.line();
            match self.core.poll(now) {
                Action::Done => break,
                Action::Sleep(t) => {
                    let mut now = now;
                    while now < t {
                        self.delay.delay_ns(nanos(t - now));
                        now = self.now.now();
                    }
                }
                Action::ClearInput => {
                    while self.uart.read_ready().map_err(Error::Io)? {
                        if self.uart.read(&mut chunk).map_err(Error::Io)? == 0 {
                            break;
                        }
                    }
                }
                Action::EnableDriver => self.de.set_high().map_err(|e| Error::Pin(e.kind()))?,
                Action::DisableDriver => self.de.set_low().map_err(|e| Error::Pin(e.kind()))?,
                Action::Write(bytes) => {
                    self.uart.write_all(bytes).map_err(Error::Io)?;
                    self.uart.flush().map_err(Error::Io)?;
                }
                Action::Read { until } => loop {
                    if self.uart.read_ready().map_err(Error::Io)? {
                        let n = self.uart.read(&mut chunk).map_err(Error::Io)?;
                        self.core.received(&chunk[..n], self.now.now());
                        break;
                    }
                    let now = self.now.now();
                    if now >= until {
                        break;
                    }
                    self.delay.delay_ns(tick(&line, until - now));
                },
            }
        }
        while self.core.take_event().is_some() {}
        match self.core.take_outcome() {
            Some(Ok(reply)) => Ok(reply),
            Some(Err(failure)) => Err(Error::Link(failure)),
            None => unreachable!("the core says Done only with an outcome"),
        }
    }
}

/// The driver as the movement loop borrows it ([`Drive`]).
struct Steps<'a, P: Link, U, N, D, DE, const CAP: usize>(&'a mut Driver<P, U, N, D, DE, CAP>);

impl<P: Link, U, N, D, DE, const CAP: usize> Drive<P> for Steps<'_, P, U, N, D, DE, CAP>
where
    U: Read + Write + ReadReady,
    N: Now,
    D: DelayNs,
    DE: OutputPin,
{
    type Error = Error<P, U::Error>;

    fn now(&mut self) -> Duration {
        self.0.now.now()
    }

    fn check_byte_order(&mut self, address: u8, trigger: P::Request) -> Result<(), Self::Error> {
        self.0.core.start_byte_order_check(address, trigger);
        self.0.run().map(|_| ())
    }

    fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, Self::Error> {
        Ok(self.0.transact(address, request)?.response)
    }

    fn sleep_until(&mut self, until: Duration) {
        // The same wait as `run`'s for `Action::Sleep`, which keeps its own copy inline, as the
        // async driver's does (there a shared helper costs the firmware example flash).
        let mut now = self.0.now.now();
        while now < until {
            self.0.delay.delay_ns(nanos(until - now));
            now = self.0.now.now();
        }
    }
}
