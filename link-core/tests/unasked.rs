//! A response the device sends unasked (`unasked: true`) heard while the master waits for a
//! reply: set aside (counted by `unasked_seen`), neither the reply nor a failure, and the
//! master keeps waiting within the same timeout. The protocol is the code generated for the
//! fixture `unasked.yaml` (its snapshot), and for `unasked_to_end.yaml` where the unasked
//! frame's list runs to its end.

// The generated module's optional derives name features this crate does not have.
#![allow(unexpected_cfgs)]

use core::time::Duration;

use busspec_link_core::master::{Action, MasterCore};
use busspec_link_core::{Message, Plain, Protocol};

include!("../../codegen/tests/snapshots/unasked.rs");
include!("../../codegen/tests/snapshots/unasked_to_end.rs");
use unasked::{request, response, Request, Response, Unasked};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn frame<M: Message>(m: &M, address: u8) -> Vec<u8> {
    let mut buf = [0u8; 32];
    let n = m.encode(address, &mut buf).unwrap();
    buf[..n].to_vec()
}

fn heartbeat() -> Vec<u8> {
    frame(
        &Response::Heartbeat(response::Heartbeat { uptime: 10 }),
        0x21,
    )
}

/// Starts `q` at `t` (after any earlier traffic's gap) and polls until the master reads;
/// the read's deadline.
fn sent<P: Protocol>(core: &mut MasterCore<Plain<P>>, q: P::Request, t: Duration) -> Duration {
    core.start(0x21, q);
    let mut t = t;
    let mut wrote = false;
    loop {
        match core.poll(t) {
            Action::Sleep(until) => t = until,
            Action::Write(_) => wrote = true,
            Action::Read { until } if wrote => return until,
            Action::ClearInput => {}
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn a_heartbeat_before_the_reply_is_set_aside() {
    let mut core: MasterCore<Plain<Unasked>> = MasterCore::new();
    let q = Request::GetStatus(request::GetStatus { channel: 1 });
    let deadline = sent(&mut core, q, ms(0));
    let status = frame(
        &Response::Status(response::Status {
            channel: 1,
            value: 5,
        }),
        0x21,
    );
    // A heartbeat and half the reply in one read, then the rest.
    let mut first = heartbeat();
    first.extend_from_slice(&status[..3]);
    core.received(&first, ms(5));
    assert_eq!(core.unasked_seen(), 1);
    assert!(matches!(core.poll(ms(5)), Action::Read { .. }));
    core.received(&status[3..], ms(6));
    assert_eq!(core.poll(ms(6)), Action::Done);
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!(
        r.response,
        Some(Response::Status(response::Status {
            channel: 1,
            value: 5
        }))
    );
    assert_eq!(r.attempts, 1);

    // A heartbeat alone: the master keeps waiting until the same deadline, then the reply.
    let deadline2 = sent(&mut core, q, ms(100));
    core.received(&heartbeat(), ms(107));
    assert_eq!(core.unasked_seen(), 2);
    assert_eq!(core.poll(ms(108)), Action::Read { until: deadline2 });
    core.received(&heartbeat(), ms(109));
    core.received(&status, ms(110));
    assert_eq!(core.unasked_seen(), 3);
    assert_eq!(core.poll(ms(110)), Action::Done);
    assert!(core.take_outcome().unwrap().is_ok());
    assert!(deadline > ms(1));
}

#[test]
fn an_unasked_frame_the_request_gets_is_its_reply() {
    let mut core: MasterCore<Plain<Unasked>> = MasterCore::new();
    let go = Request::GoTo(request::GoTo { target: 5 });
    sent(&mut core, go, ms(0));
    // The alarm is go_to's reply as well as sent unasked: taken as the reply.
    let alarm = Response::Alarm(response::Alarm { alarm_code: 3 });
    core.received(&frame(&alarm, 0x21), ms(5));
    assert_eq!(core.poll(ms(5)), Action::Done);
    assert_eq!(core.take_outcome().unwrap().unwrap().response, Some(alarm));
    assert_eq!(core.unasked_seen(), 0);
}

#[test]
fn only_heartbeats_until_the_deadline_is_no_reply() {
    let mut core: MasterCore<Plain<Unasked>> = MasterCore::new();
    let q = Request::GetStatus(request::GetStatus { channel: 1 });
    let deadline = sent(&mut core, q, ms(0));
    core.received(&heartbeat(), ms(5));
    let mut t = ms(5);
    loop {
        match core.poll(t) {
            Action::Done => break,
            Action::Read { until } | Action::Sleep(until) => t = until,
            _ => {}
        }
    }
    assert!(t >= deadline);
    assert!(core.take_outcome().unwrap().is_err());
    assert_eq!(core.unasked_seen(), 1);
}

/// A log frame (sent unasked, its list running to the frame's end: no length field, no end
/// bytes) whose head `AA 21 72 3D` decodes as a log frame too, `3D` being the sum of the bytes
/// before it. Only the line's quiet time says where such a frame ends: the master sets aside
/// the whole frame, not the head, whether it comes with the reply in one read or cut at that
/// head across two reads.
#[test]
fn an_unasked_frame_to_its_end_is_set_aside_whole() {
    use unasked_to_end::{request, response, Request, Response, UnaskedToEnd};
    let log = [0xAA, 0x21, 0x72, 0x3D, 0x02, 0x7C];
    let status = [0xAA, 0x21, 0x40, 0x00, 0x05, 0x10];
    assert_eq!(Response::decode(&log[..4]).unwrap().message.name(), "log");
    assert_eq!(Response::decode(&log).unwrap().message.name(), "log");
    let q = Request::GetStatus(request::GetStatus { channel: 1 });
    let want = Some(Response::Status(response::Status { value: 5 }));

    // The log and the reply in one read.
    let mut core: MasterCore<Plain<UnaskedToEnd>> = MasterCore::new();
    sent(&mut core, q, ms(0));
    core.received(&[&log[..], &status[..]].concat(), ms(5));
    let mut t = ms(5);
    loop {
        match core.poll(t) {
            Action::Done => break,
            Action::Read { until } | Action::Sleep(until) => t = until,
            other => panic!("{other:?}"),
        }
    }
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.attempts), (want, 1));
    assert_eq!(core.unasked_seen(), 1);

    // The log cut at its head across two reads, then the reply after a quiet gap.
    let mut core: MasterCore<Plain<UnaskedToEnd>> = MasterCore::new();
    let deadline = sent(&mut core, q, ms(0));
    core.received(&log[..4], ms(5));
    core.received(&log[4..], ms(6));
    let mut t = ms(6);
    while let Action::Read { until } = core.poll(t) {
        if until == deadline {
            break;
        }
        t = until;
    }
    assert_eq!(core.unasked_seen(), 1);
    assert_eq!(core.poll(t), Action::Read { until: deadline });
    core.received(&status, t + ms(10));
    assert_eq!(core.poll(t + ms(10)), Action::Done);
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.attempts), (want, 1));
    assert_eq!(core.unasked_seen(), 1);
}

