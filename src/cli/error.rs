//! The one error type of the command line: every command returns it, and `cli::main` renders it
//! once, on stderr, with exit status 2. Commands never print an error themselves.

use std::fmt;
use std::path::Path;

use crate::backend::bench::error::LiveError;
use crate::backend::external::serve::ServeError;
use crate::load::LoadErrors;
use crate::record::RecordError;
use crate::report::baseline::BaselineError;
use crate::session::SetupError;
use crate::sweep::SweepError;

/// Why a command could not do what it was asked (exit status 2).
#[derive(Debug)]
pub(crate) enum CliError {
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
    /// A live CPU setting, manifest or program refused, or the CPU not reached.
    Live(LiveError),
    /// A saved run to compare with that does not read.
    Baseline(BaselineError),
    /// A vector file to record into that does not read.
    Record(RecordError),
    /// `serve` could not read the harness or answer it.
    Serve(ServeError),
    /// A sweep's settings that do not fit its targets.
    Sweep(SweepError),
    /// The argument or step concerned (`--fault`, `--mailbox M`) and the error underneath.
    Within {
        part: String,
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl CliError {
    pub(crate) fn input(message: impl Into<String>) -> Self {
        CliError::Input(message.into())
    }

    /// `source` as the error of an argument or step.
    pub(crate) fn within(
        part: impl Into<String>,
        source: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> Self {
        CliError::Within {
            part: part.into(),
            source: source.into(),
        }
    }

    /// A write to `path` (or to stdout when `None`) that failed.
    pub(crate) fn write(path: Option<&Path>, source: std::io::Error) -> Self {
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
            CliError::Write { what, .. } => write!(f, "error: cannot write {what}"),
            CliError::Live(e) => write!(f, "error: {e}"),
            CliError::Baseline(e) => write!(f, "error: {e}"),
            CliError::Record(e) => write!(f, "error: {e}"),
            CliError::Serve(e) => write!(f, "error: {e}"),
            CliError::Sweep(e) => write!(f, "error: {e}"),
            CliError::Within { part, .. } => write!(f, "error: {part}"),
        }
    }
}

impl std::error::Error for CliError {
    /// The cause under the message: a wrapped error's own cause, since the message is the
    /// wrapped error's (a load error list carries its causes in its lines).
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CliError::Input(_) | CliError::Load(_) => None,
            CliError::Setup(e) => e.source(),
            CliError::Write { source, .. } => Some(source),
            CliError::Live(e) => e.source(),
            CliError::Baseline(e) => e.source(),
            CliError::Record(e) => e.source(),
            CliError::Serve(e) => e.source(),
            CliError::Sweep(e) => e.source(),
            CliError::Within { source, .. } => Some(source.as_ref()),
        }
    }
}

impl CliError {
    /// The exit status of a command that ends with this error: every error is bad input or
    /// setup (2), and an interrupted run ends as an interruption whatever it was doing.
    pub(crate) fn exit_status(&self) -> u8 {
        super::EXIT_BAD_INPUT
    }
}

impl From<LiveError> for CliError {
    fn from(e: LiveError) -> Self {
        CliError::Live(e)
    }
}

impl From<BaselineError> for CliError {
    fn from(e: BaselineError) -> Self {
        CliError::Baseline(e)
    }
}

impl From<RecordError> for CliError {
    fn from(e: RecordError) -> Self {
        CliError::Record(e)
    }
}

impl From<SweepError> for CliError {
    fn from(e: SweepError) -> Self {
        CliError::Sweep(e)
    }
}

impl From<ServeError> for CliError {
    fn from(e: ServeError) -> Self {
        CliError::Serve(e)
    }
}

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
