//! The variable-length language through the interpreter, its stream decoder and diff:
//! `fixtures/valid/minimal_variable.yaml` (sync sequence, length field, XOR-8 over all but the
//! sync bytes, repeats, values following a field or the request, a code from the request, a
//! 24-bit integer) and the two public protocols, `spec/modbus.yaml` and `spec/dynamixel.yaml`.

use std::path::Path;

use busspec_model::diff::{self, Category};
use busspec_model::interp::{self, DecodeError, EncodeError, Frame, Raw, Value};
use busspec_model::ir::{Count, Direction, MessageRef};
use busspec_model::stream::{Event, StreamDecoder};
use busspec_model::{load_file, load_str, Protocol};

fn load(rel: &str) -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    load_file(&path).unwrap_or_else(|d| panic!("{d}"))
}

fn vario() -> Protocol {
    load("tests/fixtures/valid/minimal_variable.yaml")
}

fn modbus() -> Protocol {
    load("../spec/modbus.yaml")
}

fn dynamixel() -> Protocol {
    load("../spec/dynamixel.yaml")
}

fn hex(s: &str) -> Vec<u8> {
    interp::parse_hex(s).unwrap()
}

fn cmd(p: &Protocol, name: &str) -> MessageRef {
    p.find_in(name, Direction::Request).unwrap()
}

fn rsp(p: &Protocol, name: &str) -> MessageRef {
    p.find_in(name, Direction::Response).unwrap()
}

fn v(name: &str, raw: Raw) -> Value<'_> {
    Value {
        name: name.into(),
        raw,
    }
}

fn request<'p>(p: &'p Protocol, wire: &[u8]) -> Frame<'p> {
    interp::decode(p, Some(Direction::Request), None, wire).unwrap()
}

#[test]
fn the_fixture_resolves_every_new_construct() {
    let p = vario();
    let f = &p.framing;
    assert_eq!(f.sync, [0xA5, 0x5A]);
    assert_eq!(
        f.checksum.covers_from, 2,
        "the XOR skips the two sync bytes"
    );
    let write = p.message(cmd(&p, "write"));
    let (values, r) = write.repeat().unwrap();
    assert_eq!(values.name, "values");
    assert_eq!(r.count, Count::Bytes(1));
    assert_eq!((r.min, r.max), (1, 16));
    assert_eq!((write.layout.len, write.max_len), (8, 40));
    assert_eq!(write.layout.length, Some(3));
    assert_eq!(
        p.message(rsp(&p, "read_error")).code_from_request,
        Some(0x80)
    );
}

#[test]
fn encode_fills_length_count_and_checksum_and_decode_reads_them_back() {
    let p = vario();
    let w = cmd(&p, "write");
    let values = [
        v("quantity", Raw::Int(3)),
        v("values", Raw::List(vec![1, 0x0203, 0xFFFF])),
    ];
    let wire = interp::encode(&p, w, 2, &values).unwrap();
    assert_eq!(wire, hex("A5 5A 02 0A 02 03 06 00 01 02 03 FF FF 0F"));
    let frame = interp::decode(&p, None, None, &wire).unwrap();
    assert_eq!(frame.get("byte_count"), Some(&Raw::Int(6)));
    assert_eq!(
        frame.get("values"),
        Some(&Raw::List(vec![1, 0x0203, 0xFFFF]))
    );
    // A 24-bit integer, most significant byte first as the protocol's byte order says.
    let stamp = interp::encode(&p, cmd(&p, "stamp"), 4, &[v("ticks", Raw::Int(0xABCDEF))]).unwrap();
    assert_eq!(&stamp[5..8], &[0xAB, 0xCD, 0xEF]);
    assert_eq!(
        interp::decode(&p, None, None, &stamp).unwrap().get("ticks"),
        Some(&Raw::Int(0xABCDEF))
    );
}

#[test]
fn encode_refuses_lists_the_spec_does_not_allow() {
    let p = vario();
    let w = cmd(&p, "write");
    let too_many = [
        v("quantity", Raw::Int(17)),
        v("values", Raw::List(vec![0; 17])),
    ];
    assert_eq!(
        interp::encode(&p, w, 2, &too_many),
        Err(EncodeError::WrongCount {
            field: "values".into(),
            min: 1,
            max: 16,
            found: 17
        })
    );
    // The quantity says 2 registers, the list holds 1: the byte count follows the quantity,
    // so the frame would contradict itself.
    let mismatch = [v("quantity", Raw::Int(2)), v("values", Raw::List(vec![7]))];
    assert!(matches!(
        interp::encode(&p, w, 2, &mismatch),
        Err(EncodeError::Inconsistent { .. })
    ));
    assert_eq!(
        interp::encode(
            &p,
            w,
            2,
            &[v("quantity", Raw::Int(1)), v("values", Raw::Int(7))]
        ),
        Err(EncodeError::NotList {
            field: "values".into()
        })
    );
}

