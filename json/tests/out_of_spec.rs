//! Frames that checksum but break a rule of the spec (a value out of its range, an address no
//! frame may carry, a broadcast the command refuses), in a stream and decoded leniently: the
//! lines both engines print for them.

use busspec_json::{
    event_line, lenient_line, load_spec, out_of_spec_line, parse_hex, Spec, TypedStream,
};
use busspec_model::stream::{decode_lenient, relaxed, StreamDecoder};
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;

/// `bytes` through both stream decoders of `P` in chunks of `chunk`: the interpreter's lines
/// and the generated code's.
fn lines<P: Protocol>(spec: &Spec, bytes: &[u8], chunk: usize) -> (Vec<String>, Vec<String>) {
    let mut interp = StreamDecoder::new(spec, None);
    let mut typed = TypedStream::<P>::new(spec, None, None);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for piece in bytes.chunks(chunk) {
        a.extend(interp.push(piece).iter().map(|e| event_line(spec, e)));
        b.extend(typed.push(piece));
    }
    a.extend(interp.flush().iter().map(|e| event_line(spec, e)));
    b.extend(typed.finish());
    (a, b)
}

const SD_BAD_ADDRESS: &str = r#"{"offset":1,"out_of_spec":"address 0x20 at offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address","protocol":"sd","direction":"request","address":32,"code":"0x76","message":"set_point","fields":{"freshness":0,"position":0},"bytes":"76200000BAB0"}"#;

const SD_OUT_OF_RANGE: &str = r#"{"offset":13,"out_of_spec":"electronic_serial_number_character.string_length at offset 3 is 75, outside its range 0..=32","protocol":"sd","direction":"response","address":1,"code":"0x10","message":"electronic_serial_number_character","fields":{"character":75,"string_length":75},"bytes":"10014B4BFB8A"}"#;

const SD_BROADCAST: &str = r#"{"offset":19,"out_of_spec":"read_temperatures (code 0xA0) does not accept the broadcast address 0x1F","protocol":"sd","direction":"request","address":31,"code":"0xA0","message":"read_temperatures","fields":{"arg1":0,"arg2":0},"bytes":"A01F00008198"}"#;

#[test]
fn both_engines_print_out_of_spec_frames_alike_with_reason_values_and_bytes() {
    let spec = load_spec::<Sd>().unwrap();
    // Noise, a set point to 0x20, a valid set point, a serial-number character of length 75,
    // read_temperatures to the broadcast ID.
    let bytes = parse_hex("00 76200000BAB0 760532001474 10014B4BFB8A A01F00008198").unwrap();
    for chunk in [1, 5, 4096] {
        let (a, b) = lines::<Sd>(&spec, &bytes, chunk);
        assert_eq!(a, b, "chunks of {chunk}");
        assert_eq!(a.len(), 5, "{a:#?}");
        assert_eq!(a[0], r#"{"offset":0,"skipped":1,"bytes":"00"}"#);
        assert_eq!(a[1], SD_BAD_ADDRESS);
        assert!(a[2].starts_with(r#"{"offset":7,"protocol":"sd","direction":"request","address":5,"code":"0x76","message":"set_point""#), "{}", a[2]);
        assert_eq!(a[3], SD_OUT_OF_RANGE);
        assert_eq!(a[4], SD_BROADCAST);
        for line in &a {
            serde_json::from_str::<serde_json::Value>(line).expect("valid JSON");
        }
    }
    let spec = load_spec::<Ub2>().unwrap();
    let bytes = parse_hex("AA41 4001 2C").unwrap();
    let (a, b) = lines::<Ub2>(&spec, &bytes, 4096);
    assert_eq!(a, b);
    assert_eq!(
        a,
        [
            r#"{"offset":0,"out_of_spec":"address 0x41 at offset 1 is outside the device range 0x21..=0x40 and is not the broadcast or host address","protocol":"ub2","direction":"request","address":65,"code":"0x4001","message":"get_actual_capacitance","fields":{},"bytes":"AA4140012C"}"#
        ]
    );
}

#[test]
fn an_out_of_spec_line_without_values_has_reason_and_bytes() {
    let spec = load_spec::<Sd>().unwrap();
    assert_eq!(
        out_of_spec_line(&spec, 3, "why", None, &[0x76, 0x20]),
        r#"{"offset":3,"out_of_spec":"why","bytes":"7620"}"#
    );
}

#[test]
fn a_lenient_line_is_the_frame_then_its_violations() {
    let spec = load_spec::<Sd>().unwrap();
    let lifted = relaxed(&spec);
    // read_electronic_serial_number byte 37 (0x00..=0x1F) to ID 0x20 (0x01..=0x1E).
    let mut wire = vec![0xF0, 0x20, 0x00, 0x25];
    let crc = busspec_model::checksum::compute(&spec.framing.checksum.algorithm, &wire);
    wire.extend_from_slice(&(crc as u16).to_be_bytes());
    let (frame, violations) = decode_lenient(&spec, &lifted, None, None, &wire).unwrap();
    let reasons: Vec<String> = violations.iter().map(|v| v.to_string()).collect();
    assert_eq!(
        lenient_line(&spec, &frame, &reasons),
        r#"{"protocol":"sd","direction":"request","address":32,"code":"0xF0","message":"read_electronic_serial_number","fields":{"arg1":0,"byte_number":37},"violations":["address 0x20 at offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address","read_electronic_serial_number.byte_number at offset 3 is 37, outside its range 0..=31"]}"#
    );
}
