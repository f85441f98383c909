//! `diff` over fixture pairs: `fixtures/diff/base.yaml` against a copy with the changes of one
//! category applied. Each test lists every change it expects, so a change reported in the wrong
//! category, under the wrong path, or not at all fails it.

mod common;
use std::path::{Path, PathBuf};

use busspec_model::diff::{self, Category, Change};
use busspec_model::{load_file, Protocol};
use Category::{ApiBreaking as Api, Compatible as Compat, WireBreaking as Wire};

fn fixture(name: &str) -> (PathBuf, Protocol) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/diff")
        .join(name);
    let p = load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    (path, p)
}

fn changes(old: &str, new: &str) -> Vec<Change> {
    diff::diff(&fixture(old).1, &fixture(new).1)
}

fn summary(changes: &[Change]) -> Vec<(Category, &str, &str)> {
    changes
        .iter()
        .map(|c| (c.category, c.kind, c.path.as_str()))
        .collect()
}

#[test]
fn a_spec_against_itself_has_no_changes() {
    for f in ["base.yaml", "wire.yaml", "api.yaml", "compatible.yaml"] {
        assert_eq!(changes(f, f), [], "{f}");
    }
}

#[test]
fn every_wire_breaking_change_is_found() {
    let got = changes("base.yaml", "wire.yaml");
    assert_eq!(
        summary(&got),
        [
            (Wire, "byte_order_changed", "byte_order"),
            (Wire, "serial_changed", "serial.baud"),
            (Wire, "framing_changed", "framing.start"),
            (Wire, "checksum_changed", "framing.checksum"),
            (Wire, "address_range_narrowed", "framing.address.devices"),
            (Wire, "unit_scale_changed", "units.celsius"),
            (Wire, "value_removed", "enums.mode.values.manual"),
            (Wire, "value_renumbered", "enums.mode.values.auto"),
            (Wire, "value_removed", "flags.status_bits.bits.overheat"),
            (
                Wire,
                "field_signedness_changed",
                "commands.go_to.fields.target"
            ),
            (Wire, "code_changed", "commands.set_mode"),
            (Wire, "frame_length_changed", "commands.get_status"),
            (
                Wire,
                "field_width_changed",
                "commands.get_status.fields.channel"
            ),
            (
                Wire,
                "constant_changed",
                "commands.get_upper_limit.fields.index"
            ),
            (Wire, "message_removed", "commands.reset"),
            (Wire, "frame_length_changed", "responses.status"),
            (
                Wire,
                "field_scale_changed",
                "responses.status.fields.position_word.bits.freshness"
            ),
            (
                Wire,
                "bits_changed",
                "responses.status.fields.position_word.bits.position"
            ),
            (
                Wire,
                "value_removed",
                "responses.status.fields.temperature.special.no_sensor"
            ),
            (Wire, "field_removed", "responses.status.fields.reserved"),
            (
                Wire,
                "field_offset_changed",
                "responses.limit.fields.capacitance"
            ),
            (Wire, "field_offset_changed", "responses.limit.fields.spare"),
            (Wire, "reply_removed", "commands.go_to.responses"),
        ]
    );
    // The texts name both sides.
    let text = |kind: &str| &got.iter().find(|c| c.kind == kind).unwrap().text;
    assert_eq!(
        text("code_changed"),
        "command `set_mode`: code 0x3000 → 0x3100"
    );
    assert_eq!(
        text("unit_scale_changed"),
        "unit `celsius`: physical value raw × 1 − 50 → raw × 1 − 40; every field in it reads differently"
    );
    assert_eq!(
        text("checksum_changed"),
        "checksum: sum8 (8 bits, check 0xDD) → CRC-8/SMBUS (8 bits, check 0xF4)"
    );
    assert_eq!(
        text("field_width_changed"),
        "field `get_status.channel`: u8 → u16 (1 → 2 bytes)"
    );
}

