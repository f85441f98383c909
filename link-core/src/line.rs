//! The wire a master sits on: baud rate and frame bits, and the habits of real RS485 wiring
//! the documents never mention.
//!
//! - **Local echo**: many two-wire adapters hear their own transmission. With
//!   [`Line::echo`] set, the master reads back exactly the bytes it just sent before it waits
//!   for a reply; an echo that differs is a collision on the bus
//!   ([`crate::master::Failure::Collision`], with the offset and both bytes).
//! - **Driver enable**: a half-duplex transceiver drives the bus only while its DE line is
//!   high. With [`Line::driver_enable`] set, the master raises it before the first byte and
//!   lowers it once the last byte has left the shift register: when the UART's flush says so
//!   ([`DriverEnable::Flushed`]), or at the time [`Line::tx_time`] computes from the baud rate
//!   and the frame bits ([`DriverEnable::Computed`]) when the UART cannot say.
//! - **Turnaround**: the time a device needs to switch its own transceiver before it can
//!   answer; the reply timeout starts after it ([`Line::turnaround`]).

use core::time::Duration;

use busspec_runtime::Protocol;

/// When the driver-enable line may drop after a transmission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriverEnable {
    /// The UART's flush returns once the last stop bit is out: drop the line right after it.
    Flushed,
    /// The UART cannot say: drop the line [`Line::tx_time`] after the write began.
    Computed,
}

/// The line parameters and RS485 habits of one port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Line {
    /// Bits per second.
    pub baud: u32,
    /// Bits one byte takes on the wire: start, data, parity and stop bits (10 for 8N1).
    pub bits_per_byte: u32,
    /// The adapter echoes every byte sent: read it back and compare before the reply.
    pub echo: bool,
    /// Drive a driver-enable line around each transmission, and how to time its end.
    pub driver_enable: Option<DriverEnable>,
    /// Time the device needs before its reply can start, added to the reply timeout; after a
    /// broadcast it does not answer, the quiet time before the next request.
    pub turnaround: Duration,
}

impl Line {
    /// The protocol's baud rate and character bits (8N1 unless its `transactions:` section
    /// says), its declared turnaround (none unless it says), no echo, no driver-enable line: a
    /// plain full-duplex port or a USB adapter that switches direction by itself.
    pub const fn for_protocol<P: Protocol>() -> Line {
        let turnaround = match P::BUS.transactions.turnaround_us {
            Some(us) => Duration::from_micros(us as u64),
            None => Duration::ZERO,
        };
        Line {
            baud: P::BUS.baud,
            bits_per_byte: P::BUS.transactions.character_bits,
            echo: false,
            driver_enable: None,
            turnaround,
        }
    }

    /// [`Line::for_protocol`] from what the master reads of the spec ([`crate::Link`]'s
    /// `baud` and `transactions`): the same line for a generated protocol, and the spec's for one
    /// read at run time.
    pub fn for_link<P: crate::Link>() -> Line {
        let t = P::transactions();
        let turnaround = match t.turnaround_us {
            Some(us) => Duration::from_micros(us as u64),
            None => Duration::ZERO,
        };
        Line {
            baud: P::baud(),
            bits_per_byte: t.character_bits,
            echo: false,
            driver_enable: None,
            turnaround,
        }
    }

    /// How long `bytes` bytes take on the wire, rounded up to the nanosecond.
    pub const fn tx_time(&self, bytes: usize) -> Duration {
        let bits = bytes as u64 * self.bits_per_byte as u64;
        let baud = if self.baud == 0 { 1 } else { self.baud as u64 };
        Duration::from_nanos((bits * 1_000_000_000).div_ceil(baud))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmission_time_follows_baud_and_frame_bits() {
        // UB2's line (`busspec-devices` checks `for_protocol` against its spec).
        let mut l = Line {
            baud: 19_200,
            bits_per_byte: 10,
            echo: false,
            driver_enable: None,
            turnaround: Duration::ZERO,
        };
        // 5 bytes × 10 bits at 19,200 baud: 2.604166.. ms, rounded up.
        assert_eq!(l.tx_time(5), Duration::from_nanos(2_604_167));
        l.bits_per_byte = 11; // 8E1
        assert_eq!(l.tx_time(5), Duration::from_nanos(2_864_584));
        assert_eq!(l.tx_time(0), Duration::ZERO);
    }
}
