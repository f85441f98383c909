//! Escaping and stuffing (`framing.escaping`) in the interpreter: the fixtures' examples both
//! ways, each refusal in its words and at its offset, and on random bytes that decoding accepts
//! exactly what encoding writes.

#![cfg(feature = "tools")]

mod common;

use busspec_model::escape::{escape_bytes, unescape_bytes};
use busspec_model::interp::{self, parse_hex, Frame, Raw, Value};
use busspec_model::ir::Direction;
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::Protocol;

fn fixture(name: &str) -> Protocol {
    let path = format!(
        "{}/tests/fixtures/valid/{name}.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    busspec_model::load_file(std::path::Path::new(&path)).unwrap_or_else(|d| panic!("{d}"))
}

const ESCAPED: [&str; 10] = [
    "slip_sensor",
    "garmin_link",
    "tsip",
    "kiss",
    "hdlc_like",
    "cobs_link",
    "dynamixel2_stuffed",
    "xbee_api2",
    "fport",
    "fport_uplink",
];

fn values(frame: &Frame) -> Vec<Value<'static>> {
    frame.clone().into_owned().values
}

fn refusal(p: &Protocol, hex: &str) -> String {
    let wire = parse_hex(hex).unwrap();
    interp::decode(p, None, None, &wire)
        .map(|f| format!("decoded as {}", p.message(f.message).name))
        .unwrap_or_else(|e| e.to_string())
}

/// Every example decodes from its escaped bytes and encodes back to them, and at least one
/// example of each fixture is longer on the wire than unescaped (it exercises the escaping).
#[test]
fn examples_decode_and_encode_back_escaped() {
    for name in ESCAPED {
        let p = fixture(name);
        let mut escaped = 0;
        for e in &p.examples {
            // In its direction: KISS's data frames read alike both ways.
            let d = Some(e.message.direction);
            let frame = interp::decode(&p, d, e.reply_to, &e.wire)
                .unwrap_or_else(|err| panic!("{name}: {err}"));
            assert_eq!(frame.message, e.message, "{name}");
            let again = interp::encode(&p, frame.message, frame.address, &values(&frame))
                .unwrap_or_else(|err| panic!("{name}: {err}"));
            assert_eq!(again, e.wire, "{name}: {}", p.message(e.message).name);
            let plain = unescape_bytes(&p.framing, &e.wire).unwrap();
            if plain.len() < e.wire.len() {
                escaped += 1;
            }
        }
        assert!(escaped > 0, "{name}: no example exercises the escaping");
    }
}

#[test]
fn byte_escaping_refusals_are_located() {
    let slip = fixture("slip_sensor");
    // 81 DB DC DB DD 60 28 C0 is the temperature example.
    assert_eq!(
        refusal(&slip, "81 DB 41 DB DD 60 28 C0"),
        "bad escape at offset 1: 0xDB followed by 0x41"
    );
    assert_eq!(
        refusal(&slip, "81 C0 DB DD 60 28 C0"),
        "bad escape at offset 1: 0xC0 not escaped"
    );
    assert_eq!(
        refusal(&slip, "81 DB DC DB DD 60 DB C0"),
        "bad escape at offset 6: 0xDB followed by 0xC0"
    );
    // The escapes pass; the checksum is computed on the unescaped frame.
    assert_eq!(
        refusal(&slip, "81 DB DC DB DD 60 29 C0"),
        "checksum mismatch at offset 3: expected 0x6028, found 0x6029"
    );
    let hdlc = fixture("hdlc_like");
    assert_eq!(
        refusal(&hdlc, "7E 01 90 7D 5E 7D 41 00 00 7E"),
        "bad escape at offset 5: 0x7D followed by 0x41"
    );
    // Garmin's DLE stuffing: 10 15 02 10 10 00 D9 10 03 is the NAK of packet 0x10.
    let garmin = fixture("garmin_link");
    assert_eq!(
        refusal(&garmin, "10 15 02 10 00 D9 10 03"),
        "bad escape at offset 3: 0x10 followed by 0x00"
    );
    // A DLE ETX inside the frame ends nothing: decoding a whole frame refuses it.
    assert_eq!(
        refusal(&garmin, "10 15 02 10 03 00 D9 10 03"),
        "bad escape at offset 3: 0x10 followed by 0x03"
    );
    assert_eq!(
        refusal(&garmin, "10 15 02 10 10 00 D8 10 03"),
        "checksum mismatch at offset 5: expected 0xD9, found 0xD8"
    );
    assert_eq!(
        refusal(&garmin, "10 15 02 10 10 00 D9 10 03"),
        "decoded as nak"
    );
}

