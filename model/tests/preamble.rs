//! A preamble of wake-up bytes (`framing.preamble`, DL/T 645's `FE FE FE FE`): the
//! interpreter's one-frame decoders take 0 to `max` of them before a frame and refuse more at
//! the start byte, its encoder sends `send` of them, and its stream decoder counts a run of them
//! into the frame that follows (the event's offset at the first), reporting those that open no
//! frame as noise, however the capture is cut. The generated code is held to the interpreter on
//! the same fixture in `codegen/tests/snapshots_compile.rs`
//! (`preamble_snapshot_agrees_with_the_interpreter`), the runtime's fast path included.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;
use common::Rng;

fn fixture() -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/dlt645.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// Read the address of every meter (`68 AA×6 68 13 00 DF 16`), without its preamble.
const READ_ADDRESS: [u8; 12] = [
    0x68, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0x68, 0x13, 0x00, 0xDF, 0x16,
];
/// Read data identifier 00 01 00 00 from meter 000000000001.
const READ_DATA: [u8; 16] = [
    0x68, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x68, 0x11, 0x04, 0x33, 0x33, 0x34, 0x33, 0xB3, 0x16,
];

fn with_preamble(n: usize, frame: &[u8]) -> Vec<u8> {
    [vec![0xFE; n], frame.to_vec()].concat()
}

#[test]
fn the_preamble_is_in_the_ir_and_outside_every_frame_length() {
    let p = fixture();
    let pre = p.framing.preamble.as_ref().expect("a preamble");
    assert_eq!((pre.byte, pre.send, pre.max), (0xFE, 4, 4));
    // The longest frame is 22 bytes; an encoder's buffer holds its four wake-up bytes too.
    assert_eq!(p.max_frame_len(Direction::Response), 22);
    assert_eq!(p.max_wire_len(Direction::Response), 26);
    assert_eq!(p.max_wire_len(Direction::Request), 4 + 16);
    // Every example stands for the bytes an encoder sends: four wake-up bytes, then the frame
    // (the meters' replies were printed without them).
    for e in &p.examples {
        assert_eq!(&e.wire[..4], [0xFE; 4]);
        assert_eq!(e.wire[4], 0x68);
    }
}

#[test]
fn decode_takes_none_to_four_wake_up_bytes_and_refuses_a_fifth_at_the_start_byte() {
    let p = fixture();
    let lookup = interp::Lookup::new(&p, None);
    let read_address = p.find("read_address").unwrap();
    for n in 0..=4 {
        let wire = with_preamble(n, &READ_ADDRESS);
        let f = interp::decode(&p, None, None, &wire).unwrap_or_else(|e| panic!("{n}: {e}"));
        assert_eq!(f.message, read_address);
        assert_eq!(f.get("address_low"), Some(&Raw::Int(0xAAAAAA)));
        assert_eq!(
            lookup.decode(&p, None, &wire).unwrap().message,
            read_address
        );
        assert_eq!(
            interp::decode_as(&p, read_address, &wire).unwrap().message,
            read_address
        );
    }
    // Offsets count from the frame's first byte, after the four wake-up bytes taken.
    let five = with_preamble(5, &READ_ADDRESS);
    let want = DecodeError::BadStart {
        offset: 0,
        expected: 0x68,
        found: 0xFE,
    };
    assert_eq!(interp::decode(&p, None, None, &five), Err(want.clone()));
    assert_eq!(lookup.decode(&p, None, &five), Err(want));
    // A checksum error is located in the frame, not counting the preamble.
    let mut bad = with_preamble(4, &READ_ADDRESS);
    bad[4 + 10] ^= 1;
    assert!(matches!(
        interp::decode(&p, None, None, &bad),
        Err(DecodeError::ChecksumMismatch { offset: 10, .. })
    ));
    // Wake-up bytes alone are no frame; another byte before them is no wake-up byte.
    assert!(matches!(
        interp::decode(&p, None, None, &[0xFE; 4]),
        Err(DecodeError::Truncated { found: 0, .. })
    ));
    let other = [&[0xFF][..], &with_preamble(2, &READ_ADDRESS)].concat();
    assert!(matches!(
        interp::decode(&p, None, None, &other),
        Err(DecodeError::BadStart {
            offset: 0,
            found: 0xFF,
            ..
        })
    ));
}

