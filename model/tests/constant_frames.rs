//! Constant whole frames (`frame:` on a response, M-Bus's single character `E5`): the
//! interpreter's one-frame decoder (plain and through a `Lookup`), its reply pairing, its encoder
//! and its stream decoder give the same answer for them, beside framed frames and noise. The
//! generated code is held to the interpreter on the same fixture in
//! `codegen/tests/snapshots_compile.rs`.

#![cfg(feature = "tools")]

mod common;
use std::path::Path;

use busspec_model::interp::{self, DecodeError, EncodeError, Raw, Value};
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;
use common::Rng;

fn text() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/mbus_short.yaml");
    std::fs::read_to_string(path).unwrap()
}

fn fixture() -> Protocol {
    busspec_model::load_str("mbus_short.yaml", &text()).unwrap_or_else(|d| panic!("{d}"))
}

/// The fixture with each `(from, to)` edit made (each must occur) and its examples dropped.
fn edited(edits: &[(&str, &str)]) -> Protocol {
    let mut t = text();
    for (from, to) in edits {
        assert!(t.contains(from), "no `{from}`");
        t = t.replace(from, to);
    }
    let t = format!(
        "{}examples: []\nerrata: []\n",
        &t[..t.find("examples:").unwrap()]
    );
    busspec_model::load_str("mbus_short.yaml", &t).unwrap_or_else(|d| panic!("{d}"))
}

const SND_NKE: [u8; 5] = [0x10, 0x40, 0x01, 0x41, 0x16];
const STATUS: [u8; 5] = [0x10, 0x0B, 0x05, 0x10, 0x16];

fn name(p: &Protocol, r: MessageRef) -> &str {
    &p.message(r).name
}

#[test]
fn the_constant_is_a_response_after_the_framed_ones_with_its_bytes() {
    let p = fixture();
    // Listed first in the spec, it comes after the framed responses in the IR.
    assert_eq!(p.responses.len(), 2);
    assert_eq!(p.responses[1].name, "ack");
    assert_eq!(p.responses[1].frame.as_deref(), Some(&[0xE5][..]));
    assert_eq!(p.framed(Direction::Response).len(), 1);
    assert_eq!(p.framed(Direction::Request).len(), 2);
    assert_eq!(
        p.constants(Direction::Response).collect::<Vec<_>>(),
        [(1, &[0xE5][..])]
    );
    assert_eq!(p.max_frame_len(Direction::Response), 5);
    // Both commands list it.
    let ack = p.find("ack").unwrap();
    for c in &p.commands {
        assert!(c.gets(ack.index), "{}", c.name);
    }
}

#[test]
fn e5_decodes_as_the_constant_every_way_and_nothing_else_does() {
    let p = fixture();
    let ack = p.find("ack").unwrap();
    let both = interp::Lookup::new(&p, None);
    let responses = interp::Lookup::new(&p, Some(Direction::Response));
    for f in [
        interp::decode(&p, None, None, &[0xE5]),
        interp::decode(&p, Some(Direction::Response), None, &[0xE5]),
        both.decode(&p, None, &[0xE5]),
        responses.decode(&p, None, &[0xE5]),
        interp::decode_as(&p, ack, &[0xE5]),
    ] {
        let f = f.unwrap();
        assert_eq!((f.message, f.address), (ack, 0));
        assert!(f.values.is_empty());
    }
    // Decoded as a request, it is no frame: its first byte is no start byte.
    assert_eq!(
        interp::decode(&p, Some(Direction::Request), None, &[0xE5]).unwrap_err(),
        DecodeError::BadStart {
            offset: 0,
            expected: 0x10,
            found: 0xE5
        }
    );
    // Bytes that begin with it, or with it twice, are no frame either, refused as before.
    for bad in [&[0xE5, 0xE5][..], &[0xE5, 0x10, 0x0B, 0x05, 0x10, 0x16]] {
        let e = interp::decode(&p, None, None, bad).unwrap_err();
        assert_eq!(e, both.decode(&p, None, bad).unwrap_err());
        assert!(
            matches!(
                e,
                DecodeError::BadStart { offset: 0, .. } | DecodeError::TooLong { .. }
            ),
            "{e:?}"
        );
    }
    // Decoded as the constant message, other bytes are refused and say why.
    assert_eq!(
        interp::decode_as(&p, ack, &[]).unwrap_err(),
        DecodeError::Truncated {
            needed: 1,
            found: 0
        }
    );
    assert!(matches!(
        interp::decode_as(&p, ack, &[0xE5, 0x00]).unwrap_err(),
        DecodeError::WrongLength { expected, found: 2, .. } if expected == [1]
    ));
    // The framed frames decode as before.
    let s = interp::decode(&p, None, None, &STATUS).unwrap();
    assert_eq!((name(&p, s.message), s.address), ("status_of_link", 5));
}

