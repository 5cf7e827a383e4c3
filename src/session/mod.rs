//! A session: a loaded project and the backends set up for it, built once and run the same way
//! by every way of running — the command line's `run`, `diff` (with `--against`), `sweep`,
//! `record` and `hil`, and the libtest trials of `cargo test`.
//!
//! A backend comes from a [`BackendSource`]: a built-in reference model, a process speaking the
//! protocol (started now, or on the first trial that needs it), a backend in this process (an
//! emulator or a codec written in Rust), or a live CPU. [`Session::add`] is the one place any of
//! them is built, its known differences loaded and its name checked against the others; a new
//! kind of transport (a network connection to a CPU, say) is one more variant here and one file
//! of its own under `backend/`. The command line only maps its arguments to sources and writes
//! what [`Session::run`] returns.

mod against;
mod asked;
mod first_use;
mod hello_cache;
mod run;

use std::fmt;
use std::ops::Deref;
use std::path::PathBuf;
use std::sync::Arc;

pub(crate) use against::Against;
pub(crate) use asked::Asked;
pub(crate) use first_use::LazyStart;
use first_use::Placeholder;
pub(crate) use hello_cache::HelloCache;
pub(crate) use run::{observe, run_trials, RunOptions, RunOutcome};
pub use run::{run_one, verdicts};

use crate::backend::bench::error::LiveError;
use crate::backend::bench::{BenchBackend, BenchSettings, LinkSettings};
use crate::backend::external::{ExternalBackend, ExternalError};
use crate::backend::{reference_backends, Backend};
use crate::load::LoadErrors;
use crate::model::project::ExternalSettings;
use crate::project::Project;

/// Where a backend comes from.
pub enum BackendSource {
    /// Every built-in reference model whose profile is loaded (none of them asked for by name:
    /// a run of them all does not require each to run a trial).
    References,
    /// One built-in reference model, by name.
    Reference(String),
    /// A process speaking the protocol, started now (its handshake says what it implements).
    Process(ExternalSettings),
    /// A process speaking the protocol whose profile or codec level is declared: planned now,
    /// started by the first trial that runs it, so that listing or running one trial of another
    /// backend starts nothing.
    ProcessOnFirstUse(ExternalSettings),
    /// A backend in this process, with its known-differences file.
    InProcess(Arc<dyn Backend>, Option<PathBuf>),
    /// A live CPU over any link (`backend::bench`; SLMP is one): built without a socket, then
    /// connected and its read-only interlocks run, so that a bench that is not ready is an error
    /// before any case and before any write.
    Bench(Box<BenchSettings>),
}

/// Why a backend could not be set up.
#[derive(Debug)]
pub enum SetupError {
    /// Its known-differences file is wrong.
    Load(LoadErrors),
    /// It could not be started or refused the protocol.
    External(ExternalError),
    /// Its name is already taken.
    Duplicate(String),
    /// No built-in reference model has this name.
    NoModel(String),
    /// An in-process backend of a profile the project does not have: `known` lists each
    /// profile's id and short name.
    NoProfile {
        backend: String,
        profile: String,
        known: Vec<(String, String)>,
    },
    /// A codec configured as implementing a protocol no profile defines.
    NoProtocol {
        backend: String,
        protocol: String,
        known: Vec<String>,
    },
    /// A backend asked for that cannot be had (a text that names none, or names one wrongly):
    /// what was wrong and what to give instead.
    Asked(String),
    /// A bench backend's text (`slmp:...`, `modbus:...`) refused before anything was reached.
    Spec(LiveError),
    /// A live CPU backend whose settings, program manifest or interlocks (type name, RUN, the
    /// program's signature) refused it before anything was written: the backend and why.
    Live { backend: String, source: LiveError },
}

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetupError::Load(e) => write!(f, "{e}"),
            SetupError::External(e) => write!(f, "{e}"),
            SetupError::Duplicate(name) => write!(f, "there are two backends named `{name}`"),
            SetupError::NoModel(name) => write!(f, "no built-in reference model named `{name}`"),
            SetupError::NoProfile {
                backend,
                profile,
                known,
            } => {
                write!(
                    f,
                    "backend `{backend}` names profile `{profile}`, which is not loaded"
                )?;
                if let Some((id, _)) = known.iter().find(|(_, short)| short == profile) {
                    write!(
                        f,
                        "; did you mean `{id}` (the profile whose short name it is)?"
                    )?;
                }
                let ids: Vec<&str> = known.iter().map(|(id, _)| id.as_str()).collect();
                write!(f, " The profiles are: {}", ids.join(", "))
            }
            SetupError::NoProtocol {
                backend,
                protocol,
                known,
            } => write!(
                f,
                "backend `{backend}` is configured as implementing protocol `{protocol}`, which \
                 no protocol profile defines; the protocols are: {}",
                known.join(", ")
            ),
            SetupError::Asked(message) => f.write_str(message),
            SetupError::Spec(e) => write!(f, "{e}"),
            SetupError::Live { backend, .. } => {
                write!(f, "live CPU backend `{backend}` not started")
            }
        }
    }
}