#[test]
fn a_lying_length_field_or_count_is_refused_with_its_offset() {
    let p = vario();
    // The read example with its length byte raised from 5 to 6 (checksum fixed up).
    assert_eq!(
        interp::decode(&p, None, None, &hex("A5 5A 01 06 01 00 10 02 14")),
        Err(DecodeError::LengthMismatch {
            offset: 3,
            expected: 5,
            found: 6
        })
    );
    // A write whose byte count says 4 but carries 2 bytes.
    let e = interp::decode(&p, None, None, &hex("A5 5A 03 06 02 01 04 12 34 24")).unwrap_err();
    assert!(
        e.to_string().contains("write.byte_count at offset 6"),
        "{e}"
    );
    // The checksum covers from the address: a changed sync byte is a bad start, not a checksum error.
    assert_eq!(
        interp::decode(&p, None, None, &hex("A5 5B 01 05 01 00 10 02 17")),
        Err(DecodeError::BadStart {
            offset: 1,
            expected: 0x5A,
            found: 0x5B
        })
    );
}

#[test]
fn a_reply_is_checked_against_its_request() {
    let p = vario();
    let read = request(&p, &hex("A5 5A 01 05 01 00 10 02 17")); // quantity 2
    let two = hex("A5 5A 01 06 01 00 07 01 00 00");
    assert_eq!(
        interp::decode_reply(&p, &read, &two).unwrap().get("values"),
        Some(&Raw::List(vec![7, 256]))
    );
    // Three values to a request for two: decodes alone, refused as its reply.
    let three = interp::encode(
        &p,
        rsp(&p, "read_reply"),
        1,
        &[v("values", Raw::List(vec![1, 2, 3]))],
    )
    .unwrap();
    assert!(interp::decode(&p, Some(Direction::Response), None, &three).is_ok());
    let e = interp::decode_reply(&p, &read, &three).unwrap_err();
    assert!(
        matches!(&e, DecodeError::BadCount { field, found: 3, .. } if field == "values"),
        "{e}"
    );
    // A reply the request does not get.
    let ack = interp::encode(&p, rsp(&p, "write_reply"), 1, &[v("status", Raw::Int(0))]).unwrap();
    assert_eq!(
        interp::decode_reply(&p, &read, &ack),
        Err(DecodeError::NotAnAnswer {
            message: "write_reply".into(),
            request: "read".into(),
            unasked: false
        })
    );
}

#[test]
fn modbus_byte_count_must_be_twice_the_quantity_asked_for() {
    let p = modbus();
    let read = request(&p, &hex("11 03 00 6B 00 03 76 87")); // three registers
    let reply = hex("11 03 06 02 2B 00 00 00 64 C8 BA");
    assert!(interp::decode_reply(&p, &read, &reply).is_ok());
    let read_two = interp::encode(
        &p,
        cmd(&p, "read_holding_registers"),
        0x11,
        &[
            v("starting_address", Raw::Int(0x6B)),
            v("quantity", Raw::Int(2)),
        ],
    )
    .unwrap();
    let e = interp::decode_reply(&p, &request(&p, &read_two), &reply).unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid value for read_holding_registers_reply.byte_count at offset 2: must be 2 × quantity of the request (4), found 6"
    );
    // The exception reply's code is the request's with the top bit set; another exception is
    // not an answer to it.
    let exc = hex("11 81 02 C0 54");
    let read_coils = request(&p, &hex("11 01 04 A1 00 01 AF 88"));
    assert!(interp::decode_reply(&p, &read_coils, &exc).is_ok());
    assert!(matches!(
        interp::decode_reply(&p, &read, &exc),
        Err(DecodeError::NotAnAnswer { .. })
    ));
    // Coils: three bytes for 19 coils; the last five bits are padding.
    let one = interp::encode(
        &p,
        rsp(&p, "read_coils_reply"),
        0x11,
        &[
            v("byte_count", Raw::Int(1)),
            v("coils", Raw::List(vec![1, 0, 0, 0, 0, 0, 0, 0])),
        ],
    )
    .unwrap();
    assert_eq!(one[..4], hex("11 01 01 01"));
    let coils = interp::decode_reply(&p, &read_coils, &one).unwrap();
    assert_eq!(
        coils.get("coils"),
        Some(&Raw::List(vec![1, 0, 0, 0, 0, 0, 0, 0]))
    );
}

