//! Build cost of the generator (see BENCHMARKS.md): what a build script using
//! `busspec_codegen::Builder` spends per spec, without its file I/O:
//!
//! - `generator/<p>/load_validate`: `busspec_model::load_str` (parse, validate, every example
//!   replayed through the interpreter);
//! - `generator/<p>/emit`: `busspec_codegen::emit::emit_module` of the validated spec (tokens,
//!   parse, format);
//! - `generator/both`: load, validate and emit of both built-in specs, the target
//!   (under 50 ms).
//!
//! `cargo bench -p busspec-benches --bench generator` runs it; `-- --test` runs each once.

use std::hint::black_box;
use std::time::Duration;

use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;
use criterion::{criterion_group, criterion_main, Criterion};

/// The built-in specs: name, the file the build script reads, its text.
fn specs() -> [(&'static str, String, &'static str); 2] {
    [
        (
            Ub2::NAME,
            format!("spec/{}.yaml", Ub2::NAME),
            Ub2::SOURCE.spec_yaml,
        ),
        (
            Sd::NAME,
            format!("spec/{}.yaml", Sd::NAME),
            Sd::SOURCE.spec_yaml,
        ),
    ]
}

/// Load, validate and emit one spec; the module's length, so nothing is optimised away.
fn generate(file: &str, text: &str) -> usize {
    let p = busspec_model::load_str(file, text).unwrap_or_else(|d| panic!("{d}"));
    busspec_codegen::emit::emit_module(&p, file, file)
        .unwrap_or_else(|e| panic!("{e}"))
        .len()
}

fn generator(c: &mut Criterion) {
    let mut g = c.benchmark_group("generator");
    g.sample_size(20).measurement_time(Duration::from_secs(10));
    for (name, file, text) in specs() {
        g.bench_function(format!("{name}/load_validate"), |b| {
            b.iter(|| busspec_model::load_str(black_box(&file), black_box(text)).is_ok())
        });
        let p = busspec_model::load_str(&file, text).unwrap_or_else(|d| panic!("{d}"));
        g.bench_function(format!("{name}/emit"), |b| {
            b.iter(|| busspec_codegen::emit::emit_module(black_box(&p), &file, &file).is_ok())
        });
    }
    let all = specs();
    assert!(all
        .iter()
        .all(|(_, file, text)| generate(file, text) > 1000));
    g.bench_function("both", |b| {
        b.iter(|| {
            all.iter()
                .map(|(_, file, text)| generate(black_box(file), black_box(text)))
                .sum::<usize>()
        })
    });
    g.finish();
}

criterion_group!(benches, generator);
criterion_main!(benches);
