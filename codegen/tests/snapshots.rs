//! Snapshot tests of the generator: the code emitted for the small fixture specs in
//! `model/tests/fixtures/valid/` is kept in `snapshots/`, so every change to the generated code shows up in
//! review as a diff of readable Rust. `busspec-protocols`' `tests/snapshots_compile.rs` compiles
//! the same files against the runtime and runs them.
//!
//! After an intended change, refresh them with
//! `BUSSPEC_UPDATE_SNAPSHOTS=1 cargo test -p busspec-codegen --test snapshots`.

use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests")
}

/// `fixture` is a path from the repository's root.
fn check(fixture: &str, snapshot: &str) {
    let spec = dir().join("../..").join(fixture);
    let p = busspec_model::load_file(&spec).unwrap_or_else(|d| panic!("{d}"));
    // SPEC_YAML's include_str! is relative to the snapshot file.
    let code = busspec_codegen::emit::emit_module(&p, fixture, &format!("../../../{fixture}"))
        .unwrap_or_else(|e| panic!("{e}"));
    let path = dir().join("snapshots").join(snapshot);
    if std::env::var_os("BUSSPEC_UPDATE_SNAPSHOTS").is_some() {
        std::fs::write(&path, &code).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if want != code {
        let line = want
            .lines()
            .zip(code.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(want.lines().count().min(code.lines().count()));
        panic!(
            "the code generated for {fixture} differs from snapshots/{snapshot} from line {}:\n  snapshot:  {}\n  generated: {}\n\
             If the change is intended, run BUSSPEC_UPDATE_SNAPSHOTS=1 cargo test -p busspec-codegen --test snapshots",
            line + 1,
            want.lines().nth(line).unwrap_or("<end>"),
            code.lines().nth(line).unwrap_or("<end>"),
        );
    }
}

#[test]
fn minimal_sum8_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/minimal.yaml", "mini.rs");
}

#[test]
fn minimal_crc_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/minimal_crc.yaml", "mini_crc.rs");
}

/// A spec whose units, enums, flags, messages and fields are named like core's types
/// (`Option`, `Result`, `Some`, `Ok`, `Err`), primitives (`u8`, `usize`), `core`, the runtime
/// alias `rt` and the generated functions' locals: `snapshots_compile.rs` compiles the
/// snapshot and replays its examples.
#[test]
fn spec_named_like_core_generates_its_snapshot() {
    check("codegen/tests/fixtures/core_names.yaml", "core_names.rs");
}

/// The fixed-length constructs of the newer language: a sync sequence, a length field, an
/// inverted sum-8 that skips the sync bytes, 24-bit integers, values following another field or the request, a code derived
/// from the request's (`snapshots_compile.rs` compiles and replays it).
#[test]
fn sync_sequence_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/minimal_sync.yaml", "syncy.rs");
}

/// Replies without a code, told apart by length and request (`snapshots_compile.rs` compiles
/// and replays it).
#[test]
fn codeless_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/minimal_codeless.yaml",
        "codeless.rs",
    );
}

/// A code-less message beside 2-byte coded ones (Pelco-D), told apart by a constant
/// sub-field: every code length is tried before a frame is refused (`snapshots_compile.rs`
/// compiles it and holds it to the interpreter).
#[test]
fn codeless_beside_coded_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/pelco_d_codeless.yaml",
        "pelco_d.rs",
    );
}

/// Frames that carry no address (a point-to-point link): nothing reads or writes one, encode
/// takes address 0 alone (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn unaddressed_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/unaddressed.yaml",
        "unaddressed.rs",
    );
}

/// Fixed-length frames that end in a stop byte after the checksum (FT1.2, M-Bus short frames):
/// the encoder writes the checksum and then the end byte, decode checks the end byte before the
/// checksum (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn end_byte_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/ft12_fixed.yaml",
        "ft12_fixed.rs",
    );
}

/// A constant whole frame beside framed ones (M-Bus's single character `E5` beside its short
/// frame): a unit variant whose `encode` writes the bytes and which `decode` recognises before
/// the framing is checked (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn constant_frame_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/mbus_short.yaml",
        "mbus_short.rs",
    );
}

