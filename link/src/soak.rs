//! The soak: many transactions between a master and simulated devices through a faulty line,
//! counting what got through and what did not.
//!
//! Every transaction is judged against a reference: just before it, the target device is
//! copied, and the copy answers the request as sent (undamaged) at the same instant — device
//! time is held still within a transaction, so a retry sees the same time. Then:
//!
//! - **completed**: the master returned a reply equal to the reference's, and the device ended
//!   in the reference's state; **retried** if that took more than one send;
//! - **failed**: the master returned an error (no reply, no valid reply, ...);
//! - **not sent**: the master refused the request itself, because the spec forbids it (a value
//!   outside its range: the mixes include some on purpose, as a careless caller would send);
//! - **unseen**: a request whose reply the spec leaves out (`reply: none`) or makes optional
//!   (`reply: optional`) was lost or damaged, and the master, rightly, returned no reply: the
//!   device's state or the reference's reply differs, but the protocol gives the master no way
//!   to tell (a command with no acknowledgment, a telemetry answer that may not come);
//! - **silent wrong**: the master returned a reply, but it differs from the reference's or the
//!   device's state does (a damaged request that still passed the device's checks).
//!
//! For comparison the same run also judges a master that accepts whatever arrives before the
//! line goes quiet as soon as its checksum is right — no length, address or pairing checks: the
//! first such reply in a transaction counts as silently wrong when its bytes differ from the
//! reference's reply, or when the device's state does.
//!
//! A reply is a refusal when [`Link::is_refusal`] says so: a NAK the spec declares, except
//! where the master reads it as the answer (UB2 0x93 to a movement).
//!
//! After each transaction the device is reset to the reference's state, so faults do not pile
//! up and every transaction starts from a known device.
//!
//! [`run`] works for any protocol that implements [`SoakTarget`]: a simulator to soak and a mix
//! of requests. UB2 and SD implement it in `busspec-devices`, which also runs the soak by
//! protocol name.

use std::cell::RefCell;
use std::fmt;
use std::rc::Rc;
use std::time::Duration;

use busspec_runtime::{Message, Reply, RequestMessage, ResponseMessage};

use crate::clock::{Clock, SimClock};
use crate::fault::{FaultConfig, FaultCounts, Faulty};
use crate::master::{LinkError, Master, Timing, TraceEvent};
use crate::protocol::Link;
use crate::sim::{BusConfig, Device, SimBus};

/// A protocol the soak can run: its device and a mix of requests.
pub trait SoakTarget: Link {
    type Device: Device + Clone + PartialEq;
    fn device(index: u8) -> Self::Device;
    /// A request from the soak's mix, for this device as it is now.
    fn request(rng: &mut fastrand::Rng, device: &Self::Device) -> Self::Request;
}

/// What to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoakConfig {
    pub transactions: u64,
    /// Total byte-error rate, see [`FaultConfig::byte_error_rate`].
    pub byte_error_rate: f64,
    pub seed: u64,
    /// Devices on the bus.
    pub devices: u8,
}

/// What happened.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SoakReport {
    pub protocol: &'static str,
    pub transactions: u64,
    /// Completed correctly on the first send.
    pub completed: u64,
    /// Completed correctly after one or more retries.
    pub retried: u64,
    /// Ended with an error (not counting `not_sent`).
    pub failed: u64,
    /// Refused by the master before anything was sent: the spec forbids the request.
    pub not_sent: u64,
    /// Answered with a refusal (NAK) other than the reference's answer.
    pub refused: u64,
    /// Of failed and refused, those after which the device's state differs from the intended one.
    pub failed_with_device_changed: u64,
    /// Lost where the protocol cannot tell: no reply returned to a request whose reply is
    /// none or optional, while the device's state or the reference's reply differs.
    pub unseen: u64,
    /// Returned a reply that was wrong, or left the device in a wrong state, with no error
    /// the protocol could have raised.
    pub silent_wrong: u64,
    /// The checksum-only master: transactions where some reply passed its checksum.
    pub checksum_only_accepted: u64,
    /// The checksum-only master: of those, wrong.
    pub checksum_only_silent_wrong: u64,
    pub sends: u64,
    pub faults: FaultCounts,
    /// Simulated time the run took.
    pub bus_time: Duration,
    /// A few examples of silent wrong values, for the record.
    pub examples: Vec<String>,
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

