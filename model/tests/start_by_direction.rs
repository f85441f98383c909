//! Start bytes that differ by direction (`framing.start: {request: [...], response: [...]}`,
//! MSP's `$M<` and `$M>`): the interpreter tells a request from a response by them, refuses a
//! frame with the other direction's at the byte that differs, its stream decoder keeps each
//! frame's direction, and docs and diff show them.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};

fn fixture(name: &str) -> busspec_model::Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/valid/{name}"));
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

const REQUEST: [u8; 6] = [0x24, 0x4D, 0x3C, 0x00, 0x01, 0x01];
const REPLY: [u8; 9] = [0x24, 0x4D, 0x3E, 0x03, 0x01, 0x00, 0x01, 0x2C, 0x2F];

#[test]
fn the_start_bytes_tell_a_request_from_its_reply() {
    let p = fixture("msp_by_direction.yaml");
    assert!(p.framing.sync_by_direction());
    assert_eq!(p.framing.sync_of(Direction::Request), [0x24, 0x4D, 0x3C]);
    assert_eq!(p.framing.sync_of(Direction::Response), [0x24, 0x4D, 0x3E]);
    // The request and its reply share the code 0x01.
    let q = interp::decode(&p, None, None, &REQUEST).unwrap();
    assert_eq!(p.message(q.message).name, "api_version");
    let r = interp::decode(&p, None, None, &REPLY).unwrap();
    assert_eq!(p.message(r.message).name, "api_version_reply");
    // A reply's start bytes on a request's frame: a response of no length the frame has.
    let mut swapped = REQUEST;
    swapped[2] = 0x3E;
    assert!(interp::decode(&p, None, None, &swapped).is_err());
}

#[test]
fn the_other_directions_start_bytes_are_refused_at_the_byte_that_differs() {
    let p = fixture("msp_by_direction.yaml");
    let e = interp::decode(&p, Some(Direction::Response), None, &REQUEST).unwrap_err();
    assert_eq!(
        e,
        DecodeError::BadStart {
            offset: 2,
            expected: 0x3E,
            found: 0x3C
        }
    );
    assert_eq!(
        e.to_string(),
        "bad start byte at offset 2: expected 0x3E, found 0x3C"
    );
    // Neither direction's: the request's error, where both are tried.
    let mut neither = REQUEST;
    neither[2] = 0x21;
    assert_eq!(
        interp::decode(&p, None, None, &neither).unwrap_err(),
        DecodeError::BadStart {
            offset: 2,
            expected: 0x3C,
            found: 0x21
        }
    );
}

#[test]
fn a_stream_keeps_each_frames_direction_however_it_is_cut() {
    let p = fixture("msp_by_direction.yaml");
    let mut capture = Vec::new();
    for _ in 0..3 {
        capture.extend_from_slice(&REQUEST);
        capture.push(0x3E); // noise
        capture.extend_from_slice(&REPLY);
    }
    let run = |chunks: &[&[u8]]| {
        let mut d = StreamDecoder::new(&p, None);
        let mut seen = Vec::new();
        for c in chunks {
            seen.extend(d.push(c));
        }
        seen.extend(d.flush());
        seen.into_iter()
            .filter_map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    Some((offset, p.message(frame.message).name.clone()))
                }
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let whole = run(&[&capture]);
    let names: Vec<&str> = whole.iter().map(|(_, n)| n.as_str()).collect();
    assert_eq!(
        names,
        ["api_version", "api_version_reply"].repeat(3),
        "{whole:?}"
    );
    for cut in 0..capture.len() {
        let (a, b) = capture.split_at(cut);
        assert_eq!(run(&[a, b]), whole, "cut at {cut}");
    }
}

#[test]
fn docs_and_diff_show_the_start_bytes_of_each_direction() {
    let p = fixture("msp_by_direction.yaml");
    let docs = busspec_model::docs::render(&p, "msp_by_direction.yaml");
    assert!(
        docs.contains("| start | 3 | requests 0x24 0x4D 0x3C, responses 0x24 0x4D 0x3E |"),
        "{docs}"
    );
    let (_, new) = common::revisions(
        "msp_by_direction",
        &[(
            "response: [0x24, 0x4D, 0x3E]",
            "response: [0x24, 0x4D, 0x21]",
        )],
    );
    let changes = busspec_model::diff::diff(&p, &new);
    let start: Vec<_> = changes
        .iter()
        .filter(|c| c.path == "framing.start.response")
        .collect();
    assert_eq!(start.len(), 1, "{changes:?}");
    assert_eq!(start[0].kind, "framing_changed");
    assert_eq!(
        start[0].text,
        "a response's sync bytes: 24 4D 3E → 24 4D 21"
    );
    assert!(busspec_model::diff::diff(&p, &p).is_empty());
}