#[test]
fn every_api_breaking_change_is_found_and_nothing_on_the_wire() {
    let got = changes("base.yaml", "api.yaml");
    assert_eq!(
        summary(&got),
        [
            (Api, "unit_renamed", "units.counter"),
            (Api, "enum_renamed", "enums.operating_mode"),
            (Api, "value_renamed", "flags.status_bits.bits.restarted"),
            (Api, "message_renamed", "commands.go_to_capacitance"),
            (
                Api,
                "field_renamed",
                "commands.go_to_capacitance.fields.capacitance"
            ),
            (
                Api,
                "range_narrowed",
                "commands.go_to_capacitance.fields.capacitance.range"
            ),
            (
                Api,
                "value_renamed",
                "responses.status.fields.temperature.special.sensor_missing"
            ),
            (Api, "field_type_changed", "responses.limit.fields.spare"),
        ]
    );
    assert_eq!(
        got[3].text,
        "command `go_to` (0x2000) renamed to `go_to_capacitance`"
    );
}

#[test]
fn every_compatible_change_is_found() {
    let got = changes("base.yaml", "compatible.yaml");
    assert_eq!(
        summary(&got),
        [
            (Compat, "document_changed", "document.revision"),
            (Compat, "document_changed", "document.date"),
            (Compat, "address_range_widened", "framing.address.devices"),
            (Compat, "framing_widened", "framing.response.payload"),
            (Compat, "unit_added", "units.volts"),
            (Compat, "value_added", "enums.mode.values.service"),
            (Compat, "value_added", "flags.status_bits.bits.undervoltage"),
            (Compat, "documentation_changed", "commands.go_to"),
            (
                Compat,
                "range_widened",
                "commands.get_status.fields.channel.range"
            ),
            (Compat, "message_added", "commands.get_supply"),
            (
                Compat,
                "value_added",
                "responses.status.fields.temperature.special.sensor_fault"
            ),
            (Compat, "message_added", "responses.supply"),
            (Compat, "reply_added", "commands.get_status.responses"),
            (Compat, "example_added", "examples"),
            (Compat, "erratum_added", "errata.mini-e01"),
        ]
    );
}

#[test]
fn going_back_from_additions_removes_them_on_the_wire() {
    // The reverse of compatible.yaml: what was added is removed, what was widened narrowed.
    let got = changes("compatible.yaml", "base.yaml");
    let s = summary(&got);
    for expected in [
        (Wire, "message_removed", "commands.get_supply"),
        (Wire, "message_removed", "responses.supply"),
        (Wire, "value_removed", "enums.mode.values.service"),
        (Wire, "address_range_narrowed", "framing.address.devices"),
        (Wire, "framing_changed", "framing.response.payload"),
        (Wire, "reply_removed", "commands.get_status.responses"),
        (
            Api,
            "range_narrowed",
            "commands.get_status.fields.channel.range",
        ),
        (Api, "unit_removed", "units.volts"),
        (Compat, "example_removed", "examples"),
        (Compat, "erratum_removed", "errata.mini-e01"),
    ] {
        assert!(s.contains(&expected), "{expected:?} missing from {s:#?}");
    }
}

#[test]
fn a_code_reused_with_another_layout_is_one_wire_breaking_change() {
    let got = changes("base.yaml", "reused.yaml");
    assert_eq!(
        summary(&got),
        [(Wire, "code_reused", "commands.get_version")]
    );
    assert!(
        got[0]
            .text
            .starts_with("command code 0x4000 reused: `get_status` replaced by `get_version`"),
        "{}",
        got[0].text
    );
}

#[test]
fn the_changelog_lists_breaking_changes_first_under_the_new_revision() {
    let (op, old) = fixture("base.yaml");
    let (np, new) = fixture("compatible.yaml");
    let old_side = diff::Side::of(&op.display().to_string(), &old);
    let new_side = diff::Side::of(&np.display().to_string(), &new);
    let md = diff::render_markdown(&old_side, &new_side, &diff::diff(&old, &new));
    assert!(
        md.starts_with("## mini: revision 1.1 (2024-06-01)\n"),
        "{md}"
    );
    assert!(
        md.contains(&format!("(SHA-256 `{}`)", new.spec_sha256)),
        "{md}"
    );
    assert!(
        md.contains("\n### Compatible (15)\n\n- document revision: 1.0 → 1.1\n"),
        "{md}"
    );
    assert!(!md.contains("Wire-breaking"), "{md}");

    let (wp, wire) = fixture("wire.yaml");
    let wire_side = diff::Side::of(&wp.display().to_string(), &wire);
    let mixed = [diff::diff(&old, &wire), diff::diff(&old, &new)].concat();
    let md = diff::render_markdown(&old_side, &wire_side, &mixed);
    let wire_at = md.find("### Wire-breaking (23)").expect(&md);
    let compatible_at = md.find("### Compatible (15)").expect(&md);
    assert!(wire_at < compatible_at, "{md}");
    assert!(md.contains("- command `reset` (0x1000) removed\n"), "{md}");
}

