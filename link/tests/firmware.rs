//! The firmware example's set-point loop (examples/firmware), run on the host against the SD
//! simulator through the in-memory pipe: what the thumb binary would do on a board.

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
    let bus = SimBus::new(clock.clone(), BusConfig::new(Sd::BAUD), vec![device]);
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
