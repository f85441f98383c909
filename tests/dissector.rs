//! `busspec dissector` held to busspec itself with the real tshark: for each built-in protocol
//! and for spec files given with `--spec`, captures of every example frame with noise between
//! them, out-of-spec frames (a value past its range, an address no device has, resealed with
//! a good checksum) and frames with a bad checksum go through `decode --stream --pcapng`; the
//! generated dissector reads the file (`tshark -2 -T json`) and every packet's fields must be
//! what busspec's JSON line for that offset says: message, direction, address, code, each
//! field's value as printed and its raw value, checksum status, the out-of-spec reason, and
//! the pairing (the request packet just before a response, as busspec's stream pairs them,
//! and the time between them). The dissector of every valid fixture spec must load in tshark
//! without a Lua error, and no capture, random bytes included, may raise one.
//!
//! tshark is needed; where it is missing the tests say so and pass, except where
//! `BUSSPEC_REQUIRE_TSHARK` is set (CI), where they fail.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use busspec_model::interp::{self, Raw};
use busspec_model::ir::{Direction, Protocol};
use busspec_model::{escape, load_file, stream};
use serde_json::value::RawValue;
use serde_json::Value;

#[path = "common/cli.rs"]
mod cli;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_busspec"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run busspec")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A scratch directory for `test`, removed when dropped.
fn temp_dir(test: &str) -> tempfile::TempDir {
    cli::scratch(&format!("dissector-{test}"))
}

/// A protocol to check: how `decode` and `dissector` name it, and its spec file.
struct Case {
    args: Vec<String>,
    file: &'static str,
}

fn cases() -> Vec<Case> {
    let built_in = |name: &str, file| Case {
        args: vec![name.to_owned()],
        file,
    };
    let spec = |file: &'static str| {
        let p = load(file);
        Case {
            args: vec![p.name.clone(), "--spec".into(), file.into()],
            file,
        }
    };
    vec![
        built_in("ub2", "spec/ub2.yaml"),
        built_in("sd", "spec/sd.yaml"),
        built_in("modbus", "spec/modbus.yaml"),
        built_in("dynamixel", "spec/dynamixel.yaml"),
        spec("model/tests/fixtures/valid/unaddressed.yaml"),
        spec("model/tests/fixtures/valid/unasked.yaml"),
        spec("model/tests/fixtures/valid/ubx_like.yaml"),
        // A checksum before the bytes it covers (SBF's CRC at offset 2).
        spec("model/tests/fixtures/valid/sbf_blocks.yaml"),
        // A checksum over bytes on both sides of it, followed by its complement (HerkuleX).
        spec("model/tests/fixtures/valid/herkulex.yaml"),
        spec("model/tests/fixtures/valid/pelco_p.yaml"),
        spec("model/tests/fixtures/valid/ft12_fixed.yaml"),
        // A constant whole frame (M-Bus's single character E5) beside framed ones.
        spec("model/tests/fixtures/valid/mbus_short.yaml"),
        spec("model/tests/fixtures/valid/msp_v1.yaml"),
        // Start bytes by direction: a request and its reply share a code.
        spec("model/tests/fixtures/valid/msp_by_direction.yaml"),
        // BCD fields: the dissector shows their decimal numbers.
        spec("model/tests/fixtures/valid/bcd_meter.yaml"),
        // Floats and 64-bit integers, in either byte order and word-swapped, with ranges.
        spec("model/tests/fixtures/valid/meter_floats.yaml"),
        spec("model/tests/fixtures/valid/telemetry_le.yaml"),
        // A CRC that takes each message's extra byte (MAVLink's CRC_EXTRA).
        spec("model/tests/fixtures/valid/crc_extra.yaml"),
        // Header fields every message carries (MAVLink v1's sequence, system and component).
        spec("model/tests/fixtures/valid/mavlink_v1.yaml"),
        spec("model/tests/fixtures/valid/msp_v2.yaml"),
        // Payload truncation (MAVLink v2): truncated frames dissected padded with zeros.
        spec("model/tests/fixtures/valid/mavlink_v2.yaml"),
        // A start and a length field sent twice.
        spec("model/tests/fixtures/valid/ft12_variable.yaml"),
        spec("model/tests/fixtures/valid/minimal_variable.yaml"),
        // Escaped frames: the dissector unescapes them into a tvb of their own.
        spec("model/tests/fixtures/valid/slip_sensor.yaml"),
        spec("model/tests/fixtures/valid/hdlc_like.yaml"),
        spec("model/tests/fixtures/valid/cobs_link.yaml"),
        spec("model/tests/fixtures/valid/dynamixel2_stuffed.yaml"),
        spec("model/tests/fixtures/valid/xbee_api2.yaml"),
        // FrSky F.Port v1: the end-around sum (`sum8_end_around`) in Lua, over stuffed frames.
        spec("model/tests/fixtures/valid/fport.yaml"),
        // Its uplink alone: escaped from the first byte, no flags, found by the length field.
        spec("model/tests/fixtures/valid/fport_uplink.yaml"),
        // Both ways in one spec: requests between 7E flags, responses without them
        // (`response_ends`, `response_escaping`).
        spec("model/tests/fixtures/valid/fport_both.yaml"),
        // Wake-up bytes before frames (DL/T 645's preamble): the dissector skips them; its
        // payload travels +33H (`framing.transform`): shown transformed back.
        spec("model/tests/fixtures/valid/dlt645.yaml"),
        // Fields after lists, and several lists (with and without a length field).
        spec("model/tests/fixtures/valid/lists_after.yaml"),
        spec("model/tests/fixtures/valid/lists_length.yaml"),
        // Packed elements (CRSF's 16 × 11-bit channels), least and most significant bit first.
        built_in("crsf", "spec/crsf.yaml"),
        spec("model/tests/fixtures/valid/packed_channels.yaml"),
        // Records of a fixed count (UBX-shaped fixed blocks), and lists of floats and 64-bit
        // integers counted by a field (word-swapped floats counted in bytes).
        spec("model/tests/fixtures/valid/ubx_fixed_blocks.yaml"),
        spec("model/tests/fixtures/valid/float_lists.yaml"),
        // Repeated records: a list of objects, each field as a field of its own prints.
        spec("model/tests/fixtures/valid/records.yaml"),
        // Records whose width a field gives, and Dynamixel 2.0 built in (its SYNC_WRITE).
        spec("model/tests/fixtures/valid/records_sized.yaml"),
        built_in("dynamixel2", "spec/dynamixel2.yaml"),
        // Optional fields: shown only where their condition holds.
        spec("model/tests/fixtures/valid/optional_sensor.yaml"),
        // Text a count field counts, with fields after it: shown as text.
        spec("model/tests/fixtures/valid/text_counted.yaml"),
        // Text up to a terminator, one before fields and two in one message: shown as text,
        // without the terminator.
        spec("model/tests/fixtures/valid/text_terminated.yaml"),
        // A length field whose width the start byte chooses (VESC): short and long frames
        // dissected laid out in the long form's width.
        spec("model/tests/fixtures/valid/vesc.yaml"),
        // The 16-bit sum negated, covering from the code past a header byte (JBD's BMS).
        spec("model/tests/fixtures/valid/jbd_bms.yaml"),
        // A layout per direction (Sensirion SHDLC): a reply's state byte, which requests lack,
        // and its length field one byte further.
        spec("model/tests/fixtures/valid/shdlc.yaml"),
        // Frames only end bytes delimit (Nextion): a list ends at the first FF FF FF.
        spec("model/tests/fixtures/valid/nextion.yaml"),
        // A flag two frames share (KISS's FEND): the earlier frame's packet lacks its closing
        // flag, the next packet's first byte.
        spec("model/tests/fixtures/valid/kiss.yaml"),
        // DLE stuffing (Garmin's serial link): 10 doubled inside, the frame ends at DLE ETX.
        spec("model/tests/fixtures/valid/garmin_link.yaml"),
        // The same without a size or checksum (Trimble TSIP).
        spec("model/tests/fixtures/valid/tsip.yaml"),
        // A 24-bit CRC (RTCM 3's CRC-24Q).
        spec("model/tests/fixtures/valid/rtcm3_frame.yaml"),
        // Header fields whose value every frame holds (a header length, a reserved byte).
        spec("model/tests/fixtures/valid/header_constant.yaml"),
        // Header fields in three places, around the code and the length (NovAtel OEM).
        spec("model/tests/fixtures/valid/novatel_oem.yaml"),
        // A reply whose checksum takes in its request's bytes (Pelco D's general response).
        spec("model/tests/fixtures/valid/pelco_d_replies.yaml"),
        // Messages without a checksum beside replies whose CRC takes in the read's bytes
        // (RoboClaw).
        spec("model/tests/fixtures/valid/roboclaw.yaml"),
        // A short form of the frame (M-Bus) is not compared here yet: the dissector words a
        // short frame's out-of-spec address at its laid-out offset (5, not 2). Its dissector
        // loads and survives random bytes (`every_fixture_dissector_loads_...`).
        derived_units(),
    ]
}