#[test]
fn any_two_specs_diff_without_panicking_and_each_against_itself_is_empty() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["tests/fixtures/valid", "tests/fixtures/diff", "../spec"] {
        for e in std::fs::read_dir(root.join(dir)).expect("fixture directory") {
            let path = e.expect("directory entry").path();
            if path.extension().is_some_and(|x| x == "yaml") {
                files.push(path);
            }
        }
    }
    assert!(files.len() >= 9, "{files:?}");
    let specs: Vec<Protocol> = files
        .iter()
        .map(|f| load_file(f).unwrap_or_else(|d| panic!("{d}")))
        .collect();
    for (i, a) in specs.iter().enumerate() {
        for (j, b) in specs.iter().enumerate() {
            // Every file here differs from every other in substance, not just in comments.
            let changes = diff::diff(a, b);
            assert_eq!(
                changes.is_empty(),
                i == j,
                "{} → {}",
                files[i].display(),
                files[j].display()
            );
        }
    }
}

/// Frames that stop carrying an address (or start to) change the layout (and so every frame's
/// length), not also a device range and a host address.
#[test]
fn an_address_dropped_from_the_layout_is_one_layout_change() {
    let (path, base) = fixture("base.yaml");
    let text = std::fs::read_to_string(&path).expect("base.yaml");
    let without = text
        .replace(
            "layout: [start, address, code, payload, checksum]",
            "layout: [start, code, payload, checksum]",
        )
        .replace(
            "  address:\n    host: 0x20\n    devices: {min: 0x21, max: 0x40}\n",
            "",
        );
    assert_ne!(without, text);
    let unaddressed =
        busspec_model::load_str("unaddressed.yaml", &without).unwrap_or_else(|d| panic!("{d}"));
    assert!(!unaddressed.framing.has_address());
    for (a, b) in [(&base, &unaddressed), (&unaddressed, &base)] {
        let got = diff::diff(a, b);
        let s = summary(&got);
        assert_eq!(
            s[0],
            (Wire, "framing_changed", "framing.layout"),
            "{got:#?}"
        );
        assert!(
            s[1..]
                .iter()
                .all(
                    |c| *c == (Wire, "frame_length_changed", c.2) && c.2.starts_with("commands.")
                        || c.2.starts_with("responses.")
                ),
            "{got:#?}"
        );
        assert!(!s.iter().any(|c| c.2.contains("address")), "{got:#?}");
    }
}

/// Another end byte is a wire-breaking change of `framing.end`, and nothing else.
#[test]
fn another_end_byte_is_a_framing_change() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/ft12_fixed.yaml");
    let text = std::fs::read_to_string(&path).expect("ft12_fixed.yaml");
    // The examples end in 16 alone: keep them out of both.
    let head = &text[..text.find("examples:").expect("examples")];
    let old = busspec_model::load_str("x.yaml", head).unwrap_or_else(|d| panic!("{d}"));
    let new = busspec_model::load_str("x.yaml", &head.replace("end: 0x16", "end: [0x16, 0x0D]"))
        .unwrap_or_else(|d| panic!("{d}"));
    let got = diff::diff(&old, &new);
    assert_eq!(
        got.iter()
            .map(|c| (c.category, c.kind, c.path.as_str(), c.text.as_str()))
            .collect::<Vec<_>>()[0],
        (
            Wire,
            "framing_changed",
            "framing.end",
            "end bytes: 16 → 16 0D"
        ),
        "{got:#?}"
    );
    assert!(
        got[1..].iter().all(|c| c.kind == "frame_length_changed"),
        "{got:#?}"
    );
}

