//! UB2 byte-order safety (erratum ub2-e01): before the first movement to an address the master
//! reads the factory limits and refuses to move a device whose numbers read implausibly in the
//! spec's byte order.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use busspec_devices::master::Ub2Master;
use busspec_devices::sim::ub2::{Ub2Config, Ub2Sim};
use busspec_devices::Ub2;
use busspec_link::clock::Clock;
use busspec_link::master::{LinkError, TraceEvent};
use busspec_link::sim::{BusConfig, SimBus};
use busspec_link::transport::Transport;
use busspec_link::{Master, SimClock};
use busspec_protocols::ub2::{request, response, Capacitance, Request, Response};
use busspec_protocols::{CommandKind, Protocol};

type Bus = SimBus<Ub2Sim>;
/// The request frames a master sent.
type Sent = Rc<RefCell<Vec<Vec<u8>>>>;

/// A master on a bus with `devices`, and the request frames it sends.
fn bus(devices: Vec<Ub2Sim>) -> (Bus, Master<Ub2, Bus, SimClock>, Sent) {
    let clock = SimClock::new();
    let bus = SimBus::new(clock.clone(), BusConfig::new(Ub2::BUS.baud), devices);
    let mut master = Master::new(bus.clone(), clock);
    let sent = Rc::new(RefCell::new(Vec::new()));
    let s = Rc::clone(&sent);
    master.observe(move |e| {
        if let TraceEvent::Sent { bytes, .. } = e {
            s.borrow_mut().push(bytes.to_vec());
        }
    });
    (bus, master, sent)
}

fn names(frames: &[Vec<u8>]) -> Vec<&'static str> {
    frames
        .iter()
        .map(|f| {
            Ub2::decode_request(f)
                .expect("the master sends valid frames")
                .message
                .name()
        })
        .collect()
}

fn go(pf: f64) -> Request {
    Request::GoToCapacitance(request::GoToCapacitance {
        target: Capacitance::from_value(pf).unwrap(),
    })
}

fn run(m: &mut Master<Ub2, Bus, SimClock>, address: u8, trigger: Request) -> Result<(), LinkError> {
    m.run_movement(
        address,
        trigger,
        Duration::from_millis(50),
        Duration::from_secs(60),
        &mut |_| {},
    )
    .map(|_| ())
}

#[test]
fn a_correct_device_moves_after_one_check_per_address() {
    let (bus, mut m, sent) = bus(vec![Ub2Sim::new(0x21), Ub2Sim::new(0x22)]);
    run(&mut m, 0x21, go(150.0)).unwrap();
    let first = names(&sent.borrow());
    // Two extra transactions, before the trigger: the factory limits.
    assert_eq!(
        first[..3],
        [
            "get_lower_factory_limit",
            "get_upper_factory_limit",
            "go_to_capacitance"
        ]
    );
    assert!(first[3..]
        .iter()
        .all(|n| *n != "get_lower_factory_limit" && *n != "get_upper_factory_limit"));
    let check = m.byte_order_checked(0x21).expect("checked").clone();
    assert_eq!(check.read, "factory limits 50.00..=500.00 pF");
    assert!(check.declared_fits && !check.swapped_fits, "{check:?}");
    assert_eq!(check.erratum, "ub2-e01");
    let c = bus.with_devices(|d| d[0].capacitance_at(d[0].position_at(Duration::MAX / 2)));
    assert!((c.value() - 150.0).abs() < 0.05, "{c:?}");

    // The second movement to the same address is not checked again: it costs what it did
    // before the check existed.
    sent.borrow_mut().clear();
    run(
        &mut m,
        0x21,
        Request::MoveFullSteps(request::MoveFullSteps { steps: 40 }),
    )
    .unwrap();
    assert_eq!(names(&sent.borrow())[0], "move_full_steps");

    // Another address is checked on its first movement.
    sent.borrow_mut().clear();
    run(&mut m, 0x22, Request::GoToCmin(request::GoToCmin)).unwrap();
    assert_eq!(
        names(&sent.borrow())[..3],
        [
            "get_lower_factory_limit",
            "get_upper_factory_limit",
            "go_to_cmin"
        ]
    );
    assert!(m.byte_order_checked(0x21).is_some() && m.byte_order_checked(0x22).is_some());

    // Reads never trigger the check.
    sent.borrow_mut().clear();
    m.ask(
        0x21,
        Request::GetActualCapacitance(request::GetActualCapacitance),
    )
    .unwrap();
    assert_eq!(names(&sent.borrow()), ["get_actual_capacitance"]);

    // A new slave address forgets every check: another device may answer where a checked one
    // did. The next movement, to the device at its new address, checks again.
    let r = m
        .ask(
            0x22,
            Request::SetSlaveAddress(request::SetSlaveAddress { address: 0x23 }),
        )
        .unwrap();
    assert_eq!(
        r,
        Response::SetSlaveAddressAck(response::SetSlaveAddressAck)
    );
    assert!(m.byte_order_checked(0x21).is_none() && m.byte_order_checked(0x22).is_none());
    sent.borrow_mut().clear();
    run(&mut m, 0x23, go(100.0)).unwrap();
    assert_eq!(
        names(&sent.borrow())[..3],
        [
            "get_lower_factory_limit",
            "get_upper_factory_limit",
            "go_to_capacitance"
        ]
    );
}

