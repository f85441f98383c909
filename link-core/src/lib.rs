//! busspec-link-core: the bus master of busspec without I/O, for `no_std` firmware and any
//! host runtime.
//!
//! - [`master::MasterCore`]: the sans-IO master. Every rule of a transaction (gap, timeouts,
//!   settle, pairing, safe retries, freshness counters, broadcasts, the byte-order check before
//!   a first movement) as a state machine that says what to do next and takes bytes and time.
//!   No allocation, no clock, no I/O.
//! - [`link::Link`]: what a master adds to a generated protocol beyond its spec. The crate
//!   names no protocol: `busspec-devices` implements it for UB2 and SD, a user's crate for its
//!   own.
//! - [`movement`]: movements polled to completion, as a sequence of transactions: the
//!   [`movement::Movement`] trait (`busspec-devices` has the UB2 movement and the SD move),
//!   and the movement loop every driver runs them through, once per kind of driver:
//!   [`movement::run`] (blocking) and [`movement::run_async`].
//! - [`line::Line`]: baud rate, frame bits and the RS485 habits of a port (local echo,
//!   driver-enable timing, turnaround).
//! - Drivers, each behind a feature: `embedded-io` (`blocking::Driver`) and
//!   `embedded-io-async` (`nonblocking::Driver`), sharing `driver` (the `Now` time source,
//!   errors, `NoPin`). The `std` and tokio drivers live in `busspec-link`.
#![no_std]
#![forbid(unsafe_code)]

pub mod line;
pub mod link;
pub mod master;
pub mod movement;

#[cfg(feature = "embedded-io")]
pub mod blocking;
#[cfg(any(feature = "embedded-io", feature = "embedded-io-async"))]
pub mod driver;
#[cfg(feature = "embedded-io-async")]
pub mod nonblocking;

pub use busspec_runtime::{Message, Protocol};
pub use line::{DriverEnable, Line};
pub use link::{Link, Plain};
pub use master::{Action, Event, Failure, MasterCore, Reply, Timing};
