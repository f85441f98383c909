//! A start and a length field sent twice (`layout: [start, length, length, start, ...]`,
//! FT1.2's and M-Bus's long frame `68 L L 68`): the interpreter checks both copies in layout
//! order and refuses a second that differs where it lies, encode writes both, and a stream
//! finds the frames.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError};
use busspec_model::stream::{Event, StreamDecoder};

fn fixture() -> busspec_model::Protocol {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/ft12_variable.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

const RESET: [u8; 9] = [0x68, 0x03, 0x03, 0x68, 0x53, 0xFE, 0x50, 0xA1, 0x16];

#[test]
fn both_copies_are_read_and_written() {
    let p = fixture();
    let head = p.framing.head(busspec_model::ir::Direction::Request, 1);
    assert_eq!((head.start, head.start_again), (Some(0), Some(3)));
    assert_eq!((head.length, head.length_again), (Some(1), Some(2)));
    let f = interp::decode(&p, None, None, &RESET).unwrap();
    assert_eq!(
        (p.message(f.message).name.as_str(), f.address),
        ("reset", 0xFE)
    );
    let r = p.find("reset").unwrap();
    assert_eq!(interp::encode(&p, r, 0xFE, &[]).unwrap(), RESET);
}

#[test]
fn a_second_copy_that_differs_is_refused_where_it_lies() {
    let p = fixture();
    let mut bad = RESET;
    bad[2] = 0x04;
    assert_eq!(
        interp::decode(&p, None, None, &bad).unwrap_err(),
        DecodeError::LengthMismatch {
            offset: 2,
            expected: 3,
            found: 4
        }
    );
    let mut bad = RESET;
    bad[3] = 0x10;
    let e = interp::decode(&p, None, None, &bad).unwrap_err();
    assert_eq!(
        e.to_string(),
        "bad start byte at offset 3: expected 0x68, found 0x10"
    );
    // Both copies wrong alike: the first is the one refused.
    let mut bad = RESET;
    bad[1] = 0x04;
    bad[2] = 0x04;
    assert!(matches!(
        interp::decode(&p, None, None, &bad),
        Err(DecodeError::LengthMismatch { offset: 1, .. })
    ));
}

#[test]
fn a_stream_finds_each_frame_and_skips_a_damaged_second_copy() {
    let p = fixture();
    let mut damaged = RESET;
    damaged[3] = 0x10;
    let capture: Vec<u8> = [&RESET[..], &damaged, &RESET].concat();
    let mut d = StreamDecoder::new(&p, None);
    let mut events = d.push(&capture);
    events.extend(d.flush());
    let frames: Vec<u64> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame { offset, .. } => Some(*offset),
            _ => None,
        })
        .collect();
    assert_eq!(frames, [0, 18], "{events:?}");
}
