//! One scenario suite, every driver: the scenarios of `common` (both protocols, faults, RS485
//! line habits) through the blocking `std` master, the `embedded-io` and `embedded-io-async`
//! drivers of busspec-link-core (on the simulated bus through an in-memory pipe), and the
//! tokio driver (feature `tokio`: through a real pseudo-terminal to the simulators served in a
//! thread, every transaction bounded by a timeout).

mod common;

#[cfg(feature = "tokio")]
use std::time::Duration;

use busspec_devices::{Sd, Ub2};
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::transport::Transport;
use busspec_link::{Link, Master, SimClock};
use busspec_link_core::movement::{MoveReport, Movement};
use busspec_link_core::{blocking, nonblocking};
use common::*;

type Bus = SimBus<Dev>;

fn sim_bus<P: Link>(setup: &mut Setup) -> (Bus, SimClock) {
    let clock = SimClock::new();
    let mut config = BusConfig::new(P::BUS.baud);
    config.echo = setup.echo;
    config.collide_at = setup.collide_at;
    config.driver_enable_required = setup.driver_enable_required;
    if let Some(l) = setup.reply_latency {
        config.reply_latency = l;
    }
    let devices = std::mem::take(&mut setup.devices);
    (SimBus::new(clock.clone(), config, devices), clock)
}

/// Every scenario, for drivers built by `ub2`, `sd` and `modbus` (Modbus by its spec alone).
fn run_suite<A: Drive<Ub2>, B: Drive<Sd>, C: Drive<Modbus>>(
    ub2: &mut dyn FnMut(Setup) -> A,
    sd: &mut dyn FnMut(Setup) -> B,
    modbus: &mut dyn FnMut(Setup) -> C,
) {
    modbus_by_its_spec(modbus);
    ub2_getter(ub2);
    ub2_byte_order_before_first_movement(ub2);
    ub2_movement_polled_to_completion(ub2);
    ub2_errors(ub2);
    ub2_faults_retried_only_where_safe(ub2);
    sd_freshness_and_broadcast(sd);
    sd_faults(sd);
    sd_move_polled_to_target(sd);
}

/// The RS485 scenarios, for drivers on the simulated bus (which can echo, collide and
/// require driver enable).
fn run_rs485_suite<A: Drive<Ub2>, B: Drive<Sd>>(
    ub2: &mut dyn FnMut(Setup) -> A,
    sd: &mut dyn FnMut(Setup) -> B,
) {
    rs485_echo(ub2);
    rs485_collision(sd);
    rs485_driver_enable(ub2);
    rs485_turnaround(ub2);
}

// The blocking std master.

struct StdDrive<P: Link>(Master<P, Bus, SimClock>);

fn std_master<P: Link>(mut setup: Setup) -> StdDrive<P> {
    let (bus, clock) = sim_bus::<P>(&mut setup);
    StdDrive(
        Master::new(bus, clock)
            .with_timing(setup.timing)
            .with_line(setup.line),
    )
}

impl<P: Link> Drive<P> for StdDrive<P> {
    fn transact(&mut self, address: u8, request: P::Request) -> Outcome<P::Response> {
        match self.0.transact(address, request) {
            Ok(ex) => Outcome::Reply(ex.response),
            Err(e) => Outcome::from_link_error(&e),
        }
    }
    fn start_movement(&mut self, address: u8, trigger: P::Request) -> Outcome<P::Response> {
        match self.0.start_movement(address, trigger) {
            Ok(ex) => Outcome::Reply(ex.response),
            Err(e) => Outcome::from_link_error(&e),
        }
    }
    fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
    ) -> Result<MoveReport<P::Response>, Outcome<P::Response>> {
        self.0
            .run_to_end(address, movement, &mut |_| {})
            .map_err(|e| Outcome::from_link_error(&e))
    }
}

