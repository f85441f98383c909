//! `busspec demo`, the README's first command: runs without hardware and shows each feature.

use std::process::Command;

#[test]
fn the_demo_runs_and_shows_each_feature() {
    let out = Command::new(env!("CARGO_BIN_EXE_busspec"))
        .arg("demo")
        .output()
        .expect("busspec runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "← {\"protocol\":\"ub2\",\"direction\":\"response\",\"address\":33,\"code\":\"0x4101\",\"message\":\"actual_capacitance\",\"fields\":{\"capacitance\":79.98}}",
        "\"message\":\"firmware_version\",\"fields\":{\"firmware_version\":\"20100433.00\"}",
        "\"message\":\"actual_capacitance\",\"fields\":{\"capacitance\":150}",
        "\"message\":\"nak_limit_reached\"",
        "(not sent) cannot encode get_stored_full_step_position: index = 12 is outside its range 0..=9",
        "\"message\":\"nak_index_out_of_range\"",
        "\"message\":\"nak_incompatible_status\"",
        "\"message\":\"actual_capacitance\",\"fields\":{\"capacitance\":300}",
        "\"movement_completed_with_step_loss\",\"fields\":{\"lost_micro_steps\":40}",
        "read 200 entries from 0x22",
        "\"SD-02 servo actuator (busspec si\"",
        "← (broadcast: no reply expected)",
        "\"skipped_frames_counter\",\"fields\":{\"host_freshness_counter\":1,\"dropped_frames\":0}",
        "no reply within 200 ms (3 attempts)",
    ] {
        assert!(text.contains(needle), "missing {needle}:\n{text}");
    }
    let sd = text
        .lines()
        .find(|l| l.trim_start().starts_with("sd: "))
        .expect("sd soak line");
    assert!(sd.contains(" 0 wrong values accepted"), "{sd}");
}
