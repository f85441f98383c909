//! Two SD actuators on two ports, polled concurrently by one tokio task each: every actuator
//! is moved through a few set points (the master keeps each one's freshness counter) and its
//! position read until it arrives. The ports are pseudo-terminals with the simulators serving
//! their other ends in this process (`PtySim`), so it runs anywhere; on hardware, open
//! `tokio_serial::SerialStream`s on the two ports instead.
//!
//! `cargo run -p busspec-link --features tokio --example tokio_two_ports`

use std::time::{Duration, Instant};

use busspec_devices::movement::SdMove;
use busspec_devices::sim::sd::SdSim;
use busspec_devices::Sd;
use busspec_link::sim::pty::PtySim;
use busspec_link::tokio_driver::AsyncMaster;
use busspec_link::LinkError;
use busspec_protocols::sd;
use tokio_serial::SerialStream;

/// Moves the actuator at `address` on `port` through `targets`; the time each move took.
async fn drive(
    name: &str,
    port: SerialStream,
    address: u8,
    targets: &[i16],
) -> Result<Vec<Duration>, LinkError> {
    let mut master: AsyncMaster<Sd, _> = AsyncMaster::new(port);
    let mut took = Vec::new();
    for &t in targets {
        let start = Instant::now();
        let target = sd::Angle(t);
        let movement = SdMove::new(target, Duration::from_millis(20), Duration::from_secs(10));
        let report = master.run_movement(address, movement, |_| {}).await?;
        println!(
            "{name}: actuator {address} at {:.1}° after {} position reads, {:?}",
            target.value(),
            report.polls,
            start.elapsed()
        );
        took.push(start.elapsed());
    }
    Ok(took)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (port_a, _sim_a) = PtySim::spawn(vec![SdSim::new(1)])?;
    let (port_b, _sim_b) = PtySim::spawn(vec![SdSim::new(2)])?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    rt.block_on(async {
        let a = SerialStream::try_from(port_a)?;
        let b = SerialStream::try_from(port_b)?;
        let started = Instant::now();
        let both = async {
            tokio::join!(
                drive("port A", a, 1, &[400, -400, 0]),
                drive("port B", b, 2, &[-800, 800, 100]),
            )
        };
        // Never hang: both ports have 30 s between them.
        let (ra, rb) = tokio::time::timeout(Duration::from_secs(30), both).await?;
        let (ta, tb) = (ra?, rb?);
        let total = started.elapsed();
        let sequential: Duration = ta.iter().chain(&tb).sum();
        println!(
            "both ports done in {total:?}; one after the other they would take about {sequential:?}"
        );
        Ok(())
    })
}