#[test]
fn an_msb_first_device_is_not_moved() {
    let (bus, mut m, sent) = bus(vec![Ub2Sim::new(0x21).msb_first(true)]);
    let before = bus.with_devices(|d| d[0].clone());
    for trigger in [
        go(150.0),
        Request::GoToFullStepPosition(request::GoToFullStepPosition { target: 5000 }),
        Request::MoveFullSteps(request::MoveFullSteps { steps: -150 }),
        Request::ReferenceRun(request::ReferenceRun),
        Request::GoToCmax(request::GoToCmax),
    ] {
        let err = run(&mut m, 0x21, trigger).unwrap_err();
        let text = err.to_string();
        let LinkError::ByteOrder { check, .. } = &err else {
            panic!("expected a byte-order refusal, got {text}");
        };
        assert!(!check.declared_fits && check.swapped_fits, "{check:?}");
        assert_eq!(check.swapped, "factory limits 50.00..=500.00 pF");
        for part in [
            "not sent",
            "implausible little-endian",
            "spec/ub2.yaml:8: byte_order: little",
            "big-endian",
            "erratum ub2-e01",
            "50.00..=500.00 pF",
        ] {
            assert!(text.contains(part), "{part:?} not in {text}");
        }
        assert!(m.byte_order_checked(0x21).is_none());
    }
    // Nothing that moves ever went out: only the probe's reads, again for every attempt.
    let frames = sent.borrow();
    assert_eq!(frames.len(), 2 * 5);
    for f in frames.iter() {
        let q = Ub2::decode_request(f).unwrap().message;
        assert_ne!(q.command().kind, CommandKind::Movement, "{q:?} was sent");
    }
    assert!(names(&frames)
        .iter()
        .all(|n| *n == "get_lower_factory_limit" || *n == "get_upper_factory_limit"));
    // The device did not move.
    bus.with_devices(|d| {
        assert_eq!(d[0].movement, None);
        assert_eq!(d[0].position, before.position);
    });
}

