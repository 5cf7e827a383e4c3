//! A loaded project: profiles, corpus and the backends to run, from the usual folders.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::backend::external::config::{self, Configured};
use crate::backend::external::known::KnownDifferences;
use crate::backend::external::{ExternalBackend, ExternalError, ExternalSpec};
use crate::backend::{reference_backends, Backend};
use crate::compare::Verdict;
use crate::load::{load_corpus, load_profiles, LoadErrors};
use crate::model::Corpus;
use crate::plan::Trial;
use crate::profile::Profiles;

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
}

pub struct Session {
    pub profiles: Profiles,
    pub corpus: Corpus,
    pub backends: Vec<Arc<dyn Backend>>,
    /// Known differences by backend name.
    pub known: BTreeMap<String, KnownDifferences>,
}

/// Why an external backend could not be added.
#[derive(Debug)]
pub enum SessionError {
    /// Its known-differences file (or the project file) is wrong.
    Load(LoadErrors),
    /// It could not be started or refused the protocol.
    External(ExternalError),
    /// Its name is already taken.
    Duplicate(String),
}

impl fmt::Display for SessionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SessionError::Load(e) => write!(f, "{e}"),
            SessionError::External(e) => write!(f, "error: {e}"),
            SessionError::Duplicate(name) => {
                write!(f, "error: there are two backends named `{name}`")
            }
        }
    }
}

impl std::error::Error for SessionError {}

impl Session {
    /// Loads profiles and corpus and sets up the built-in reference backends.
    pub fn load(paths: &Paths) -> Result<Session, LoadErrors> {
        let profiles = load_profiles(&paths.vendors)?;
        let corpus = load_corpus(&paths.vectors, &profiles)?;
        let backends = reference_backends(&profiles);
        Ok(Session {
            profiles,
            corpus,
            backends,
            known: BTreeMap::new(),
        })
    }

    /// Starts an external backend and adds it, with its known differences. `strict_known`
    /// makes entries for cases outside the corpus errors (see [`KnownDifferences::load`]).
    pub fn add_external(
        &mut self,
        spec: ExternalSpec,
        strict_known: bool,
    ) -> Result<Arc<ExternalBackend>, SessionError> {
        if self.backends.iter().any(|b| b.name() == spec.name) {
            return Err(SessionError::Duplicate(spec.name));
        }
        let known_file = spec.known_differences.clone();
        let backend =
            Arc::new(ExternalBackend::start(spec, &self.profiles).map_err(SessionError::External)?);
        // The backend's profile was checked when it started.
        if let (Some(file), Some(profile)) = (known_file, self.profiles.get(backend.profile())) {
            let known = KnownDifferences::load(&file, profile, &self.corpus, strict_known)
                .map_err(SessionError::Load)?;
            self.known.insert(backend.name().to_string(), known);
        }
        self.backends.push(backend.clone());
        Ok(backend)
    }

    /// Runs one trial and applies its backend's known differences.
    pub fn verdict(&self, trial: &Trial) -> Verdict {
        self.apply_known(trial, trial.run())
    }

    /// Runs one cross-vendor trial and applies its backend's known differences.
    pub fn neutral_verdict(
        &self,
        trial: &crate::neutral::lower::NeutralTrial,
    ) -> crate::neutral::lower::NeutralVerdict {
        let verdict = trial.run();
        match self.known.get(trial.backend.name()) {
            Some(known) => known.apply_neutral(trial, verdict),
            None => verdict,
        }
    }

    /// Runs cross-vendor trials with their backends' known differences; skipped trials get
    /// `None`.
    pub fn run_neutral(
        &self,
        trials: &[crate::neutral::lower::NeutralTrial],
    ) -> Vec<Option<crate::neutral::lower::NeutralVerdict>> {
        trials
            .iter()
            .map(|t| t.skip.is_none().then(|| self.neutral_verdict(t)))
            .collect()
    }

    /// A verdict as the known-differences list of the trial's backend has it.
    pub fn apply_known(&self, trial: &Trial, verdict: Verdict) -> Verdict {
        match self.known.get(trial.backend.name()) {
            Some(known) => known.apply(trial, verdict),
            None => verdict,
        }
    }

    /// Runs many trials, each backend's in one batch (which an external backend sends in a few
    /// large messages), and applies known differences. Skipped trials get `None`.
    pub fn run_all(&self, trials: &[Trial]) -> Vec<Option<Verdict>> {
        let mut verdicts: Vec<Option<Verdict>> = vec![None; trials.len()];
        let mut by_backend: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (i, t) in trials.iter().enumerate() {
            if t.skip.is_none() {
                by_backend.entry(t.backend.name()).or_default().push(i);
            }
        }
        for indices in by_backend.values() {
            let images: Vec<_> = indices.iter().map(|&i| trials[i].images()).collect();
            let mut requests = Vec::new();
            let mut spans = Vec::new();
            for (&i, images) in indices.iter().zip(&images) {
                match trials[i].requests(images) {
                    Ok(r) => {
                        spans.push((i, requests.len(), r.len()));
                        requests.extend(r);
                    }
                    Err(v) => verdicts[i] = Some(v),
                }
            }
            let Some(&(first, ..)) = spans.first() else {
                continue;
            };
            let mut results = trials[first].backend.execute_batch(&requests).into_iter();
            for (i, _, len) in spans {
                let answers: Vec<_> = results.by_ref().take(len).collect();
                verdicts[i] = Some(self.apply_known(&trials[i], trials[i].judge(answers)));
            }
        }
        verdicts
    }
}

/// The external backends of a project file, and what to say about those left out.
pub struct ProjectBackends {
    pub configured: Vec<Configured>,
    /// Backends skipped because something they need is missing.
    pub skipped: Vec<String>,
}

/// Reads the project file at `file` (see [`config::locate`]). A missing file that was not named
/// explicitly means no external backends. Backends whose requirements are missing are set aside
/// with a message, or are an error when [`config::requirements_enforced`].
pub fn project_backends(
    file: &Path,
    explicit: bool,
    plc_conformance: &Path,
) -> Result<ProjectBackends, LoadErrors> {
    if !explicit && !file.exists() {
        return Ok(ProjectBackends {
            configured: Vec::new(),
            skipped: Vec::new(),
        });
    }
    let all = config::load(file, plc_conformance)?;
    let enforced = config::requirements_enforced();
    let mut configured = Vec::new();
    let mut skipped = Vec::new();
    let mut errors = Vec::new();
    for c in all {
        match c.missing() {
            None => configured.push(c),
            Some(why) if enforced => errors.push(crate::load::LoadError {
                file: c.location.file.clone(),
                line: Some(c.location.line),
                key: Some("requires".into()),
                kind: crate::load::LoadErrorKind::Invalid(format!(
                    "{why} ({} is set, so every configured backend must run)",
                    config::ENV_REQUIRE
                ))
                .into(),
            }),
            Some(why) => skipped.push(why),
        }
    }
    if errors.is_empty() {
        Ok(ProjectBackends {
            configured,
            skipped,
        })
    } else {
        Err(LoadErrors(errors))
    }
}
