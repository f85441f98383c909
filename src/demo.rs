//! `busspec demo`: a scripted session against simulated devices, no hardware. Time is
//! simulated, so movements that take seconds on a real bus print at once.

use std::path::Path;
use std::time::Duration;

use busspec_devices::master::{SdMaster, SdString, Ub2Master};
use busspec_devices::sim::sd::SdSim;
use busspec_devices::sim::ub2::Ub2Sim;
use busspec_devices::{Sd, Ub2};
use busspec_link::clock::Clock;
use busspec_link::fault::{FaultConfig, Faulty};
use busspec_link::master::Progress;
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::soak::{self, SoakConfig};
use busspec_link::{Link, Master, Message, Protocol, SimClock, Transport};
use busspec_model::Protocol as Spec;
use busspec_protocols::sd::{self, Angle};
use busspec_protocols::ub2::{self, Capacitance};

use crate::frames::hex;
use crate::link_cli::{reply_json, svg_file};

struct Out<'a> {
    lines: Vec<String>,
    spec: &'a Spec,
}

impl Out<'_> {
    fn say(&mut self, s: impl Into<String>) {
        let s = s.into();
        println!("{s}");
        self.lines.push(s);
    }

    /// One transaction, printed as the request (name, hex) and the reply as `decode` prints it.
    fn step<P: Link, T: Transport, C: Clock>(
        &mut self,
        m: &mut Master<P, T, C>,
        address: u8,
        request: P::Request,
    ) -> Result<Option<P::Response>, String>
    where
        P::Response: busspec_protocols::Message,
    {
        let ex = m
            .transact(address, request)
            .map_err(|e| format!("demo failed: {e}"))?;
        self.say(format!(
            "→ 0x{address:02X} {:<40} {}",
            request.name(),
            hex(&ex.sent)
        ));
        match ex.response {
            Some(r) => {
                let retried = if ex.attempts > 1 {
                    format!("   (after {} sends)", ex.attempts)
                } else {
                    String::new()
                };
                self.say(format!(
                    "← {}{retried}",
                    reply_json::<P>(self.spec, &r, ex.address)
                ));
                Ok(Some(r))
            }
            None => {
                self.say("← (broadcast: no reply expected)");
                Ok(None)
            }
        }
    }
}

/// Prints movement progress every half second of simulated time.
fn progress<'a>(lines: &'a mut Vec<String>, unit: &'static str) -> impl FnMut(Progress) + 'a {
    let mut next = Duration::ZERO;
    move |p| {
        if let Progress::Moving { elapsed, position } = p {
            if elapsed >= next {
                let s = format!(
                    "   … {position:.1} {unit} at {:.1} s",
                    elapsed.as_secs_f64()
                );
                println!("{s}");
                lines.push(s);
                next = elapsed + Duration::from_millis(500);
            }
        }
    }
}

/// Runs the scripted session; returns what it printed.
pub fn demo(ub2_spec: &Spec, sd_spec: &Spec, svg: Option<&Path>) -> Result<Vec<String>, String> {
    let mut out = Out {
        lines: Vec::new(),
        spec: ub2_spec,
    };
    document_frame(&mut out)?;
    ub2_part(&mut out, svg)?;
    out.spec = sd_spec;
    sd_part(&mut out)?;
    faults_part(&mut out)?;
    Ok(out.lines)
}

/// First, what `busspec decode` does with a frame the UB2 document prints (§6.1).
fn document_frame(out: &mut Out) -> Result<(), String> {
    let printed = "AA21 4101 0000 1F3E 6A";
    let wire = "AA21 4101 3E1F 0000 6A";
    out.say(format!(
        "== A frame from the UB2 document (§6.1, printed {printed}; on the wire {wire}, erratum ub2-e01): busspec decode ub2 \"{wire}\""
    ));
    let bytes = busspec_json::parse_hex(wire)?;
    let frame = busspec_json::decode_typed::<ub2::Ub2>(out.spec, None, None, &bytes)?;
    out.say(format!("← {}", frame.line(out.spec, None)?));
    Ok(())
}

