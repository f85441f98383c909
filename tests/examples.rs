//! Every example frame of both specs replays through the interpreter: it decodes on its own to
//! the message it shows (with its request where only that can tell), and re-encodes from the
//! decoded values to exactly the same wire bytes.

use busspec_model::interp::{self, Raw};
use busspec_model::ir::{Direction, StatedValue};
use busspec_model::{load_file, Protocol};

fn spec(name: &str) -> Protocol {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("spec")
        .join(name);
    load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn replay(p: &Protocol) -> usize {
    assert!(!p.examples.is_empty(), "{} has no examples", p.name);
    for (i, e) in p.examples.iter().enumerate() {
        let m = p.message(e.message);
        let frame = interp::decode(p, Some(e.message.direction), e.reply_to, &e.wire)
            .unwrap_or_else(|err| panic!("{} example {i} (§{}): {err}", p.name, e.section));
        assert_eq!(
            frame.message, e.message,
            "{} example {i} decoded as another message",
            p.name
        );
        // Every stated value is among the decoded ones (validation compares the numbers).
        for (name, _) in &e.values {
            assert!(
                frame.get(name).is_some(),
                "example {i}: no decoded value for {name}"
            );
        }
        let again =
            interp::encode(p, e.message, frame.address, &frame.values).unwrap_or_else(|err| {
                panic!("{} example {i} (§{}) re-encode: {err}", p.name, e.section)
            });
        assert_eq!(
            again, e.wire,
            "{} example {i} (§{} {}) re-encodes differently",
            p.name, e.section, m.name
        );
    }
    p.examples.len()
}

#[test]
fn every_ub2_example_replays() {
    let p = spec("ub2.yaml");
    assert!(
        replay(&p) >= 80,
        "the UB2 document prints about 80 frames or more"
    );
}

#[test]
fn every_sd_example_replays() {
    let p = spec("sd.yaml");
    replay(&p);
}

#[test]
fn sd_examples_cover_every_command_and_response() {
    let p = spec("sd.yaml");
    for d in [Direction::Request, Direction::Response] {
        for (index, m) in p.messages(d).iter().enumerate() {
            assert!(
                p.examples
                    .iter()
                    .any(|e| e.message.direction == d && e.message.index == index),
                "no example for sd {} `{}`",
                d.as_str(),
                m.name
            );
        }
    }
    assert!(
        p.examples
            .iter()
            .all(|e| e.printed.is_none() && e.derived.is_some()),
        "the SD document prints no frames: every example is derived"
    );
}

#[test]
fn sd_examples_include_the_documented_angles() {
    let p = spec("sd.yaml");
    for want in ["45", "0", "-45", "-180"] {
        let want = busspec_model::rational::Rational::parse(want).unwrap();
        let found = p.examples.iter().any(|e| {
            e.values
                .iter()
                .any(|(k, v)| k == "position" && *v == StatedValue::Number(want))
        });
        assert!(found, "no SD set-point example at {want}°");
    }
}

/// The byte order is declared once; flipping it changes the wire bytes of every multi-byte
/// example and nothing else, and the flipped spec still validates (the additive checksum cannot
/// tell the two apart — which is why the document's examples could not settle the question).
#[test]
fn flipping_ub2_byte_order_is_one_line() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("spec/ub2.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("byte_order:"))
        .expect("a byte_order line");
    assert!(
        line.starts_with("byte_order: little"),
        "ub2 travels little-endian (§3)"
    );
    let flipped = text.replacen("byte_order: little", "byte_order: big", 1);
    let little = busspec_model::load_str("ub2.yaml", &text).unwrap();
    let big =
        busspec_model::load_str("ub2-flipped.yaml", &flipped).unwrap_or_else(|d| panic!("{d}"));
    let mut changed = 0;
    for (a, b) in little.examples.iter().zip(&big.examples) {
        let m = little.message(a.message);
        let multi = m.fields.iter().any(|f| f.width > 1 && !f.is_ascii());
        assert_eq!(a.wire != b.wire, multi, "§{} {}", a.section, m.name);
        changed += usize::from(multi);
        // Printed big-endian, so the flipped spec's wire bytes are the printed bytes.
        if let (Some(printed), None) = (&b.printed, &b.corrected) {
            assert_eq!(b.wire, interp::parse_hex(printed).unwrap());
        }
    }
    assert!(changed > 10, "many UB2 examples carry multi-byte numbers");
    // 150 pF, printed `0000 3A98`, goes out as 98 3A 00 00.
    let e = little
        .examples
        .iter()
        .find(|e| little.message(e.message).name == "go_to_capacitance")
        .unwrap();
    assert_eq!(
        e.wire,
        [0xAA, 0x21, 0x20, 0x00, 0x98, 0x3A, 0x00, 0x00, 0xBD]
    );
}

#[test]
fn decode_reports_what_and_where() {
    let p = spec("ub2.yaml");
    let err = |bytes: &[u8]| {
        interp::decode(&p, None, None, bytes)
            .unwrap_err()
            .to_string()
    };
    // §6.1 reply with its checksum off by one.
    let bad = interp::parse_hex("AA21 4101 3E1F 0000 6B").unwrap();
    assert_eq!(
        err(&bad),
        "checksum mismatch at offset 8: expected 0x6A, found 0x6B"
    );
    assert_eq!(
        err(&[0x55, 0x21, 0x50, 0x76]),
        "bad start byte at offset 0: expected 0xAA, found 0x55"
    );
    assert!(err(&[0xAA, 0x21]).starts_with("truncated frame"));
    let mut unknown = vec![0xAA, 0x21, 0x77, 0x77, 0x00];
    unknown[4] = unknown[..4].iter().fold(0u8, |s, b| s.wrapping_add(*b));
    assert_eq!(err(&unknown), "unknown command code 0x7777 at offset 2");

    // SD 0x22 carries hours or minutes+seconds, told apart only by the request.
    let sd = spec("sd.yaml");
    let hours = sd.find("total_runtime_hours").unwrap();
    let bytes = interp::encode(
        &sd,
        hours,
        1,
        &[interp::Value {
            name: "runtime_hours".into(),
            raw: Raw::Int(7),
        }],
    )
    .unwrap();
    let e = interp::decode(&sd, Some(Direction::Response), None, &bytes)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("ambiguous frame: could be total_runtime_hours or total_runtime_min_sec"),
        "{e}"
    );
    let request = sd
        .commands
        .iter()
        .position(|c| c.name == "read_total_runtime_hours")
        .expect("the hours readout");
    let frame = interp::decode(&sd, Some(Direction::Response), Some(request), &bytes).unwrap();
    assert_eq!(frame.message, hours);
    assert_eq!(frame.get("runtime_hours"), Some(&Raw::Int(7)));
}