#[test]
fn the_constant_is_the_reply_only_of_the_commands_that_list_it() {
    let p = fixture();
    for c in ["snd_nke", "req_ske"] {
        let q = p.find(c).unwrap();
        let request = interp::decode_as(
            &p,
            q,
            &if c == "snd_nke" {
                SND_NKE
            } else {
                [0x10, 0x49, 0x05, 0x4E, 0x16]
            },
        )
        .unwrap();
        let r = interp::decode_reply(&p, &request, &[0xE5]).unwrap();
        assert_eq!(name(&p, r.message), "ack");
    }
    // A revision where req_ske does not list it: not its reply, in the words of any reply.
    let p = edited(&[
        ("responses: [status_of_link, ack]", "responses: [status_of_link]"),
        (
            "    response_meanings:\n      ack: \"Some secondaries confirm with the single character only.\"\n",
            "",
        ),
    ]);
    let q = p.find("req_ske").unwrap();
    let request = interp::decode_as(&p, q, &[0x10, 0x49, 0x05, 0x4E, 0x16]).unwrap();
    let e = interp::decode_reply(&p, &request, &[0xE5]).unwrap_err();
    assert_eq!(
        e,
        DecodeError::NotAnAnswer {
            message: "ack".into(),
            request: "req_ske".into(),
            unasked: false
        }
    );
    assert!(interp::decode_reply(&p, &request, &STATUS).is_ok());
}

#[test]
fn encode_writes_the_bytes_whatever_the_address_and_takes_no_value() {
    let p = fixture();
    let ack = p.find("ack").unwrap();
    for address in [0x00, 0x05, 0xFA, 0xFE, 0xFF] {
        assert_eq!(interp::encode(&p, ack, address, &[]).unwrap(), [0xE5]);
    }
    let value = Value {
        name: "status".into(),
        raw: Raw::Int(1),
    };
    assert_eq!(
        interp::encode(&p, ack, 0, &[value]).unwrap_err(),
        EncodeError::UnknownValue {
            field: "status".into()
        }
    );
    // What encode writes decodes to the message again.
    let wire = interp::encode(&p, ack, 0, &[]).unwrap();
    assert_eq!(interp::decode(&p, None, None, &wire).unwrap().message, ack);
}

/// What the stream decoder reports, as (offset, what): a message's name, `skipped N`.
fn events(p: &Protocol, direction: Option<Direction>, chunks: &[&[u8]]) -> Vec<(u64, String)> {
    let mut d = StreamDecoder::new(p, direction);
    let mut out = Vec::new();
    for c in chunks {
        out.extend(d.push(c));
    }
    out.extend(d.flush());
    out.iter()
        .map(|e| match e {
            Event::Frame { offset, frame, .. } => (*offset, name(p, frame.message).to_owned()),
            Event::Skipped { offset, bytes } => (*offset, format!("skipped {}", bytes.len())),
            Event::Ambiguous { offset, .. } => (*offset, "ambiguous".into()),
            Event::OutOfSpec { offset, .. } => (*offset, "out of spec".into()),
        })
        .collect()
}

#[test]
fn a_stream_finds_the_constant_among_frames_and_noise_however_it_is_cut() {
    let p = fixture();
    let mut rng = Rng(0xE5);
    let mut acks = 0;
    for _ in 0..300 {
        // Frames, E5s and noise that can start nothing (neither 0x10 nor 0xE5): every event is
        // known beforehand.
        let (mut cap, mut want) = (Vec::new(), Vec::<(u64, String)>::new());
        for _ in 0..10 {
            let at = cap.len() as u64;
            match rng.below(4) {
                0 => {
                    cap.push(0xE5);
                    want.push((at, "ack".into()));
                    acks += 1;
                }
                1 => {
                    cap.extend_from_slice(&SND_NKE);
                    want.push((at, "snd_nke".into()));
                }
                2 => {
                    cap.extend_from_slice(&STATUS);
                    want.push((at, "status_of_link".into()));
                }
                _ => {
                    let n = 1 + rng.below(3);
                    cap.extend((0..n).map(|_| [0x00, 0x16, 0xE4, 0xE6, 0x42][rng.below(5)]));
                    match want.last_mut() {
                        Some((_, w)) if w.starts_with("skipped") => {
                            let k: usize = w[8..].parse().unwrap();
                            *w = format!("skipped {}", k + n);
                        }
                        _ => want.push((at, format!("skipped {n}"))),
                    }
                }
            }
        }
        assert_eq!(events(&p, None, &[&cap]), want, "{cap:02X?}");
        // Pushed a byte at a time, and in random chunks: the same.
        let bytes: Vec<&[u8]> = cap.chunks(1).collect();
        assert_eq!(events(&p, None, &bytes), want, "{cap:02X?} byte by byte");
        let cut = 1 + rng.below(cap.len());
        assert_eq!(events(&p, None, &[&cap[..cut], &cap[cut..]]), want);
        // Each frame event's bytes decode alone to the same message.
        let mut d = StreamDecoder::new(&p, None);
        let mut all = d.push(&cap);
        all.extend(d.flush());
        for e in all {
            if let Event::Frame { bytes, frame, .. } = e {
                assert_eq!(
                    interp::decode(&p, None, None, &bytes).unwrap().message,
                    frame.message
                );
            }
        }
        // A decoder of requests only takes every E5 for noise.
        let requests = events(&p, Some(Direction::Request), &[&cap]);
        assert!(requests
            .iter()
            .all(|(_, w)| w != "ack" && w != "status_of_link"));
    }
    assert!(acks > 500, "{acks}");
}

