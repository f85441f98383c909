//! Diagnostics: what is wrong and where, collected so that every error is reported at once.

use std::fmt;

/// One problem in a spec: a dotted path into the file (`commands.go_to_capacitance.fields.target`)
/// and what is wrong there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    pub path: String,
    pub message: String,
}

impl Diagnostic {
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Diagnostic {
            path: path.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

/// All the problems found in one file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostics {
    pub file: String,
    pub items: Vec<Diagnostic>,
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.items.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{}: {}", self.file, d)?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}

/// A collector that hands out paths and gathers diagnostics.
#[derive(Debug, Default)]
pub struct Sink {
    pub items: Vec<Diagnostic>,
}

impl Sink {
    pub fn error(&mut self, path: impl Into<String>, message: impl Into<String>) {
        self.items.push(Diagnostic::new(path, message));
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// Joins a path and a child segment: `join("commands", "go_to")` is `commands.go_to`.
pub fn join(path: &str, child: &str) -> String {
    if path.is_empty() {
        child.to_owned()
    } else if child.starts_with('[') {
        format!("{path}{child}")
    } else {
        format!("{path}.{child}")
    }
}
