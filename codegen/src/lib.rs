//! busspec-codegen: load a protocol spec, validate it into an IR, interpret frames from it, and
//! emit documentation from it.
//!
//! ```text
//! spec/*.yaml ──load──▶ model ──validate──▶ IR ──┬─ docs      (Markdown reference)
//!                                                └─ interp    (decode/encode at run time)
//!                                                     └─ stream   (frames out of a bus capture)
//! ```
//!
//! Every stage is a pure function of its input; file I/O happens only in [`load_file`] and in
//! the callers (build scripts, the CLI).

pub mod checksum;
pub mod diag;
pub mod docs;
pub mod emit;
pub mod interp;
pub mod ir;
pub mod load;
pub mod model;
pub mod rational;
pub mod stream;
pub mod validate;

use std::path::Path;

pub use diag::{Diagnostic, Diagnostics};
pub use ir::Protocol;

/// Specs larger than this are refused before parsing: a real one is a few hundred KiB.
pub const MAX_SPEC_BYTES: usize = 16 << 20;

/// Loads and validates spec text. `file` names it in diagnostics.
pub fn load_str(file: &str, text: &str) -> Result<Protocol, Diagnostics> {
    let mut sink = diag::Sink::default();
    let fail = |sink: diag::Sink| Diagnostics {
        file: file.to_owned(),
        items: sink.items,
    };
    if text.len() > MAX_SPEC_BYTES {
        sink.error(
            "",
            format!(
                "file is {} bytes; specs are limited to {MAX_SPEC_BYTES}",
                text.len()
            ),
        );
        return Err(fail(sink));
    }
    let Some(spec) = load::parse(text, &mut sink) else {
        return Err(fail(sink));
    };
    match validate::validate(&spec, &mut sink) {
        Some(p) => Ok(p),
        None => Err(fail(sink)),
    }
}

/// Reads and validates a spec file.
pub fn load_file(path: &Path) -> Result<Protocol, Diagnostics> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| Diagnostics {
        file: file.clone(),
        items: vec![Diagnostic::new("", format!("cannot read: {e}"))],
    })?;
    let text = String::from_utf8(bytes).map_err(|e| Diagnostics {
        file: file.clone(),
        items: vec![Diagnostic::new(
            "",
            format!(
                "not UTF-8 text: invalid byte at offset {}",
                e.utf8_error().valid_up_to()
            ),
        )],
    })?;
    load_str(&file, &text)
}
