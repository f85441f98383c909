//! The JSON contract, in process, through both engines at once: the generated codec of each
//! built-in protocol and the interpreter must give the same lines, the same bytes and the same
//! reasons. (tests/cli_decode.rs of the `busspec` package keeps what only the process shows:
//! exit codes, the stderr format, arguments.)

use std::marker::PhantomData;

use busspec_json::{
    decode_frame, decode_typed, event_line, frame_line, hex, load_spec, parse_hex, parse_line,
    Spec, TypedStream,
};
use busspec_model::ir::Direction;
use busspec_model::stream::StreamDecoder;
use busspec_protocols::{sd::Sd, ub2::Ub2, Protocol};

const ACTUAL_79_98: &str = r#"{"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":79.98}}"#;

/// A built-in protocol, decoded and encoded by both engines.
struct Both<P> {
    spec: Spec,
    _p: PhantomData<P>,
}

impl<P: Protocol> Both<P> {
    fn new() -> Self {
        Both {
            spec: load_spec::<P>().unwrap_or_else(|e| panic!("{e}")),
            _p: PhantomData,
        }
    }

    fn command(&self, name: &str) -> usize {
        self.spec
            .commands
            .iter()
            .position(|c| c.name == name)
            .unwrap_or_else(|| panic!("no command {name}"))
    }

    /// Both engines' results for one frame in hex: (interpreter, generated).
    fn decode_both(
        &self,
        text: &str,
        direction: Option<Direction>,
        reply_to: Option<&str>,
    ) -> (Result<String, String>, Result<String, String>) {
        let r = reply_to.map(|n| self.command(n));
        let a = parse_hex(text)
            .and_then(|w| decode_frame(&self.spec, direction, r, &w))
            .map(|f| frame_line(&self.spec, &f, None));
        let b = parse_hex(text)
            .and_then(|w| decode_typed::<P>(&self.spec, direction, r, &w))
            .and_then(|t| t.line(&self.spec, None));
        (a, b)
    }

    /// The line of a frame, the same from both engines (or both engines' failure; the
    /// generated code's reason, which `busspec decode` prints for a built-in protocol).
    fn decode_dir(
        &self,
        text: &str,
        direction: Option<Direction>,
        reply_to: Option<&str>,
    ) -> Result<String, String> {
        let (a, b) = self.decode_both(text, direction, reply_to);
        match (&a, &b) {
            (Ok(x), Ok(y)) => assert_eq!(x, y, "{text}: the engines print differently"),
            (Err(_), Err(_)) => {}
            _ => panic!("{text}: the engines disagree: interpreter {a:?}, generated {b:?}"),
        }
        b
    }

    fn decode(&self, text: &str) -> Result<String, String> {
        self.decode_dir(text, None, None)
    }

    /// The hex of a JSON line, the same from both engines (or the same reason).
    fn encode(&self, line: &str) -> Result<String, String> {
        let a = parse_line(&self.spec, line)
            .and_then(|p| p.encode(&self.spec))
            .map(|w| hex(&w));
        let b = parse_line(&self.spec, line)
            .and_then(|p| p.to_typed::<P>(&self.spec))
            .and_then(|t| t.encode().map_err(|e| e.to_string()))
            .map(|w| hex(&w));
        assert_eq!(a, b, "{line}: the engines encode differently");
        b
    }

    /// The lines of a capture, the same from both stream decoders.
    fn stream(&self, bytes: &[u8], reply_to: Option<&str>) -> Vec<String> {
        let r = reply_to.map(|n| self.command(n));
        let mut interp = StreamDecoder::new(&self.spec, None).with_default_request(r);
        let mut a: Vec<String> = interp
            .push(bytes)
            .iter()
            .map(|e| event_line(&self.spec, e))
            .collect();
        a.extend(interp.flush().iter().map(|e| event_line(&self.spec, e)));
        let mut typed = TypedStream::<P>::new(&self.spec, None, r);
        let mut b = typed.push(bytes);
        b.extend(typed.finish());
        assert_eq!(a, b, "the stream decoders print differently");
        b
    }

