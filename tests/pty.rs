//! End to end through a real pseudo-terminal pair: `busspec sim --pty` on one end,
//! `busspec talk` processes on the other.

#![cfg(unix)]

use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_busspec");

#[path = "common/cli.rs"]
mod cli;
use cli::Sim;

/// `busspec talk --port SIM ARGS`.
fn talk(sim: &Sim, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(["talk", "--port", &sim.path])
        .args(args)
        .output()
        .expect("busspec runs")
}

fn lines(o: &Output) -> Vec<serde_json::Value> {
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

#[test]
fn talk_to_simulated_capacitors_through_a_pty() {
    let sim = Sim::start(&["ub2", "--address", "0x21", "--address", "0x22"]);
    let out = talk(&sim, &["ub2", "--address", "0x21", "get_firmware_version"]);
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "{\"protocol\":\"ub2\",\"direction\":\"response\",\"address\":33,\"code\":\"0x4161\",\"message\":\"firmware_version\",\"fields\":{\"firmware_version\":\"20100433.00\"}}\n"
    );
    // Writes land in the device and read back, on the second capacitor only.
    let r = lines(&talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x22",
            "store_indexed_position",
            "index=2",
            "position=532",
        ],
    ));
    assert_eq!(r[0]["message"], "store_indexed_position_ack");
    let r = lines(&talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x22",
            "get_stored_full_step_position",
            "index=2",
        ],
    ));
    assert_eq!(r[0]["fields"]["full_steps"], 532);
    let r = lines(&talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "get_stored_full_step_position",
            "index=2",
        ],
    ));
    assert_eq!(r[0]["fields"]["full_steps"], 0);
    // A short movement, waited for: the trigger's reply, then the completion.
    let r = lines(&talk(
        &sim,
        &["ub2", "--address", "0x21", "move_full_steps", "steps=60"],
    ));
    assert_eq!(r.len(), 2);
    assert_eq!(r[0]["message"], "movement_started");
    assert_eq!(r[1]["message"], "movement_completed");
    let r = lines(&talk(
        &sim,
        &["ub2", "--address", "0x21", "get_actual_full_step_position"],
    ));
    assert_eq!(r[0]["fields"]["full_steps"], 638 + 60);
    // A refusal is a reply, printed like any other.
    let r = lines(&talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "get_c_curve_indexed_full_step_capacitance",
            "index=499",
        ],
    ));
    assert_eq!(r[0]["message"], "nak_index_out_of_range");
    // Nobody at 0x30: a clear error and exit status 1.
    let out = talk(
        &sim,
        &["ub2", "--address", "0x30", "--timeout", "50", "get_status"],
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: ub2 get_status to address 0x30: no reply within 50 ms (1 attempt)\n"
    );
}

