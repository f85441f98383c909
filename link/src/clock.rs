//! Time, real or simulated.
//!
//! Everything in the link that waits — the UB2 gap between commands, reply timeouts, movement
//! durations in the simulators — asks a [`Clock`]. [`SystemClock`] is the wall clock;
//! [`SimClock`] is a counter that only moves when someone sleeps on it, so a test or a soak of
//! 100,000 transactions with their timeouts runs in CPU time, not in wall-clock time.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A source of time that can also be waited on.
pub trait Clock {
    /// Time since this clock's epoch.
    fn now(&self) -> Duration;
    /// Waits `d`. A simulated clock just moves forward.
    fn sleep(&self, d: Duration);
    /// Waits until `t` (since the epoch); returns at once if `t` has passed.
    fn sleep_until(&self, t: Duration) {
        let now = self.now();
        if t > now {
            self.sleep(t - now);
        }
    }
}

/// The wall clock, with its epoch at construction.
#[derive(Debug, Clone, Copy)]
pub struct SystemClock {
    start: Instant,
}

impl SystemClock {
    pub fn new() -> Self {
        SystemClock {
            start: Instant::now(),
        }
    }
}

impl Default for SystemClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for SystemClock {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }
    fn sleep(&self, d: Duration) {
        std::thread::sleep(d);
    }
}

/// Simulated time: starts at 0 and advances only through [`Clock::sleep`] or [`SimClock::advance`].
/// Clones share the same time, so a master, a simulated bus and its devices stay in step.
#[derive(Debug, Clone, Default)]
pub struct SimClock {
    nanos: Arc<AtomicU64>,
}

impl SimClock {
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves time forward by `d`.
    pub fn advance(&self, d: Duration) {
        let n = u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
        let _ = self
            .nanos
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |v| {
                Some(v.saturating_add(n))
            });
    }

    /// Moves time forward to `t`; never backwards.
    pub fn advance_to(&self, t: Duration) {
        let n = u64::try_from(t.as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_max(n, Ordering::SeqCst);
    }
}

impl Clock for SimClock {
    fn now(&self) -> Duration {
        Duration::from_nanos(self.nanos.load(Ordering::SeqCst))
    }
    fn sleep(&self, d: Duration) {
        self.advance(d);
    }
}

impl<C: Clock + ?Sized> Clock for &C {
    fn now(&self) -> Duration {
        (**self).now()
    }
    fn sleep(&self, d: Duration) {
        (**self).sleep(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sim_clock_moves_only_when_told_and_never_backwards() {
        let c = SimClock::new();
        let other = c.clone();
        assert_eq!(c.now(), Duration::ZERO);
        c.sleep(Duration::from_millis(10));
        assert_eq!(other.now(), Duration::from_millis(10));
        other.advance_to(Duration::from_millis(5));
        assert_eq!(c.now(), Duration::from_millis(10));
        c.sleep_until(Duration::from_millis(25));
        assert_eq!(c.now(), Duration::from_millis(25));
    }
}