#[test]
fn cobs_refusals_are_located() {
    let p = fixture("cobs_link");
    let ex = |i: usize| interp::format_hex(&p.examples[i].wire);
    // read_position: 00 10 crc, stuffed 01 03 10 crc 00.
    assert_eq!(ex(0).replace(' ', "")[..6].to_owned(), "010310");
    assert_eq!(
        refusal(&p, "01 04 10 07 00"),
        "bad escape at offset 1: COBS block 0x04 runs past the end byte"
    );
    assert_eq!(
        refusal(&p, "01 03 00 07 00"),
        "bad escape at offset 2: COBS block holds 0x00"
    );
    assert_eq!(
        refusal(&p, "00"),
        "bad escape at offset 0: no COBS block before the end byte"
    );
    // A full block then an empty one at the end: the same bytes as the full block alone, which
    // is how encoding ends; refused so that decoding accepts only what encoding writes.
    let mut long = parse_hex("FF").unwrap();
    long.extend(std::iter::repeat(0x11).take(254));
    long.extend([0x01, 0x00]);
    let e = interp::decode(&p, None, None, &long).unwrap_err();
    assert_eq!(
        e.to_string(),
        "bad escape at offset 255: COBS block 0x01 after a full block ends the frame"
    );
}

#[test]
fn stuffing_is_checked_and_counted_on_the_stuffed_bytes() {
    let p = fixture("dynamixel2_stuffed");
    let good = "FF FF FD 00 01 0A 00 03 74 00 FF FF FD FD 00 21 E7";
    assert_eq!(refusal(&p, good), "decoded as write4");
    assert_eq!(
        refusal(&p, "FF FF FD 00 01 0A 00 03 74 00 FF FF FD 41 00 21 E7"),
        "bad escape at offset 13: expected inserted byte 0xFD, found 0x41"
    );
    // The CRC covers the stuffed packet: its error names the stuffed frame's offset and values.
    assert_eq!(
        refusal(&p, "FF FF FD 00 01 0A 00 03 74 00 FF FF FD FD 00 21 E8"),
        "checksum mismatch at offset 15: expected 0xE721, found 0xE821"
    );
    // A length field one short, resealed: the length counts the stuffed bytes (10).
    let mut wire = parse_hex("FF FF FD 00 01 09 00 03 74 00 FF FF FD FD 00 00 00").unwrap();
    let n = wire.len();
    let crc = busspec_model::checksum::compute(&p.framing.checksum.algorithm, &wire[..n - 2]);
    wire[n - 2] = crc as u8;
    wire[n - 1] = (crc >> 8) as u8;
    assert_eq!(
        interp::decode(&p, None, None, &wire)
            .unwrap_err()
            .to_string(),
        "length field at offset 5 says 9, the frame's length gives 10"
    );
    // The e-manual's PING and its status packet (no stuffing in them).
    assert_eq!(
        refusal(&p, "FF FF FD 00 01 03 00 01 19 4E"),
        "decoded as ping"
    );
    assert_eq!(
        refusal(&p, "FF FF FD 00 01 07 00 55 00 06 04 26 65 5D"),
        "decoded as ping_status"
    );
    // A value whose bytes end in the pattern is stuffed after it, before the CRC.
    let r = p.find("write4").unwrap();
    let vals = [
        Value {
            name: "address".into(),
            raw: Raw::Int(0xFDFF),
        },
        Value {
            name: "value".into(),
            raw: Raw::Int(0xFDFF_FF00u32 as i64),
        },
    ];
    let wire = interp::encode(&p, r, 1, &vals).unwrap();
    // The pattern ends the parameters: FD is inserted before the CRC, and the length (10)
    // counts it.
    assert_eq!(
        wire[..15],
        parse_hex("FF FF FD 00 01 0A 00 03 FF FD 00 FF FF FD FD").unwrap()[..]
    );
    assert_eq!(wire.len(), 17);
    assert_eq!(interp::decode(&p, None, None, &wire).unwrap().message, r);
}

/// A byte, drawn often from the bytes escaping treats specially.
fn byte(rng: &mut common::Rng, special: &[u8]) -> u8 {
    let v = rng.next();
    if v % 3 == 0 && !special.is_empty() {
        special[(v >> 8) as usize % special.len()]
    } else {
        (v >> 16) as u8
    }
}