/// Adding escaping, changing it, or changing where the checksum is computed is a
/// wire-breaking change of `framing.escaping`.
#[test]
fn escaping_changes_are_wire_breaking() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/hdlc_like.yaml");
    let text = std::fs::read_to_string(&path).expect("hdlc_like.yaml");
    let head = &text[..text.find("examples:").expect("examples")];
    let load = |t: &str| busspec_model::load_str("x.yaml", t).unwrap_or_else(|d| panic!("{d}"));
    let escaped = load(head);
    let block = &head[head.find("  escaping:").unwrap()..head.find("\nunits:").unwrap()];
    let plain = load(&head.replace(block, ""));
    let more = load(&head.replace("bytes: [0x7E, 0x7D]", "bytes: [0x7E, 0x7D, 0x11, 0x13]"));
    let summary_of = |a: &Protocol, b: &Protocol| {
        diff::diff(a, b)
            .into_iter()
            .map(|c| (c.category, c.kind, c.path, c.text))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        summary_of(&plain, &escaped),
        [(
            Wire,
            "escaping_changed",
            "framing.escaping".to_owned(),
            "escaping: none → escape byte 7D: 7E as 7D 5E, 7D as 7D 5D (checksum and length computed before escaping)".to_owned()
        )]
    );
    assert_eq!(summary_of(&escaped, &plain)[0].1, "escaping_changed");
    let got = summary_of(&escaped, &more);
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!((got[0].0, got[0].1), (Wire, "escaping_changed"));
    assert_eq!(summary_of(&escaped, &escaped), []);
}

/// DLE stuffing (Garmin's serial link): other end bytes, or another byte doubled or escaped
/// beside the doubled one, are wire-breaking changes (`framing_changed` of the end bytes,
/// `escaping_changed`), each said in its bytes.
#[test]
fn dle_stuffing_changes_are_wire_breaking() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/garmin_link.yaml");
    let text = std::fs::read_to_string(&path).expect("garmin_link.yaml");
    let head = &text[..text.find("examples:").expect("examples")];
    let load = |t: &str| busspec_model::load_str("x.yaml", t).unwrap_or_else(|d| panic!("{d}"));
    let dle = load(head);
    let etb = load(&head.replace("end: [0x10, 0x03]", "end: [0x10, 0x17]"));
    let more = load(&head.replace(
        "      - {byte: 0x10, as: 0x10}        # DLE travels doubled: 10 10\n",
        "      - {byte: 0x10, as: 0x10}        # DLE travels doubled: 10 10\n      - {byte: 0x03, as: 0x83}\n",
    ));
    let summary_of = |a: &Protocol, b: &Protocol| {
        diff::diff(a, b)
            .into_iter()
            .map(|c| (c.category, c.kind, c.path, c.text))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        summary_of(&dle, &etb),
        [(
            Wire,
            "framing_changed",
            "framing.end".to_owned(),
            "end bytes: 10 03 → 10 17".to_owned()
        )]
    );
    assert_eq!(
        summary_of(&dle, &more),
        [(
            Wire,
            "escaping_changed",
            "framing.escaping".to_owned(),
            "escaping: escape byte 10: 10 doubled; a frame ends at the first 10 not doubled (checksum and length computed before escaping) → escape byte 10: 10 doubled, 03 as 10 83; a frame ends at the first 10 not doubled (checksum and length computed before escaping)".to_owned()
        )]
    );
    assert_eq!(summary_of(&dle, &dle), []);
}

/// `base.yaml` with a `transactions:` section (empty text: none).
fn with_transactions(section: &str) -> Protocol {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/diff/base.yaml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.replacen("\nframing:\n", &format!("\n{section}\nframing:\n"), 1);
    busspec_model::load_str("base.yaml", &text).unwrap_or_else(|d| panic!("{d}"))
}