impl fmt::Display for SoakReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pct = |n: u64| 100.0 * n as f64 / (self.transactions.max(1) as f64);
        writeln!(
            f,
            "{}: {} transactions, {} sends, {:.0} s of simulated bus time",
            self.protocol,
            self.transactions,
            self.sends,
            self.bus_time.as_secs_f64()
        )?;
        writeln!(f, "  {}", self.faults)?;
        writeln!(
            f,
            "  completed first time      {:>8} ({:.2} %)",
            self.completed,
            pct(self.completed)
        )?;
        writeln!(
            f,
            "  completed after retries   {:>8} ({:.2} %)",
            self.retried,
            pct(self.retried)
        )?;
        writeln!(
            f,
            "  failed with a clear error {:>8} ({:.2} %; device changed anyway in {} failed or refused)",
            self.failed,
            pct(self.failed),
            self.failed_with_device_changed
        )?;
        writeln!(
            f,
            "  refused (unexpected NAK)  {:>8} ({:.2} %)",
            self.refused,
            pct(self.refused)
        )?;
        writeln!(
            f,
            "  not sent (outside spec)   {:>8} ({:.2} %)",
            self.not_sent,
            pct(self.not_sent)
        )?;
        writeln!(
            f,
            "  lost unseen (no or optional reply) {:>8} ({:.2} %)",
            self.unseen,
            pct(self.unseen)
        )?;
        writeln!(f, "  wrong, accepted silently  {:>8}", self.silent_wrong)?;
        write!(
            f,
            "  checksum-only master: accepted {}, of which wrong {}",
            self.checksum_only_accepted, self.checksum_only_silent_wrong
        )
    }
}

/// Runs the soak for protocol `P`.
pub fn run<P: SoakTarget>(config: SoakConfig) -> SoakReport {
    run_with::<P, P::Device>(config, P::device, P::request)
}

