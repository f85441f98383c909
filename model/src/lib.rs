//! busspec-model: load a protocol spec, validate it into an IR, interpret frames from it, render
//! its documentation and classify the changes between two revisions. Code generation from the
//! same IR is `busspec-codegen`'s.
//!
//! ```text
//! spec/*.yaml ──load──▶ model ──validate──▶ IR ──┬─ docs      (Markdown reference)
//!                                                ├─ dissector (Wireshark Lua)
//!                                                ├─ interp    (decode/encode at run time)
//!                                                │    └─ stream   (frames out of a bus capture)
//!                                                ├─ diff      (what a revision breaks)
//!                                                └─ (busspec-codegen: Rust modules)
//! ```
//!
//! `stream`, `docs`, `dissector`, `diff` and the interpreter's encoding (`interp::encode`, `decode_reply`)
//! are behind the default feature `tools`; a build script that only generates code
//! (`busspec-codegen`) turns it off and compiles load, validate, the IR and the interpreter's
//! decoding, which validation replays every example through.
//!
//! Every stage is a pure function of its input; file I/O happens only in [`load_file`] and in
//! the callers (build scripts, the CLI).

pub mod checksum;
pub mod device;
pub mod diag;
#[cfg(feature = "tools")]
pub mod diff;
#[cfg(feature = "tools")]
pub mod dissector;
#[cfg(feature = "tools")]
pub mod docs;
pub mod escape;
pub mod interp;
pub mod ir;
pub mod load;
pub mod model;
pub mod number;
pub mod rational;
#[cfg(feature = "tools")]
pub mod sim;
#[cfg(feature = "tools")]
pub mod stream;
pub mod transactions;
pub mod validate;

use std::path::Path;

pub use diag::{Diagnostic, Diagnostics};
pub use ir::Protocol;

pub use load::MAX_SPEC_BYTES;

/// Loads and validates spec text. `file` names it in diagnostics.
pub fn load_str(file: &str, text: &str) -> Result<Protocol, Diagnostics> {
    let mut sink = diag::Sink::default();
    let fail = |sink: diag::Sink| Diagnostics {
        file: file.to_owned(),
        items: sink.items,
    };
    // The text's size, depth, aliases and characters are checked first (`load::prescan`).
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

/// Reads and validates a spec file. At most [`MAX_SPEC_BYTES`] (and one more) are read.
pub fn load_file(path: &Path) -> Result<Protocol, Diagnostics> {
    use std::io::Read;
    let file = path.display().to_string();
    let refuse = |path: String, message: String| Diagnostics {
        file: file.clone(),
        items: vec![Diagnostic::new(path, message)],
    };
    let cannot = |e: std::io::Error| refuse(String::new(), format!("cannot read: {e}"));
    let f = std::fs::File::open(path).map_err(cannot)?;
    let declared = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::new();
    f.take(MAX_SPEC_BYTES as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() > MAX_SPEC_BYTES {
        let len = declared.max(bytes.len() as u64) as usize;
        let r = load::too_large(&bytes, len);
        return Err(refuse(r.path(), r.message));
    }
    let text = match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => {
            let bytes = e.as_bytes();
            let at = e.utf8_error().valid_up_to();
            let r = load::Refusal::at(
                bytes,
                at,
                format!(
                    "not UTF-8 text: invalid byte 0x{:02X} at offset {at}",
                    bytes.get(at).copied().unwrap_or(0)
                ),
            );
            return Err(refuse(r.path(), r.message));
        }
    };
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