/// The 16-bit sum negated (JBD's battery management protocol), high byte first, covering from
/// the code past a header byte (`snapshots_compile.rs` compiles it and holds it to the
/// interpreter).
#[test]
fn sum16_complement_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/jbd_bms.yaml", "jbd_bms.rs");
    check(
        "model/tests/fixtures/valid/header_constant.yaml",
        "header_constant.rs",
    );
    check(
        "model/tests/fixtures/valid/novatel_oem.yaml",
        "novatel_oem.rs",
    );
    check("model/tests/fixtures/valid/nextion.yaml", "nextion.rs");
    check(
        "model/tests/fixtures/valid/rtcm3_frame.yaml",
        "rtcm3_frame.rs",
    );
}

/// A reply whose checksum takes in its request's bytes (`checksum_over_request`).
#[test]
fn over_request_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/pelco_d_replies.yaml",
        "pelco_d_replies.rs",
    );
}

/// Messages without a checksum (`checksum: none`) beside replies whose checksum takes in
/// their request's bytes (RoboClaw's packet serial: reads travel without a CRC, their
/// code-less replies' CRC covers the read's two bytes).
#[test]
fn unchecked_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/roboclaw.yaml", "roboclaw.rs");
}

/// A layout per direction (Sensirion SHDLC, the SPS30): replies carry a state byte, a header
/// field of replies only, that requests lack; byte stuffing of 7E 7D 11 13 and a shared flag
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn layout_by_direction_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/shdlc.yaml", "shdlc.rs");
}

/// The 8-bit Fletcher checksum of UBX-shaped frames, over code, a 16-bit length and payload
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn fletcher_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/ubx_like.yaml", "ubx_like.rs");
}

/// A checksum before the bytes it covers (Septentrio SBF: `$@`, a CRC-16/XMODEM at offset 2
/// over the ID, the length and the body after it): `FRAME.lead`, the frame sum over the bytes
/// from offset 4 to the end (`snapshots_compile.rs` compiles it and holds it to the
/// interpreter).
#[test]
fn checksum_before_the_payload_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/sbf_blocks.yaml",
        "sbf_blocks.rs",
    );
}

/// A checksum before the payload over bytes on both sides of it, followed by its complement
/// (HerkuleX): `frame_sum` over the two spans, `checksum` the value and its complement.
#[test]
fn herkulex_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/herkulex.yaml", "herkulex.rs");
}

/// Records of a fixed count in UBX-shaped frames (`rt::CountBy::Fixed`): three satellite
/// records followed by a field, two port records followed by a counted list
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn fixed_records_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/ubx_fixed_blocks.yaml",
        "ubx_fixed_blocks.rs",
    );
}

/// Lists of floats (their words swapped) and 64-bit integers counted by a field
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn float_lists_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/float_lists.yaml",
        "float_lists.rs",
    );
}

/// Frames with no start byte, no address and no checksum (Maestro's compact protocol)
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn no_checksum_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/maestro_compact.yaml",
        "maestro_compact.rs",
    );
}

/// Pelco-P: an end byte (ETX) before the checksum, which covers it and the start byte, and
/// commands that get no reply, so no response at all (`snapshots_compile.rs` compiles it and
/// holds it to the interpreter).
#[test]
fn pelco_p_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/pelco_p.yaml", "pelco_p.rs");
}

/// MSP v1: the direction byte as the code, the command as a constant first field, a length
/// that leaves it out, an XOR from the length field on, an error reply common to every command
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn msp_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/msp_v1.yaml", "msp_v1.rs");
}

/// MSP v1 with start bytes that differ by direction (`$M<`, `$M>`): the command is the code of
/// a request and of its reply alike; `FRAME.start` is `None` and each direction's `decode`
/// checks its own start bytes; the stream tables keep the candidates of the directions whose
/// start bytes agree with the head.
#[test]
fn start_by_direction_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/msp_by_direction.yaml",
        "msp_by_direction.rs",
    );
}

