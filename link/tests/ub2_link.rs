//! The UB2 master against simulated capacitors on a simulated bus, in simulated time.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use busspec_devices::master::Ub2Master;
use busspec_devices::movement::ub2_completion_check;
use busspec_devices::sim::ub2::{Ub2Sim, MICRO_STEPS};
use busspec_devices::Ub2;
use busspec_link::clock::Clock;
use busspec_link::fault::{FaultConfig, Faulty};
use busspec_link::master::{LinkError, Progress, TraceEvent};
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::{Master, SimClock};
use busspec_protocols::ub2::{self, request, response, Capacitance, Request, Response};
use busspec_protocols::Framing as _;

type Bus = SimBus<Ub2Sim>;

fn bus(addresses: &[u8]) -> (Bus, Master<Ub2, Bus, SimClock>, SimClock) {
    let clock = SimClock::new();
    let devices = addresses.iter().map(|&a| Ub2Sim::new(a)).collect();
    let bus = SimBus::new(clock.clone(), BusConfig::new(19_200), devices);
    let master = Master::new(bus.clone(), clock.clone());
    (bus, master, clock)
}

#[test]
fn reads_answer_from_the_device_state() {
    let (bus, mut m, _) = bus(&[0x21]);
    let r = m
        .ask(
            0x21,
            Request::GetFirmwareVersion(request::GetFirmwareVersion),
        )
        .unwrap();
    assert_eq!(
        r,
        Response::FirmwareVersion(response::FirmwareVersion {
            firmware_version: busspec_runtime::Ascii(*b"20100433.00")
        })
    );
    let expected = bus.with_devices(|d| d[0].capacitance_at(d[0].position));
    assert_eq!(
        m.ask(
            0x21,
            Request::GetActualCapacitance(request::GetActualCapacitance)
        )
        .unwrap(),
        Response::ActualCapacitance(response::ActualCapacitance {
            capacitance: expected
        })
    );
}

#[test]
fn requests_are_at_least_10_ms_apart() {
    let (_, mut m, clock) = bus(&[0x21]);
    let sends = Rc::new(RefCell::new(Vec::new()));
    let s = Rc::clone(&sends);
    let c = clock.clone();
    m.observe(move |e| {
        if let TraceEvent::Sent { .. } = e {
            s.borrow_mut().push(c.now());
        }
    });
    for _ in 0..5 {
        m.ask(
            0x21,
            Request::GetActualFullStepPosition(request::GetActualFullStepPosition),
        )
        .unwrap();
    }
    let t = sends.borrow();
    assert_eq!(t.len(), 5);
    for w in t.windows(2) {
        // The gap counts from the end of the reply, so starts are more than 10 ms apart.
        assert!(w[1] - w[0] > Duration::from_millis(10), "{:?}", w);
    }
}

