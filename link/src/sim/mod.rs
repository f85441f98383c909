//! Device simulators and the simulated bus they sit on.
//!
//! A simulator is sans-IO: [`Device::on_frame`] takes one request frame — the bytes between two
//! quiet spells on the line, which is how the UB2 document's 10 ms gap lets slaves tell
//! commands apart (§2.1) — and the time, and returns its reply. [`SimBus`] puts any number of
//! them (distinct addresses) behind a [`Transport`] on a [`SimClock`]: bytes take their time on
//! the wire at the bus's baud rate, replies come after a short latency, and replies that overlap
//! in time collide. [`serve`] runs simulators on a real transport (a pseudo-terminal) instead.
//! The simulators of particular devices (UB2, SD) are `busspec-devices`'; [`reply`],
//! [`number_positions`] and [`swap_numbers`] are what they build on.

#[cfg(all(unix, feature = "serial"))]
pub mod pty;

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io;
use std::rc::Rc;
use std::time::Duration;

use busspec_runtime::{Elements, FieldValue, Message, Protocol};

use crate::clock::{Clock, SimClock};
use crate::transport::Transport;

/// A simulated slave.
pub trait Device {
    /// Handles one frame received at `now`; returns the reply to send, if any.
    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>>;
    /// The device's current address.
    fn address(&self) -> u8;
}

impl<D: Device + ?Sized> Device for Box<D> {
    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        (**self).on_frame(frame, now)
    }
    fn address(&self) -> u8 {
        (**self).address()
    }
}

/// Line parameters of a simulated bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusConfig {
    pub baud: u32,
    /// Quiet time after which a device takes the bytes received so far as one frame.
    pub frame_gap: Duration,
    /// Time a device takes between the end of a request and the first byte of its reply (its
    /// turnaround).
    pub reply_latency: Duration,
    /// The master's adapter hears its own transmission: every byte written comes back to the
    /// master as it leaves (a two-wire RS485 adapter without echo suppression).
    pub echo: bool,
    /// Another transmitter drives the bus during byte `n` of every request: that byte is
    /// garbled (inverted) for the devices and in the echo alike. A collision.
    pub collide_at: Option<usize>,
    /// The master's transceiver drives the bus only while its driver-enable line is high
    /// ([`Transport::set_driver_enable`]): bytes written while it is low reach nobody.
    pub driver_enable_required: bool,
}

impl BusConfig {
    pub fn new(baud: u32) -> Self {
        BusConfig {
            baud,
            frame_gap: Duration::from_millis(2),
            reply_latency: Duration::from_millis(1),
            echo: false,
            collide_at: None,
            driver_enable_required: false,
        }
    }

    /// Time one byte (start, 8 data, stop bits) takes on the wire.
    pub fn byte_time(&self) -> Duration {
        Duration::from_nanos(10_000_000_000 / u64::from(self.baud.max(1)))
    }
}

struct Inner<D> {
    devices: Vec<D>,
    clock: SimClock,
    config: BusConfig,
    /// Request bytes not yet taken as a frame, and when the last of them ended.
    pending: Vec<u8>,
    pending_end: Duration,
    /// Reply bytes on their way to the master, each with its arrival time.
    rx: VecDeque<(Duration, u8)>,
    /// When set, devices see this time instead of the bus clock (the soak holds time still
    /// within a transaction, so a reference copy of a device can answer the same question).
    frozen: Option<Duration>,
    /// The master's driver-enable line.
    driver_enabled: bool,
}

impl<D: Device> Inner<D> {
    /// Hands the pending bytes to every device as one frame, and queues the replies.
    fn deliver(&mut self) {
        if self.pending.is_empty() {
            return;
        }
        let frame = std::mem::take(&mut self.pending);
        let at = self.pending_end + self.config.frame_gap;
        let seen = self.frozen.unwrap_or(at);
        let byte = self.config.byte_time();
        let mut replies: Vec<(Duration, u8)> = Vec::new();
        for d in &mut self.devices {
            if let Some(reply) = d.on_frame(&frame, seen) {
                let start = at + self.config.reply_latency;
                for (i, b) in reply.into_iter().enumerate() {
                    replies.push((start + byte * (i as u32 + 1), b));
                }
            }
        }
        // Two devices talking at once garble each other: overlapping bytes interleave.
        replies.sort_by_key(|(t, _)| *t);
        let last = self.rx.back().map(|(t, _)| *t);
        for (t, b) in replies {
            let t = last.map_or(t, |l| t.max(l));
            self.rx.push_back((t, b));
        }
    }
}

/// A simulated bus: the master's end is a [`Transport`]. Clones share the bus, so a test can
/// keep one to look at (or change) the devices while a master owns the other.
pub struct SimBus<D> {
    inner: Rc<RefCell<Inner<D>>>,
}

