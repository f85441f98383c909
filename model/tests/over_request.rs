//! A reply whose checksum takes in its request's bytes (`checksum_over_request`, Pelco D's
//! general response: "the transmitted check sum added to the alarm information"): decoded
//! and encoded over the request's covered bytes, refused without them, kept by the stream
//! decoder from the request before it, and refused where it cannot be told apart.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError, EncodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};

fn fixture() -> busspec_model::Protocol {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/pelco_d_replies.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

/// Zoom In, and the FLIR manual's reply to it: the request's sum 21 plus alarms 00.
const ZOOM_IN: [u8; 7] = [0xFF, 0x01, 0x00, 0x20, 0x00, 0x00, 0x21];
const ZOOM_REPLY: [u8; 4] = [0xFF, 0x01, 0x00, 0x21];
/// Aux On 1, whose reply is FF 01 00 0B.
const AUX_ON: [u8; 7] = [0xFF, 0x01, 0x00, 0x09, 0x00, 0x01, 0x0B];

fn reply_ref(p: &busspec_model::Protocol) -> MessageRef {
    MessageRef {
        direction: Direction::Response,
        index: p
            .responses
            .iter()
            .position(|m| m.name == "general_response")
            .unwrap(),
    }
}

fn command(p: &busspec_model::Protocol, name: &str) -> usize {
    p.commands.iter().position(|m| m.name == name).unwrap()
}

#[test]
fn the_reply_covers_its_own_bytes_from_the_payload_after_the_request_s() {
    let p = fixture();
    let r = &p.responses[reply_ref(&p).index];
    assert_eq!(r.over_request, Some(2));
    assert!(p.has_over_request());
    assert_eq!(
        p.checksum_span(&ZOOM_IN),
        Some(&[0x01, 0x00, 0x20, 0x00, 0x00][..])
    );
    // The extended response keeps its own sum.
    assert!(p.responses.iter().any(|m| m.over_request.is_none()));
}

#[test]
fn without_its_request_the_reply_is_refused_naming_it() {
    let p = fixture();
    let e = interp::decode(&p, Some(Direction::Response), None, &ZOOM_REPLY).unwrap_err();
    assert_eq!(
        e,
        DecodeError::NeedsRequest {
            message: "general_response".into(),
            offset: 3
        }
    );
    assert_eq!(
        e.to_string(),
        "general_response's checksum at offset 3 takes in its request's bytes: decode it as the reply to its request"
    );
    // Both ways, too: no frame is accepted unchecked.
    assert!(matches!(
        interp::decode(&p, None, None, &ZOOM_REPLY),
        Err(DecodeError::NeedsRequest { .. })
    ));
    // And as a plain reply to its command, which gives no bytes.
    let q = interp::decode(&p, Some(Direction::Request), None, &ZOOM_IN).unwrap();
    assert!(matches!(
        interp::decode_reply(&p, &q, &ZOOM_REPLY),
        Err(DecodeError::NeedsRequest { .. })
    ));
}

#[test]
fn with_its_request_the_reply_is_checked_over_the_request_s_bytes() {
    let p = fixture();
    let q = interp::decode(&p, Some(Direction::Request), None, &ZOOM_IN).unwrap();
    let f = interp::decode_reply_with(&p, &q, Some(&ZOOM_IN), &ZOOM_REPLY).unwrap();
    assert_eq!(f.message, reply_ref(&p));
    assert_eq!(f.address, 1);
    // The same reply to another request fails its checksum: 01 00 09 00 01 + 00 is 0B.
    let aux = interp::decode(&p, Some(Direction::Request), None, &AUX_ON).unwrap();
    assert_eq!(
        interp::decode_reply_with(&p, &aux, Some(&AUX_ON), &ZOOM_REPLY).unwrap_err(),
        DecodeError::ChecksumMismatch {
            offset: 3,
            expected: 0x0B,
            found: 0x21,
            width: 8
        }
    );
    // Its own bytes' sum (01 + 00) is no longer what is checked.
    let own = [0xFF, 0x01, 0x00, 0x01];
    assert!(matches!(
        interp::decode_reply_with(&p, &q, Some(&ZOOM_IN), &own),
        Err(DecodeError::ChecksumMismatch { expected: 0x21, .. })
    ));
    // An extended response is checked over its own bytes, with or without a request.
    let pan = [0xFF, 0x01, 0x00, 0x59, 0x0F, 0xA0, 0x09];
    let query = [0xFF, 0x01, 0x00, 0x51, 0x00, 0x00, 0x52];
    assert!(interp::decode(&p, Some(Direction::Response), None, &pan).is_ok());
    let qq = interp::decode(&p, Some(Direction::Request), None, &query).unwrap();
    assert!(interp::decode_reply_with(&p, &qq, Some(&query), &pan).is_ok());
}

#[test]
fn encoding_the_reply_needs_the_request_s_bytes() {
    let p = fixture();
    let r = reply_ref(&p);
    let values = [Value {
        name: "alarms".into(),
        raw: Raw::Int(0),
    }];
    assert_eq!(
        interp::encode(&p, r, 1, &values).unwrap_err(),
        EncodeError::NeedsRequest {
            message: "general_response".into()
        }
    );
    let covered = p.checksum_span(&ZOOM_IN);
    assert_eq!(
        interp::encode_with(&p, r, 1, &values, covered).unwrap(),
        ZOOM_REPLY
    );
    let covered = p.checksum_span(&AUX_ON);
    assert_eq!(
        interp::encode_with(&p, r, 1, &values, covered).unwrap(),
        [0xFF, 0x01, 0x00, 0x0B]
    );
}

#[test]
fn the_stream_decoder_checks_a_reply_over_the_request_before_it() {
    let p = fixture();
    let mut d = StreamDecoder::new(&p, None);
    let mut events = d.push(
        &[
            &ZOOM_IN[..],
            &ZOOM_REPLY,
            &AUX_ON,
            &[0xFF, 0x01, 0x00, 0x0B],
        ]
        .concat(),
    );
    events.extend(d.flush());
    let frames: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame { frame, .. } => Some(p.message(frame.message).name.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(
        frames,
        [
            "ptz",
            "general_response",
            "set_auxiliary",
            "general_response"
        ]
    );
    // A reply with no request before it (a capture joined late) is no frame: its checksum
    // cannot be checked, and it is not accepted unchecked.
    let mut d = StreamDecoder::new(&p, None);
    let mut events = d.push(&ZOOM_REPLY);
    events.extend(d.flush());
    assert!(events.iter().all(|e| !matches!(e, Event::Frame { .. })));
    // Nor after the wrong request.
    let mut d = StreamDecoder::new(&p, None);
    let mut events = d.push(&[&AUX_ON[..], &ZOOM_REPLY].concat());
    events.extend(d.flush());
    let frames = events
        .iter()
        .filter(|e| matches!(e, Event::Frame { .. }))
        .count();
    assert_eq!(frames, 1);
}

#[test]
fn the_simulator_answers_with_the_checksum_over_the_request() {
    let p = std::sync::Arc::new(fixture());
    let mut sim = busspec_model::sim::Sim::new(p.clone(), 1);
    let reply = sim.answer(&AUX_ON).expect("a reply");
    let q = interp::decode(&p, Some(Direction::Request), None, &AUX_ON).unwrap();
    let f = interp::decode_reply_with(&p, &q, Some(&AUX_ON), &reply).unwrap();
    assert_eq!(p.message(f.message).name, "general_response");
    assert_eq!(reply, [0xFF, 0x01, 0x00, 0x0B]);
    let _ = command(&p, "ptz");
}

fn refused(edits: &[(&str, &str)]) -> String {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/pelco_d_replies.yaml");
    let mut text = std::fs::read_to_string(path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "no `{from}`");
        text = text.replace(from, to);
    }
    match busspec_model::load_str("changed.yaml", &text) {
        Ok(_) => panic!("accepted: {edits:?}"),
        Err(d) => d.to_string(),
    }
}

#[test]
fn what_cannot_be_told_apart_or_checked_is_refused_where_it_is_written() {
    // A part the reply's layout lacks before its checksum.
    let e = refused(&[(
        "checksum_over_request: {covers_from: payload}",
        "checksum_over_request: {covers_from: checksum}",
    )]);
    assert!(
        e.contains("responses.general_response.checksum_over_request.covers_from: the checksum cannot cover from `checksum`"),
        "{e}"
    );
    // An example of such a reply without its request's frame.
    let e = refused(&[(
        "reply_to: ptz, request: \"FF 01 00 20 00 00 21\", ",
        "reply_to: ptz, ",
    )]);
    assert!(e.contains("give the request's frame with `request`"), "{e}");
    // A request frame of another command.
    let e = refused(&[(
        "reply_to: ptz, request: \"FF 01 00 20 00 00 21\"",
        "reply_to: ptz, request: \"FF 01 00 09 00 01 0B\"",
    )]);
    assert!(
        e.contains("the request decodes as `set_auxiliary`, not `ptz`"),
        "{e}"
    );
    // A response of another rule with the same code and length: a four-byte extended reply.
    let e = refused(&[(
        "  response: {code_lengths: [0, 2], payload: {min: 1, max: 2}}",
        "  response: {code_lengths: [0, 2], payload: {min: 0, max: 2}}",
    ), (
        "    responses: [pan_position_response]",
        "    responses: [pan_position_response, busy]",
    ), (
        "  - name: pan_position_response\n",
        "  - name: busy\n    title: \"Busy\"\n    section: \"6\"\n    kind: nak\n    code: \"0x00\"\n    fields: []\n  - name: pan_position_response\n",
    )]);
    assert!(
        e.contains("responses.general_response.checksum_over_request: busy can have the same code and length"),
        "{e}"
    );
    // On a framing without a checksum.
    let e = refused(&[
        ("layout: [start, address, code, payload, checksum]", "layout: [start, address, code, payload]"),
        ("  checksum:\n    algorithm: sum8\n    width: 8\n    covers_from: address\n    check: 0xDD\n", ""),
    ]);
    assert!(
        e.contains("the framing has no checksum to take in the request's bytes"),
        "{e}"
    );
}
