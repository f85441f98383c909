//! `sim` and `soak` for every protocol: Modbus and Dynamixel soaked against devices of their
//! specs' `device:` sections (no wrong value accepted); `sim --spec FILE` serving a spec file's
//! devices on a pseudo-terminal, to the generated master (`talk`) and to raw frames of a spec
//! with no `device:` section; wrong arguments refused with the reason.

#![cfg(unix)]

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

use busspec_model::interp;
use busspec_model::ir::{Direction, MessageRef};
use busspec_model::load_file;

const BIN: &str = env!("CARGO_BIN_EXE_busspec");

#[path = "common/cli.rs"]
mod cli;
use cli::Sim;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(root())
        .output()
        .expect("busspec runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A figure from a soak report line: the number after `label`.
fn figure(report: &str, label: &str) -> u64 {
    let line = report
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no `{label}` in {report}"));
    let after = &line[line.find(label).unwrap() + label.len()..];
    after
        .split(|c: char| !c.is_ascii_digit())
        .find(|s| !s.is_empty())
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn modbus_dynamixel_and_pelco_d_soak_against_their_device_sections() {
    for protocol in ["modbus", "dynamixel", "pelco_d"] {
        let out = run(&["soak", "--transactions", "3000", "--seed", "7", protocol]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let report = text(&out.stdout);
        assert!(
            report.starts_with(&format!("{protocol}: 3000 transactions")),
            "{report}"
        );
        // Faults were injected, most transactions completed, and none accepted a wrong value.
        assert!(figure(&report, "faults injected: ") > 0, "{report}");
        let completed =
            figure(&report, "completed first time") + figure(&report, "completed after retries");
        assert!(completed > 2500, "{report}");
        assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
        assert!(
            report.contains("checksum-only master: accepted"),
            "{report}"
        );
    }
    // Pelco P's commands get no reply (its position queries aside): a command lost or garbled
    // on the line is not seen by the master, so the device may differ from what was sent; the
    // soak counts those as lost unseen, not as a wrong value accepted.
    let out = run(&["soak", "--transactions", "3000", "--seed", "7", "pelco_p"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    let completed =
        figure(&report, "completed first time") + figure(&report, "completed after retries");
    assert!(completed > 2500, "{report}");
    assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
    // On a line without faults every transaction completes, also where commands get no reply
    // or an optional one, and where a reply is longer than 256 bytes. (Commands that get none
    // were judged before their device had seen them, and frames sent back to back reached the
    // simulated devices as one: Pelco P lost 2 and CRSF 98 of 400 this way; the master kept
    // 256 received bytes, and Dynamixel 2.0 failed 4 reads of 246 bytes and more.)
    for protocol in ["pelco_p", "crsf", "dynamixel2"] {
        let out = run(&[
            "soak",
            "--transactions",
            "400",
            "--seed",
            "7",
            "--rate",
            "0",
            protocol,
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let report = text(&out.stdout);
        assert_eq!(figure(&report, "completed first time"), 400, "{report}");
    }
    // CRSF's RC frames get an optional GPS answer: one the line loses is silence the spec
    // allows, lost unseen (it was counted as a wrong value accepted).
    let out = run(&["soak", "--transactions", "400", "--seed", "7", "crsf"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    assert!(
        figure(&report, "lost unseen (no or optional reply)") > 0,
        "{report}"
    );
    assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
    // Without a protocol: all six, UB2 and SD with their own models.
    let out = run(&["soak", "--transactions", "200"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    for p in ["ub2", "sd", "modbus", "dynamixel", "pelco_d", "pelco_p"] {
        assert!(
            report.contains(&format!("{p}: 200 transactions")),
            "{report}"
        );
    }
    let out = run(&["soak", "--transactions", "10", "nosuch"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("no soak for `nosuch`: there are ub2, sd"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn a_spec_files_devices_answer_the_generated_master() {
    // The interpreter's simulator of spec/modbus.yaml, talked to by the generated master.
    let sim = Sim::start(&["modbus", "--spec", "spec/modbus.yaml", "--address", "7"]);
    let talk = |args: &[&str]| {
        let mut all = vec![
            "talk",
            "--port",
            &sim.path,
            "--timeout",
            "2000",
            "modbus",
            "--address",
            "7",
        ];
        all.extend_from_slice(args);
        run(&all)
    };
    let out = talk(&[
        "write_multiple_registers",
        "starting_address=20",
        "quantity=3",
        "values=[11,12,13]",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = talk(&[
        "read_holding_registers",
        "starting_address=19",
        "quantity=5",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        line["fields"]["registers"],
        serde_json::json!([0, 11, 12, 13, 0])
    );
    // The spec's start values of the input registers.
    let out = talk(&["read_input_registers", "starting_address=0", "quantity=2"]);
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["fields"]["registers"], serde_json::json!([1000, 2000]));
    // Past the end of the table: exception 2, shown as the refusal it is.
    let out = talk(&["read_coils", "starting_address=9999", "quantity=2"]);
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["fields"]["exception_code"], "illegal_data_address");
}

#[test]
fn a_spec_without_a_device_section_answers_each_command_with_its_reply() {
    let file = root().join("model/tests/fixtures/valid/minimal.yaml");
    let p = load_file(&file).unwrap();
    let sim = Sim::start(&[
        "mini",
        "--spec",
        file.to_str().unwrap(),
        "--address",
        "0x21",
    ]);
    let mut port = serialport::new(&sim.path, 9600)
        .timeout(Duration::from_millis(200))
        .open()
        .expect("the pseudo-terminal opens");
    let index = p
        .commands
        .iter()
        .position(|c| c.name == "set_mode")
        .unwrap();
    let r = MessageRef {
        direction: Direction::Request,
        index,
    };
    let value = interp::Value {
        name: "mode".into(),
        raw: interp::Raw::Int(2),
    };
    let frame = interp::encode(&p, r, 0x21, &[value]).unwrap();
    port.write_all(&frame).unwrap();
    let mut reply = Vec::new();
    let mut buf = [0u8; 64];
    let deadline = std::time::Instant::now() + Duration::from_secs(5);
    while std::time::Instant::now() < deadline {
        match port.read(&mut buf) {
            Ok(n) if n > 0 => reply.extend_from_slice(&buf[..n]),
            _ if !reply.is_empty() => break,
            _ => {}
        }
    }
    let request = interp::decode(&p, Some(Direction::Request), None, &frame).unwrap();
    let got = interp::decode_reply(&p, &request, &reply)
        .unwrap_or_else(|e| panic!("{}: {e}", interp::format_hex(&reply)));
    assert_eq!(p.message(got.message).name, "set_mode_ack");
    assert_eq!(got.address, 0x21);
}

#[test]
fn wrong_sim_arguments_are_refused_with_the_reason() {
    for (args, says) in [
        (
            &["sim", "modbus", "--pty", "--address", "0"][..],
            "address 0x00 is not a modbus device address (0x01..=0xF7)",
        ),
        (
            &["sim", "modbus", "--pty", "--address", "3", "--address", "3"][..],
            "address 0x03 given twice",
        ),
        (&["sim", "nosuch", "--pty"][..], "nosuch"),
        (
            &["sim", "modbus", "--pty", "--msb-first"][..],
            "--msb-first is for the ub2 simulator",
        ),
        (
            &["sim", "x", "--spec", "/nonexistent.yaml", "--pty"][..],
            "/nonexistent.yaml",
        ),
    ] {
        let out = run(args);
        assert_ne!(out.status.code(), Some(0), "{args:?}");
        let err = text(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}: nothing served");
    }
}

#[test]
fn a_spec_read_at_run_time_soaks_as_its_generated_code_does() {
    // The master over the interpreter (`--spec`) and over the generated code, against the same
    // devices, same seed: the same report, line for line.
    for (protocol, file) in [
        ("modbus", "spec/modbus.yaml"),
        ("dynamixel", "spec/dynamixel.yaml"),
    ] {
        let built_in = run(&["soak", "--transactions", "2000", "--seed", "3", protocol]);
        let by_spec = run(&[
            "soak",
            "--transactions",
            "2000",
            "--seed",
            "3",
            "--spec",
            file,
            protocol,
        ]);
        assert!(by_spec.status.success(), "{}", text(&by_spec.stderr));
        assert_eq!(text(&by_spec.stdout), text(&built_in.stdout), "{protocol}");
        assert_eq!(
            figure(&text(&by_spec.stdout), "wrong, accepted silently"),
            0
        );
    }
    // A spec no build has seen, with no device section: every command answered, nothing wrong.
    let out = run(&[
        "soak",
        "--transactions",
        "2000",
        "--spec",
        "model/tests/fixtures/valid/minimal.yaml",
        "mini",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    assert!(report.starts_with("mini: 2000 transactions"), "{report}");
    assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
    // Floats with a range below 0 (raw bits that do not order as the numbers) and lists of a
    // fixed count of every number type: soaked, not a panic drawing a request.
    let out = run(&[
        "soak",
        "--transactions",
        "500",
        "--seed",
        "3",
        "--spec",
        "model/tests/fixtures/valid/packed_channels.yaml",
        "packed_channels",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
    // A protocol without addresses: one device on the bus (two would both answer every
    // request, and every transaction would fail in the collision).
    let out = run(&[
        "soak",
        "--transactions",
        "2000",
        "--spec",
        "model/tests/fixtures/valid/telemetry_le.yaml",
        "telemetry_le",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report = text(&out.stdout);
    let completed =
        figure(&report, "completed first time") + figure(&report, "completed after retries");
    assert!(completed > 1800, "{report}");
    assert_eq!(figure(&report, "wrong, accepted silently"), 0, "{report}");
}

#[test]
fn talk_speaks_a_spec_read_at_run_time() {
    let file = "model/tests/fixtures/valid/minimal.yaml";
    let sim = Sim::start(&["mini", "--spec", file, "--address", "0x21"]);
    let talk = |args: &[&str]| {
        let mut all = vec!["talk", "--port", &sim.path, "--spec", file, "mini"];
        all.extend_from_slice(args);
        run(&all)
    };
    let out = talk(&["--address", "0x21", "set_mode", "mode=auto"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["message"], "set_mode_ack");
    assert_eq!(line["address"], 0x21);
    // A value outside its range is refused before anything is sent, in encode's words.
    let out = talk(&["--address", "0x21", "get_status", "channel=9"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("channel"),
        "{}",
        text(&out.stderr)
    );
    // Nobody at another address: the master's error, naming the protocol the spec defines.
    let out = talk(&[
        "--address",
        "0x22",
        "--timeout",
        "100",
        "get_status",
        "channel=1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.contains("mini get_status to address 0x22: no reply"),
        "{err}"
    );
    // The spec's protocol is named, and must be the one given.
    let out = run(&[
        "talk",
        "--port",
        &sim.path,
        "--spec",
        file,
        "other",
        "--address",
        "1",
        "x",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("defines protocol `mini`"),
        "{}",
        text(&out.stderr)
    );
}

/// RoboClaw's packet serial (`model/tests/fixtures/valid/roboclaw.yaml`), simulated and
/// talked to by its spec alone: a read travels without a CRC and its reply, which carries no
/// address, has one over the read's bytes; a write is acknowledged with FF. Before replies
/// without an address were known to the simulator and the master, the simulator stayed
/// silent, then the master refused every reply as "from address 0x00".
#[test]
fn talk_and_sim_speak_a_spec_whose_replies_carry_no_address() {
    let file = "model/tests/fixtures/valid/roboclaw.yaml";
    let sim = Sim::start(&["roboclaw", "--spec", file, "--address", "0x80"]);
    let talk = |args: &[&str]| {
        let mut all = vec![
            "talk",
            "--port",
            &sim.path,
            "--spec",
            file,
            "roboclaw",
            "--address",
            "0x80",
        ];
        all.extend_from_slice(args);
        run(&all)
    };
    for (args, reply) in [
        (&["read_main_battery"][..], "main_battery"),
        (&["read_encoder_m1"][..], "encoder_m1"),
        (&["drive_forward_m1", "speed=64"][..], "ack"),
        (&["speed_m1", "speed=-1000"][..], "ack"),
    ] {
        let out = talk(args);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(line["message"], reply, "{args:?}");
    }
    // Nobody at another address: no reply, though replies carry none.
    let out = run(&[
        "talk",
        "--port",
        &sim.path,
        "--spec",
        file,
        "roboclaw",
        "--address",
        "0x81",
        "--timeout",
        "100",
        "read_status",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("no reply"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn talk_by_spec_reads_back_what_it_wrote_to_a_modbus_device() {
    let sim = Sim::start(&["modbus", "--address", "9"]);
    let talk = |args: &[&str]| {
        let mut all = vec![
            "talk",
            "--port",
            &sim.path,
            "--timeout",
            "2000",
            "--spec",
            "spec/modbus.yaml",
            "modbus",
            "--address",
            "9",
        ];
        all.extend_from_slice(args);
        run(&all)
    };
    let out = talk(&[
        "write_single_register",
        "register_address=4",
        "register_value=513",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = talk(&["read_holding_registers", "starting_address=3", "quantity=3"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["fields"]["registers"], serde_json::json!([0, 513, 0]));
    // A broadcast: sent, carried out, not waited for.
    let out = run(&[
        "talk",
        "--port",
        &sim.path,
        "--spec",
        "spec/modbus.yaml",
        "modbus",
        "--address",
        "0",
        "write_single_register",
        "register_address=5",
        "register_value=7",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    std::thread::sleep(Duration::from_millis(200));
    let out = talk(&["read_holding_registers", "starting_address=5", "quantity=1"]);
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["fields"]["registers"], serde_json::json!([7]));
}

/// `sim pelco_d` and `sim pelco_p` serve the built-in Pelco protocols: Pelco D answers every
/// command (the general response, a query's extended response); a Pelco P command gets no
/// reply, which talk says without calling the receiver's address a broadcast.
#[test]
fn talk_and_sim_speak_pelco_d_and_pelco_p() {
    let sim = Sim::start(&["pelco_d"]);
    let talk = |args: &[&str]| {
        let mut all = vec!["talk", "--port", &sim.path, "--timeout", "2000", "pelco_d"];
        all.extend_from_slice(args);
        run(&all)
    };
    let out = talk(&["--address", "1", "set_zoom_speed", "speed=2"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["message"], "general_response", "{line}");
    assert_eq!(line["fields"]["alarms"], serde_json::json!([]), "{line}");
    let out = talk(&["--address", "1", "query_pan_position"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["message"], "pan_position_response", "{line}");
    drop(sim);

    let sim = Sim::start(&["pelco_p"]);
    let out = run(&[
        "talk",
        "--port",
        &sim.path,
        "--timeout",
        "2000",
        "pelco_p",
        "--address",
        "0",
        "go_to_preset",
        "preset=5",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    assert_eq!(
        text(&out.stderr),
        "sent go_to_preset to 0x00; it gets no reply\n"
    );
}