/// [`run`] with the devices and the request mix given, for a protocol whose simulator is not
/// its own type's (any spec's, by its `device:` section): `device(i)` makes the `i`-th device
/// on the bus, `request` draws a request for a device as it is now.
pub fn run_with<P: Link, D: Device + Clone + PartialEq>(
    config: SoakConfig,
    device: impl FnMut(u8) -> D,
    mut request: impl FnMut(&mut fastrand::Rng, &D) -> P::Request,
) -> SoakReport {
    let clock = SimClock::new();
    let devices: Vec<D> = (0..config.devices.max(1)).map(device).collect();
    let addresses: Vec<u8> = devices.iter().map(Device::address).collect();
    let bus_config = BusConfig::new(P::baud());
    let frame_gap = bus_config.frame_gap;
    let bus = SimBus::new(clock.clone(), bus_config, devices);
    let timing = Timing::for_protocol::<P>();
    let faults = FaultConfig::byte_error_rate(config.byte_error_rate, timing.reply_timeout);
    let line = Faulty::new(bus.clone(), clock.clone(), faults, config.seed);
    let mut master: Master<P, _, _> = Master::new(line, clock.clone()).with_timing(timing);
    let received: Rc<RefCell<Vec<Vec<u8>>>> = Rc::default();
    let sends = Rc::new(RefCell::new(0u64));
    {
        let received = Rc::clone(&received);
        let sends = Rc::clone(&sends);
        master.observe(move |e| match e {
            TraceEvent::Received { bytes, .. } => received.borrow_mut().push(bytes.to_vec()),
            TraceEvent::Sent { .. } => *sends.borrow_mut() += 1,
            _ => {}
        });
    }
    for &a in &addresses {
        // Known from the start, so no request needs a readout first: the first carries 0.
        master.set_freshness(a, (P::FRESHNESS_MODULUS.max(1) - 1) as u8);
    }
    let mut rng = fastrand::Rng::with_seed(config.seed ^ 0x5EED);
    let mut report = SoakReport {
        protocol: P::name(),
        transactions: config.transactions,
        ..SoakReport::default()
    };
    for _ in 0..config.transactions {
        let which = rng.usize(0..addresses.len());
        let address = addresses[which];
        let device = bus.with_devices(|d| d[which].clone());
        let mut request = request(&mut rng, &device);
        if let Some(f) = P::freshness_mut(&mut request) {
            *f = master.next_freshness_value(address).unwrap_or(0);
        }
        // The reference: the device as it is, answering the request as sent, at this instant.
        let t0 = clock.now();
        let mut reference = device;
        let mut sent = vec![0u8; P::MAX_FRAME_LEN];
        let n = request.encode(address, &mut sent).unwrap_or(0);
        sent.truncate(n);
        let expected = reference.on_frame(&sent, t0);
        let expected_response = expected
            .as_deref()
            .and_then(|f| {
                P::Response::decode_as_reply_over(
                    f,
                    Some(&request),
                    Some(P::Request::covered(&sent)),
                )
                .ok()
            })
            .map(|d| d.message);
        bus.freeze_time(Some(t0));
        received.borrow_mut().clear();
        let result = master.transact(address, request);
        // The devices take the last bytes sent as a frame once the line is quiet for the
        // bus's frame gap: a command that gets no reply ends its transaction as soon as it is
        // sent, and is judged after its device has seen it.
        clock.advance(frame_gap);
        let actual = bus.with_devices(|d| std::mem::replace(&mut d[which], reference.clone()));
        bus.freeze_time(None);
        let state_ok = actual == reference;
        match result {
            Ok(ex) if ex.response == expected_response && state_ok => {
                if ex.attempts > 1 {
                    report.retried += 1;
                } else {
                    report.completed += 1;
                }
            }
            // A refusal is not taken for a value: the caller sees the NAK.
            Ok(ex)
                if ex
                    .response
                    .as_ref()
                    .is_some_and(|r| P::is_refusal(&request, r)) =>
            {
                report.refused += 1;
                if !state_ok {
                    report.failed_with_device_changed += 1;
                }
            }
            // Nothing came back, as the spec allows for this request: what was lost, the
            // protocol does not let a master see.
            Ok(ex) if ex.response.is_none() && request.command().reply != Reply::Required => {
                report.unseen += 1;
            }
            Ok(ex) => {
                report.silent_wrong += 1;
                if report.examples.len() < 5 {
                    report.examples.push(format!(
                        "{} to 0x{address:02X}: sent {}, accepted {} ({:?}), expected {:?}{}",
                        request.name(),
                        hex(&sent),
                        hex(&ex.frame),
                        ex.response,
                        expected_response,
                        if state_ok {
                            ""
                        } else {
                            "; device state differs"
                        }
                    ));
                }
            }
            Err(LinkError::Encode { .. }) => {
                report.not_sent += 1;
                if !state_ok {
                    report.failed_with_device_changed += 1;
                }
            }
            Err(_) => {
                report.failed += 1;
                if !state_ok {
                    report.failed_with_device_changed += 1;
                }
            }
        }
        // The checksum-only master takes the first reply whose checksum is right. It still
        // tells a NAK from an answer: a checksum NAK makes it send again, another NAK is a
        // refusal, not a value.
        for bytes in received.borrow().iter().filter(|b| P::checksum_ok(b)) {
            match P::decode_reply(bytes, &request) {
                Ok(d) if P::is_checksum_nak(&d.message) => continue,
                Ok(d) if P::is_refusal(&request, &d.message) => break,
                _ => {}
            }
            report.checksum_only_accepted += 1;
            if Some(bytes.as_slice()) != expected.as_deref() || !state_ok {
                report.checksum_only_silent_wrong += 1;
            }
            break;
        }
    }
    report.sends = *sends.borrow();
    report.faults = master.transport_mut().counts();
    report.bus_time = clock.now();
    report
}
