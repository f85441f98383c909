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
pub mod forms;
pub mod interp;
pub mod ir;
pub mod load;
pub mod long;
pub mod model;
#[cfg(feature = "tools")]
pub mod mutate;
pub mod number;
pub mod rational;
#[cfg(feature = "tools")]
pub mod sim;
#[cfg(feature = "tools")]
pub mod stream;
pub mod transactions;
pub mod truncate;
pub mod validate;

use std::path::Path;

pub use diag::{Diagnostic, Diagnostics};
pub use ir::Protocol;

pub use load::MAX_SPEC_BYTES;

/// Loads and validates spec text. `file` names it in diagnostics. Text cannot `include` files
/// (there is no directory to find them in): [`load_file`] can.
pub fn load_str(file: &str, text: &str) -> Result<Protocol, Diagnostics> {
    load(file, text, None).map(|l| l.protocol)
}

/// A spec loaded from its file, with what its `include` read.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub protocol: Protocol,
    /// The files `include` read (none without includes): their text, where they were read
    /// from, and the spec as one text without them (what a generated crate embeds).
    pub included: load::Included,
}

/// Reads and validates a spec file. At most [`MAX_SPEC_BYTES`] (and one more) are read, the
/// spec and the files its `include` names together.
pub fn load_file(path: &Path) -> Result<Protocol, Diagnostics> {
    load_file_with_includes(path).map(|l| l.protocol)
}

/// [`load_file`], keeping what `include` read.
pub fn load_file_with_includes(path: &Path) -> Result<Loaded, Diagnostics> {
    let file = path.display().to_string();
    let text = load::read_text(path, MAX_SPEC_BYTES).map_err(|(at, message)| Diagnostics {
        file: file.clone(),
        items: vec![Diagnostic::new(at, message)],
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
    load(&file, &text, Some(dir))
}

fn load(file: &str, text: &str, dir: Option<&Path>) -> Result<Loaded, Diagnostics> {
    let mut sink = diag::Sink::default();
    let mut included = load::Included::default();
    // Diagnostics about what an included file holds name that file.
    let fail = |sink: diag::Sink, included: &load::Included| Diagnostics {
        file: file.to_owned(),
        items: sink
            .items
            .into_iter()
            .map(|d| Diagnostic::new(included.locate(&d.path), d.message))
            .collect(),
    };
    // The text's size, depth, aliases and characters are checked first (`load::prescan`).
    let Some(spec) = load::parse_with(text, dir, &mut included, &mut sink) else {
        return Err(fail(sink, &included));
    };
    match validate::validate(&spec, &mut sink) {
        Some(mut p) => {
            let texts = std::iter::once(text).chain(included.files.iter().map(|f| f.2.as_str()));
            p.spec_sha256 = sha256_hex(texts);
            Ok(Loaded {
                protocol: p,
                included,
            })
        }
        None => Err(fail(sink, &included)),
    }
}

/// SHA-256 of a spec's text as lowercase hex: the same digest `sha256sum FILE` prints, so a
/// generated artifact can be traced to the exact file it came from. (A spec that includes
/// files is traced by [`Protocol::spec_sha256`], the digest of its text followed by each
/// included file's in the order read: `cat spec.yaml common.yaml | sha256sum`.)
pub fn spec_sha256(text: &str) -> String {
    sha256_hex(std::iter::once(text))
}

fn sha256_hex<'t>(texts: impl Iterator<Item = &'t str>) -> String {
    let mut h = hmac_sha256::Hash::new();
    for t in texts {
        h.update(t.as_bytes());
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
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
