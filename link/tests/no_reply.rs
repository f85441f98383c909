//! Commands the spec says get no reply, or an optional one, through `MasterCore` over any
//! protocol (`Plain`): Pelco-P's commands are done once sent and never wait; FT1.2's
//! `request_class_2` (its reply optional in the fixture) is done with no response when the
//! line stays silent, and not retried, while a command whose reply is required is retried and
//! then fails.

include!("../../codegen/tests/snapshots/pelco_p.rs");
include!("../../codegen/tests/snapshots/ft12_fixed.rs");

use core::time::Duration;

use busspec_link_core::master::{Action, Failure, MasterCore};
use busspec_link_core::Plain;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

/// Runs the core without any reply until it is done; the frames it wrote.
fn silent<P: busspec_link_core::Link>(core: &mut MasterCore<P>) -> usize {
    let mut now = ms(0);
    let mut writes = 0;
    for _ in 0..100 {
        match core.poll(now) {
            Action::Done => return writes,
            Action::Write(_) => writes += 1,
            Action::Sleep(d) => now += d,
            Action::Read { until } => now = until,
            _ => {}
        }
    }
    panic!("the master never finished");
}

#[test]
fn a_command_without_a_reply_is_done_once_sent() {
    let mut core: MasterCore<Plain<pelco_p::PelcoP>> = MasterCore::new();
    core.start(
        0x01,
        pelco_p::Request::GoToPreset(pelco_p::request::GoToPreset { preset: 3 }),
    );
    assert_eq!(core.poll(ms(0)), Action::ClearInput);
    assert!(matches!(core.poll(ms(0)), Action::Write(_)));
    assert_eq!(
        core.poll(ms(0)),
        Action::Done,
        "no wait for a reply that never comes"
    );
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.attempts), (None, 1));
}

#[test]
fn an_optional_reply_that_does_not_come_ends_the_transaction_without_a_retry() {
    use ft12_fixed::{Ft12Fixed, Request};
    let mut core: MasterCore<Plain<Ft12Fixed>> = MasterCore::new();
    core.start(
        0x05,
        Request::RequestClass2(ft12_fixed::request::RequestClass2),
    );
    assert_eq!(silent(&mut core), 1);
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.attempts), (None, 1));
    // The same silence after a command whose reply is required: retried, then no reply.
    core.start(
        0x05,
        Request::RequestStatusOfLink(ft12_fixed::request::RequestStatusOfLink),
    );
    let writes = silent(&mut core);
    assert!(
        writes > 1,
        "a getter whose reply is required is retried ({writes} frames)"
    );
    assert!(matches!(
        core.take_outcome().unwrap(),
        Err(Failure::NoReply { .. })
    ));
}