/// On random frames: unescaping what escaping wrote gives the frame back, and whatever random
/// bytes unescape, escaping them again gives the same bytes (one way to write each frame).
/// Decoding random bytes never panics.
#[test]
fn escaping_is_one_to_one_on_random_bytes() {
    let mut rng = common::Rng(0x9E37_79B9_7F4A_7C15);
    for name in ESCAPED {
        let p = fixture(name);
        let f = &p.framing;
        let special: Vec<u8> = vec![
            0x00, 0xC0, 0xDB, 0xDC, 0xDD, 0x7E, 0x7D, 0x5E, 0x5D, 0xFF, 0xFD, 0x10, 0x03,
        ];
        let (mut round, mut accepted) = (0, 0);
        for _ in 0..20_000 {
            let len = rng.below(300);
            let mut bytes: Vec<u8> = (0..len).map(|_| byte(&mut rng, &special)).collect();
            // Keep the fixed bytes around the escaped ones, so most frames reach the escaping.
            let start = f.sync.clone();
            if bytes.len() > start.len() + f.end.len() {
                bytes[..start.len()].copy_from_slice(&start);
                let n = bytes.len();
                bytes[n - f.end.len()..].copy_from_slice(&f.end);
            }
            let wire = escape_bytes(f, &bytes);
            if wire.len() != bytes.len() || f.escaped_region(bytes.len()).is_some() {
                assert_eq!(
                    unescape_bytes(f, &wire).as_deref(),
                    Ok(&bytes[..]),
                    "{name}"
                );
                round += 1;
            }
            if let Ok(plain) = unescape_bytes(f, &bytes) {
                assert_eq!(escape_bytes(f, &plain), bytes, "{name}");
                accepted += 1;
            }
            let _ = interp::decode(&p, None, None, &bytes);
            let _ = interp::decode(&p, Some(Direction::Response), None, &wire);
        }
        assert!(
            round > 10_000 && accepted > 50,
            "{name}: {round} {accepted}"
        );
    }
}

/// A stream of escaped frames with noise between them frames exactly (the escaped fixtures'
/// examples), and every cut into two chunks gives the same events.
#[test]
fn streams_of_escaped_frames() {
    for name in ESCAPED {
        let p = fixture(name);
        // Noise, then the first example damaged (a byte flipped before its checksum), then
        // every example.
        let mut capture = vec![0x33, 0x44];
        // The byte before the end bytes (DLE stuffing ends in two).
        let mut damaged = p.examples[0].wire.clone();
        let mid = damaged.len() - p.framing.end.len().max(1) - 1;
        damaged[mid] ^= 0x01;
        capture.extend_from_slice(&damaged);
        let mut at = Vec::new();
        if p.framing.checksum.is_empty() && interp::decode(&p, None, None, &damaged).is_ok() {
            // No checksum (KISS): the damaged frame is still a frame (TSIP's is not: its
            // code changed).
            at.push(2);
        }
        for e in &p.examples {
            at.push(capture.len() as u64);
            capture.extend_from_slice(&e.wire);
        }
        let run = |chunks: &[&[u8]]| {
            let mut d = StreamDecoder::new(&p, None);
            let mut events = Vec::new();
            for c in chunks {
                events.extend(d.push(c));
            }
            events.extend(d.flush());
            events
                .into_iter()
                .map(|e| match e {
                    Event::Frame { offset, frame, .. } => {
                        (offset, p.message(frame.message).name.clone())
                    }
                    Event::Ambiguous { offset, .. } => (offset, "ambiguous".to_owned()),
                    Event::Skipped { offset, bytes } => {
                        (offset, format!("skipped {}", bytes.len()))
                    }
                    Event::OutOfSpec { offset, reason, .. } => {
                        (offset, format!("out of spec: {reason}"))
                    }
                })
                .collect::<Vec<_>>()
        };
        let whole = run(&[&capture]);
        let frames: Vec<u64> = whole
            .iter()
            .filter(|(_, what)| !what.starts_with("skipped"))
            .map(|(o, _)| *o)
            .collect();
        assert_eq!(frames, at, "{name}: {whole:?}");
        for cut in 0..capture.len() {
            let (a, b) = capture.split_at(cut);
            assert_eq!(run(&[a, b]), whole, "{name}: cut at {cut}");
        }
    }
}