#[test]
fn the_c_curve_reads_through_a_pty_and_draws() {
    let sim = Sim::start(&["ub2"]);
    let dir = std::env::temp_dir().join(format!("busspec-pty-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let svg = dir.join("c-curve.svg");
    let out = talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "c-curve",
            "--svg",
            svg.to_str().expect("utf-8 path"),
        ],
    );
    let r = lines(&out);
    assert_eq!(r.len(), 200);
    assert_eq!(r[3]["message"], "c_curve_entry");
    assert_eq!(r[3]["fields"]["index"], 3);
    assert_eq!(r[3]["fields"]["full_steps"], 150);
    let picture = std::fs::read_to_string(&svg).expect("svg written");
    assert!(picture.contains("capacitance [pF]") && picture.contains("position [full-steps]"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn talk_to_simulated_actuators_through_a_pty() {
    let sim = Sim::start(&["sd", "--address", "1"]);
    let r = lines(&talk(
        &sim,
        &["sd", "--address", "1", "read_product_description"],
    ));
    assert_eq!(r[0]["text"], "SD-02 servo actuator (busspec si");
    let r = lines(&talk(
        &sim,
        &["sd", "--address", "1", "set_velocity", "set_velocity=360"],
    ));
    assert_eq!(r[0]["message"], "set_velocity_reply");
    let r = lines(&talk(
        &sim,
        &["sd", "--address", "1", "set_point", "position=22.5"],
    ));
    assert_eq!(r[0]["message"], "set_point_reply");
    assert_eq!(r[1]["message"], "actual_position");
    assert_eq!(r[1]["fields"]["position"], 22.5);
    // The next process starts its freshness counter from the actuator's (read with 0x37), so
    // no frame counts as dropped.
    let _ = lines(&talk(
        &sim,
        &["sd", "--address", "1", "set_point", "position=-22.5"],
    ));
    let r = lines(&talk(
        &sim,
        &["sd", "--address", "1", "read_skipped_frames_counter"],
    ));
    assert_eq!(r[0]["fields"]["dropped_frames"], 0);
    let r = lines(&talk(
        &sim,
        &["sd", "--address", "1", "read_actuator_status_word"],
    ));
    assert_eq!(r[0]["fields"]["status_bits"], serde_json::json!([]));
    // A broadcast set point is not answered: nothing on stdout, a note on stderr.
    let out = talk(
        &sim,
        &["sd", "--address", "0x1F", "set_point", "position=0"],
    );
    assert!(out.status.success());
    assert!(out.stdout.is_empty());
}

/// UB2 byte-order safety (ub2-e01): a capacitor built to the document's examples (numbers MSB
/// first) is not moved; one built to its text moves as before, and `talk` says it checked.
#[test]
fn an_msb_first_capacitor_is_refused_and_a_correct_one_moves() {
    let sim = Sim::start(&["ub2", "--msb-first"]);
    let out = talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "go_to_capacitance",
            "target=150",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(out.stdout.is_empty());
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: ub2 go_to_capacitance to address 0x21: not sent: "),
        "{stderr}"
    );
    for part in [
        "implausible little-endian",
        "spec/ub2.yaml:8: byte_order: little",
        "read big-endian (most significant byte first) they are factory limits 50.00..=500.00 pF, plausible",
        "erratum ub2-e01",
    ] {
        assert!(stderr.contains(part), "{part:?} not in {stderr}");
    }
    // It did not move: still at its preset position, 638 full steps, which it sends MSB first.
    let r = lines(&talk(
        &sim,
        &["ub2", "--address", "0x21", "get_actual_full_step_position"],
    ));
    assert_eq!(r[0]["fields"]["full_steps"], 638u16.swap_bytes());
    // --no-wait refuses the same way.
    let out = talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "--no-wait",
            "move_full_steps",
            "steps=60",
        ],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("ub2-e01"));
    drop(sim);

    let sim = Sim::start(&["ub2"]);
    let out = talk(
        &sim,
        &[
            "ub2",
            "--address",
            "0x21",
            "go_to_capacitance",
            "target=150",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let r = lines(&out);
    assert_eq!(r.len(), 2);
    assert_eq!(r[0]["message"], "movement_started");
    assert_eq!(r[1]["message"], "movement_completed");
    assert_eq!(
        stderr.lines().next(),
        Some(
            "byte order checked: factory limits 50.00..=500.00 pF plausible little-endian \
             (spec/ub2.yaml:8: byte_order: little)"
        ),
        "{stderr}"
    );
    let r = lines(&talk(
        &sim,
        &["ub2", "--address", "0x21", "get_actual_capacitance"],
    ));
    let c = r[0]["fields"]["capacitance"].as_f64().expect("a number");
    assert!((c - 150.0).abs() < 0.05, "{c}");
    // Reads are not checked, and the simulator's switch is UB2's only.
    assert!(String::from_utf8_lossy(
        &talk(&sim, &["ub2", "--address", "0x21", "get_status"]).stderr
    )
    .is_empty());
    let out = Command::new(BIN)
        .args(["sim", "sd", "--msb-first", "--pty"])
        .output()
        .expect("busspec runs");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--msb-first is for the ub2 simulator"));
}
