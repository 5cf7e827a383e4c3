//! A project's external backends, validated: how to start each one, and those that cannot run
//! here, with why.

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

use super::Location;

/// The per-case time limit unless configured.
pub(crate) const DEFAULT_TIMEOUT: Duration = Duration::from_secs(5);
/// The time a backend has to start and answer `hello` unless configured.
pub(crate) const DEFAULT_STARTUP_TIMEOUT: Duration = Duration::from_secs(20);
/// Cases per `run` message unless configured.
pub(crate) const DEFAULT_BATCH: usize = 256;
/// Faults in a row after which a backend's remaining trials are not run, unless configured.
pub(crate) const DEFAULT_MAX_CONSECUTIVE_FAULTS: usize = 5;

/// How to start a backend.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Launch {
    /// A command line run by the shell (`sh -c`).
    Shell(String),
    /// A program and its arguments, run directly.
    Exec(Vec<String>),
}

impl fmt::Display for Launch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Launch::Shell(s) => f.write_str(s),
            Launch::Exec(args) => f.write_str(&args.join(" ")),
        }
    }
}

/// How to run one external backend.
#[derive(Debug, Clone)]
pub struct ExternalSettings {
    /// The name in trial names and on the command line.
    pub name: String,
    pub launch: Launch,
    /// The profile family the configuration says the backend implements; the handshake must
    /// agree. `None` takes the handshake's word.
    pub profile: Option<String>,
    /// Whether the configuration says the backend is codec-level; the handshake must agree.
    pub codec: bool,
    /// The protocol a codec-level backend is configured as implementing; the handshake must
    /// agree. `None` takes the handshake's word (not for a backend planned before it starts).
    pub protocol: Option<String>,
    /// With `protocol`: the configuration asks for the cross-vendor view too.
    pub cross_vendor: bool,
    /// The limit for one case's answer.
    pub timeout: Duration,
    /// The limit for starting and answering `hello`.
    pub startup_timeout: Duration,
    /// The backend's known-differences file.
    pub known_differences: Option<PathBuf>,
    /// The working directory of the process.
    pub cwd: Option<PathBuf>,
    /// Extra environment variables for the process.
    pub env: Vec<(String, String)>,
    /// Cases per `run` message.
    pub batch: usize,
    /// Faults (crash, timeout, protocol error) in a row after which the backend's remaining
    /// trials are reported as not run, failures with the reason, instead of costing each its
    /// time limit: the circuit breaker. At least 1.
    pub max_consecutive_faults: usize,
    /// Whether the process stays up between cases (the normal way), or is started for each
    /// case and shut down after it (for measuring what persistence buys).
    pub persistent: bool,
}

impl ExternalSettings {
    pub fn new(name: impl Into<String>, launch: Launch) -> Self {
        ExternalSettings {
            name: name.into(),
            launch,
            profile: None,
            codec: false,
            protocol: None,
            cross_vendor: false,
            timeout: DEFAULT_TIMEOUT,
            startup_timeout: DEFAULT_STARTUP_TIMEOUT,
            known_differences: None,
            cwd: None,
            env: Vec::new(),
            batch: DEFAULT_BATCH,
            max_consecutive_faults: DEFAULT_MAX_CONSECUTIVE_FAULTS,
            persistent: true,
        }
    }
}

/// A backend from the project file.
#[derive(Debug, Clone)]
pub struct Configured {
    pub settings: ExternalSettings,
    pub requires: Vec<PathBuf>,
    pub location: Location,
    /// Run only when named with `--backend`.
    pub on_request: bool,
}

impl Configured {
    /// What is missing for this backend to run, if anything.
    pub fn missing(&self) -> Option<SkippedBackend> {
        let missing: Vec<PathBuf> = self
            .requires
            .iter()
            .filter(|p| !p.exists())
            .cloned()
            .collect();
        (!missing.is_empty()).then(|| SkippedBackend {
            name: self.settings.name.clone(),
            location: self.location.clone(),
            missing,
        })
    }
}

/// A configured backend left out because something it needs is missing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedBackend {
    pub name: String,
    /// Where it is configured.
    pub location: Location,
    /// The required files that do not exist.
    pub missing: Vec<PathBuf>,
}

impl fmt::Display for SkippedBackend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let missing: Vec<String> = self
            .missing
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        write!(
            f,
            "external backend `{}` ({}) needs {}, which is missing",
            self.name,
            self.location,
            missing.join(", ")
        )
    }
}

/// The external backends of a project file: those to run and those left out.
#[derive(Debug, Clone, Default)]
pub struct ProjectBackends {
    pub configured: Vec<Configured>,
    pub skipped: Vec<SkippedBackend>,
}
