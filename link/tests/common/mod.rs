//! The scenario suite every driver runs, and what the drivers need to reach the simulators.
//!
//! A scenario is a function over [`Drive`], which every driver implements in
//! `tests/scenarios.rs`: the std `Master` and the two `embedded-io` drivers on the simulated
//! bus (the embedded ones through [`Port`], an in-memory pipe implementing the `embedded-io`
//! traits over it), the tokio driver through a pseudo-terminal to the simulators served in a
//! thread. Devices are [`Shared`], so a scenario can look at them wherever they run, and
//! [`Flaky`] injects the faults.
#![allow(dead_code)]

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use busspec_devices::movement::{SdMove, Ub2Movement};
use busspec_devices::sim::sd::SdSim;
use busspec_devices::sim::ub2::Ub2Sim;
use busspec_devices::{Sd, Ub2};
use busspec_link::clock::{Clock, SimClock};
use busspec_link::master::LinkError;
use busspec_link::sim::Device;
use busspec_link::transport::Transport;
use busspec_link::{Line, Link, Protocol, Timing};
use busspec_link_core::driver::{Error as DriverError, Now};
use busspec_link_core::movement::{MoveError, MoveReport, Movement};
use busspec_link_core::Failure;
use busspec_protocols::{sd, ub2};

/// What a transaction came to, the same for every driver.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome<R> {
    Reply(Option<R>),
    NoReply,
    BadReply,
    Collision { offset: usize },
    NoEcho,
    ByteOrder,
    Address,
    MoveTimeout,
    Other(String),
}

impl<R> Outcome<R> {
    pub fn from_link_error(e: &LinkError) -> Self {
        match e {
            LinkError::NoReply { .. } => Outcome::NoReply,
            LinkError::BadReply { .. } => Outcome::BadReply,
            LinkError::Collision { offset, .. } => Outcome::Collision { offset: *offset },
            LinkError::NoEcho { .. } => Outcome::NoEcho,
            LinkError::ByteOrder { .. } => Outcome::ByteOrder,
            LinkError::Address { .. } => Outcome::Address,
            LinkError::MovementTimeout { .. } => Outcome::MoveTimeout,
            other => Outcome::Other(other.to_string()),
        }
    }

    pub fn from_failure<P: Link<Response = R>, E: std::fmt::Debug>(e: &DriverError<P, E>) -> Self {
        match e {
            DriverError::Link(Failure::NoReply { .. }) => Outcome::NoReply,
            DriverError::Link(Failure::BadReply { .. }) => Outcome::BadReply,
            DriverError::Link(Failure::Collision { offset, .. }) => {
                Outcome::Collision { offset: *offset }
            }
            DriverError::Link(Failure::NoEcho { .. }) => Outcome::NoEcho,
            DriverError::Link(Failure::ByteOrder { .. }) => Outcome::ByteOrder,
            DriverError::Link(Failure::Address { .. }) => Outcome::Address,
            DriverError::Move(MoveError::Timeout { .. }) => Outcome::MoveTimeout,
            other => Outcome::Other(format!("{other:?}")),
        }
    }
}

/// A driver, as the scenarios use it.
pub trait Drive<P: Link> {
    fn transact(&mut self, address: u8, request: P::Request) -> Outcome<P::Response>;
    fn start_movement(&mut self, address: u8, trigger: P::Request) -> Outcome<P::Response>;
    fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
    ) -> Result<MoveReport<P::Response>, Outcome<P::Response>>;
}

/// A device several owners can reach (the bus or a serving thread, and the test).
pub struct Shared<D>(pub Arc<Mutex<D>>);

impl<D> Clone for Shared<D> {
    fn clone(&self) -> Self {
        Shared(Arc::clone(&self.0))
    }
}

impl<D: Device> Shared<D> {
    pub fn new(d: D) -> Self {
        Shared(Arc::new(Mutex::new(d)))
    }
    pub fn with<R>(&self, f: impl FnOnce(&mut D) -> R) -> R {
        f(&mut self.0.lock().unwrap())
    }
}

impl<D: Device> Device for Shared<D> {
    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        self.0.lock().unwrap().on_frame(frame, now)
    }
    fn address(&self) -> u8 {
        self.0.lock().unwrap().address()
    }
}