impl<D> Clone for SimBus<D> {
    fn clone(&self) -> Self {
        SimBus {
            inner: Rc::clone(&self.inner),
        }
    }
}

impl<D: Device> SimBus<D> {
    pub fn new(clock: SimClock, config: BusConfig, devices: Vec<D>) -> Self {
        SimBus {
            inner: Rc::new(RefCell::new(Inner {
                devices,
                clock,
                config,
                pending: Vec::new(),
                pending_end: Duration::ZERO,
                rx: VecDeque::new(),
                frozen: None,
                driver_enabled: false,
            })),
        }
    }

    /// Runs `f` on the devices (after handing them a request the line has gone quiet after).
    pub fn with_devices<R>(&self, f: impl FnOnce(&mut Vec<D>) -> R) -> R {
        let mut bus = self.inner.borrow_mut();
        if bus.clock.now() >= bus.pending_end + bus.config.frame_gap {
            bus.deliver();
        }
        f(&mut bus.devices)
    }

    /// Makes devices see time `t` (or the bus clock again, with `None`).
    pub fn freeze_time(&self, t: Option<Duration>) {
        self.inner.borrow_mut().frozen = t;
    }

    pub fn clock(&self) -> SimClock {
        self.inner.borrow().clock.clone()
    }
}

impl<D: Device> Transport for SimBus<D> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        let mut bus = self.inner.borrow_mut();
        let now = bus.clock.now();
        // Bytes that follow the previous ones within the frame gap belong to the same frame:
        // a master that ignores the gap garbles its own requests.
        if !bus.pending.is_empty() && now >= bus.pending_end + bus.config.frame_gap {
            bus.deliver();
        }
        let start = bus.clock.now();
        let took = bus.config.byte_time() * bytes.len() as u32;
        bus.clock.advance(took);
        if bus.config.driver_enable_required && !bus.driver_enabled {
            // The transceiver is not driving: the bytes never reach the bus.
            return Ok(());
        }
        let offset = bus.pending.len();
        let mut on_bus = bytes.to_vec();
        if let Some(n) = bus.config.collide_at {
            if let Some(b) = n.checked_sub(offset).and_then(|i| on_bus.get_mut(i)) {
                *b = !*b;
            }
        }
        if bus.config.echo {
            let byte = bus.config.byte_time();
            let last = bus.rx.back().map(|(t, _)| *t);
            for (i, &b) in on_bus.iter().enumerate() {
                let t = start + byte * (i as u32 + 1);
                bus.rx.push_back((last.map_or(t, |l| t.max(l)), b));
            }
        }
        bus.pending.extend_from_slice(&on_bus);
        bus.pending_end = bus.clock.now();
        Ok(())
    }

    fn set_driver_enable(&mut self, on: bool) -> io::Result<()> {
        self.inner.borrow_mut().driver_enabled = on;
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        let mut bus = self.inner.borrow_mut();
        bus.deliver();
        let now = bus.clock.now();
        let deadline = now + timeout;
        match bus.rx.front() {
            Some(&(t, _)) if t <= deadline => {
                bus.clock.advance_to(t);
                // Take the whole run of bytes that follow each other without a pause.
                let pause = bus.config.byte_time() * 2;
                let mut n = 0;
                let mut last = t;
                while n < buf.len() {
                    match bus.rx.front() {
                        Some(&(t, b)) if t <= last + pause => {
                            buf[n] = b;
                            n += 1;
                            last = t;
                            bus.rx.pop_front();
                        }
                        _ => break,
                    }
                }
                bus.clock.advance_to(last);
                Ok(n)
            }
            _ => {
                bus.clock.advance_to(deadline);
                Ok(0)
            }
        }
    }

    fn clear_input(&mut self) -> io::Result<()> {
        let mut bus = self.inner.borrow_mut();
        let now = bus.clock.now();
        while bus.rx.front().is_some_and(|&(t, _)| t <= now) {
            bus.rx.pop_front();
        }
        Ok(())
    }
}

