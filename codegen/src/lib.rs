//! busspec-codegen: turns busspec protocol specs into typed `no_std` Rust modules, from a build
//! script.
//!
//! ```text
//! spec.yaml ──busspec-model: load, validate──▶ IR ──emit──▶ OUT_DIR/<name>.rs + OUT_DIR/protocols.rs
//! ```
//!
//! [`Builder`] is the build-script API, in the manner of prost-build: name your spec files, call
//! [`Builder::compile`], and `include!` the result. Each spec becomes one module named after
//! the protocol, whose unit type (`ub2::Ub2`) implements `busspec_runtime::Protocol`;
//! `protocols.rs` includes every module and adds `PROTOCOLS` (their names) and
//! `with_protocol` (a name to a type, through a `ProtocolVisitor`).
//!
//! ```no_run
//! // build.rs, in `fn main`
//! busspec_codegen::Builder::new()
//!     .spec("spec/my_device.yaml")
//!     .compile();
//! ```
//!
//! ```ignore
//! // src/lib.rs (the crate depends on busspec-runtime)
//! include!(concat!(env!("OUT_DIR"), "/protocols.rs"));
//! ```
//!
//! Files are rewritten only when their text changes, so an unchanged spec rebuilds nothing.
//! Every spec error becomes one cargo diagnostic line, `file: path: message`.

pub mod emit;
mod transactions;

use std::fmt;
use std::path::{Path, PathBuf};

use proc_macro2::TokenStream;
use quote::{format_ident, quote};

pub use busspec_model::{Diagnostic, Diagnostics};

/// The name of the file that includes every generated module.
pub const INDEX_FILE: &str = "protocols.rs";

/// Generates Rust modules from spec files: the build-script API.
#[derive(Debug, Clone, Default)]
pub struct Builder {
    specs: Vec<PathBuf>,
    out_dir: Option<PathBuf>,
}

/// Why generation failed: every spec's diagnostics, or a file that could not be read or
/// written.
#[derive(Debug)]
pub enum Error {
    /// A spec did not load or validate; each diagnostic says where.
    Spec(Diagnostics),
    /// Two specs declare the same protocol name, so their modules would collide.
    DuplicateProtocol {
        name: String,
        first: PathBuf,
        second: PathBuf,
    },
    /// No spec was named.
    NoSpecs,
    /// Neither [`Builder::out_dir`] nor the `OUT_DIR` environment variable says where to write.
    NoOutDir,
    /// Generated code that does not parse: a bug in the generator, reported as such.
    Emit(String),
    /// A file could not be written.
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Spec(d) => write!(f, "{d}"),
            Error::DuplicateProtocol {
                name,
                first,
                second,
            } => write!(
                f,
                "{}: name: protocol `{name}` is already generated from {}",
                second.display(),
                first.display()
            ),
            Error::NoSpecs => f.write_str("no spec files given to busspec_codegen::Builder"),
            Error::NoOutDir => f.write_str(
                "no output directory: OUT_DIR is not set (not in a build script?) and Builder::out_dir was not called",
            ),
            Error::Emit(e) => write!(f, "{e}"),
            Error::Io { path, error } => write!(f, "{}: cannot write: {error}", path.display()),
        }
    }
}

impl std::error::Error for Error {}

/// What [`Builder::generate`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Generated {
    /// Protocol names, in the order the specs were given.
    pub protocols: Vec<String>,
    /// Every file written or left as it was (already up to date), the index last: the
    /// modules, and for a spec that includes files, the spec as one text (`NAME.spec.yaml`,
    /// which the module embeds as `SPEC_YAML`).
    pub files: Vec<PathBuf>,
    /// Every file read: each spec, and each file a spec's `include` read.
    pub inputs: Vec<PathBuf>,
}

