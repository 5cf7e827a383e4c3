//! The backends a command or a harness asks for, read once: a `--backend` text (a reference
//! model's name, a project file's backend, a backend in this process, `external:NAME=COMMAND`,
//! or a bench over a link, `slmp:...` / `modbus:...`) becomes a [`BackendSource`] here and
//! nowhere else, so the command line and [`crate::Harness`] cannot read the same text two ways.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use super::{BackendSource, SetupError};
use crate::backend::{reference_backends, Backend};
use crate::load::{valid_name, ENV_SELF};
use crate::model::project::{ExternalSettings, Launch, ProjectBackends};
use crate::project::Project;

/// What is asked for, before anything is set up.
pub(crate) struct Asked<'a> {
    /// The backend texts, in the order given; none: the reference models and the project file's
    /// backends (but those run on request).
    pub texts: &'a [String],
    /// `NAME=FILE`: a known-differences file for an `external:` or in-process backend given.
    pub known_differences: &'a [String],
    /// The backends of this process (an emulator or codec written in Rust) that a text may name.
    pub in_process: &'a [Arc<dyn Backend>],
    /// The project file's backends.
    pub file: &'a ProjectBackends,
    /// How long an `external:` backend given here may take on one case.
    pub timeout: Duration,
    /// Faults in a row after which an `external:` backend given here is not asked any more.
    pub max_faults: usize,
    /// The binary that `external:` backends see as `$PLC_CONFORMANCE`.
    pub binary: &'a Path,
    /// The reference models first, always (a sweep's oracle), the names given among them not
    /// again.
    pub references: bool,
}

/// The sources of what was asked, in order, and the names of the backends given.
pub(crate) struct Chosen {
    pub sources: Vec<BackendSource>,
    pub names: Vec<String>,
}

/// A backend text read on its own: what it names before the session is asked about it.
#[allow(clippy::large_enum_variant)] // one per text, read once: not worth a box
enum Spec {
    External(ExternalSettings),
    Bench(crate::backend::bench::BenchSettings),
    Named(String),
}

impl Spec {
    fn parse(text: &str, asked: &Asked<'_>, project: &Project) -> Result<Spec, SetupError> {
        if let Some(settings) =
            crate::backend::bench_settings(text, Path::new("."), &project.profiles)
                .map_err(SetupError::Spec)?
        {
            return Ok(Spec::Bench(settings));
        }
        let Some(rest) = text.strip_prefix("external:") else {
            return Ok(Spec::Named(text.to_string()));
        };
        let Some((name, command)) = rest.split_once('=') else {
            return Err(SetupError::Asked(format!(
                "`{text}`: expected `external:NAME=COMMAND`, e.g. `external:my-emu=./my-emu --serve`"
            )));
        };
        if !valid_name(name) {
            return Err(SetupError::Asked(format!(
                "`{name}` is not a backend name: use lowercase letters, digits, `-` and `_`"
            )));
        }
        if command.trim().is_empty() {
            return Err(SetupError::Asked(format!(
                "external backend `{name}` has an empty command"
            )));
        }
        let seconds = asked.timeout.as_secs_f64();
        if !(seconds > 0.0 && seconds <= 86_400.0) {
            return Err(SetupError::Asked(format!(
                "--timeout {seconds}: give seconds above 0 and at most a day"
            )));
        }
        if asked.max_faults == 0 {
            return Err(SetupError::Asked("--max-faults 0: give at least 1".into()));
        }
        let mut settings = ExternalSettings::new(name, Launch::Shell(command.to_string()));
        settings.timeout = asked.timeout;
        settings.max_consecutive_faults = asked.max_faults;
        settings.env = vec![(ENV_SELF.into(), asked.binary.display().to_string())];
        Ok(Spec::External(settings))
    }
}

impl Asked<'_> {
    /// The sources of what is asked in `project`, in the order given, or why one cannot be had.
    pub(crate) fn sources(&self, project: &Project) -> Result<Chosen, SetupError> {
        let asked = self;
        let mut known_files: BTreeMap<&str, PathBuf> = BTreeMap::new();
        for entry in asked.known_differences {
            let Some((name, path)) = entry.split_once('=') else {
                return Err(SetupError::Asked(format!(
                    "--known-differences `{entry}`: expected NAME=FILE"
                )));
            };
            known_files.insert(name, PathBuf::from(path));
        }
        let file = asked.file;
        let models: Vec<String> = (reference_backends(&project.profiles).iter())
            .map(|b| b.name().to_string())
            .collect();
        let mut sources = Vec::new();
        let mut names = Vec::new();
        if asked.references || asked.texts.is_empty() {
            sources.push(BackendSource::References);
        }
        if asked.texts.is_empty() {
            for c in file.configured.iter().filter(|c| !c.on_request) {
                sources.push(BackendSource::Process(c.settings.clone()));
            }
        }
        for text in asked.texts {
            let name = match Spec::parse(text, asked, project)? {
                Spec::Bench(settings) => {
                    names.push(settings.name.clone());
                    sources.push(BackendSource::Bench(Box::new(settings)));
                    continue;
                }
                Spec::External(mut settings) => {
                    settings.known_differences = known_files.remove(settings.name.as_str());
                    names.push(settings.name.clone());
                    sources.push(BackendSource::Process(settings));
                    continue;
                }
                Spec::Named(name) => name,
            };
            if let Some(b) = asked.in_process.iter().find(|b| b.name() == name) {
                let known = known_files.remove(name.as_str());
                sources.push(BackendSource::InProcess(b.clone(), known));
            } else if models.contains(&name) {
                if !asked.references {
                    sources.push(BackendSource::Reference(name.clone()));
                }
            } else if let Some(c) = file.configured.iter().find(|c| c.settings.name == name) {
                sources.push(BackendSource::Process(c.settings.clone()));
            } else if let Some(skipped) = file.skipped.iter().find(|s| s.name == name) {
                return Err(SetupError::Asked(skipped.to_string()));
            } else {
                let mut known: Vec<&str> = models.iter().map(String::as_str).collect();
                known.extend(asked.in_process.iter().map(|b| b.name()));
                known.extend(file.configured.iter().map(|c| c.settings.name.as_str()));
                return Err(SetupError::Asked(format!(
                    "unknown backend `{name}`; expected one of: {}, external:NAME=COMMAND, {}",
                    known.join(", "),
                    crate::backend::BENCH_FORMS
                )));
            }
            names.push(name);
        }
        if let Some(name) = known_files.keys().next() {
            return Err(SetupError::Asked(format!(
                "--known-differences names `{name}`, which is not an `external:` or in-process \
                 backend of this run"
            )));
        }
        Ok(Chosen { sources, names })
    }
}
