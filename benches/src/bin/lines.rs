//! Lines of generated code for each spec file named (`benches/lines.py` runs it over each
//! built-in spec with one message taken out at a time): one line per file, `FILE LINES`, or
//! `FILE error: …` where the spec does not load or the generator refuses it.
//!
//! ```text
//! lines SPEC...
//! ```

use std::process::ExitCode;

fn main() -> ExitCode {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        eprintln!("usage: lines SPEC...");
        return ExitCode::from(2);
    }
    for f in &files {
        let lines = busspec_model::load_file(std::path::Path::new(f))
            .map_err(|d| d.to_string())
            .and_then(|p| busspec_codegen::emit::emit_module(&p, f, f))
            .map(|code| code.lines().count());
        match lines {
            Ok(n) => println!("{f} {n}"),
            Err(e) => println!("{f} error: {}", e.lines().next().unwrap_or("")),
        }
    }
    ExitCode::SUCCESS
}