#[test]
fn a_constant_of_two_bytes_waits_for_its_second_and_is_noise_without_it() {
    let p = edited(&[("frame: \"E5\"", "frame: \"A2 01\"")]);
    let mut d = StreamDecoder::new(&p, None);
    assert!(d.push(&[0xA2]).is_empty(), "waits for the second byte");
    let ev = d.push(&[0x01]);
    assert!(matches!(&ev[..], [Event::Frame { offset: 0, bytes, .. }] if bytes == &[0xA2, 0x01]));
    // Its first byte alone at the end of a capture, or followed by another byte, is noise.
    assert_eq!(events(&p, None, &[&[0xA2]]), [(0, "skipped 1".to_owned())]);
    assert_eq!(
        events(&p, None, &[&[0xA2, 0x02, 0xA2, 0x01], &SND_NKE]),
        [
            (0, "skipped 2".to_owned()),
            (2, "ack".to_owned()),
            (4, "snd_nke".to_owned())
        ]
    );
    assert_eq!(
        interp::decode(&p, None, None, &[0xA2, 0x01])
            .unwrap()
            .message,
        p.find("ack").unwrap()
    );
}

#[test]
fn docs_show_the_constant_frames_bytes() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "mbus_short.yaml");
    assert!(
        md.contains("| `E5 (whole frame)` | [`ack`](#ack) | ACK | 5.4 | 1 |"),
        "{md}"
    );
    assert!(md.contains(
        "Constant whole frame `E5`, ACK, 1 bytes: the frame is these bytes alone, without start, address, code or checksum."
    ));
    // The commands' reply lists show it by its bytes too.
    assert!(md.contains("- [`ack`](#ack) `E5 (whole frame)`"));
}

#[test]
fn diff_classifies_constant_frames_changed_added_and_made() {
    use busspec_model::diff::{Category, Change};
    // The edited revision drops the examples: those changes aside.
    let diff = |a: &Protocol, b: &Protocol| -> Vec<Change> {
        busspec_model::diff::diff(a, b)
            .into_iter()
            .filter(|c| c.kind != "example_removed")
            .collect()
    };
    let (old, new) = common::revisions("mbus_short", &[("frame: \"E5\"", "frame: \"06\"")]);
    let changes = diff(&old, &new);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(changes[0].category, Category::WireBreaking);
    assert_eq!(changes[0].kind, "constant_frame_changed");
    assert_eq!(changes[0].path, "responses.ack.frame");
    assert_eq!(changes[0].text, "response `ack`: frame E5 → frame 06");
    // A framed response made a constant one: wire-breaking, said once.
    let (old, new) = common::revisions(
        "mbus_short",
        &[("    code: \"0x0B\"\n", "    frame: \"A2\"\n")],
    );
    let changes = diff(&old, &new);
    assert_eq!(changes.len(), 1, "{changes:?}");
    assert_eq!(
        (changes[0].kind, changes[0].text.as_str()),
        (
            "constant_frame_changed",
            "response `status_of_link`: 0x0B → frame A2"
        )
    );
    // A constant response added (and listed by a command): compatible, named by its bytes.
    let (old, new) = common::revisions(
        "mbus_short",
        &[
            ("responses: [ack]\n", "responses: [ack, nak]\n"),
            (
                "  - name: status_of_link\n",
                "  - name: nak\n    title: \"NAK\"\n    section: \"5.4\"\n    kind: nak\n    frame: \"15\"\n  - name: status_of_link\n",
            ),
        ],
    );
    let changes = diff(&old, &new);
    let added = changes
        .iter()
        .find(|c| c.kind == "message_added")
        .unwrap_or_else(|| panic!("{changes:?}"));
    assert_eq!(added.category, Category::Compatible);
    assert_eq!(added.text, "response `nak` (frame 15, §5.4) added");
    // Renamed with the same bytes: paired by them, a rename.
    let (old, new) = common::revisions(
        "mbus_short",
        &[
            ("name: ack\n", "name: confirm\n"),
            ("[ack]", "[confirm]"),
            ("[status_of_link, ack]", "[status_of_link, confirm]"),
            ("      ack: \"", "      confirm: \""),
        ],
    );
    let changes = diff(&old, &new);
    assert!(
        changes.iter().any(|c| c.kind == "message_renamed"
            && c.text == "response `ack` (frame E5) renamed to `confirm`"),
        "{changes:?}"
    );
    assert!(
        changes.iter().all(|c| c.category != Category::WireBreaking),
        "{changes:?}"
    );
}