/// Every example of `p` that decodes without its request, in spec order, with noise between.
fn capture(p: &Protocol) -> (Vec<u8>, Vec<Vec<u8>>) {
    let mut bytes = vec![0x00, 0x13];
    let mut frames = Vec::new();
    for e in &p.examples {
        if interp::decode(p, Some(e.message.direction), None, &e.wire).is_ok() {
            bytes.extend_from_slice(&e.wire);
            bytes.push(0x00);
            frames.push(e.wire.clone());
        }
    }
    (bytes, frames)
}

fn stream_frames(p: &Protocol, d: Option<Direction>, bytes: &[u8], chunk: usize) -> Vec<Vec<u8>> {
    let mut s = StreamDecoder::new(p, d);
    let mut events = Vec::new();
    for c in bytes.chunks(chunk) {
        events.extend(s.push(c));
    }
    events.extend(s.flush());
    events
        .into_iter()
        .filter_map(|e| match e {
            Event::Frame { bytes, .. } | Event::Ambiguous { bytes, .. } => Some(bytes),
            _ => None,
        })
        .collect()
}

#[test]
fn the_stream_frames_by_length_and_count_fields_in_chunks_of_any_size() {
    for (p, d) in [
        (vario(), None),
        (modbus(), Some(Direction::Request)),
        (modbus(), Some(Direction::Response)),
        (dynamixel(), Some(Direction::Request)),
        (dynamixel(), Some(Direction::Response)),
    ] {
        let examples: Vec<_> = p
            .examples
            .iter()
            .filter(|e| d.map_or(true, |d| e.message.direction == d))
            .cloned()
            .collect();
        let mut q = p.clone();
        q.examples = examples;
        let (bytes, frames) = capture(&q);
        assert!(!frames.is_empty(), "{}", p.name);
        for chunk in [1, 3, 7, bytes.len()] {
            assert_eq!(
                stream_frames(&p, d, &bytes, chunk),
                frames,
                "{} {d:?} in chunks of {chunk}",
                p.name
            );
        }
    }
}

#[test]
fn the_stream_resynchronises_after_a_length_field_that_lies() {
    let p = vario();
    let good = hex("A5 5A 01 05 01 00 10 02 17");
    // A frame whose length byte says 0x28 (40): longer than any frame; and one that says 7
    // (the next frame's first bytes would complete it, but the checksum fails).
    let mut bytes = hex("A5 5A 01 28 01 00 10 02 17");
    bytes.extend(hex("A5 5A 01 07 01 00 10 02 17"));
    bytes.extend(&good);
    bytes.extend(&good);
    assert_eq!(
        stream_frames(&p, None, &bytes, 1),
        [good.clone(), good.clone()]
    );
    assert_eq!(
        stream_frames(&p, None, &bytes, bytes.len()),
        [good.clone(), good]
    );
}

#[test]
fn dynamixel_status_packets_are_told_apart_by_their_length_and_request() {
    let p = dynamixel();
    let status = interp::decode(
        &p,
        Some(Direction::Response),
        None,
        &hex("FF FF 01 02 24 D8"),
    )
    .unwrap();
    assert_eq!(p.message(status.message).name, "status");
    let read = request(&p, &hex("FF FF 01 04 02 2B 01 CC"));
    let data = interp::decode_reply(&p, &read, &hex("FF FF 01 03 00 20 DB")).unwrap();
    assert_eq!(data.get("data"), Some(&Raw::List(vec![0x20])));
    // Two bytes to a request for one.
    let two = interp::encode(
        &p,
        rsp(&p, "read_status"),
        1,
        &[v("error", Raw::Int(0)), v("data", Raw::List(vec![1, 2]))],
    )
    .unwrap();
    assert!(matches!(
        interp::decode_reply(&p, &read, &two),
        Err(DecodeError::BadCount { .. })
    ));
}