/// HDLC's flag both opens and closes a frame, and a sender may share one flag between two
/// frames (ISO/IEC 13239, RFC 1662 4.3). A stream of the examples with every flag shared, then
/// with doubled flags and a damaged frame between them, finds every frame (each sharing its
/// opening flag with the frame before, so the events overlap by that byte), reports no shared
/// or doubled flag as noise, and decides the same however the capture is cut.
#[test]
fn shared_flags_open_the_next_frame() {
    let p = fixture("hdlc_like");
    assert_eq!(p.framing.shared_flag(), Some(0x7E));
    for other in [
        "slip_sensor",
        "cobs_link",
        "dynamixel2_stuffed",
        "xbee_api2",
    ] {
        assert_eq!(fixture(other).framing.shared_flag(), None, "{other}");
    }
    let run = |capture: &[u8], chunks: &[&[u8]]| {
        let mut d = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in chunks {
            events.extend(d.push(c));
        }
        events.extend(d.flush());
        let seen: Vec<(u64, String)> = events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                Event::Skipped { offset, bytes } => (*offset, format!("skipped {bytes:02X?}")),
                other => (other.offset(), format!("{other:?}")),
            })
            .collect();
        let whole: Vec<u8> = chunks.concat();
        assert_eq!(whole, capture);
        seen
    };
    // Every flag shared: each frame after the first starts at the flag that closed the one
    // before.
    let mut shared = Vec::new();
    let mut want = Vec::new();
    for e in &p.examples {
        let from = usize::from(!shared.is_empty());
        want.push((
            (shared.len() - from) as u64,
            p.message(e.message).name.clone(),
        ));
        shared.extend_from_slice(&e.wire[from..]);
    }
    let got = run(&shared, &[&shared]);
    assert_eq!(got, want);
    for cut in 0..shared.len() {
        let (a, b) = shared.split_at(cut);
        assert_eq!(run(&shared, &[a, b]), want, "cut at {cut}");
    }
    // Doubled flags (an empty frame, idle fill) and a damaged frame: a frame's closing flag
    // that opens none is silent (its frame reported it), a second flag is noise, and the
    // damaged frame's closing flag opens the next.
    let status = &p.examples[1].wire;
    let mut damaged = status.clone();
    damaged[2] ^= 0x01;
    let mut capture = status.clone();
    capture.push(0x7E);
    capture.extend_from_slice(status);
    capture.extend_from_slice(&damaged[1..]);
    capture.extend_from_slice(&status[1..]);
    let n = status.len() as u64;
    let got = run(&capture, &[&capture]);
    assert_eq!(
        got,
        vec![
            (0, "status".to_owned()),
            (n, "skipped [7E]".to_owned()),
            (n + 1, "status".to_owned()),
            (
                2 * n + 1,
                "skipped [01, 91, 7D, 5E, 7D, 5D, AA, AB]".to_owned()
            ),
            (3 * n - 1, "status".to_owned()),
        ],
        "{capture:02X?}"
    );
    for cut in 0..capture.len() {
        let (a, b) = capture.split_at(cut);
        assert_eq!(run(&capture, &[a, b]), got, "cut at {cut}");
    }
}