/// Faults on a device's replies: the first `mute` replies are lost, the next `corrupt` have
/// their last byte (the checksum) inverted.
pub struct Flaky<D> {
    pub inner: D,
    pub mute: u32,
    pub corrupt: u32,
}

impl<D: Device> Device for Flaky<D> {
    fn on_frame(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        let mut reply = self.inner.on_frame(frame, now)?;
        if self.mute > 0 {
            self.mute -= 1;
            return None;
        }
        if self.corrupt > 0 {
            self.corrupt -= 1;
            if let Some(b) = reply.last_mut() {
                *b = !*b;
            }
        }
        Some(reply)
    }
    fn address(&self) -> u8 {
        self.inner.address()
    }
}

pub type Dev = Box<dyn Device + Send>;

/// What a scenario asks of a driver factory: the devices, the timing and the line.
pub struct Setup {
    pub devices: Vec<Dev>,
    pub timing: Timing,
    pub line: Line,
    /// Line behaviour of the simulated bus, where the driver runs on one.
    pub echo: bool,
    pub collide_at: Option<usize>,
    pub driver_enable_required: bool,
    pub reply_latency: Option<Duration>,
}

impl Setup {
    pub fn new<P: Link>(devices: Vec<Dev>) -> Self {
        Setup {
            devices,
            // Short enough that a scenario without a device is quick on a real pty too.
            timing: Timing {
                reply_timeout: Duration::from_millis(60),
                settle: Duration::from_millis(60),
                ..Timing::for_protocol::<P>()
            },
            line: Line::for_protocol::<P>(),
            echo: false,
            collide_at: None,
            driver_enable_required: false,
            reply_latency: None,
        }
    }
}

// The scenarios. Each builds its own devices and driver through `make`.

pub fn ub2_getter<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let dev = Shared::new(Ub2Sim::new(0x21));
    let mut m = make(Setup::new::<Ub2>(vec![Box::new(dev.clone())]));
    let expected = dev.with(|d| {
        d.respond(
            &ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
            Duration::ZERO,
        )
    });
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::Reply(Some(expected))
    );
    // A setter, then the getter that reads it back.
    let set = ub2::Request::SetAccelerationSpeedIndex(ub2::request::SetAccelerationSpeedIndex {
        acceleration_index: 3,
        speed_index: 4,
    });
    assert!(matches!(m.transact(0x21, set), Outcome::Reply(Some(_))));
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetAccelerationSpeed(ub2::request::GetAccelerationSpeed)
        ),
        Outcome::Reply(Some(ub2::Response::AccelerationSpeed(
            ub2::response::AccelerationSpeed {
                acceleration_index: 3,
                speed_index: 4
            }
        )))
    );
    assert_eq!(dev.with(|d| (d.acceleration_index, d.speed_index)), (3, 4));
}

pub fn ub2_byte_order_before_first_movement<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let go = ub2::Request::GoToCapacitance(ub2::request::GoToCapacitance {
        target: ub2::Capacitance(15000),
    });
    let good = Shared::new(Ub2Sim::new(0x21));
    let swapped = Shared::new(Ub2Sim::new(0x22).msb_first(true));
    let mut m = make(Setup::new::<Ub2>(vec![
        Box::new(good.clone()),
        Box::new(swapped.clone()),
    ]));
    assert_eq!(
        m.start_movement(0x21, go),
        Outcome::Reply(Some(ub2::Response::MovementStarted(
            ub2::response::MovementStarted
        )))
    );
    assert!(good.with(|d| d.movement.is_some()));
    assert_eq!(m.start_movement(0x22, go), Outcome::ByteOrder);
    assert!(swapped.with(|d| d.movement.is_none()), "moved anyway");
}