#[test]
fn encode_sends_four_wake_up_bytes_then_the_frame() {
    let p = fixture();
    let r = p.find("read_data").unwrap();
    let values = [
        Value {
            name: "address_low".into(),
            raw: Raw::Int(1),
        },
        Value {
            name: "address_high".into(),
            raw: Raw::Int(0),
        },
        Value {
            name: "data_id".into(),
            raw: Raw::Int(0x0001_0000),
        },
    ];
    let wire = interp::encode(&p, r, 0, &values).unwrap();
    assert_eq!(wire, with_preamble(4, &READ_DATA));
    assert_eq!(interp::decode(&p, None, None, &wire).unwrap().message, r);
}

/// Events as (what, offset, bytes): a message's name, `-` for skipped bytes (runs merged).
fn events(p: &Protocol, cap: &[u8], cuts: &[usize]) -> Vec<(String, u64, Vec<u8>)> {
    let mut d = StreamDecoder::new(p, None);
    let mut all = Vec::new();
    let mut rest = cap;
    for &n in cuts.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        let (chunk, r) = rest.split_at(n.min(rest.len()));
        rest = r;
        all.extend(d.push(chunk));
    }
    all.extend(d.flush());
    let mut out: Vec<(String, u64, Vec<u8>)> = Vec::new();
    for e in all {
        let (what, offset, bytes) = match e {
            Event::Frame {
                offset,
                bytes,
                frame,
            } => (p.message(frame.message).name.clone(), offset, bytes),
            Event::Skipped { offset, bytes } => ("-".to_owned(), offset, bytes),
            Event::Ambiguous { offset, bytes, .. } => ("?".to_owned(), offset, bytes),
            Event::OutOfSpec { offset, bytes, .. } => ("!".to_owned(), offset, bytes),
        };
        if let Some(last) = out.last_mut() {
            if what == "-" && last.0 == "-" && last.1 + last.2.len() as u64 == offset {
                last.2.extend(bytes);
                continue;
            }
        }
        out.push((what, offset, bytes));
    }
    out
}

#[test]
fn a_frame_takes_the_wake_up_bytes_before_it_and_the_rest_are_noise() {
    let p = fixture();
    let mut cap = Vec::new();
    // Four before the first frame: all its own.
    cap.extend(with_preamble(4, &READ_ADDRESS));
    // Noise, then three (one, then two more): the frame's.
    cap.extend([0x00, 0xFE]);
    cap.extend(with_preamble(2, &READ_DATA));
    // Six in a row: the first two noise, the last four the frame's.
    cap.extend(with_preamble(6, &READ_DATA));
    // None.
    cap.extend(READ_ADDRESS);
    // Three that open no frame (a byte that starts none follows), then three at the end.
    cap.extend([0xFE, 0xFE, 0xFE, 0x33]);
    cap.extend([0xFE; 3]);
    let want: Vec<(String, u64, Vec<u8>)> = vec![
        ("read_address".into(), 0, with_preamble(4, &READ_ADDRESS)),
        ("-".into(), 16, vec![0x00]),
        ("read_data".into(), 17, with_preamble(3, &READ_DATA)),
        ("-".into(), 36, vec![0xFE, 0xFE]),
        ("read_data".into(), 38, with_preamble(4, &READ_DATA)),
        ("read_address".into(), 58, READ_ADDRESS.to_vec()),
        (
            "-".into(),
            70,
            vec![0xFE, 0xFE, 0xFE, 0x33, 0xFE, 0xFE, 0xFE],
        ),
    ];
    assert_eq!(events(&p, &cap, &[cap.len()]), want);
    // However the capture is cut.
    let mut rng = Rng(0xFEFE);
    for _ in 0..200 {
        let cuts: Vec<usize> = (0..5).map(|_| 1 + rng.below(12)).collect();
        assert_eq!(events(&p, &cap, &cuts), want, "cut {cuts:?}");
    }
    // Nothing is lost: the events' bytes are the capture.
    let bytes: Vec<u8> = want.iter().flat_map(|e| e.2.clone()).collect();
    assert_eq!(bytes, cap);
}