/// Runs `devices` on a real transport until `keep_going` returns false: bytes are gathered
/// until the line is quiet for `frame_gap`, then handed to every device as one frame, and the
/// replies written back. Errors of the transport end the run.
pub fn serve<D: Device, T: Transport, C: Clock>(
    transport: &mut T,
    clock: &C,
    devices: &mut [D],
    frame_gap: Duration,
    mut keep_going: impl FnMut() -> bool,
    mut on_frame: impl FnMut(&[u8], Option<&[u8]>),
) -> io::Result<()> {
    let mut frame = Vec::new();
    let mut chunk = [0u8; 256];
    while keep_going() {
        let n = transport.read(&mut chunk, frame_gap)?;
        if n > 0 {
            frame.extend_from_slice(&chunk[..n]);
            // Noise without pause must not grow without bound.
            if frame.len() <= 1024 {
                continue;
            }
        }
        if frame.is_empty() {
            continue;
        }
        let now = clock.now();
        let mut replied = false;
        for d in devices.iter_mut() {
            if let Some(reply) = d.on_frame(&frame, now) {
                transport.write(&reply)?;
                on_frame(&frame, Some(&reply));
                replied = true;
            }
        }
        if !replied {
            on_frame(&frame, None);
        }
        frame.clear();
    }
    Ok(())
}

/// Encodes a reply frame of protocol `P`; `None` (no reply) if the value does not fit, which a
/// simulator bug would cause and a test then sees as a timeout.
pub fn reply<P: Protocol>(response: &P::Response, address: u8) -> Option<Vec<u8>> {
    let mut buf = vec![0u8; P::MAX_FRAME_LEN];
    let n = response.encode(address, &mut buf).ok()?;
    buf.truncate(n);
    Some(buf)
}

/// Where the multi-byte numbers of `m`'s frame to `address` lie: (offset, width) for each
/// integer field of more than one byte, for a protocol whose numbers travel little-endian.
///
/// Found through the message's own codec: a field's width is the widest wire type
/// [`Message::from_fields`] takes a value of (1, 2, 4 or 8 bytes), its offset the first byte
/// that changes when the field's lowest bit does. A simulator uses it to act as a device that
/// sends its numbers the other way round (swapping the bytes of each keeps an additive
/// checksum).
pub fn number_positions<M: Message>(m: &M, address: u8) -> Vec<(usize, usize)> {
    enum Value {
        Int(i64),
        Text(Vec<u8>),
        List(Vec<i64>),
        /// Records' raw values, record after record, and the fields to a record.
        Records(Vec<i64>, usize),
    }
    let mut fields: Vec<(&'static str, Value)> = Vec::new();
    m.visit(|name, v| {
        fields.push((
            name,
            match v {
                FieldValue::Int(i) => Value::Int(i),
                FieldValue::Text(t) => Value::Text(t.to_vec()),
                FieldValue::List(items) => Value::List(items.iter().collect()),
                FieldValue::Records(l) => Value::Records(
                    (0..l.len())
                        .flat_map(|k| (0..l.fields()).map(move |j| (k, j)))
                        .map(|(k, j)| l.get(k, j).unwrap_or(0))
                        .collect(),
                    l.fields(),
                ),
            },
        ))
    });
    let with = |name: &str, value: i64| {
        M::from_fields(m.name(), |f| {
            fields.iter().find(|(n, _)| *n == f).map(|(n, v)| match v {
                _ if *n == name => FieldValue::Int(value),
                Value::Int(i) => FieldValue::Int(*i),
                Value::Text(t) => FieldValue::Text(t),
                Value::List(l) => FieldValue::List(Elements::I64(l)),
                Value::Records(l, w) => FieldValue::Records(busspec_runtime::RecordList::Flat {
                    values: l,
                    fields: *w,
                }),
            })
        })
    };
    let encode = |msg: &M| {
        let mut buf = vec![0u8; msg.frame_len().max(1) + 8];
        let n = msg.encode(address, &mut buf).ok()?;
        buf.truncate(n);
        Some(buf)
    };
    let Some(base) = encode(m) else {
        return Vec::new();
    };
    let mut positions = Vec::new();
    for (name, value) in &fields {
        let Value::Int(v) = *value else { continue };
        let width = [(1i64 << 32, 8), (1 << 16, 4), (1 << 8, 2)]
            .into_iter()
            .find(|&(probe, _)| with(name, probe).is_ok())
            .map_or(1, |(_, w)| w);
        if width == 1 {
            continue;
        }
        let offset = [v ^ 1, v + 1, v - 1].into_iter().find_map(|alt| {
            let other = encode(&with(name, alt).ok()?)?;
            // The last byte is the checksum, which changes too.
            let body = base.len().saturating_sub(1);
            (0..body).find(|&i| base.get(i) != other.get(i))
        });
        if let Some(offset) = offset {
            if offset + width < base.len() {
                positions.push((offset, width));
            }
        }
    }
    positions
}

/// Reverses the bytes of each multi-byte number of `m`'s frame in `frame` (see
/// [`number_positions`]).
pub fn swap_numbers<M: Message>(m: &M, address: u8, frame: &mut [u8]) {
    for (offset, width) in number_positions(m, address) {
        if let Some(bytes) = frame.get_mut(offset..offset + width) {
            bytes.reverse();
        }
    }
}