/// The start byte and the length field sent twice (FT1.2's and M-Bus's `68 L L 68`): decode
/// checks both copies in the interpreter's order, encode writes both.
#[test]
fn repeated_start_and_length_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/ft12_variable.yaml",
        "ft12_variable.rs",
    );
}

/// A short form of the frame (`framing.forms`: M-Bus's `10 C A CS 16` beside `68 L L 68 ...`
/// and the single character `E5`): `FORM`, decode laid out, encode sent short where the
/// payload is empty, the stream framed by start byte and length field.
#[test]
fn short_form_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/mbus.yaml", "mbus.rs");
}

/// The start bytes again after a two-byte code: decode reads the second copy at the
/// direction's own code length.
#[test]
fn start_after_code_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/sync_after_code.yaml",
        "sync_after_code.rs",
    );
}

/// BCD fields (`encoding: bcd`): decode checks each digit (`rt::bcd`) and reads the decimal
/// number, encode writes its digits (`rt::to_bcd`) after the range check.
#[test]
fn bcd_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/bcd_meter.yaml", "bcd_meter.rs");
    check("model/tests/fixtures/valid/crc_extra.yaml", "crc_extra.rs");
}

/// Header fields every message carries (MAVLink v1's sequence, system and component IDs):
/// each variant carries them as fields, read and written at the header's offset in the frame.
#[test]
fn header_fields_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/mavlink_v1.yaml",
        "mavlink_v1.rs",
    );
    check("model/tests/fixtures/valid/msp_v2.yaml", "msp_v2.rs");
}

/// Payload truncation (MAVLink v2's trailing zeros, `framing.truncation`): `TRUNCATION`, decode
/// of a truncated frame padded into a copy, encode stripped, the stream framed by the length
/// field; a 3-byte message id as the code.
#[test]
fn truncation_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/mavlink_v2.yaml",
        "mavlink_v2.rs",
    );
}

/// Repeated fields (variable-length frames): a list counted in bytes by a field that follows
/// another, a reply's list to the end of the frame whose count follows the request, a length
/// field from each frame's length (`snapshots_compile.rs` compiles and replays it).
#[test]
fn variable_length_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/minimal_variable.yaml",
        "variable.rs",
    );
}

/// A reply's list to the end of the frame with no length field: the stream decoder frames it
/// by the lengths listed in `FRAME_LENGTHS` (`snapshots_compile.rs` compiles it and holds its
/// stream decoder to the interpreter's).
#[test]
fn repeat_to_the_end_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/minimal_end.yaml", "ending.rs");
}

/// Fields after a list and several lists, without and with a length field
/// (`snapshots_compile.rs` compiles them and holds them to the interpreter).
#[test]
fn lists_specs_generate_their_snapshots() {
    check(
        "model/tests/fixtures/valid/lists_after.yaml",
        "lists_after.rs",
    );
    check(
        "model/tests/fixtures/valid/lists_length.yaml",
        "lists_length.rs",
    );
}

/// Packed elements (`packed:`), least and most significant bit first, with padding bits and
/// fields after them (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn packed_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/packed_channels.yaml",
        "packed_channels.rs",
    );
}

/// Repeated records (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn records_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/records.yaml", "records.rs");
}

/// Records whose width a field gives (`snapshots_compile.rs` compiles it and holds it to the
/// interpreter).
#[test]
fn records_sized_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/records_sized.yaml",
        "records_sized.rs",
    );
}

/// The two public protocols, generated whole (`snapshots_compile.rs` and
/// `generated_public.rs` compile them, replay their examples and hold them to the
/// interpreter).
#[test]
fn modbus_spec_generates_its_snapshot() {
    check("spec/modbus.yaml", "modbus.rs");
}

#[test]
fn dynamixel_spec_generates_its_snapshot() {
    check("spec/dynamixel.yaml", "dynamixel.rs");
}

/// The two document protocols the project began with (`flagships.rs` compiles them, replays
/// their examples and holds them to the interpreter), so a review of their shape needs no build.
#[test]
fn ub2_spec_generates_its_snapshot() {
    check("spec/ub2.yaml", "ub2.rs");
}

#[test]
fn sd_spec_generates_its_snapshot() {
    check("spec/sd.yaml", "sd.rs");
}