    fn wire(&self, message: &str) -> Vec<u8> {
        self.spec
            .examples
            .iter()
            .find(|e| self.spec.message(e.message).name == message)
            .unwrap_or_else(|| panic!("no example of {message}"))
            .wire
            .clone()
    }
}

#[test]
fn documented_frame_decodes_to_exact_json() {
    let ub2 = Both::<Ub2>::new();
    for frame in [
        "AA21 4101 3E1F 0000 6A",
        "0xAA21 4101 3E1F 0000 6A",
        "AA2141013E1F00006A",
        "0xAA 0x21 0x41 0x01 0x3E 0x1F 0x00 0x00 0x6A",
    ] {
        assert_eq!(ub2.decode(frame).as_deref(), Ok(ACTUAL_79_98), "{frame}");
    }
}

#[test]
fn ub2_is_little_endian_on_the_wire_so_the_printed_frame_is_another_value() {
    // §6.1 prints `AA21 4101 0000 1F3E 6A` most significant byte first; on the wire (§3,
    // little-endian) that frame is `AA 21 41 01 3E 1F 00 00 6A` = 79.98 pF.
    let ub2 = Both::<Ub2>::new();
    let e = ub2
        .spec
        .examples
        .iter()
        .find(|e| e.printed.as_deref() == Some("AA21 4101 0000 1F3E 6A"))
        .expect("the §6.1 example");
    assert_eq!(e.section, "6.1");
    assert_eq!(hex(&e.wire), "AA2141013E1F00006A");
    // The printed bytes taken as wire bytes still checksum (an 8-bit sum does not see the
    // order) and decode, to 0x3E1F0000 * 0.01 pF.
    assert_eq!(0x3E1F_0000u32, 1_042_219_008);
    assert_eq!(
        ub2.decode("AA21 4101 0000 1F3E 6A").as_deref(),
        Ok(
            r#"{"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":10422190.08}}"#
        )
    );
}

