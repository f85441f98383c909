//! A short form of the frame (`framing.forms`, M-Bus's short frame `10 C A CS 16` beside its
//! long frame `68 L L 68 C A CI data CS 16` and the single character `E5`): the interpreter
//! decodes all three, sends a frame short exactly where its payload is empty, refuses a long
//! frame with an empty payload and a short frame of another length, locates a short frame's
//! errors on its own bytes, and its stream decoder frames every form. Docs and diff say it. The
//! generated code is held to the interpreter on the same fixture in
//! `codegen/tests/snapshots_compile.rs` (`short_form_snapshot_agrees_with_the_interpreter`).

#![cfg(feature = "tools")]

mod common;

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn fixture() -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/mbus.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

const REQ_UD2: &str = "10 5B 01 5C 16";
const SND_NKE: &str = "10 40 01 41 16";
const RESET: &str = "68 03 03 68 53 01 50 A4 16";
const RSP_UD: &str =
    "68 15 15 68 08 01 72 78 56 34 12 24 40 01 07 55 00 00 00 04 13 2F 06 00 00 9C 16";

#[test]
fn every_form_decodes_and_the_layout_is_the_long_frames() {
    let p = fixture();
    let f = p.framing.form.as_ref().unwrap();
    assert_eq!(
        (
            f.start,
            f.long_start,
            f.at,
            f.fill.as_slice(),
            f.most,
            f.laid_len
        ),
        (0x10, 0x68, 1, &[0x02u8, 0x02, 0x68][..], 2, 8)
    );
    for (wire, name, address) in [
        (REQ_UD2, "req_ud2", 1),
        (SND_NKE, "snd_nke", 1),
        ("10 40 FF 3F 16", "snd_nke", 0xFF),
        (RESET, "snd_ud_reset", 1),
        (RSP_UD, "rsp_ud", 1),
        ("E5", "ack", 0),
    ] {
        let d = interp::decode(&p, None, None, &hex(wire)).unwrap();
        assert_eq!(
            (p.message(d.message).name.as_str(), d.address),
            (name, address),
            "{wire}"
        );
    }
    let d = interp::decode(&p, None, None, &hex(RSP_UD)).unwrap();
    assert_eq!(d.get("volume"), Some(&Raw::Int(1583)));
}

/// A frame travels short exactly where its payload is empty.
#[test]
fn encode_sends_short_exactly_an_empty_payload() {
    let p = fixture();
    let enc = |name: &str| interp::encode(&p, p.find(name).unwrap(), 1, &[]).unwrap();
    assert_eq!(enc("req_ud2"), hex(REQ_UD2));
    assert_eq!(enc("snd_nke"), hex(SND_NKE));
    assert_eq!(enc("snd_ud_reset"), hex(RESET));
}

/// A long frame with an empty payload is refused before anything else (it travels short), so
/// strict decoding round-trips byte for byte; a short frame of another length is refused as it
/// travelled; a short frame's errors are located on its own bytes.
#[test]
fn strict_decoding_refuses_what_does_not_travel_so() {
    let p = fixture();
    let e = interp::decode(&p, None, None, &hex("68 02 02 68 40 01 41 16")).unwrap_err();
    assert!(
        matches!(
            e,
            DecodeError::NeedlessLong {
                offset: 1,
                length: 2,
                most: 2
            }
        ),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "long length field at offset 1 says 2: lengths up to 2 take the short form"
    );
    // Even with a bad checksum: the form is judged first.
    let e = interp::decode(&p, None, None, &hex("68 02 02 68 40 01 00 16")).unwrap_err();
    assert!(matches!(e, DecodeError::NeedlessLong { .. }), "{e:?}");
    let e = interp::decode(&p, None, None, &hex("10 40 01 00 41 16")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "frame too long: 6 bytes, the longest frame has 5"
    );
    let e = interp::decode(&p, None, None, &hex("10 40 01 41")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "truncated frame: need at least 5 bytes, found 4"
    );
    // The checksum of a short frame at offset 3 (6 laid out), its end byte at 4.
    let e = interp::decode(&p, None, None, &hex("10 40 01 42 16")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "checksum mismatch at offset 3: expected 0x41, found 0x42"
    );
    let e = interp::decode(&p, None, None, &hex("10 40 01 41 17")).unwrap_err();
    assert!(e.to_string().contains("offset 4"), "{e}");
    // A short frame whose message has a payload: its lengths as it travelled.
    let e = interp::decode(&p, Some(Direction::Request), None, &hex("10 53 01 54 16")).unwrap_err();
    assert!(e.to_string().contains("found 5"), "{e}");
    // The reply check of a short request's reply, and a long reply to it.
    let req = interp::decode(&p, None, None, &hex(REQ_UD2)).unwrap();
    let reply = interp::decode_reply(&p, &req, &hex(RSP_UD)).unwrap();
    assert_eq!(p.message(reply.message).name, "rsp_ud");
}