#[test]
fn diff_classifies_changes_to_the_new_constructs_as_wire_breaking() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/minimal_variable.yaml"),
    )
    .unwrap();
    let old = load_str("old.yaml", &text).unwrap();
    assert_eq!(diff::diff(&old, &old), []);
    let edits = [
        (
            "start: [0xA5, 0x5A]",
            "start: [0xA5, 0x5B]",
            "framing.start",
        ),
        (
            "length: {width: 1, counts: [code, payload, checksum]}",
            "length: {width: 1, counts: [code, payload, checksum], adjust: 1}",
            "framing.length",
        ),
        (
            "covers_from: address",
            "covers_from: start",
            "framing.checksum.covers_from",
        ),
        (
            "of: bytes, min: 1, max: 16}}",
            "of: bytes, min: 1, max: 12}}",
            "commands.write",
        ),
        (
            "follows: {field: quantity, multiply: 2}",
            "follows: {field: quantity, multiply: 4}",
            "commands.write.fields.byte_count",
        ),
        (
            "request: {field: quantity}",
            "request: {field: first}",
            "responses.read_reply.fields.values",
        ),
        (
            "    code_from_request: {or: 0x80}\n",
            "",
            "responses.read_error.code_from_request",
        ),
    ];
    for (from, to, path) in edits {
        // Examples whose frames the edit changes are dropped: diff compares specs, not frames.
        let mut edited = text.replacen(from, to, 1);
        if let Some(at) = edited.find("examples:") {
            edited.truncate(at);
            edited.push_str("examples: []\nerrata: []\n");
        }
        let new = load_str("new.yaml", &edited).unwrap_or_else(|d| panic!("{from}: {d}"));
        let mut base = text.clone();
        if let Some(at) = base.find("examples:") {
            base.truncate(at);
            base.push_str("examples: []\nerrata: []\n");
        }
        let old = load_str("old.yaml", &base).unwrap();
        let changes = diff::diff(&old, &new);
        assert!(
            changes
                .iter()
                .any(|c| c.category == Category::WireBreaking && c.path.starts_with(path)),
            "{from} -> {to}: {changes:#?}"
        );
    }
}

#[test]
fn an_element_out_of_its_range_is_refused_and_listed_by_lenient_decoding() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/minimal_variable.yaml"),
    )
    .unwrap()
    .replacen(
        "{name: values, type: u16, unit: count, repeat: {count: byte_count",
        "{name: values, type: u16, unit: count, range: {min: 0, max: 8192}, repeat: {count: byte_count",
        1,
    );
    let p = load_str("ranged.yaml", &text).unwrap_or_else(|d| panic!("{d}"));
    let relaxed = busspec_model::stream::relaxed(&p);
    let wire = interp::encode(
        &relaxed,
        cmd(&p, "write"),
        2,
        &[
            v("quantity", Raw::Int(2)),
            v("values", Raw::List(vec![7, 12288])),
        ],
    )
    .unwrap();
    let strict = interp::decode(&p, None, None, &wire).unwrap_err();
    assert!(
        matches!(&strict, DecodeError::OutOfRange { field, found: 12288, .. } if field == "values"),
        "{strict}"
    );
    let (frame, violations) =
        busspec_model::stream::decode_lenient(&p, &relaxed, None, None, &wire).unwrap();
    assert_eq!(frame.get("values"), Some(&Raw::List(vec![7, 12288])));
    assert_eq!(violations, [strict]);
}

fn lists_after() -> Protocol {
    load("tests/fixtures/valid/lists_after.yaml")
}

fn lists_length() -> Protocol {
    load("tests/fixtures/valid/lists_length.yaml")
}

/// `wire` with its XOR-8 (from the address on) recomputed: lists_after's frames.
fn xor_sealed(mut wire: Vec<u8>) -> Vec<u8> {
    let n = wire.len();
    wire[n - 1] = wire[1..n - 1].iter().fold(0, |a, b| a ^ b);
    wire
}

#[test]
fn fields_after_a_list_sit_where_its_elements_end() {
    let p = lists_after();
    let wire = hex("7E 03 11 02 1234 5678 0005 1D");
    let f = request(&p, &wire);
    assert_eq!(f.get("values"), Some(&Raw::List(vec![0x1234, 0x5678])));
    assert_eq!(f.get("flags"), Some(&Raw::Int(5)));
    // With one value the flags move two bytes closer.
    let one = xor_sealed(hex("7E 03 11 01 1234 0007 00"));
    let f = request(&p, &one);
    assert_eq!(f.get("values"), Some(&Raw::List(vec![0x1234])));
    assert_eq!(f.get("flags"), Some(&Raw::Int(7)));
    // The flags' range is checked where they sit, and said at that offset.
    let bad = xor_sealed(hex("7E 03 11 02 1234 5678 0100 00"));
    assert_eq!(
        interp::decode(&p, None, None, &bad)
            .unwrap_err()
            .to_string(),
        "write_block.flags at offset 8 is 256, outside its range 0..=255"
    );
    // Encode writes what decode reads.
    let encoded = interp::encode(
        &p,
        cmd(&p, "write_block"),
        3,
        &[
            v("values", Raw::List(vec![0x1234, 0x5678])),
            v("flags", Raw::Int(5)),
        ],
    )
    .unwrap();
    assert_eq!(encoded, wire);
}

