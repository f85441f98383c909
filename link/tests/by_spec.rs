//! The master's timing for a protocol that only has its spec: what Modbus's `transactions:`
//! section declares (serial 2.4.1, 2.5.1.1) drives `MasterCore<Plain<Modbus>>` step by step.

use core::time::Duration;

use busspec_link_core::master::{Action, MasterCore, Timing};
use busspec_link_core::{Line, Link, Plain};
use busspec_protocols::modbus::{self, Request as Q};

type Modbus = Plain<modbus::Modbus>;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

#[test]
fn the_spec_sets_timeout_gap_in_characters_and_turnaround() {
    let line = Line::for_protocol::<Modbus>();
    // 8E1: 11 bits a character; the turnaround delay, 100 ms.
    assert_eq!((line.baud, line.bits_per_byte), (19_200, 11));
    assert_eq!(line.turnaround, ms(100));
    let t = Timing::for_protocol::<Modbus>();
    assert_eq!(t.reply_timeout, ms(1000));
    // t3.5 at 19,200 baud: 3.5 × 11 / 19,200 s = 2.005 ms (rounded up to the µs).
    assert_eq!(t.inter_request_gap, Duration::from_micros(2006));
    assert_eq!(Modbus::INTER_REQUEST_GAP, Duration::from_micros(2006));
    // At 9,600 baud twice as long; above 19,200 baud the fixed 1.75 ms.
    let at = |baud| Timing::for_line::<Modbus>(&Line { baud, ..line }).inter_request_gap;
    assert_eq!(at(9_600), Duration::from_micros(4011));
    assert_eq!(at(38_400), Duration::from_micros(1750));
    assert_eq!(at(115_200), Duration::from_micros(1750));
    // Reads may be sent twice, writes not.
    let read = Q::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
        starting_address: 0,
        quantity: 1,
    });
    let write = Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
        register_address: 0,
        register_value: 1,
    });
    assert!(Modbus::retry_safe(&read));
    assert!(!Modbus::retry_safe(&write));
    // A spec without the section keeps the master's defaults.
    let d = Timing::for_protocol::<Plain<busspec_protocols::dynamixel::Dynamixel>>();
    assert_eq!(d.reply_timeout, ms(50));
}

#[test]
fn after_an_unanswered_broadcast_the_next_request_waits_the_turnaround() {
    let mut core: MasterCore<Modbus> = MasterCore::new();
    let write = Q::WriteSingleRegister(modbus::request::WriteSingleRegister {
        register_address: 3,
        register_value: 7,
    });
    core.start(0, write);
    assert_eq!(core.poll(ms(0)), Action::ClearInput);
    assert!(matches!(core.poll(ms(0)), Action::Write(_)));
    assert_eq!(core.poll(ms(0)), Action::Done);
    let r = core.take_outcome().unwrap().unwrap();
    assert_eq!((r.response, r.attempts), (None, 1));
    // Sent at 0: the devices take 100 ms to turn around, then the t3.5 gap.
    core.start(
        7,
        Q::ReadHoldingRegisters(modbus::request::ReadHoldingRegisters {
            starting_address: 3,
            quantity: 1,
        }),
    );
    assert_eq!(
        core.poll(ms(1)),
        Action::Sleep(ms(100) + Duration::from_micros(2006))
    );
}