pub fn ub2_movement_polled_to_completion<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let dev = Shared::new(Ub2Sim::new(0x21));
    let mut m = make(Setup::new::<Ub2>(vec![Box::new(dev.clone())]));
    let go = ub2::Request::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target: 40 });
    let poll = Duration::from_millis(20);
    let report = m
        .run_movement(0x21, Ub2Movement::new(go, poll, Duration::from_secs(20)))
        .expect("the movement completes");
    assert_eq!(
        report.started,
        ub2::Response::MovementStarted(ub2::response::MovementStarted)
    );
    assert_eq!(
        report.finished,
        Some(ub2::Response::MovementCompleted(
            ub2::response::MovementCompleted
        ))
    );
    assert!(report.polls >= 1);
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetActualFullStepPosition(ub2::request::GetActualFullStepPosition)
        ),
        Outcome::Reply(Some(ub2::Response::ActualFullStepPosition(
            ub2::response::ActualFullStepPosition { full_steps: 40 }
        )))
    );
    // Not a trigger: nothing is sent.
    let not = Ub2Movement::new(
        ub2::Request::GetStatus(ub2::request::GetStatus),
        poll,
        Duration::ZERO,
    );
    assert!(m.run_movement(0x21, not).is_err());
    // Not done in no time.
    let far =
        ub2::Request::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target: 4000 });
    assert_eq!(
        m.run_movement(0x21, Ub2Movement::new(far, poll, Duration::ZERO))
            .unwrap_err(),
        Outcome::MoveTimeout
    );
}

pub fn sd_move_polled_to_target<D: Drive<Sd>>(make: &mut dyn FnMut(Setup) -> D) {
    let dev = Shared::new(SdSim::new(1));
    let mut m = make(Setup::new::<Sd>(vec![Box::new(dev.clone())]));
    let target = sd::Angle(300);
    let report = m
        .run_movement(
            1,
            SdMove::new(target, Duration::from_millis(20), Duration::from_secs(20)),
        )
        .expect("the actuator gets there");
    assert_eq!(
        report.finished,
        Some(sd::Response::ActualPosition(sd::response::ActualPosition {
            position: target
        }))
    );
    assert_eq!(dev.with(|d| d.target), 300);
}

pub fn ub2_errors<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let mut m = make(Setup::new::<Ub2>(vec![Box::new(Ub2Sim::new(0x21))]));
    // Nobody at 0x25; 0x00 is no device address (and UB2 has no broadcast).
    assert_eq!(
        m.transact(
            0x25,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::NoReply
    );
    assert_eq!(
        m.transact(
            0x00,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::Address
    );
    // The line is usable afterwards.
    assert!(matches!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::Reply(Some(ub2::Response::ActualCapacitance(_)))
    ));
}

pub fn ub2_faults_retried_only_where_safe<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    // A getter whose first reply is lost and second garbled: the third send gets through.
    let dev = Shared::new(Flaky {
        inner: Ub2Sim::new(0x21),
        mute: 1,
        corrupt: 1,
    });
    let mut m = make(Setup::new::<Ub2>(vec![Box::new(dev.clone())]));
    assert!(matches!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::Reply(Some(ub2::Response::ActualCapacitance(_)))
    ));
    // A movement whose reply is garbled is not sent again.
    dev.with(|d| d.corrupt = 1);
    let go = ub2::Request::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target: 100 });
    assert_eq!(m.transact(0x21, go), Outcome::BadReply);
    assert!(dev.with(|d| d.inner.movement.is_some()));
}

pub fn sd_freshness_and_broadcast<D: Drive<Sd>>(make: &mut dyn FnMut(Setup) -> D) {
    let a = Shared::new(SdSim::new(1));
    let b = Shared::new(SdSim::new(2));
    a.with(|d| d.host_freshness = Some(9));
    let mut m = make(Setup::new::<Sd>(vec![
        Box::new(a.clone()),
        Box::new(b.clone()),
    ]));
    for i in 0..20 {
        let sp = sd::Request::SetPoint(sd::request::SetPoint {
            freshness: 0,
            position: sd::Angle(100 + i),
        });
        assert!(matches!(m.transact(1, sp), Outcome::Reply(Some(_))), "{i}");
    }
    // Every set point carried the next counter, starting from the device's 9.
    assert_eq!(a.with(|d| d.dropped_frames), 0);
    assert_eq!(a.with(|d| d.host_freshness), Some((9 + 20) % 16));
    assert_eq!(a.with(|d| d.target), 119);
    // A set point to everyone is not answered.
    let all = sd::Request::SetPoint(sd::request::SetPoint {
        freshness: 0,
        position: sd::Angle(-200),
    });
    let broadcast = Sd::BUS.broadcast_address.unwrap();
    assert_eq!(m.transact(broadcast, all), Outcome::Reply(None));
    // The next transaction goes out after the broadcast has been taken in, wherever the
    // devices run.
    assert!(m
        .transact(
            2,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
        )
        .is_reply());
    assert_eq!(b.with(|d| d.target), -200);
}

