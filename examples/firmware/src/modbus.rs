//! The Modbus RTU master variant: an MCU polling a Modbus device over RS485 through
//! `busspec-link-core`'s `embedded-io-async` driver, with no code of its own for Modbus: the
//! generated codec run by its spec through [`Plain`] (response timeout, turnaround, t3.5 gap at
//! the line's baud rate, retries of reads only, exceptions as refusals). `no_std`, no
//! allocation.
//!
//! [`poll_and_count`] reads a block of holding registers, adds one to the first (a write the
//! device echoes) and reads it back. `src/bin/modbus_master.rs` is the same on the thumbv7em
//! board shape (CI builds it for the target); `busspec-link`'s `tests/firmware.rs` runs it on
//! the host against a device simulated from the spec's `device:` section.

use busspec_link_core::driver::{Error, Now};
use busspec_link_core::nonblocking::Driver;
use busspec_link_core::Plain;
use busspec_protocols::modbus::{self, Modbus};
use embedded_hal_async::delay::DelayNs;
use embedded_io_async::{Read, ReadReady, Write};

/// The most registers one poll reads.
pub const MAX_REGISTERS: usize = 16;

/// What one poll saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModbusReport {
    /// The registers read first, `count` of them.
    pub before: [u16; MAX_REGISTERS],
    pub count: usize,
    /// The first register as read back after the write.
    pub after: u16,
    /// The device refused a request with an exception (its code), if it did.
    pub exception: Option<u8>,
}

/// Reads `count` (1 to [`MAX_REGISTERS`]) holding registers from `start`, writes the first one
/// plus one, and reads it back.
pub async fn poll_and_count<U, N, D, DE>(
    driver: &mut Driver<Plain<Modbus>, U, N, D, DE>,
    address: u8,
    start: u16,
    count: usize,
) -> Result<ModbusReport, Error<Plain<Modbus>, U::Error>>
where
    U: Read + Write + ReadReady,
    N: Now,
    D: DelayNs,
    DE: embedded_hal::digital::OutputPin,
{
    let count = count.clamp(1, MAX_REGISTERS);
    let mut report = ModbusReport {
        before: [0; MAX_REGISTERS],
        count,
        after: 0,
        exception: None,
    };
    let read = |quantity: usize| {
        modbus::Request::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
            starting_address: start,
            quantity: quantity as u16,
        })
    };
    let reply = driver.transact(address, read(count)).await?;
    match reply.response {
        Some(modbus::Response::ReadHoldingRegistersReply(
            modbus::response::ReadHoldingRegistersReply { registers, .. },
        )) => {
            for (slot, r) in report.before.iter_mut().zip(registers.iter()) {
                *slot = *r;
            }
        }
        Some(other) => {
            report.exception = exception(&other);
            return Ok(report);
        }
        None => return Ok(report),
    }
    let write = modbus::Request::WriteSingleRegister(modbus::request::WriteSingleRegister {
        register_address: start,
        register_value: report.before[0].wrapping_add(1),
    });
    let reply = driver.transact(address, write).await?;
    if let Some(r) = &reply.response {
        report.exception = exception(r);
    }
    let reply = driver.transact(address, read(1)).await?;
    if let Some(modbus::Response::ReadHoldingRegistersReply(
        modbus::response::ReadHoldingRegistersReply { registers, .. },
    )) = reply.response
    {
        report.after = registers.first().copied().unwrap_or(0);
    }
    Ok(report)
}

/// The exception code of an exception reply.
fn exception(r: &modbus::Response) -> Option<u8> {
    use modbus::{response, Response::*};
    match r {
        ReadHoldingRegistersException(response::ReadHoldingRegistersException {
            exception_code,
        })
        | WriteSingleRegisterException(response::WriteSingleRegisterException { exception_code }) => {
            Some(exception_code.raw())
        }
        _ => None,
    }
}