/// `minimal.yaml` with units whose values have no finite decimal (1/3, busspec prints the
/// nearest double) or need many places and an offset, its examples' stated values left out.
fn derived_units() -> Case {
    let text = std::fs::read_to_string(root().join("model/tests/fixtures/valid/minimal.yaml"))
        .unwrap()
        .replace("scale: \"0.01\"", "scale: \"1/3\"")
        .replace(
            "scale: \"360/4096\"",
            "scale: \"7/1048576\"\n    offset: \"-0.000123\"",
        );
    let mut out = Vec::new();
    let (mut skipping, mut examples) = (false, false);
    for line in text.lines() {
        examples |= line.starts_with("examples:");
        let indent = line.len() - line.trim_start().len();
        if skipping && indent > 4 {
            continue;
        }
        skipping = false;
        if examples && line.trim_start().starts_with("values:") {
            skipping = !line.contains('{');
            continue;
        }
        out.push(line);
    }
    // Under cargo's scratch directory for tests, one file whatever the process: written
    // whole, then renamed over, so a test reading it while another writes it sees all of it.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let file = dir.join("busspec-dissector-units.yaml");
    let part = dir.join(format!(
        "busspec-dissector-units.{}.{:?}.part",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::write(&part, out.join("\n")).unwrap();
    std::fs::rename(&part, &file).unwrap();
    let file: &'static str = Box::leak(file.display().to_string().into_boxed_str());
    let p = load(file);
    Case {
        args: vec![p.name.clone(), "--spec".into(), file.into()],
        file,
    }
}

fn load(file: &str) -> Protocol {
    load_file(&root().join(file)).unwrap_or_else(|d| panic!("{d}"))
}

/// The frame of example `e` with one value past its range (a whole field, not repeated, with
/// room in its width), with a header field holding another value than its message gives it,
/// or with an address no device has, resealed: out of spec or no frame, good checksum.
fn out_of_spec(p: &Protocol, wire: &[u8], r: busspec_model::ir::MessageRef) -> Vec<Vec<u8>> {
    let m = p.message(r);
    let mut frames = Vec::new();
    for (i, f) in m.fields.iter().enumerate() {
        let Some((min, max)) = f.range else { continue };
        if f.repeat.is_some() || !f.bits.is_empty() || f.is_ascii() || f.equals.is_some() {
            continue;
        }
        let (lo, hi) = interp::raw_limits(8 * f.width as u32, f.signed);
        let v = if max < hi {
            max + 1
        } else if min > lo {
            min - 1
        } else {
            continue;
        };
        if f.special.iter().any(|s| s.value == v) {
            continue;
        }
        let mut w = laid(p, r.direction, wire);
        let mut at = f.frame_at(&m.layout);
        if f.present.is_some() {
            // An optional field: where the frame has it, if it does.
            let Ok(sh) = interp::shape(p, m, &w) else {
                continue;
            };
            if !sh.present(m, i) {
                continue;
            }
            at = m.layout.payload + sh.at(m, i);
        }
        interp::write_uint(v as u64, &mut w[at..at + f.width], f.byte_order);
        interp::reseal_as(p, r.direction, &mut w);
        frames.push(sent(p, r.direction, w));
        break;
    }
    // A header field the message gives a value (`header:`) holding another: not that message.
    if let Some(f) = m.fields.iter().find(|f| f.header && f.constant.is_some()) {
        let mut w = laid(p, r.direction, wire);
        let at = f.frame_at(&m.layout);
        let other = f.constant.unwrap_or(0) ^ 1;
        interp::write_uint(other, &mut w[at..at + f.width], f.byte_order);
        interp::reseal_as(p, r.direction, &mut w);
        frames.push(sent(p, r.direction, w));
    }
    if let Some(at) = m.layout.address {
        let bad = (0..=255u8).rev().find(|a| !interp::address_allowed(p, *a));
        if let Some(a) = bad {
            let mut w = laid(p, r.direction, wire);
            w[at] = a;
            interp::reseal_as(p, r.direction, &mut w);
            frames.push(sent(p, r.direction, w));
        }
    }
    frames
}

/// `wire` after its preamble and unescaped as a frame of direction `d` (`framing.preamble`,
/// `framing.escaping`; as it is without): frames are changed unescaped and escaped again
/// ([`escape::escape_as`]), and sent without a preamble.
fn plain(p: &Protocol, d: Direction, wire: &[u8]) -> Vec<u8> {
    escape::unescape_bytes_of(&p.framing, d, p.framing.after_preamble(wire)).unwrap()
}

/// [`plain`], laid out as the IR lays it out (a short form's or a long length form's short
/// frame with the bytes it lacks), where offsets of the IR count.
fn laid(p: &Protocol, d: Direction, wire: &[u8]) -> Vec<u8> {
    let w = plain(p, d, wire);
    busspec_model::long::canonical(p, &w).map_or(w.clone(), |c| c.frame.into_owned())
}

/// A frame [`laid`] out, as it travels: in the form it takes, escaped.
fn sent(p: &Protocol, d: Direction, w: Vec<u8>) -> Vec<u8> {
    escape::escape_as(p, d, &busspec_model::long::travel(p, w))
}

/// The capture of `p`: every example with noise before every third, then out-of-spec frames
/// each between two good ones, then every example with a bad checksum between two good ones.
/// Returns it and the bad-checksum frames with their messages.
fn capture(p: &Protocol) -> (Vec<u8>, Vec<(Vec<u8>, String)>) {
    let noise: [&[u8]; 3] = [&[0x00, 0x13], &[0xFF], &[0x01, 0x02, 0x03]];
    let mut bytes = Vec::new();
    for (n, e) in p.examples.iter().enumerate() {
        if n % 3 == 1 {
            bytes.extend_from_slice(noise[(n / 3) % noise.len()]);
        }
        bytes.extend_from_slice(&e.wire);
    }
    let good = p
        .examples
        .first()
        .map(|e| e.wire.clone())
        .unwrap_or_default();
    for e in &p.examples {
        for f in out_of_spec(p, &e.wire, e.message) {
            bytes.extend_from_slice(&f);
            bytes.extend_from_slice(&good);
        }
    }
    // Each example with random payload bytes, resealed: values all over their range (and
    // past it), whatever busspec makes of them.
    let mut rng = fastrand::Rng::with_seed(p.examples.len() as u64);
    for e in &p.examples {
        let m = p.message(e.message);
        let end = e.wire.len().saturating_sub(interp::trailer_of(p, m));
        if end <= m.layout.payload {
            continue;
        }
        // Floats and 64-bit numbers printed in Lua as busspec prints them: many more bit
        // patterns (subnormals, infinities and NaNs among them).
        let rounds = if m.fields.iter().any(|f| f.is_wide()) {
            60
        } else {
            3
        };
        for _ in 0..rounds {
            let d = e.message.direction;
            let mut w = plain(p, d, &e.wire);
            let end = w.len().saturating_sub(interp::trailer_of(p, m));
            w[m.layout.payload..end]
                .iter_mut()
                .for_each(|b| *b = rng.u8(..));
            interp::reseal_as(p, d, &mut w);
            bytes.extend_from_slice(&escape::escape_as(p, d, &w));
            bytes.extend_from_slice(&good);
        }
    }
    let mut bad = Vec::new();
    if !p.framing.checksum.is_empty() {
        // A constant whole frame has no checksum to change, nor a message without one.
        for e in p.examples.iter().filter(|e| {
            let m = p.message(e.message);
            m.frame.is_none() && !m.unchecked
        }) {
            // The checksum changed where the spec computes it: before escaping, or on the
            // bytes as they travel.
            let escaped = p
                .framing
                .escaping
                .as_ref()
                .is_some_and(|x| x.computed == busspec_model::ir::Computed::Escaped);
            let mut w = if escaped {
                e.wire.clone()
            } else {
                plain(p, e.message.direction, &e.wire)
            };
            let at = p.framing.checksum_at_of(e.message.direction, w.len());
            w[at] ^= 0x01;
            if !escaped {
                w = escape::escape_bytes_of(&p.framing, e.message.direction, &w);
            }
            bytes.extend_from_slice(&good);
            bytes.extend_from_slice(&w);
            bad.push((w, p.message(e.message).name.clone()));
        }
        bytes.extend_from_slice(&good);
    }
    // Each reply whose values follow from its request's (`follows: {request}`, a count from
    // the request) after a request whose field says otherwise: busspec decodes it as if
    // unpaired (ambiguous where only the request told it apart), the dissector alike.
    for (request, reply) in mismatched_pairs(p) {
        bytes.extend_from_slice(&request);
        bytes.extend_from_slice(&reply);
        bytes.extend_from_slice(&good);
    }
    (bytes, bad)
}

/// For each example reply with a field that follows from its request's field `x` (its value or
/// its element count), an example of that request with `x` one more (or one less, within its
/// range), and the reply as it is.
fn mismatched_pairs(p: &Protocol) -> Vec<(Vec<u8>, Vec<u8>)> {
    use busspec_model::ir::Follows;
    let mut out = Vec::new();
    for e in &p.examples {
        let Some(c) = e.reply_to else { continue };
        let m = p.message(e.message);
        let rules: Vec<&str> = m
            .fields
            .iter()
            .filter_map(|f| {
                match (
                    &f.follows,
                    f.repeat.as_ref().and_then(|r| r.request.as_ref()),
                ) {
                    (Some(Follows::Request(rel)), _) | (_, Some(rel)) => Some(rel.field.as_str()),
                    _ => None,
                }
            })
            .collect();
        let Some(q) = p
            .examples
            .iter()
            .find(|x| x.message.direction == Direction::Request && x.message.index == c)
        else {
            continue;
        };
        let Ok(frame) = interp::decode(p, Some(Direction::Request), None, &q.wire) else {
            continue;
        };
        let cmd = &p.commands[c];
        for name in rules {
            let Some(f) = cmd.fields.iter().find(|f| f.name == name) else {
                continue;
            };
            let (lo, hi) = f
                .range
                .unwrap_or(interp::raw_limits(8 * f.width as u32, f.signed));
            let mut values = frame.values.clone();
            let Some(v) = values.iter_mut().find(|v| v.name == name) else {
                continue;
            };
            let Raw::Int(x) = v.raw else { continue };
            v.raw = Raw::Int(if x < hi {
                x + 1
            } else if x > lo {
                x - 1
            } else {
                continue;
            });
            if let Ok(w) = interp::encode(p, q.message, frame.address, &values) {
                out.push((w, e.wire.clone()));
            }
        }
    }
    out
}

/// Every (key, value) of a packet's layers as tshark prints them, trees flattened.
fn flatten(v: &Value, out: &mut BTreeMap<String, Vec<String>>) {
    match v {
        Value::Object(map) => {
            for (k, v) in map {
                match v {
                    Value::String(s) => out.entry(k.clone()).or_default().push(s.clone()),
                    Value::Array(items) => {
                        for i in items {
                            match i {
                                Value::String(s) => {
                                    out.entry(k.clone()).or_default().push(s.clone())
                                }
                                other => flatten(other, out),
                            }
                        }
                    }
                    other => flatten(other, out),
                }
            }
        }
        Value::Array(items) => items.iter().for_each(|i| flatten(i, out)),
        _ => {}
    }
}

/// The packets tshark shows with `lua`, each flattened; fails on a Lua error anywhere.
fn tshark(pcapng: &Path, lua: &Path) -> Vec<BTreeMap<String, Vec<String>>> {
    let out = Command::new("tshark")
        .args(["-r", pcapng.to_str().unwrap(), "-X"])
        .arg(format!("lua_script:{}", lua.display()))
        .args(["-2", "-T", "json", "--no-duplicate-keys"])
        .output()
        .expect("run tshark");
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_no_lua_error(&stderr, &text(&out.stdout));
    let packets: Vec<Value> = serde_json::from_slice(&out.stdout).expect("tshark's JSON");
    packets
        .iter()
        .map(|p| {
            let mut m = BTreeMap::new();
            flatten(&p["_source"]["layers"], &mut m);
            m
        })
        .collect()
}

/// tshark reports a script that does not load on stderr, and an error a dissector raises in
/// the packet's tree (`_ws.lua.error`, "Lua Error").
fn assert_no_lua_error(stderr: &str, stdout: &str) {
    assert!(
        !stderr.to_lowercase().contains("lua"),
        "a Lua error: {stderr}"
    );
    let at = ["Lua Error", "_ws.lua.error", "_ws.malformed"]
        .iter()
        .find_map(|e| stdout.find(e));
    if let Some(at) = at {
        panic!(
            "a Lua error: {}",
            &stdout[at.saturating_sub(2000)..(at + 2000).min(stdout.len())]
        );
    }
}

/// A packet's one value of `key`, if it has it.
fn one<'a>(packet: &'a BTreeMap<String, Vec<String>>, key: &str) -> Option<&'a str> {
    packet.get(key).map(|v| {
        assert_eq!(v.len(), 1, "{key}: {v:?}");
        v[0].as_str()
    })
}

