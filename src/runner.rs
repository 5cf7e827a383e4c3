//! Running a project: its profiles, corpus and backends, through plan -> execute -> judge, with
//! every result sent to a reporter as it is judged.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crate::backend::external::{ExternalBackend, ExternalError};
use crate::backend::slmp::error::LiveError;
use crate::backend::{reference_backends, Backend};
use crate::execute::{execute, execute_all, Pace, Progress};
use crate::judge::{judge, skipped, Verdict};
use crate::load::{
    embedded_vectors, embedded_vendors, load_corpus, load_known, load_profiles, LoadErrors,
};
use crate::model::known::KnownDifferences;
use crate::model::profile::Profiles;
use crate::model::project::ExternalSettings;
use crate::model::Corpus;
use crate::plan::{plan, Trial};
use crate::report::{Event, Reporter, Summary};

/// Where a project keeps its data.
#[derive(Debug, Clone)]
pub struct Paths {
    pub vendors: PathBuf,
    pub vectors: Vec<PathBuf>,
}

impl Paths {
    /// `vendors/` and `vectors/` under a project root.
    pub fn under(root: &Path) -> Self {
        Paths {
            vendors: root.join("vendors"),
            vectors: vec![root.join("vectors")],
        }
    }

    /// The vendor profiles and corpus shipped inside the binary.
    pub fn embedded() -> Self {
        Paths {
            vendors: embedded_vendors(),
            vectors: vec![embedded_vectors()],
        }
    }

    /// A project folder's `vendors/` and `vectors/`, each replaced by the shipped one where the
    /// folder has none (a project that only lists its own backends runs the shipped corpus).
    pub fn of_project(root: &Path) -> Self {
        let (vendors, vectors) = (root.join("vendors"), root.join("vectors"));
        Paths {
            vendors: if vendors.is_dir() {
                vendors
            } else {
                embedded_vendors()
            },
            vectors: vec![if vectors.is_dir() {
                vectors
            } else {
                embedded_vectors()
            }],
        }
    }
}

/// A loaded project: what a run plans from.
pub struct Project {
    pub profiles: Profiles,
    pub corpus: Corpus,
    /// The built-in reference models and the external backends added so far.
    pub backends: Vec<Arc<dyn Backend>>,
    /// Known differences by backend name.
    pub known: BTreeMap<String, KnownDifferences>,
}

/// Why an external backend could not be added.
#[derive(Debug)]
pub enum SetupError {
    /// Its known-differences file is wrong.
    Load(LoadErrors),
    /// It could not be started or refused the protocol.
    External(ExternalError),
    /// Its name is already taken.
    Duplicate(String),
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
            SetupError::Duplicate(_) => None,
            SetupError::Live { source, .. } => Some(source),
        }
    }
}

impl Project {
    /// Loads profiles and corpus and sets up the built-in reference backends.
    pub fn load(paths: &Paths) -> Result<Project, LoadErrors> {
        let profiles = load_profiles(&paths.vendors)?;
        let corpus = load_corpus(&paths.vectors, &profiles)?;
        let backends = reference_backends(&profiles);
        Ok(Project {
            profiles,
            corpus,
            backends,
            known: BTreeMap::new(),
        })
    }

    /// Starts an external backend and adds it, with its known differences. `strict_known`
    /// makes entries for cases outside the corpus errors (see [`load_known`]).
    pub fn add_external(
        &mut self,
        settings: ExternalSettings,
        strict_known: bool,
    ) -> Result<Arc<ExternalBackend>, SetupError> {
        check_name(&settings.name, &self.backends)?;
        let known_file = settings.known_differences.clone();
        let backend = Arc::new(
            ExternalBackend::start(settings, &self.profiles).map_err(SetupError::External)?,
        );
        // The backend's profile was checked when it started; a codec-level one has none.
        if let Some(file) = known_file {
            self.add_known(backend.name(), backend.profile(), &file, strict_known)?;
        }
        self.backends.push(backend.clone());
        Ok(backend)
    }

    /// Loads `file` as backend `name`'s known differences, checked against its profile (none,
    /// or an empty id, for a codec-level backend) and the corpus: the one place a project takes
    /// a known-differences file. `strict_known` makes an entry for a case outside the corpus
    /// an error (see [`load_known`]).
    pub(crate) fn add_known(
        &mut self,
        name: &str,
        profile: &str,
        file: &Path,
        strict_known: bool,
    ) -> Result<(), SetupError> {
        let known = self
            .read_known(profile, file, strict_known)
            .map_err(SetupError::Load)?;
        self.known.insert(name.to_string(), known);
        Ok(())
    }