#[test]
fn the_std_master_runs_the_suite() {
    run_suite(
        &mut std_master::<Ub2>,
        &mut std_master::<Sd>,
        &mut std_master::<Modbus>,
    );
    run_rs485_suite(&mut std_master::<Ub2>, &mut std_master::<Sd>);
}

// The embedded-io drivers, through an in-memory pipe to the simulated bus.

/// The bus's driver-enable line as an `embedded-hal` pin.
struct BusPin(Bus);

impl embedded_hal::digital::ErrorType for BusPin {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::OutputPin for BusPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        let _ = self.0.set_driver_enable(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        let _ = self.0.set_driver_enable(true);
        Ok(())
    }
}

struct EmbeddedDrive<P: Link>(blocking::Driver<P, Port<Bus>, SimTime, SimTime, BusPin>);

fn embedded_io<P: Link>(mut setup: Setup) -> EmbeddedDrive<P> {
    let (bus, clock) = sim_bus::<P>(&mut setup);
    let pin = BusPin(bus.clone());
    EmbeddedDrive(
        blocking::Driver::new(Port::new(bus), SimTime(clock.clone()), SimTime(clock))
            .with_driver_enable(pin)
            .with_timing(setup.timing)
            .with_line(setup.line),
    )
}

impl<P: Link> Drive<P> for EmbeddedDrive<P> {
    fn transact(&mut self, address: u8, request: P::Request) -> Outcome<P::Response> {
        match self.0.transact(address, request) {
            Ok(r) => Outcome::Reply(r.response),
            Err(e) => Outcome::from_failure(&e),
        }
    }
    fn start_movement(&mut self, address: u8, trigger: P::Request) -> Outcome<P::Response> {
        match self.0.start_movement(address, trigger) {
            Ok(r) => Outcome::Reply(r.response),
            Err(e) => Outcome::from_failure(&e),
        }
    }
    fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
    ) -> Result<MoveReport<P::Response>, Outcome<P::Response>> {
        self.0
            .run_movement(address, movement, |_| {})
            .map_err(|e| Outcome::from_failure(&e))
    }
}

#[test]
fn the_embedded_io_driver_runs_the_suite() {
    run_suite(
        &mut embedded_io::<Ub2>,
        &mut embedded_io::<Sd>,
        &mut embedded_io::<Modbus>,
    );
    run_rs485_suite(&mut embedded_io::<Ub2>, &mut embedded_io::<Sd>);
}

struct AsyncEmbeddedDrive<P: Link>(nonblocking::Driver<P, Port<Bus>, SimTime, SimTime, BusPin>);

fn embedded_io_async<P: Link>(mut setup: Setup) -> AsyncEmbeddedDrive<P> {
    let (bus, clock) = sim_bus::<P>(&mut setup);
    let pin = BusPin(bus.clone());
    AsyncEmbeddedDrive(
        nonblocking::Driver::new(Port::new(bus), SimTime(clock.clone()), SimTime(clock))
            .with_driver_enable(pin)
            .with_timing(setup.timing)
            .with_line(setup.line),
    )
}

impl<P: Link> Drive<P> for AsyncEmbeddedDrive<P> {
    fn transact(&mut self, address: u8, request: P::Request) -> Outcome<P::Response> {
        match block_on(self.0.transact(address, request)) {
            Ok(r) => Outcome::Reply(r.response),
            Err(e) => Outcome::from_failure(&e),
        }
    }
    fn start_movement(&mut self, address: u8, trigger: P::Request) -> Outcome<P::Response> {
        match block_on(self.0.start_movement(address, trigger)) {
            Ok(r) => Outcome::Reply(r.response),
            Err(e) => Outcome::from_failure(&e),
        }
    }
    fn run_movement<M: Movement<P>>(
        &mut self,
        address: u8,
        movement: M,
    ) -> Result<MoveReport<P::Response>, Outcome<P::Response>> {
        block_on(self.0.run_movement(address, movement, |_| {}))
            .map_err(|e| Outcome::from_failure(&e))
    }
}