/// tshark's relative time (`0.002604166`) in nanoseconds.
fn nanos(t: &str) -> i128 {
    let (s, f) = t.split_once('.').unwrap_or((t, ""));
    let f = format!("{f:0<9}");
    s.parse::<i128>().unwrap() * 1_000_000_000 + f[..9].parse::<i128>().unwrap()
}

fn raw_text(raw: &Raw) -> String {
    match raw {
        Raw::Int(i) => i.to_string(),
        Raw::List(l) => format!(
            "[{}]",
            l.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ),
        Raw::Text(t) => t.iter().map(|b| format!("{b:02x}")).collect(),
        Raw::Records(r) => format!(
            "[{}]",
            r.iter()
                .map(|rec| format!(
                    "[{}]",
                    rec.iter()
                        .map(|v| v.to_string())
                        .collect::<Vec<_>>()
                        .join(",")
                ))
                .collect::<Vec<_>>()
                .join(",")
        ),
    }
}

#[derive(Default)]
struct Counts {
    frames: usize,
    fields: usize,
    out_of_spec: usize,
    bad_checksum: usize,
    paired: usize,
    noise: usize,
}

/// Holds every packet of `p`'s capture as tshark shows it to busspec's JSON lines.
fn compare(p: &Protocol, case: &Case, dir: &Path) -> Counts {
    let (bytes, bad) = capture(p);
    let raw = dir.join(format!("{}.bin", p.name));
    let pcapng = dir.join(format!("{}.pcapng", p.name));
    let lua = dir.join(format!("{}.lua", p.name));
    std::fs::write(&raw, &bytes).unwrap();
    let mut args: Vec<&str> = vec!["decode"];
    args.extend(case.args.iter().map(String::as_str));
    args.extend([
        "--stream",
        raw.to_str().unwrap(),
        "--pcapng",
        pcapng.to_str().unwrap(),
    ]);
    let out = run(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let lines = text(&out.stdout);
    let mut args: Vec<&str> = vec!["dissector"];
    if case.args.len() > 1 {
        args.extend(["--spec", case.file]);
    } else {
        args.push(&case.args[0]);
    }
    args.extend(["-o", lua.to_str().unwrap()]);
    let out = run(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));

    let packets = tshark(&pcapng, &lua);
    let events: Vec<BTreeMap<String, Box<RawValue>>> = lines
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(packets.len(), events.len(), "{}: {lines}", p.name);

    let abbr = format!("busspec_{}", p.name);
    let key = |k: &str| format!("{abbr}.{k}");
    let relaxed = stream::relaxed(p);
    let parity = u128::from(!matches!(p.serial.parity, busspec_model::ir::Parity::None));
    let bits = 1 + u128::from(p.serial.data_bits) + parity + u128::from(p.serial.stop_bits);
    let time = |offset: u64| {
        (u128::from(offset) * bits * 1_000_000_000 / u128::from(p.serial.baud)) as i128
    };
    let mut counts = Counts::default();
    // busspec's pairing: the last request since the previous response (packet number, command
    // index, offset); a response (but one sent unasked the request does not get), an
    // out-of-spec or an ambiguous frame ends it.
    let mut last: Option<(usize, usize, u64)> = None;
    let mut response_in: BTreeMap<usize, usize> = BTreeMap::new();
    let mut expected_response_to: Vec<Option<usize>> = vec![None; events.len()];
    // Whether each event is a response sent unasked that the request before it does not get.
    let mut aside = vec![false; events.len()];
    for (i, e) in events.iter().enumerate() {
        let get = |k: &str| e.get(k).map(|v| v.get().to_owned());
        let offset: u64 = get("offset").unwrap().parse().unwrap();
        let direction = get("direction").map(|d| d.trim_matches('"').to_owned());
        if e.contains_key("out_of_spec") || e.contains_key("ambiguous") {
            last = None;
        } else if let (Some(d), Some(m)) = (&direction, get("message")) {
            let m = m.trim_matches('"');
            if d == "request" {
                let r = p.find_in(m, Direction::Request).unwrap();
                last = Some((i + 1, r.index, offset));
            } else {
                // A response sent unasked that the request does not get is not its reply,
                // and leaves the request waiting for it.
                let r = p.find_in(m, Direction::Response).unwrap();
                let reply = |c: usize| !p.message(r).unasked || p.commands[c].gets(r.index);
                aside[i] = last.is_some_and(|(_, c, _)| !reply(c));
                if let Some((n, _, _)) = last.filter(|&(_, c, _)| reply(c)) {
                    expected_response_to[i] = Some(n);
                    response_in.insert(n, i + 1);
                }
                if !aside[i] {
                    last = None;
                }
            }
        }
    }

    let mut last_request: Option<(usize, u64)> = None;
    // That request's frame, whose bytes a reply's checksum may take in.
    let mut last_bytes: Vec<u8> = Vec::new();
    for (i, (e, packet)) in events.iter().zip(&packets).enumerate() {
        let what = format!("{} packet {}: {e:?}\n{packet:#?}", p.name, i + 1);
        let get = |k: &str| e.get(k).map(|v| v.get().to_owned());
        let unquote = |s: String| s.trim_matches('"').to_owned();
        let hex = get("bytes").map(unquote);
        let offset: u64 = get("offset").unwrap().parse().unwrap();
        match (get("message").map(unquote), get("direction").map(unquote)) {
            (Some(message), Some(direction)) => {
                let d = if direction == "request" {
                    Direction::Request
                } else {
                    Direction::Response
                };
                assert_eq!(
                    one(packet, &key("message")),
                    Some(message.as_str()),
                    "{what}"
                );
                assert_eq!(
                    one(packet, &key("direction")),
                    Some(direction.as_str()),
                    "{what}"
                );
                assert_eq!(
                    one(packet, &key("code")),
                    get("code").map(unquote).as_deref(),
                    "{what}"
                );
                assert_eq!(
                    one(packet, &key("address")),
                    get("address").as_deref(),
                    "{what}"
                );
                let r = p.find_in(&message, d).unwrap();
                assert_eq!(
                    one(packet, &key("section")),
                    Some(p.message(r).section.as_str()),
                    "{what}"
                );
                // A constant whole frame (M-Bus's E5) has no checksum to show, nor a message
                // that travels without one (RoboClaw's reads).
                if p.message(r).frame.is_some() || p.message(r).unchecked {
                    assert_eq!(one(packet, &key("checksum.status")), None, "{what}");
                } else if !p.framing.checksum.is_empty() {
                    assert_eq!(one(packet, &key("checksum.status")), Some("1"), "{what}");
                }
                // The raw values, as busspec decodes them with the spec's rules lifted.
                let end = events
                    .get(i + 1)
                    .map_or(bytes.len(), |n| n["offset"].get().parse().unwrap());
                let frame_bytes = match &hex {
                    Some(h) => interp::parse_hex(h).unwrap(),
                    // A flag two frames share is the later one's packet's: this frame's
                    // closing flag is the next event's first byte (a frame of a direction
                    // that ends in it: F.Port's uplink has no flags).
                    None => match p.framing.shared_flag() {
                        Some(f)
                            if p.framing.end_of(d) == [f]
                                && bytes[..end].last() != Some(&f)
                                && bytes.get(end) == Some(&f) =>
                        {
                            bytes[offset as usize..=end].to_vec()
                        }
                        _ => bytes[offset as usize..end].to_vec(),
                    },
                };
                // The stream decodes an out-of-spec frame without its request.
                let reply_to = match d {
                    Direction::Response if !e.contains_key("out_of_spec") => {
                        last_request.map(|(idx, _)| idx)
                    }
                    _ => None,
                };
                // Strictly where the frame is in spec, with its request where that settles it
                // (a frame only one message fits is that message whatever came before it).
                let covered = reply_to.and_then(|_| p.checksum_span(&last_bytes));
                let decoded = interp::decode_with(p, Some(d), reply_to, covered, &frame_bytes)
                    .or_else(|_| interp::decode(p, Some(d), None, &frame_bytes))
                    .or_else(|_| {
                        stream::decode_lenient(p, &relaxed, Some(d), reply_to, &frame_bytes)
                            .map(|f| f.0)
                    })
                    .or_else(|_| {
                        stream::decode_lenient(p, &relaxed, Some(d), None, &frame_bytes)
                            .map(|f| f.0)
                    })
                    .unwrap_or_else(|err| panic!("{err}: {what}"));
                let fields: BTreeMap<String, Box<RawValue>> =
                    serde_json::from_str(e["fields"].get()).unwrap();
                assert_eq!(fields.len(), decoded.values.len(), "{what}");
                let mname = p
                    .message(r)
                    .name
                    .replace(|c: char| !c.is_alphanumeric() && c != '_', "_");
                for v in &decoded.values {
                    let leaf = v
                        .name
                        .replace(|c: char| !c.is_alphanumeric() && c != '_', "_");
                    let k = key(&format!("field.{mname}.{leaf}"));
                    let printed = fields[v.name.as_ref()].get();
                    assert_eq!(one(packet, &k), Some(printed), "{k}: {what}");
                    let shown_raw = one(packet, &format!("{k}.raw")).unwrap_or_default();
                    assert_eq!(
                        shown_raw.replace(':', "").to_lowercase(),
                        raw_text(&v.raw).to_lowercase(),
                        "{k}.raw: {what}"
                    );
                    counts.fields += 1;
                }
                match get("out_of_spec").map(unquote) {
                    Some(reason) => {
                        let shown = packet.get(&key("out_of_spec")).cloned().unwrap_or_default();
                        assert_eq!(shown.first(), Some(&reason), "{what}");
                        counts.out_of_spec += 1;
                        last_request = None;
                    }
                    None => {
                        assert_eq!(packet.get(&key("out_of_spec")), None, "{what}");
                        counts.frames += 1;
                        // An unasked response its request does not get leaves it waiting.
                        if !aside[i] {
                            last_request = match d {
                                Direction::Request => Some((r.index, offset)),
                                Direction::Response => None,
                            };
                            last_bytes = frame_bytes.clone();
                        }
                    }
                }
                // Pairing and the time between request and response.
                let to = one(packet, &key("response_to"));
                assert_eq!(
                    to.map(|t| t.parse::<usize>().unwrap()),
                    expected_response_to[i],
                    "response_to: {what}"
                );
                if let Some(n) = expected_response_to[i] {
                    let req_offset: u64 = events[n - 1]["offset"].get().parse().unwrap();
                    let shown = one(packet, &key("time")).expect("time");
                    assert_eq!(nanos(shown), time(offset) - time(req_offset), "{what}");
                    counts.paired += 1;
                }
                assert_eq!(
                    one(packet, &key("response_in")).map(|t| t.parse::<usize>().unwrap()),
                    response_in.get(&(i + 1)).copied(),
                    "response_in: {what}"
                );
            }
            _ if e.contains_key("ambiguous") || e.contains_key("out_of_spec") => {
                last_request = None;
                assert!(
                    packet.contains_key(&key("ambiguous"))
                        || packet.contains_key(&key("out_of_spec"))
                        || packet.contains_key(&key("skipped")),
                    "{what}"
                );
            }
            _ => {
                // Noise to busspec: never a good frame to the dissector. A packet that is
                // one of the frames given a bad checksum is decoded with it.
                let frame = interp::parse_hex(hex.as_deref().unwrap_or("")).unwrap();
                let status = one(packet, &key("checksum.status"));
                assert_ne!(
                    (status, packet.contains_key(&key("message"))),
                    (Some("1"), true),
                    "{what}"
                );
                if let Some((_, message)) = bad.iter().find(|(b, _)| *b == frame) {
                    assert_eq!(status, Some("0"), "{what}");
                    // After the first example (a request where the spec has one): a reply's
                    // checksum that takes in its request's bytes is checked over them.
                    let covered = p.examples.first().and_then(|e| p.checksum_span(&e.wire));
                    let why = interp::decode_with(p, None, None, covered, &frame)
                        .unwrap_err()
                        .to_string();
                    assert!(why.starts_with("checksum mismatch"), "{why}");
                    let experts = packet
                        .get("_ws.expert.message")
                        .cloned()
                        .unwrap_or_default();
                    assert!(experts.contains(&why), "{why}: {what}");
                    if let Some(shown) = one(packet, &key("message")) {
                        assert_eq!(shown, message, "{what}");
                    }
                    counts.bad_checksum += 1;
                } else {
                    counts.noise += 1;
                }
            }
        }
    }
    counts
}