/// Nothing the spec language says is left to the interpreter alone: every valid fixture and
/// spec generates (optional fields too: fixture `optional_sensor`).
#[test]
fn the_generator_has_no_gaps() {
    let root = dir().join("../..");
    let mut specs: Vec<_> = std::fs::read_dir(root.join("model/tests/fixtures/valid"))
        .unwrap()
        .chain(std::fs::read_dir(root.join("spec")).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    specs.sort();
    assert!(specs.len() > 8, "{specs:?}");
    for spec in specs {
        let p = busspec_model::load_file(&spec).unwrap_or_else(|d| panic!("{d}"));
        assert_eq!(
            p.generator_gaps(),
            Vec::<String>::new(),
            "{}",
            spec.display()
        );
        busspec_codegen::emit::emit_module(&p, "x", "x")
            .unwrap_or_else(|e| panic!("{}: {e}", spec.display()));
    }
}

/// The one construct the generator refuses: a repeat to the end of the frame without a length
/// field, whose every length the stream decoder must list beforehand, when that makes more
/// than 64 frame lengths. Refused by name, pointing at the interpreter; with 16 elements at
/// most it is generated, its lengths listed.
#[test]
fn a_repeat_to_the_end_without_a_length_field_lists_its_lengths_up_to_64() {
    let path = dir().join("../../model/tests/fixtures/valid/minimal_variable.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let head = &text[..text.find("examples:").unwrap()];
    let without = head
        .replace(
            "layout: [start, address, length, code, payload, checksum]",
            "layout: [start, address, code, payload, checksum]",
        )
        .replace(
            "  length: {width: 1, counts: [code, payload, checksum]}\n",
            "",
        )
        .replace("payload: {min: 1, max: 40}", "payload: {min: 1, max: 250}")
        + "examples: []\n";
    let many = without.replace(
        "repeat: {count: end, min: 1, max: 16, request",
        "repeat: {count: end, min: 1, max: 100, request",
    );
    assert_ne!(many, without);
    let p = busspec_model::load_str("few", &without).unwrap_or_else(|d| panic!("{d}"));
    let code = busspec_codegen::emit::emit_module(&p, "x", "x").unwrap();
    // The reply's lengths, 5 to 37 bytes (none to 16 two-byte elements), longest first
    // among the fixed ones (8 and 6).
    let at = code.find("const FRAME_LENGTHS").unwrap();
    let list: String = code[at..]
        .chars()
        .skip_while(|&c| c != '[')
        .skip(1)
        .skip_while(|&c| c != '[')
        .take_while(|&c| c != ']')
        .filter(|c| !c.is_whitespace())
        .collect();
    assert_eq!(
        list,
        "[37,35,33,31,29,27,25,23,21,19,17,15,13,11,9,8,7,6,5,"
    );
    let p = busspec_model::load_str("many", &many).unwrap_or_else(|d| panic!("{d}"));
    let e = busspec_codegen::emit::emit_module(&p, "x", "x").unwrap_err();
    for said in [
        "`read_reply.values`: a repeat to the end of the frame without a length field",
        "busspec decode --spec",
    ] {
        assert!(e.contains(said), "{said:?} not in {e}");
    }
}

/// IEEE-754 floats and 64-bit integers, big-endian with word-swapped registers as a Modbus
/// energy meter sends them, and little-endian telemetry (`snapshots_compile.rs` compiles both
/// and holds them to the interpreter).
#[test]
fn float_and_64_bit_specs_generate_their_snapshots() {
    check(
        "model/tests/fixtures/valid/meter_floats.yaml",
        "meter_floats.rs",
    );
    check(
        "model/tests/fixtures/valid/telemetry_le.yaml",
        "telemetry_le.rs",
    );
}

/// Escaping and stuffing (`framing.escaping`): SLIP, HDLC, COBS, Dynamixel 2.0's stuffing and
/// XBee's escaping without an end byte, Garmin's and TSIP's DLE stuffing (`snapshots_compile.rs` compiles them and holds them to the interpreter).
#[test]
fn escaped_specs_generate_their_snapshots() {
    check(
        "model/tests/fixtures/valid/slip_sensor.yaml",
        "slip_sensor.rs",
    );
    check("model/tests/fixtures/valid/hdlc_like.yaml", "hdlc_like.rs");
    check("model/tests/fixtures/valid/cobs_link.yaml", "cobs_link.rs");
    check(
        "model/tests/fixtures/valid/dynamixel2_stuffed.yaml",
        "dynamixel2_stuffed.rs",
    );
    check("model/tests/fixtures/valid/xbee_api2.yaml", "xbee_api2.rs");
    check("model/tests/fixtures/valid/kiss.yaml", "kiss.rs");
    check(
        "model/tests/fixtures/valid/garmin_link.yaml",
        "garmin_link.rs",
    );
    check("model/tests/fixtures/valid/tsip.yaml", "tsip.rs");
}

/// FrSky F.Port v1: its CRC the end-around sum (`sum8_end_around`, `rt::sum8_end_around`) from
/// the length byte, 7E and 7D stuffed, a shared 7E flag, 16 packed 11-bit channels
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn end_around_sum_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/fport.yaml", "fport.rs");
}

/// F.Port's uplink data frames alone: escaped from the first byte to the last, without start
/// or end bytes, framed by the length field at offset 0 as the bytes unstuff
/// (`snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn escaped_without_start_or_end_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/fport_uplink.yaml",
        "fport_uplink.rs",
    );
}

