//! The broken-spec fixture suite.
//!
//! `fixtures/valid/` holds two small, complete, valid specs: `minimal.yaml` (sum8, start byte,
//! little-endian wire, printed big-endian) and `minimal_crc.yaml` (CRC-16/CMS, code-first layout,
//! a `needs_request` pair). Every file in `fixtures/broken/` is one of them with one deliberate
//! defect (a few hold several on purpose, to prove all are reported at once). [`CASES`] says, for
//! each, exactly which diagnostics it must give: their number, each one's path, and a distinctive
//! part of each one's message. A fixture cannot pass through an unrelated error, and a new
//! fixture cannot be forgotten: every file in `fixtures/broken/` must have a row.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use busspec_model::ir::{ChecksumAlgorithm, Direction};
use busspec_model::{load_str, Diagnostics};

/// Fixture name → every diagnostic it must give, as (path, part of the message).
/// The number of diagnostics must equal the number of rows.
const CASES: &[(&str, &[(&str, &str)])] = &[
    // ---- a layout per direction (made from valid/shdlc, without its examples)
    (
        "layout_dir_broadcast_unaddressed_requests",
        &[("framing.address.broadcast", "requests carry no address (their layout has no `address`): none is a broadcast")],
    ),
    (
        "layout_dir_checksum_one_direction",
        &[("framing.layout.response", "the response's layout has no `checksum`, the other direction's has: `checksum` in one")],
    ),
    (
        "layout_dir_start_one_direction",
        &[("framing.layout.response", "the response's layout has no `start`, the other direction's has: `start` in one")],
    ),
    (
        "header_value_unfit",
        &[
            ("commands.read_basic_info.header.state", "0x1A5 does not fit in the 8-bit header field `state`"),
            ("commands.read_cell_voltages.header.mode", "no header field `mode` in requests; they carry `state`"),
            ("commands.read_version.header.status", "no header field `status` in requests; they carry `state`"),
        ],
    ),
    (
        "layout_dir_end_one_direction",
        &[("framing.layout.response", "the response's layout has no `end`, the other direction's has: `end` in one direction only")],
    ),
    (
        "layout_dir_length_one_direction",
        &[("framing.layout.response", "the response's layout has no `length`, the other direction's has: `length` in one")],
    ),
    (
        "layout_dir_fport_uplink_unstuffed",
        &[
            ("framing.layout.response", "the response's layout has no `start`, the other direction's has: `start` in one"),
            ("framing.layout.response", "the response's layout has no `end`, the other direction's has: `end` in one"),
        ],
    ),
    (
        "layout_dir_bare_responses_start_unescaped",
        &[("framing.escaping", "responses have no start or end bytes (their layout has neither): the requests' start and end bytes travel escaped so that none appears inside a response, and 0x7E does not")],
    ),
    (
        "layout_dir_counts_missing",
        &[("framing.length.counts", "counts `header`, which the layout does not have")],
    ),
    (
        "layout_dir_extra_covers_from_differs",
        &[("framing.checksum.extra", "the checksum covers from another offset in each direction: an extra byte per message is not")],
    ),
    (
        "layout_dir_header_direction_lacks",
        &[("framing.header.response", "`framing.header` needs a `header` part in the layout, where its fields sit")],
    ),
    (
        "layout_dir_covers_from_direction_lacks",
        &[("framing.checksum.covers_from.request", "the checksum cannot cover from `header`: name a part of the layout before the payload")],
    ),

    (
        "layout_dir_covers_from_missing",
        &[("framing.checksum.covers_from", "the checksum cannot cover from `header`: name a part of the layout before the payload")],
    ),
    (
        "layout_dir_end_order",
        &[("framing.layout.response", "end bytes before the checksum in one direction and after it in the other is not")],
    ),
    (
        "layout_dir_escaping_by_length",
        &[("framing.escaping", "escaping without an end byte (frames found by their length field) is not expressible with")],
    ),
    (
        "layout_dir_escaping_insert",
        &[("framing.escaping", "escaping by insertion is not expressible with a layout per direction (`framing.layout:")],
    ),
    (
        "layout_dir_header_without_section",
        &[("framing.layout.response", "layout has `header` but `framing.header` is missing")],
    ),
    (
        "layout_dir_second_length",
        &[("framing.layout.response", "a second `length` is not expressible with a layout per direction (`framing.layout:")],
    ),
    (
        "layout_dir_start_offsets",
        &[("framing.layout.response", "the start bytes sit at offset 0 in requests and 1 in responses: start bytes at another")],
    ),
    (
        "layout_dir_unknown_direction",
        &[("framing.layout", "unknown field `reply`, expected `request` or `response`")],
    ),
    (
        "layout_dir_with_forms",
        &[("framing.forms", "a short form of the frame is not expressible with a layout per direction")],
    ),
    (
        "layout_dir_with_long",
        &[("framing.length.long", "a long length form is not expressible with a layout per direction (`framing.layout:")],
    ),
    (
        "layout_dir_with_preamble",
        &[("framing.preamble", "a preamble is not expressible with a layout per direction (`framing.layout: {request,")],
    ),
    (
        "layout_dir_with_transform",
        &[("framing.transform", "a transform of the payload is not expressible with a layout per direction")],
    ),
    (
        "layout_dir_with_truncation",
        &[("framing.truncation", "payload truncation is not expressible with a layout per direction (`framing.layout:")],
    ),
    // ---- text up to a terminator (made from valid/text_terminated, without its examples)
    (
        "until_beside_text_without_length",
        &[
            ("responses.parameter.fields.label.repeat.until", "text up to a terminator without a length field (framing.length) must be its message's only repeated field: its terminator alone tells where the frame ends"),
            ("responses.parameter.fields.unit.repeat.until", "text up to a terminator without a length field (framing.length) must be its message's only repeated field"),
        ],
    ),
    (
        "until_without_length_escaped",
        &[("commands.set_threshold.fields.label.repeat.until", "text up to a terminator without a length field (framing.length) beside escaping (framing.escaping) is not expressible yet")],
    ),
    (
        "until_without_length_codeless",
        &[
            ("responses.firmware_version.fields.version.repeat.until", "text up to a terminator without a length field (framing.length) beside `name`, a variable-length message its code does not tell apart, is not expressible yet: a stream decoder frames one variable-length message per code"),
            ("responses.name.fields.name.repeat.until", "beside `firmware_version`, a variable-length message its code does not tell apart"),
        ],
    ),
    (
        "until_with_transform",
        &[
            ("commands.set_name.fields.name.repeat.until", "text up to a terminator beside a transform (framing.transform) is not expressible yet"),
            ("responses.device_info.fields.name.repeat.until", "text up to a terminator beside a transform (framing.transform) is not expressible yet"),
            ("responses.parameter.fields.label.repeat.until", "text up to a terminator beside a transform (framing.transform) is not expressible yet"),
            ("responses.parameter.fields.unit.repeat.until", "text up to a terminator beside a transform (framing.transform) is not expressible yet"),
        ],
    ),
    (
        "until_and_count",
        &[("commands.set_name.fields.name.repeat.count", "`until` and `count` are two ways to end a list: give one")],
    ),
    (
        "until_on_numbers",
        &[("responses.parameter.fields.value.repeat.until", "a terminator ends text (type: ascii)")],
    ),
    (
        "until_not_a_byte",
        &[("commands.set_name.fields.name.repeat.until", "a terminator is one byte, 0x00..=0xFF, not 256")],
    ),
    (
        "repeat_without_count",
        &[("commands.set_name.fields.name.repeat", "a repeat needs `count` (an earlier field, `end`, or a number of elements) or, for text, `until`")],
    ),
    // ---- preambles (made from valid/dlt645, hdlc_like and mbus_short, without their examples)
    (
        "preamble_start_byte",
        &[("framing.preamble.byte", "the preamble byte 0x68 is a start byte of the framing")],
    ),
    (
        "preamble_send_over_max",
        &[("framing.preamble.max", "a preamble cannot send more bytes than it accepts: send 5 > max 4")],
    ),
    (
        "preamble_too_long",
        &[("framing.preamble.send", "a preamble sends 0 to 16 bytes, not 17")],
    ),
    (
        "preamble_accepts_none",
        &[("framing.preamble.send", "a preamble accepts 1 to 16 bytes, not 0")],
    ),
    (
        "preamble_without_start",
        &[("framing.preamble", "a preamble needs frames that begin with start bytes")],
    ),
    (
        "preamble_with_escaping",
        &[("framing.preamble", "a preamble is not expressible with `escaping`, yet")],
    ),
    (
        "preamble_with_constant_frame",
        &[("responses.ack.frame", "a constant frame is not expressible with a preamble (framing.preamble), yet")],
    ),
    // ---- a length field whose width the start byte chooses (made from valid/vesc, without
    // its examples)
    (
        "long_not_wider",
        &[
            ("framing.length.long.width", "wider than the short one's 1 byte(s) and at most 2 bytes, not 1"),
            ("commands.write_new_app_data", "the length field would say 517, outside a 1-byte length's 0..=255"),
        ],
    ),
    (
        "long_too_wide",
        &[("framing.length.long.width", "wider than the short one's 1 byte(s) and at most 2 bytes, not 3")],
    ),
    (
        "long_same_start",
        &[("framing.length.long.start", "the long form's start byte 0x02 is the short form's")],
    ),
    (
        "long_unknown_key",
        &[("framing.length.long.adjust", "unknown field `adjust`, expected `start` or `width`")],
    ),
    (
        "long_start_sequence",
        &[("framing.length.long", "a long form needs one start byte, the same both ways (not a start sequence or start bytes by direction), yet")],
    ),
    (
        "long_start_by_direction",
        &[("framing.length.long", "a long form needs one start byte, the same both ways")],
    ),
    (
        "long_without_start",
        &[
            ("framing.length.long", "a long form needs a start byte (`start`)"),
            ("framing.layout", "needs the layout to begin with `start, length`"),
        ],
    ),
    (
        "long_length_twice",
        &[("framing.layout", "a second `start` or `length` beside a long length form (framing.length.long) is not expressible yet")],
    ),
    (
        "long_checksum_covers_length",
        &[("framing.checksum", "the checksum covers neither the start byte nor the length field")],
    ),
    (
        "long_counts_start",
        &[("framing.length.counts", "beside a long form (`long`), the length counts no `start`")],
    ),
    (
        "long_with_preamble",
        &[("framing.length.long", "a long length form beside `preamble` is not expressible yet")],
    ),
    (
        "long_with_escaping",
        &[("framing.length.long", "a long length form beside `escaping` is not expressible yet")],
    ),
    (
        "long_with_constant_frame",
        &[("responses.nak.frame", "a constant whole frame beside a long length form (framing.length.long) is not expressible yet")],
    ),
    (
        "long_printed_little",
        &[("printed_byte_order", "examples printed in another byte order beside a long length form (framing.length.long) are not expressible yet")],
    ),
    (
        "long_payload_too_long",
        &[("framing.request.payload", "payload length range 0..=5000 is invalid (0 <= min <= max <= 4096)")],
    ),
    // ---- lists of a fixed count (made from valid/packed_channels, without its examples)
    (
        "fixed_list_of_bits",
        &[("commands.calibrate.fields.offsets.type", "a list of a fixed count (`count: 3`) holds numbers (integers of 1 to 8 bytes, floats), each maybe of an enum or a unit, or records; bit elements are not expressible yet (a list counted by a field or to the `end` takes them)")],
    ),
    (
        "fixed_records_min",
        &[("responses.sat_blocks.fields.blocks.repeat.min", "a list of a fixed count of 3 holds 3 elements; `min: 1` says otherwise (leave it out)")],
    ),
    (
        "fixed_records_too_many",
        &[("responses.sat_blocks.fields.blocks.repeat.count", "a fixed count is 1..=256 elements, not 300")],
    ),
    (
        "fixed_records_sized",
        &[("responses.sat_blocks.fields.blocks.fields.azim.bytes", "a record whose width a field gives runs to the `end` of the frame (count: end); counted records of it are not expressible yet")],
    ),
    (
        "float_list_until",
        &[
            ("responses.samples.fields.samples.repeat.until", "a terminator ends text (type: ascii); a list of numbers is counted by a field or runs to the `end`"),
        ],
    ),
    (
        "fixed_list_with_value",
        &[("commands.calibrate.fields.offsets.value", "`value` cannot be combined with a list of a fixed count (not expressible yet)")],
    ),
    (
        "fixed_list_max_differs",
        &[("commands.calibrate.fields.gains.repeat.max", "a list of a fixed count of 2 holds 2 elements; `max: 4` says otherwise (leave it out)")],
    ),
    (
        "fixed_list_zero",
        &[("commands.calibrate.fields.offsets.repeat.count", "a fixed count is 1..=256 elements, not 0")],
    ),
    (
        "fixed_list_of_bytes",
        &[("commands.calibrate.fields.offsets.repeat.of", "`of` says what a count field counts; a fixed count is of elements")],
    ),
    (
        "repeat_without_max",
        &[("commands.calibrate.fields.gains.repeat", "missing field `max` (the most elements a frame may carry; only a fixed count, `count: 4`, needs none)")],
    ),
    (
        "escaped_payload_too_long",
        &[("framing.response.payload", "payload length range 0..=5000 is invalid (0 <= min <= max <= 4096; a frame without a length field is bounded by this range, and every decoder's buffer by it)")],
    ),
    (
        "payload_past_one_byte_length",
        &[("framing.response.payload", "payload length range 1..=300 is invalid (0 <= min <= max <= 255; a one-byte length field counts at most 255 bytes, a two-byte one or a long form (`framing.length.long`) up to 4096)")],
    ),
    // ---- a short form of the frame (made from valid/mbus, without its examples)
    (
        "forms_same_start",
        &[("framing.forms[0].start", "the form's start byte 0x68 is the layout's own")],
    ),
    (
        "forms_two",
        &[("framing.forms", "one short form beside the layout's own is expressible yet, not 2")],
    ),
    (
        "forms_drops_code",
        &[("framing.forms[0].drops", "a form drops `length` and perhaps the second `start`, not `code`")],
    ),
    (
        "forms_drops_twice",
        &[("framing.forms[0].drops", "`length` dropped twice")],
    ),
    (
        "forms_keeps_length",
        &[("framing.forms[0].drops", "a form drops the length field (`length`)")],
    ),
    (
        "forms_keeps_second_start",
        &[("framing.forms[0].drops", "the layout's second `start` stays in the short form")],
    ),
    (
        "forms_drops_start_once",
        &[("framing.forms[0].drops", "the layout holds the start byte once: only a second `start` can be dropped")],
    ),
    (
        "forms_drops_apart",
        &[("framing.layout", "a frame form drops parts that sit together after the first start byte")],
    ),
    (
        "forms_without_length",
        &[("framing.forms", "a frame form needs a length field (`length`) in the layout")],
    ),
    (
        "forms_checksum_covers_length",
        &[("framing.checksum", "beside a frame form (framing.forms), the checksum covers neither the start byte nor the parts the form drops")],
    ),
    (
        "forms_two_code_lengths",
        &[
            ("framing.layout", "the code comes before the address"),
            ("framing.forms", "a frame form needs one code length, the same both ways"),
        ],
    ),
    (
        "forms_start_sequence",
        &[("framing.forms", "a frame form needs one start byte, the same both ways")],
    ),
    (
        "forms_with_preamble",
        &[
            ("framing.forms", "a frame form (framing.forms) beside preamble is not expressible yet"),
            ("responses.ack.frame", "a constant frame is not expressible with a preamble"),
        ],
    ),
    (
        "forms_with_transform",
        &[("framing.forms", "a frame form (framing.forms) beside transform is not expressible yet")],
    ),
    (
        "forms_with_long",
        &[
            ("framing.layout", "a second `start` or `length` beside a long length form"),
            ("framing.forms", "a frame form (framing.forms) beside a long length form (framing.length.long) is not expressible yet"),
        ],
    ),
    (
        "forms_constant_frame_start",
        &[("responses.ack.frame", "a constant frame cannot begin with 0x10, a start byte of the framing")],
    ),
    (
        "forms_printed_big",
        &[("printed_byte_order", "examples printed in another byte order beside a frame form (framing.forms) are not expressible yet")],
    ),
    (
        "forms_unknown_key",
        &[("framing.forms[0].stop", "unknown field `stop`, expected one of `section`, `start`, `drops`")],
    ),
    // ---- payload truncation (made from valid/mavlink_v2, without its examples)
    (
        "truncation_without_length",
        &[("framing.truncation", "payload truncation needs a length field (framing.length)")],
    ),
    (
        "truncation_with_list",
        &[("responses.raw_rpm", "beside payload truncation (framing.truncation) every message has one length")],
    ),
    (
        "truncation_code_payloads_differ",
        &[("responses.ping_reply", "a request and a response of one code have one payload length")],
    ),
    (
        "truncation_unknown_kind",
        &[("framing.truncation", "unknown variant `leading_zeros`, expected `trailing_zeros`")],
    ),
    (
        "truncation_printed_big",
        &[("printed_byte_order", "examples printed in another byte order beside payload truncation (framing.truncation) are not expressible yet")],
    ),
    (
        "truncation_with_end",
        &[("framing.truncation", "payload truncation beside end bytes is not expressible yet")],
    ),
    // ---- transforms (made from valid/dlt645, hdlc_like, pelco_d_codeless and minimal_end,
    // without their examples)
    (
        "transform_add_zero",
        &[("framing.transform.add", "a transform with `add: 0` changes no byte")],
    ),
    (
        "transform_xor_zero",
        &[("framing.transform.xor", "a transform with `xor: 0` changes no byte")],
    ),
    (
        "transform_add_and_xor",
        &[("framing.transform", "a transform either adds (`add`) or XORs (`xor`) a byte, not both")],
    ),
    (
        "transform_neither",
        &[("framing.transform", "a transform needs `add` or `xor`")],
    ),
    (
        "transform_unknown_key",
        &[("framing.transform.sub", "unknown field `sub`, expected one of `section`, `add`, `xor`")],
    ),
    (
        "transform_too_wide",
        &[("framing.transform.add", "a transform's addend 307 does not fit in one byte")],
    ),
    (
        "counted_text_with_length",
        &[("commands.set_name.fields.name.length", "`length` cannot be combined with `repeat`: the count field gives the text's length, `repeat.max` its most")],
    ),
    (
        "counted_text_with_unit",
        &[("commands.set_name.fields.name.unit", "`unit` cannot be combined with an ascii field")],
    ),
    (
        "transform_with_escaping",
        &[("framing.transform", "a transform is not expressible with `escaping`, yet")],
    ),
    (
        "transform_code_lengths",
        &[("framing.transform", "a transform needs every code of one length (the payload at one offset), not 0 and 2, yet")],
    ),
    (
        "transform_counted_list",
        &[("commands.write.fields.values", "a list counted by a field beside a transform (framing.transform) needs a length field (framing.length), yet")],
    ),
    (
        "delimited_with_transform",
        &[
            ("commands.instruction.fields.text", "a list to the end of a frame that end bytes alone delimit (no length field, no checksum) beside a transform (framing.transform) is not expressible yet"),
            ("responses.string.fields.text", "a list to the end of a frame that end bytes alone delimit (no length field, no checksum) beside a transform (framing.transform) is not expressible yet"),
        ],
    ),
    // ---- messages without a checksum (made from valid/roboclaw)
    (
        "unchecked_told_apart",
        &[
            ("responses.status.checksum", "reset_encoders can have the same code and length, and carries a checksum: a message without one must be told apart by its code and length alone"),
            ("responses.main_battery.checksum_over_request", "status can have the same code and length, and its checksum covers other bytes"),
            ("responses.logic_battery.checksum_over_request", "status can have the same code and length, and its checksum covers other bytes"),
            ("responses.temperature.checksum_over_request", "status can have the same code and length, and its checksum covers other bytes"),
        ],
    ),
    (
        "unchecked_empty",
        &[("responses.ack.checksum", "without its checksum the message's frame holds no byte (no start byte, address, code or field): nothing would travel")],
    ),
    (
        "unchecked_beside",
        &[
            ("commands.read_status.checksum", "a message without a checksum has one length yet: it takes no repeated or optional field"),
            ("responses.status.checksum", "a message without a checksum is not expressible beside `checksum_over_request` yet"),
        ],
    ),
    // ---- a reply's checksum over its request's bytes (made from valid/pelco_d_replies)
    (
        "over_request_told_apart",
        &[
            ("responses.general_response.checksum_over_request", "busy can have the same code and length, and its checksum covers other bytes: a reply whose checksum takes in its request's bytes must be told apart by its code and length alone"),
            ("responses.busy", "duplicate code: `general_response` (no code) and `busy` (no code) have the same length and no constant field tells them apart (if only the request can tell them apart, mark both `needs_request: true`)"),
        ],
    ),
    (
        "over_request_with_escaping",
        &[("responses.general_response.checksum_over_request", "a checksum over the request's bytes is not expressible beside escaping (`framing.escaping`) yet")],
    ),
    (
        "over_request_example",
        &[
            ("examples[1].request", "§5 general_response: the checksum of `general_response` takes in its request's bytes: give the request's frame with `request` (and the command with `reply_to`)"),
            ("examples[3].request", "§5 general_response: the request decodes as `ptz`, not `set_auxiliary`"),
        ],
    ),
    // ---- optional fields (made from valid/optional_sensor, without its examples)
    (
        "optional_with_escaping",
        &[
            ("responses.reading.fields.humidity.present", "optional fields with `escaping` are not expressible yet"),
            ("responses.event.fields.detail.present", "optional fields with `escaping` are not expressible yet"),
        ],
    ),
    (
        "optional_code_from_request",
        &[("responses.event.fields.detail.present", "optional fields in a message whose code comes from the request are not expressible yet")],
    ),
    (
        "optional_beside_list",
        &[
            ("responses.event.fields.log", "a field after the optional field `detail`: optional fields end the message, yet"),
            ("responses.event.fields.detail.present", "optional fields beside a repeated field (`log`) are not expressible yet"),
        ],
    ),
    (
        "optional_bit_and_equals",
        &[
            ("responses.event.fields.detail.present", "`present` takes exactly one of `bit` and `equals` beside `field`"),
        ],
    ),
    (
        "optional_bit_outside",
        &[
            ("responses.reading.fields.humidity.present.bit", "bit 8 is outside `status`'s bits 0..=7"),
        ],
    ),
    (
        "optional_condition_later",
        &[
            ("responses.reading.fields.humidity.present.field", "`pressure` comes later: a condition reads a field before the optional one"),
        ],
    ),
    (
        "optional_condition_missing",
        &[
            ("responses.reading.fields.humidity.present.field", "no field `stat` before this one"),
        ],
    ),
    (
        "optional_condition_optional",
        &[
            ("responses.reading.fields.pressure.present.field", "`humidity` is an optional field: a condition reads an unsigned binary integer that is always on the wire"),
        ],
    ),
    (
        "optional_condition_signed",
        &[
            ("responses.reading.fields.humidity.present.field", "`temperature` is signed"),
        ],
    ),
    (
        "optional_constant",
        &[
            ("responses.event.fields.detail.value", "`value` cannot be combined with `present`: an optional field is a plain number of a fixed width"),
        ],
    ),
    (
        "optional_equals_too_wide",
        &[
            ("responses.event.fields.detail.present.equals", "256 does not fit `kind` (0..=255)"),
        ],
    ),
    (
        "optional_field_after",
        &[
            ("responses.reading.fields.battery", "a field after the optional field `humidity`: optional fields end the message, yet"),
        ],
    ),
    (
        "optional_in_header",
        &[
            ("framing.header.seq.present", "`present` cannot be used in a header field"),
        ],
    ),
    (
        "optional_in_record",
        &[
            ("responses.event.fields.recs.fields.a.present", "`present` cannot be used in a record's field"),
            ("responses.event.fields.recs", "a field after the optional field `detail`"),
            ("responses.event.fields.detail.present", "optional fields beside a repeated field (`recs`) are not expressible yet"),
        ],
    ),
    (
        "optional_shared_code",
        &[
            ("responses.reading.fields.humidity.present", "optional fields in a message whose code `0x81` `event` shares are not expressible yet"),
            ("responses.event.fields.detail.present", "optional fields in a message whose code `0x81` `reading` shares are not expressible yet"),
            ("responses.event", "duplicate code: `reading` (0x81) and `event` (0x81)"),
        ],
    ),
    (
        "optional_text",
        &[
            ("responses.event.fields.detail.type", "an optional field (`present`) is a number of a fixed width"),
        ],
    ),
    (
        "optional_too_many",
        &[
            ("responses.reading.fields", "5 optional fields; a message has at most 4"),
        ],
    ),
    (
        "optional_without_length_field",
        &[
            ("responses.reading.fields.humidity.present", "optional fields need a length field (framing.length)"),
            ("responses.event.fields.detail.present", "optional fields need a length field (framing.length)"),
        ],
    ),
    // ---- constant whole frames (made from valid/mbus_short, without its examples)
    (
        "constant_frame_not_hex",
        &[("responses.ack.frame", "a constant frame is hex bytes: `G` at character 4 is not a hex digit")],
    ),
    (
        "constant_frame_empty",
        &[("responses.ack.frame", "a constant frame is 1 to 16 bytes, not 0")],
    ),
    (
        "constant_frame_too_long",
        &[("responses.ack.frame", "a constant frame is 1 to 16 bytes, not 17")],
    ),
    (
        "constant_frame_with_code_and_fields",
        &[
            ("responses.ack.code", "a constant frame (`frame`) is its bytes alone: it takes no `code`"),
            ("responses.ack.fields", "a constant frame (`frame`) is its bytes alone: it takes no `fields`"),
        ],
    ),
    (
        "constant_frames_same",
        &[("responses.ack.frame", "the same constant frame as response `ack_again`")],
    ),
    (
        "constant_frames_prefix",
        &[("responses.ack.frame", "constant frame E5 and response `ack_again`'s E5 01: one is a prefix of the other")],
    ),
    (
        "constant_frame_start_byte",
        &[("responses.ack.frame", "a constant frame cannot begin with 0x10, a start byte of the framing")],
    ),
    (
        "constant_frame_without_start",
        &[("responses.ack.frame", "a constant frame needs frames that begin with start bytes")],
    ),
    (
        "response_without_code",
        &[("responses.status_of_link", "missing field `code` (a response without one is a constant whole frame: `frame`)")],
    ),
    // ---- repeated records (made from valid/records, without its examples)
    (
        "record_without_repeat",
        &[("commands.sync_write.fields.blocks.type", "a `record` is only the element of a repeated field")],
    ),
    (
        "record_field_repeated",
        &[("commands.sync_write.fields.blocks.fields.id.repeat", "`repeat` cannot be used in a record's field")],
    ),
    (
        "record_field_not_fixed",
        &[("commands.sync_write.fields.blocks.fields.id.type", "a record's field is an integer of 8 to 32 bits")],
    ),
    (
        "record_field_duplicate",
        &[("commands.sync_write.fields.blocks.fields.id", "duplicate field name `id` in the record")],
    ),
    (
        "record_empty",
        &[("commands.sync_write.fields.blocks.fields", "a record needs at least one field")],
    ),
    (
        "record_with_unit",
        &[("commands.sync_write.fields.blocks.unit", "`unit` cannot be combined with a record")],
    ),
    (
        "fields_without_record",
        &[("commands.sync_write.fields.flags.fields", "`fields` is only for a `type: record`")],
    ),
    (
        "record_field_without_unit",
        &[("commands.sync_write.fields.blocks.fields.id", "a number field needs a `unit`")],
    ),
    // ---- records whose width a field gives (made from valid/records_sized, without its
    // examples)
    (
        "record_bytes_not_last",
        &[("commands.sync_write.fields.blocks.fields.data.bytes", "only a record's last field takes its bytes from another field")],
    ),
    (
        "record_bytes_unknown",
        &[("commands.sync_write.fields.blocks.fields.data.bytes", "refers to `data_size`, which is not an earlier field of this message")],
    ),
    (
        "record_bytes_counted",
        &[("commands.sync_write.fields.blocks.fields.data.bytes", "a record whose width a field gives runs to the `end` of the frame")],
    ),
    (
        "record_bytes_plain_field",
        &[("commands.sync_write.fields.start_address.bytes", "`bytes` is only for a record's last field")],
    ),
    (
        "record_bytes_field_after",
        &[("commands.sync_write.fields.blocks.fields.data.bytes", "is the message's only repeated field and its last field")],
    ),
    (
        "record_bytes_signed_width",
        &[("commands.trim.fields.offsets.fields.offset.bytes", "`width` is not an unsigned number field the sender sets")],
    ),
    (
        "record_bytes_by_request",
        &[("responses.trim_reply.fields.vals.fields.v.bytes", "take no count from the request")],
    ),
    (
        "record_bytes_without_length",
        &[
            ("commands.sync_write.fields.blocks.fields.data.bytes", "needs a length field (framing.length)"),
            ("commands.trim.fields.offsets.fields.offset.bytes", "needs a length field (framing.length)"),
        ],
    ),
    // ---- escaping and stuffing (made from valid/slip_sensor, hdlc_like, cobs_link and
    // dynamixel2_stuffed, without their examples)
    (
        "escaping_two_kinds",
        &[("framing.escaping", "give exactly one kind: `escape` (SLIP, KISS, HDLC), `insert` (Dynamixel 2.0) or `cobs`")],
    ),
    (
        "escaping_escape_not_listed",
        &[("framing.escaping.escape", "the escape byte 0x7D must itself travel escaped: list it")],
    ),
    (
        "escaping_replacement_escaped",
        &[("framing.escaping.map", "0xC0 travels as 0xDB, a byte that is itself escaped")],
    ),
    // DLE stuffing (made from valid/garmin_link, without its examples)
    (
        "dle_without_two_byte_end",
        &[("framing.escaping.map", "0x10 travels doubled (0x10 0x10): frames then end in two `end` bytes, the escape byte and a byte no escape stands for")],
    ),
    (
        "dle_end_replacement",
        &[("framing.end", "0x10 0x03 also stands for 0x02 inside a frame: the byte after the escape byte that ends a frame must be no replacement")],
    ),
    (
        "dle_end_doubled",
        &[("framing.end", "0x10 0x10 is a doubled escape byte, not an end")],
    ),
    (
        "dle_doubled_other_byte",
        &[("framing.escaping.map", "0xC0 travels as 0xC0, a byte that is itself escaped")],
    ),
    (
        "escaping_without_end",
        &[("framing.escaping", "escaped frames end in one `end` byte (the last part of the layout) that travels escaped inside them")],
    ),
    (
        "escaping_length_moves",
        &[("framing.escaping", "or, without `end`, carry a length field at one offset (before the code, or every code one length)")],
    ),
    (
        "escaping_computed_escaped",
        &[("framing.escaping.computed", "they are computed on the frame before escaping (`computed: unescaped`)")],
    ),
    (
        "stuffing_computed_unescaped",
        &[("framing.escaping.computed", "stuffed frames are framed by their length field: it and the checksum count the stuffed bytes")],
    ),
    (
        "stuffing_from_payload",
        &[("framing.escaping.from", "stuffing from `payload`: name the address or the code, after the length field")],
    ),
    (
        "stuffing_length_not_counting_code",
        &[("framing.length.counts", "the length field counts the stuffed bytes: it must count `code`")],
    ),
    (
        "cobs_end_not_zero",
        &[("framing.escaping", "COBS frames end in the end byte 0x00 (`end: 0x00`, the last part of the layout)")],
    ),
    // ---- checksum coverage from a part after codes of two lengths (made from valid/msp_v1.yaml)
    (
        "header_by_direction_one_layout",
        &[("framing.header", "header fields per direction (`{request: [...], response: [...]}`) need a layout per direction")],
    ),
    (
        "covers_from_by_direction_one_layout",
        &[("framing.checksum.covers_from", "a part per direction (`{request: ..., response: ...}`) needs a layout per direction")],
    ),
    (
        "covers_from_after_codes_of_two_lengths",
        &[("framing.checksum.covers_from", "the checksum cannot cover from `length`: it comes after the code, whose lengths [1, 2] would move it")],
    ),
    // ---- commands that get no reply (made from valid/minimal.yaml)
    (
        "reply_none_with_responses",
        &[("commands.go_to.responses", "a command with `reply: none` gets no response: list none")],
    ),
    (
        "reply_none_answered_on_broadcast",
        &[
            ("commands.get_status.broadcast", "a command with `reply: none` is not answered on broadcast either"),
            ("responses.status", "no command lists this response"),
        ],
    ),
    // ---- the `device:` section (made from valid/minimal.yaml)
    (
        "device_defects",
        &[
            ("device.spaces[0].size", "size 0: a space holds 1 to 1048576 elements"),
            ("device.spaces[1].type", "a space holds integers or bits"),
            ("device.spaces[2].initial[0].values", "3 values from element 6 run past the space's 8 elements"),
            ("device.commands[0].command", "unknown command `go_too`"),
            ("device.refuse.outside.fields.nope", "`nak` has no field `nope`"),
            ("device.commands[2].command", "`go_to` is listed twice"),
            ("device.commands[3].reads", "unknown space `nowhere`"),
            ("device.commands[4]", "a command reads, writes, commits or resets: one of them"),
        ],
    ),
    (
        "device_reads_at",
        &[
            ("device.commands[0].at.firmware", "`status.firmware` is not a single integer of up to 4 bytes"),
            ("device.commands[0].at.nope", "`status` has no field `nope`"),
            ("device.commands[0].at.position_word", "`status.position_word` is not a single integer of up to 4 bytes"),
            ("device.commands[0].at.temperature", "element 8 is past the end of `regs` (8 elements)"),
            ("device.commands[1].at.target", "`started` has no field `target`"),
            ("device.commands[2].at", "`at` belongs to a read"),
            ("device.commands[2].listed", "`set_mode` has no repeated field `mode` of addresses"),
        ],
    ),
    // ---- the `transactions:` section (made from valid/minimal.yaml)
    (
        "transactions_unknown_command",
        &[("transactions.retry.unsafe[0]", "unknown command `get_statuz`")],
    ),
    (
        "transactions_retry_redundant",
        &[
            ("transactions.retry.safe[0]", "`get_status` is a getter command, which is safe by its kind already"),
            ("transactions.retry.unsafe[0]", "`go_to` is a movement command, which is unsafe by its kind already"),
        ],
    ),
    (
        "transactions_timeout_zero",
        &[
            ("transactions.response_timeout_ms", "0 ms: must be positive"),
            ("transactions.turnaround_ms", "0.0005 ms is not a whole number of microseconds"),
        ],
    ),
    (
        "transactions_gap_disagrees",
        &[(
            "transactions.inter_frame_gap.characters",
            "3.5 character times at 9600 baud (10 bits each) are 3.646 ms, but serial.inter_frame_gap_ms says 10 ms",
        )],
    ),
    (
        "transactions_gap_characters_bad",
        &[
            ("transactions.inter_frame_gap.characters", "3.25 character times: give tenths at most"),
            ("transactions.inter_frame_gap.at_least_ms", "-1 ms: must be 0 or more"),
            ("transactions.retry.safe_kinds[1]", "getter is listed twice"),
        ],
    ),
    (
        "transactions_unknown_key",
        &[("transactions.response_timeout", "unknown field `response_timeout`")],
    ),
    // ---- checksums: none, masks, Fletcher (made from valid/minimal.yaml)
    (
        "checksum_without_layout_part",
        &[("framing.checksum", "a checksum is described but the layout has no `checksum`")],
    ),
    (
        "checksum_part_without_section",
        &[("framing.checksum", "layout has `checksum` but no `checksum` section describes it")],
    ),
    (
        "checksum_lead_covers_before_it",
        &[("framing.checksum.covers_from", "the checksum covers from `start`, before it, to the frame's end, skipping itself: over two spans only a sum or XOR (sum8, xor8, sum16, their inverted or negated forms, lrc; masked, or followed by its complement) is expressible yet, not sum8_end_around")],
    ),
    (
        "complement_on_a_crc",
        &[("framing.checksum.complement", "a complement byte follows an 8-bit sum or XOR (sum8, sum8_ones_complement, sum8_twos_complement, sum8_end_around, lrc, xor8; width 8), not this checksum")],
    ),
    (
        "complement_with_byte_order",
        &[("framing.checksum.byte_order", "a checksum followed by its complement sends its value first: it takes no byte order")],
    ),
    (
        "checksum_lead_without_covers_from",
        &[("framing.checksum.covers_from", "the checksum comes before the payload and covers from a part after it to the frame's end: say which (`covers_from`)")],
    ),
    (
        "mask_on_a_crc",
        &[("framing.checksum.mask", "a mask keeps some bits of a sum or XOR")],
    ),
    (
        "fletcher8_eight_bits",
        &[("framing.checksum.width", "fletcher8 is 16 bits wide")],
    ),
    (
        "sum16_complement_eight_bits",
        &[("framing.checksum.width", "sum16_twos_complement is 16 bits wide")],
    ),
    (
        "sum8_end_around_sixteen_bits",
        &[("framing.checksum.width", "sum8_end_around is 8 bits wide")],
    ),
    (
        "sum8_end_around_plain_check",
        &[("framing.checksum.check", "check value 0x22 does not match the parameters, which give 0x21 over \"123456789\"")],
    ),
    (
        "mask_zero",
        &[("framing.checksum.mask", "a mask of 0 keeps no bit")],
    ),
    // ---- end bytes after the checksum (made from valid/minimal.yaml)
    (
        "end_before_payload",
        &[("framing.layout", "`end` must be the last part of the frame, or come just before the checksum")],
    ),
    (
        "end_without_bytes",
        &[("framing.end", "layout has `end` but no end byte is given")],
    ),
    (
        "end_bytes_without_layout_part",
        &[("framing.end", "an end byte is given but the layout has no `end`")],
    ),
    (
        "end_too_long",
        &[("framing.end", "end bytes are 1 to 4 bytes, found 5")],
    ),
    // ---- frames without an address (made from valid/minimal.yaml)
    (
        "address_without_layout_part",
        &[("framing.address", "addresses are described but the layout has no `address`")],
    ),
    (
        "address_part_without_addresses",
        &[("framing.address", "layout has `address` but no `address` section")],
    ),
    (
        "address_twice",
        &[("framing.layout", "layout holds `address` more than once")],
    ),
    // ---- the variable-length language (fixtures made from valid/minimal_variable.yaml)
    (
        "length_width_too_wide",
        &[("framing.length.width", "a length field is 1 or 2 bytes, not 3")],
    ),
    (
        "length_without_layout_part",
        &[("framing.length", "a length field is described but the layout has no `length`")],
    ),
    (
        "length_counts_part_twice",
        &[("framing.length.counts", "`start` listed twice")],
    ),
    (
        "sync_too_long",
        &[("framing.start", "a sync sequence is 1 to 4 bytes, found 5")],
    ),
    // ---- a start and a length sent twice (made from valid/ft12_variable.yaml)
    (
        "length_three_times",
        &[("framing.layout", "layout holds `length` more than twice")],
    ),
    (
        "second_length_after_code",
        &[("framing.layout", "a second `length` after the code needs every code to have one length, not [1, 2]: the code's length would move it")],
    ),
    (
        "second_start_after_payload",
        &[("framing.layout", "a second `start` must come before the payload")],
    ),
    (
        "repeated_with_escaping",
        &[
            ("framing.layout", "a second `start` is not expressible with `escaping` yet"),
            ("framing.layout", "a second `length` is not expressible with `escaping` yet"),
        ],
    ),
    // ---- BCD beside packed elements and records (made from valid/packed_channels.yaml and
    // valid/records.yaml, without their examples)
    (
        "packed_bcd",
        &[("commands.channels.fields.channels.encoding", "`encoding` cannot be combined with `packed`")],
    ),
    (
        "record_field_bcd",
        &[("commands.sync_write.fields.blocks.fields.id.encoding", "`encoding` cannot be used in a record's field (each is a plain number of a fixed width)")],
    ),
    // ---- BCD fields (made from valid/bcd_meter.yaml, without its examples)
    (
        "bcd_signed",
        &[("commands.set_clock.fields.year.encoding", "`encoding: bcd` is for unsigned fields of 1 to 4 bytes (u8 u16 u24 u32)")],
    ),
    (
        "bcd_range_past_digits",
        &[("commands.set_clock.fields.minute.range.max", "max 100 does not fit the field: its 2 BCD digits hold 0..=99")],
    ),
    (
        "bcd_with_special",
        &[("responses.energy.fields.tariff.special", "`special` cannot be combined with `encoding: bcd` (not expressible yet)")],
    ),
    (
        "bcd_without_unit",
        &[("commands.set_clock.fields.year", "a BCD field needs a `unit`")],
    ),
    // ---- header fields every message carries (made from valid/mavlink_v1.yaml, without its examples)
    (
        "header_not_in_layout",
        &[("framing.header", "`framing.header` needs a `header` part in the layout, where its fields sit")],
    ),
    (
        "header_missing",
        &[("framing.layout", "layout has `header` but `framing.header` is missing")],
    ),
    (
        "header_constant_unfit",
        &[
            ("framing.header.sequence.unit", "`unit` cannot be combined with a constant `value`"),
            ("framing.header.sysid.value", "constant 0x1FF does not fit in a 8-bit field"),
            ("commands.ping.header.compid", "header field `compid` is a constant of framing.header (0x01): every message carries it"),
        ],
    ),
    (
        "header_float",
        &[("framing.header.sysid.type", "a header field is an integer of 1 to 4 bytes")],
    ),
    (
        "header_name_clash",
        &[("responses.heartbeat.fields.sysid", "duplicate field name `sysid` (a header field every message carries: framing.header)")],
    ),
    (
        "header_sub_field_name_clash",
        &[("responses.api_version_reply.fields.dont_reply", "duplicate field name `dont_reply` (a header field every message carries: framing.header)")],
    ),
    (
        "header_after_payload",
        &[("framing.layout", "`header` must come before the payload")],
    ),
    // ---- header fields in several places (`part`; made from valid/novatel_oem.yaml, without its examples)
    (
        "header_part_out_of_order",
        &[("framing.header.port_address.part", "part 2 after a field of part 3: list the fields in layout order")],
    ),
    (
        "header_parts_unfilled",
        &[("framing.header", "the layout holds `header` 3 times and the fields fill 2: give each part its fields (`part: N`)")],
    ),
    (
        "header_part_empty",
        &[("framing.header.message_type.part", "`header` part 2 holds no field: every `header` of the layout holds at least one")],
    ),
    (
        "header_part_beyond",
        &[("framing.header.software_version.part", "part 4 is not one of the layout's `header` parts, 1 to 3")],
    ),
    (
        "header_part_without_part",
        &[("framing.header.sequence.part", "a field after those of `header` part 2 needs its `part`: fields are listed in layout order")],
    ),
    (
        "header_parts_side_by_side",
        &[("framing.layout", "two `header` parts side by side: one `header` holds all their fields")],
    ),
    (
        "header_part_in_message",
        &[("responses.bestpos.fields.datum.part", "`part` places a header field (framing.header) in one of the layout's `header` parts: other fields sit in the payload")],
    ),
    (
        "header_parts_too_many",
        &[("framing.layout", "layout holds `header` 5 times: at most 4")],
    ),
    (
        "header_part_one_header",
        &[("framing.header.message_type.part", "part 2: the layout holds `header` once, so every field sits in part 1 (leave `part` out)")],
    ),
    (
        "header_counts_a_list",
        &[("responses.heartbeat.fields.extra", "refers to `compid`, a header field (framing.header)")],
    ),
    // ---- a checksum's extra byte per message (made from valid/crc_extra.yaml)
    (
        "crc_extra_not_a_crc",
        &[("framing.checksum.extra", "an extra byte per message is taken by a CRC only (MAVLink's CRC_EXTRA)")],
    ),
    (
        "crc_extra_missing",
        &[("commands.request_data_stream.checksum_extra", "missing: `framing.checksum.extra: per_message` wants each message's byte")],
    ),
    (
        "crc_extra_without_framing",
        &[
            ("commands.ping.checksum_extra", "a message's checksum extra byte needs `framing.checksum.extra: per_message`"),
            ("commands.request_data_stream.checksum_extra", "a message's checksum extra byte needs `framing.checksum.extra: per_message`"),
            ("responses.ping_reply.checksum_extra", "a message's checksum extra byte needs `framing.checksum.extra: per_message`"),
            ("responses.heartbeat.checksum_extra", "a message's checksum extra byte needs `framing.checksum.extra: per_message`"),
        ],
    ),
    (
        "crc_extra_differs_by_direction",
        &[("responses.ping_reply.checksum_extra", "238 differs from 237, ping's, which has the same code: the extra byte is found by the code")],
    ),
    (
        "crc_extra_too_large",
        &[("responses.heartbeat.checksum_extra", "a checksum extra byte 300 does not fit in one byte (0..=255)")],
    ),
    (
        "crc_extra_code_not_covered",
        &[("framing.checksum.extra", "the checksum must cover the code, by which its extra byte is found")],
    ),
    // ---- start bytes by direction (made from valid/msp_by_direction.yaml)
    (
        "start_by_direction_lengths_differ",
        &[("framing.start", "the start bytes of both directions must be as many (every offset after them is shared), found 3 for requests and 2 for responses")],
    ),
    (
        "start_by_direction_same",
        &[("framing.start", "the start bytes of both directions are the same: give them once")],
    ),
    (
        "start_by_direction_escaped",
        &[("framing.start", "start bytes that differ by direction are not expressible with `escaping` yet")],
    ),
    (
        "start_by_direction_misspelt",
        &[("framing.start", "unknown field `reply`, expected `request` or `response`")],
    ),
    (
        "start_by_direction_not_bytes",
        &[("framing.start", "expected a byte (0x7E) or a list of bytes ([0xFF, 0xFF])")],
    ),
    (
        "start_by_direction_empty",
        &[
            ("framing.start.request", "a sync sequence is 1 to 4 bytes, found 0"),
            ("framing.start.response", "a sync sequence is 1 to 4 bytes, found 0"),
        ],
    ),
    (
        "start_not_bytes",
        &[("framing.start", "expected a start byte, a list of start bytes, or `{request: [...], response: [...]}`")],
    ),
    (
        "covers_from_payload",
        &[("framing.checksum.covers_from", "cannot cover from `payload`")],
    ),
    (
        "xor8_with_crc_params",
        &[("framing.checksum.poly", "`poly` is a CRC parameter; xor8 takes none")],
    ),
    (
        "xor8_check_mismatch",
        &[("framing.checksum.check", "check value 0x32 does not match the parameters, which give 0x31")],
    ),
    (
        "repeat_end_not_last",
        &[("commands.write.fields.values.repeat.count", "a repeat to the `end` must be the last repeated field (the fields after it must have a fixed size)")],
    ),
    // ---- several lists (made from valid/lists_after.yaml)
    (
        "repeat_end_beside_list_without_length",
        &[("commands.copy.fields.targets.repeat.count", "a repeat to the `end` beside another repeated field needs a length field (framing.length): without one a stream decoder cannot tell where the frame ends")],
    ),
    (
        "equals_repeated_field",
        &[("commands.write_block.fields.flags.equals", "`values` is a repeated field; a field repeats one earlier value")],
    ),
    (
        "repeat_count_shared",
        &[("commands.copy.fields.targets.repeat.count", "`na` already counts another repeated field; each list has a count field of its own")],
    ),
    (
        "repeat_count_undefined",
        &[("commands.write.fields.values.repeat.count", "refers to `bytecount`, which is not an earlier field")],
    ),
    (
        "repeat_max_zero",
        &[("responses.read_reply.fields.values.repeat.max", "a repeat's maximum is 1..=65535 elements, not 0")],
    ),
    (
        "repeat_too_long_for_payload",
        &[("commands.write.fields", "(and up to 60 more in the repeated field), but request payloads are 0..=40 bytes")],
    ),
    // ---- packed elements (made from valid/packed_channels, without its examples)
    (
        "packed_bits_too_wide",
        &[("commands.levels.fields.levels.packed.bits", "a packed u8 element is 2..=8 bits wide, not 9")],
    ),
    (
        "packed_signed_type",
        &[("commands.channels.fields.channels.type", "packed elements are unsigned integers: u8, u16 or u32")],
    ),
    (
        "packed_with_repeat",
        &[
            ("commands.channels.fields.channels.repeat", "`repeat` cannot be combined with `packed`"),
            ("commands.channels.fields.channels.range.max", "max 2048 does not fit in a 11-bit field (0..=2047)"),
        ],
    ),
    (
        "packed_count_zero",
        &[
            ("responses.readings.fields.readings.packed.count", "packed elements number 1..=256, not 0"),
            ("responses.readings.fields", "fields add up to 4 payload bytes, but response payloads are 8..=8 bytes"),
        ],
    ),
    (
        "packed_as_count",
        &[("commands.channels.fields.flags.repeat.count", "`channels` is not an unsigned number field")],
    ),
    (
        "packed_without_order",
        &[("commands.levels.fields.levels.packed", "missing field `bit_order`")],
    ),
    (
        "bit_without_repeat",
        &[("commands.stamp.fields.ticks.type", "a `bit` is only the element of a repeated field")],
    ),
    (
        "follows_later_field",
        &[("commands.write.fields.byte_count.follows.field", "refers to `values`, which is not an earlier field")],
    ),
    (
        "follows_both_sources",
        &[
            ("commands.write.fields.byte_count.follows", "give exactly one of `field`"),
            ("commands.write.fields.byte_count", "a number field needs a `unit`"),
        ],
    ),
    (
        "request_field_missing",
        &[("responses.read_reply.fields.values.repeat.request", "`values` answers `read`, which has no number field `amount`")],
    ),
    (
        "code_from_request_wrong",
        &[("responses.read_error.code_from_request", "answers `read` (0x01), whose code with 0x80 set is not this reply's 0x82")],
    ),
    (
        "example_length_field_lies",
        &[("examples[0].derived", "length field at offset 3 says 6, the frame's length gives 5")],
    ),
    (
        "example_count_wrong",
        &[("examples[2].derived", "invalid value for write.byte_count at offset 6: must be the bytes of values (2), found 3")],
    ),
    // ---- shape: the loader
    (
        "yaml_syntax_error",
        &[(
            "line 22 column 8",
            "not valid YAML: did not find expected ',' or ']'",
        )],
    ),
    (
        "top_level_not_mapping",
        &[("", "expected a mapping of spec keys at the top, found a list")],
    ),
    (
        "top_level_scalar",
        &[("", "expected a mapping of spec keys at the top, found a string")],
    ),
    ("unknown_top_level_key", &[("eratta", "unknown key `eratta`")]),
    (
        "unknown_field_key",
        &[(
            "commands.go_to.fields.target.widht",
            "unknown field `widht`, expected one of `name`, `type`",
        )],
    ),
    (
        "wrong_type_string_for_int",
        &[("serial.baud", "invalid type: string \"fast\", expected u32")],
    ),
    (
        "wrong_enum_variant",
        &[(
            "commands.get_status.fields.channel.type",
            "unknown variant `u48`",
        )],
    ),
    (
        "list_is_mapping",
        &[("flags", "expected a list, found a mapping")],
    ),
    (
        "two_shape_errors_in_list",
        &[
            ("commands.go_to.knid", "unknown field `knid`"),
            ("commands.get_status.tilte", "unknown field `tilte`"),
        ],
    ),
    (
        "missing_required_key",
        &[("responses.started", "missing field `kind`")],
    ),
    (
        "duplicate_yaml_key",
        &[("line 65 column 5", "duplicate entry with key \"code\"")],
    ),
    (
        "integer_too_large",
        &[(
            "line 71 column 75",
            "integer `99999999999999999999999` is too large: numbers must fit in 64 bits",
        )],
    ),
    // ---- framing and codes
    (
        "duplicate_command_code",
        &[(
            "commands.get_status",
            "duplicate code: `set_mode` (0x3000) and `get_status` (0x3000) have the same length",
        )],
    ),
    (
        "code_prefix_overlap",
        &[(
            "responses.set_mode_ack",
            "code 0x50 of `started` is a prefix of code 0x5000 of `set_mode_ack`",
        )],
    ),
    (
        "responses_same_code_and_length",
        &[(
            "responses.nak",
            "duplicate code: `started` (0x50) and `nak` (0x50) have the same length",
        )],
    ),
    // ---- code-less messages are compared too (made from valid/minimal_codeless.yaml)
    (
        "codeless_responses_clash",
        &[(
            "responses.read_status",
            "duplicate code: `status` (no code) and `read_status` (no code) have the same length and no constant field tells them apart",
        )],
    ),
    (
        "length_field_with_two_code_lengths",
        &[(
            "framing.request.code_lengths",
            "a frame with a length field has codes of one length per direction; code_lengths give [1, 2]",
        )],
    ),
    (
        "codeless_command_clashes_with_coded",
        &[(
            "commands.raw",
            "overlapping codes: `read` (0x02) and `raw` (no code) have the same length and no constant field tells them apart",
        )],
    ),
    (
        "unasked_follows_request",
        &[(
            "responses.status.fields.channel.follows",
            "a response sent unasked (`unasked: true`) must decode without a request; `channel` cannot take its value from the request",
        )],
    ),
    (
        "unasked_on_command",
        &[("commands.go_to.unasked", "unknown field `unasked`")],
    ),
    (
        "unasked_missing",
        &[(
            "responses.heartbeat",
            "no command lists this response (add it to a command's `responses` or to `common_responses`, or mark it `unasked: true` if the device sends it on its own)",
        )],
    ),
    (
        "needs_request_alone",
        &[(
            "responses.status",
            "`needs_request` is set, but no other response shares its code and length",
        )],
    ),
    (
        "payload_too_long",
        &[(
            "responses.status.fields",
            "fields add up to 9 payload bytes, but response payloads are 0..=8 bytes",
        )],
    ),
    (
        "payload_too_short",
        &[
            (
                "commands.set_mode.fields",
                "fields add up to 1 payload bytes, but request payloads are 2..=4 bytes",
            ),
            (
                "commands.get_status.fields",
                "fields add up to 1 payload bytes, but request payloads are 2..=4 bytes",
            ),
        ],
    ),
    (
        "code_length_not_allowed",
        &[(
            "commands.go_to.code",
            "a 1-byte code, but requests have codes of [2] bytes",
        )],
    ),
    (
        "code_not_hex",
        &[(
            "commands.go_to.code",
            "code `8192` must be written as 0x followed by an even number of hex digits",
        )],
    ),
    // ---- field values
    (
        "constant_too_wide",
        &[(
            "responses.status.fields.reserved.value",
            "constant 0x100 does not fit in a 8-bit field",
        )],
    ),
    (
        "constant_negative",
        &[(
            "responses.status.fields.reserved.value",
            "constant -1 does not fit in a 8-bit field",
        )],
    ),
    (
        "float_scaled_unit",
        &[
            (
                "commands.set_limits.fields.voltage_limit.unit",
                "unit `volts` has scale 0.1 and offset 0: a float field takes a unit of scale 1 and offset 0",
            ),
            (
                "responses.readings.fields.voltage.unit",
                "unit `volts` has scale 0.1 and offset 0: a float field takes a unit of scale 1 and offset 0",
            ),
        ],
    ),
    (
        "float_range_not_finite",
        &[(
            "responses.readings.fields.frequency.range.max",
            "max inf does not fit the field: a float's range is finite numbers of its type",
        )],
    ),
    (
        "float_range_empty",
        &[(
            "responses.readings.fields.frequency.range",
            "range is empty: min 65.5 > max 45.0",
        )],
    ),
    (
        "float_with_special",
        &[(
            "responses.readings.fields.frequency.special",
            "`special` cannot be combined with a float field (not expressible yet)",
        )],
    ),
    (
        "u64_range_negative",
        &[(
            "responses.limits_set.fields.serial.range.min",
            "min -1 does not fit the field: a 64-bit integer's range is integers of its type",
        )],
    ),
    (
        "i64_range_too_large",
        &[(
            "responses.readings.fields.drift.range.max",
            "max 9223372036854775808 does not fit the field",
        )],
    ),
    (
        "example_wrong_float_value",
        &[(
            "examples[1].derived",
            "voltage: the frame carries 230.1, the example states 230.2",
        )],
    ),
    (
        "word_order_on_u8",
        &[(
            "commands.get_status.fields.channel.word_order",
            "`word_order` is for 32- and 64-bit numbers",
        )],
    ),
    (
        "range_too_wide",
        &[(
            "commands.get_status.fields.channel.range.max",
            "max 300 does not fit in a 8-bit field (0..=255)",
        )],
    ),
    (
        "range_min_greater_than_max",
        &[(
            "commands.get_status.fields.channel.range",
            "range is empty: min 3 > max 1",
        )],
    ),
    (
        "enum_value_too_wide",
        &[(
            "commands.set_mode.fields.mode.enum",
            "enum `mode` value auto (256) does not fit in a 8-bit field",
        )],
    ),
    (
        "flag_bit_outside_field",
        &[(
            "responses.status.fields.error_bits.flags",
            "flag `reset` is bit 8, outside a 8-bit field",
        )],
    ),
    (
        "bits_overlap",
        &[(
            "responses.status.fields.position_word.bits.position",
            "bits 11..0 overlap another sub-field",
        )],
    ),
    (
        "bits_not_covering",
        &[(
            "responses.status.fields.position_word.bits",
            "sub-fields must cover all 16 bits; bits 12 are not covered",
        )],
    ),
    (
        "ascii_with_unit",
        &[(
            "responses.status.fields.firmware.unit",
            "`unit` cannot be combined with an ascii field",
        )],
    ),
    (
        "equals_later_field",
        &[(
            "commands.set_counter.fields.counter.equals",
            "refers to `spare`, which is not an earlier field of this message",
        )],
    ),
    // ---- units
    (
        "bad_scale_text",
        &[(
            "units.capacitance.scale",
            "bad scale: `abc` is not a decimal number or fraction",
        )],
    ),
    (
        "bad_scale_zero",
        &[("units.capacitance.scale", "scale 0 must be greater than zero")],
    ),
    (
        "bad_scale_negative",
        &[("units.capacitance.scale", "scale -1 must be greater than zero")],
    ),
    (
        "bad_scale_negative_fraction",
        &[(
            "units.capacitance.scale",
            "scale -1/1099511627776 must be greater than zero",
        )],
    ),
    (
        "bad_scale_division_by_zero",
        &[("units.capacitance.scale", "bad scale: `1/0` divides by zero")],
    ),
    (
        "undefined_unit",
        &[(
            "commands.go_to.fields.target.unit",
            "refers to unit `picofarad`, which is not defined in `units`",
        )],
    ),
    (
        "number_without_unit",
        &[(
            "commands.get_status.fields.channel",
            "a number field needs a `unit`",
        )],
    ),
    // ---- names
    (
        "name_camel_case",
        &[(
            "commands.GoTo",
            "message `GoTo` is not a valid identifier: use lower snake_case",
        )],
    ),
    (
        "name_starts_with_digit",
        &[(
            "units.2celsius",
            "unit `2celsius` is not a valid identifier",
        )],
    ),
    (
        "name_rust_keyword",
        &[(
            "commands.set_mode.fields.type",
            "field `type` is a Rust keyword",
        )],
    ),
    (
        "duplicate_message_name",
        &[(
            "responses.go_to",
            "duplicate message name `go_to` (commands and responses share one name space)",
        )],
    ),
    // ---- references
    (
        "response_reference_undefined",
        &[(
            "commands.go_to.responses[1]",
            "refers to response `nakk`, which is not defined",
        )],
    ),
    (
        "command_listed_as_response",
        &[(
            "commands.go_to.responses[2]",
            "`set_mode` is a command, not a response",
        )],
    ),
    (
        "response_unused",
        &[("responses.started", "no command lists this response")],
    ),
    (
        "broadcast_without_address",
        &[(
            "commands.get_status.broadcast",
            "the protocol has no broadcast address",
        )],
    ),
    // ---- checksum
    (
        "sum8_with_crc_params",
        &[(
            "framing.checksum.poly",
            "`poly` is a CRC parameter; sum8 takes none",
        )],
    ),
    (
        "sum8_check_mismatch",
        &[(
            "framing.checksum.check",
            "check value 0xDE does not match the parameters, which give 0xDD",
        )],
    ),
    (
        "crc_check_mismatch",
        &[(
            "framing.checksum.check",
            "check value 0xAEE8 does not match the parameters, which give 0xAEE7 over \"123456789\"",
        )],
    ),
    (
        "crc_missing_param",
        &[("framing.checksum.refout", "a CRC needs `refout`")],
    ),
    (
        "crc_even_poly",
        &[("framing.checksum.poly", "poly 0x8004 is even")],
    ),
    (
        "crc_negative_init",
        &[("framing.checksum.init", "init -1 does not fit in 16 bits")],
    ),
    // ---- examples
    (
        "example_bad_checksum",
        &[(
            "examples[0].printed",
            "§4.1 go_to: checksum mismatch at offset 8: expected 0xBD, found 0xBE",
        )],
    ),
    (
        "example_wrong_length",
        &[(
            "examples[0].printed",
            "has 8 bytes, but a go_to frame has 9 (3 overhead + 2-byte code + 4 payload)",
        )],
    ),
    (
        "example_wrong_value",
        &[(
            "examples[0].printed",
            "target: the frame carries 150 pF (raw 15000), the example states 151",
        )],
    ),
    (
        "example_wrong_value_binary_scale",
        &[(
            "examples[5].printed",
            "position: the frame carries 1/1099511627776 ° (raw 512), the example states 46",
        )],
    ),
    (
        "example_wrong_flags",
        &[(
            "examples[5].printed",
            "error_bits: the frame sets {\"overcurrent\", \"reset\"}, the example states {\"overheat\", \"reset\"}",
        )],
    ),
    (
        "example_unknown_value_name",
        &[(
            "examples[4].values.chanel",
            "states a value for `chanel`, which `get_status` does not have",
        )],
    ),
    (
        "example_unknown_erratum",
        &[(
            "examples[2].erratum",
            "refers to erratum `mini-e99`, which is not recorded in `errata`",
        )],
    ),
    (
        "example_corrected_valid_frame",
        &[(
            "examples[4].corrected",
            "the printed frame replays as it stands; `corrected` is only for frames the document got wrong",
        )],
    ),
    (
        "example_undefined_message",
        &[(
            "examples[0].message",
            "refers to message `goto`, which is not defined",
        )],
    ),
    (
        "example_reply_to_not_listing",
        &[(
            "examples[1].reply_to",
            "command `get_status` does not list `started` among its responses",
        )],
    ),
    (
        "example_needs_request_without_reply_to",
        &[(
            "examples[3].reply_to",
            "`runtime_min_sec` can only be decoded with its request: say which with `reply_to`",
        )],
    ),
    (
        "example_printed_and_derived",
        &[("examples[4]", "give exactly one of `printed`")],
    ),
    (
        "example_constant_mismatch",
        &[(
            "examples[0].derived",
            "invalid value for read_runtime_hours.selector at offset 2: expected 0x01, found 0x02",
        )],
    ),
    // ---- several defects in one file: every one is reported, each at its own path
    (
        "multiple_errors",
        &[
            ("units.angle.scale", "bad scale: `360/0` divides by zero"),
            (
                "commands.go_to.fields.target.unit",
                "refers to unit `picofarad`",
            ),
            (
                "commands.get_status.fields.channel.range",
                "range is empty: min 3 > max 1",
            ),
        ],
    ),
    (
        "code_first_mixed_code_lengths",
        &[(
            "framing.layout",
            "the code comes before the address, so every code must have one length",
        )],
    ),
    (
        "multiple_shape_errors",
        &[
            ("", "missing field `title`"),
            ("serial.baud", "invalid type: string \"fast\", expected u32"),
            ("framing.checksum.algorithm", "unknown variant `md5`"),
            ("commands.go_to.knid", "unknown field `knid`"),
        ],
    ),
    (
        "multiple_errors_crc",
        &[
            (
                "units.count.scale",
                "bad scale: `one` is not a decimal number or fraction",
            ),
            (
                "framing.checksum.check",
                "check value 0xAEE8 does not match the parameters, which give 0xAEE7",
            ),
        ],
    ),
];

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn label(kind: &str, name: &str) -> String {
    format!("fixtures/{kind}/{name}.yaml")
}

