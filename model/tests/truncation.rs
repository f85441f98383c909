//! Payload truncation (`framing.truncation: trailing_zeros`, MAVLink v2): the interpreter pads
//! a payload of 1 byte up to its message's whole with zeros before decoding, refuses an empty
//! or longer one as any frame of another length, checks a truncated frame's checksum as it
//! travelled, strips trailing zeros on encode (one byte kept), and its stream decoder frames
//! truncated frames by their length field. Fixture `mavlink_v2`, its frames pymavlink 2.4.50's.
//! The generated code is held to the interpreter on the same fixture in
//! `codegen/tests/snapshots_compile.rs` (`truncation_snapshot_agrees_with_the_interpreter`).

#![cfg(feature = "tools")]

mod common;

use std::path::Path;

use busspec_model::interp::{self, DecodeError, Raw};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn fixture() -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/mavlink_v2.yaml");
    busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

/// SYS_STATUS (43 payload bytes) with every payload byte 1..=43: nothing to strip.
fn sys_status_whole(p: &Protocol) -> Vec<u8> {
    let mut f = vec![0xFD, 43, 0, 0, 7, 1, 1, 0x01, 0x00, 0x00];
    f.extend(1..=43u8);
    f.extend([0, 0]);
    interp::reseal(p, &mut f);
    f
}

/// `frame`'s payload cut to `n` bytes, its length byte and checksum made to agree.
fn cut(p: &Protocol, frame: &[u8], n: usize) -> Vec<u8> {
    let mut f = frame[..10 + n].to_vec();
    f[1] = n as u8;
    f.extend([0, 0]);
    interp::reseal(p, &mut f);
    f
}

#[test]
fn every_truncation_length_decodes_as_the_payload_padded_with_zeros() {
    let p = fixture();
    let whole = sys_status_whole(&p);
    interp::decode(&p, None, None, &whole).unwrap();
    for n in 1..=43 {
        let wire = cut(&p, &whole, n);
        let got = interp::decode(&p, None, None, &wire).unwrap_or_else(|e| panic!("{n}: {e}"));
        // The same values as the whole frame with the payload's bytes from n on zero.
        let mut padded = whole.clone();
        padded[10 + n..10 + 43].fill(0);
        interp::reseal(&p, &mut padded);
        let want = interp::decode(&p, None, None, &padded).unwrap();
        assert_eq!(got, want, "{n} payload bytes");
        // Encoding strips back to exactly the bytes that came (the last one is not zero).
        let again = interp::encode(&p, got.message, 0, &got.values).unwrap();
        assert_eq!(again, wire, "{n} payload bytes");
    }
}

#[test]
fn an_empty_or_longer_payload_and_a_bad_checksum_are_refused() {
    let p = fixture();
    let whole = sys_status_whole(&p);
    // No payload byte: decoded as it came, shorter than any frame.
    let e = interp::decode(&p, None, None, &cut(&p, &whole, 0)).unwrap_err();
    assert!(matches!(e, DecodeError::Truncated { .. }), "{e:?}");
    // One byte more than the message's: refused for SYS_STATUS's length (ATTITUDE_QUATERNION's
    // 48 payload bytes make 44 no length past every response's).
    let mut long = whole[..10 + 43].to_vec();
    long.push(9);
    long[1] = 44;
    long.extend([0, 0]);
    interp::reseal(&p, &mut long);
    let e = interp::decode(&p, Some(Direction::Response), None, &long).unwrap_err();
    assert!(
        matches!(e, DecodeError::WrongLength { found: 56, ref expected, .. } if expected == &[55]),
        "{e:?}"
    );
    // A truncated frame's checksum is checked as it travelled, at its offset there.
    let mut bad = cut(&p, &whole, 5);
    bad[10] ^= 0x40;
    let e = interp::decode(&p, None, None, &bad).unwrap_err();
    assert!(
        matches!(e, DecodeError::ChecksumMismatch { offset: 15, .. }),
        "{e:?}"
    );
    // A length byte that disagrees with the frame: decoded as it came, and refused.
    let mut wrong = cut(&p, &whole, 5);
    wrong[1] = 6;
    interp::reseal(&p, &mut wrong);
    assert!(interp::decode(&p, None, None, &wrong).is_err());
    // A signed frame (incompat_flags bit 0) is refused at that field.
    let mut signed = cut(&p, &whole, 5);
    signed[2] = 1;
    interp::reseal(&p, &mut signed);
    let e = interp::decode(&p, None, None, &signed).unwrap_err();
    assert!(e.to_string().contains("incompat_flags"), "{e}");
}

#[test]
fn encode_strips_trailing_zeros_and_keeps_one_byte() {
    let p = fixture();
    let ping = p.find("ping").unwrap();
    let zero = interp::decode(
        &p,
        Some(Direction::Request),
        None,
        &hex("FD 01 00 00 09 FF BE 04 00 00 00 37 6D"),
    )
    .unwrap();
    assert_eq!(zero.get("time_usec"), Some(&Raw::Int(0)));
    assert_eq!(
        interp::encode(&p, ping, 0, &zero.values).unwrap(),
        hex("FD 01 00 00 09 FF BE 04 00 00 00 37 6D")
    );
    // A frame sent whole although its payload ends in zeros (a sender that does not strip)
    // decodes all the same, and encodes back stripped.
    let whole = hex("FD 06 00 00 07 FF BE 42 00 00 04 00 01 01 00 00 00 00");
    let mut whole = whole;
    interp::reseal(&p, &mut whole);
    let d = interp::decode(&p, None, None, &whole).unwrap();
    assert_eq!(
        interp::encode(&p, d.message, 0, &d.values).unwrap(),
        hex("FD 04 00 00 07 FF BE 42 00 00 04 00 01 01 F4 E0")
    );
}

