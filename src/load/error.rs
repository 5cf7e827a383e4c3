//! Load errors: what is wrong with a vector or profile file, and where.

use std::fmt;
use std::path::PathBuf;

use crate::device::DeviceSyntaxError;
use crate::model::Location;
use crate::value::ValueError;

/// One problem in one file. Rendered as `file:line: key: message`, the shape editors and
/// terminals turn into a link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LoadError {
    pub file: PathBuf,
    pub line: Option<usize>,
    /// The key path, e.g. `cases[3].operands.s`.
    pub key: Option<String>,
    pub kind: Box<LoadErrorKind>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum LoadErrorKind {
    /// The file or folder could not be read.
    Io(String),
    /// The YAML does not have the format's shape (syntax, unknown key, wrong type).
    Shape(String),
    /// A name that the profile (or the corpus) does not define.
    Unknown {
        what: &'static str,
        name: String,
        expected: Vec<String>,
    },
    /// A required key is missing.
    Missing(&'static str),
    /// An id used before.
    DuplicateId {
        id: String,
        first: Location,
    },
    Device(DeviceSyntaxError),
    Value(ValueError),
    /// Anything else the format rules out, said in words.
    Invalid(String),
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(key) = &self.key {
            write!(f, ": {key}")?;
        }
        // A device or value that does not read is the cause, shown after the place.
        match std::error::Error::source(self) {
            Some(_) => Ok(()),
            None => write!(f, ": {}", self.kind),
        }
    }
}

impl fmt::Display for LoadErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadErrorKind::Io(msg) | LoadErrorKind::Shape(msg) | LoadErrorKind::Invalid(msg) => {
                f.write_str(msg)
            }
            LoadErrorKind::Unknown {
                what,
                name,
                expected,
            } => {
                write!(f, "unknown {what} `{name}`")?;
                if expected.is_empty() {
                    write!(f, "; none is defined here")
                } else {
                    write!(f, "; expected one of: {}", expected.join(", "))
                }
            }
            LoadErrorKind::Missing(what) => write!(f, "missing {what}"),
            LoadErrorKind::DuplicateId { id, first } => {
                write!(f, "duplicate case id `{id}`, first used at {first}")
            }
            LoadErrorKind::Device(e) => write!(f, "{e}"),
            LoadErrorKind::Value(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &*self.kind {
            LoadErrorKind::Device(e) => Some(e),
            LoadErrorKind::Value(e) => Some(e),
            _ => None,
        }
    }
}

/// All the problems found in a corpus or a set of profiles; loading reports every one rather
/// than stopping at the first.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LoadErrors(pub(crate) Vec<LoadError>);

impl fmt::Display for LoadErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for e in &self.0 {
            writeln!(f, "error: {}", crate::error_chain::chain(e))?;
        }
        write!(
            f,
            "{} error{} found",
            self.0.len(),
            if self.0.len() == 1 { "" } else { "s" }
        )
    }
}

impl std::error::Error for LoadErrors {}