/// The MSB-first simulator is a device built to the document's examples: its factory-limit
/// replies are byte for byte the frames §6.16 and §6.17 print, and it reads a request's
/// numbers the other way round.
#[test]
fn the_msb_first_simulator_sends_what_the_examples_print() {
    let clock = SimClock::new();
    let mut bus = SimBus::new(
        clock.clone(),
        BusConfig::new(Ub2::BUS.baud),
        vec![Ub2Sim::new(0x21).msb_first(true)],
    );
    let mut ask = |bytes: &[u8]| {
        bus.write(bytes).unwrap();
        let mut buf = [0u8; 64];
        let n = bus.read(&mut buf, Duration::from_millis(100)).unwrap();
        clock.sleep(Duration::from_millis(20));
        buf[..n].to_vec()
    };
    let frame = |q: Request| {
        let mut buf = [0u8; 16];
        let n = q.encode(0x21, &mut buf).unwrap();
        buf[..n].to_vec()
    };
    assert_eq!(
        ask(&frame(Request::GetLowerFactoryLimit(
            request::GetLowerFactoryLimit
        ))),
        [0xAA, 0x21, 0x41, 0x72, 0x03, 0x00, 0x00, 0x13, 0x88, 0x1C]
    );
    assert_eq!(
        ask(&frame(Request::GetUpperFactoryLimit(
            request::GetUpperFactoryLimit
        ))),
        [0xAA, 0x21, 0x41, 0x72, 0x04, 0x00, 0x00, 0xC3, 0x50, 0x95]
    );
    // The spec's reading of those bytes is what the check refuses.
    let d = Ub2::decode_reply(
        &[0xAA, 0x21, 0x41, 0x72, 0x03, 0x00, 0x00, 0x13, 0x88, 0x1C],
        &Request::GetLowerFactoryLimit(request::GetLowerFactoryLimit),
    )
    .unwrap();
    assert_eq!(
        d.message,
        Response::LowerFactoryLimit(response::LowerFactoryLimit {
            capacitance: Capacitance(0x8813_0000)
        })
    );
    // A C-curve index of 1 is 0x0100 = 256 to it, beyond its 200 entries; 3 is 768, beyond
    // the 500 the spec allows: both "index out of range" (§6.7, §7.1, 0x94).
    for index in [1, 3] {
        assert_eq!(
            ask(&frame(Request::GetCCurveIndexedFullStepCapacitance(
                request::GetCCurveIndexedFullStepCapacitance { index }
            ))),
            frame_reply(Response::NakIndexOutOfRange(response::NakIndexOutOfRange))
        );
    }
    // One-byte numbers are the same either way: stored position 1 is index 1 to it too.
    let r = ask(&frame(Request::GetStoredFullStepPosition(
        request::GetStoredFullStepPosition { index: 1 },
    )));
    assert_eq!(
        Ub2::decode_reply(
            &r,
            &Request::GetStoredFullStepPosition(request::GetStoredFullStepPosition { index: 1 })
        )
        .unwrap()
        .message,
        Response::StoredFullStepPosition(response::StoredFullStepPosition {
            index: 1,
            full_steps: 0
        })
    );
    let r = ask(&frame(Request::GetControllerTemperature(
        request::GetControllerTemperature,
    )));
    assert_eq!(
        Ub2::decode_reply(
            &r,
            &Request::GetControllerTemperature(request::GetControllerTemperature)
        )
        .unwrap()
        .message
        .name(),
        "controller_temperature"
    );
}

fn frame_reply(r: Response) -> Vec<u8> {
    let mut buf = [0u8; 16];
    let n = r.encode(0x21, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// Limits that fit neither byte order (a lower factory limit of 0 pF, which reads 0 either way)
/// are refused too, with what was read both ways.
#[test]
fn limits_implausible_both_ways_are_refused() {
    let mut config = Ub2Config::default();
    config.c_curve[0].1 = Capacitance(0);
    let (bus, mut m, sent) = bus(vec![Ub2Sim::with_config(0x21, config)]);
    let err = run(&mut m, 0x21, go(150.0)).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, LinkError::ByteOrder { .. }), "{text}");
    for part in [
        "factory limits 0.00..=500.00 pF",
        "implausible too: neither byte order fits",
        "spec/ub2.yaml:8: byte_order: little",
        "ub2-e01",
    ] {
        assert!(text.contains(part), "{part:?} not in {text}");
    }
    assert_eq!(sent.borrow().len(), 2);
    bus.with_devices(|d| assert_eq!(d[0].movement, None));
}

/// `start_movement` is the generic way to start a movement: checked the same way. Plain
/// `transact` is the transaction layer and sends what it is given.
#[test]
fn start_movement_checks_and_transact_does_not() {
    let (_, mut m, sent) = bus(vec![Ub2Sim::new(0x21).msb_first(true)]);
    let err = m.start_movement(0x21, go(150.0)).unwrap_err();
    assert!(matches!(err, LinkError::ByteOrder { .. }), "{err}");
    assert_eq!(
        names(&sent.borrow()),
        ["get_lower_factory_limit", "get_upper_factory_limit"]
    );
    let (_, mut m, sent) = bus(vec![Ub2Sim::new(0x21)]);
    let ex = m.start_movement(0x21, go(150.0)).unwrap();
    assert_eq!(
        ex.response,
        Some(Response::MovementStarted(response::MovementStarted))
    );
    assert_eq!(
        names(&sent.borrow()),
        [
            "get_lower_factory_limit",
            "get_upper_factory_limit",
            "go_to_capacitance"
        ]
    );
    sent.borrow_mut().clear();
    m.transact(
        0x21,
        Request::GoToCapacitanceStatus(request::GoToCapacitanceStatus),
    )
    .unwrap();
    assert_eq!(names(&sent.borrow()), ["go_to_capacitance_status"]);
}