fn load_broken(name: &str) -> Diagnostics {
    let text = read(&fixtures().join(format!("broken/{name}.yaml")));
    match load_str(&label("broken", name), &text) {
        Ok(_) => panic!("fixtures/broken/{name}.yaml loaded without error"),
        Err(d) => d,
    }
}

/// Checks one fixture against its row; returns what is wrong, if anything.
fn mismatch(name: &str, want: &[(&str, &str)]) -> Option<String> {
    let got = load_broken(name);
    let listing = || {
        got.items
            .iter()
            .map(|d| format!("    [{}] {}", d.path, d.message))
            .collect::<Vec<_>>()
            .join("\n")
    };
    if got.file != label("broken", name) {
        return Some(format!("{name}: diagnostics name file `{}`", got.file));
    }
    if got.items.len() != want.len() {
        return Some(format!(
            "{name}: expected {} diagnostic(s), got {}:\n{}",
            want.len(),
            got.items.len(),
            listing()
        ));
    }
    let mut used = vec![false; got.items.len()];
    for (path, part) in want {
        let hit = got
            .items
            .iter()
            .enumerate()
            .position(|(i, d)| !used[i] && d.path == *path && d.message.contains(part));
        match hit {
            Some(i) => used[i] = true,
            None => {
                return Some(format!(
                    "{name}: no diagnostic at `{path}` containing `{part}`; got:\n{}",
                    listing()
                ))
            }
        }
    }
    None
}