pub fn sd_faults<D: Drive<Sd>>(make: &mut dyn FnMut(Setup) -> D) {
    let dev = Shared::new(Flaky {
        inner: SdSim::new(3),
        mute: 1,
        corrupt: 1,
    });
    let mut m = make(Setup::new::<Sd>(vec![Box::new(dev.clone())]));
    assert!(matches!(
        m.transact(
            3,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
        ),
        Outcome::Reply(Some(sd::Response::ActualPosition(_)))
    ));
    assert_eq!(
        m.transact(
            4,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
        ),
        Outcome::NoReply
    );
}

// RS485 line habits, on a simulated line that has them.

/// An adapter that echoes: with echo suppression the master reads back its own request and
/// then the reply; without, it takes its echo for the reply and fails.
pub fn rs485_echo<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let echoing = |suppress: bool| {
        let mut s = Setup::new::<Ub2>(vec![Box::new(Ub2Sim::new(0x21))]);
        s.echo = true;
        s.line.echo = suppress;
        s
    };
    let mut m = make(echoing(true));
    for _ in 0..3 {
        assert!(m
            .transact(
                0x21,
                ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
            )
            .is_reply());
    }
    let mut m = make(echoing(false));
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::BadReply
    );
}

/// Another transmitter garbles byte 2 of every request: the echo differs there, and the
/// master says so (after its retries, the request being a getter).
pub fn rs485_collision<D: Drive<Sd>>(make: &mut dyn FnMut(Setup) -> D) {
    let mut s = Setup::new::<Sd>(vec![Box::new(SdSim::new(1))]);
    s.echo = true;
    s.line.echo = true;
    s.collide_at = Some(2);
    let mut m = make(s);
    assert_eq!(
        m.transact(
            1,
            sd::Request::ReadActualPosition(sd::request::ReadActualPosition)
        ),
        Outcome::Collision { offset: 2 }
    );
}

/// A transceiver that drives the bus only while driver enable is high: without the hook
/// nothing reaches the device; with it (timed from the baud rate) every request does.
pub fn rs485_driver_enable<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let gated = |hook: Option<busspec_link::DriverEnable>| {
        let mut s = Setup::new::<Ub2>(vec![Box::new(Ub2Sim::new(0x21))]);
        s.driver_enable_required = true;
        s.line.driver_enable = hook;
        s
    };
    let mut m = make(gated(None));
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::NoReply
    );
    let mut m = make(gated(Some(busspec_link::DriverEnable::Computed)));
    for _ in 0..3 {
        assert!(m
            .transact(
                0x21,
                ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
            )
            .is_reply());
    }
}

/// A device that needs 150 ms to turn its line around, against a 60 ms reply timeout: lost
/// without the turnaround delay, answered with it.
pub fn rs485_turnaround<D: Drive<Ub2>>(make: &mut dyn FnMut(Setup) -> D) {
    let slow = |turnaround: Duration| {
        let mut s = Setup::new::<Ub2>(vec![Box::new(Ub2Sim::new(0x21))]);
        s.reply_latency = Some(Duration::from_millis(150));
        s.line.turnaround = turnaround;
        // One send: a retry would take the late answer to the first one.
        s.timing.attempts = 1;
        s
    };
    let mut m = make(slow(Duration::ZERO));
    assert_eq!(
        m.transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        ),
        Outcome::NoReply
    );
    let mut m = make(slow(Duration::from_millis(150)));
    assert!(m
        .transact(
            0x21,
            ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance)
        )
        .is_reply());
}

impl<R> Outcome<R> {
    pub fn is_reply(&self) -> bool {
        matches!(self, Outcome::Reply(Some(_)))
    }
}

// Reaching the simulated bus through embedded-io.

/// An in-memory pipe to any [`Transport`] (the simulated bus) through the `embedded-io` and
/// `embedded-io-async` traits: reads look ahead one chunk, so `ReadReady` can say whether
/// bytes are there without waiting.
pub struct Port<T> {
    pub inner: T,
    ahead: VecDeque<u8>,
}

impl<T: Transport> Port<T> {
    pub fn new(inner: T) -> Self {
        Port {
            inner,
            ahead: VecDeque::new(),
        }
    }