#[test]
fn value_kinds() {
    let sd = Both::<Sd>::new();
    let lines: Vec<String> = [
        "20 01 55 5C 7F F2", // temperatures 35 °C, 42 °C (offset -50)
        "20 01 00 FF 02 3D", // special values by name
        "76 01 3E 00 BC 27", // packed bits: freshness 3, position -45°
    ]
    .iter()
    .map(|f| sd.decode(f).unwrap_or_else(|e| panic!("{f}: {e}")))
    .collect();
    assert_eq!(
        lines,
        [
            r#"{"protocol":"sd","direction":"response","address":1,"code":"0x20","message":"temperatures","fields":{"motor_temperature":35,"pcb_temperature":42}}"#,
            r#"{"protocol":"sd","direction":"response","address":1,"code":"0x20","message":"temperatures","fields":{"motor_temperature":"no_sensor","pcb_temperature":"defective"}}"#,
            r#"{"protocol":"sd","direction":"request","address":1,"code":"0x76","message":"set_point","fields":{"freshness":3,"position":-45}}"#,
        ]
    );
    for l in lines {
        serde_json::from_str::<serde_json::Value>(&l).unwrap();
    }
    // Flags: the names of the set bits, then an unnamed set bit as its mask.
    let ub2 = Both::<Ub2>::new();
    let line = ub2.decode("AA214122A100CF").unwrap();
    assert!(
        line.contains(r#""fields":{"error_bits":["oca","reset",128],"reserved":0}"#),
        "{line}"
    );
}

#[test]
fn direction_is_inferred_from_code_and_length() {
    let ub2 = Both::<Ub2>::new();
    let direction = |frame: &str, d: Option<Direction>| {
        let line = ub2
            .decode_dir(frame, d, None)
            .unwrap_or_else(|e| panic!("{frame}: {e}"));
        let v: serde_json::Value = serde_json::from_str(&line).unwrap();
        (
            v["direction"].as_str().unwrap().to_owned(),
            v["message"].as_str().unwrap().to_owned(),
        )
    };
    assert_eq!(
        direction("AA21 1000 DB", None),
        ("request".into(), "reference_run".into())
    );
    assert_eq!(
        direction("AA21 501B", None),
        ("response".into(), "movement_started".into())
    );
    // A setter request and its echo ACK share code 0x4300; length tells them apart.
    assert_eq!(
        direction("AA21 4300 0405 17", None),
        ("request".into(), "set_acceleration_speed_index".into())
    );
    assert_eq!(
        direction("AA21 4300 0E", None),
        ("response".into(), "set_acceleration_speed_index_ack".into())
    );
    assert_eq!(
        direction("AA21 4300 0E", Some(Direction::Response)),
        ("response".into(), "set_acceleration_speed_index_ack".into())
    );
    // Forcing the wrong direction fails, in both engines.
    assert!(ub2
        .decode_dir("AA21 501B", Some(Direction::Request), None)
        .is_err());
}

#[test]
fn bad_frames_say_what_and_where() {
    let ub2 = Both::<Ub2>::new();
    let (a, b) = ub2.decode_both("AA21 4101 0000 1F3E 6B", None, None);
    let checksum = "checksum mismatch at offset 8: expected 0x6A, found 0x6B";
    assert_eq!(a.unwrap_err(), checksum);
    assert_eq!(b.unwrap_err(), checksum);
    assert_eq!(
        ub2.decode("zz").unwrap_err(),
        "`z` at character 1 is not a hex digit"
    );
    let mut unknown = vec![0xAA, 0x21, 0x77, 0x77, 0x00];
    unknown[4] = unknown[..4].iter().fold(0u8, |s, b| s.wrapping_add(*b));
    let (a, b) = ub2.decode_both(&hex(&unknown), None, None);
    assert_eq!(a.unwrap_err(), "unknown command code 0x7777 at offset 2");
    assert_eq!(b.unwrap_err(), "unknown command code 0x7777 at offset 2");
    assert!(ub2
        .decode("AA21")
        .unwrap_err()
        .starts_with("truncated frame"));
}

#[test]
fn reply_to_settles_responses_only_the_request_tells_apart() {
    let sd = Both::<Sd>::new();
    let frame = "22 01 1E 3B 6C A5";
    let (a, b) = sd.decode_both(frame, None, None);
    let why = "ambiguous frame: could be total_runtime_hours or total_runtime_min_sec; \
               only the request it answers tells them apart: give --reply-to read_total_runtime_hours \
               or --reply-to read_total_runtime_min_sec";
    assert_eq!(a.unwrap_err(), why);
    assert_eq!(b.unwrap_err(), why);
    assert_eq!(sd.decode_dir(frame, None, Some("read_total_runtime_min_sec")).as_deref(),
        Ok("{\"protocol\":\"sd\",\"direction\":\"response\",\"address\":1,\"code\":\"0x22\",\"message\":\"total_runtime_min_sec\",\"fields\":{\"runtime_minutes\":30,\"runtime_seconds\":59}}")
    );
    assert!(sd
        .decode_dir(frame, None, Some("read_total_runtime_hours"))
        .unwrap()
        .contains(r#""message":"total_runtime_hours","fields":{"runtime_hours":7739}"#));
    // A request that gets neither reply says so.
    let (a, b) = sd.decode_both(frame, None, Some("read_temperatures"));
    for e in [a, b] {
        assert!(e
            .unwrap_err()
            .contains("read_temperatures (--reply-to) gets none of them"));
    }
    // Direction and reply_to together.
    assert!(sd
        .decode_dir(
            frame,
            Some(Direction::Response),
            Some("read_total_runtime_min_sec")
        )
        .is_ok());
}

#[test]
fn encode_takes_direction_and_code_optionally() {
    let ub2 = Both::<Ub2>::new();
    for (line, want) in [
        (
            r#"{"message":"actual_capacitance","address":33,"fields":{"capacitance":79.98}}"#,
            "AA2141013E1F00006A",
        ),
        (
            r#"{"protocol":"ub2","direction":"request","code":"0x2000","message":"go_to_capacitance","address":33,"fields":{"target":150}}"#,
            "AA212000983A0000BD",
        ),
        (
            r#"{"message":"go_to_capacitance","address":33,"fields":{"target":1.5e2}}"#,
            "AA212000983A0000BD",
        ),
        (r#"{"message":"reference_run","address":33}"#, "AA211000DB"),
        (
            r#"{"message":"status","address":33,"fields":{"error_bits":["oca","reset",128],"reserved":0}}"#,
            "AA214122A100CF",
        ),
        // What `--stream` prints is accepted too: its offset is ignored.
        (
            r#"{"offset":12,"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":79.98}}"#,
            "AA2141013E1F00006A",
        ),
    ] {
        assert_eq!(ub2.encode(line).as_deref(), Ok(want), "{line}");
    }
}

#[test]
fn encode_says_what_is_wrong_with_a_line() {
    let ub2 = Both::<Ub2>::new();
    for (line, why) in [
        (
            r#"{"message":"go_to_capacitance","address":33,"fields":{"target":79.985}}"#,
            "target: 79.985 pF is not a whole number of steps of 0.01 pF",
        ),
        ("not json", "invalid JSON at column 2: expected ident"),
        (
            r#"{"message":"go_to_capacitanse","address":33}"#,
            "unknown message `go_to_capacitanse` in ub2",
        ),
        (
            r#"{"message":"go_to_capacitance","address":33,"fields":{}}"#,
            "no value given for field target",
        ),
        (
            r#"{"message":"go_to_capacitance","address":33,"fields":{"target":50000000}}"#,
            "target: 50000000 pF is out of range: the field holds 0 pF to 42949672.95 pF",
        ),
        (
            r#"{"message":"go_to_capacitance","address":33,"code":"0x2001","fields":{"target":1}}"#,
            "code 0x2001 does not match go_to_capacitance (0x2000)",
        ),
        (
            r#"{"message":"set_mode_of_operation","address":33,"fields":{"mode":"turbo"}}"#,
            "mode: `turbo` is not a value of mode_of_operation (one of: encoder_disabled, close_loop_control, open_loop_control)",
        ),
        (
            r#"{"message":"go_to_capacitance","address":33,"fields":{"targt":1}}"#,
            "go_to_capacitance has no field `targt` (its fields: target)",
        ),
        (
            r#"{"message":"go_to_capacitance","direction":"response","address":33,"fields":{"target":1}}"#,
            "go_to_capacitance is a request, not a response",
        ),
        (
            r#"{"protocol":"sd","message":"reference_run","address":33}"#,
            "protocol `sd` does not match this spec (`ub2`)",
        ),
        (
            r#"{"message":"reference_run","address":300}"#,
            "address 300 is not a byte (0..=255)",
        ),
        (
            r#"{"offset":3,"skipped":2,"bytes":"0013"}"#,
            "a skipped-bytes report, not a frame",
        ),
    ] {
        assert_eq!(ub2.encode(line).unwrap_err(), why, "{line}");
    }
}

/// The checks a line passes only at encoding (the value against its field's wire type, text
/// against its length, constant and repeated fields, the address) give the same reasons from
/// both engines: the interpreter's encoder and `Message::from_fields`.
#[test]
fn encode_checks_values_alike_in_both_engines() {
    let ub2 = Both::<Ub2>::new();
    for (line, want) in [
        (
            r#"{"message":"set_baud_rate","address":33,"fields":{"baud_rate":300}}"#,
            Err("baud_rate = 300 does not fit the field (0..=255)"),
        ),
        (
            r#"{"message":"set_baud_rate","address":33,"fields":{"baud_rate":-1}}"#,
            Err("baud_rate = -1 does not fit the field (0..=255)"),
        ),
        (
            r#"{"message":"firmware_version","address":33,"fields":{"firmware_version":"2010"}}"#,
            Err("firmware_version takes exactly 11 characters, got 4"),
        ),
        (
            r#"{"message":"firmware_version","address":33,"fields":{"firmware_version":"20100433.000"}}"#,
            Err("firmware_version takes exactly 11 characters, got 12"),
        ),
        (
            r#"{"message":"get_lower_customer_limit","address":33,"fields":{"index":2}}"#,
            Err("index is fixed at 1 in this message, got 2"),
        ),
        (
            r#"{"message":"get_lower_customer_limit","address":33,"fields":{"index":1}}"#,
            Ok(()),
        ),
        (
            r#"{"message":"reference_run","address":5}"#,
            Err("address 0x05 is outside the device range 0x21..=0x40 and is not the broadcast or host address"),
        ),
        // Past the device range by one (the document's 0x41, erratum ub2-e02).
        (
            r#"{"message":"reference_run","address":65}"#,
            Err("address 0x41 is outside the device range 0x21..=0x40 and is not the broadcast or host address"),
        ),
        // The host address (0x20) is one a frame may carry, as the strict decoders accept it.
        (r#"{"message":"reference_run","address":32}"#, Ok(())),
        // A value outside its field's spec range (the wire byte would hold it).
        (
            r#"{"message":"get_stored_full_step_position","address":33,"fields":{"index":10}}"#,
            Err("index = 10 is outside its range 0..=9"),
        ),
        (
            r#"{"message":"get_stored_full_step_position","address":33,"fields":{"index":9}}"#,
            Ok(()),
        ),
    ] {
        let got = ub2.encode(line);
        match want {
            Ok(()) => assert!(got.is_ok(), "{line}: {got:?}"),
            Err(why) => assert_eq!(got.unwrap_err(), why, "{line}"),
        }
    }
    let sd = Both::<Sd>::new();
    for (line, want) in [
        (
            r#"{"message":"set_servo_id","address":1,"fields":{"new_id":5,"new_id_repeat":6}}"#,
            Err("new_id_repeat is fixed at 5 in this message, got 6"),
        ),
        (
            r#"{"message":"set_servo_id","address":1,"fields":{"new_id":5,"new_id_repeat":5}}"#,
            Ok(()),
        ),
        // The broadcast address: a command that accepts broadcast goes there, one that does not
        // is refused. The strict rule lets any frame carry the broadcast address (a response
        // too: the address check does not look at the direction), as the strict decoders do.
        (
            r#"{"message":"set_servo_id","address":31,"fields":{"new_id":5}}"#,
            Ok(()),
        ),
        (
            r#"{"message":"read_temperatures","address":31}"#,
            Err("read_temperatures does not accept the broadcast address 0x1F"),
        ),
        (
            r#"{"message":"set_servo_id_reply","address":31,"fields":{"new_id":5}}"#,
            Ok(()),
        ),
        // Outside the device range 0x01..=0x1E and not the broadcast address.
        (
            r#"{"message":"set_servo_id_reply","address":32,"fields":{"new_id":5}}"#,
            Err("address 0x20 is outside the device range 0x01..=0x1E and is not the broadcast or host address"),
        ),
        (
            r#"{"message":"read_temperatures","address":0}"#,
            Err("address 0x00 is outside the device range 0x01..=0x1E and is not the broadcast or host address"),
        ),
        // new_id is a device address: 0 is outside its spec range.
        (
            r#"{"message":"set_servo_id","address":1,"fields":{"new_id":0}}"#,
            Err("new_id = 0 is outside its range 1..=30"),
        ),
    ] {
        let got = sd.encode(line);
        match want {
            Ok(()) => assert!(got.is_ok(), "{line}: {got:?}"),
            Err(why) => assert_eq!(got.unwrap_err(), why, "{line}"),
        }
    }
}

#[test]
fn encode_converts_offsets_and_angles_exactly() {
    // SD temperature: °C = raw - 50; angle: 360/4096 ° per digit.
    let sd = Both::<Sd>::new();
    assert_eq!(sd.encode(r#"{"message":"temperatures","address":1,"fields":{"motor_temperature":35,"pcb_temperature":42}}"#).as_deref(),
        Ok("2001555C7FF2")
    );
    assert_eq!(
        sd.encode(r#"{"message":"set_point","address":1,"fields":{"freshness":3,"position":-45}}"#)
            .as_deref(),
        Ok("76013E00BC27")
    );
    let one_step = sd
        .encode(r#"{"message":"set_point","address":1,"fields":{"freshness":3,"position":0.087890625}}"#)
        .unwrap();
    assert!(one_step.starts_with("76013001"), "{one_step}");
    assert_eq!(
        sd.encode(
            r#"{"message":"set_point","address":1,"fields":{"freshness":3,"position":0.088}}"#
        )
        .unwrap_err(),
        "position: 0.088 ° is not a whole number of steps of 0.087890625 °"
    );
}

/// A capture of example frames (those that decode without their request) with noise between
/// some of them, and the lines expected: each frame's line with its offset first.
fn capture<P: Protocol>(p: &Both<P>, noise: &[&[u8]]) -> (Vec<u8>, Vec<String>) {
    let frames: Vec<&[u8]> = p
        .spec
        .examples
        .iter()
        .filter(|e| !p.spec.message(e.message).needs_request)
        .map(|e| e.wire.as_slice())
        .collect();
    let mut bytes = Vec::new();
    let mut expected = Vec::new();
    for (n, frame) in frames.iter().enumerate() {
        let line = p.decode(&hex(frame)).unwrap();
        if n % 4 == 1 {
            let junk = noise[(n / 4) % noise.len()];
            expected.push(format!(
                r#"{{"offset":{},"skipped":{},"bytes":"{}"}}"#,
                bytes.len(),
                junk.len(),
                hex(junk)
            ));
            bytes.extend_from_slice(junk);
        }
        expected.push(format!(
            r#"{{"offset":{},{}"#,
            bytes.len(),
            line.trim_start_matches('{')
        ));
        bytes.extend_from_slice(frame);
    }
    (bytes, expected)
}

#[test]
fn stream_reports_frames_with_offsets_and_skipped_noise() {
    let ub2 = Both::<Ub2>::new();
    let (bytes, expected) = capture(&ub2, &[&[0x00, 0x13], &[0xAA], &[0xFF, 0x55, 0x21]]);
    assert!(expected.iter().filter(|l| l.contains("skipped")).count() >= 3);
    assert_eq!(ub2.stream(&bytes, None), expected);
    let sd = Both::<Sd>::new();
    let (bytes, expected) = capture(&sd, &[&[0x00], &[0xFF, 0xEE], &[0x01, 0x02, 0x03]]);
    assert!(expected.iter().filter(|l| l.contains("skipped")).count() >= 3);
    assert_eq!(sd.stream(&bytes, None), expected);
}

#[test]
fn stream_pairs_ambiguous_responses_with_the_request_before_them() {
    let sd = Both::<Sd>::new();
    let reply = sd.wire("total_runtime_min_sec");
    let mut bytes = sd.wire("read_total_runtime_min_sec");
    bytes.extend_from_slice(&reply);
    bytes.extend_from_slice(&reply);
    let lines = sd.stream(&bytes, None);
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(lines[0].starts_with(r#"{"offset":0,"protocol":"sd","direction":"request""#));
    assert!(lines[1].starts_with(r#"{"offset":6,"#));
    assert!(lines[1].contains(r#""message":"total_runtime_min_sec""#));
    assert_eq!(
        lines[2],
        format!(
            r#"{{"offset":12,"ambiguous":["total_runtime_hours","total_runtime_min_sec"],"bytes":"{}"}}"#,
            hex(&reply)
        )
    );
    // The request assumed when none came before.
    let lines = sd.stream(&reply, Some("read_total_runtime_hours"));
    assert!(lines[0].contains(r#""message":"total_runtime_hours""#));
}