#[test]
fn several_capacitors_share_the_bus_and_answer_only_to_their_address() {
    let (bus, mut m, _) = bus(&[0x21, 0x22, 0x30]);
    bus.with_devices(|d| d[1].stored_positions[4] = 777);
    let r = m
        .transact(
            0x22,
            Request::GetStoredFullStepPosition(request::GetStoredFullStepPosition { index: 4 }),
        )
        .unwrap();
    assert_eq!(r.address, 0x22);
    assert_eq!(
        r.response,
        Some(Response::StoredFullStepPosition(
            response::StoredFullStepPosition {
                index: 4,
                full_steps: 777
            }
        ))
    );
    let r = m
        .ask(
            0x21,
            Request::GetStoredFullStepPosition(request::GetStoredFullStepPosition { index: 4 }),
        )
        .unwrap();
    assert_eq!(
        r,
        Response::StoredFullStepPosition(response::StoredFullStepPosition {
            index: 4,
            full_steps: 0
        })
    );
    // Nobody at 0x25: a clear timeout, retried as a read may be.
    match m.transact(
        0x25,
        Request::GetActualCapacitance(request::GetActualCapacitance),
    ) {
        Err(LinkError::NoReply {
            attempts: 3,
            address: 0x25,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_movement_runs_in_simulated_time_and_reports_progress() {
    let (bus, mut m, clock) = bus(&[0x21]);
    let mut seen = Vec::new();
    let report = m
        .run_movement(
            0x21,
            Request::GoToFullStepPosition(request::GoToFullStepPosition { target: 3000 }),
            Duration::from_millis(100),
            Duration::from_secs(60),
            &mut |p| seen.push(p),
        )
        .unwrap();
    assert_eq!(
        report.started,
        Response::MovementStarted(response::MovementStarted)
    );
    assert_eq!(
        report.finished,
        Some(Response::MovementCompleted(response::MovementCompleted))
    );
    assert!(!report.clipped);
    assert_eq!(report.lost_micro_steps, None);
    // 2362 full steps at speed index 7 (450 steps/s) take several seconds.
    assert!(report.elapsed > Duration::from_secs(4), "{report:?}");
    assert!(clock.now() > Duration::from_secs(4));
    let positions: Vec<f64> = seen
        .iter()
        .map(|p| match p {
            Progress::Moving { position, .. } => *position,
            other => panic!("{other:?}"),
        })
        .collect();
    assert!(positions.len() > 10);
    assert!(positions.windows(2).all(|w| w[0] <= w[1]), "{positions:?}");
    assert_eq!(
        bus.with_devices(|d| d[0].position_at(clock.now())),
        3000 * MICRO_STEPS
    );
}

#[test]
fn step_loss_and_limit_clipping_are_surfaced() {
    let (bus, mut m, _) = bus(&[0x21]);
    bus.with_devices(|d| d[0].lose_steps_next_move = 3);
    let r = m
        .run_movement(
            0x21,
            Request::MoveFullSteps(request::MoveFullSteps { steps: 100 }),
            Duration::from_millis(50),
            Duration::from_secs(30),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(r.lost_micro_steps, Some(3));
    assert_eq!(
        r.finished,
        Some(Response::MovementCompletedWithStepLoss(
            response::MovementCompletedWithStepLoss {
                lost_micro_steps: 3
            }
        ))
    );

    // An upper customer limit of 300 pF: going to 400 pF runs to the limit, with 0x93.
    assert_eq!(
        m.ask(
            0x21,
            Request::SetUpperCustomerLimit(request::SetUpperCustomerLimit {
                limit: Capacitance(30000)
            })
        )
        .unwrap(),
        Response::SetUpperCustomerLimitAck(response::SetUpperCustomerLimitAck)
    );
    let r = m
        .run_movement(
            0x21,
            Request::GoToCapacitance(request::GoToCapacitance {
                target: Capacitance(40000),
            }),
            Duration::from_millis(50),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .unwrap();
    assert!(r.clipped);
    assert_eq!(
        r.started,
        Response::NakLimitReached(response::NakLimitReached)
    );
    match m
        .ask(
            0x21,
            Request::GetActualCapacitance(request::GetActualCapacitance),
        )
        .unwrap()
    {
        Response::ActualCapacitance(response::ActualCapacitance { capacitance }) => {
            assert!(capacitance.0.abs_diff(30000) <= 2, "{capacitance:?}")
        }
        other => panic!("{other:?}"),
    }
}

/// A UB2 request frame built by hand: start byte, address, code, payload, 8-bit sum. Frames
/// busspec's own encoder refuses to write (values outside the spec's ranges) are built this way.
fn hand_frame(address: u8, code: [u8; 2], payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xAA, address, code[0], code[1]];
    f.extend_from_slice(payload);
    f.push(busspec_runtime::sum8(&f));
    f
}

#[test]
fn naks_follow_the_document() {
    let (bus, mut m, _) = bus(&[0x21]);
    let sent = Rc::new(RefCell::new(0usize));
    let s = Rc::clone(&sent);
    m.observe(move |e| {
        if let TraceEvent::Sent { .. } = e {
            *s.borrow_mut() += 1;
        }
    });
    // Out-of-range indices: busspec refuses to send them (the spec's ranges), naming the field
    // and its range, and puts nothing on the bus ...
    let refused = [
        (
            Request::GetStoredFullStepPosition(request::GetStoredFullStepPosition { index: 10 }),
            ("index", 10, 0, 9),
        ),
        (
            Request::GoToStoredPosition(request::GoToStoredPosition { index: 12 }),
            ("index", 12, 0, 9),
        ),
        (
            Request::SetAccelerationSpeedIndex(request::SetAccelerationSpeedIndex {
                acceleration_index: 19,
                speed_index: 3,
            }),
            ("acceleration_index", 19, 0, 18),
        ),
        (
            Request::SetSlaveAddress(request::SetSlaveAddress { address: 0x41 }),
            ("address", 0x41, 0x21, 0x40),
        ),
    ];
    for (request, (field, value, min, max)) in refused {
        match m.ask(0x21, request) {
            Err(LinkError::Encode { source, .. }) => {
                assert_eq!(
                    source,
                    busspec_protocols::EncodeError::NotInRange {
                        field,
                        value,
                        min,
                        max,
                        kind: busspec_runtime::NumKind::Int,
                    },
                    "{request:?}"
                );
                let text = source.to_string();
                assert!(text.contains(field), "{text}");
                assert!(text.contains(&format!("{min}..={max}")), "{text}");
            }
            other => panic!("{request:?}: {other:?}"),
        }
    }
    assert_eq!(*sent.borrow(), 0, "a refused request reached the bus");
    // ... and a device that gets such a frame anyway (another master, a lenient tool) NAKs it
    // as the document says.
    let nak_index = Some(vec![0xAA, 0x21, 0x94, 0x5F]);
    let frames = [
        hand_frame(0x21, [0x40, 0x75], &[10]),
        hand_frame(0x21, [0x27, 0x00], &[12]),
        hand_frame(0x21, [0x43, 0x00], &[19, 3]),
        hand_frame(0x21, [0x60, 0x00], &[0x41]),
    ];
    for f in &frames {
        assert!(Ub2::checksum_ok(f), "{f:02X?}");
        let t = bus.clock().now();
        let got = bus.with_devices(|d| d[0].on_frame_bytes(f, t));
        assert_eq!(got, nak_index, "{f:02X?}");
    }
    bus.with_devices(|d| assert_eq!(d[0].address, 0x21));
    let nak = |m: &mut Master<Ub2, Bus, SimClock>, r| m.ask(0x21, r).unwrap();
    // An index inside the spec's range that the device has no entry for (its C-curve table is
    // shorter): the device's NAK, through the master.
    assert_eq!(
        nak(
            &mut m,
            Request::GetCCurveIndexedFullStepCapacitance(
                request::GetCCurveIndexedFullStepCapacitance { index: 499 }
            )
        ),
        Response::NakIndexOutOfRange(response::NakIndexOutOfRange)
    );
    assert_eq!(
        nak(
            &mut m,
            Request::SetLowerCustomerLimit(request::SetLowerCustomerLimit {
                limit: Capacitance(1000)
            })
        ),
        Response::NakLimitReached(response::NakLimitReached)
    );
    // Not idle: mode changes and new movements are refused while moving.
    assert_eq!(
        nak(
            &mut m,
            Request::GoToFullStepPosition(request::GoToFullStepPosition { target: 9000 })
        ),
        Response::MovementStarted(response::MovementStarted)
    );
    assert_eq!(
        nak(
            &mut m,
            Request::SetModeOfOperation(request::SetModeOfOperation {
                mode: ub2::ModeOfOperation::CloseLoopControl
            })
        ),
        Response::NakIncompatibleStatus(response::NakIncompatibleStatus)
    );
    assert_eq!(
        nak(
            &mut m,
            Request::MoveFullSteps(request::MoveFullSteps { steps: 1 })
        ),
        Response::NakIncompatibleStatus(response::NakIncompatibleStatus)
    );
    assert_eq!(
        nak(&mut m, Request::GoToCminStatus(request::GoToCminStatus)),
        Response::MovementNotTriggered(response::MovementNotTriggered)
    );
    assert_eq!(
        nak(
            &mut m,
            Request::GoToFullStepPositionStatus(request::GoToFullStepPositionStatus)
        ),
        Response::MovementNotCompleted(response::MovementNotCompleted)
    );
}

#[test]
fn the_device_naks_a_bad_checksum_and_ignores_other_addresses_and_start_bytes() {
    let mut sim = Ub2Sim::new(0x21);
    let t = Duration::ZERO;
    assert_eq!(
        sim.on_frame_bytes(&[0xAA, 0x21, 0x40, 0x01, 0x0D], t),
        Some(vec![0xAA, 0x21, 0x92, 0x5D])
    );
    assert_eq!(
        sim.on_frame_bytes(&[0xAA, 0x21, 0x40, 0x99, 0xA4], t),
        Some(vec![0xAA, 0x21, 0x90, 0x5B])
    );
    assert_eq!(sim.on_frame_bytes(&[0xAA, 0x22, 0x40, 0x01, 0x0D], t), None);
    assert_eq!(sim.on_frame_bytes(&[0xAB, 0x21, 0x40, 0x01, 0x0D], t), None);
    // 0x4072 with index 5: no such limit, "index out of range".
    assert_eq!(
        sim.on_frame_bytes(&[0xAA, 0x21, 0x40, 0x72, 0x05, 0x82], t),
        Some(vec![0xAA, 0x21, 0x94, 0x5F])
    );
}

trait FrameBytes {
    fn on_frame_bytes(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>>;
}

impl FrameBytes for Ub2Sim {
    fn on_frame_bytes(&mut self, frame: &[u8], now: Duration) -> Option<Vec<u8>> {
        busspec_link::sim::Device::on_frame(self, frame, now)
    }
}

#[test]
fn status_reports_reset_once() {
    let (_, mut m, _) = bus(&[0x21]);
    let bits = |r| match r {
        Response::Status(response::Status { error_bits, .. }) => error_bits,
        other => panic!("{other:?}"),
    };
    assert!(
        bits(m.ask(0x21, Request::GetStatus(request::GetStatus)).unwrap())
            .contains(ub2::StatusErrorBits::RESET)
    );
    assert!(
        !bits(m.ask(0x21, Request::GetStatus(request::GetStatus)).unwrap())
            .contains(ub2::StatusErrorBits::RESET)
    );
}

#[test]
fn the_c_curve_table_reads_whole() {
    let (bus, mut m, _) = bus(&[0x21]);
    let mut last = 0;
    let table = m
        .read_c_curve(0x21, &mut |p| {
            if let Progress::Read { done } = p {
                last = done
            }
        })
        .unwrap();
    let curve = bus.with_devices(|d| d[0].config.c_curve.clone());
    assert_eq!(table.len(), curve.len());
    assert_eq!(last, curve.len());
    for (p, (steps, c)) in table.iter().zip(&curve) {
        assert_eq!((p.full_steps, p.capacitance), (*steps, *c));
    }
}

#[test]
fn a_500_entry_table_reads_to_the_end() {
    let clock = SimClock::new();
    let mut sim = Ub2Sim::new(0x21);
    sim.config.c_curve = (0..500u16)
        .map(|i| (i * 20, Capacitance(5000 + u32::from(i) * 90)))
        .collect();
    let bus = SimBus::new(clock.clone(), BusConfig::new(19_200), vec![sim]);
    let mut m: Master<Ub2, _, _> = Master::new(bus, clock);
    assert_eq!(m.read_c_curve(0x21, &mut |_| {}).unwrap().len(), 500);
}

#[test]
fn the_slave_address_changes_after_the_ack_from_the_old_one() {
    let (_, mut m, _) = bus(&[0x21]);
    let ex = m
        .transact(
            0x21,
            Request::SetSlaveAddress(request::SetSlaveAddress { address: 0x24 }),
        )
        .unwrap();
    assert_eq!(
        (ex.address, ex.response),
        (
            0x21,
            Some(Response::SetSlaveAddressAck(response::SetSlaveAddressAck))
        )
    );
    assert!(m
        .ask(0x24, Request::GetSerialNumber(request::GetSerialNumber))
        .is_ok());
    assert!(matches!(
        m.transact(0x21, Request::GetSerialNumber(request::GetSerialNumber)),
        Err(LinkError::NoReply { .. })
    ));
}

/// A master to one capacitor at 0x21 through a line with these faults.
fn faulty(cfg: FaultConfig) -> Master<Ub2, Faulty<Bus, SimClock>, SimClock> {
    let (bus, _, clock) = bus(&[0x21]);
    Master::new(Faulty::new(bus, clock.clone(), cfg, 7), clock)
}

#[test]
fn movements_are_never_retried_but_reads_are() {
    // A line that swallows every reply: the read is sent 3 times, the movement once.
    let mut cfg = FaultConfig::none();
    cfg.silence = 1.0;
    let mut m = faulty(cfg);
    let sends = Rc::new(RefCell::new(0));
    let s = Rc::clone(&sends);
    m.observe(move |e| {
        if let TraceEvent::Sent { .. } = e {
            *s.borrow_mut() += 1
        }
    });
    assert!(matches!(
        m.transact(
            0x21,
            Request::GetActualCapacitance(request::GetActualCapacitance)
        ),
        Err(LinkError::NoReply { attempts: 3, .. })
    ));
    assert_eq!(*sends.borrow(), 3);
    let err = m
        .transact(
            0x21,
            Request::GoToFullStepPosition(request::GoToFullStepPosition { target: 100 }),
        )
        .unwrap_err();
    assert!(
        matches!(err, LinkError::NoReply { attempts: 1, .. }),
        "{err}"
    );
    assert_eq!(*sends.borrow(), 4);
    assert_eq!(
        err.to_string(),
        "ub2 go_to_full_step_position to address 0x21: no reply within 200 ms (1 attempt)"
    );
}

#[test]
fn a_corrupted_reply_is_retried_and_the_error_says_what_was_wrong() {
    let mut cfg = FaultConfig::none();
    cfg.corrupt = 1.0;
    cfg.replies_only = true;
    let mut m = faulty(cfg);
    let err = m
        .transact(
            0x21,
            Request::GetMinimumCapacitance(request::GetMinimumCapacitance),
        )
        .unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with(
            "ub2 get_minimum_capacitance to address 0x21: no valid reply (3 attempts); last reply "
        ),
        "{text}"
    );
}

#[test]
fn every_trigger_has_its_completion_check() {
    let triggers = [
        Request::ReferenceRun(request::ReferenceRun),
        Request::GoToCapacitance(request::GoToCapacitance {
            target: Capacitance(0),
        }),
        Request::GoToFullStepPosition(request::GoToFullStepPosition { target: 0 }),
        Request::MoveFullSteps(request::MoveFullSteps { steps: 0 }),
        Request::GoToCmin(request::GoToCmin),
        Request::GoToCmax(request::GoToCmax),
        Request::GoToMicroStepPosition(request::GoToMicroStepPosition { target: 0 }),
        Request::MoveMicroSteps(request::MoveMicroSteps { steps: 0 }),
        Request::GoToStoredPosition(request::GoToStoredPosition { index: 0 }),
    ];
    for t in triggers {
        let check = ub2_completion_check(&t).unwrap_or_else(|| panic!("{t:?}"));
        assert_eq!(check.name(), format!("{}_status", t.name()));
    }
    assert_eq!(
        ub2_completion_check(&Request::GetStatus(request::GetStatus)),
        None
    );
}
