//! Runs the generator over the built-in specs a given number of times, for counting
//! instructions under callgrind (`benches/icount-gen.sh`): the difference between two pass
//! counts, divided by the difference in passes, is what one pass costs, with the process's
//! start-up subtracted out. The same work as the `generator` bench, without its timing noise.
//!
//! ```text
//! icount_gen <load|emit|both> <passes> [SPEC...]
//! ```
//!
//! `load`: `busspec_model::load_str` of both specs (parse, validate, every example replayed);
//! `emit`: `busspec_codegen::emit::emit_module` of both, loaded once beforehand; `both`: load,
//! validate and emit of both, as a build script does without its file I/O. Spec files named
//! after the pass count take the built-in specs' place (a large spec's generator cost).

use std::hint::black_box;
use std::process::ExitCode;

use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;

fn load(file: &str, text: &str) -> busspec_model::Protocol {
    busspec_model::load_str(file, text).unwrap_or_else(|d| panic!("{d}"))
}

fn emit(p: &busspec_model::Protocol, file: &str) -> usize {
    busspec_codegen::emit::emit_module(p, file, file)
        .unwrap_or_else(|e| panic!("{e}"))
        .len()
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(what), Some(Ok(passes))) = (args.first(), args.get(1).map(|n| n.parse::<u32>()))
    else {
        eprintln!("usage: icount_gen <load|emit|both> <passes> [SPEC...]");
        return ExitCode::FAILURE;
    };
    let mut specs = vec![
        (
            format!("spec/{}.yaml", Ub2::NAME),
            Ub2::SOURCE.spec_yaml.to_string(),
        ),
        (
            format!("spec/{}.yaml", Sd::NAME),
            Sd::SOURCE.spec_yaml.to_string(),
        ),
    ];
    if args.len() > 2 {
        specs.clear();
        for file in &args[2..] {
            match std::fs::read_to_string(file) {
                Ok(text) => specs.push((file.clone(), text)),
                Err(e) => {
                    eprintln!("icount_gen: {file}: {e}");
                    return ExitCode::FAILURE;
                }
            }
        }
    }
    let loaded: Vec<_> = specs.iter().map(|(f, t)| load(f, t)).collect();
    let mut out = 0usize;
    for _ in 0..passes {
        for ((file, text), p) in specs.iter().zip(&loaded) {
            out += match what.as_str() {
                "load" => load(black_box(file), black_box(text)).commands.len(),
                "emit" => emit(black_box(p), file),
                "both" => emit(&load(black_box(file), black_box(text)), file),
                _ => {
                    eprintln!("usage: icount_gen <load|emit|both> <passes> [SPEC...]");
                    return ExitCode::FAILURE;
                }
            };
        }
    }
    black_box(out);
    println!("units per pass: 1");
    ExitCode::SUCCESS
}
