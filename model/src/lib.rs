//! busspec-model: load a protocol spec, validate it into an IR, interpret frames from it, render
//! its documentation and classify the changes between two revisions. Code generation from the
//! same IR is `busspec-codegen`'s.
//!
//! ```text
//! spec/*.yaml ──load──▶ model ──validate──▶ IR ──┬─ docs      (Markdown reference)
//!                                                ├─ interp    (decode/encode at run time)
//!                                                │    └─ stream   (frames out of a bus capture)
//!                                                ├─ diff      (what a revision breaks)
//!                                                └─ (busspec-codegen: Rust modules)
//! ```
//!
//! `stream`, `docs`, `diff` and the interpreter's encoding (`interp::encode`, `decode_reply`)
//! are behind the default feature `tools`; a build script that only generates code
//! (`busspec-codegen`) turns it off and compiles load, validate, the IR and the interpreter's
//! decoding, which validation replays every example through.
//!
//! Every stage is a pure function of its input; file I/O happens only in [`load_file`] and in
//! the callers (build scripts, the CLI).

pub mod checksum;
pub mod diag;
#[cfg(feature = "tools")]
pub mod diff;
#[cfg(feature = "tools")]
pub mod docs;
pub mod interp;
pub mod ir;
pub mod load;
pub mod model;
pub mod rational;
#[cfg(feature = "tools")]
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
        Some(mut p) => {
            p.spec_sha256 = spec_sha256(text);
            Ok(p)
        }
        None => Err(fail(sink)),
    }
}

/// SHA-256 of a spec's text as lowercase hex: the same digest `sha256sum FILE` prints, so a
/// generated artifact can be traced to the exact file it came from.
pub fn spec_sha256(text: &str) -> String {
    hmac_sha256::Hash::hash(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
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

#[cfg(test)]
mod tests {
    #[test]
    fn spec_hash_is_plain_sha256_of_the_text() {
        // The FIPS 180-2 test vector for "abc".
        assert_eq!(
            super::spec_sha256("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