impl Builder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a spec file. A relative path is taken from the current directory, which for a build
    /// script is the package's root.
    pub fn spec(mut self, path: impl AsRef<Path>) -> Self {
        self.specs.push(path.as_ref().to_path_buf());
        self
    }

    /// Adds several spec files.
    pub fn specs<I, P>(mut self, paths: I) -> Self
    where
        I: IntoIterator<Item = P>,
        P: AsRef<Path>,
    {
        self.specs
            .extend(paths.into_iter().map(|p| p.as_ref().to_path_buf()));
        self
    }

    /// Writes the modules here instead of `OUT_DIR`.
    pub fn out_dir(mut self, dir: impl AsRef<Path>) -> Self {
        self.out_dir = Some(dir.as_ref().to_path_buf());
        self
    }

    /// Loads, validates and emits every spec, and writes one module per spec plus
    /// [`INDEX_FILE`]. Every spec is loaded before anything is written, and every spec's errors
    /// are reported together.
    pub fn generate(&self) -> Result<Generated, Vec<Error>> {
        if self.specs.is_empty() {
            return Err(vec![Error::NoSpecs]);
        }
        let out = match &self.out_dir {
            Some(d) => d.clone(),
            None => match std::env::var_os("OUT_DIR") {
                Some(d) => PathBuf::from(d),
                None => return Err(vec![Error::NoOutDir]),
            },
        };
        let mut errors = Vec::new();
        let mut modules: Vec<(String, PathBuf, String)> = Vec::new();
        // A spec that includes files is embedded as one text without them (`SPEC_YAML`),
        // written beside the modules.
        let mut flattened: Vec<(PathBuf, String)> = Vec::new();
        let mut inputs: Vec<PathBuf> = Vec::new();
        for spec in &self.specs {
            inputs.push(spec.clone());
            let (protocol, included) = match busspec_model::load_file_with_includes(spec) {
                Ok(l) => (l.protocol, l.included),
                Err(d) => {
                    errors.push(Error::Spec(d));
                    continue;
                }
            };
            inputs.extend(included.files.iter().map(|f| f.1.clone()));
            if let Some((_, first, _)) = modules.iter().find(|m| m.0 == protocol.name) {
                errors.push(Error::DuplicateProtocol {
                    name: protocol.name.clone(),
                    first: first.clone(),
                    second: spec.clone(),
                });
                continue;
            }
            // include_str! needs a path that holds wherever the module is included from.
            let absolute = match included.flattened {
                Some(text) => {
                    // What the crate embeds must load as it is, without the files.
                    if let Err(d) = busspec_model::load_str(&spec.display().to_string(), &text) {
                        errors.push(Error::Emit(format!(
                            "{}: the spec with its includes in place does not load on its own:\n{d}",
                            spec.display()
                        )));
                        continue;
                    }
                    let path = out.join(format!("{}.spec.yaml", protocol.name));
                    flattened.push((path.clone(), text));
                    std::path::absolute(&path).unwrap_or(path)
                }
                None => std::fs::canonicalize(spec).unwrap_or_else(|_| spec.clone()),
            };
            let source = spec.display().to_string();
            match emit::emit_module(&protocol, &source, &absolute.to_string_lossy()) {
                Ok(code) => modules.push((protocol.name.clone(), spec.clone(), code)),
                Err(e) => errors.push(Error::Emit(e)),
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let io = |path: &Path, error| Error::Io {
            path: path.to_path_buf(),
            error,
        };
        std::fs::create_dir_all(&out).map_err(|e| vec![io(&out, e)])?;
        let mut files = Vec::new();
        for (path, text) in &flattened {
            write_if_changed(path, text).map_err(|e| vec![io(path, e)])?;
            files.push(path.clone());
        }
        for (name, _, code) in &modules {
            let path = out.join(format!("{name}.rs"));
            write_if_changed(&path, code).map_err(|e| vec![io(&path, e)])?;
            files.push(path);
        }
        let names: Vec<&str> = modules.iter().map(|m| m.0.as_str()).collect();
        let index = emit_index(&names).map_err(|e| vec![Error::Emit(e)])?;
        let path = out.join(INDEX_FILE);
        write_if_changed(&path, &index).map_err(|e| vec![io(&path, e)])?;
        files.push(path);
        Ok(Generated {
            protocols: names.iter().map(|n| n.to_string()).collect(),
            files,
            inputs,
        })
    }

    /// [`Self::generate`] for a build script: tells cargo to rerun when a spec changes, and on
    /// failure prints every error as a cargo diagnostic line (`file: path: message`) and exits
    /// the build script with status 1.
    pub fn compile(&self) {
        // Generated types derive serde and arbitrary behind features of those names; the
        // including crate may not declare them.
        println!("cargo::rustc-check-cfg=cfg(feature, values(\"serde\", \"arbitrary\"))");
        match self.generate() {
            Ok(g) => {
                for input in &g.inputs {
                    println!("cargo::rerun-if-changed={}", input.display());
                }
            }
            Err(errors) => {
                // Which files a broken spec includes may not be known: rerun on any change
                // beside each spec (cargo scans a directory's files).
                for spec in &self.specs {
                    println!("cargo::rerun-if-changed={}", spec.display());
                    if let Some(dir) = spec.parent().filter(|d| !d.as_os_str().is_empty()) {
                        println!("cargo::rerun-if-changed={}", dir.display());
                    }
                }
                Self::fail(errors);
            }
        }
    }

    /// Prints every error as a cargo diagnostic line and exits the build script.
    fn fail(errors: Vec<Error>) -> ! {
        for e in errors {
            for line in e.to_string().lines() {
                println!("cargo::error={line}");
            }
        }
        std::process::exit(1);
    }
}

/// Writes `text` to `path` unless the file already holds exactly that, so an unchanged spec
/// does not make cargo rebuild what includes the file.
pub fn write_if_changed(path: &Path, text: &str) -> std::io::Result<()> {
    if std::fs::read_to_string(path).ok().as_deref() == Some(text) {
        return Ok(());
    }
    std::fs::write(path, text)
}

/// The index file: every module, the list of names, and the name-to-type dispatch.
pub fn emit_index(names: &[&str]) -> Result<String, String> {
    let files = names.iter().map(|n| format!("/{n}.rs"));
    let arms = names.iter().map(|n| {
        let module = format_ident!("{n}");
        let ty = format_ident!("{}", emit::camel(n));
        quote!(#n => ::core::option::Option::Some(visitor.visit::<#module::#ty>()))
    });
    let tokens: TokenStream = quote! {
        #(include!(concat!(env!("OUT_DIR"), #files));)*
        /// The name of every protocol generated into this crate, in the order its specs were given.
        pub const PROTOCOLS: &[&str] = &[#(#names),*];
        /// Runs `visitor` with the protocol called `name` (its spec's `name`), or returns `None`
        /// when this crate has no such protocol.
        pub fn with_protocol<V: ::busspec_runtime::ProtocolVisitor>(
            name: &str,
            visitor: V,
        ) -> ::core::option::Option<V::Output> {
            match name {
                #(#arms,)*
                _ => {
                    let _ = visitor;
                    ::core::option::Option::None
                }
            }
        }
    };
    let file: syn::File =
        syn::parse2(tokens).map_err(|e| format!("generated index does not parse: {e}"))?;
    Ok(format!(
        "{}\n{}",
        emit::PREAMBLE,
        prettyplease::unparse(&file)
    ))
}