fn ub2_part(out: &mut Out, svg: Option<&Path>) -> Result<(), String> {
    use ub2::Request as Q;
    out.say("== UB2: two motorized capacitors, 0x21 and 0x22, on one simulated RS485 bus (19,200 baud, 10 ms between commands)");
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Ub2::BUS.baud),
        vec![Ub2Sim::new(0x21), Ub2Sim::new(0x22)],
    );
    let mut m: Master<Ub2, _, _> = Master::new(bus.clone(), clock.clone());
    for q in [
        Q::GetFirmwareVersion(ub2::request::GetFirmwareVersion),
        Q::GetSerialNumber(ub2::request::GetSerialNumber),
        Q::GetLowerFactoryLimit(ub2::request::GetLowerFactoryLimit),
        Q::GetUpperFactoryLimit(ub2::request::GetUpperFactoryLimit),
        Q::GetStatus(ub2::request::GetStatus),
        Q::GetStatus(ub2::request::GetStatus),
    ] {
        out.step(&mut m, 0x21, q)?;
    }
    out.say(
        "-- a movement: go to 150 pF at acceleration index 10, speed index 12, polling until done",
    );
    out.step(
        &mut m,
        0x21,
        Q::SetAccelerationSpeedIndex(ub2::request::SetAccelerationSpeedIndex {
            acceleration_index: 10,
            speed_index: 12,
        }),
    )?;
    movement(
        out,
        &mut m,
        Q::GoToCapacitance(ub2::request::GoToCapacitance {
            target: Capacitance(15000),
        }),
    )?;
    out.step(
        &mut m,
        0x21,
        Q::GetActualCapacitance(ub2::request::GetActualCapacitance),
    )?;
    out.say("-- limits: with the upper customer limit at 300 pF, 400 pF runs to the limit (0x93)");
    out.step(
        &mut m,
        0x21,
        Q::SetUpperCustomerLimit(ub2::request::SetUpperCustomerLimit {
            limit: Capacitance(30000),
        }),
    )?;
    movement(
        out,
        &mut m,
        Q::GoToCapacitance(ub2::request::GoToCapacitance {
            target: Capacitance(40000),
        }),
    )?;
    out.step(
        &mut m,
        0x21,
        Q::GetActualCapacitance(ub2::request::GetActualCapacitance),
    )?;
    out.say("-- stored positions, and a movement that loses 40 micro-steps (0x5400)");
    out.step(
        &mut m,
        0x21,
        Q::StoreIndexedPosition(ub2::request::StoreIndexedPosition {
            index: 3,
            position: 800,
        }),
    )?;
    bus.with_devices(|d| d[0].lose_steps_next_move = 40);
    movement(
        out,
        &mut m,
        Q::GoToStoredPosition(ub2::request::GoToStoredPosition { index: 3 }),
    )?;
    out.say("-- refusals: busspec refuses an index outside the spec's range before it reaches the bus; the device refuses an index past its table (0x94) and a mode change while moving (0x91)");
    let out_of_range =
        Q::GetStoredFullStepPosition(ub2::request::GetStoredFullStepPosition { index: 12 });
    match m.transact(0x21, out_of_range) {
        Err(e) => out.say(format!("→ 0x21 {:<40} (not sent) {e}", out_of_range.name())),
        Ok(ex) => {
            return Err(format!(
                "demo failed: an index outside the spec's range was sent: {}",
                hex(&ex.sent)
            ))
        }
    }
    out.step(
        &mut m,
        0x21,
        Q::GetCCurveIndexedFullStepCapacitance(ub2::request::GetCCurveIndexedFullStepCapacitance {
            index: 499,
        }),
    )?;
    out.step(
        &mut m,
        0x21,
        Q::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target: 1000 }),
    )?;
    out.step(
        &mut m,
        0x21,
        Q::SetModeOfOperation(ub2::request::SetModeOfOperation {
            mode: ub2::ModeOfOperation::CloseLoopControl,
        }),
    )?;
    out.say("-- the second capacitor's C-curve table, entry by entry");
    let mut read = 0;
    let table = m
        .read_c_curve(0x22, &mut |p| {
            if let Progress::Read { done } = p {
                read = done;
            }
        })
        .map_err(|e| format!("demo failed: {e}"))?;
    let first = table
        .first()
        .map(|p| p.capacitance.value())
        .unwrap_or_default();
    let last = table
        .last()
        .map(|p| p.capacitance.value())
        .unwrap_or_default();
    out.say(format!(
        "   read {read} entries from 0x22: {} to {} full-steps, {first:.2} to {last:.2} pF",
        table.first().map_or(0, |p| p.full_steps),
        table.last().map_or(0, |p| p.full_steps)
    ));
    if let Some(path) = svg {
        svg_file(path, &table, 0x22)?;
        out.say(format!("   drew it in {}", path.display()));
    }
    out.say(format!(
        "   (simulated bus time so far: {:.1} s)",
        clock.now().as_secs_f64()
    ));
    Ok(())
}

fn movement<T: Transport, C: Clock>(
    out: &mut Out,
    m: &mut Master<Ub2, T, C>,
    trigger: ub2::Request,
) -> Result<(), String> {
    let spec = out.spec;
    let mut frame = [0u8; ub2::MAX_FRAME_LEN];
    let n = trigger.encode(0x21, &mut frame).unwrap_or(0);
    out.say(format!(
        "→ 0x21 {:<40} {}",
        trigger.name(),
        hex(&frame[..n])
    ));
    let mut lines = Vec::new();
    let result = m.run_movement(
        0x21,
        trigger,
        Duration::from_millis(100),
        Duration::from_secs(120),
        &mut progress(&mut lines, "full-steps"),
    );
    out.lines.extend(lines);
    let r = result.map_err(|e| format!("demo failed: {e}"))?;
    out.say(format!("← {}", reply_json::<Ub2>(spec, &r.started, 0x21)));
    if let Some(done) = r.finished {
        out.say(format!(
            "← {}   (after {} completion checks, {:.1} s)",
            reply_json::<Ub2>(spec, &done, 0x21),
            r.polls,
            r.elapsed.as_secs_f64()
        ));
    }
    Ok(())
}