/// A log frame `AA 21 72 43 80` whose bytes sum to zero, then the reply in the same quiet gap:
/// the twelve bytes also decode as one longer log frame (`43 80 AA 21 40 00 05` its text, the
/// reply's checksum `10` the sum of all before it). The master splits them where the rest is
/// the reply, rather than setting aside the longest head and the reply with it.
#[test]
fn a_reply_after_an_unasked_frame_to_its_end_is_not_swallowed() {
    use unasked_to_end::{request, response, Request, Response, UnaskedToEnd};
    let log = [0xAA, 0x21, 0x72, 0x43, 0x80];
    let status = [0xAA, 0x21, 0x40, 0x00, 0x05, 0x10];
    let both = [&log[..], &status[..]].concat();
    assert_eq!(Response::decode(&log).unwrap().message.name(), "log");
    assert_eq!(Response::decode(&both).unwrap().message.name(), "log");
    let q = Request::GetStatus(request::GetStatus { channel: 1 });

    let mut core: MasterCore<Plain<UnaskedToEnd>> = MasterCore::new();
    sent(&mut core, q, ms(0));
    core.received(&both, ms(5));
    let mut t = ms(5);
    loop {
        match core.poll(t) {
            Action::Done => break,
            Action::Read { until } | Action::Sleep(until) => t = until,
            other => panic!("{other:?}"),
        }
    }
    let r = core.take_outcome().unwrap().unwrap();
    let want = Some(Response::Status(response::Status { value: 5 }));
    assert_eq!((r.response, r.attempts), (want, 1));
    assert_eq!(core.unasked_seen(), 1);
}

/// Three unasked frames to their end, then the reply, in one quiet gap: no one head of the
/// bytes leaves the reply, and after the first log the longest head that decodes runs to the
/// reply's end (the reply's bytes extend the second log with a matching checksum). The master
/// splits the bytes into the three logs and the reply.
#[test]
fn a_reply_after_several_unasked_frames_to_their_end_is_not_swallowed() {
    use unasked_to_end::{request, response, Request, Response, UnaskedToEnd};
    let logs: [&[u8]; 3] = [
        &[0xAA, 0x21, 0x72, 0xAA, 0xE7],
        &[0xAA, 0x21, 0x72, 0x43, 0x43, 0xC3],
        &[0xAA, 0x21, 0x72, 0x3D],
    ];
    let status = [0xAA, 0x21, 0x40, 0x00, 0x05, 0x10];
    let all = [logs[0], logs[1], logs[2], &status[..]].concat();
    for log in logs {
        assert_eq!(Response::decode(log).unwrap().message.name(), "log");
    }
    // What made a split one frame at a time fail: after the first log, the rest (the reply
    // too) decodes as one log, and no head leaves the reply alone.
    let heads = |at: usize| -> Vec<usize> {
        (at + 1..=all.len())
            .filter(|&n| Response::decode(&all[at..n]).is_ok_and(|d| d.message.name() == "log"))
            .collect()
    };
    assert_eq!((heads(0), heads(5)), (vec![5], vec![11, all.len()]));
    let q = Request::GetStatus(request::GetStatus { channel: 1 });

    let mut core: MasterCore<Plain<UnaskedToEnd>> = MasterCore::new();
    sent(&mut core, q, ms(0));
    core.received(&all, ms(5));
    let mut t = ms(5);
    loop {
        match core.poll(t) {
            Action::Done => break,
            Action::Read { until } | Action::Sleep(until) => t = until,
            other => panic!("{other:?}"),
        }
    }
    let r = core.take_outcome().unwrap().unwrap();
    let want = Some(Response::Status(response::Status { value: 5 }));
    assert_eq!((r.response, r.attempts), (want, 1));
    assert_eq!(core.unasked_seen(), 3);
}