    fn read_known(
        &self,
        profile: &str,
        file: &Path,
        strict_known: bool,
    ) -> Result<KnownDifferences, LoadErrors> {
        let profile = self.profiles.get(profile).map(|p| p.as_ref());
        load_known(file, profile, &self.corpus, strict_known)
    }

    /// A known-differences file for `backend`, checked against its profile (none for a codec)
    /// and the whole corpus: an entry for a case the corpus does not have is an error.
    pub fn known_differences(
        &self,
        backend: &dyn Backend,
        file: &Path,
    ) -> Result<KnownDifferences, LoadErrors> {
        self.read_known(backend.profile(), file, true)
    }

    /// Every trial of the corpus on these backends, with their known differences.
    pub fn plan(&self, backends: &[Arc<dyn Backend>]) -> Vec<Trial> {
        plan(&self.corpus, &self.profiles, backends, &self.known)
    }
}

/// Refuses a backend name that one of `taken` has: the one check every way of adding a backend
/// makes (a run's sources against the backends assembled so far, a started process against
/// the project's).
pub(crate) fn check_name(name: &str, taken: &[Arc<dyn Backend>]) -> Result<(), SetupError> {
    match taken.iter().any(|b| b.name() == name) {
        true => Err(SetupError::Duplicate(name.to_string())),
        false => Ok(()),
    }
}

/// Runs one trial: skipped, or executed under every fill and judged.
pub fn run_one(trial: &Trial) -> Verdict {
    match &trial.skip {
        Some(reason) => skipped(reason),
        None => judge(trial, &execute(trial)),
    }
}

/// Runs trials and reports each verdict as it is judged: skipped trials first, then each
/// backend's results as they come in (backends side by side, at most `jobs` at once). When
/// `stop` is set, no further chunk is started and the run finishes with what it has, reported
/// as interrupted. Returns the counts, or the reporter's first write error: the run ends
/// there, since a report that cannot be written would only be truncated.
pub(crate) fn run(
    trials: &[Trial],
    jobs: usize,
    stop: &AtomicBool,
    pace: Pace,
    reporter: &mut dyn Reporter,
) -> std::io::Result<Summary> {
    let mut summary = Summary::default();
    reporter.event(&Event::RunStarted {
        trials: trials.len(),
    })?;
    for (i, t) in trials.iter().enumerate() {
        if let Some(reason) = &t.skip {
            finished(
                reporter,
                &mut summary,
                trials,
                i,
                skipped(reason),
                Duration::ZERO,
            )?;
        }
    }
    let indices: Vec<usize> = (0..trials.len()).collect();
    let mut failed = None;
    execute_all(trials, &indices, jobs, stop, pace, |progress| {
        let written = match progress {
            Progress::Observed(i, observations, elapsed) => {
                let mut verdict = judge(&trials[i], &observations);
                // Once the run is interrupted, its backends are killed: a trial that then
                // faults was cancelled, not failed.
                if stop.load(Ordering::Relaxed) && matches!(verdict, Verdict::Fault { .. }) {
                    verdict = Verdict::cancelled();
                }
                finished(reporter, &mut summary, trials, i, verdict, elapsed)
            }
            Progress::Restarted { backend, restarts } => reporter.event(&Event::BackendRestarted {
                backend: &backend,
                restarts,
            }),
            Progress::Answering {
                backend,
                answered,
                of,
            } => reporter.event(&Event::BackendAnswering {
                backend: &backend,
                answered,
                of,
            }),
        };
        match written {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                failed = Some(e);
                ControlFlow::Break(())
            }
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    let interrupted = stop.load(Ordering::Relaxed);
    reporter.event(&Event::RunFinished {
        summary: &summary,
        interrupted,
    })?;
    Ok(summary)
}

/// Runs trials (each backend's batched) and returns their verdicts in plan order.
pub fn verdicts(trials: &[Trial]) -> Vec<Verdict> {
    struct Keep(Vec<Option<Verdict>>);
    impl Reporter for Keep {
        fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
            if let Event::TrialFinished { index, verdict, .. } = event {
                self.0[*index] = Some((*verdict).clone());
            }
            Ok(())
        }
    }
    let mut keep = Keep(vec![None; trials.len()]);
    // Keep writes nothing, so it cannot fail.
    let _ = run(trials, 1, &AtomicBool::new(false), Pace::Ahead, &mut keep);
    keep.0
        .into_iter()
        .map(|v| v.unwrap_or_else(|| skipped("not run")))
        .collect()
}

fn finished(
    reporter: &mut dyn Reporter,
    summary: &mut Summary,
    trials: &[Trial],
    index: usize,
    verdict: Verdict,
    elapsed: Duration,
) -> std::io::Result<()> {
    summary.add(&verdict);
    reporter.event(&Event::TrialFinished {
        index,
        trial: &trials[index],
        verdict: &verdict,
        elapsed,
    })
}
