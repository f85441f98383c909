//! busspec-link: talk to the devices busspec's specs describe.
//!
//! - [`protocol::Link`]: what a master adds to a generated protocol beyond its spec (safe
//!   retries, reply address, checksum NAK, freshness counter, gap between requests), an
//!   extension of [`busspec_runtime::Protocol`]. This crate names no protocol:
//!   `busspec-devices` implements it for UB2 and SD, with their movements, readouts,
//!   simulators and soak mixes.
//! - [`master::Master`]: the transaction layer for any [`Link`] protocol over any
//!   [`transport::Transport`] — typed request out, paired typed response back, with the bus's
//!   rules (gap between commands, timeouts, safe retries, the freshness counter, broadcasts)
//!   and movements run to their end ([`Master::run_to_end`]).
//! - [`transport`]: serial ports (through `serialport`, feature `serial`, on by default) and
//!   the trait the rest is written to.
//! - `tokio_driver` (feature `tokio`): the same master, async, over `tokio-serial`.
//!
//! Every rule of a transaction lives in the `no_std` sans-IO core, `busspec-link-core`
//! ([`busspec_link_core::MasterCore`]); [`Master`] and the tokio driver only carry out what it
//! says. Firmware uses the core's own `embedded-io` and `embedded-io-async` drivers.
//! - [`sim`]: the simulated bus that holds device simulators (any [`sim::Device`]), and a loop
//!   that serves them on a real port (a pseudo-terminal).
//! - [`fault`]: a transport wrapper that damages traffic, seeded and replayable.
//! - [`soak`]: many transactions through faults, counting what got through and what did not,
//!   for any protocol with a simulator and a request mix ([`soak::SoakTarget`]).
//! - [`clock`]: real or simulated time; everything that waits asks a clock, so tests and soaks
//!   run in CPU time.

pub use busspec_link_core;

pub mod clock;
pub mod fault;
pub mod master;
pub mod protocol;
pub mod sim;
pub mod soak;
#[cfg(feature = "tokio")]
pub mod tokio_driver;
pub mod transport;

pub use busspec_link_core::{DriverEnable, Line};
pub use busspec_runtime::{Message, Protocol};
pub use clock::{Clock, SimClock, SystemClock};
pub use master::{Exchange, LinkError, Master, Progress, Timing, TraceEvent};
pub use protocol::{Link, Plain};
#[cfg(feature = "serial")]
pub use transport::SerialTransport;
pub use transport::Transport;
