//! Fault injection between a master and its bus.
//!
//! [`Faulty`] wraps any [`Transport`] and, with a seeded generator (so a failing run can be
//! replayed), damages what passes through: per byte it corrupts (XOR with a random non-zero
//! byte), drops or duplicates; per chunk (one write, or one run of bytes read) it truncates,
//! swallows whole (silence) or holds back past the reply timeout (a late reply). Each
//! direction is damaged on its own. [`FaultyReplies`] does the same to what a simulator writes
//! (its replies) and nothing to what it reads; [`Damage`] is the part both share.

use std::collections::VecDeque;
use std::io;
use std::sync::{Arc, Mutex};
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

impl std::fmt::Display for FaultCounts {
    /// `faults injected: ...`, the line the soak reports and `busspec sim --fault-rate` ends with.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "faults injected: {} bytes corrupted, {} dropped, {} duplicated; {} chunks truncated, {} silenced, {} late (of {} bytes)",
            self.corrupted, self.dropped, self.duplicated, self.truncated, self.silenced, self.delayed, self.bytes
        )
    }
}

/// The damage [`FaultConfig`] describes, done to one chunk at a time with a seeded generator:
/// what [`Faulty`] does to the traffic through it, and [`FaultyReplies`] to what a simulator
/// writes.
pub struct Damage {
    rng: fastrand::Rng,
    config: FaultConfig,
    pub counts: FaultCounts,
}

impl Damage {
    pub fn new(config: FaultConfig, seed: u64) -> Self {
        Damage {
            rng: fastrand::Rng::with_seed(seed),
            config,
            counts: FaultCounts::default(),
        }
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.f64() < p
    }

    /// Damages one chunk; `None` when it is swallowed whole.
    pub fn chunk(&mut self, bytes: &[u8]) -> Option<Vec<u8>> {
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

    /// How late a chunk comes: `None` (on time), or a delay within the config's `late_by`.
    pub fn delay(&mut self) -> Option<Duration> {
        if !self.chance(self.config.late) {
            return None;
        }
        self.counts.delayed += 1;
        let (lo, hi) = self.config.late_by;
        let span = hi.saturating_sub(lo).as_nanos() as u64;
        let extra = if span == 0 { 0 } else { self.rng.u64(0..span) };
        Some(lo + Duration::from_nanos(extra))
    }
}

/// A transport that damages traffic; see the module docs.
pub struct Faulty<T, C> {
    inner: T,
    clock: C,
    damage: Damage,
    replies_only: bool,
    /// Received bytes held back, with when they may be read.
    held: VecDeque<(Duration, u8)>,
}

impl<T: Transport, C: Clock> Faulty<T, C> {
    pub fn new(inner: T, clock: C, config: FaultConfig, seed: u64) -> Self {
        Faulty {
            inner,
            clock,
            damage: Damage::new(config, seed),
            replies_only: config.replies_only,
            held: VecDeque::new(),
        }
    }

    pub fn inner_mut(&mut self) -> &mut T {
        &mut self.inner
    }

    /// What was injected so far.
    pub fn counts(&self) -> FaultCounts {
        self.damage.counts
    }
}

impl<T: Transport, C: Clock> Transport for Faulty<T, C> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if self.replies_only {
            return self.inner.write(bytes);
        }
        match self.damage.chunk(bytes) {
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
            let Some(out) = self.damage.chunk(&got) else {
                continue;
            };
            let mut at = self.clock.now();
            if let Some(d) = self.damage.delay() {
                at += d;
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

/// A simulator's end of a line, damaging what it writes (its replies) as [`Faulty`] damages a
/// chunk; what it reads (the requests) passes untouched. A late reply is held back and written
/// by the first `read` (or `write`) after its time, the replies written after it behind it, so
/// the simulator goes on reading requests meanwhile. What `busspec sim --fault-rate` serves
/// through.
pub struct FaultyReplies<T, C> {
    inner: T,
    clock: C,
    damage: Damage,
    /// Late replies, and those behind them, with when they may go out.
    held: VecDeque<(Duration, Vec<u8>)>,
    /// What became of the last reply written, for [`Self::last_fate`]'s handles.
    last: Arc<Mutex<Option<Fate>>>,
}

/// What [`FaultyReplies`] did to a reply: what a log of the simulator's traffic shows beside
/// the reply the device made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fate {
    /// Not written at all (silenced, or every byte dropped).
    Lost,
    /// Written as these bytes (damaged or not), this late.
    Sent { bytes: Vec<u8>, late: Duration },
}

impl std::fmt::Display for Fate {
    /// `lost`, or the bytes in hex as busspec prints frames (`AA01`) with `, 200 ms late`
    /// where it was held back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fate::Lost => f.write_str("lost"),
            Fate::Sent { bytes, late } => {
                for b in bytes {
                    write!(f, "{b:02X}")?;
                }
                if !late.is_zero() {
                    write!(f, ", {} ms late", late.as_millis())?;
                }
                Ok(())
            }
        }
    }
}