/// Lenient decoding words a short frame's broken rules as strict decoding does: on the frame
/// as it travelled (its address at offset 2, not 5).
#[test]
fn lenient_decoding_locates_a_short_frames_violations() {
    let p = fixture();
    let relaxed = busspec_model::stream::relaxed(&p);
    let wire = hex("10 40 FC 3C 16");
    let strict = interp::decode(&p, None, None, &wire).unwrap_err();
    assert!(strict.to_string().contains("offset 2"), "{strict}");
    let (_, violations) =
        busspec_model::stream::decode_lenient(&p, &relaxed, None, None, &wire).unwrap();
    assert_eq!(violations, [strict]);
}

/// The stream decoder frames short frames, long frames and `E5` with noise between them, and
/// takes a long frame with an empty payload for noise, however the capture is cut.
#[test]
fn the_stream_frames_every_form() {
    let p = fixture();
    let mut cap = hex(REQ_UD2);
    cap.extend([0x55, 0xAA]);
    cap.extend(hex(RSP_UD));
    cap.extend(hex("E5"));
    cap.extend(hex("68 02 02 68 40 01 41 16"));
    cap.extend(hex(SND_NKE));
    cap.extend(hex(RESET));
    for chunk in [1, 3, cap.len()] {
        let mut d = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in cap.chunks(chunk) {
            events.extend(d.push(c));
        }
        events.extend(d.flush());
        let seen: Vec<(u64, String)> = events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                Event::Skipped { offset, bytes } => (*offset, format!("skipped {}", bytes.len())),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            seen,
            [
                (0, "req_ud2".to_owned()),
                (5, "skipped 2".to_owned()),
                (7, "rsp_ud".to_owned()),
                (34, "ack".to_owned()),
                (35, "skipped 8".to_owned()),
                (43, "snd_nke".to_owned()),
                (48, "snd_ud_reset".to_owned()),
            ],
            "chunks of {chunk}"
        );
    }
}

/// Docs show both start bytes and state the rule; diff classifies a changed form on its own.
#[test]
fn docs_and_diff_say_it() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "mbus.yaml");
    assert!(
        md.contains("| start | 1 | 0x68, or 0x10 (short form) |"),
        "{md}"
    );
    assert!(
        md.contains("Short form (§5.4): start 0x10 without [length, start] for frames with an empty payload (5 bytes), 0x68 with them for every other."),
        "{md}"
    );
    let (old, new) = common::revisions("mbus", &[("{start: 0x10, drops", "{start: 0x11, drops")]);
    let changes: Vec<_> = busspec_model::diff::diff(&old, &new)
        .into_iter()
        .filter(|c| c.kind != "example_removed")
        .map(|c| (c.kind, c.path))
        .collect();
    assert_eq!(changes, [("form_changed", "framing.forms".to_owned())]);
}