impl std::error::Error for SetupError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SetupError::Load(e) => e.source(),
            SetupError::External(e) => e.source(),
            SetupError::Duplicate(_)
            | SetupError::NoModel(_)
            | SetupError::NoProfile { .. }
            | SetupError::NoProtocol { .. }
            | SetupError::Asked(_) => None,
            SetupError::Spec(e) => e.source(),
            SetupError::Live { source, .. } => Some(source),
        }
    }
}

/// A project and its backends, in the order of their sources.
pub struct Session {
    pub project: Project,
    pub backends: Vec<Arc<dyn Backend>>,
    /// The backends started on first use: their trials start them through these.
    pub(crate) on_first_use: Vec<Arc<LazyStart>>,
    /// The processes started while setting up, by backend name, with their answers to `hello`.
    pub(crate) hellos: Vec<(String, Vec<u8>)>,
    /// The backends named by their source (all but [`BackendSource::References`]): a run they
    /// were asked for must run a trial on each.
    asked: Vec<String>,
}

/// A session reads as its project: its profiles, corpus, known differences and planning.
impl Deref for Session {
    type Target = Project;
    fn deref(&self) -> &Project {
        &self.project
    }
}

impl Session {
    /// A session with no backend yet.
    pub fn new(project: Project) -> Session {
        Session {
            project,
            backends: Vec::new(),
            on_first_use: Vec::new(),
            hellos: Vec::new(),
            asked: Vec::new(),
        }
    }

    /// A session with every built-in reference model.
    pub fn with_references(project: Project) -> Session {
        let mut session = Session::new(project);
        // The reference models have distinct names and no known-differences file.
        let _ = session.add(BackendSource::References, true);
        session
    }

    /// Sets up every source, in order; the sources that could not be set up, by backend name.
    /// `strict_known` makes a known-differences entry for a case outside the corpus an error
    /// (see [`crate::load::load_known`]).
    pub(crate) fn assemble(
        project: Project,
        sources: Vec<BackendSource>,
        strict_known: bool,
    ) -> (Session, Vec<(String, SetupError)>) {
        let mut session = Session::new(project);
        // The processes start side by side: each handshake mostly waits for an interpreter
        // and a library to load (a quarter of a second for a Python library, more for Node),
        // and listing the trials (as nextest does before every run) starts them all.
        let profiles = &session.project.profiles;
        let mut started: Vec<Option<Result<ExternalBackend, ExternalError>>> =
            std::thread::scope(|scope| {
                let starting: Vec<_> = (sources.iter())
                    .map(|source| match source {
                        BackendSource::Process(settings) => Some(
                            scope.spawn(move || ExternalBackend::start(settings.clone(), profiles)),
                        ),
                        _ => None,
                    })
                    .collect();
                (starting.into_iter())
                    .map(|s| {
                        s.map(|s| {
                            s.join()
                                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                        })
                    })
                    .collect()
            });
        let mut failed = Vec::new();
        for (source, started) in sources.into_iter().zip(started.iter_mut()) {
            let name = source.name();
            let added = match (source, started.take()) {
                (BackendSource::Process(settings), Some(started)) => {
                    session.add_started(settings, started, strict_known)
                }
                (source, _) => session.add(source, strict_known).map(|_| ()),
            };
            if let Err(e) = added {
                failed.push((name, e));
            }
        }
        (session, failed)
    }

