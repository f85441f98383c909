//! Fault injection between a master and its bus.
//!
//! [`Faulty`] wraps any [`Transport`] and, with a seeded generator (so a failing run can be
//! replayed), damages what passes through: per byte it corrupts (XOR with a random non-zero
//! byte), drops or duplicates; per chunk (one write, or one run of bytes read) it truncates,
//! swallows whole (silence) or holds back past the reply timeout (a late reply). Each
//! direction is damaged on its own.

use std::collections::VecDeque;
use std::io;
use std::time::Duration;

use crate::clock::Clock;
use crate::transport::Transport;

/// Fault probabilities; byte faults per byte, chunk faults per chunk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultConfig {
    pub corrupt: f64,
    pub drop: f64,
    pub duplicate: f64,
    pub truncate: f64,
    pub silence: f64,
    pub late: f64,
    /// How late a late chunk comes: uniformly within this range.
    pub late_by: (Duration, Duration),
    /// Leave requests alone and damage replies only.
    pub replies_only: bool,
}

impl FaultConfig {
    /// No faults.
    pub fn none() -> Self {
        FaultConfig {
            corrupt: 0.0,
            drop: 0.0,
            duplicate: 0.0,
            truncate: 0.0,
            silence: 0.0,
            late: 0.0,
            late_by: (Duration::ZERO, Duration::ZERO),
            replies_only: false,
        }
    }

    /// A total byte-error rate split 60/20/20 over corrupted, dropped and duplicated bytes, and
    /// a fifth of it per chunk for truncation, silence and late delivery each; late chunks come
    /// 1 to 1.8 times `timeout` late.
    pub fn byte_error_rate(rate: f64, timeout: Duration) -> Self {
        FaultConfig {
            corrupt: 0.6 * rate,
            drop: 0.2 * rate,
            duplicate: 0.2 * rate,
            truncate: 0.2 * rate,
            silence: 0.2 * rate,
            late: 0.2 * rate,
            late_by: (timeout, timeout.mul_f64(1.8)),
            replies_only: false,
        }
    }
}

/// What was injected so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaultCounts {
    pub corrupted: u64,
    pub dropped: u64,
    pub duplicated: u64,
    pub truncated: u64,
    pub silenced: u64,
    pub delayed: u64,
    /// Bytes that went through, damaged or not.
    pub bytes: u64,
}

/// A transport that damages traffic; see the module docs.
pub struct Faulty<T, C> {
    inner: T,
    clock: C,
    rng: fastrand::Rng,
    config: FaultConfig,
    /// Received bytes held back, with when they may be read.
    held: VecDeque<(Duration, u8)>,
    pub counts: FaultCounts,
}

impl<T: Transport, C: Clock> Faulty<T, C> {
    pub fn new(inner: T, clock: C, config: FaultConfig, seed: u64) -> Self {
        Faulty {
            inner,
            clock,
            rng: fastrand::Rng::with_seed(seed),
            config,
            held: VecDeque::new(),
            counts: FaultCounts::default(),
        }
    }

    pub fn inner_mut(&mut self) -> &mut T {
        &mut self.inner
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.f64() < p
    }

    /// Damages one chunk; `None` when it is swallowed whole.
    fn damage(&mut self, bytes: &[u8]) -> Option<Vec<u8>> {
        self.counts.bytes += bytes.len() as u64;
        if self.chance(self.config.silence) {
            self.counts.silenced += 1;
            return None;
        }
        let mut out = Vec::with_capacity(bytes.len() + 2);
        for &b in bytes {
            let c = self.config;
            if self.chance(c.drop) {
                self.counts.dropped += 1;
                continue;
            }
            if self.chance(c.corrupt) {
                self.counts.corrupted += 1;
                out.push(b ^ self.rng.u8(1..=255));
            } else {
                out.push(b);
            }
            if self.chance(c.duplicate) {
                self.counts.duplicated += 1;
                out.push(*out.last().unwrap_or(&b));
            }
        }
        if out.len() > 1 && self.chance(self.config.truncate) {
            self.counts.truncated += 1;
            let keep = self.rng.usize(1..out.len());
            out.truncate(keep);
        }
        Some(out)
    }
}

impl<T: Transport, C: Clock> Transport for Faulty<T, C> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if self.config.replies_only {
            return self.inner.write(bytes);
        }
        match self.damage(bytes) {
            Some(out) if !out.is_empty() => self.inner.write(&out),
            // Nothing reaches the line, but sending still takes the master its time.
            _ => self.inner.write(&[]),
        }
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        let deadline = self.clock.now() + timeout;
        let mut chunk = [0u8; 256];
        loop {
            let now = self.clock.now();
            if self.held.front().is_some_and(|&(t, _)| t <= now) {
                let mut n = 0;
                while n < buf.len() && self.held.front().is_some_and(|&(t, _)| t <= now) {
                    if let Some((_, b)) = self.held.pop_front() {
                        buf[n] = b;
                        n += 1;
                    }
                }
                return Ok(n);
            }
            if now >= deadline {
                return Ok(0);
            }
            let until = match self.held.front() {
                Some(&(t, _)) => t.min(deadline),
                None => deadline,
            };
            let n = self.inner.read(&mut chunk, until - now)?;
            if n == 0 {
                // A real transport may return early; the simulated one has moved the clock.
                if self.clock.now() < until {
                    self.clock.sleep_until(until);
                }
                continue;
            }
            let got = chunk[..n].to_vec();
            let Some(out) = self.damage(&got) else {
                continue;
            };
            let mut at = self.clock.now();
            if self.chance(self.config.late) {
                self.counts.delayed += 1;
                let (lo, hi) = self.config.late_by;
                let span = hi.saturating_sub(lo).as_nanos() as u64;
                let extra = if span == 0 { 0 } else { self.rng.u64(0..span) };
                at += lo + Duration::from_nanos(extra);
            }
            let at = self.held.back().map_or(at, |&(t, _)| t.max(at));
            self.held.extend(out.into_iter().map(|b| (at, b)));
        }
    }

    fn clear_input(&mut self) -> io::Result<()> {
        let now = self.clock.now();
        while self.held.front().is_some_and(|&(t, _)| t <= now) {
            self.held.pop_front();
        }
        self.inner.clear_input()
    }
}
