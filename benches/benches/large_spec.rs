//! Load and validation of a large spec (see BENCHMARKS.md, "Hostile and large specs"):
//!
//! - `large_spec/10000_commands/load`: `busspec_model::load_str` of a spec of 10,000 commands,
//!   each with a field and an example (parse, every validator pass, every example replayed),
//!   generated here from a template, about 2.4 MB of YAML. Target: under 2 s in release;
//!   every pass over messages is close to linear.
//! - `large_spec/10000_commands/prescan`: the loader's pre-scan of the same text alone.
//! - `large_spec/1000_commands/emit` and `2000_commands/emit`: the generator
//!   (`busspec_codegen::emit::emit_module`) over the first 1,000 and 2,000 of those commands;
//!   the second takes about twice the first, as every pass of the generator over messages is
//!   linear (it grouped messages by code with a scan per code before).
//!
//! `cargo bench -p busspec-benches --bench large_spec` runs it; `-- --test` runs each once.

use std::fmt::Write;
use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};

/// A valid spec of `n` commands (codes 0x0000 upward), one response common to all, and one
/// printed example per command.
fn spec(n: usize) -> String {
    let mut s = String::from(
        r#"protocol: many
title: "Many commands"
document: {title: "Generated", revision: "1", date: "2024-01-01"}
byte_order: big
printed_byte_order: big
serial: {section: "1", baud: 9600, data_bits: 8, parity: none, stop_bits: 1}
framing:
  section: "2"
  layout: [start, address, code, payload, checksum]
  start: 0xAA
  address: {host: 0x20, devices: {min: 0x21, max: 0x40}}
  request:  {code_lengths: [2], payload: {min: 0, max: 4}}
  response: {code_lengths: [1], payload: {min: 0, max: 4}}
  checksum: {algorithm: sum8, width: 8, check: 0xDD}
units:
  - {name: count, symbol: "", scale: "1"}
common_responses: [ack]
responses:
  - {name: ack, title: "Ack", section: "5", kind: ack, code: "0x50"}
commands:
"#,
    );
    for i in 0..n {
        let _ = writeln!(
            s,
            r#"  - {{name: c{i}, title: "Command {i}", section: "4", kind: getter, code: "0x{i:04X}", fields: [{{name: channel, type: u8, unit: count, range: {{min: 0, max: 3}}}}]}}"#
        );
    }
    s.push_str("examples:\n");
    for i in 0..n {
        // start + address + code + channel 1, modulo 256.
        let sum = (0xAA + 0x21 + (i >> 8) + (i & 0xFF) + 1) & 0xFF;
        let _ = writeln!(
            s,
            r#"  - {{section: "4", message: c{i}, printed: "AA21 {i:04X} 01 {sum:02X}", values: {{channel: 1}}}}"#
        );
    }
    s
}

fn large_spec(c: &mut Criterion) {
    let text = spec(10_000);
    let p = busspec_model::load_str("many.yaml", &text).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!((p.commands.len(), p.examples.len()), (10_000, 10_000));
    let mut g = c.benchmark_group("large_spec");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("10000_commands/load", |b| {
        b.iter(|| busspec_model::load_str("many.yaml", black_box(&text)).is_ok())
    });
    g.bench_function("10000_commands/prescan", |b| {
        b.iter(|| busspec_model::load::prescan(black_box(&text)).is_ok())
    });
    for n in [1_000, 2_000] {
        let p = busspec_model::load_str("many.yaml", &spec(n)).unwrap_or_else(|d| panic!("{d}"));
        g.bench_function(format!("{n}_commands/emit"), |b| {
            b.iter(|| busspec_codegen::emit::emit_module(black_box(&p), "many.yaml", "many.yaml"))
        });
    }
    g.finish();
}

criterion_group!(benches, large_spec);
criterion_main!(benches);