/// A handle on what became of the last reply a [`FaultyReplies`] was given
/// ([`FaultyReplies::last_fate`]): it can be read while the line is lent to a server loop.
#[derive(Debug, Clone)]
pub struct LastFate(Arc<Mutex<Option<Fate>>>);

impl LastFate {
    /// The last reply's fate, taken (so each is read once); `None` before the first reply.
    pub fn take(&self) -> Option<Fate> {
        self.0.lock().ok().and_then(|mut last| last.take())
    }
}

impl<T: Transport, C: Clock> FaultyReplies<T, C> {
    pub fn new(inner: T, clock: C, config: FaultConfig, seed: u64) -> Self {
        FaultyReplies {
            inner,
            clock,
            damage: Damage::new(config, seed),
            held: VecDeque::new(),
            last: Arc::new(Mutex::new(None)),
        }
    }

    /// What was injected so far.
    pub fn counts(&self) -> FaultCounts {
        self.damage.counts
    }

    /// A handle that says what became of each reply written (`busspec sim --verbose` logs
    /// it beside the reply the device made).
    pub fn last_fate(&self) -> LastFate {
        LastFate(Arc::clone(&self.last))
    }

    fn note(&self, fate: Fate) {
        if let Ok(mut last) = self.last.lock() {
            *last = Some(fate);
        }
    }

    /// Writes the held replies whose time has come.
    fn release(&mut self) -> io::Result<()> {
        let now = self.clock.now();
        while self.held.front().is_some_and(|(t, _)| *t <= now) {
            if let Some((_, bytes)) = self.held.pop_front() {
                self.inner.write(&bytes)?;
            }
        }
        Ok(())
    }
}