#[test]
fn two_lists_each_take_their_own_count_even_after_the_first() {
    let p = lists_after();
    let wire = hex("7E 03 12 03 01 02 03 04 000A 03E8 01 F6");
    let f = request(&p, &wire);
    assert_eq!(f.get("sources"), Some(&Raw::List(vec![1, 2, 3])));
    assert_eq!(f.get("nb"), Some(&Raw::Int(4)));
    assert_eq!(f.get("targets"), Some(&Raw::List(vec![10, 1000])));
    assert_eq!(f.get("mode"), Some(&Raw::Int(1)));
    // No sources: nb moves to offset 4.
    let none = xor_sealed(hex("7E 03 12 00 02 0001 01 00"));
    let f = request(&p, &none);
    assert_eq!(f.get("sources"), Some(&Raw::List(vec![])));
    assert_eq!(f.get("targets"), Some(&Raw::List(vec![1])));
    let encoded = interp::encode(
        &p,
        cmd(&p, "copy"),
        3,
        &[
            v("sources", Raw::List(vec![])),
            v("targets", Raw::List(vec![1])),
        ],
    )
    .unwrap();
    assert_eq!(encoded, none);
    // Hostile counts, each refused at the offset of what disagrees.
    for (frame, said) in [
        // The first list claims more bytes than the frame has.
        (
            "7E 03 12 09 01 02 03 04 000A 03E8 01 00",
            "copy.sources at offset 4: 9 elements, expected at most 7 by the frame's length",
        ),
        // Too many for its bounds.
        (
            "7E 03 12 05 01 02 03 04 05 02 000A 01 00",
            "copy.sources at offset 4: 5 elements, expected 0..=4",
        ),
        // The second count (after the first list) disagrees with the frame's length.
        (
            "7E 03 12 03 01 02 03 06 000A 03E8 01 00",
            "invalid value for copy.nb at offset 7: must be the bytes of targets (4), found 6",
        ),
        // The constant after both lists.
        (
            "7E 03 12 03 01 02 03 04 000A 03E8 02 00",
            "invalid value for copy.mode at offset 12: expected 0x01, found 0x02",
        ),
        // A target out of its range, at its own offset after the sources.
        (
            "7E 03 12 01 05 04 000A 0000 01 00",
            "copy.targets at offset 8 is 0, outside its range 1..=1000",
        ),
    ] {
        let wire = xor_sealed(hex(frame));
        let e = interp::decode(&p, Some(Direction::Request), None, &wire).unwrap_err();
        assert_eq!(e.to_string(), said, "{frame}");
    }
    // Encode refuses a list outside its bounds by name.
    let e = interp::encode(
        &p,
        cmd(&p, "copy"),
        3,
        &[
            v("sources", Raw::List(vec![1, 2, 3, 4, 5])),
            v("targets", Raw::List(vec![1])),
        ],
    )
    .unwrap_err();
    assert!(e.to_string().contains("sources"), "{e}");
}

#[test]
fn a_list_to_the_end_leaves_the_fields_after_it_their_bytes() {
    let p = lists_after();
    let read = request(&p, &hex("7E 03 10 0100 02 10"));
    let reply = interp::decode_reply(&p, &read, &hex("7E 03 10 0007 0008 0201 1F")).unwrap();
    assert_eq!(reply.get("values"), Some(&Raw::List(vec![7, 8])));
    assert_eq!(reply.get("status"), Some(&Raw::Int(0x0201)));
    // One value where the request asked for two: refused against the request.
    let short = xor_sealed(hex("7E 03 10 0007 0201 00"));
    let e = interp::decode_reply(&p, &read, &short).unwrap_err();
    assert_eq!(
        e.to_string(),
        "block_reply.values at offset 3: 1 elements, expected 2 (quantity of the request)"
    );
    // An odd number of bytes before the status word.
    let odd = xor_sealed(hex("7E 03 10 0007 08 0201 00"));
    let e = interp::decode(&p, Some(Direction::Response), None, &odd).unwrap_err();
    assert_eq!(
        e.to_string(),
        "block_reply.values at offset 3: 3 elements, expected whole 2-byte elements"
    );
}