#[test]
fn every_broken_fixture_gives_exactly_its_diagnostics() {
    let failures: Vec<String> = CASES
        .iter()
        .filter_map(|(name, want)| mismatch(name, want))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} fixtures failed:\n{}",
        failures.len(),
        CASES.len(),
        failures.join("\n")
    );
}

#[test]
fn every_broken_fixture_is_in_the_table_and_every_row_has_a_fixture() {
    let dir = fixtures().join("broken");
    let on_disk: BTreeSet<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .map(|p| {
            assert_eq!(
                p.extension().and_then(|x| x.to_str()),
                Some("yaml"),
                "{}: fixtures are .yaml files",
                p.display()
            );
            p.file_stem()
                .and_then(|s| s.to_str())
                .expect("UTF-8 file name")
                .to_owned()
        })
        .collect();
    let mut in_table = BTreeSet::new();
    for (name, want) in CASES {
        assert!(in_table.insert(name.to_string()), "`{name}` has two rows");
        assert!(!want.is_empty(), "`{name}`: a row must expect a diagnostic");
    }
    let untested: Vec<_> = on_disk.difference(&in_table).collect();
    let missing: Vec<_> = in_table.difference(&on_disk).collect();
    assert!(
        untested.is_empty(),
        "fixtures without a row in CASES: {untested:?}"
    );
    assert!(
        missing.is_empty(),
        "rows in CASES without a fixture: {missing:?}"
    );
    assert!(
        on_disk.len() >= 30,
        "only {} broken fixtures",
        on_disk.len()
    );
}