    /// Sets up one source: its backend built (a process started or prepared to start on first
    /// use, a live CPU connected and its interlocks run), its name checked against the
    /// backends so far, its known-differences file loaded into the project. Returns the
    /// backends it added: one, or every reference model.
    pub fn add(
        &mut self,
        source: BackendSource,
        strict_known: bool,
    ) -> Result<&[Arc<dyn Backend>], SetupError> {
        let name = source.name();
        let before = self.backends.len();
        if !matches!(source, BackendSource::References) {
            self.check_name(&name)?;
        }
        let backend: Arc<dyn Backend> = match source {
            BackendSource::References => {
                for model in reference_backends(&self.project.profiles) {
                    self.check_name(model.name())?;
                    self.backends.push(model);
                }
                return Ok(&self.backends[before..]);
            }
            BackendSource::Reference(name) => reference_backends(&self.project.profiles)
                .into_iter()
                .find(|b| b.name() == name)
                .ok_or(SetupError::NoModel(name))?,
            BackendSource::Process(settings) => {
                let started = ExternalBackend::start(settings.clone(), &self.project.profiles);
                self.add_started(settings, started, strict_known)?;
                return Ok(&self.backends[before..]);
            }
            BackendSource::ProcessOnFirstUse(settings) => {
                let profile = settings.profile.clone();
                let protocol = match &settings.protocol {
                    None => None,
                    Some(id) if self.project.profiles.protocols.get(id).is_some() => {
                        Some((id.clone(), settings.cross_vendor))
                    }
                    Some(id) => {
                        return Err(SetupError::NoProtocol {
                            backend: name.clone(),
                            protocol: id.clone(),
                            known: self.project.profiles.protocols.ids(),
                        })
                    }
                };
                if let Some(file) = &settings.known_differences {
                    let p = profile.as_deref().unwrap_or("");
                    self.project
                        .add_known(&name, p, file, strict_known)
                        .map_err(SetupError::Load)?;
                }
                let lazy = Arc::new(LazyStart::new(settings, self.project.profiles.clone()));
                self.on_first_use.push(lazy.clone());
                Arc::new(Placeholder::new(name.clone(), profile, protocol, lazy))
            }
            BackendSource::Bench(settings) => {
                let live = self.live(*settings)?;
                live.connect().map_err(|source| SetupError::Live {
                    backend: name.clone(),
                    source,
                })?;
                live
            }
            BackendSource::InProcess(backend, known) => {
                // An emulator of a profile the project does not have would get no trial: a
                // run that checks nothing, never a pass.
                if backend.codec().is_none()
                    && self.project.profiles.get(backend.profile()).is_none()
                {
                    return Err(SetupError::NoProfile {
                        backend: name,
                        profile: backend.profile().to_string(),
                        known: (self.project.profiles.iter())
                            .map(|p| (p.id.clone(), p.short.clone()))
                            .collect(),
                    });
                }
                if let Some(file) = known {
                    self.project
                        .add_known(&name, backend.profile(), &file, strict_known)
                        .map_err(SetupError::Load)?;
                }
                backend
            }
        };
        self.backends.push(backend);
        self.asked.push(name);
        Ok(&self.backends[before..])
    }

    /// Adds a process started from `settings` (or why it did not start), with its known
    /// differences; its name is checked as [`Session::add`] checks every name.
    fn add_started(
        &mut self,
        settings: ExternalSettings,
        started: Result<ExternalBackend, ExternalError>,
        strict_known: bool,
    ) -> Result<(), SetupError> {
        self.check_name(&settings.name)?;
        let started = started.map_err(SetupError::External)?;
        self.hellos
            .push((settings.name.clone(), started.hello().to_vec()));
        // The backend's profile was checked when it started; a codec-level one has none.
        if let Some(file) = &settings.known_differences {
            self.project
                .add_known(&settings.name, started.profile(), file, strict_known)
                .map_err(SetupError::Load)?;
        }
        self.backends.push(Arc::new(started));
        self.asked.push(settings.name);
        Ok(())
    }

    /// A live CPU backend built from its settings and manifest, with no socket opened: what a
    /// dry run plans with, and what [`BackendSource::Bench`] then connects.
    pub(crate) fn live<L: LinkSettings + Clone + 'static>(
        &self,
        settings: BenchSettings<L>,
    ) -> Result<Arc<BenchBackend>, SetupError> {
        let backend = settings.name.clone();
        BenchBackend::new(settings, &self.project.profiles)
            .map(Arc::new)
            .map_err(|source| SetupError::Live { backend, source })
    }

    /// Refuses a backend name the session already has: the one check every way of adding a
    /// backend makes.
    fn check_name(&self, name: &str) -> Result<(), SetupError> {
        match self.backends.iter().any(|b| b.name() == name) {
            true => Err(SetupError::Duplicate(name.to_string())),
            false => Ok(()),
        }
    }

    /// The backend of this name.
    pub fn backend(&self, name: &str) -> Option<&Arc<dyn Backend>> {
        self.backends.iter().find(|b| b.name() == name)
    }
}

impl BackendSource {
    /// The backend's name (empty for the set of reference models).
    pub(crate) fn name(&self) -> String {
        match self {
            BackendSource::References => String::new(),
            BackendSource::Reference(name) => name.clone(),
            BackendSource::Process(s) | BackendSource::ProcessOnFirstUse(s) => s.name.clone(),
            BackendSource::InProcess(b, _) => b.name().to_string(),
            BackendSource::Bench(s) => s.name.clone(),
        }
    }
}

#[cfg(test)]
mod white_box;