#[test]
fn the_embedded_io_async_driver_runs_the_suite() {
    run_suite(
        &mut embedded_io_async::<Ub2>,
        &mut embedded_io_async::<Sd>,
        &mut embedded_io_async::<Modbus>,
    );
    run_rs485_suite(&mut embedded_io_async::<Ub2>, &mut embedded_io_async::<Sd>);
}

// The tokio driver, through a pseudo-terminal.

#[cfg(feature = "tokio")]
mod pty {
    use super::*;
    use busspec_link::sim::pty::PtySim;
    use busspec_link::tokio_driver::AsyncMaster;
    use tokio_serial::SerialStream;

    /// Longest any one transaction may take before the test calls it hung.
    const BOUND: Duration = Duration::from_secs(10);

    pub struct PtyDrive<P: Link> {
        rt: tokio::runtime::Runtime,
        master: Option<AsyncMaster<P, SerialStream>>,
        // Dropped after the master: stops serving and waits for the thread.
        _sim: PtySim,
    }

    /// A pseudo-terminal pair: the simulators serve one end in a thread (as `busspec sim
    /// --pty` does), the tokio master drives the other.
    pub fn tokio_pty<P: Link>(setup: Setup) -> PtyDrive<P> {
        let (master_end, sim) = PtySim::spawn(setup.devices).expect("a pseudo-terminal pair");
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("a tokio runtime");
        // A real line on a shared machine: more patience than in simulated time.
        let mut timing = setup.timing;
        timing.reply_timeout = timing.reply_timeout.max(Duration::from_millis(200));
        timing.settle = timing.reply_timeout;
        let master = rt.block_on(async {
            let stream = SerialStream::try_from(master_end).expect("a tokio serial stream");
            AsyncMaster::new(stream)
                .with_timing(timing)
                .with_line(setup.line)
        });
        PtyDrive {
            rt,
            master: Some(master),
            _sim: sim,
        }
    }

    impl<P: Link> PtyDrive<P> {
        fn bounded(
            &mut self,
            address: u8,
            request: P::Request,
            movement: bool,
        ) -> Outcome<P::Response> {
            let master = self.master.as_mut().expect("the master");
            let result = self.rt.block_on(async {
                let work = async {
                    if movement {
                        master.start_movement(address, request).await
                    } else {
                        master.transact(address, request).await
                    }
                };
                tokio::time::timeout(BOUND, work).await
            });
            match result {
                Ok(Ok(ex)) => Outcome::Reply(ex.response),
                Ok(Err(e)) => Outcome::from_link_error(&e),
                Err(_) => Outcome::Other(format!("no result within {BOUND:?}")),
            }
        }
    }

    impl<P: Link> Drive<P> for PtyDrive<P> {
        fn transact(&mut self, address: u8, request: P::Request) -> Outcome<P::Response> {
            self.bounded(address, request, false)
        }
        fn start_movement(&mut self, address: u8, trigger: P::Request) -> Outcome<P::Response> {
            self.bounded(address, trigger, true)
        }
        fn run_movement<M: Movement<P>>(
            &mut self,
            address: u8,
            movement: M,
        ) -> Result<MoveReport<P::Response>, Outcome<P::Response>> {
            let master = self.master.as_mut().expect("the master");
            let work = master.run_movement(address, movement, |_| {});
            match self
                .rt
                .block_on(async { tokio::time::timeout(BOUND, work).await })
            {
                Ok(r) => r.map_err(|e| Outcome::from_link_error(&e)),
                Err(_) => Err(Outcome::Other(format!("no result within {BOUND:?}"))),
            }
        }
    }

    #[test]
    fn the_tokio_driver_runs_the_suite_through_a_pseudo_terminal() {
        run_suite(
            &mut tokio_pty::<Ub2>,
            &mut tokio_pty::<Sd>,
            &mut tokio_pty::<Modbus>,
        );
    }
}