#[test]
fn every_broken_fixture_says_what_is_wrong_with_it() {
    for (name, _) in CASES {
        let text = read(&fixtures().join(format!("broken/{name}.yaml")));
        assert!(
            text.starts_with("# Broken fixture: "),
            "fixtures/broken/{name}.yaml must open with a `# Broken fixture: <defect>` comment"
        );
    }
}

#[test]
fn diagnostics_display_as_file_path_message() {
    let d = load_broken("multiple_errors");
    let text = d.to_string();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(
        lines.contains(
            &"fixtures/broken/multiple_errors.yaml: commands.go_to.fields.target.unit: \
              refers to unit `picofarad`, which is not defined in `units`"
        ),
        "{text}"
    );
    // A diagnostic about the whole file has no path segment.
    let top = load_broken("top_level_not_mapping").to_string();
    assert_eq!(
        top,
        "fixtures/broken/top_level_not_mapping.yaml: \
         expected a mapping of spec keys at the top, found a list"
    );
}

fn load_valid(name: &str) -> busspec_model::Protocol {
    let text = read(&fixtures().join(format!("valid/{name}.yaml")));
    load_str(&label("valid", name), &text).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn minimal_sum8_fixture_loads() {
    let p = load_valid("minimal");
    assert_eq!(p.name, "mini");
    assert_eq!(p.framing.checksum.algorithm, ChecksumAlgorithm::Sum8);
    assert_eq!(p.framing.start, Some(0xAA));
    assert_eq!((p.commands.len(), p.responses.len()), (3, 4));
    assert_eq!((p.units.len(), p.enums.len(), p.flags.len()), (4, 1, 1));
    assert_eq!((p.examples.len(), p.errata.len()), (6, 1));
    let status = &p.responses[3];
    assert_eq!(status.payload_len, 8);
    assert_eq!(status.fields[1].bits.len(), 2, "position_word is packed");
    assert!(status.fields[2].is_ascii());
    assert_eq!(status.fields[4].constant, Some(0));
    // Printed most significant byte first, sent little-endian: the replay reordered the target.
    let go_to = &p.examples[0];
    assert_eq!(
        go_to.wire,
        [0xAA, 0x21, 0x20, 0x00, 0x98, 0x3A, 0x00, 0x00, 0xBD]
    );
    // The one printed frame with a wrong checksum is excused by its erratum and corrected.
    let set_mode = &p.examples[2];
    assert_eq!(set_mode.erratum, Some(0));
    assert_eq!(set_mode.wire.last(), Some(&0xFD));
    assert_eq!(
        p.examples.iter().filter(|e| e.corrected.is_some()).count(),
        1
    );
}

#[test]
fn minimal_crc_fixture_loads() {
    let p = load_valid("minimal_crc");
    assert_eq!(p.name, "mini_crc");
    let ChecksumAlgorithm::Crc(crc) = &p.framing.checksum.algorithm else {
        panic!("expected a CRC");
    };
    assert_eq!(
        (crc.width, crc.poly, crc.init, crc.refin, crc.refout, crc.xorout),
        (16, 0x8005, 0xFFFF, false, false, 0)
    );
    assert_eq!(p.framing.checksum.catalogue.as_deref(), Some("CRC-16/CMS"));
    assert_eq!(p.framing.start, None);
    let paired: Vec<&str> = p
        .responses
        .iter()
        .filter(|r| r.needs_request)
        .map(|r| r.name.as_str())
        .collect();
    assert_eq!(paired, ["runtime_hours", "runtime_min_sec"]);
    assert_eq!(p.examples.len(), 5);
    // The two paired responses' examples were replayed with the request they answer.
    for e in &p.examples {
        if e.message.direction == Direction::Response && p.message(e.message).needs_request {
            assert!(e.reply_to.is_some());
        }
    }
}

/// The generated stream decoder tracks candidate frame lengths in a 64-bit set, so a spec with
/// more distinct frame lengths is refused at validation rather than at code generation.
#[test]
fn more_than_64_distinct_frame_lengths_is_refused() {
    let base = read(&fixtures().join("valid/minimal_crc.yaml"));
    let commands_at = base.find("commands:\n").expect("minimal_crc has commands");
    let mut text = base[..commands_at]
        .replace(
            "request:  {code_lengths: [1], payload: {min: 2, max: 2}}",
            "request:  {code_lengths: [1], payload: {min: 1, max: 255}}",
        )
        .replace(
            "response: {code_lengths: [1], payload: {min: 2, max: 2}}",
            "response: {code_lengths: [1], payload: {min: 1, max: 255}}",
        );
    text.push_str("commands:\n");
    // Command k carries k one-byte fields: frame lengths 6..=70, 65 of them.
    for k in 1..=65u32 {
        text.push_str(&format!(
            "  - name: set_{k}\n    title: \"Set {k}\"\n    section: \"3\"\n    kind: setter\n    code: \"0x{:02X}\"\n    fields:\n",
            k + 0x80
        ));
        for f in 0..k {
            text.push_str(&format!("      - {{name: b{f}, type: u8, unit: count}}\n"));
        }
        text.push_str("    responses: [counter_echo]\n");
    }
    text.push_str(
        "responses:\n  - name: counter_echo\n    title: \"Counter echo\"\n    section: \"3.3\"\n    kind: echo\n    code: \"0x70\"\n    fields:\n      - {name: counter, type: u16, unit: count}\n",
    );
    text.push_str("examples: []\nerrata: []\n");
    let diags = match load_str("many_lengths.yaml", &text) {
        Ok(_) => panic!("a spec with 65 distinct frame lengths loaded"),
        Err(d) => d,
    };
    let all = diags.to_string();
    assert!(
        all.contains("many_lengths.yaml: framing: messages have 65 distinct frame lengths; the generated stream decoder tracks at most 64"),
        "{all}"
    );
    assert_eq!(
        all.lines().count(),
        1,
        "only the length limit is wrong:\n{all}"
    );
}

/// A constant tells a code-less message from a coded one of the same length, whether it is a
/// whole field or a sub-field's bits: the fixture's clash goes away.
#[test]
fn a_constant_tells_a_codeless_message_from_a_coded_one() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/broken");
    let text = std::fs::read_to_string(dir.join("codeless_command_clashes_with_coded.yaml"))
        .expect("fixture");
    let field = "- {name: op, type: u8, unit: count}";
    assert!(text.contains(field));
    for (what, op) in [
        // `read`'s code is 0x02.
        ("a constant field", "- {name: op, type: u8, value: 0x03}"),
        (
            "a constant bit",
            "- {name: op, type: u8, bits: [{name: high, msb: 7, lsb: 1, unit: count}, {name: odd, msb: 0, lsb: 0, value: 1}]}",
        ),
    ] {
        let fixed = text.replace(field, op);
        if let Err(d) = load_str("codeless_told_apart.yaml", &fixed) {
            panic!("{what}: {d}");
        }
    }
    // The same bit, equal to the code's, tells nothing apart.
    let same = text.replace(
        field,
        "- {name: op, type: u8, bits: [{name: high, msb: 7, lsb: 1, unit: count}, {name: odd, msb: 0, lsb: 0, value: 0}]}",
    );
    let d = load_str("codeless_not_told_apart.yaml", &same).expect_err("a clash");
    assert!(d.items[0].message.starts_with("overlapping codes"), "{d}");
}