#[test]
fn transactions_changes_are_classified() {
    let none = with_transactions("");
    let old = with_transactions(
        "transactions:\n  response_timeout_ms: 100\n  turnaround_ms: 1\n  inter_frame_gap: {characters: 3.5}\n",
    );
    // Added: a longer timeout and gap than none at all are wire-breaking for a master built
    // without them; the section alone changes no command's retry safety.
    assert_eq!(
        summary(&diff::diff(&none, &old)),
        [
            (Wire, "timing_changed", "transactions.response_timeout_ms"),
            (Wire, "timing_changed", "transactions.turnaround_ms"),
            (Wire, "timing_changed", "transactions.inter_frame_gap"),
        ]
    );
    // Shorter timeout and gap: compatible; set_mode no longer safe to retry: breaking;
    // go_to (a movement) now safe: compatible.
    let new = with_transactions(
        "transactions:\n  response_timeout_ms: 50\n  turnaround_ms: 1\n  inter_frame_gap: {characters: 1.5}\n  retry:\n    safe: [go_to]\n    unsafe: [set_mode]\n",
    );
    let got = diff::diff(&old, &new);
    assert_eq!(
        summary(&got),
        [
            (Compat, "timing_changed", "transactions.response_timeout_ms"),
            (Compat, "timing_changed", "transactions.inter_frame_gap"),
            (Compat, "retry_changed", "commands.go_to"),
            (Wire, "retry_changed", "commands.set_mode"),
        ]
    );
    assert_eq!(got[0].text, "response timeout: 100 ms → 50 ms");
    assert_eq!(got[3].text, "set_mode to retry: safe → not safe");
    assert_eq!(diff::diff(&new, &new), []);
}

/// Floats and 64-bit integers: a word order flipped, the same bits read as a float, a float's
/// range narrowed and a u64's widened above `i64::MAX` are each classified as their bits say.
#[test]
fn word_order_and_number_kind_changes_are_classified() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/meter_floats.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let old = busspec_model::load_str("old", &text).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(diff::diff(&old, &old), []);
    let edited = text
        .replace(
            "{name: voltage, type: f32, word_order: swapped,",
            "{name: voltage, type: f32,",
        )
        .replace(
            "{name: counter, type: u32, word_order: swapped, unit: count}",
            "{name: counter, type: f32, word_order: swapped, unit: count}",
        )
        .replace("range: {min: 45, max: 65}", "range: {min: 45.5, max: 65}")
        .replace("range: {min: 1, max: 18446744073709551615}", "range: {min: 0, max: 18446744073709551615}")
        // The examples no longer replay: give the counter and voltage the new reading's bytes.
        .replace("values: {voltage: 230.1, frequency: 50, energy: 12345.678, energy_swapped: 0.1, pulses: 18446744073709551000, drift: -1234567890123, counter: 305419896, temperature: -5}", "values: {}")
        .replace("19 9A 43 66 42 48", "43 66 19 9A 42 48");
    let edited = fix_crc(&edited);
    let new = busspec_model::load_str("new", &edited).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(
        summary(&diff::diff(&old, &new)),
        [
            (
                Wire,
                "field_word_order_changed",
                "responses.readings.fields.voltage"
            ),
            (
                Api,
                "range_narrowed",
                "responses.readings.fields.frequency.range"
            ),
            (
                Wire,
                "field_number_kind_changed",
                "responses.readings.fields.counter"
            ),
            (
                Compat,
                "range_widened",
                "responses.limits_set.fields.serial.range"
            ),
            (Compat, "example_removed", "examples"),
            (Compat, "example_added", "examples"),
        ]
    );
}

