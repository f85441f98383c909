//! The async `embedded-io-async` driver (feature `embedded-io-async`): [`MasterCore`](crate::MasterCore) over a
//! UART that implements [`Read`] + [`Write`] + [`ReadReady`] (embassy's buffered UARTs do),
//! timed by a [`Now`] and an `embedded-hal-async` [`DelayNs`], with an optional
//! driver-enable [`OutputPin`].
//!
//! A read never waits past its deadline: the driver looks at [`ReadReady`] and awaits the
//! delay for one byte time (or what is left) in between, so the executor runs other tasks
//! meanwhile and the UART needs no timeout support.

use core::time::Duration;

use embedded_hal::digital::{Error as _, OutputPin};
use embedded_hal_async::delay::DelayNs;
use embedded_io_async::{Read, ReadReady, Write};

use crate::driver::{nanos, tick, Async, Error, NoPin, Now};
use crate::link::Link;
use crate::master::{Action, Reply, RX};
use crate::movement::{run_async, DriveAsync, MoveReport, Movement, Moving};

/// An async master for protocol `P` on the UART `U` (builders: [`crate::driver::Driver`]).
pub type Driver<P, U, N, D, DE = NoPin, const CAP: usize = RX> =
    crate::driver::Driver<P, U, N, D, DE, Async, CAP>;

impl<P: Link, U, N, D, DE, const CAP: usize> Driver<P, U, N, D, DE, CAP>
where
    U: Read + Write + ReadReady,
    N: Now,
    D: DelayNs,
    DE: OutputPin,
{
    /// Sends `request` to `address` and returns the paired reply.
    pub async fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Reply<P>, Error<P, U::Error>> {
        self.core.start(address, request);
        self.run().await
    }

    /// Sends a movement trigger after the byte-order check before a first movement.
    pub async fn start_movement(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<Reply<P>, Error<P, U::Error>> {
        self.core.start_checked(address, trigger);
        self.run().await
    }

    /// Runs a movement to its end: the byte-order check before its trigger, then its
    /// transactions and sleeps; `progress` hears where the device is in between
    /// ([`run_async`]).
    pub async fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
        progress: impl FnMut(Moving),
    ) -> Result<MoveReport<P::Response>, Error<P, U::Error>> {
        run_async(&mut Steps(self), address, movement, progress).await
    }

    async fn run(&mut self) -> Result<Reply<P>, Error<P, U::Error>> {
        let mut chunk = [0u8; 64];
        loop {
            let now = self.now.now();
            let line = self.core.line();
            match self.core.poll(now) {
                Action::Done => break,
                Action::Sleep(t) => {
                    let mut now = now;
                    while now < t {
                        self.delay.delay_ns(nanos(t - now)).await;
                        now = self.now.now();
                    }
                }
                Action::ClearInput => {
                    while self.uart.read_ready().map_err(Error::Io)? {
                        if self.uart.read(&mut chunk).await.map_err(Error::Io)? == 0 {
                            break;
                        }
                    }
                }
                Action::EnableDriver => self.de.set_high().map_err(|e| Error::Pin(e.kind()))?,
                Action::DisableDriver => self.de.set_low().map_err(|e| Error::Pin(e.kind()))?,
                Action::Write(bytes) => {
                    self.uart.write_all(bytes).await.map_err(Error::Io)?;
                    self.uart.flush().await.map_err(Error::Io)?;
                }
                Action::Read { until } => loop {
                    if self.uart.read_ready().map_err(Error::Io)? {
                        let n = self.uart.read(&mut chunk).await.map_err(Error::Io)?;
                        self.core.received(&chunk[..n], self.now.now());
                        break;
                    }
                    let now = self.now.now();
                    if now >= until {
                        break;
                    }
                    self.delay.delay_ns(tick(&line, until - now)).await;
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

/// The driver as the movement loop borrows it ([`DriveAsync`]).
struct Steps<'a, P: Link, U, N, D, DE, const CAP: usize>(&'a mut Driver<P, U, N, D, DE, CAP>);

impl<P: Link, U, N, D, DE, const CAP: usize> DriveAsync<P> for Steps<'_, P, U, N, D, DE, CAP>
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

    async fn check_byte_order(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<(), Self::Error> {
        self.0.core.start_byte_order_check(address, trigger);
        self.0.run().await.map(|_| ())
    }

    async fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, Self::Error> {
        Ok(self.0.transact(address, request).await?.response)
    }

    async fn sleep_until(&mut self, until: Duration) {
        // The same wait as `run`'s for `Action::Sleep`, which keeps its own copy inline: an
        // awaited helper there made the firmware example's .text 56 to 148 bytes larger
        // (thumbv7em, `--profile firmware`).
        let mut now = self.0.now.now();
        while now < until {
            self.0.delay.delay_ns(nanos(until - now)).await;
            now = self.0.now.now();
        }
    }
}