impl<T: Transport, C: Clock> Transport for FaultyReplies<T, C> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.release()?;
        let Some(out) = self.damage.chunk(bytes) else {
            self.note(Fate::Lost);
            return Ok(());
        };
        let delay = self.damage.delay();
        if out.is_empty() {
            self.note(Fate::Lost);
            return Ok(());
        }
        let now = self.clock.now();
        match (delay, self.held.back()) {
            (None, None) => {
                self.note(Fate::Sent {
                    bytes: out.clone(),
                    late: Duration::ZERO,
                });
                self.inner.write(&out)
            }
            (delay, last) => {
                let at = now + delay.unwrap_or_default();
                let at = last.map_or(at, |(t, _)| at.max(*t));
                self.note(Fate::Sent {
                    bytes: out.clone(),
                    late: at.saturating_sub(now),
                });
                self.held.push_back((at, out));
                Ok(())
            }
        }
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.release()?;
        let timeout = match self.held.front() {
            Some((t, _)) => timeout.min(t.saturating_sub(self.clock.now())),
            None => timeout,
        };
        let n = self.inner.read(buf, timeout)?;
        self.release()?;
        Ok(n)
    }

    fn clear_input(&mut self) -> io::Result<()> {
        self.inner.clear_input()
    }

    fn set_driver_enable(&mut self, on: bool) -> io::Result<()> {
        self.inner.set_driver_enable(on)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::SimClock;

    /// Records what is written; reads hand out `incoming`.
    #[derive(Default)]
    struct Wire {
        written: Vec<Vec<u8>>,
        incoming: Vec<u8>,
    }

    impl Transport for Wire {
        fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
            self.written.push(bytes.to_vec());
            Ok(())
        }
        fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
            let n = buf.len().min(self.incoming.len());
            buf[..n].copy_from_slice(&self.incoming[..n]);
            self.incoming.drain(..n);
            Ok(n)
        }
        fn clear_input(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    /// 200 replies written 10 ms apart, as a simulator would (reading between them), and all
    /// that has gone out a second after the last.
    fn replies(rate: f64, seed: u64) -> (Vec<Vec<u8>>, FaultCounts) {
        let clock = SimClock::new();
        let config = FaultConfig::byte_error_rate(rate, ms(200));
        let mut line = FaultyReplies::new(Wire::default(), clock.clone(), config, seed);
        let mut buf = [0u8; 8];
        for i in 0..200u8 {
            line.write(&[0xAA, i, 1, 2, 3, 4, 5, 6, 7, i ^ 0x55])
                .unwrap();
            clock.advance(ms(10));
            line.read(&mut buf, ms(3)).unwrap();
        }
        clock.advance(ms(1000));
        line.read(&mut buf, ms(3)).unwrap();
        let counts = line.counts();
        (line.inner.written, counts)
    }

    #[test]
    fn at_rate_zero_replies_go_out_as_written() {
        let (written, counts) = replies(0.0, 3);
        assert_eq!(written.len(), 200);
        assert!(written
            .iter()
            .enumerate()
            .all(|(i, w)| w[..] == [0xAA, i as u8, 1, 2, 3, 4, 5, 6, 7, i as u8 ^ 0x55]));
        assert_eq!(
            counts,
            FaultCounts {
                bytes: 2000,
                ..FaultCounts::default()
            }
        );
    }

    #[test]
    fn replies_are_damaged_the_same_way_for_the_same_seed() {
        let (a, counts) = replies(0.2, 7);
        assert_eq!(replies(0.2, 7), (a.clone(), counts));
        assert_ne!(replies(0.2, 8).0, a);
        // Every kind of fault, the silenced replies not written at all.
        let c = counts;
        assert!(
            c.corrupted > 0 && c.dropped > 0 && c.duplicated > 0,
            "{c:?}"
        );
        assert!(c.truncated > 0 && c.silenced > 0 && c.delayed > 0, "{c:?}");
        // (A reply all of whose bytes are dropped is not written either: none is, here.)
        assert_eq!(a.len() as u64, 200 - c.silenced);
        assert_eq!(
            c.to_string(),
            format!(
                "faults injected: {} bytes corrupted, {} dropped, {} duplicated; {} chunks truncated, {} silenced, {} late (of 2000 bytes)",
                c.corrupted, c.dropped, c.duplicated, c.truncated, c.silenced, c.delayed
            )
        );
    }

    /// The fate of each reply is what went out on the wire: its bytes as written (damaged),
    /// how late, or lost; at rate 0 the reply itself.
    #[test]
    fn each_reply_s_fate_is_what_the_line_carried() {
        let clock = SimClock::new();
        let config = FaultConfig::byte_error_rate(0.2, ms(200));
        let mut line = FaultyReplies::new(Wire::default(), clock.clone(), config, 7);
        let fates = line.last_fate();
        assert_eq!(fates.take(), None);
        let mut buf = [0u8; 8];
        let (mut sent, mut lost, mut damaged, mut late) = (Vec::new(), 0, 0, 0);
        for i in 0..200u8 {
            let reply = [0xAA, i, 1, 2, 3, 4, 5, 6, 7, i ^ 0x55];
            line.write(&reply).unwrap();
            match fates.take() {
                Some(Fate::Sent { bytes, late: l }) => {
                    damaged += usize::from(bytes[..] != reply[..]);
                    late += usize::from(!l.is_zero());
                    sent.push(bytes);
                }
                Some(Fate::Lost) => lost += 1,
                None => panic!("reply {i} has no fate"),
            }
            assert_eq!(fates.take(), None, "a fate is read once");
            clock.advance(ms(10));
            line.read(&mut buf, ms(3)).unwrap();
        }
        clock.advance(ms(1000));
        line.read(&mut buf, ms(3)).unwrap();
        assert_eq!(line.inner.written, sent);
        assert!(
            lost > 0 && damaged > 0 && late > 0,
            "{lost} {damaged} {late}"
        );
        let fate = Fate::Sent {
            bytes: vec![0xAA, 0x01],
            late: ms(200),
        };
        assert_eq!(fate.to_string(), "AA01, 200 ms late");
        assert_eq!(Fate::Lost.to_string(), "lost");
        let mut clean = FaultyReplies::new(Wire::default(), clock, FaultConfig::none(), 1);
        let fates = clean.last_fate();
        clean.write(&[0xAA, 2]).unwrap();
        assert_eq!(
            fates.take(),
            Some(Fate::Sent {
                bytes: vec![0xAA, 2],
                late: Duration::ZERO
            })
        );
    }

    #[test]
    fn a_late_reply_does_not_hold_up_the_requests_after_it() {
        let clock = SimClock::new();
        let config = FaultConfig {
            late: 1.0,
            late_by: (ms(200), ms(200)),
            ..FaultConfig::none()
        };
        let wire = Wire {
            incoming: vec![1, 2, 3],
            ..Wire::default()
        };
        let mut line = FaultyReplies::new(wire, clock.clone(), config, 1);
        line.write(&[0xAA, 1]).unwrap();
        // The simulator is not kept waiting: the next request is read at once.
        assert_eq!(clock.now(), Duration::ZERO);
        let mut buf = [0u8; 8];
        assert_eq!(line.read(&mut buf, ms(3)).unwrap(), 3);
        assert!(line.inner.written.is_empty());
        // A reply written meanwhile goes out behind the late one, not before it.
        line.write(&[0xAA, 2]).unwrap();
        clock.advance(ms(199));
        line.read(&mut buf, ms(3)).unwrap();
        assert!(line.inner.written.is_empty());
        clock.advance(ms(201));
        line.read(&mut buf, ms(3)).unwrap();
        assert_eq!(line.inner.written, [vec![0xAA, 1], vec![0xAA, 2]]);
        assert_eq!(line.counts().delayed, 2);
    }

    #[test]
    fn what_the_simulator_reads_is_never_damaged() {
        let request: Vec<u8> = (0..=255).collect();
        let wire = Wire {
            incoming: request.clone(),
            ..Wire::default()
        };
        let mut line = FaultyReplies::new(
            wire,
            SimClock::new(),
            FaultConfig::byte_error_rate(1.0, Duration::ZERO),
            1,
        );
        let mut got = vec![0u8; 256];
        assert_eq!(line.read(&mut got, Duration::from_millis(5)).unwrap(), 256);
        assert_eq!(got, request);
        assert_eq!(line.counts(), FaultCounts::default());
    }
}