/// The meter fixture's readings example with its CRC-16/MODBUS recomputed.
fn fix_crc(text: &str) -> String {
    let at = text.find("derived: \"01 04 43").unwrap() + "derived: \"".len();
    let end = at + text[at..].find('"').unwrap();
    let mut bytes: Vec<u8> = text[at..end]
        .split(' ')
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect();
    bytes.truncate(bytes.len() - 2);
    let mut crc = 0xFFFFu16;
    for b in &bytes {
        crc ^= u16::from(*b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    // Printed high byte first (printed_byte_order big).
    bytes.extend([(crc >> 8) as u8, crc as u8]);
    let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    format!("{}{}{}", &text[..at], hex.join(" "), &text[end..])
}

/// Packed elements regrouped in the same bytes (another bit order, another width that keeps
/// the bytes) are wire-breaking; so is another count that changes the bytes.
#[test]
fn packed_element_changes_are_wire_breaking() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/packed_channels.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let head = &text[..text.find("examples:").unwrap()];
    let old = busspec_model::load_str("old", head).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(diff::diff(&old, &old), []);
    let edited = head
        .replace(
            "packed: {count: 4, bits: 11, bit_order: lsb_first}",
            "packed: {count: 4, bits: 11, bit_order: msb_first}",
        )
        .replace(
            "packed: {count: 5, bits: 3, bit_order: msb_first}",
            "packed: {count: 5, bits: 2, bit_order: msb_first}",
        )
        .replace("range: {min: 0, max: 6}", "range: {min: 0, max: 3}");
    let new = busspec_model::load_str("new", &edited).unwrap_or_else(|d| panic!("{d}"));
    let found = diff::diff(&old, &new);
    let kinds: Vec<(Category, &str, &str)> = summary(&found);
    assert!(
        kinds.contains(&(
            Wire,
            "field_packing_changed",
            "commands.channels.fields.channels"
        )),
        "{kinds:?}"
    );
    assert!(
        kinds.contains(&(
            Wire,
            "field_packing_changed",
            "commands.levels.fields.levels"
        )),
        "{kinds:?}"
    );
    let text = found
        .iter()
        .find(|c| c.path == "commands.channels.fields.channels")
        .map(|c| c.text.clone())
        .unwrap_or_default();
    assert!(
        text.contains("u16[4] × 11 bits lsb first → u16[4] × 11 bits msb first"),
        "{text}"
    );
}

/// A list of a fixed count: another count, another element type of the same width (signed,
/// float) or another word order is wire-breaking, and is named by its elements (`i16[2]`).
#[test]
fn fixed_count_and_element_changes_are_wire_breaking() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/packed_channels.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let head = &text[..text.find("examples:").unwrap()];
    let old = busspec_model::load_str("old", head).unwrap_or_else(|d| panic!("{d}"));
    let edited = head
        .replace(
            "{name: deltas, type: i16, unit: tenth_degree, range: {min: -900, max: 900}, repeat: {count: 2}}",
            "{name: deltas, type: i16, unit: tenth_degree, range: {min: -900, max: 900}, repeat: {count: 3}}",
        )
        .replace(
            "{name: modes, type: u8, enum: mode, repeat: {count: 2}}",
            "{name: modes, type: i8, enum: mode, repeat: {count: 2}}",
        )
        .replace(
            "{name: factors, type: f32, unit: ticks, range: {min: -2.0, max: 2.0}, repeat: {count: 2}}",
            "{name: factors, type: u32, unit: ticks, repeat: {count: 2}}",
        )
        .replace("type: f64, unit: ticks, word_order: swapped,", "type: f64, unit: ticks,")
        .replace("payload: {min: 3, max: 36}", "payload: {min: 3, max: 38}");
    let new = busspec_model::load_str("new", &edited).unwrap_or_else(|d| panic!("{d}"));
    let found = diff::diff(&old, &new);
    let kinds: Vec<(Category, &str, &str)> = summary(&found);
    for (kind, field) in [
        ("field_width_changed", "deltas"),
        ("field_signedness_changed", "modes"),
        ("field_number_kind_changed", "factors"),
    ] {
        let path = format!("commands.trim.fields.{field}");
        assert!(
            kinds.contains(&(Wire, kind, path.as_str())),
            "{kind} {field}: {kinds:?}"
        );
    }
    assert!(
        kinds
            .iter()
            .any(|(c, _, p)| *c == Wire && *p == "commands.trim.fields.scale"),
        "{kinds:?}"
    );
    let text = found
        .iter()
        .find(|c| c.path == "commands.trim.fields.deltas")
        .map(|c| c.text.clone())
        .unwrap_or_default();
    assert!(text.contains("i16[2] → i16[3] (4 → 6 bytes)"), "{text}");
}