#[test]
fn the_stream_frames_truncated_frames_by_their_length() {
    let p = fixture();
    let frames = [
        "FD 10 00 00 03 01 01 1E 00 00 40 E2 01 00 00 00 80 3D 00 00 00 BE 00 00 C0 3F 7C 41",
        "FD 04 00 00 4E 01 01 53 01 00 00 90 BB 44 3C B5",
        "FD 04 00 00 07 FF BE 42 00 00 04 00 01 01 F4 E0",
        "FD 28 00 00 C9 01 01 01 00 00 2F FC 20 00 2F FC 20 00 2F FC 20 00 FA 00 76 2F 3E 03 00 00 03 00 00 00 00 00 00 00 00 00 57 01 00 00 00 01 00 00 00 01 BF E2",
    ];
    let mut cap = Vec::new();
    let mut want = Vec::new();
    for (i, f) in frames.iter().enumerate() {
        if i == 2 {
            cap.extend([0x55, 0xFD]);
        }
        want.push(cap.len() as u64);
        cap.extend(hex(f));
    }
    for chunk in [1, 5, cap.len()] {
        let mut d = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in cap.chunks(chunk) {
            events.extend(d.push(c));
        }
        events.extend(d.flush());
        let got: Vec<(u64, String)> = events
            .iter()
            .filter_map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    Some((*offset, p.message(frame.message).name.clone()))
                }
                Event::Skipped { .. } => None,
                other => panic!("{other:?}"),
            })
            .collect();
        let names = ["attitude", "raw_rpm", "request_data_stream", "sys_status"];
        let want: Vec<(u64, String)> = want
            .iter()
            .zip(names)
            .map(|(o, n)| (*o, n.to_owned()))
            .collect();
        assert_eq!(got, want, "chunks of {chunk}");
    }
}

#[test]
fn a_three_byte_code_is_sent_as_written() {
    let p = fixture();
    let r = p.find("raw_rpm").unwrap();
    assert_eq!(p.message(r).code, [0x53, 0x01, 0x00]);
    let d = interp::decode(
        &p,
        None,
        None,
        &hex("FD 04 00 00 4E 01 01 53 01 00 00 90 BB 44 3C B5"),
    )
    .unwrap();
    assert_eq!(d.message, r);
    assert_eq!(d.get("index"), Some(&Raw::Int(0)));
}

/// Docs state the rule; diff calls adding or removing truncation wire-breaking, on its own.
#[test]
fn docs_and_diff_say_it() {
    let p = fixture();
    let md = busspec_model::docs::render(&p, "mavlink_v2.yaml");
    assert!(
        md.contains("Payload truncation (trailing zeros): a sender strips the payload's trailing zero bytes, keeping at least one"),
        "{md}"
    );
    let (with, without) =
        common::revisions("mavlink_v2", &[("  truncation: trailing_zeros\n", "")]);
    let summary = |a: &Protocol, b: &Protocol| {
        busspec_model::diff::diff(a, b)
            .into_iter()
            .filter(|c| c.kind != "example_removed")
            .map(|c| (c.kind, c.path, c.text))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        summary(&with, &without),
        [(
            "truncation_changed",
            "framing.truncation".to_owned(),
            "payload truncation: trailing zeros stripped → none".to_owned()
        )]
    );
    let back = busspec_model::diff::diff(&without, &with);
    assert!(back.iter().any(|c| c.kind == "truncation_changed"
        && c.category == busspec_model::diff::Category::WireBreaking));
    assert_eq!(summary(&with, &with), []);
}

/// Example text beside truncation is the bytes as they travel: a checksum whose byte order is
/// not the protocol's is not flipped at the place the whole payload's layout puts it (a
/// truncated frame's checksum sits earlier). Found by the random specs: the validator refused
/// an example the interpreter had encoded.
#[test]
fn example_text_is_the_bytes_as_they_travel() {
    let (_, p) = common::revisions(
        "mavlink_v2",
        &[(
            "    byte_order: little\n    poly",
            "    byte_order: big\n    poly",
        )],
    );
    let r = p.find("attitude").unwrap();
    let m = p.message(r);
    let original = fixture();
    let values = interp::decode(
        &original,
        None,
        None,
        &hex("FD 10 00 00 03 01 01 1E 00 00 40 E2 01 00 00 00 80 3D 00 00 00 BE 00 00 C0 3F 7C 41"),
    )
    .unwrap()
    .values;
    let wire = interp::encode(&p, r, 0, &values).unwrap();
    assert_eq!(wire.len(), 28, "{wire:02X?}");
    assert_eq!(interp::printed_to_wire(&p, m, &wire), wire);
    assert_eq!(interp::wire_to_printed(&p, m, &wire), wire);
    interp::decode(&p, None, None, &wire).unwrap();
}