/// F.Port's uplink data frames, as the `fport` fixture's comment gives them (computed: no
/// independent source quotes one byte for byte): 08 81 PRIM APPID DATA CRC without the 7E
/// flags, stuffed throughout. Each unstuffs to a frame whose length counts the type and the
/// payload and whose CRC is the one the fixture's checksum (`sum8_end_around`, from the length)
/// computes; and no 7E travels in one. Fixture `fport`'s own examples are the receiver's frames
/// alone, so its comment is checked here (fixture `fport_both` has these frames as examples).
#[test]
fn fport_uplink_frames_in_the_comment_check() {
    let p = fixture("fport");
    let text = std::fs::read_to_string(format!(
        "{}/tests/fixtures/valid/fport.yaml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let uplink = [
        "08 81 00 00 00 00 00 00 00 76",
        "08 81 10 10 01 7D 5E 00 00 00 D6",
        "08 81 32 7D 5D 0D 78 56 34 12 A4",
    ];
    for hex in uplink {
        assert!(
            text.contains(&format!("\"{hex}\"")),
            "{hex} not in the comment"
        );
        let wire = parse_hex(hex).unwrap();
        assert!(!wire.contains(&0x7E), "{hex}");
        let mut plain = Vec::new();
        let mut bytes = wire.iter();
        while let Some(&b) = bytes.next() {
            plain.push(if b == 0x7D {
                bytes.next().unwrap() ^ 0x20
            } else {
                b
            });
        }
        assert_eq!(plain.len(), 10, "{hex}");
        assert_eq!(plain[0] as usize, plain.len() - 2, "{hex}");
        assert_eq!(plain[1], 0x81, "{hex}");
        let crc = p.framing.checksum.compute(&plain[..plain.len() - 1]);
        assert_eq!(crc, u64::from(plain[plain.len() - 1]), "{hex}");
    }
}

/// F.Port's uplink alone (fixture `fport_uplink`): frames escaped from their first byte, with
/// neither start nor end bytes, found by the length field as the bytes unstuff. A stream with
/// ArduPilot's FF pad byte before some frames (`fport_pad`) reports each pad as noise and every
/// frame, however the capture is cut; a frame whose CRC is wrong is no frame.
#[test]
fn fport_uplink_stream_skips_the_pad_byte() {
    let p = fixture("fport_uplink");
    let wire: Vec<&[u8]> = p.examples.iter().map(|e| e.wire.as_slice()).collect();
    let mut capture = vec![0xFF];
    capture.extend_from_slice(wire[0]);
    capture.extend_from_slice(wire[1]);
    capture.push(0xFF);
    capture.extend_from_slice(wire[2]);
    let run = |chunks: &[&[u8]]| {
        let mut d = StreamDecoder::new(&p, None);
        let mut events = Vec::new();
        for c in chunks {
            events.extend(d.push(c));
        }
        events.extend(d.flush());
        events
            .iter()
            .map(|e| match e {
                Event::Frame { offset, frame, .. } => {
                    (*offset, p.message(frame.message).name.clone())
                }
                Event::Skipped { offset, bytes } => (*offset, format!("skipped {bytes:02X?}")),
                other => (other.offset(), format!("{other:?}")),
            })
            .collect::<Vec<_>>()
    };
    let got = run(&[&capture]);
    let second = 1 + wire[0].len() as u64;
    let pad = second + wire[1].len() as u64;
    assert_eq!(
        got,
        [
            (0, "skipped [FF]".to_string()),
            (1, "uplink_data".to_string()),
            (second, "uplink_data".to_string()),
            (pad, "skipped [FF]".to_string()),
            (pad + 1, "uplink_data".to_string()),
        ],
        "{capture:02X?}"
    );
    for cut in 0..capture.len() {
        let (a, b) = capture.split_at(cut);
        assert_eq!(run(&[a, b]), got, "cut at {cut}");
    }
    let mut bad = wire[0].to_vec();
    *bad.last_mut().unwrap() ^= 1;
    assert_eq!(
        refusal(&p, "08 81 00 00 00 00 00 00 00 77"),
        "checksum mismatch at offset 9: expected 0x76, found 0x77"
    );
    assert!(run(&[&bad]).iter().all(|(_, e)| e != "uplink_data"));
}

/// FrSky F.Port v1 (fixture `fport`): its CRC is the end-around sum (`sum8_end_around`) of the
/// unstuffed length through payload. ArduPilot's control frame decodes with its CRC FA; the
/// same frame with the plain sum inverted (04, what `sum8_ones_complement` gives) is refused
/// at the CRC; a CRC of 7D travels stuffed; and frames sharing their 7E flag all decode from
/// one stream.
#[test]
fn fport_frames_check_their_end_around_sum() {
    let p = fixture("fport");
    assert_eq!(p.framing.shared_flag(), Some(0x7E));
    assert_eq!(p.framing.checksum.algorithm.name(), "sum8_end_around");
    let ardupilot = parse_hex(
        "7E 19 00 E7 3B DF 5A CE 07 10 75 49 9C 15 E0 03 1F F8 C0 07 3E F0 81 0F 7C 00 38 FA 7E",
    )
    .unwrap();
    let f = interp::decode(&p, None, None, &ardupilot).unwrap();
    assert_eq!(p.message(f.message).name, "control");
    let mut plain = ardupilot.clone();
    plain[27] = 0x04;
    assert_eq!(
        interp::decode(&p, None, None, &plain)
            .unwrap_err()
            .to_string(),
        "checksum mismatch at offset 27: expected 0xFA, found 0x04"
    );
    // The CRC 7D of the derived failsafe frame travels as 7D 5D, before the closing flag.
    let failsafe = &p.examples[2].wire;
    assert_eq!(failsafe[failsafe.len() - 3..], [0x7D, 0x5D, 0x7E]);
    let plain_frame = unescape_bytes(&p.framing, failsafe).unwrap();
    assert_eq!(plain_frame[plain_frame.len() - 2], 0x7D);
    // Control frame, poll, control frame: each sharing the flag before it.
    let poll = &p.examples[1].wire;
    let mut capture = ardupilot.clone();
    capture.extend_from_slice(&poll[1..]);
    capture.extend_from_slice(&failsafe[1..]);
    let mut d = StreamDecoder::new(&p, None);
    let mut events = d.push(&capture);
    events.extend(d.flush());
    let seen: Vec<(u64, String)> = events
        .iter()
        .map(|e| match e {
            Event::Frame { offset, frame, .. } => (*offset, p.message(frame.message).name.clone()),
            other => (other.offset(), format!("{other:?}")),
        })
        .collect();
    assert_eq!(
        seen,
        [
            (0, "control".to_owned()),
            (28, "downlink_data".to_owned()),
            (39, "control".to_owned()),
        ]
    );
}

/// The end bytes and the escaped region are each direction's own in the IR
/// (`Framing::end_of`, `escaped_region_of`): a downlink frame of F.Port is escaped between its
/// flags, an uplink frame (no start or end byte in its direction's layout) from its first
/// byte to its last, and each engine's escaping by direction stuffs and unstuffs it so. The IR
/// is made by hand from fixture `fport`, and is what the validator makes of `fport_both`.
#[test]
fn end_bytes_and_escaped_region_are_each_directions() {
    use busspec_model::ir::Part;
    let mut p = fixture("fport");
    let f = &p.framing;
    assert_eq!(f.end_of(Direction::Request), f.end_of(Direction::Response));
    assert!(!f.end_by_direction());
    assert_eq!(f.escaped_region_of(Direction::Response, 12), Some((1, 11)));
    let f = &mut p.framing;
    f.response_layout = vec![Part::Length, Part::Code, Part::Payload, Part::Checksum];
    f.response_sync = Vec::new();
    f.response_end = Vec::new();
    assert!(f.end_by_direction());
    assert_eq!(f.end_of(Direction::Request), &[0x7E]);
    assert_eq!(f.end_of(Direction::Response), &[] as &[u8]);
    assert_eq!(f.escaped_region_of(Direction::Request, 12), Some((1, 11)));
    assert_eq!(f.escaped_region(12), Some((1, 11)));
    assert_eq!(f.escaped_region_of(Direction::Response, 10), Some((0, 10)));
    assert_eq!(
        (
            f.trailer_len_of(Direction::Request),
            f.trailer_len_of(Direction::Response)
        ),
        (2, 1)
    );
    assert_eq!(
        (
            f.checksum_at_of(Direction::Request, 12),
            f.checksum_at_of(Direction::Response, 10)
        ),
        (10, 9)
    );
    assert_eq!(
        (
            f.end_at_of(Direction::Request, 12),
            f.end_at_of(Direction::Response, 10)
        ),
        (11, 10)
    );
    // "08 81 10 10 01 7D 5E 00 00 00 D6" of the comment: the uplink stuffed from its first byte.
    let plain = parse_hex("08 81 10 10 01 7E 00 00 00 D6").unwrap();
    let wire = busspec_model::escape::escape_bytes_of(f, Direction::Response, &plain);
    assert_eq!(wire, parse_hex("08 81 10 10 01 7D 5E 00 00 00 D6").unwrap());
    let back = busspec_model::escape::unescape_bytes_of(f, Direction::Response, &wire).unwrap();
    assert_eq!(back, plain);
    // A 7E leading an uplink frame is stuffed too, where a request's first byte is its flag.
    let lead = parse_hex("7E 81").unwrap();
    assert_eq!(
        busspec_model::escape::escape_bytes_of(f, Direction::Response, &lead),
        parse_hex("7D 5E 81").unwrap()
    );
    assert_eq!(
        busspec_model::escape::escape_bytes_of(
            f,
            Direction::Request,
            &parse_hex("7E 7E 7E").unwrap()
        ),
        parse_hex("7E 7D 5E 7E").unwrap()
    );
    let both = fixture("fport_both");
    let g = &both.framing;
    assert_eq!(
        (&g.response_layout, &g.response_sync, &g.response_end),
        (&f.response_layout, &f.response_sync, &f.response_end)
    );
    assert_eq!((&g.sync, &g.end), (&f.sync, &f.end));
    assert_eq!(g.shared_flag(), Some(0x7E));
}