fn sd_part(out: &mut Out) -> Result<(), String> {
    use sd::Request as Q;
    out.say("");
    out.say("== SD: two servo actuators, IDs 1 and 2, on one simulated RS485 bus (115,200 baud, at most 100 frames/s)");
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Sd::BUS.baud),
        vec![SdSim::new(1), SdSim::new(2)],
    );
    let mut m: Master<Sd, _, _> = Master::new(bus.clone(), clock.clone());
    out.step(&mut m, 1, Q::ReadServoId(sd::request::ReadServoId))?;
    for which in SdString::ALL {
        let text = m
            .read_string(1, which, &mut |_| {})
            .map_err(|e| format!("demo failed: {e}"))?;
        out.say(format!(
            "   {:<34} {:?} (assembled from {} one-character readouts)",
            which.request(0).name(),
            String::from_utf8_lossy(&text),
            text.len()
        ));
    }
    out.say("-- a broadcast set point goes to every actuator and is not answered");
    out.step(
        &mut m,
        0x1F,
        Q::SetPoint(sd::request::SetPoint {
            freshness: 0,
            position: Angle(-256),
        }),
    )?;
    clock.advance(Duration::from_secs(2));
    out.step(
        &mut m,
        1,
        Q::ReadActualPosition(sd::request::ReadActualPosition),
    )?;
    out.step(
        &mut m,
        2,
        Q::ReadActualPosition(sd::request::ReadActualPosition),
    )?;
    out.say("-- set points: the master keeps the freshness counter, starting from the actuator's own (0x37)");
    out.step(
        &mut m,
        1,
        Q::SetVelocity(sd::request::SetVelocity {
            set_velocity: sd::Velocity(900),
        }),
    )?;
    out.say("→ 0x01 set_point                                position=45 (then polls read_actual_position)");
    let mut lines = Vec::new();
    let r = m.move_to(
        1,
        Angle::from_value(45.0).unwrap_or_default(),
        Duration::from_millis(20),
        Duration::from_secs(30),
        &mut progress(&mut lines, "°"),
    );
    out.lines.extend(lines);
    let r = r.map_err(|e| format!("demo failed: {e}"))?;
    out.say(format!("← {}", reply_json::<Sd>(out.spec, &r.started, 1)));
    if let Some(done) = r.finished {
        out.say(format!(
            "← {}   (reached after {:.2} s)",
            reply_json::<Sd>(out.spec, &done, 1),
            r.elapsed.as_secs_f64()
        ));
    }
    out.step(
        &mut m,
        1,
        Q::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter),
    )?;
    out.say("-- zero offset, and a counter reset that reports the value before it");
    out.step(
        &mut m,
        2,
        Q::SetCurrentPositionAsZero(sd::request::SetCurrentPositionAsZero),
    )?;
    out.step(
        &mut m,
        2,
        Q::ReadActualPosition(sd::request::ReadActualPosition),
    )?;
    out.step(
        &mut m,
        2,
        Q::ResetLoadRuntime024(sd::request::ResetLoadRuntime024),
    )?;
    out.step(
        &mut m,
        2,
        Q::ReadLoadRuntime024Hours(sd::request::ReadLoadRuntime024Hours),
    )?;
    Ok(())
}

fn faults_part(out: &mut Out) -> Result<(), String> {
    out.say("");
    out.say("== faults: 1 % of bytes corrupted, dropped or duplicated, frames truncated, silenced or late");
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Ub2::BUS.baud),
        vec![Ub2Sim::new(0x21)],
    );
    let mut cfg = FaultConfig::none();
    cfg.silence = 1.0;
    cfg.replies_only = true;
    let mut m: Master<Ub2, _, _> = Master::new(Faulty::new(bus, clock.clone(), cfg, 1), clock);
    match m.transact(
        0x21,
        ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
    ) {
        Err(e) => out.say(format!("   a line that never answers: {e}")),
        Ok(_) => return Err("demo failed: a silent line answered".to_owned()),
    }
    for (name, report) in [
        (Ub2::NAME, soak::run::<Ub2>(soak_config())),
        (Sd::NAME, soak::run::<Sd>(soak_config())),
    ] {
        out.say(format!(
            "   {name}: {} transactions: {} completed, {} after retries, {} failed with an error, {} refused, {} not sent (outside the spec), {} wrong values accepted (a checksum-only master: {})",
            report.transactions,
            report.completed,
            report.retried,
            report.failed,
            report.refused,
            report.not_sent,
            report.silent_wrong,
            report.checksum_only_silent_wrong
        ));
    }
    out.say("   (`busspec soak` runs the full figure; see the README's reliability section)");
    Ok(())
}

fn soak_config() -> SoakConfig {
    SoakConfig {
        transactions: 2000,
        byte_error_rate: 0.01,
        seed: 1,
        devices: 2,
    }
}