/// A preamble added, removed, or sending another byte or count is a wire-breaking change of
/// `framing.preamble`; taking more wake-up bytes is compatible, fewer wire-breaking.
#[test]
fn preamble_changes_are_classified() {
    let line = "  preamble: {section: \"5.1\", byte: 0xFE, send: 4, max: 4}\n";
    let (with, without) = common::revisions("dlt645", &[(line, "")]);
    let summary_of = |a: &Protocol, b: &Protocol| {
        diff::diff(a, b)
            .into_iter()
            .map(|c| (c.category, c.kind, c.path, c.text))
            .collect::<Vec<_>>()
    };
    let removed = summary_of(&with, &without);
    assert_eq!(
        removed[0],
        (
            Wire,
            "preamble_changed",
            "framing.preamble".to_owned(),
            "preamble: 0xFE sent 4 times before every frame; 0 to 4 taken before one → none"
                .to_owned()
        ),
        "{removed:#?}"
    );
    assert_eq!(summary_of(&without, &with)[0].1, "preamble_changed");
    for (to, category) in [
        ("byte: 0xFF, send: 4, max: 4", Wire),
        ("byte: 0xFE, send: 2, max: 4", Wire),
        ("byte: 0xFE, send: 4, max: 8", Compat),
    ] {
        let (old, new) = common::revisions("dlt645", &[("byte: 0xFE, send: 4, max: 4", to)]);
        let got = summary_of(&old, &new);
        let preamble: Vec<_> = got.iter().filter(|c| c.1 == "preamble_changed").collect();
        assert_eq!(preamble.len(), 1, "{to}: {got:#?}");
        assert_eq!(preamble[0].0, category, "{to}");
    }
    // Taking fewer: the other way round.
    let (old, new) = common::revisions("dlt645", &[("max: 4}", "max: 8}")]);
    let fewer = summary_of(&new, &old);
    assert_eq!(
        (fewer[0].0, fewer[0].1),
        (Wire, "preamble_changed"),
        "{fewer:#?}"
    );
    assert_eq!(summary_of(&with, &with), []);
}

/// A per-byte transform added, removed, or adding or XORing another byte is a wire-breaking
/// change of `framing.transform`.
#[test]
fn transform_changes_are_classified() {
    let line = "  transform: {section: \"5.3\", add: 0x33}\n";
    let (with, without) = common::revisions("dlt645", &[(line, "")]);
    let summary_of = |a: &Protocol, b: &Protocol| {
        // The edited revision has no examples: their removal aside.
        diff::diff(a, b)
            .into_iter()
            .filter(|c| c.kind != "example_removed")
            .map(|c| (c.category, c.kind, c.path, c.text))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        summary_of(&with, &without),
        [(
            Wire,
            "transform_changed",
            "framing.transform".to_owned(),
            "transform: every payload byte travels plus 0x33 (mod 256) → none".to_owned()
        )]
    );
    assert_eq!(summary_of(&without, &with)[0].1, "transform_changed");
    for to in ["add: 0x34", "xor: 0x33"] {
        let (old, new) = common::revisions("dlt645", &[("add: 0x33", to)]);
        let got = summary_of(&old, &new);
        assert_eq!(got.len(), 1, "{to}: {got:#?}");
        assert_eq!((got[0].0, got[0].1), (Wire, "transform_changed"), "{to}");
    }
    // Another section only: no change.
    let (old, new) = common::revisions("dlt645", &[("section: \"5.3\", add", "add")]);
    assert_eq!(summary_of(&old, &new), []);
}

/// A response made also sent unasked (`unasked: true`) is compatible; the flag dropped (the
/// response then listed by a command) is wire-breaking: a device that still sends it on its
/// own breaks a master waiting for another reply. A response sent unasked only cannot lose
/// the flag without being listed.
#[test]
fn unasked_changes_are_classified() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid/unasked.yaml");
    let text = std::fs::read_to_string(&path).expect("unasked.yaml");
    let load = |t: &str| busspec_model::load_str("x.yaml", t).unwrap_or_else(|d| panic!("{d}"));
    let base = load(&text);
    let flag = "    code: \"0x71\"\n    unasked: true\n";
    assert!(text.contains(flag));
    let reply_only = load(&text.replace(flag, "    code: \"0x71\"\n"));
    let summary_of = |a: &Protocol, b: &Protocol| {
        diff::diff(a, b)
            .into_iter()
            .map(|c| (c.category, c.kind, c.path))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        summary_of(&reply_only, &base),
        [(
            Compat,
            "unasked_added",
            "responses.alarm.unasked".to_owned()
        )]
    );
    assert_eq!(
        summary_of(&base, &reply_only),
        [(
            Wire,
            "unasked_removed",
            "responses.alarm.unasked".to_owned()
        )]
    );
    // The heartbeat, listed by no command, cannot drop the flag alone.
    let hb = "    code: \"0x70\"\n    unasked: true\n";
    let Err(e) = busspec_model::load_str("x.yaml", &text.replace(hb, "    code: \"0x70\"\n"))
    else {
        panic!("a response listed by no command and not unasked must be refused");
    };
    assert!(
        e.to_string().contains("no command lists this response"),
        "{e}"
    );
}
