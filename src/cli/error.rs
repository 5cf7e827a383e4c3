//! The one error type of the command line: every command returns it, and `cli::main` renders it
//! once, on stderr, with exit status 2. Commands never print an error themselves.

use std::fmt;
use std::path::Path;

use crate::load::LoadErrors;
use crate::runner::SetupError;

/// Why a command could not do what it was asked (exit status 2).
#[derive(Debug)]
pub enum CliError {
    /// Bad arguments or data, as one message: what was wrong, and what to do instead.
    Input(String),
    /// Files that do not load: every problem with its `file:line` and key.
    Load(LoadErrors),
    /// A backend could not be set up (started, agreed on the protocol, its known differences).
    Setup(SetupError),
    /// A report, a saved run, a vector file or stdout could not be written.
    Write {
        what: String,
        source: std::io::Error,
    },
}

impl CliError {
    pub fn input(message: impl Into<String>) -> Self {
        CliError::Input(message.into())
    }

    /// A write to `path` (or to stdout when `None`) that failed.
    pub fn write(path: Option<&Path>, source: std::io::Error) -> Self {
        CliError::Write {
            what: path.map_or_else(|| "stdout".to_string(), |p| p.display().to_string()),
            source,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            // Already one `error:` line per problem.
            CliError::Load(e) => write!(f, "{e}"),
            CliError::Input(m) => write!(f, "error: {m}"),
            CliError::Setup(e) => write!(f, "error: {e}"),
            CliError::Write { what, source } => write!(f, "error: cannot write {what}: {source}"),
        }
    }
}

impl std::error::Error for CliError {}

impl From<LoadErrors> for CliError {
    fn from(e: LoadErrors) -> Self {
        CliError::Load(e)
    }
}

/// A message of bad input from an argument parser.
impl From<String> for CliError {
    fn from(message: String) -> Self {
        CliError::Input(message)
    }
}

impl From<SetupError> for CliError {
    fn from(e: SetupError) -> Self {
        CliError::Setup(e)
    }
}
