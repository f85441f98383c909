//! Responses a device sends unasked (`unasked: true`, fixture `unasked.yaml`): the
//! interpreter decodes one on its own, refuses it as the reply to a request that does not
//! list it, and its stream decoder reports it on its own wherever it appears, right after a
//! request too; the docs say so. The generated code is held to the interpreter on the same
//! fixture in `codegen/tests/snapshots_compile.rs`.

#![cfg(feature = "tools")]

use std::path::Path;

use busspec_model::interp::{self, DecodeError};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn text(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/valid")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

fn fixture() -> Protocol {
    busspec_model::load_str("unasked.yaml", &text("unasked.yaml")).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

#[test]
fn the_flag_reaches_the_ir() {
    let p = fixture();
    let flags: Vec<(&str, bool, usize)> = p
        .responses
        .iter()
        .map(|m| (m.name.as_str(), m.unasked, m.answers.len()))
        .collect();
    assert_eq!(
        flags,
        [
            ("started", false, 1),
            ("status", false, 1),
            ("limit", false, 1),
            ("span", false, 1),
            ("heartbeat", true, 0),
            ("alarm", true, 1)
        ]
    );
}

#[test]
fn an_unasked_frame_after_a_request_is_not_its_reply() {
    let p = fixture();
    let q = interp::decode(&p, Some(Direction::Request), None, &hex("AA 21 40 01 0C")).unwrap();
    let heartbeat = hex("AA 21 70 00 00 00 0A 45");
    let alone = interp::decode(&p, None, None, &heartbeat).unwrap();
    assert_eq!(p.message(alone.message).name, "heartbeat");
    let e = interp::decode_reply(&p, &q, &heartbeat).unwrap_err();
    assert!(
        matches!(&e, DecodeError::NotAnAnswer { message, request, .. } if message == "heartbeat" && request == "get_status"),
        "{e:?}"
    );
    // Worded as sent unasked, not as a wrong reply.
    assert_eq!(
        e.to_string(),
        "heartbeat is sent unasked, not a reply get_status gets"
    );
    // A reply the request does not get, sent only as a reply, is worded as before.
    let started = interp::decode_reply(&p, &q, &hex("AA 21 50 1B")).unwrap_err();
    assert_eq!(
        started.to_string(),
        "started is not a reply get_status gets"
    );
    // The alarm is go_to's reply as well as sent unasked.
    let go_to = interp::decode(
        &p,
        Some(Direction::Request),
        None,
        &hex("AA 21 20 00 05 F0"),
    )
    .unwrap();
    let alarm = hex("AA 21 71 03 3F");
    let r = interp::decode_reply(&p, &go_to, &alarm).unwrap();
    assert_eq!(p.message(r.message).name, "alarm");
    assert_eq!(
        interp::decode_reply(&p, &q, &alarm)
            .unwrap_err()
            .to_string(),
        "alarm is sent unasked, not a reply get_status gets"
    );
}

/// An unasked frame between a request and its reply leaves the request waiting: the reply is
/// still paired with it (`limit` and `span` share code and length, only the request tells
/// them apart; the heartbeat ended the pairing and left the reply ambiguous until it did not).
#[test]
fn the_stream_reports_an_unasked_frame_wherever_it_appears() {
    let p = fixture();
    let cap: Vec<u8> = [
        "AA 21 40 01 0C",          // get_status
        "AA 21 70 00 00 00 0A 45", // heartbeat, right after the request
        "AA 21 40 01 00 05 11",    // status, its reply
        "AA 21 71 03 3F",          // alarm, unasked after a reply
        "AA 21 20 00 05 F0",       // go_to
        "AA 21 71 03 3F",          // alarm, its reply
        "AA 21 40 02 0D",          // get_status, channel 2
        "AA 21 71 03 3F",          // alarm, unasked after a request that does not list it
        "AA 21 40 02 00 05 12",    // status, its reply
        "AA 21 41 0C",             // get_limit
        "AA 21 70 00 00 00 0A 45", // heartbeat, between the request and its reply
        "AA 21 42 02 00 10 1F",    // limit, its reply: only the request tells it from span
    ]
    .iter()
    .flat_map(|s| hex(s))
    .collect();
    for cut in [1, 3, cap.len()] {
        let mut d = StreamDecoder::new(&p, None);
        let mut names = Vec::new();
        let mut events: Vec<Event> = Vec::new();
        for chunk in cap.chunks(cut) {
            events.extend(d.push(chunk));
        }
        events.extend(d.flush());
        for e in events {
            match e {
                Event::Frame { frame, .. } => names.push(p.message(frame.message).name.clone()),
                other => panic!("cut {cut}: {other:?}"),
            }
        }
        assert_eq!(
            names,
            [
                "get_status",
                "heartbeat",
                "status",
                "alarm",
                "go_to",
                "alarm",
                "get_status",
                "alarm",
                "status",
                "get_limit",
                "heartbeat",
                "limit"
            ],
            "cut {cut}"
        );
    }
}

#[test]
fn the_reference_says_sent_unasked() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "unasked.yaml");
    assert!(
        md.contains("Sent unasked: the device sends it on its own, not as a reply to any command."),
        "{md}"
    );
    assert!(
        md.contains("Answers: [`go_to`](#go-to); also sent unasked"),
        "{md}"
    );
}

/// A constant whole frame may be sent unasked too (an M-Bus `E5` no command lists).
#[test]
fn a_constant_frame_may_be_sent_unasked() {
    let t = text("mbus_short.yaml");
    let t = &t[..t.find("examples:").unwrap()];
    let t = t
        .replace("    responses: [ack]\n", "    reply: none\n")
        .replace("responses: [status_of_link, ack]", "responses: [status_of_link]")
        .replace(
            "    response_meanings:\n      ack: \"Some secondaries confirm with the single character only.\"\n",
            "",
        )
        .replace("    frame: \"E5\"\n", "    frame: \"E5\"\n    unasked: true\n");
    let p = busspec_model::load_str("x.yaml", &format!("{t}examples: []\nerrata: []\n"))
        .unwrap_or_else(|d| panic!("{d}"));
    let ack = p.responses.iter().find(|m| m.name == "ack").unwrap();
    assert!(ack.unasked && ack.answers.is_empty());
    let f = interp::decode(&p, Some(Direction::Response), None, &[0xE5]).unwrap();
    assert_eq!(p.message(f.message).name, "ack");
}
