//! The SD master against simulated actuators on a simulated bus, in simulated time.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use busspec_devices::master::{SdMaster, SdString};
use busspec_devices::sim::sd::SdSim;
use busspec_devices::Sd;
use busspec_link::clock::Clock;
use busspec_link::master::{LinkError, TraceEvent};
use busspec_link::sim::{BusConfig, Device, SimBus};
use busspec_link::{Master, SimClock};
use busspec_protocols::sd::{
    self, request, response, ActuatorStatusBits, Angle, Request, Response,
};

type Bus = SimBus<SdSim>;

fn bus(ids: &[u8]) -> (Bus, Master<Sd, Bus, SimClock>, SimClock) {
    let clock = SimClock::new();
    let devices = ids.iter().map(|&a| SdSim::new(a)).collect();
    let bus = SimBus::new(clock.clone(), BusConfig::new(115_200), devices);
    let master = Master::new(bus.clone(), clock.clone());
    (bus, master, clock)
}

fn set_point(position: i16) -> Request {
    Request::SetPoint(request::SetPoint {
        freshness: 0,
        position: Angle(position),
    })
}

#[test]
fn the_master_keeps_the_freshness_counter_starting_from_the_devices_view() {
    let (bus, mut m, _) = bus(&[1]);
    bus.with_devices(|d| d[0].host_freshness = Some(9));
    let sent = Rc::new(RefCell::new(Vec::new()));
    let s = Rc::clone(&sent);
    m.observe(move |e| {
        if let TraceEvent::Sent { bytes, .. } = e {
            s.borrow_mut().push(bytes.to_vec())
        }
    });
    for _ in 0..20 {
        m.ask(1, set_point(100)).unwrap();
    }
    let frames = sent.borrow();
    // First the 0x37 readout of the device's counter, then set points counting on from 9.
    assert_eq!(frames[0][0], 0x37);
    let counters: Vec<u8> = frames[1..].iter().map(|f| f[2] >> 4).collect();
    let expected: Vec<u8> = (0..20).map(|i| (10 + i) % 16).collect();
    assert_eq!(counters, expected);
    bus.with_devices(|d| {
        assert_eq!(d[0].dropped_frames, 0);
        assert!(!d[0].status_bits.contains(ActuatorStatusBits::FRC));
    });
}

#[test]
fn skipped_counts_are_dropped_frames_and_too_many_load_the_fail_safe_position() {
    let mut a = SdSim::new(1);
    a.config.freshness_threshold = 2;
    a.config.fail_safe_position = -300;
    let t = Duration::ZERO;
    let sp = |f: u8, p: i16| {
        Request::SetPoint(request::SetPoint {
            freshness: f,
            position: Angle(p),
        })
    };
    a.respond(&sp(1, 100), t);
    a.respond(&sp(3, 100), t); // one skipped
    a.respond(&sp(6, 100), t); // two skipped
    assert_eq!(a.dropped_frames, 3);
    assert_eq!(a.target, 100);
    a.respond(&sp(10, 500), t); // three skipped: beyond the threshold
    assert_eq!(a.target, -300);
    assert!(a.status_bits.contains(ActuatorStatusBits::FRC));
    // A repeated counter is a violation too.
    a.status_bits = ActuatorStatusBits(0);
    a.respond(&sp(10, 500), t);
    assert!(a.status_bits.contains(ActuatorStatusBits::FRC));
    assert_eq!(
        a.respond(
            &Request::ReadSkippedFramesCounter(request::ReadSkippedFramesCounter),
            t
        ),
        Response::SkippedFramesCounter(response::SkippedFramesCounter {
            host_freshness_counter: 10,
            dropped_frames: 3
        })
    );
}

#[test]
fn the_position_slews_at_the_set_velocity() {
    let (_, mut m, clock) = bus(&[1]);
    assert!(matches!(
        m.ask(
            1,
            Request::SetVelocity(request::SetVelocity {
                set_velocity: sd::Velocity(450)
            })
        )
        .unwrap(),
        Response::SetVelocityReply(_)
    ));
    let start = clock.now();
    let report = m
        .move_to(
            1,
            Angle::from_value(90.0).unwrap(),
            Duration::from_millis(20),
            Duration::from_secs(10),
            &mut |_| {},
        )
        .unwrap();
    // 90° at 45 °/s: two seconds.
    let took = clock.now() - start;
    assert!(
        took >= Duration::from_secs(2) && took < Duration::from_millis(2100),
        "{took:?}"
    );
    assert_eq!(
        report.finished,
        Some(Response::ActualPosition(response::ActualPosition {
            position: Angle(1024)
        }))
    );
}

