//! The `busspec` CLI's decode and encode as a process: exit codes, the stderr format, one
//! decode, one encode, one stream, run-time specs, arguments. The JSON contract itself (every
//! value kind, the round trip, errors, streams, request pairing) is tested in process, through
//! both engines, in busspec-json's tests (json/tests/).

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use busspec_model::ir::Direction;
use busspec_model::{load_file, Protocol};

#[path = "common/cli.rs"]
mod cli;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run_in(dir: &Path, args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_busspec"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run busspec");
    {
        let mut input = child.stdin.take().expect("stdin");
        input.write_all(stdin).expect("write stdin");
    }
    child.wait_with_output().expect("wait for busspec")
}

fn busspec(args: &[&str]) -> Output {
    run_in(root(), args, b"")
}

fn busspec_stdin(args: &[&str], stdin: &str) -> Output {
    run_in(root(), args, stdin.as_bytes())
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn spec(name: &str) -> Protocol {
    load_file(&root().join("spec").join(name)).unwrap_or_else(|d| panic!("{d}"))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

/// A scratch directory for `tag`, removed when dropped.
fn temp_dir(tag: &str) -> tempfile::TempDir {
    cli::scratch(&format!("cli-decode-{tag}"))
}

const ACTUAL_79_98: &str = r#"{"protocol":"ub2","direction":"response","address":33,"code":"0x4101","message":"actual_capacitance","fields":{"capacitance":79.98}}"#;

#[test]
fn documented_frame_decodes_to_exact_json() {
    for frame in [
        "AA21 4101 3E1F 0000 6A",
        "0xAA21 4101 3E1F 0000 6A",
        "AA2141013E1F00006A",
        "0xAA 0x21 0x41 0x01 0x3E 0x1F 0x00 0x00 0x6A",
    ] {
        let out = busspec(&["decode", "ub2", frame]);
        assert_eq!(out.status.code(), Some(0), "{frame}: {}", text(&out.stderr));
        assert_eq!(text(&out.stdout), format!("{ACTUAL_79_98}\n"), "{frame}");
        assert!(out.stderr.is_empty());
    }
}

#[test]
fn forcing_the_wrong_direction_fails_naming_the_frame() {
    let out = busspec(&["decode", "ub2", "--direction", "response", "AA21 4300 0E"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains(r#""message":"set_acceleration_speed_index_ack""#));
    let out = busspec(&["decode", "ub2", "--direction", "request", "AA21 501B"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    assert!(
        text(&out.stderr).starts_with("frame 1 (AA21 501B): "),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn a_bad_frame_is_named_on_stderr_and_the_others_still_print() {
    let out = busspec(&[
        "decode",
        "ub2",
        "AA21 4101 3E1F 0000 6A",
        "AA21 4101 0000 1F3E 6B",
        "zz",
        "AA21 501B",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    assert_eq!(lines[0], ACTUAL_79_98);
    assert!(lines[1].contains(r#""message":"movement_started""#));
    assert_eq!(
        text(&out.stderr),
        "frame 2 (AA21 4101 0000 1F3E 6B): checksum mismatch at offset 8: expected 0x6A, found 0x6B\n\
         frame 3 (zz): `z` at character 1 is not a hex digit\n"
    );
}

#[test]
fn encode_takes_direction_and_code_optionally() {
    let out = busspec_stdin(
        &["encode", "ub2"],
        "{\"message\":\"actual_capacitance\",\"address\":33,\"fields\":{\"capacitance\":79.98}}\n\
         \n\
         {\"protocol\":\"ub2\",\"direction\":\"request\",\"code\":\"0x2000\",\"message\":\"go_to_capacitance\",\"address\":33,\"fields\":{\"target\":150}}\n\
         {\"message\":\"go_to_capacitance\",\"address\":33,\"fields\":{\"target\":1.5e2}}\n\
         {\"message\":\"reference_run\",\"address\":33}\n\
         {\"message\":\"status\",\"address\":33,\"fields\":{\"error_bits\":[\"oca\",\"reset\",128],\"reserved\":0}}\n",
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "AA2141013E1F00006A\nAA212000983A0000BD\nAA212000983A0000BD\nAA211000DB\nAA214122A100CF\n"
    );
    // The flags round trip, unnamed bit included.
    let out = busspec(&["decode", "ub2", "AA214122A100CF"]);
    assert!(
        text(&out.stdout).contains(r#""fields":{"error_bits":["oca","reset",128],"reserved":0}"#),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn encode_reports_each_bad_line_and_goes_on() {
    let input = [
        r#"{"message":"go_to_capacitance","address":33,"fields":{"target":79.985}}"#,
        r#"not json"#,
        r#"{"message":"go_to_capacitanse","address":33}"#,
        r#"{"message":"go_to_capacitance","address":33,"fields":{}}"#,
        r#"{"message":"go_to_capacitance","address":33,"fields":{"target":50000000}}"#,
        "",
        r#"{"message":"reference_run","address":33}"#,
        r#"{"message":"go_to_capacitance","address":33,"code":"0x2001","fields":{"target":1}}"#,
        r#"{"message":"set_mode_of_operation","address":33,"fields":{"mode":"turbo"}}"#,
        r#"{"message":"go_to_capacitance","address":33,"fields":{"targt":1}}"#,
        r#"{"message":"go_to_capacitance","direction":"response","address":33,"fields":{"target":1}}"#,
        r#"{"protocol":"sd","message":"reference_run","address":33}"#,
        r#"{"message":"reference_run","address":300}"#,
    ]
    .join("\n");
    let out = busspec_stdin(&["encode", "ub2"], &input);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout), "AA211000DB\n");
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(
        lines,
        [
            "line 1: target: 79.985 pF is not a whole number of steps of 0.01 pF",
            "line 2: invalid JSON at column 2: expected ident",
            "line 3: unknown message `go_to_capacitanse` in ub2",
            "line 4: no value given for field target",
            "line 5: target: 50000000 pF is out of range: the field holds 0 pF to 42949672.95 pF",
            "line 8: code 0x2001 does not match go_to_capacitance (0x2000)",
            "line 9: mode: `turbo` is not a value of mode_of_operation (one of: encoder_disabled, close_loop_control, open_loop_control)",
            "line 10: go_to_capacitance has no field `targt` (its fields: target)",
            "line 11: go_to_capacitance is a request, not a response",
            "line 12: protocol `sd` does not match this spec (`ub2`)",
            "line 13: address 300 is not a byte (0..=255)",
        ]
    );
}

/// The frames of issue 12, as public code for these servos sends them: each breaks only a rule
/// of the spec (an address, a range, a broadcast refusal). Strict decoding refuses each with
/// the reason and exit 1; `--lenient` prints each with its violations and exits 0.
const OUT_OF_SPEC: [(&str, &str, &str); 4] = [
    (
        "sd",
        "76 20 00 00 BA B0",
        "address 0x20 at offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address",
    ),
    (
        "sd",
        "10 01 4B 4B FB 8A",
        "electronic_serial_number_character.string_length at offset 3 is 75, outside its range 0..=32",
    ),
    (
        "sd",
        "A01F00008198",
        "read_temperatures (code 0xA0) does not accept the broadcast address 0x1F",
    ),
    (
        "ub2",
        "AA41 4001 2C",
        "address 0x41 at offset 1 is outside the device range 0x21..=0x40 and is not the broadcast or host address",
    ),
];

#[test]
fn out_of_spec_frames_fail_strictly_with_the_reason() {
    for (protocol, frame, reason) in OUT_OF_SPEC {
        let out = busspec(&["decode", protocol, frame]);
        assert_eq!(out.status.code(), Some(1), "{frame}");
        assert!(out.stdout.is_empty(), "{frame}: {}", text(&out.stdout));
        assert_eq!(
            text(&out.stderr),
            format!("frame 1 ({frame}): {reason}\n"),
            "{frame}"
        );
    }
}

#[test]
fn lenient_decode_prints_out_of_spec_frames_with_their_violations() {
    let out = busspec(&["decode", "sd", "--lenient", "76 20 00 00 BA B0"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "{\"protocol\":\"sd\",\"direction\":\"request\",\"address\":32,\"code\":\"0x76\",\"message\":\"set_point\",\"fields\":{\"freshness\":0,\"position\":0},\"violations\":[\"address 0x20 at offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address\"]}\n"
    );
    assert!(out.stderr.is_empty());
    for (protocol, frame, _) in OUT_OF_SPEC {
        for spec in [None, Some(format!("spec/{protocol}.yaml"))] {
            let mut args = vec!["decode", protocol, "--lenient", frame];
            if let Some(s) = &spec {
                args.extend(["--spec", s]);
            }
            let out = busspec(&args);
            assert_eq!(
                out.status.code(),
                Some(0),
                "{args:?}: {}",
                text(&out.stderr)
            );
            let line: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
            let violations = line["violations"].as_array().expect("violations");
            assert_eq!(violations.len(), 1, "{args:?}: {line}");
        }
    }
    // A frame that decodes prints as ever, without violations; one that does not checksum is
    // refused as ever, --lenient or not.
    let out = busspec(&["decode", "ub2", "--lenient", "AA21 4101 3E1F 0000 6A"]);
    assert_eq!(text(&out.stdout), format!("{ACTUAL_79_98}\n"));
    let out = busspec(&["decode", "ub2", "--lenient", "AA41 4001 2D"]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "frame 1 (AA41 4001 2D): checksum mismatch at offset 4: expected 0x2C, found 0x2D\n"
    );
}

#[test]
fn a_stream_reports_out_of_spec_frames_where_they_are() {
    let bytes: Vec<u8> = [
        &[0x00u8][..],
        &[0x76, 0x20, 0x00, 0x00, 0xBA, 0xB0],
        &[0x76, 0x05, 0x32, 0x00, 0x14, 0x74],
    ]
    .concat();
    for spec in [None, Some("spec/sd.yaml")] {
        let mut args = vec!["decode", "sd", "--stream", "-"];
        if let Some(s) = spec {
            args.extend(["--spec", s]);
        }
        let out = run_in(root(), &args, &bytes);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let stdout = text(&out.stdout);
        let lines: Vec<&str> = stdout.lines().collect();
        assert_eq!(lines.len(), 3, "{stdout}");
        assert_eq!(lines[0], r#"{"offset":0,"skipped":1,"bytes":"00"}"#);
        assert_eq!(
            lines[1],
            r#"{"offset":1,"out_of_spec":"address 0x20 at offset 1 is outside the device range 0x01..=0x1E and is not the broadcast or host address","protocol":"sd","direction":"request","address":32,"code":"0x76","message":"set_point","fields":{"freshness":0,"position":0},"bytes":"76200000BAB0"}"#
        );
        assert!(
            lines[2].starts_with(r#"{"offset":7,"protocol":"sd""#),
            "{}",
            lines[2]
        );
    }
}

#[test]
fn an_error_quotes_a_long_frame_in_proportion() {
    let frame = "AA".repeat(50_000);
    let out = busspec(&["decode", "ub2", &frame, "AA21 4101 3E1F 0000 6A"]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout), format!("{ACTUAL_79_98}\n"));
    let stderr = text(&out.stderr);
    assert_eq!(
        stderr,
        format!(
            "frame 1 ({}… (50000 bytes)): frame too long: 50000 bytes, the longest frame has 9\n",
            "AA".repeat(32)
        )
    );
    assert!(stderr.len() < 200, "{} bytes of stderr", stderr.len());
    // Text that is not hex, likewise by characters.
    let junk = "zz".repeat(1000);
    let out = busspec(&["decode", "ub2", &junk]);
    assert_eq!(
        text(&out.stderr),
        format!(
            "frame 1 ({}… (2000 characters)): `z` at character 1 is not a hex digit\n",
            "z".repeat(64)
        )
    );
    // A frame of 32 bytes or fewer is quoted as given.
    let frame = "AA ".repeat(32);
    let out = busspec(&["decode", "ub2", frame.trim_end()]);
    assert!(
        text(&out.stderr).starts_with(&format!("frame 1 ({}): ", frame.trim_end())),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn encode_refuses_what_the_spec_forbids_and_writes_nothing() {
    for (protocol, line, reason) in [
        (
            "sd",
            r#"{"message":"read_electronic_serial_number","address":1,"fields":{"byte_number":37}}"#,
            "byte_number = 37 is outside its range 0..=31",
        ),
        (
            "sd",
            r#"{"message":"read_temperatures","address":31}"#,
            "read_temperatures does not accept the broadcast address 0x1F",
        ),
        (
            "sd",
            r#"{"message":"set_point","address":32,"fields":{"freshness":0,"position":0}}"#,
            "address 0x20 is outside the device range 0x01..=0x1E and is not the broadcast or host address",
        ),
        (
            "ub2",
            r#"{"message":"get_actual_capacitance","address":65}"#,
            "address 0x41 is outside the device range 0x21..=0x40 and is not the broadcast or host address",
        ),
        (
            "ub2",
            r#"{"message":"go_to_stored_position","address":33,"fields":{"index":12}}"#,
            "index = 12 is outside its range 0..=9",
        ),
    ] {
        for spec in [None, Some(format!("spec/{protocol}.yaml"))] {
            let mut args = vec!["encode", protocol];
            if let Some(s) = &spec {
                args.extend(["--spec", s]);
            }
            let out = busspec_stdin(&args, line);
            assert_eq!(out.status.code(), Some(1), "{args:?} {line}");
            assert!(out.stdout.is_empty(), "{line}: {}", text(&out.stdout));
            assert_eq!(text(&out.stderr), format!("line 1: {reason}\n"), "{args:?}");
        }
    }
}

/// The example frames that decode without their request, and `busspec decode` of all of them
/// as arguments.
fn standalone(p: &Protocol) -> (Vec<&[u8]>, Output) {
    let frames: Vec<&[u8]> = p
        .examples
        .iter()
        .filter(|e| !p.message(e.message).needs_request)
        .map(|e| e.wire.as_slice())
        .collect();
    let mut args = vec!["decode".to_owned(), p.name.clone()];
    args.extend(frames.iter().map(|f| hex(f)));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = busspec(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    (frames, out)
}

/// A capture of example frames (those that decode without their request) with noise between
/// some of them, and the JSON lines expected from `--stream`: each frame's `decode` line with
/// its offset first.
fn capture(p: &Protocol, noise: &[&[u8]]) -> (Vec<u8>, Vec<String>) {
    let (frames, out) = standalone(p);
    let stdout = text(&out.stdout);
    let mut bytes = Vec::new();
    let mut expected = Vec::new();
    for (n, (frame, line)) in frames.iter().zip(stdout.lines()).enumerate() {
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
    let scratch = temp_dir("stream");
    let dir = scratch.path();
    for (file, noise) in [
        (
            "ub2.yaml",
            &[&[0x00u8, 0x13][..], &[0xAA], &[0xFF, 0x55, 0x21]][..],
        ),
        (
            "sd.yaml",
            &[&[0x00u8][..], &[0xFF, 0xEE], &[0x01, 0x02, 0x03]][..],
        ),
    ] {
        let p = spec(file);
        let (bytes, expected) = capture(&p, noise);
        assert!(expected.iter().filter(|l| l.contains("skipped")).count() >= 3);
        let path = dir.join(format!("{}.bin", p.name));
        std::fs::write(&path, &bytes).unwrap();
        let out = busspec(&["decode", &p.name, "--stream", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let stdout = text(&out.stdout);
        let lines: Vec<&str> = stdout.lines().collect();
        assert_eq!(lines.len(), expected.len());
        for (got, want) in lines.iter().zip(&expected) {
            assert_eq!(got, want);
        }
        // The same from stdin.
        let out = run_in(root(), &["decode", &p.name, "--stream", "-"], &bytes);
        assert_eq!(out.status.code(), Some(0));
        assert_eq!(text(&out.stdout), stdout);
    }
}

#[test]
fn reply_to_settles_responses_only_the_request_tells_apart() {
    let frame = "22 01 1E 3B 6C A5";
    let out = busspec(&["decode", "sd", frame]);
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    assert_eq!(
        text(&out.stderr),
        format!(
            "frame 1 ({frame}): ambiguous frame: could be total_runtime_hours or total_runtime_min_sec; \
             only the request it answers tells them apart: give --reply-to read_total_runtime_hours \
             or --reply-to read_total_runtime_min_sec\n"
        )
    );
    let decoded = |cmd: &str| {
        let out = busspec(&["decode", "sd", "--reply-to", cmd, frame]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    assert_eq!(
        decoded("read_total_runtime_min_sec"),
        "{\"protocol\":\"sd\",\"direction\":\"response\",\"address\":1,\"code\":\"0x22\",\"message\":\"total_runtime_min_sec\",\"fields\":{\"runtime_minutes\":30,\"runtime_seconds\":59}}\n"
    );
    assert!(decoded("read_total_runtime_hours")
        .contains(r#""message":"total_runtime_hours","fields":{"runtime_hours":7739}"#));
    // A request that gets neither reply says so; an unknown command is a usage error.
    let out = busspec(&["decode", "sd", "--reply-to", "read_temperatures", frame]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("read_temperatures (--reply-to) gets none of them"));
    let out = busspec(&["decode", "sd", "--reply-to", "read_nothing", frame]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("`read_nothing` is not a command of sd"));
    // Direction decided by --direction is compatible with --reply-to.
    let out = busspec(&[
        "decode",
        "sd",
        "--direction",
        "response",
        "--reply-to",
        "read_total_runtime_min_sec",
        frame,
    ]);
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn spec_file_is_loaded_at_run_time() {
    let scratch = temp_dir("spec");
    let dir = scratch.path();
    let good = std::fs::read_to_string(root().join("spec/ub2.yaml")).unwrap();
    // Scale capacitance by 0.1 instead of 0.01: the frame now reads ten times larger. (The
    // examples state values in pF, so their stated values go too.)
    let changed = good.replacen("    scale: \"0.01\"", "    scale: \"0.1\"", 1);
    assert_ne!(changed, good);
    let changed = strip_examples(&changed);
    let file = dir.join("ub2-tenth.yaml");
    std::fs::write(&file, changed).unwrap();
    let f = file.to_str().unwrap();
    let out = busspec(&["decode", "ub2", "--spec", f, "AA21 4101 3E1F 0000 6A"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains(r#""fields":{"capacitance":799.8}"#));
    let out = busspec_stdin(
        &["encode", "ub2", "--spec", f],
        r#"{"message":"actual_capacitance","address":33,"fields":{"capacitance":799.8}}"#,
    );
    assert_eq!(text(&out.stdout), "AA2141013E1F00006A\n");
    // The protocol named must be the one the spec defines.
    let out = busspec(&["decode", "sd", "--spec", f, "AA21 501B"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains(&format!("{f} defines protocol `ub2`, not `sd`")),
        "{}",
        text(&out.stderr)
    );
    // A spec that does not load is reported as `check` reports it.
    let broken = dir.join("broken.yaml");
    std::fs::write(&broken, "protocol: ub2\n").unwrap();
    let out = busspec(&[
        "decode",
        "ub2",
        "--spec",
        broken.to_str().unwrap(),
        "AA21 501B",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains(broken.to_str().unwrap()));
}

/// Drops `examples:` (and what follows it up to `errata:`) so a spec whose units changed still
/// validates.
fn strip_examples(spec: &str) -> String {
    let start = spec.find("\nexamples:\n").expect("examples") + 1;
    let end = spec[start..]
        .find("\nerrata:\n")
        .map(|i| start + i + 1)
        .unwrap_or(spec.len());
    format!("{}examples: []\n{}", &spec[..start], &spec[end..])
}

#[test]
fn built_in_specs_work_from_any_directory() {
    let scratch = temp_dir("cwd");
    let dir = scratch.path();
    let out = run_in(dir, &["decode", "ub2", "AA21 4101 3E1F 0000 6A"], b"");
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), format!("{ACTUAL_79_98}\n"));
}

#[test]
fn wrong_arguments_are_usage_errors() {
    for args in [
        &["decode", "ub3", "AA21 501B"][..],
        &["decode", "ub2"],
        &["decode", "ub2", "--direction", "sideways", "AA21 501B"],
        &["decode", "ub2", "--stream", "-", "AA21 501B"],
        &["encode"],
    ] {
        let out = busspec(args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(text(&out.stderr).starts_with("error: "), "{args:?}");
    }
    // The output format is documented.
    let out = busspec(&["encode", "--help"]);
    assert!(text(&out.stdout).contains("uppercase hex"));
}

/// A frame decoded as a response whose code no response has is an unknown *response* code, in
/// the generated code (built-in protocol) and the interpreter (`--spec`) alike; as a request,
/// or in either direction, it stays an unknown command code.
#[test]
fn an_unknown_code_is_named_for_the_direction_it_was_decoded_as() {
    let frame = "F5 01 00 00 04 1B"; // 0xF5: no SD command or response; CRC right
    for spec in [None, Some("spec/sd.yaml")] {
        let mut args = vec!["decode"];
        if let Some(s) = spec {
            args.extend(["--spec", s]);
        }
        args.push("sd");
        for (direction, want) in [
            (Some("response"), "unknown response code 0xF5"),
            (Some("request"), "unknown command code 0xF5"),
            (None, "unknown command code 0xF5"),
        ] {
            let mut a = args.clone();
            if let Some(d) = direction {
                a.extend(["--direction", d]);
            }
            a.push(frame);
            let out = busspec(&a);
            assert_eq!(out.status.code(), Some(1), "{a:?}");
            let err = text(&out.stderr);
            assert!(err.contains(want), "{a:?}: {err}");
        }
    }
}

/// A Modbus reply given with `--request` is checked against it; a Dynamixel status packet (no
/// code) goes through decode and back through encode; a frame a request and a reply share asks
/// for the direction.
#[test]
fn variable_length_specs_decode_against_their_request_and_round_trip() {
    let modbus = ["decode", "--spec", "spec/modbus.yaml", "modbus"];
    let reply = "11 03 06 02 2B 00 00 00 64 C8 BA";
    let out = busspec(
        &[
            &modbus[..],
            &["--request", "11 03 00 6B 00 03 76 87", reply],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains(r#""registers":[555,0,100]"#));
    let out = busspec(
        &[
            &modbus[..],
            &["--request", "11 03 00 6B 00 02 B7 47", reply],
        ]
        .concat(),
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "frame 1 (11 03 06 02 2B 00 00 00 64 C8 BA): invalid value for read_holding_registers_reply.byte_count at offset 2: must be 2 × quantity of the request (4), found 6\n"
    );
    let out = busspec(&[&modbus[..], &["11 05 00 AC FF 00 4E 8B"]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("give --direction request or --direction response"),
        "{}",
        text(&out.stderr)
    );

    // Built in (generated code): no --spec needed.
    let out = busspec(&["decode", "modbus", reply]);
    assert!(
        text(&out.stdout).contains(r#""registers":[555,0,100]"#),
        "{}",
        text(&out.stderr)
    );

    let status = "FF FF 01 03 00 20 DB";
    let out = busspec(&[
        "decode",
        "--spec",
        "spec/dynamixel.yaml",
        "dynamixel",
        "--request",
        "FF FF 01 04 02 2B 01 CC",
        status,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line = text(&out.stdout);
    assert!(
        line.contains(r#""message":"read_status","fields":{"error":[],"data":[32]}"#),
        "{line}"
    );
    let back = busspec_stdin(
        &["encode", "--spec", "spec/dynamixel.yaml", "dynamixel"],
        &line,
    );
    assert!(back.status.success(), "{}", text(&back.stderr));
    assert_eq!(text(&back.stdout), "FFFF01030020DB\n");
}

/// Modbus and Dynamixel are built in with generated code: every CLI path prints for them what
/// the interpreter prints given the spec file (`--spec`), status and stderr included — each
/// example as an argument (with its direction and the command it answers), each reply example
/// against a request example with `--request`, all of them as hex lines on stdin and as a raw
/// capture, and their lines encoded back to the same bytes.
#[test]
fn built_in_variable_length_protocols_print_what_the_interpreter_prints() {
    for file in ["modbus.yaml", "dynamixel.yaml"] {
        let p = spec(file);
        let path = format!("spec/{file}");
        let both = |args: &[&str], stdin: &[u8]| {
            let built_in = run_in(root(), args, stdin);
            let interpreted = run_in(root(), &[args, &["--spec", &path]].concat(), stdin);
            let seen = |o: &Output| (o.status.code(), text(&o.stdout), text(&o.stderr));
            assert_eq!(seen(&built_in), seen(&interpreted), "{args:?}");
            built_in
        };
        let mut lines = String::new();
        let mut wires = String::new();
        let mut capture = Vec::new();
        let mut replies = 0;
        for e in &p.examples {
            let frame = hex(&e.wire);
            let direction = match e.message.direction {
                Direction::Request => "request",
                Direction::Response => "response",
            };
            let mut args = vec!["decode", &p.name, "--direction", direction];
            if let Some(c) = e.reply_to {
                args.extend(["--reply-to", &p.commands[c].name]);
            }
            args.push(&frame);
            let out = both(&args, b"");
            assert_eq!(
                out.status.code(),
                Some(0),
                "{args:?}: {}",
                text(&out.stderr)
            );
            lines.push_str(&text(&out.stdout));
            wires.push_str(&frame);
            wires.push('\n');
            capture.extend_from_slice(&e.wire);
            let request = e.reply_to.and_then(|c| {
                p.examples
                    .iter()
                    .find(|r| r.message.direction == Direction::Request && r.message.index == c)
            });
            if let Some(request) = request {
                let out = both(
                    &["decode", &p.name, "--request", &hex(&request.wire), &frame],
                    b"",
                );
                assert_eq!(out.status.code(), Some(0), "{frame}: {}", text(&out.stderr));
                replies += 1;
            }
        }
        assert!(
            replies >= 3,
            "{file}: {replies} replies against their request"
        );
        let out = both(&["encode", &p.name], lines.as_bytes());
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        assert_eq!(text(&out.stdout), wires);
        // Without a direction some frames read both ways: the same lines and the same errors.
        let out = both(&["decode", &p.name, "-"], wires.as_bytes());
        assert!(!out.stdout.is_empty());
        let out = both(&["decode", &p.name, "--stream", "-"], &capture);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        assert!(text(&out.stdout).lines().count() >= p.examples.len() / 2);
    }
}

#[test]
fn hex_lines_from_stdin_decode_as_arguments_do() {
    for file in ["ub2.yaml", "sd.yaml"] {
        let p = spec(file);
        let (frames, want) = standalone(&p);
        // As loggers print them: spaced, 0x-prefixed, commented, CRLF, blank lines.
        let mut input = String::from("# a capture\n\n");
        for (i, f) in frames.iter().enumerate() {
            let line = match i % 4 {
                0 => hex(f),
                1 => f
                    .iter()
                    .map(|b| format!("{b:02X}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                2 => f
                    .iter()
                    .map(|b| format!("0x{b:02x}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                _ => format!("  {}\t# frame {i}\r", hex(f)),
            };
            input.push_str(&line);
            input.push('\n');
        }
        for engine in [vec![], vec!["--spec".to_owned(), format!("spec/{file}")]] {
            let mut args = vec!["decode", p.name.as_str(), "-"];
            args.extend(engine.iter().map(String::as_str));
            let out = busspec_stdin(&args, &input);
            assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
            assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
            assert_eq!(text(&out.stdout), text(&want.stdout), "{args:?}");
        }
    }
}

#[test]
fn a_bad_hex_line_is_named_by_its_number_and_the_rest_still_print() {
    let input = "AA21 4101 3E1F 0000 6A\n\
                 AA21 4101 3E1F 0000 6B\n\
                 # only a comment\n\
                 zz21\n\
                 \n\
                 AA21\n\
                 0xAA 0x21 0x41 0x01 0x3E 0x1F 0x00 0x00 0x6A # again\n";
    let out = busspec_stdin(&["decode", "ub2", "-"], input);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stdout),
        format!("{ACTUAL_79_98}\n{ACTUAL_79_98}\n"),
        "{}",
        text(&out.stderr)
    );
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 3, "{stderr}");
    assert!(
        lines[0].starts_with("line 2 (AA21 4101 3E1F 0000 6B): checksum"),
        "{stderr}"
    );
    assert_eq!(
        lines[1],
        "line 4 (zz21): `z` at character 1 is not a hex digit"
    );
    assert!(
        lines[2].starts_with("line 6 (AA21): truncated frame"),
        "{stderr}"
    );
    // Not UTF-8: named by its line, and the next line is read.
    let out = run_in(
        root(),
        &["decode", "ub2", "-"],
        b"\xFF\xFE\nAA2141013E1F00006A\n",
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout), format!("{ACTUAL_79_98}\n"));
    assert_eq!(
        text(&out.stderr),
        "line 1: not UTF-8 text: invalid byte at offset 0\n"
    );
    // `-` is the only frame argument.
    let out = busspec(&["decode", "ub2", "-", "AA2141013E1F00006A"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("`-`"), "{}", text(&out.stderr));
}

#[test]
fn a_capture_that_cannot_be_read_is_reported_with_what_was_read() {
    let scratch = temp_dir("unreadable");
    let dir = scratch.path();
    let out = busspec(&["decode", "ub2", "--stream", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    let stderr = text(&out.stderr);
    assert!(
        stderr.starts_with(&format!(
            "error: cannot read {} (after 0 bytes): ",
            dir.display()
        )),
        "{stderr}"
    );
    let out = busspec(&["decode", "ub2", "--stream", "/nonexistent/capture.bin"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).starts_with("error: cannot read /nonexistent/capture.bin: "),
        "{}",
        text(&out.stderr)
    );
}

/// A reader that closes its end after the first bytes, as `| head -c` does.
#[test]
fn output_closed_early_ends_the_run_quietly() {
    let p = spec("ub2.yaml");
    let mut capture = Vec::new();
    while capture.len() < 1 << 20 {
        for e in &p.examples {
            capture.extend_from_slice(&e.wire);
        }
    }
    let scratch = temp_dir("pipe");
    let dir = scratch.path();
    let path = dir.join("ub2.bin");
    std::fs::write(&path, &capture).unwrap();
    let mut hex_lines = String::new();
    for e in p.examples.iter().cycle().take(100_000) {
        hex_lines.push_str(&hex(&e.wire));
        hex_lines.push('\n');
    }
    let lines_path = dir.join("ub2.hex");
    std::fs::write(&lines_path, &hex_lines).unwrap();
    for (args, input) in [
        (
            vec!["decode", "ub2", "--stream", path.to_str().unwrap()],
            None,
        ),
        (vec!["decode", "ub2", "-"], Some(&lines_path)),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_busspec"))
            .args(&args)
            .current_dir(root())
            .stdin(match input {
                Some(f) => Stdio::from(std::fs::File::open(f).unwrap()),
                None => Stdio::null(),
            })
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run busspec");
        let mut stdout = child.stdout.take().expect("stdout");
        let mut first = [0u8; 100];
        std::io::Read::read_exact(&mut stdout, &mut first).expect("some output");
        drop(stdout);
        let out = child.wait_with_output().expect("wait");
        assert!(first.starts_with(b"{\""), "{args:?}");
        assert!(out.stderr.is_empty(), "{args:?}: {}", text(&out.stderr));
        assert!(out.status.code().is_some(), "{args:?}: killed by a signal");
    }
}

/// A spec of the new frame shapes through the CLI (`--spec`, the interpreter): frames without
/// an address print without one and encode back from lines without one; an end byte and a
/// command that gets no reply are said in the errors' words; a capture of such frames streams.
#[test]
fn frames_of_other_shapes_decode_and_encode_through_the_cli() {
    let ft12 = "model/tests/fixtures/valid/ft12_fixed.yaml";
    let out = busspec(&[
        "decode",
        "--spec",
        ft12,
        "ft12_fixed",
        "10 40 01 41 16",
        "10 40 01 41 17",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "{\"protocol\":\"ft12_fixed\",\"direction\":\"request\",\"address\":1,\"code\":\"0x40\",\"message\":\"reset_remote_link\",\"fields\":{}}\n"
    );
    assert!(
        text(&out.stderr).contains(
            "frame 2 (10 40 01 41 17): bad end byte at offset 4: expected 0x16, found 0x17"
        ),
        "{}",
        text(&out.stderr)
    );

    let ubx = "model/tests/fixtures/valid/ubx_like.yaml";
    let out = busspec(&[
        "decode",
        "--spec",
        ubx,
        "ubx_like",
        "B5 62 05 01 02 00 06 08 16 3F",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line = text(&out.stdout);
    assert!(!line.contains("\"address\""), "{line}");
    let back = busspec_stdin(&["encode", "--spec", ubx, "ubx_like"], &line);
    assert!(back.status.success(), "{}", text(&back.stderr));
    assert_eq!(text(&back.stdout).trim(), "B562050102000608163F");

    let pelco = "model/tests/fixtures/valid/pelco_p.yaml";
    let out = busspec(&[
        "decode",
        "--spec",
        pelco,
        "pelco_p",
        "--direction",
        "response",
        "A0 00 00 07 00 01 AF 09",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let scratch = temp_dir("shapes");
    let stream = scratch.path().join("pelco.bin");
    let frame = [0xA0, 0x00, 0x00, 0x07, 0x00, 0x01, 0xAF, 0x09];
    let mut capture = frame.to_vec();
    capture.extend([0x55, 0x00]);
    capture.extend(frame);
    std::fs::write(&stream, &capture).unwrap();
    let out = busspec(&[
        "decode",
        "--spec",
        pelco,
        "pelco_p",
        "--stream",
        stream.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let lines = text(&out.stdout);
    assert_eq!(
        lines.matches("\"message\":\"go_to_preset\"").count(),
        2,
        "{lines}"
    );
    assert!(
        lines.contains("{\"offset\":8,\"skipped\":2,\"bytes\":\"5500\"}"),
        "{lines}"
    );
}

/// Pelco D and Pelco P are built in: their frames decode and encode by name, with the generated
/// code, as the interpreter reads the specs; Pelco D's code-less standard command beside its
/// coded extended commands, a query's reply checked against its request, Pelco P's end byte
/// before its check byte, and its commands that get no reply.
#[test]
fn pelco_d_and_pelco_p_decode_and_encode_as_built_in_protocols() {
    let right = "{\"protocol\":\"pelco_d\",\"direction\":\"request\",\"address\":1,\"code\":\"0x\",\"message\":\"standard\",\"fields\":{\"sense\":0,\"reserved\":0,\"auto_manual_scan\":0,\"camera_on_off\":0,\"iris_close\":0,\"iris_open\":0,\"focus_near\":0,\"focus_far\":0,\"zoom_wide\":0,\"zoom_tele\":0,\"tilt_down\":0,\"tilt_up\":0,\"pan_left\":0,\"pan_right\":1,\"extended\":0,\"pan_speed\":32,\"tilt_speed\":0}}\n";
    let out = busspec(&["decode", "pelco_d", "FF 01 00 02 20 00 23"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), right);
    let interpreted = busspec(&[
        "decode",
        "--spec",
        "spec/pelco_d.yaml",
        "pelco_d",
        "FF 01 00 02 20 00 23",
    ]);
    assert_eq!(text(&interpreted.stdout), right);
    let back = busspec_stdin(&["encode", "pelco_d"], right);
    assert!(back.status.success(), "{}", text(&back.stderr));
    assert_eq!(text(&back.stdout), "FF010002200023\n");

    // An extended command, a preset number with a meaning of its own, and the sum checked.
    let out = busspec(&[
        "decode",
        "pelco_d",
        "FF 01 00 07 00 21 29",
        "FF 01 00 07 00 21 2A",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stdout),
        "{\"protocol\":\"pelco_d\",\"direction\":\"request\",\"address\":1,\"code\":\"0x0007\",\"message\":\"go_to_preset\",\"fields\":{\"data1\":0,\"preset\":\"flip\"}}\n"
    );
    assert!(
        text(&out.stderr).starts_with("frame 2 (FF 01 00 07 00 21 2A): "),
        "{}",
        text(&out.stderr)
    );

    // A query's extended response, as the reply to its request; the general response (four
    // bytes) as the reply to a standard command.
    let out = busspec(&[
        "decode",
        "pelco_d",
        "--request",
        "FF 01 00 51 00 00 52",
        "FF 01 00 59 46 50 F0",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "{\"protocol\":\"pelco_d\",\"direction\":\"response\",\"address\":1,\"code\":\"0x0059\",\"message\":\"pan_position_response\",\"fields\":{\"position\":180}}\n"
    );
    let out = busspec(&[
        "decode",
        "pelco_d",
        "--request",
        "FF 01 00 51 00 00 52",
        "FF 01 05 06",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    // The general response's checksum is its request's plus the alarm byte (erratum
    // pelco-d-e02, as C466M-E and a camera manual print it): 01 00 02 20 00 sum to 23, then 05.
    let out = busspec(&[
        "decode",
        "pelco_d",
        "--request",
        "FF 01 00 02 20 00 23",
        "FF 01 05 28",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains(
            "\"message\":\"general_response\",\"fields\":{\"alarms\":[\"alarm_1\",\"alarm_3\"]}"
        ),
        "{}",
        text(&out.stdout)
    );
    // The reading of its own bytes' sum (01 + 05) is refused, with the checksum it should be.
    let out = busspec(&[
        "decode",
        "pelco_d",
        "--request",
        "FF 01 00 02 20 00 23",
        "FF 01 05 06",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    assert_eq!(
        text(&out.stderr),
        "frame 1 (FF 01 05 06): checksum mismatch at offset 3: expected 0x28, found 0x06\n"
    );
    // The FLIR manual's reply to Zoom In, checked over the request's bytes.
    let out = busspec(&[
        "decode",
        "pelco_d",
        "--request",
        "FF 01 00 20 00 00 21",
        "FF 01 00 21",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // Without the request it cannot be checked, and is refused saying so.
    let out = busspec(&["decode", "pelco_d", "FF 01 00 21"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    assert!(
        text(&out.stderr).contains("takes in its request's bytes"),
        "{}",
        text(&out.stderr)
    );

    // Pelco P: address 0 is camera 1, the ETX before the XOR, which covers it.
    let out = busspec(&["decode", "pelco_p", "A0 00 00 07 00 01 AF 09"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line = text(&out.stdout);
    assert_eq!(
        line,
        "{\"protocol\":\"pelco_p\",\"direction\":\"request\",\"address\":0,\"code\":\"0x0007\",\"message\":\"go_to_preset\",\"fields\":{\"data1\":0,\"preset\":1}}\n"
    );
    let back = busspec_stdin(&["encode", "pelco_p"], &line);
    assert_eq!(text(&back.stdout), "A00000070001AF09\n");
    let out = busspec(&["decode", "pelco_p", "A0 00 00 07 00 01 AE 08"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("bad end byte at offset 6: expected 0xAF, found 0xAE"),
        "{}",
        text(&out.stderr)
    );
    // Its commands get no reply: nothing decodes as the reply to one.
    let out = busspec(&[
        "decode",
        "pelco_p",
        "--request",
        "A0 00 00 07 00 01 AF 09",
        "A0 00 00 59 46 50 AF 40",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    assert!(out.stdout.is_empty());
}

/// Escaped frames (`framing.escaping`) through the CLI with a spec read at run time: decode,
/// encode back to the same bytes, a stream with noise and a bad escape, and the refusal's
/// words on stderr.
#[test]
fn escaped_frames_decode_encode_and_stream() {
    let spec = "model/tests/fixtures/valid/slip_sensor.yaml";
    let wire = "81DBDCDBDD6028C0";
    let out = busspec(&["decode", "--spec", spec, "slip_sensor", wire]);
    assert!(out.status.success(), "{out:?}");
    let line = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        line,
        "{\"protocol\":\"slip_sensor\",\"direction\":\"response\",\"code\":\"0x81\",\"message\":\"temperature\",\"fields\":{\"temperature\":-161.65}}\n"
    );
    let out = busspec_stdin(&["encode", "--spec", spec, "slip_sensor"], &line);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(String::from_utf8(out.stdout).unwrap().trim(), wire);
    let out = busspec(&[
        "decode",
        "--spec",
        spec,
        "slip_sensor",
        "81 DB 41 DB DD 60 28 C0",
    ]);
    assert!(!out.status.success());
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        "frame 1 (81 DB 41 DB DD 60 28 C0): bad escape at offset 1: 0xDB followed by 0x41\n"
    );
    let scratch = temp_dir("slip");
    let capture = scratch.path().join("slip.bin");
    let bytes =
        busspec_model::interp::parse_hex("3344 81DBDCDBDD6028C0 81DB41C0 82B1CAC0").unwrap();
    std::fs::write(&capture, bytes).unwrap();
    let out = busspec(&[
        "decode",
        "--spec",
        spec,
        "slip_sensor",
        "--stream",
        capture.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4, "{text}");
    assert!(
        lines[1].starts_with("{\"offset\":2,") && lines[1].contains("\"temperature\""),
        "{text}"
    );
    assert_eq!(
        lines[2],
        "{\"offset\":10,\"skipped\":4,\"bytes\":\"81DB41C0\"}"
    );
    assert!(
        lines[3].starts_with("{\"offset\":14,") && lines[3].contains("\"ack\""),
        "{text}"
    );
}

/// Fields after a list and several lists through the CLI: every example decodes to a JSON line
/// whose lists are lists, `decode | encode` gives the frame back byte for byte, and a capture of
/// the examples between noise streams frame by frame.
#[test]
fn lists_followed_by_fields_round_trip_through_the_cli() {
    for (spec, name) in [
        ("model/tests/fixtures/valid/lists_after.yaml", "lists_after"),
        (
            "model/tests/fixtures/valid/lists_length.yaml",
            "lists_length",
        ),
        // Repeated records: lists of objects.
        ("model/tests/fixtures/valid/records.yaml", "records"),
    ] {
        let p =
            busspec_model::load_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(spec))
                .unwrap_or_else(|d| panic!("{d}"));
        let hex: Vec<String> = p
            .examples
            .iter()
            .map(|e| e.wire.iter().map(|b| format!("{b:02X}")).collect())
            .collect();
        let mut args = vec!["decode", "--spec", spec, name];
        args.extend(hex.iter().map(String::as_str));
        let out = busspec(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let lines = text(&out.stdout);
        assert_eq!(lines.lines().count(), hex.len(), "{lines}");
        let back = busspec_stdin(&["encode", "--spec", spec, name], &lines);
        assert!(back.status.success(), "{}", text(&back.stderr));
        assert_eq!(
            text(&back.stdout).lines().collect::<Vec<_>>(),
            hex,
            "{name}"
        );
        // A capture: noise, then every example.
        let mut cap = vec![0x00, 0xFF];
        for e in &p.examples {
            cap.extend(&e.wire);
        }
        let scratch = temp_dir("lists");
        let file = scratch.path().join(format!("{name}.bin"));
        std::fs::write(&file, &cap).unwrap();
        let out = busspec(&[
            "decode",
            "--spec",
            spec,
            name,
            "--stream",
            file.to_str().unwrap(),
        ]);
        let said = text(&out.stdout);
        let frames = said.lines().filter(|l| l.contains("\"message\"")).count();
        assert_eq!(frames, p.examples.len(), "{said}");
    }
    // The list of lists_after's write_block, then the flags after it, as the line prints them.
    let out = busspec(&[
        "decode",
        "--spec",
        "model/tests/fixtures/valid/lists_after.yaml",
        "lists_after",
        "7E 03 11 02 1234 5678 0005 1D",
    ]);
    assert!(text(&out.stdout).contains("\"fields\":{\"n\":2,\"values\":[4660,22136],\"flags\":5}"));
    // The records of records' sync_write, each an object, then the flags after them.
    let out = busspec(&[
        "decode",
        "--spec",
        "model/tests/fixtures/valid/records.yaml",
        "records",
        "7E 01 83 02 01 0002 00 05 FF03 01 07 7C",
    ]);
    assert!(
        text(&out.stdout).contains(
            "\"blocks\":[{\"id\":1,\"position\":51.2,\"mode\":\"velocity\"},{\"id\":5,\"position\":102.3,\"mode\":\"position\"}],\"flags\":7"
        ),
        "{}",
        text(&out.stdout)
    );
}

/// CRSF, built in: its RC channels (16 × 11 bits packed, channel 1 first) decode to the same
/// line from the generated code and from the spec read at run time, and encode back byte for
/// byte; telemetry and an extended frame decode with their addresses; crsf-parser's one-byte
/// heartbeat (erratum crsf-e04) and a channel wider than 11 bits are refused; a stream of its
/// examples between noise gives each frame once.
#[test]
fn crsf_decodes_and_encodes_as_a_built_in_protocol() {
    let rc = "C8 18 16 E0 03 1F F8 C0 C7 8A 89 83 0F 7C E0 03 1F F8 C0 07 3E F0 81 0F 7C A1";
    let right = "{\"protocol\":\"crsf\",\"direction\":\"request\",\"address\":200,\"code\":\"0x16\",\"message\":\"rc_channels_packed\",\"fields\":{\"channels\":[992,992,992,992,172,1811,992,992,992,992,992,992,992,992,992,992]}}\n";
    let out = busspec(&["decode", "crsf", rc]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), right);
    let interpreted = busspec(&["decode", "--spec", "spec/crsf.yaml", "crsf", rc]);
    assert_eq!(text(&interpreted.stdout), right);
    let back = busspec_stdin(&["encode", "crsf"], right);
    assert!(back.status.success(), "{}", text(&back.stderr));
    assert_eq!(text(&back.stdout), format!("{}\n", rc.replace(' ', "")));

    let out = busspec(&[
        "decode",
        "crsf",
        "EA 0A 08 00 A8 00 7B 00 04 E2 50 1C",
        "EE 04 28 00 EA 54",
        "C8 03 0B C8 1E",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stdout),
        "{\"protocol\":\"crsf\",\"direction\":\"response\",\"address\":234,\"code\":\"0x08\",\"message\":\"battery_sensor\",\"fields\":{\"voltage\":16.8,\"current\":12.3,\"capacity_used\":1250,\"remaining\":80}}\n\
         {\"protocol\":\"crsf\",\"direction\":\"request\",\"address\":238,\"code\":\"0x28\",\"message\":\"device_ping\",\"fields\":{\"destination\":\"broadcast\",\"origin\":\"remote_control\"}}\n"
    );
    assert!(
        text(&out.stderr).starts_with("frame 3 (C8 03 0B C8 1E): "),
        "{}",
        text(&out.stderr)
    );

    // A channel of 2048 does not fit its 11 bits: refused, nothing written.
    let wide = right.replace("[992,992,992,992,172", "[2048,992,992,992,172");
    let out = busspec_stdin(&["encode", "crsf"], &wide);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout), "");
    assert!(
        text(&out.stderr).contains("channels"),
        "{}",
        text(&out.stderr)
    );

    // The examples as one stream between noise bytes.
    let p = spec("crsf.yaml");
    let (bytes, expected) = capture(&p, &[&[0x00u8][..], &[0x16, 0x18], &[0xC8, 0x18, 0x16]]);
    assert!(expected.iter().filter(|l| l.contains("skipped")).count() >= 3);
    let out = run_in(root(), &["decode", "crsf", "--stream", "-"], &bytes);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines, expected);
    assert!(
        lines
            .iter()
            .filter(|l| l.contains("rc_channels_packed"))
            .count()
            >= 2
    );
}

/// Dynamixel 2.0, built in: the e-Manual's Sync Write decodes to its blocks (records whose
/// width `data_length` gives) from the generated code and from the spec read at run time, and
/// encodes back byte for byte; a data length past four bytes is refused; a status packet that
/// only its request tells apart is named alike by both engines, and settled by `--reply-to`
/// (the generated code's reply to a neutral READ once asked for zero bytes: refused); a stream
/// of its examples between noise gives each frame once.
#[test]
fn dynamixel2_decodes_and_encodes_as_a_built_in_protocol() {
    let sync = "FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87";
    let right = "{\"protocol\":\"dynamixel2\",\"direction\":\"request\",\"address\":254,\"code\":\"0x83\",\"message\":\"sync_write\",\"fields\":{\"address\":116,\"data_length\":4,\"blocks\":[{\"id\":1,\"data\":150},{\"id\":2,\"data\":170}]}}\n";
    let out = busspec(&["decode", "dynamixel2", sync]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), right);
    let interpreted = busspec(&[
        "decode",
        "--spec",
        "spec/dynamixel2.yaml",
        "dynamixel2",
        sync,
    ]);
    assert_eq!(text(&interpreted.stdout), right);
    let back = busspec_stdin(&["encode", "dynamixel2"], right);
    assert!(back.status.success(), "{}", text(&back.stderr));
    assert_eq!(text(&back.stdout), format!("{}\n", sync.replace(' ', "")));
    let wide = right.replace("\"data_length\":4", "\"data_length\":5");
    for args in [
        &["encode", "dynamixel2"][..],
        &["encode", "--spec", "spec/dynamixel2.yaml", "dynamixel2"],
    ] {
        let out = busspec_stdin(args, &wide);
        assert_eq!(out.status.code(), Some(1));
        assert!(
            text(&out.stderr).contains("data_length"),
            "{}",
            text(&out.stderr)
        );
    }

    // Present Position 166: a READ's or a BULK READ's reply, told apart by the request.
    let status = "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0";
    for spec in [&[][..], &["--spec", "spec/dynamixel2.yaml"]] {
        let mut args = vec!["decode"];
        args.extend_from_slice(spec);
        args.extend_from_slice(&["dynamixel2", status]);
        let out = busspec(&args);
        assert_eq!(out.status.code(), Some(1));
        assert!(
            text(&out.stderr).contains("could be read_status or bulk_read_status;"),
            "{}",
            text(&out.stderr)
        );
        args.extend_from_slice(&["--reply-to", "read"]);
        let out = busspec(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(
            text(&out.stdout).contains("\"message\":\"read_status\",\"fields\":{\"read_alert\":0,\"read_error_number\":0,\"data\":[166,0,0,0]}"),
            "{}",
            text(&out.stdout)
        );
    }

    // As a stream, `--reply-to` settles such a status packet where no request comes before
    // it, and the READ before one settles it by what it asked for; a status packet that
    // does not follow the READ before it stays ambiguous. Both engines give the same lines
    // (the generated stream once reported the first as ambiguous: its default request was
    // a READ of zero bytes).
    let two = "FF FF FD 00 01 06 00 55 00 A6 00 CC 0F";
    let read2 = "FF FF FD 00 01 07 00 02 84 00 02 00 1D 01";
    let bytes: Vec<u8> = [status, read2, two, read2, status]
        .iter()
        .flat_map(|f| f.split(' ').map(|b| u8::from_str_radix(b, 16).unwrap()))
        .collect();
    let mut lines = Vec::new();
    for spec in [&[][..], &["--spec", "spec/dynamixel2.yaml"]] {
        let mut args = vec!["decode"];
        args.extend_from_slice(spec);
        args.extend_from_slice(&["dynamixel2", "--reply-to", "read", "--stream", "-"]);
        let out = run_in(root(), &args, &bytes);
        assert!(out.status.success(), "{}", text(&out.stderr));
        lines.push(text(&out.stdout));
    }
    assert_eq!(lines[0], lines[1]);
    let messages: Vec<&str> = lines[0]
        .lines()
        .map(|l| {
            l.split("\"message\":\"")
                .nth(1)
                .and_then(|rest| rest.split('"').next())
                .unwrap_or_default()
        })
        .collect();
    assert_eq!(
        messages,
        ["read_status", "read", "read_status", "read", ""],
        "{}",
        lines[0]
    );
    assert!(
        lines[0].lines().last().unwrap().contains("\"ambiguous\""),
        "{}",
        lines[0]
    );

    // The examples as one stream between noise bytes.
    let p = spec("dynamixel2.yaml");
    let (bytes, expected) = capture(
        &p,
        &[&[0x00u8][..], &[0xFF, 0xFF], &[0xFF, 0xFF, 0xFD, 0x00]],
    );
    let out = run_in(root(), &["decode", "dynamixel2", "--stream", "-"], &bytes);
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines, expected, "{}", text(&out.stderr));
    assert!(lines.iter().any(|l| l.contains("sync_write")));
}

/// Wake-up bytes (DL/T 645's preamble, a spec read at run time): decode takes a frame with
/// four or none before it, encode writes four, and a stream counts them into the frame's line
/// (its offset at the first), the ones that open no frame skipped.
#[test]
fn frames_with_a_preamble_decode_encode_and_stream() {
    let spec = "model/tests/fixtures/valid/dlt645.yaml";
    let frame = "68 AA AA AA AA AA AA 68 13 00 DF 16";
    let line = r#"{"protocol":"dlt645","direction":"request","code":"0x13","message":"read_address","fields":{"address_low":11184810,"address_high":11184810}}"#;
    for wire in [format!("FE FE FE FE {frame}"), frame.to_owned()] {
        let out = busspec(&["decode", "dlt645", "--spec", spec, &wire]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        assert_eq!(text(&out.stdout).trim_end(), line);
    }
    let out = busspec_stdin(&["encode", "dlt645", "--spec", spec], line);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout).trim_end(),
        format!("FE FE FE FE {frame}").replace(' ', "")
    );
    let scratch = temp_dir("preamble");
    let dir = scratch.path();
    let cap = dir.join("cap.bin");
    let mut bytes = vec![0x00, 0xFE, 0xFE];
    bytes.extend(busspec_model::interp::parse_hex(frame).unwrap());
    bytes.extend([0xFE, 0xFE]);
    std::fs::write(&cap, &bytes).unwrap();
    let out = busspec(&[
        "decode",
        "dlt645",
        "--spec",
        spec,
        "--stream",
        cap.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let lines: Vec<String> = text(&out.stdout).lines().map(str::to_owned).collect();
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(
        lines[0].starts_with(r#"{"offset":0,"skipped":1,"bytes":"00"}"#),
        "{lines:?}"
    );
    assert!(
        lines[1].starts_with(r#"{"offset":1,"protocol":"dlt645","direction":"request""#),
        "{lines:?}"
    );
    assert!(
        lines[2].starts_with(r#"{"offset":15,"skipped":2,"bytes":"FEFE"}"#),
        "{lines:?}"
    );
}

/// A per-byte transform of the payload (DL/T 645's +33H, a spec read at run time): decode
/// prints go645's frames with their real values (data identifier 00 01 00 00 as 65536), encode
/// writes them back byte for byte, the sum over the bytes as they travel, and a reply decodes
/// as the reply to its request from a stream.
#[test]
fn frames_with_a_transformed_payload_decode_encode_and_stream() {
    let spec = "model/tests/fixtures/valid/dlt645.yaml";
    let request = "68 01 00 00 00 00 00 68 11 04 33 33 34 33 B3 16";
    let reply = "68 01 00 00 00 00 00 68 91 08 33 33 34 33 59 B3 55 44 DC 16";
    let line = r#"{"protocol":"dlt645","direction":"request","code":"0x11","message":"read_data","fields":{"address_low":1,"address_high":0,"data_id":65536}}"#;
    let out = busspec(&["decode", "dlt645", "--spec", spec, request]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout).trim_end(), line);
    let out = busspec_stdin(&["encode", "dlt645", "--spec", spec], line);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout).trim_end(),
        format!("FE FE FE FE {request}").replace(' ', "")
    );
    let scratch = temp_dir("transform");
    let dir = scratch.path();
    let cap = dir.join("cap.bin");
    let mut bytes = busspec_model::interp::parse_hex(request).unwrap();
    bytes.extend(busspec_model::interp::parse_hex(reply).unwrap());
    std::fs::write(&cap, &bytes).unwrap();
    let out = busspec(&[
        "decode",
        "dlt645",
        "--spec",
        spec,
        "--stream",
        cap.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let lines: Vec<String> = text(&out.stdout).lines().map(str::to_owned).collect();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[1].contains(r#""message":"data_reply","fields":{"address_low":1,"address_high":0,"data_id":65536,"value":11228026}"#),
        "{lines:?}"
    );
    // The reply's line encodes back to the frame (with the wake-up bytes an encoder sends).
    let reply_line = lines[1].replacen(r#"{"offset":16,"#, "{", 1);
    let out = busspec_stdin(&["encode", "dlt645", "--spec", spec], &reply_line);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout).trim_end(),
        format!("FE FE FE FE {reply}").replace(' ', "")
    );
}

/// A length field whose width the start byte chooses (VESC, a spec read at run time): decode
/// prints pyvesc's short frame, encode writes it back, a 256-byte payload goes out long and
/// decodes, a long form of a length the short field holds is refused with its reason and
/// place, and a stream frames both forms.
#[test]
fn frames_of_both_length_forms_decode_encode_and_stream() {
    let spec = "model/tests/fixtures/valid/vesc.yaml";
    let set_rpm = "02 05 08 FF FF EE 6C 18 7A 03";
    let line = r#"{"protocol":"vesc","direction":"request","code":"0x08","message":"set_rpm","fields":{"rpm":-4500}}"#;
    let out = busspec(&["decode", "vesc", "--spec", spec, set_rpm]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout).trim_end(), line);
    let out = busspec_stdin(&["encode", "vesc", "--spec", spec], line);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout).trim_end(), set_rpm.replace(' ', ""));
    // 4 + 251 data bytes and the code: 256, long.
    let data: Vec<String> = (0..251).map(|i| (i % 256).to_string()).collect();
    let write = format!(
        r#"{{"protocol":"vesc","direction":"request","code":"0x03","message":"write_new_app_data","fields":{{"offset":4096,"data":[{}]}}}}"#,
        data.join(",")
    );
    let out = busspec_stdin(&["encode", "vesc", "--spec", spec], &write);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let long = text(&out.stdout).trim_end().to_owned();
    assert!(long.starts_with("0301000300001000"), "{long}");
    assert_eq!(long.len(), 2 * 262);
    let out = busspec(&["decode", "vesc", "--spec", spec, &long]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout).trim_end(), write);
    let needless = "03 00 05 08 FF FF EE 6C 18 7A 03";
    let out = busspec(&["decode", "vesc", "--spec", spec, needless]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr).trim_end(),
        format!("frame 1 ({needless}): long length field at offset 1 says 5: lengths up to 255 take the short form")
    );
    let scratch = temp_dir("long_length");
    let dir = scratch.path();
    let cap = dir.join("cap.bin");
    let mut bytes = busspec_model::interp::parse_hex(set_rpm).unwrap();
    bytes.extend(busspec_model::interp::parse_hex(&long).unwrap());
    bytes.extend(busspec_model::interp::parse_hex("02 01 04 40 84 03").unwrap());
    std::fs::write(&cap, &bytes).unwrap();
    let out = busspec(&[
        "decode",
        "vesc",
        "--spec",
        spec,
        "--stream",
        cap.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let lines: Vec<String> = text(&out.stdout).lines().map(str::to_owned).collect();
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(
        lines[0].starts_with(r#"{"offset":0,"protocol":"vesc""#),
        "{lines:?}"
    );
    assert!(
        lines[1]
            .starts_with(r#"{"offset":10,"protocol":"vesc","direction":"request","code":"0x03""#),
        "{lines:?}"
    );
    assert!(lines[2].starts_with(r#"{"offset":272,"#), "{lines:?}");
    assert!(lines[2].contains(r#""message":"get_values""#), "{lines:?}");
}

/// A reply whose checksum takes in its request's bytes (`checksum_over_request`, Pelco D's
/// general response): decoded with `--request`, over its bytes; refused without it, naming
/// what it needs; refused after another request, with the checksum that request gives.
#[test]
fn a_reply_whose_checksum_takes_in_its_request_decodes_with_it() {
    let spec = [
        "decode",
        "--spec",
        "model/tests/fixtures/valid/pelco_d_replies.yaml",
        "pelco_d_replies",
    ];
    let out = busspec(
        &[
            &spec[..],
            &["--request", "FF 01 00 20 00 00 21", "FF 01 00 21"],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains(r#""message":"general_response""#),
        "{}",
        text(&out.stdout)
    );
    let out = busspec(&[&spec[..], &["FF 01 00 21"]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "frame 1 (FF 01 00 21): general_response's checksum at offset 3 takes in its request's bytes: decode it as the reply to its request\n"
    );
    let out = busspec(
        &[
            &spec[..],
            &["--request", "FF 01 00 09 00 01 0B", "FF 01 00 21"],
        ]
        .concat(),
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "frame 1 (FF 01 00 21): checksum mismatch at offset 3: expected 0x0B, found 0x21\n"
    );
}

/// `busspec encode --request HEX`: a reply whose checksum takes in its request's bytes is
/// written over them; without the request it is refused, naming what it needs.
#[test]
fn a_reply_whose_checksum_takes_in_its_request_encodes_with_it() {
    let spec = [
        "encode",
        "--spec",
        "model/tests/fixtures/valid/pelco_d_replies.yaml",
        "pelco_d_replies",
    ];
    let line = r#"{"direction":"response","message":"general_response","address":1,"fields":{"alarms":[]}}"#;
    let out = busspec_stdin(
        &[&spec[..], &["--request", "FF 01 00 09 00 01 0B"]].concat(),
        line,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), "FF01000B\n");
    let out = busspec_stdin(&spec, line);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr),
        "line 1: general_response's checksum takes in its request's bytes: encode it as the reply to its request\n"
    );
    let out = busspec_stdin(&[&spec[..], &["--request", "FF 01"]].concat(), line);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
}
