//! `busspec`: check protocol specs and render their reference documentation.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use busspec_codegen::{docs, load_file, Protocol};
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "busspec",
    version,
    about = "Vendor serial protocols as declarative specs: check them, document them."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate spec files and print a summary per protocol; on failure print every error.
    Check {
        /// Spec files (default: every *.yaml in spec/).
        files: Vec<PathBuf>,
    },
    /// Render the Markdown reference of each spec into a directory.
    Docs {
        /// Spec files (default: every *.yaml in spec/).
        files: Vec<PathBuf>,
        /// Where the references go.
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Write nothing; fail if any reference is missing or differs from what the spec gives.
        #[arg(long)]
        check: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check { files } => check(files),
        Command::Docs { files, out, check } => render_docs(files, &out, check),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            if !msg.is_empty() {
                eprintln!("{msg}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The spec files to work on: those given, or every `*.yaml` in `spec/`, sorted.
fn spec_files(files: Vec<PathBuf>) -> Result<Vec<PathBuf>, String> {
    if !files.is_empty() {
        return Ok(files);
    }
    let dir = Path::new("spec");
    let entries = std::fs::read_dir(dir).map_err(|e| {
        format!(
            "error: no spec files given and cannot read {}: {e}",
            dir.display()
        )
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    found.sort();
    if found.is_empty() {
        return Err(format!(
            "error: no spec files given and no *.yaml in {}",
            dir.display()
        ));
    }
    Ok(found)
}

/// Loads every file, printing all diagnostics of every file that fails.
fn load_all(files: Vec<PathBuf>) -> Result<Vec<(PathBuf, Protocol)>, String> {
    let mut loaded = Vec::new();
    let mut errors = Vec::new();
    for f in spec_files(files)? {
        match load_file(&f) {
            Ok(p) => loaded.push((f, p)),
            Err(d) => {
                let n = d.items.len();
                errors.push(format!(
                    "{d}\n{}: {n} error{}",
                    d.file,
                    if n == 1 { "" } else { "s" }
                ));
            }
        }
    }
    if errors.is_empty() {
        Ok(loaded)
    } else {
        Err(errors.join("\n"))
    }
}

fn check(files: Vec<PathBuf>) -> Result<(), String> {
    for (f, p) in load_all(files)? {
        let printed = p.examples.iter().filter(|e| e.printed.is_some()).count();
        let corrected = p.examples.iter().filter(|e| e.corrected.is_some()).count();
        println!(
            "{}: {} ({} rev {}): {} commands, {} responses, {} examples ({} printed, {} derived, {} corrected), {} errata: ok",
            f.display(),
            p.name,
            p.document.title,
            p.document.revision,
            p.commands.len(),
            p.responses.len(),
            p.examples.len(),
            printed,
            p.examples.len() - printed,
            corrected,
            p.errata.len()
        );
    }
    Ok(())
}

fn render_docs(files: Vec<PathBuf>, out: &Path, check: bool) -> Result<(), String> {
    let loaded = load_all(files)?;
    if !check {
        std::fs::create_dir_all(out)
            .map_err(|e| format!("error: cannot create {}: {e}", out.display()))?;
    }
    let mut stale = Vec::new();
    for (f, p) in loaded {
        let source = f.to_string_lossy().replace('\\', "/");
        let text = docs::render(&p, &source);
        let target = out.join(format!("{}.md", p.name));
        let current = std::fs::read_to_string(&target).ok();
        if current.as_deref() == Some(text.as_str()) {
            continue;
        }
        if check {
            stale.push(target.display().to_string());
        } else {
            std::fs::write(&target, text)
                .map_err(|e| format!("error: cannot write {}: {e}", target.display()))?;
            println!("wrote {}", target.display());
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "stale documentation (run `busspec docs` and commit): {}",
            stale.join(", ")
        ))
    }
}
