//! busspec-link: talk to the devices busspec's specs describe.
//!
//! - [`master::Master`]: the transaction layer over any [`transport::Transport`] — typed
//!   request out, paired typed response back, with the bus's rules (gap between commands,
//!   timeouts, safe retries, the SD freshness counter, broadcasts) and the long operations built
//!   on them (movements, the UB2 C-curve table, SD string readouts).
//! - [`transport`]: serial ports (through `serialport`) and the trait the rest is written to.
//! - [`sim`]: UB2 and SD device simulators on the generated codec, a simulated bus that holds
//!   several of them, and a loop that serves them on a real port (a pseudo-terminal).
//! - [`fault`]: a transport wrapper that damages traffic, seeded and replayable.
//! - [`soak`]: many transactions through faults, counting what got through and what did not.
//! - [`clock`]: real or simulated time; everything that waits asks a clock, so tests and soaks
//!   run in CPU time.

pub mod clock;
pub mod fault;
pub mod master;
pub mod protocol;
pub mod sim;
pub mod soak;
pub mod transport;

pub use clock::{Clock, SimClock, SystemClock};
pub use master::{Exchange, LinkError, Master, Progress, Timing, TraceEvent};
pub use protocol::{Kind, Policy, Protocol, Sd, Ub2};
pub use transport::{SerialTransport, Transport};
