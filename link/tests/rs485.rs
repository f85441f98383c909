//! RS485 realities beyond the scenario suite: the driver-enable line's timing on a fake clock
//! (a UART whose writes return at once, as a buffered one's do, so only the driver's own
//! computation keeps the line up), and the collision error's text.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use busspec_devices::sim::sd::SdSim;
use busspec_devices::{Sd, Ub2};
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::{DriverEnable, Line, Master, Protocol, SimClock};
use busspec_link_core::blocking::Driver;
use busspec_link_core::driver::{Error, Now};
use busspec_link_core::Failure;
use busspec_protocols::{sd, ub2};

/// What happened, and when on the fake clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Seen {
    High(Duration),
    Low(Duration),
    Write {
        at: Duration,
        bytes: usize,
        de: bool,
    },
}

#[derive(Clone, Default)]
struct Fake {
    now: Rc<RefCell<Duration>>,
    de: Rc<RefCell<bool>>,
    log: Rc<RefCell<Vec<Seen>>>,
}

impl Now for Fake {
    fn now(&self) -> Duration {
        *self.now.borrow()
    }
}

impl embedded_hal::delay::DelayNs for Fake {
    fn delay_ns(&mut self, ns: u32) {
        *self.now.borrow_mut() += Duration::from_nanos(u64::from(ns));
    }
}

impl embedded_hal::digital::ErrorType for Fake {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::OutputPin for Fake {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        *self.de.borrow_mut() = false;
        self.log.borrow_mut().push(Seen::Low(self.now()));
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        *self.de.borrow_mut() = true;
        self.log.borrow_mut().push(Seen::High(self.now()));
        Ok(())
    }
}

/// A UART that takes every write at once into its buffer and never receives anything.
impl embedded_io::ErrorType for Fake {
    type Error = embedded_io::ErrorKind;
}

impl embedded_io::Write for Fake {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        let seen = Seen::Write {
            at: self.now(),
            bytes: buf.len(),
            de: *self.de.borrow(),
        };
        self.log.borrow_mut().push(seen);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl embedded_io::Read for Fake {
    fn read(&mut self, _buf: &mut [u8]) -> Result<usize, Self::Error> {
        Ok(0)
    }
}

impl embedded_io::ReadReady for Fake {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(false)
    }
}

/// The log of one UB2 request (5 bytes) sent once into silence.
fn one_request(line: Line) -> Vec<Seen> {
    let fake = Fake::default();
    *fake.now.borrow_mut() = Duration::from_millis(7);
    let mut timing = busspec_link::Timing::for_protocol::<Ub2>();
    timing.attempts = 1;
    let mut d: Driver<Ub2, _, _, _, _> = Driver::new(fake.clone(), fake.clone(), fake.clone())
        .with_driver_enable(fake.clone())
        .with_timing(timing)
        .with_line(line);
    let r = d.transact(
        0x21,
        ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
    );
    assert!(
        matches!(r, Err(Error::Link(Failure::NoReply { attempts: 1, .. }))),
        "{r:?}"
    );
    let log = fake.log.borrow().clone();
    log
}

#[test]
fn driver_enable_rises_before_the_first_byte_and_falls_when_the_last_has_left() {
    let mut line = Line::for_protocol::<Ub2>();
    line.driver_enable = Some(DriverEnable::Computed);
    let t0 = Duration::from_millis(7);
    // 5 bytes × 10 bits at 19,200 baud = 2,604,166.7 ns, rounded up.
    assert_eq!(
        one_request(line),
        [
            Seen::High(t0),
            Seen::Write {
                at: t0,
                bytes: 5,
                de: true
            },
            Seen::Low(t0 + Duration::from_nanos(2_604_167)),
        ]
    );
    // With a parity bit each byte takes 11 bits.
    line.bits_per_byte = 11;
    assert_eq!(
        one_request(line).last(),
        Some(&Seen::Low(t0 + Duration::from_nanos(2_864_584)))
    );
    // A UART whose flush waits for the shift register: down right after it.
    line.driver_enable = Some(DriverEnable::Flushed);
    assert_eq!(one_request(line).last(), Some(&Seen::Low(t0)));
    // No hook: the pin is never touched.
    line.driver_enable = None;
    assert_eq!(
        one_request(line),
        [Seen::Write {
            at: t0,
            bytes: 5,
            de: false
        }]
    );
}

#[test]
fn a_collision_names_the_offset_and_both_bytes() {
    let clock = SimClock::new();
    let mut config = BusConfig::new(Sd::BUS.baud);
    config.echo = true;
    config.collide_at = Some(1);
    let bus = SimBus::new(clock.clone(), config, vec![SdSim::new(1)]);
    let mut line = Line::for_protocol::<Sd>();
    line.echo = true;
    let mut m: Master<Sd, _, _> = Master::new(bus.clone(), clock).with_line(line);
    let err = m
        .transact(
            1,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
        )
        .unwrap_err();
    let mut frame = [0u8; 8];
    let n = busspec_link::Message::encode(
        &sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
        1,
        &mut frame,
    )
    .unwrap();
    let sent: String = frame[..n].iter().map(|b| format!("{b:02X}")).collect();
    assert_eq!(
        err.to_string(),
        format!(
            "sd read_actual_position to address 0x01: collision on the bus (3 attempts): the echo \
             of {sent} differs at offset 1: expected 0x{:02X}, received 0x{:02X}",
            frame[1], !frame[1]
        )
    );
    // The garbled requests never moved the device to answer.
    assert!(bus.with_devices(|d| d[0].target == 0));
    assert_eq!(Sd::NAME, "sd");
}

#[test]
fn a_missing_echo_says_how_much_came_back() {
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Sd::BUS.baud),
        vec![SdSim::new(1)],
    );
    let mut line = Line::for_protocol::<Sd>();
    line.echo = true;
    let mut m: Master<Sd, _, _> = Master::new(bus, clock).with_line(line);
    // Nobody at 2 answers, and the adapter does not echo after all. (With a device there, its
    // reply would be taken for a garbled echo: a collision at offset 0.)
    let err = m
        .transact(
            2,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
        )
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "sd read_actual_position to address 0x02: the line echoes, but only 0 of the 6 bytes of \
         69020000341E came back (3 attempts)"
    );
}
