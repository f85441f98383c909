//! Runs transactions through the sans-IO master core (`busspec-link-core`), in memory, a given
//! number of times, for counting instructions under callgrind (`benches/icount-link.sh`): the
//! difference between two pass counts, divided by the difference in transactions, is the cost
//! of one transaction — the core's rules plus the codec's encode of the request and decode of
//! the reply — with the set-up (simulated replies) subtracted out.
//!
//! ```text
//! icount_link <ub2|sd> <passes>
//! ```
//!
//! A pass is one transaction per request of a small mix (getters, a setter, for SD set
//! points with their freshness counter), each answered by the reply the simulator gave.

use std::process::ExitCode;
use std::time::Duration;

use busspec_devices::sim::sd::SdSim;
use busspec_devices::sim::ub2::Ub2Sim;
use busspec_link::sim::Device;
use busspec_link::Link;
use busspec_link_core::master::{Action, MasterCore};
use busspec_protocols::{sd, ub2, Message};

/// Each request with the reply the device gives it (the frame the core will send, answered).
fn answered<P: Link, D: Device>(
    mut device: D,
    core: &MasterCore<P>,
    requests: &[P::Request],
) -> Vec<(P::Request, Vec<u8>)> {
    let address = device.address();
    requests
        .iter()
        .map(|q| {
            let mut q = *q;
            if let Some(f) = P::freshness_mut(&mut q) {
                *f = core.next_freshness_value(address).unwrap_or(0);
            }
            let mut frame = vec![0u8; P::MAX_FRAME_LEN];
            let n = q.encode(address, &mut frame).expect("the mix encodes");
            let reply = device
                .on_frame(&frame[..n], Duration::ZERO)
                .expect("the device answers the mix");
            (q, reply)
        })
        .collect()
}

/// Runs `passes` passes of `mix` through `core`; returns the transactions' total attempts.
fn run<P: Link>(
    core: &mut MasterCore<P>,
    address: u8,
    mix: &[(P::Request, Vec<u8>)],
    passes: u64,
) -> u64 {
    let mut now = Duration::ZERO;
    let mut attempts = 0u64;
    for _ in 0..passes {
        for (request, reply) in mix {
            core.start(address, *request);
            loop {
                match core.poll(now) {
                    Action::Done => break,
                    Action::Sleep(t) => now = t,
                    Action::Read { .. } => core.received(reply, now),
                    _ => {}
                }
                while core.take_event().is_some() {}
            }
            match core.take_outcome() {
                Some(Ok(r)) => attempts += u64::from(r.attempts),
                other => panic!("{:?} failed: {other:?}", request.name()),
            }
        }
    }
    attempts
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (proto, passes) = match args.as_slice() {
        [p, n] => match n.parse::<u64>() {
            Ok(n) => (p.as_str(), n),
            Err(_) => {
                eprintln!("passes must be a number\nusage: icount_link <ub2|sd> <passes>");
                return ExitCode::FAILURE;
            }
        },
        _ => {
            eprintln!("usage: icount_link <ub2|sd> <passes>");
            return ExitCode::FAILURE;
        }
    };
    let (units, total) = match proto {
        "ub2" => {
            let mut core: MasterCore<busspec_devices::Ub2> = MasterCore::new();
            let mix = answered(
                Ub2Sim::new(0x21),
                &core,
                &[
                    ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
                    ub2::Request::GetActualFullStepPosition(
                        ub2::request::GetActualFullStepPosition,
                    ),
                    ub2::Request::GetControllerTemperature(ub2::request::GetControllerTemperature),
                    ub2::Request::GetCCurveIndexedFullStepCapacitance(
                        ub2::request::GetCCurveIndexedFullStepCapacitance { index: 3 },
                    ),
                    ub2::Request::SetAccelerationSpeedIndex(
                        ub2::request::SetAccelerationSpeedIndex {
                            acceleration_index: 3,
                            speed_index: 4,
                        },
                    ),
                ],
            );
            (mix.len(), run(&mut core, 0x21, &mix, passes))
        }
        "sd" => {
            let mut core: MasterCore<busspec_devices::Sd> = MasterCore::new();
            // The counter is known, so no set point reads it first: every pass is alike.
            core.set_freshness(1, 0);
            let set_point = sd::Request::SetPoint(sd::request::SetPoint {
                freshness: 0,
                position: sd::Angle(100),
            });
            let mix = answered(
                SdSim::new(1),
                &core,
                &[
                    sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
                    sd::Request::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter),
                    set_point,
                    sd::Request::ReadActualPosition(sd::request::ReadActualPosition),
                    set_point,
                ],
            );
            (mix.len(), run(&mut core, 1, &mix, passes))
        }
        other => {
            eprintln!("unknown protocol `{other}`\nusage: icount_link <ub2|sd> <passes>");
            return ExitCode::FAILURE;
        }
    };
    println!("units per pass: {units}");
    println!("attempts: {total}");
    ExitCode::SUCCESS
}