#[test]
fn strings_are_assembled_from_their_characters() {
    let (bus, mut m, _) = bus(&[1, 2]);
    for which in SdString::ALL {
        let text = m.read_string(2, which, &mut |_| {}).unwrap();
        let expected = bus.with_devices(|d| {
            let c = &d[1].config;
            match which {
                SdString::SerialNumber => c.serial_number.clone(),
                SdString::ProductDescription => c.product_description.clone(),
                SdString::SoftwareRevision => c.software_revision.clone(),
                SdString::HardwareRevision => c.hardware_revision.clone(),
            }
        });
        assert_eq!(text, expected);
    }
}

#[test]
fn zero_offset_shifts_reported_positions() {
    let (bus, mut m, clock) = bus(&[1]);
    m.move_to(
        1,
        Angle(400),
        Duration::from_millis(20),
        Duration::from_secs(10),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(
        m.ask(
            1,
            Request::SetCurrentPositionAsZero(request::SetCurrentPositionAsZero)
        )
        .unwrap(),
        Response::SetCurrentPositionAsZeroReply(response::SetCurrentPositionAsZeroReply {
            zero_offset: Angle(400)
        })
    );
    assert_eq!(
        m.ask(1, Request::ReadActualPosition(request::ReadActualPosition))
            .unwrap(),
        Response::ActualPosition(response::ActualPosition { position: Angle(0) })
    );
    assert_eq!(
        m.ask(
            1,
            Request::ReadCurrentZeroOffset(request::ReadCurrentZeroOffset)
        )
        .unwrap(),
        Response::CurrentZeroOffset(response::CurrentZeroOffset {
            zero_offset: Angle(400)
        })
    );
    m.move_to(
        1,
        Angle(-100),
        Duration::from_millis(20),
        Duration::from_secs(10),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(
        bus.with_devices(|d| d[0].encoder_position(clock.now())),
        300
    );
    assert_eq!(
        m.ask(1, Request::ResetZeroOffset(request::ResetZeroOffset))
            .unwrap(),
        Response::ResetZeroOffsetReply(response::ResetZeroOffsetReply)
    );
    assert_eq!(
        m.ask(1, Request::ReadActualPosition(request::ReadActualPosition))
            .unwrap(),
        Response::ActualPosition(response::ActualPosition {
            position: Angle(300)
        })
    );
}

#[test]
fn the_id_changes_and_the_reply_comes_from_the_new_one() {
    let (_, mut m, _) = bus(&[1]);
    let ex = m
        .transact(1, Request::SetServoId(request::SetServoId { new_id: 7 }))
        .unwrap();
    assert_eq!(
        (ex.address, ex.response),
        (
            7,
            Some(Response::SetServoIdReply(response::SetServoIdReply {
                new_id: 7
            }))
        )
    );
    // The master checks replies come from the address asked; 7 answers now, 1 does not.
    assert_eq!(
        m.ask(7, Request::ReadServoId(request::ReadServoId))
            .unwrap(),
        Response::ServoId(response::ServoId { id: 7 })
    );
    assert!(matches!(
        m.transact(1, Request::ReadServoId(request::ReadServoId)),
        Err(LinkError::NoReply { .. })
    ));
}

#[test]
fn broadcasts_reach_every_actuator_and_only_some_are_answered() {
    let (bus, mut m, clock) = bus(&[1, 2]);
    let ex = m.transact(0x1F, set_point(200)).unwrap();
    assert_eq!(ex.response, None);
    clock.advance(Duration::from_secs(5));
    bus.with_devices(|d| {
        for a in d.iter() {
            assert_eq!(a.position_at(clock.now()), Angle(200));
        }
    });
    // An answered broadcast with two actuators: the replies collide, and the master says so.
    assert!(m
        .transact(
            0x1F,
            Request::ReadActualPosition(request::ReadActualPosition)
        )
        .is_err());
    // A command that does not accept the broadcast ID is refused before it is sent.
    let err = m
        .transact(0x1F, Request::ReadHumidity(request::ReadHumidity))
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "sd read_humidity to address 0x1F: this command does not accept the broadcast address"
    );
}

#[test]
fn a_single_actuator_answers_a_broadcast_read_with_its_own_id() {
    let (_, mut m, _) = bus(&[5]);
    let ex = m
        .transact(0x1F, Request::ReadServoId(request::ReadServoId))
        .unwrap();
    assert_eq!(
        (ex.address, ex.response),
        (5, Some(Response::ServoId(response::ServoId { id: 5 })))
    );
}

#[test]
fn counters_reset_and_report_what_they_held() {
    let mut a = SdSim::new(1);
    a.stall_events = 4;
    let t = Duration::ZERO;
    assert_eq!(
        a.respond(
            &Request::ResetStallEventCounter(request::ResetStallEventCounter),
            t
        ),
        Response::StallEventCounterBeforeReset(response::StallEventCounterBeforeReset {
            stall_events_before_reset: 4
        })
    );
    assert_eq!(
        a.respond(
            &Request::ReadStallEventCounter(request::ReadStallEventCounter),
            t
        ),
        Response::StallEventCounter(response::StallEventCounter { stall_events: 0 })
    );
    assert_eq!(
        a.respond(
            &Request::ResetLoadRuntime100(request::ResetLoadRuntime100),
            t
        ),
        Response::LoadRuntime100HoursBeforeReset(response::LoadRuntime100HoursBeforeReset {
            runtime_hours_before_reset: 1
        })
    );
    assert_eq!(
        a.respond(
            &Request::ReadLoadRuntime100Hours(request::ReadLoadRuntime100Hours),
            t
        ),
        Response::LoadRuntime100Hours(response::LoadRuntime100Hours { runtime_hours: 0 })
    );
    // The total run-time counter runs with time.
    let t1 = Duration::from_secs(3600);
    let before = a.respond(
        &Request::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours),
        t,
    );
    let after = a.respond(
        &Request::ReadTotalRuntimeHours(request::ReadTotalRuntimeHours),
        t1,
    );
    match (before, after) {
        (
            Response::TotalRuntimeHours(response::TotalRuntimeHours { runtime_hours: h0 }),
            Response::TotalRuntimeHours(response::TotalRuntimeHours { runtime_hours: h1 }),
        ) => assert_eq!(h1, h0 + 1),
        other => panic!("{other:?}"),
    }
}