#[test]
fn tshark_shows_every_packet_as_busspec_decodes_it() {
    if !cli::tshark_present("the dissector against busspec") {
        return;
    }
    let scratch = temp_dir("every_packet");
    let dir = scratch.path();
    let mut failures = Vec::new();
    for case in cases() {
        let p = load(case.file);
        let c = compare(&p, &case, dir);
        eprintln!(
            "{:>12}: {} frames, {} fields, {} out of spec, {} bad checksums, {} pairs, {} noise packets compared with tshark",
            p.name, c.frames, c.fields, c.out_of_spec, c.bad_checksum, c.paired, c.noise
        );
        let has_fields = p
            .commands
            .iter()
            .chain(&p.responses)
            .any(|m| !m.fields.is_empty());
        if c.frames == 0 || (has_fields && c.fields == 0) {
            failures.push(format!("{}: nothing compared", p.name));
        }
        if !p.framing.checksum.is_empty() && c.bad_checksum == 0 {
            failures.push(format!("{}: no bad checksum compared", p.name));
        }
        if case.args.len() == 1 && c.out_of_spec == 0 {
            failures.push(format!("{}: no out-of-spec frame compared", p.name));
        }
        // Dynamixel's replies to its examples are ambiguous without timing (issue 25).
        if ["ub2", "sd", "modbus"].contains(&p.name.as_str()) && c.paired == 0 {
            failures.push(format!("{}: no pair compared", p.name));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// Every valid fixture spec's dissector loads without a Lua error, and shows a capture of its
/// examples, and random bytes, without one.
#[test]
fn every_fixture_dissector_loads_and_survives_random_bytes() {
    if !cli::tshark_present("loading the fixtures' dissectors") {
        return;
    }
    let scratch = temp_dir("fixtures");
    let dir = scratch.path();
    let mut files: Vec<PathBuf> = ["model/tests/fixtures/valid", "difftest/fixtures"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root().join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .chain([
            root().join("codegen/tests/fixtures/core_names.yaml"),
            root().join("spec/ub2.yaml"),
            root().join("spec/sd.yaml"),
            root().join("spec/modbus.yaml"),
            root().join("spec/dynamixel.yaml"),
        ])
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    files.sort();
    let mut rng = fastrand::Rng::with_seed(25);
    let mut loaded = 0;
    for file in &files {
        let Ok(p) = load_file(file) else { continue };
        let lua = dir.join(format!("{}.lua", p.name));
        let out = run(&[
            "dissector",
            "--spec",
            file.to_str().unwrap(),
            "-o",
            lua.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        // Random bytes, then the examples cut short and run together.
        let mut bytes: Vec<u8> = (0..4000).map(|_| rng.u8(..)).collect();
        for e in &p.examples {
            bytes.extend_from_slice(&e.wire[..e.wire.len() / 2]);
            bytes.extend_from_slice(&e.wire);
            bytes.extend((0..rng.usize(0..4)).map(|_| rng.u8(..)));
        }
        let raw = dir.join(format!("{}.bin", p.name));
        let pcapng = dir.join(format!("{}.pcapng", p.name));
        std::fs::write(&raw, &bytes).unwrap();
        let out = run(&[
            "decode",
            &p.name,
            "--spec",
            file.to_str().unwrap(),
            "--stream",
            raw.to_str().unwrap(),
            "--pcapng",
            pcapng.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let packets = tshark(&pcapng, &lua);
        assert_eq!(
            packets.len(),
            text(&out.stdout).lines().count(),
            "{}",
            p.name
        );
        // Packets no stream cut: examples with bytes changed (resealed or not), cut short or
        // grown, random bytes, in either direction or none.
        let fuzzed = dir.join(format!("{}-fuzzed.pcapng", p.name));
        std::fs::write(&fuzzed, fuzzed_capture(&p, &mut rng)).unwrap();
        let packets = tshark(&fuzzed, &lua);
        assert_eq!(packets.len(), FUZZED, "{}", p.name);
        loaded += 1;
    }
    eprintln!("{loaded} fixture dissectors loaded and read random bytes without a Lua error");
    assert!(loaded >= 18, "{loaded}");
}

const FUZZED: usize = 600;

/// A pcapng file of [`FUZZED`] packets made to reach every path of the dissector.
fn fuzzed_capture(p: &Protocol, rng: &mut fastrand::Rng) -> Vec<u8> {
    use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
    use pcap_file::pcapng::blocks::interface_description::{
        InterfaceDescriptionBlock, InterfaceDescriptionOption,
    };
    use pcap_file::pcapng::PcapNgWriter;
    use pcap_file::DataLink;
    use std::borrow::Cow;

    let mut w = PcapNgWriter::new(Vec::new()).unwrap();
    w.write_pcapng_block(InterfaceDescriptionBlock {
        linktype: DataLink::from(147u32),
        snaplen: 0,
        options: vec![InterfaceDescriptionOption::IfDescription(Cow::Owned(
            format!("busspec {}", p.name),
        ))],
    })
    .unwrap();
    for n in 0..FUZZED {
        let mut data = match (p.examples.is_empty(), n % 4) {
            (true, _) | (_, 0) => (0..rng.usize(0..80)).map(|_| rng.u8(..)).collect(),
            _ => p.examples[rng.usize(..p.examples.len())].wire.clone(),
        };
        if n % 4 != 0 && !data.is_empty() {
            for _ in 0..rng.usize(1..4) {
                let at = rng.usize(..data.len());
                data[at] = rng.u8(..);
            }
            match n % 4 {
                1 => interp::reseal(p, &mut data),
                2 => data.truncate(rng.usize(..data.len())),
                _ => data.extend((0..rng.usize(1..600)).map(|_| rng.u8(..))),
            }
        }
        let mut options = Vec::new();
        let flags = rng.u32(0..3);
        if flags != 0 {
            options.push(EnhancedPacketOption::Flags(flags));
        }
        w.write_pcapng_block(EnhancedPacketBlock {
            interface_id: 0,
            timestamp: std::time::Duration::from_micros(n as u64 * 1000),
            original_len: data.len() as u32,
            data: Cow::Owned(data),
            options,
        })
        .unwrap();
    }
    w.into_inner()
}

/// A file of several protocols picks each packet's protocol by its interface description.
#[test]
fn one_file_of_every_protocol_picks_each_capture_by_its_interface() {
    if !cli::tshark_present("the dissector of several protocols") {
        return;
    }
    let scratch = temp_dir("several");
    let dir = scratch.path();
    let lua = dir.join("all.lua");
    let out = run(&["dissector", "-o", lua.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    for name in ["ub2", "sd", "modbus", "dynamixel"] {
        let p = load(&format!("spec/{name}.yaml"));
        let raw = dir.join(format!("{name}.bin"));
        let pcapng = dir.join(format!("{name}.pcapng"));
        std::fs::write(&raw, capture(&p).0).unwrap();
        let out = run(&[
            "decode",
            name,
            "--stream",
            raw.to_str().unwrap(),
            "--pcapng",
            pcapng.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(0));
        let packets = tshark(&pcapng, &lua);
        let messages = packets
            .iter()
            .filter(|p| p.contains_key(&format!("busspec_{name}.message")))
            .count();
        let events = text(&out.stdout)
            .lines()
            .filter(|l| l.contains("\"message\""))
            .count();
        assert!(
            messages > 0 && messages >= events,
            "{name}: {messages} of {events}"
        );
    }
}

/// The command line: all four built-in protocols by default, a spec file's protocol with
/// --spec, the same text each time; wrong arguments refused with exit status 2.
#[test]
fn the_command_names_its_protocols_and_refuses_wrong_arguments() {
    let all = run(&["dissector"]);
    assert_eq!(all.status.code(), Some(0), "{}", text(&all.stderr));
    let lua = text(&all.stdout);
    for name in ["ub2", "sd", "modbus", "dynamixel"] {
        let p = load(&format!("spec/{name}.yaml"));
        assert!(lua.contains(&format!("  name = \"{name}\", ")), "{name}");
        assert!(lua.contains(&p.spec_sha256), "{name}");
    }
    assert_eq!(text(&run(&["dissector"]).stdout), lua);

    let fixture = "model/tests/fixtures/valid/pelco_p.yaml";
    let one = text(&run(&["dissector", "--spec", fixture]).stdout);
    assert_eq!(one.matches("SPECS[#SPECS + 1] = {").count(), 1);
    assert!(one.contains(&load(fixture).spec_sha256));
    let two = text(&run(&["dissector", "sd", "--spec", fixture]).stdout);
    assert_eq!(two.matches("SPECS[#SPECS + 1] = {").count(), 2);

    for (args, says) in [
        (vec!["dissector", "nope"], "unknown protocol `nope`"),
        (
            vec!["dissector", "ub2", "ub2"],
            "protocol `ub2` is named twice",
        ),
        (
            vec![
                "dissector",
                "--spec",
                "spec/ub2.yaml",
                "--spec",
                "spec/ub2.yaml",
            ],
            "protocol `ub2` is given twice",
        ),
        (
            vec![
                "dissector",
                "--spec",
                "model/tests/fixtures/broken/address_twice.yaml",
            ],
            "address_twice.yaml",
        ),
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
        assert!(
            text(&out.stderr).contains(says),
            "{args:?}: {}",
            text(&out.stderr)
        );
    }
}

/// The README's picture, `docs/wireshark/ub2.svg`: what tshark shows of a short UB2 capture
/// with the generated dissector (`-V -O busspec_ub2`: the busspec tree of every packet), drawn
/// as a terminal. The test runs tshark again and draws the picture from what it prints; the
/// committed file must be that drawing (`BUSSPEC_UPDATE_SNAPSHOTS=1` writes it), so the
/// picture cannot drift from what the dissector shows.
#[test]
fn the_readme_picture_is_what_tshark_shows() {
    if !cli::tshark_present("the README picture") {
        return;
    }
    // A read and its reply, a stored-position move with an index past the spec's 0..9 (out of
    // spec, checksum good), the device's refusal, and a reply with a bad checksum.
    const CAPTURE: &str = "AA2140010C AA2141013E1F00006A AA2127000CFE AA21945F AA2141013E1F00006B";
    let scratch = temp_dir("picture");
    let dir = scratch.path();
    let raw = dir.join("ub2.bin");
    let bytes: Vec<u8> = busspec_json::parse_hex(CAPTURE).unwrap();
    std::fs::write(&raw, bytes).unwrap();
    let pcapng = dir.join("ub2.pcapng");
    let lua = dir.join("ub2.lua");
    let out = run(&[
        "decode",
        "ub2",
        "--stream",
        raw.to_str().unwrap(),
        "--pcapng",
        pcapng.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let out = run(&["dissector", "ub2", "-o", lua.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let shown = Command::new("tshark")
        .args(["-r", pcapng.to_str().unwrap(), "-X"])
        .arg(format!("lua_script:{}", lua.display()))
        .args(["-2", "-V", "-O", "busspec_ub2"])
        .env("TZ", "UTC")
        .output()
        .expect("run tshark");
    assert!(shown.status.success(), "{}", text(&shown.stderr));
    let shown = text(&shown.stdout);
    assert_no_lua_error("", &shown);
    // What the picture must show, so that a change that loses it fails here and not only in
    // the picture.
    for must in [
        "capacitance: 79.98 pF (raw 7998)",
        "[Response to frame: 1]",
        "[Expert Info (Warning/Protocol): go_to_stored_position.index at offset 4 is 12, outside its range 0..=9]",
        "[Checksum status: Bad (0)]",
    ] {
        assert!(shown.contains(must), "tshark does not show {must:?}:\n{shown}");
    }
    let command = "tshark -r ub2.pcapng -X lua_script:ub2.lua -2 -V -O busspec_ub2";
    // The capture's name in the interface is where the test wrote it: shown as `ub2.bin`.
    let shown = shown.replace(raw.to_str().unwrap(), "ub2.bin");
    let svg = terminal_svg(command, &shown);
    let path = root().join("docs/wireshark/ub2.svg");
    if std::env::var_os("BUSSPEC_UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &svg).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == svg,
        "{} is not what tshark shows now (BUSSPEC_UPDATE_SNAPSHOTS=1 cargo test --test dissector \
         the_readme_picture rewrites it); tshark shows:\n{shown}",
        path.display()
    );
}

/// `text` drawn as a terminal window running `command`: monospace lines, a frame's summary
/// line and the protocol's line in their own colours, errors in red, warnings in yellow.
fn terminal_svg(command: &str, text: &str) -> String {
    const LINE: usize = 16;
    const CHAR: f64 = 7.2;
    const TOP: usize = 44;
    let lines: Vec<&str> = text.lines().filter(|l| *l != "Packet comments").collect();
    let widest = lines
        .iter()
        .map(|l| l.chars().count())
        .chain([command.chars().count() + 2])
        .max()
        .unwrap_or(0);
    let width = (widest as f64 * CHAR).ceil() as usize + 48;
    let height = TOP + LINE * lines.len() + 16;
    let escape = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" \
         viewBox=\"0 0 {width} {height}\" font-family=\"DejaVu Sans Mono, Menlo, Consolas, monospace\" \
         font-size=\"12\">\n\
         <!-- Drawn by tests/dissector.rs from what tshark printed; do not edit. -->\n\
         <rect width=\"{width}\" height=\"{height}\" rx=\"8\" fill=\"#1e1e1e\"/>\n\
         <rect width=\"{width}\" height=\"24\" rx=\"8\" fill=\"#3c3c3c\"/>\n\
         <circle cx=\"16\" cy=\"12\" r=\"5\" fill=\"#ff5f56\"/><circle cx=\"32\" cy=\"12\" r=\"5\" \
         fill=\"#ffbd2e\"/><circle cx=\"48\" cy=\"12\" r=\"5\" fill=\"#27c93f\"/>\n\
         <text x=\"16\" y=\"{}\" fill=\"#9cdcfe\" xml:space=\"preserve\">$ {}</text>\n",
        TOP - 4,
        escape(command)
    );
    for (n, line) in lines.iter().enumerate() {
        let colour = if line.starts_with("Frame ") {
            "#808080"
        } else if line.starts_with("busspec ") {
            "#4ec9b0"
        } else if line.contains("Expert Info (Error") || line.contains("Bad (0)") {
            "#f48771"
        } else if line.contains("Expert Info (Warning") || line.contains("[Out of spec") {
            "#dcdcaa"
        } else {
            "#d4d4d4"
        };
        svg.push_str(&format!(
            "<text x=\"16\" y=\"{}\" fill=\"{colour}\" xml:space=\"preserve\">{}</text>\n",
            TOP + LINE * (n + 1),
            escape(line)
        ));
    }
    svg.push_str("</svg>\n");
    svg
}