#[test]
fn a_frame_after_wake_up_bytes_that_fails_leaves_them_noise() {
    let p = fixture();
    let mut bad = with_preamble(3, &READ_ADDRESS);
    bad[3 + 10] ^= 0x01;
    let mut cap = bad.clone();
    cap.extend(with_preamble(1, &READ_ADDRESS));
    let got = events(&p, &cap, &[cap.len()]);
    assert_eq!(
        got,
        vec![
            ("-".to_owned(), 0, bad.clone()),
            (
                "read_address".to_owned(),
                bad.len() as u64,
                with_preamble(1, &READ_ADDRESS)
            ),
        ]
    );
}

/// Random captures of the examples with runs of wake-up bytes, noise and cut frames: every
/// byte is in exactly one event, in order, and every frame event's bytes decode on their own
/// as its message.
#[test]
fn random_captures_lose_nothing_and_frames_decode_with_their_wake_up_bytes() {
    let p = fixture();
    let frames: Vec<Vec<u8>> = p
        .examples
        .iter()
        .map(|e| p.framing.after_preamble(&e.wire).to_vec())
        .collect();
    let mut rng = Rng(0x645);
    let mut found = 0;
    for _ in 0..200 {
        let mut cap = Vec::new();
        for _ in 0..10 {
            match rng.below(5) {
                0 => cap.extend((0..1 + rng.below(3)).map(|_| rng.below(256) as u8)),
                1 => cap.extend(std::iter::repeat(0xFE).take(rng.below(7))),
                _ => {
                    let f = &frames[rng.below(frames.len())];
                    cap.extend(with_preamble(rng.below(6), f));
                }
            }
        }
        let cuts: Vec<usize> = (0..4).map(|_| 1 + rng.below(30)).collect();
        let got = events(&p, &cap, &cuts);
        let mut at = 0u64;
        for (what, offset, bytes) in &got {
            assert_eq!(*offset, at, "{cap:02X?}");
            at += bytes.len() as u64;
            if !matches!(&**what, "-" | "?" | "!") {
                found += 1;
                assert!(bytes.iter().take_while(|b| **b == 0xFE).count() <= 4);
                let f = interp::decode(&p, None, None, bytes)
                    .or_else(|_| interp::decode(&p, Some(Direction::Response), Some(1), bytes))
                    .unwrap_or_else(|e| panic!("{bytes:02X?}: {e}"));
                assert_eq!(&p.message(f.message).name, what);
            }
        }
        assert_eq!(at, cap.len() as u64);
        assert_eq!(got, events(&p, &cap, &[cap.len()]));
    }
    assert!(found > 800, "only {found} frames");
}

/// Example text printed in another byte order than the wire's is reordered after the
/// preamble: the wake-up bytes stay first, and the text reads back as the bytes sent. (The
/// random specs' derived examples were reordered from the preamble's first byte on, and
/// refused by the validator.)
#[test]
fn printed_text_is_reordered_after_the_preamble() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/dlt645.yaml");
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("printed_byte_order: little", "printed_byte_order: big");
    let head = &text[..text.find("examples:").unwrap()];
    let p = busspec_model::load_str("dlt645.yaml", &format!("{head}examples: []\nerrata: []\n"))
        .unwrap_or_else(|d| panic!("{d}"));
    let r = p.find("read_data").unwrap();
    let wire = with_preamble(4, &READ_DATA);
    let printed = interp::wire_to_printed(&p, p.message(r), &wire);
    assert_eq!(&printed[..5], [0xFE, 0xFE, 0xFE, 0xFE, 0x68]);
    // The data identifier and the address fields are printed high byte first.
    assert_eq!(&printed[4 + 10..4 + 14], [0x33, 0x34, 0x33, 0x33]);
    assert_eq!(&printed[4 + 1..4 + 4], [0x00, 0x00, 0x01]);
    let example = format!(
        "{head}examples:\n  - {{section: \"1\", message: read_data, derived: \"{}\", values: {{data_id: 0x00010000}}}}\nerrata: []\n",
        interp::format_hex(&printed)
    );
    let q = busspec_model::load_str("dlt645.yaml", &example).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(q.examples[0].wire, wire);
}