#[test]
fn frames_that_do_not_decode_get_no_reply() {
    let mut a = SdSim::new(1);
    let mut frame = [0u8; 6];
    let n = Request::ReadServoId(request::ReadServoId)
        .encode(1, &mut frame)
        .unwrap();
    assert!(a.on_frame(&frame[..n], Duration::ZERO).is_some());
    frame[5] ^= 1;
    assert_eq!(a.on_frame(&frame, Duration::ZERO), None);
    assert_eq!(a.on_frame(&frame[..5], Duration::ZERO), None);
}

/// The freshness counter wraps at the protocol's modulus: SD's 4 bits, a whole byte where a
/// protocol does not say.
#[test]
fn the_freshness_counter_wraps_at_the_protocols_modulus() {
    use busspec_devices::sim::ub2::Ub2Sim;
    use busspec_devices::{Protocol, Ub2};
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Sd::BUS.baud),
        vec![SdSim::new(1)],
    );
    let mut m: Master<Sd, _, _> = Master::new(bus, clock);
    m.set_freshness(1, 0x0F);
    assert_eq!(m.next_freshness_value(1), Some(0));
    m.set_freshness(1, 0x1E);
    assert_eq!(m.next_freshness_value(1), Some(0x0F));
    let clock = SimClock::new();
    let bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Ub2::BUS.baud),
        vec![Ub2Sim::new(0x21)],
    );
    let mut m: Master<Ub2, _, _> = Master::new(bus, clock);
    m.set_freshness(0x21, 0x0F);
    assert_eq!(m.next_freshness_value(0x21), Some(0x10));
    m.set_freshness(0x21, 0xFF);
    assert_eq!(m.next_freshness_value(0x21), Some(0));
}