    fn fill(&mut self) -> Result<(), embedded_io::ErrorKind> {
        if self.ahead.is_empty() {
            let mut chunk = [0u8; 64];
            let n = self
                .inner
                .read(&mut chunk, Duration::ZERO)
                .map_err(|_| embedded_io::ErrorKind::Other)?;
            self.ahead.extend(&chunk[..n]);
        }
        Ok(())
    }

    fn take(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.ahead.len());
        for (b, v) in buf.iter_mut().zip(self.ahead.drain(..n)) {
            *b = v;
        }
        n
    }
}

impl<T> embedded_io::ErrorType for Port<T> {
    type Error = embedded_io::ErrorKind;
}

impl<T: Transport> embedded_io::ReadReady for Port<T> {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        self.fill()?;
        Ok(!self.ahead.is_empty())
    }
}

impl<T: Transport> embedded_io::Read for Port<T> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        self.fill()?;
        Ok(self.take(buf))
    }
}

impl<T: Transport> embedded_io::Write for Port<T> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.inner
            .write(buf)
            .map_err(|_| embedded_io::ErrorKind::Other)?;
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl<T: Transport> embedded_io_async::Read for Port<T> {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        embedded_io::Read::read(self, buf)
    }
}

impl<T: Transport> embedded_io_async::Write for Port<T> {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        embedded_io::Write::write(self, buf)
    }
    async fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Simulated time as the embedded drivers see it: a [`Now`] and a delay (blocking and async)
/// that moves the clock forward.
#[derive(Clone)]
pub struct SimTime(pub SimClock);

impl Now for SimTime {
    fn now(&self) -> Duration {
        self.0.now()
    }
}

impl embedded_hal::delay::DelayNs for SimTime {
    fn delay_ns(&mut self, ns: u32) {
        self.0.advance(Duration::from_nanos(u64::from(ns)));
    }
}

impl embedded_hal_async::delay::DelayNs for SimTime {
    async fn delay_ns(&mut self, ns: u32) {
        self.0.advance(Duration::from_nanos(u64::from(ns)));
    }
}

/// Runs a future that never waits on anything but simulated time (so it is ready when
/// polled, or pending only in between): polls it until it is done, at most a million times.
pub fn block_on<F: std::future::Future>(f: F) -> F::Output {
    use std::task::{Context, Poll, Wake, Waker};
    struct Noop;
    impl Wake for Noop {
        fn wake(self: Arc<Self>) {}
    }
    let waker = Waker::from(Arc::new(Noop));
    let mut cx = Context::from_waker(&waker);
    let mut f = std::pin::pin!(f);
    for _ in 0..1_000_000 {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
    panic!("the future did not finish: it waits on something besides simulated time");
}

// Any protocol, by its spec alone: Modbus RTU through `Plain`, no rules of its own.

/// The generic master's view of Modbus: the codec's `Protocol` with the spec-driven `Link`.
pub type Modbus = busspec_link_core::link::Plain<busspec_protocols::modbus::Modbus>;

/// A Modbus server of ten holding registers (0..=9) at `address`: reads of them are answered,
/// reads beyond are refused with exception 2 (illegal data address), writes land and are
/// echoed; a broadcast write lands unanswered. Counts the frames it took.
pub struct ModbusRegisters {
    pub address: u8,
    pub registers: [u16; 10],
    pub frames: u32,
}

impl ModbusRegisters {
    pub fn new(address: u8) -> Self {
        ModbusRegisters {
            address,
            registers: core::array::from_fn(|i| 100 + i as u16),
            frames: 0,
        }
    }
}

impl Device for ModbusRegisters {
    fn on_frame(&mut self, frame: &[u8], _now: Duration) -> Option<Vec<u8>> {
        use busspec_protocols::modbus::{self, ExceptionCode, Request as Q, Response as R};
        let d = Modbus::decode_request(frame).ok()?;
        let broadcast = Some(d.address) == Modbus::BUS.broadcast_address;
        if d.address != self.address && !broadcast {
            return None;
        }
        self.frames += 1;
        let response = match d.message {
            Q::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
                starting_address,
                quantity,
            }) => {
                let (start, n) = (usize::from(starting_address), usize::from(quantity));
                match self.registers.get(start..start + n) {
                    Some(regs) => {
                        R::ReadHoldingRegistersReply(modbus::response::ReadHoldingRegistersReply {
                            registers: busspec_protocols::Repeated::from_slice(regs).ok()?,
                        })
                    }
                    None => R::ReadHoldingRegistersException(
                        modbus::response::ReadHoldingRegistersException {
                            exception_code: ExceptionCode::IllegalDataAddress,
                        },
                    ),
                }
            }
            Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
                register_address,
                register_value,
            }) => match self.registers.get_mut(usize::from(register_address)) {
                Some(r) => {
                    *r = register_value;
                    R::WriteSingleRegisterReply(modbus::response::WriteSingleRegisterReply {
                        register_address,
                        register_value,
                    })
                }
                None => R::WriteSingleRegisterException(
                    modbus::response::WriteSingleRegisterException {
                        exception_code: ExceptionCode::IllegalDataAddress,
                    },
                ),
            },
            _ => return None,
        };
        if broadcast {
            return None;
        }
        busspec_link::sim::reply::<Modbus>(&response, self.address)
    }
    fn address(&self) -> u8 {
        self.address
    }
}

