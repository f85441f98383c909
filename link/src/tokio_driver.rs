//! The tokio driver of [`MasterCore`] (feature `tokio`): the same transactions as
//! [`crate::Master`], awaited instead of blocked on, so a service can talk to its devices next
//! to its other I/O and poll several ports concurrently.
//!
//! Any [`AsyncPort`] works: a `tokio_serial::SerialStream` (a serial port, or one end of a
//! pseudo-terminal pair), or a stream of a test's own. Time is tokio's: [`tokio::time`]
//! (so `tokio::time::pause` makes tests run in virtual time).

use std::io;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::Instant;

use busspec_link_core::master::{Action, MasterCore, RX};
use busspec_link_core::{Line, Link};

use busspec_link_core::movement::{run_async, DriveAsync, MoveReport, Movement, Moving};

use crate::master::{exchange, link_error, Exchange, LinkError, Timing};

/// A byte stream a tokio master drives: reads and writes, plus what a serial port does
/// beyond them.
pub trait AsyncPort: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin {
    /// Discards bytes received but not yet read.
    fn clear_input(&mut self) -> io::Result<()>;
    /// Drives the RS485 driver-enable line, where the port has one; nothing by default.
    fn set_driver_enable(&mut self, _on: bool) -> io::Result<()> {
        Ok(())
    }
}

impl AsyncPort for tokio_serial::SerialStream {
    fn clear_input(&mut self) -> io::Result<()> {
        tokio_serial::SerialPort::clear(self, tokio_serial::ClearBuffer::Input)
            .map_err(|e| io::Error::other(e.to_string()))
    }

    /// RTS as the driver-enable line.
    fn set_driver_enable(&mut self, on: bool) -> io::Result<()> {
        tokio_serial::SerialPort::write_request_to_send(self, on)
            .map_err(|e| io::Error::other(e.to_string()))
    }
}

/// A bus master for protocol `P` on the async port `S`.
pub struct AsyncMaster<P: Link, S: AsyncPort, const CAP: usize = RX> {
    port: S,
    core: MasterCore<P, CAP>,
    epoch: Instant,
}

impl<P: Link, S: AsyncPort, const CAP: usize> AsyncMaster<P, S, CAP> {
    pub fn new(port: S) -> Self {
        AsyncMaster {
            port,
            core: MasterCore::new(),
            epoch: Instant::now(),
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

    /// The sans-IO core: freshness counters, byte-order checks, timing.
    pub fn core_mut(&mut self) -> &mut MasterCore<P, CAP> {
        &mut self.core
    }

    /// Sends `request` to `address` and returns the paired reply.
    pub async fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Exchange<P::Response>, LinkError> {
        self.core.start(address, request);
        self.run().await
    }

    /// Sends a movement trigger after the byte-order check before a first movement.
    pub async fn start_movement(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<Exchange<P::Response>, LinkError> {
        self.core.start_checked(address, trigger);
        self.run().await
    }

    /// Like [`AsyncMaster::transact`] for a request that must be answered: the response.
    pub async fn ask(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<P::Response, LinkError> {
        let ex = self.transact(address, request).await?;
        ex.response
            .ok_or_else(|| LinkError::unanswered::<P>(&request, address))
    }

    /// Runs a movement to its end: the byte-order check before its trigger, then its
    /// transactions and sleeps; `progress` hears where the device is in between (the core's
    /// movement loop, [`run_async`]).
    pub async fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
        progress: impl FnMut(Moving),
    ) -> Result<MoveReport<P::Response>, LinkError> {
        run_async(&mut Steps(self), address, movement, progress).await
    }

    async fn run(&mut self) -> Result<Exchange<P::Response>, LinkError> {
        let io = |context: &str, source: io::Error| LinkError::Io {
            context: format!("{} {context}", P::name()),
            source,
        };
        let mut chunk = [0u8; 64];
        loop {
            let now = self.epoch.elapsed();
            match self.core.poll(now) {
                Action::Done => break,
                Action::Sleep(t) => tokio::time::sleep_until(self.epoch + t).await,
                Action::ClearInput => self.port.clear_input().map_err(|e| io("clear input", e))?,
                Action::EnableDriver => self
                    .port
                    .set_driver_enable(true)
                    .map_err(|e| io("raise driver enable", e))?,
                Action::DisableDriver => self
                    .port
                    .set_driver_enable(false)
                    .map_err(|e| io("lower driver enable", e))?,
                Action::Write(bytes) => {
                    self.port
                        .write_all(bytes)
                        .await
                        .map_err(|e| io("write", e))?;
                    self.port.flush().await.map_err(|e| io("write", e))?;
                }
                Action::Read { until } => {
                    let read = self.port.read(&mut chunk);
                    match tokio::time::timeout_at(self.epoch + until, read).await {
                        Err(_elapsed) => {}
                        Ok(Ok(0)) => {
                            return Err(io(
                                "read",
                                io::Error::new(io::ErrorKind::UnexpectedEof, "the port closed"),
                            ))
                        }
                        Ok(Ok(n)) => self.core.received(&chunk[..n], self.epoch.elapsed()),
                        Ok(Err(e)) => return Err(io("read", e)),
                    }
                }
            }
            // Events are for observers; this driver has none.
            while self.core.take_event().is_some() {}
        }
        match self.core.take_outcome() {
            Some(Ok(reply)) => Ok(exchange(&self.core, reply)),
            Some(Err(failure)) => Err(link_error(&mut self.core, failure)),
            None => unreachable!("the core says Done only with an outcome"),
        }
    }
}

/// The driver as the movement loop borrows it ([`DriveAsync`]).
struct Steps<'a, P: Link, S: AsyncPort, const CAP: usize>(&'a mut AsyncMaster<P, S, CAP>);

impl<P: Link, S: AsyncPort, const CAP: usize> DriveAsync<P> for Steps<'_, P, S, CAP> {
    type Error = LinkError;

    fn now(&mut self) -> Duration {
        self.0.epoch.elapsed()
    }

    async fn check_byte_order(
        &mut self,
        address: u8,
        trigger: P::Request,
    ) -> Result<(), LinkError> {
        self.0.core.start_byte_order_check(address, trigger);
        self.0.run().await.map(|_| ())
    }

    async fn transact(
        &mut self,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, LinkError> {
        Ok(self.0.transact(address, request).await?.response)
    }

    async fn sleep_until(&mut self, until: Duration) {
        tokio::time::sleep_until(self.0.epoch + until).await
    }
}
