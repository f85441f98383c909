//! The firmware example's set-point loop (examples/firmware), run on the host against the SD
//! simulator through the in-memory pipe: what the thumb binary would do on a board; and its
//! Modbus master variant against a device simulated from spec/modbus.yaml's `device:` section.

mod common;

use busspec_devices::sim::sd::SdSim;
use busspec_devices::Sd;
use busspec_firmware_example::set_point_loop;
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::{Protocol, SimClock};
use busspec_link_core::nonblocking::Driver;
use common::{block_on, Port, SimTime};

#[test]
fn the_set_point_loop_keeps_the_freshness_counter_and_drops_no_frame() {
    let clock = SimClock::new();
    let mut device = SdSim::new(1);
    // Another master counted to 5 before this one started.
    device.host_freshness = Some(5);
    let bus = SimBus::new(clock.clone(), BusConfig::new(Sd::BUS.baud), vec![device]);
    let mut driver: Driver<Sd, _, _, _> = Driver::new(
        Port::new(bus.clone()),
        SimTime(clock.clone()),
        SimTime(clock),
    );
    let targets: Vec<i16> = (0..40).map(|i| i * 50 - 1000).collect();
    let report = block_on(set_point_loop(&mut driver, 1, &targets)).expect("the loop runs");
    assert_eq!(report.answered, 40);
    // 40 set points counted on from 5, modulo 16.
    assert_eq!(report.last_freshness, Some((5 + 40) % 16));
    assert_eq!(report.host_freshness, (5 + 40) % 16);
    assert_eq!(report.dropped_frames, 0);
    bus.with_devices(|d| assert_eq!(d[0].target, *targets.last().unwrap()));
}

/// A Modbus device of the spec's `device:` section, on the simulated bus.
#[derive(Clone, PartialEq)]
struct ModbusDevice(busspec_model::sim::Sim);

impl busspec_link::sim::Device for ModbusDevice {
    fn on_frame(&mut self, frame: &[u8], _now: std::time::Duration) -> Option<Vec<u8>> {
        self.0.answer(frame)
    }
    fn address(&self) -> u8 {
        self.0.address()
    }
}

#[test]
fn the_modbus_variant_reads_writes_and_reads_back_by_the_spec_alone() {
    use busspec_firmware_example::modbus::poll_and_count;
    use busspec_link_core::Plain;
    use busspec_protocols::modbus::Modbus;

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/modbus.yaml");
    let spec = std::sync::Arc::new(busspec_model::load_file(&path).expect("spec loads"));
    let mut sim = busspec_model::sim::Sim::new(spec, 1);
    for (i, v) in [41, 7, 8].into_iter().enumerate() {
        assert!(sim.set_element("holding_registers", 100 + i as u32, v));
    }
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Modbus::BUS.baud),
        vec![ModbusDevice(sim)],
    );
    let mut driver: Driver<Plain<Modbus>, _, _, _> = Driver::new(
        Port::new(bus.clone()),
        SimTime(clock.clone()),
        SimTime(clock),
    );
    let report = block_on(poll_and_count(&mut driver, 1, 100, 3)).expect("the poll runs");
    assert_eq!(&report.before[..3], &[41, 7, 8]);
    assert_eq!(report.after, 42);
    assert_eq!(report.exception, None);
    bus.with_devices(|d| assert_eq!(d[0].0.element("holding_registers", 100), Some(42)));
    // Past the end of the table: the device's exception 2, as the refusal it is.
    let report = block_on(poll_and_count(&mut driver, 1, 9995, 8)).expect("the poll runs");
    assert_eq!(report.exception, Some(2));
}