/// The master runs Modbus from its spec alone: a read is answered, a refusal (exception reply,
/// `kind: nak`) is the device's answer and not retried, a read whose replies are lost is sent
/// again (reads are `retry.safe_kinds`), a write whose reply is lost is not, and a broadcast
/// write lands unanswered.
pub fn modbus_by_its_spec<D: Drive<Modbus>>(make: &mut dyn FnMut(Setup) -> D) {
    use busspec_protocols::modbus::{self, ExceptionCode, Request as Q, Response as R};
    let dev = Shared::new(Flaky {
        inner: ModbusRegisters::new(7),
        mute: 0,
        corrupt: 0,
    });
    let mut m = make(Setup::new::<Modbus>(vec![Box::new(dev.clone())]));
    let read = |start: u16, quantity: u16| {
        Q::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
            starting_address: start,
            quantity,
        })
    };
    let regs = |v: &[u16]| {
        R::ReadHoldingRegistersReply(modbus::response::ReadHoldingRegistersReply {
            registers: busspec_protocols::Repeated::from_slice(v).unwrap(),
        })
    };
    assert_eq!(
        m.transact(7, read(2, 3)),
        Outcome::Reply(Some(regs(&[102, 103, 104])))
    );
    // A refusal is an answer: once, no retry.
    let frames = dev.with(|d| d.inner.frames);
    let refused = m.transact(7, read(9, 2));
    let exception =
        R::ReadHoldingRegistersException(modbus::response::ReadHoldingRegistersException {
            exception_code: ExceptionCode::IllegalDataAddress,
        });
    assert_eq!(refused, Outcome::Reply(Some(exception)));
    assert!(Modbus::is_refusal(&read(9, 2), &exception));
    assert_eq!(dev.with(|d| d.inner.frames), frames + 1);
    // A read whose first two replies are lost: sent three times, answered the third.
    dev.with(|d| d.mute = 2);
    let frames = dev.with(|d| d.inner.frames);
    assert_eq!(
        m.transact(7, read(0, 1)),
        Outcome::Reply(Some(regs(&[100])))
    );
    assert_eq!(dev.with(|d| d.inner.frames), frames + 3);
    // A write whose reply is lost: sent once, the write landed, the master says no reply.
    dev.with(|d| d.mute = 1);
    let frames = dev.with(|d| d.inner.frames);
    let write = Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
        register_address: 4,
        register_value: 0xBEEF,
    });
    assert_eq!(m.transact(7, write), Outcome::NoReply);
    assert_eq!(
        dev.with(|d| (d.inner.frames, d.inner.registers[4])),
        (frames + 1, 0xBEEF)
    );
    // A broadcast write (address 0): not answered, carried out.
    let write = Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
        register_address: 5,
        register_value: 55,
    });
    assert_eq!(m.transact(0, write), Outcome::Reply(None));
    // The next request, after the turnaround, reads what it wrote.
    assert_eq!(m.transact(7, read(5, 1)), Outcome::Reply(Some(regs(&[55]))));
    // A read does not accept the broadcast address.
    assert_eq!(m.transact(0, read(0, 1)), Outcome::Address);
}
