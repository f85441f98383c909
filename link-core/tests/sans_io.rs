//! The core driven by hand, as a driver does: what it asks for, step by step, in time.

use core::time::Duration;

use busspec_devices::protocols::{sd, ub2};
use busspec_devices::{Sd, Ub2};
use busspec_link_core::master::{Action, Event, Failure, MasterCore};
use busspec_link_core::Message;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn frame<M: Message>(m: &M, address: u8) -> Vec<u8> {
    let mut buf = [0u8; 32];
    let n = m.encode(address, &mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn a_transaction_step_by_step() {
    let mut core: MasterCore<Ub2> = MasterCore::new();
    let q = ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance);
    core.start(0x21, q);
    assert_eq!(core.poll(ms(0)), Action::ClearInput);
    assert_eq!(core.poll(ms(0)), Action::Write(&frame(&q, 0x21)));
    assert_eq!(core.take_event(), Some(Event::Sent { attempt: 1 }));
    // The write took 3 ms; the reply timeout (200 ms at 19,200 baud) starts then.
    assert_eq!(core.poll(ms(3)), Action::Read { until: ms(203) });
    let reply = ub2::Response::ActualCapacitance(ub2::response::ActualCapacitance {
        capacitance: ub2::Capacitance(12345),
    });
    let bytes = frame(&reply, 0x21);
    // Half a reply, then the rest: it is complete as soon as it decodes.
    core.received(&bytes[..3], ms(10));
    assert_eq!(core.poll(ms(10)), Action::Read { until: ms(15) });
    core.received(&bytes[3..], ms(11));
    assert_eq!(core.poll(ms(11)), Action::Done);
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.address, r.attempts), (Some(reply), 0x21, 1));
    assert_eq!(core.reply(), &bytes[..]);
    assert!(!core.busy());
    // The next request waits out the 10 ms gap since the last byte.
    core.start(0x21, q);
    assert_eq!(core.poll(ms(12)), Action::Sleep(ms(21)));
    assert_eq!(core.poll(ms(21)), Action::ClearInput);
}

#[test]
fn silence_settles_then_retries_a_getter_but_never_a_movement() {
    let mut core: MasterCore<Ub2> = MasterCore::new();
    core.start(
        0x21,
        ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
    );
    core.poll(ms(0));
    core.poll(ms(0));
    assert_eq!(core.poll(ms(0)), Action::Read { until: ms(200) });
    // Nothing by the deadline: the line must be quiet for the settle time, 200 ms.
    assert_eq!(core.poll(ms(200)), Action::Read { until: ms(400) });
    // A late byte restarts the quiet time.
    core.received(&[0xAA], ms(250));
    assert_eq!(core.poll(ms(250)), Action::Read { until: ms(450) });
    assert_eq!(core.poll(ms(450)), Action::ClearInput);
    core.poll(ms(450));
    assert_eq!(core.take_event(), Some(Event::Sent { attempt: 1 }));
    assert_eq!(core.take_event(), Some(Event::NoReply { attempt: 1 }));
    assert_eq!(core.take_event(), Some(Event::Discarded));
    assert_eq!(core.take_event(), Some(Event::Sent { attempt: 2 }));

    let go = ub2::Request::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target: 5 });
    core.start(0x21, go);
    let mut t = ms(1000);
    let mut writes = 0;
    loop {
        match core.poll(t) {
            Action::Done => break,
            Action::Write(_) => writes += 1,
            Action::Read { until } | Action::Sleep(until) => t = until,
            _ => {}
        }
    }
    assert_eq!(writes, 1);
    assert!(matches!(
        core.take_outcome(),
        Some(Err(Failure::NoReply { attempts: 1, .. }))
    ));
}

#[test]
fn the_first_set_point_reads_the_devices_counter_first() {
    let mut core: MasterCore<Sd> = MasterCore::new();
    let set = |freshness| {
        sd::Request::SetPoint(sd::request::SetPoint {
            freshness,
            position: sd::Angle(10),
        })
    };
    core.start(1, set(0));
    core.poll(ms(0));
    assert_eq!(
        core.poll(ms(0)),
        Action::Write(&frame(
            &sd::Request::ReadSkippedFramesCounter(sd::request::ReadSkippedFramesCounter),
            1
        ))
    );
    assert!(matches!(core.poll(ms(1)), Action::Read { .. }));
    let counter = sd::Response::SkippedFramesCounter(sd::response::SkippedFramesCounter {
        host_freshness_counter: 12,
        dropped_frames: 0,
    });
    core.received(&frame(&counter, 1), ms(2));
    // Then the set point, after the gap, carrying 13 whatever the caller put in it.
    assert_eq!(core.poll(ms(2)), Action::Sleep(ms(12)));
    assert_eq!(core.poll(ms(12)), Action::ClearInput);
    assert_eq!(core.poll(ms(12)), Action::Write(&frame(&set(13), 1)));
    assert_eq!(core.next_freshness_value(1), Some(14));
}

#[test]
fn a_smaller_receive_buffer_runs_the_same_transaction_in_less_memory() {
    // UB2's longest frame is 16 bytes: a 16-byte buffer holds any one reply.
    let mut small: MasterCore<Ub2, 16> = MasterCore::new();
    let mut default: MasterCore<Ub2> = MasterCore::new();
    assert_eq!(
        core::mem::size_of::<MasterCore<Ub2>>() - core::mem::size_of::<MasterCore<Ub2, 16>>(),
        1024 - 16
    );
    let q = ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance);
    let reply = ub2::Response::ActualCapacitance(ub2::response::ActualCapacitance {
        capacitance: ub2::Capacitance(321),
    });
    let bytes = frame(&reply, 0x21);
    small.start(0x21, q);
    default.start(0x21, q);
    for t in [0, 0, 3] {
        assert_eq!(small.poll(ms(t)), default.poll(ms(t)));
    }
    small.received(&bytes, ms(10));
    default.received(&bytes, ms(10));
    assert_eq!(small.poll(ms(10)), Action::Done);
    assert_eq!(default.poll(ms(10)), Action::Done);
    let (s, d) = (
        small.take_outcome().unwrap(),
        default.take_outcome().unwrap(),
    );
    assert_eq!(s.unwrap().response, Some(reply));
    assert_eq!(d.unwrap().response, Some(reply));
    assert_eq!(small.reply(), default.reply());
}

#[test]
fn a_babbling_line_overflows_a_small_buffer_into_a_bad_reply_not_a_panic() {
    let mut core: MasterCore<Ub2, 16> = MasterCore::new();
    core.start(
        0x21,
        ub2::Request::GetActualCapacitance(ub2::request::GetActualCapacitance),
    );
    core.poll(ms(0));
    core.poll(ms(0));
    assert_eq!(core.poll(ms(3)), Action::Read { until: ms(203) });
    // Four frames' worth of noise (64 bytes) in pieces: the buffer keeps its first 16 and
    // the reply is judged then, without waiting for the line to fall quiet.
    for i in 0..8u64 {
        core.received(&[0x55; 8], ms(10 + i));
    }
    assert_eq!(core.reply(), &[0x55; 16][..]);
    assert!(matches!(
        core.take_event(),
        Some(Event::Sent { attempt: 1 })
    ));
    assert!(matches!(
        core.take_event(),
        Some(Event::Received {
            attempt: 1,
            rejected: Some(_)
        })
    ));
}