/// F.Port both ways: requests between 7E flags, responses without start or end bytes,
/// escaped from their first byte to their last and framed by their length field
/// (`RESPONSE_ESCAPING`, `RESPONSE_FRAME`, `rt::escaped_lens_by_direction`;
/// `snapshots_compile.rs` compiles it and holds it to the interpreter).
#[test]
fn escaped_and_ended_by_direction_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/fport_both.yaml",
        "fport_both.rs",
    );
}

/// Responses sent unasked (`unasked: true`): `Response::is_unasked` and the
/// `ResponseMessage::is_unasked` override; `snapshots_compile.rs` compiles it and holds it to
/// the interpreter.
#[test]
fn unasked_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/unasked.yaml", "unasked.rs");
}

/// A response sent unasked whose list runs to the end of its frame, without a length field or
/// end bytes: `link-core/tests/unasked.rs` holds the master to it.
#[test]
fn unasked_to_end_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/unasked_to_end.yaml",
        "unasked_to_end.rs",
    );
}

/// A preamble of wake-up bytes (`framing.preamble`, DL/T 645's `FE FE FE FE`):
/// `snapshots_compile.rs` compiles it and holds it to the interpreter.
#[test]
fn preamble_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/dlt645.yaml", "dlt645.rs");
}

/// A length field whose width the start byte chooses (`framing.length.long`, VESC's
/// `02 len …` and `03 lenH lenL …`): `snapshots_compile.rs` compiles it and holds it to the
/// interpreter.
#[test]
fn long_length_spec_generates_its_snapshot() {
    check("model/tests/fixtures/valid/vesc.yaml", "vesc.rs");
}

/// Optional fields (`present:`), on a flag bit and on a value: `rt::Option` fields, the frame
/// laid out as if every one were present (`rt::Optionals`). `snapshots_compile.rs` compiles it
/// and holds it to the interpreter.
#[test]
fn optional_fields_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/optional_sensor.yaml",
        "optional_sensor.rs",
    );
}

/// Counted text (`type: ascii` with `repeat`), followed by fields: `rt::Repeated<u8, max>`
/// lent as text (`FieldValue::Text`). `snapshots_compile.rs` compiles it and holds it to the
/// interpreter.
#[test]
fn counted_text_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/text_counted.yaml",
        "text_counted.rs",
    );
}

/// Text up to a terminator (`repeat: {until: 0x00}`), one followed by fields and two in one
/// message: decoded through `rt::Lists` with `rt::CountBy::Until`. `snapshots_compile.rs`
/// compiles it and holds it to the interpreter.
#[test]
fn terminated_text_spec_generates_its_snapshot() {
    check(
        "model/tests/fixtures/valid/text_terminated.yaml",
        "text_terminated.rs",
    );
}
