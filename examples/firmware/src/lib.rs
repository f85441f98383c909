//! A firmware-style set-point loop: an MCU driving SD actuators over RS485 through
//! `busspec-link-core`'s `embedded-io-async` driver. `no_std`, no allocation.
//!
//! [`set_point_loop`] sends one set point per target (the master fills in the freshness
//! counter, starting from the actuator's own view of it, SD §3.1 and §3.12), then reads the
//! actuator's skipped-frames counter: zero when every set point carried the next counter.
//! `src/main.rs` is the same loop on a thumbv7em board shape (CI builds it for the target);
//! `busspec-link`'s `tests/firmware.rs` runs it against the SD simulator on the host.
//!
//! [`modbus`] is the Modbus RTU master variant: any protocol's master from its spec alone.
#![no_std]
#![forbid(unsafe_code)]

pub mod modbus;

use busspec_devices::protocols::sd;
use busspec_devices::Sd;
use busspec_link_core::driver::{Error, Now};
use busspec_link_core::nonblocking::Driver;
use embedded_hal_async::delay::DelayNs;
use embedded_io_async::{Read, ReadReady, Write};

/// What the loop saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Report {
    /// Set points answered.
    pub answered: u32,
    /// The freshness counter the last set point carried.
    pub last_freshness: Option<u8>,
    /// The actuator's count of skipped frames at the end (SD §3.12).
    pub dropped_frames: u8,
    /// The host freshness counter the actuator saw last.
    pub host_freshness: u8,
}

/// Sends a set point to `address` for each of `targets` (in 360/4096 degree counts), then reads
/// the actuator's skipped-frames counter. `CAP` is the driver's receive buffer in bytes.
pub async fn set_point_loop<U, N, D, DE, const CAP: usize>(
    driver: &mut Driver<Sd, U, N, D, DE, CAP>,
    address: u8,
    targets: &[i16],
) -> Result<Report, Error<Sd, U::Error>>
where
    U: Read + Write + ReadReady,
    N: Now,
    D: DelayNs,
    DE: embedded_hal::digital::OutputPin,
{
    let mut report = Report {
        answered: 0,
        last_freshness: None,
        dropped_frames: 0,
        host_freshness: 0,
    };
    for &target in targets {
        let request = sd::Request::SetPoint(sd::request::SetPoint {
            // The master puts the next counter here.
            freshness: 0,
            position: sd::Angle(target),
        });
        let reply = driver.transact(address, request).await?;
        if reply.response.is_some() {
            report.answered += 1;
        }
        report.last_freshness = driver
            .core()
            .next_freshness_value(address)
            .map(|next| next.wrapping_add(15) % 16);
    }
    let reply = driver
        .transact(
            address,
            sd::Request::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter),
        )
        .await?;
    if let Some(sd::Response::SkippedFramesCounter(sd::response::SkippedFramesCounter {
        host_freshness_counter,
        dropped_frames,
    })) = reply.response
    {
        report.dropped_frames = dropped_frames;
        report.host_freshness = host_freshness_counter;
    }
    Ok(report)
}