#[test]
fn several_lists_under_a_length_field_and_printed_in_the_other_byte_order() {
    let p = lists_length();
    // The example's printed text (big-endian) replays to little-endian wire bytes.
    let e = &p.examples[0];
    assert_eq!(e.wire, hex("C5 0C 20 02 01 02 FBFF C800 0100 0201 F7"));
    let m = p.message(e.message);
    assert_eq!(
        interp::wire_to_printed(&p, m, &e.wire),
        hex("C5 0C 20 02 01 02 FFFB 00C8 0001 0102 F7")
    );
    let f = request(&p, &e.wire);
    assert_eq!(f.get("channels"), Some(&Raw::List(vec![1, 2])));
    assert_eq!(f.get("samples"), Some(&Raw::List(vec![-5, 200, 1])));
    assert_eq!(f.get("seq"), Some(&Raw::Int(0x0102)));
    // Bits counted in bytes, then a field after them.
    let f = request(&p, &p.examples[1].wire);
    assert_eq!(f.get("mask"), Some(&Raw::Int(0x1234)));
    // Docs place a field after a list by that list.
    assert_eq!(m.place(3), "`samples` + 0");
    assert_eq!(m.place(2), "`channels` + 0");
    assert_eq!(m.place(0), "0");
}

#[test]
fn the_stream_frames_lists_followed_by_fields_by_their_count_fields() {
    for p in [lists_after(), lists_length()] {
        let (bytes, frames) = capture(&p);
        assert_eq!(frames.len(), p.examples.len(), "{}", p.name);
        for chunk in [1, 2, 5, bytes.len()] {
            assert_eq!(
                stream_frames(&p, Some(Direction::Request), &bytes, chunk)
                    .iter()
                    .filter(|f| frames.contains(f))
                    .count(),
                p.examples
                    .iter()
                    .filter(|e| e.message.direction == Direction::Request)
                    .count(),
                "{} in chunks of {chunk}",
                p.name
            );
        }
    }
    // Without a length field, a count after the first list: the stream reads it there.
    let p = lists_after();
    let copy = hex("7E 03 12 03 01 02 03 04 000A 03E8 01 F6");
    let mut bytes = hex("00 7E");
    bytes.extend(&copy);
    bytes.extend(&copy);
    assert_eq!(
        stream_frames(&p, Some(Direction::Request), &bytes, 1),
        [copy.clone(), copy]
    );
}

#[test]
fn lenient_decoding_says_a_field_after_a_list_at_its_own_offset() {
    let p = lists_after();
    let relaxed = busspec_model::stream::relaxed(&p);
    let wire = xor_sealed(hex("7E 03 11 02 1234 5678 0100 00"));
    let strict = interp::decode(&p, None, None, &wire).unwrap_err();
    let (_, violations) =
        busspec_model::stream::decode_lenient(&p, &relaxed, None, None, &wire).unwrap();
    assert_eq!(violations, [strict]);
}

#[test]
fn diff_sees_a_field_moved_across_a_list() {
    let p = lists_after();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/lists_after.yaml"),
    )
    .unwrap();
    let head = &text[..text.find("examples:").unwrap()];
    let moved = head.replace(
        "      - {name: n, type: u8, unit: count}\n      - {name: values, type: u16, unit: count, repeat: {count: n, min: 1, max: 8}}\n      - {name: flags, type: u16, unit: count, range: {min: 0, max: 0x00FF}}",
        "      - {name: n, type: u8, unit: count}\n      - {name: flags, type: u16, unit: count, range: {min: 0, max: 0x00FF}}\n      - {name: values, type: u16, unit: count, repeat: {count: n, min: 1, max: 8}}",
    ) + "examples: []\n";
    assert_ne!(moved, head.to_owned() + "examples: []\n");
    let q = load_str("moved.yaml", &moved).unwrap_or_else(|d| panic!("{d}"));
    let d = diff::diff(&p, &q);
    let moved = d
        .iter()
        .find(|c| c.path == "commands.write_block.fields.flags")
        .unwrap_or_else(|| panic!("{d:#?}"));
    assert_eq!(moved.kind, "field_offset_changed");
    assert_eq!(moved.category, Category::WireBreaking);
    assert_eq!(
        moved.text,
        "field `write_block.flags`: offset `values` + 0 → 1"
    );
    assert_eq!(diff::diff(&p, &p), []);
}
