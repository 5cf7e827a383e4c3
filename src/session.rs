//! What a run is made of, put together once for every way of running: the command line's
//! `run`, `diff`, `sweep` and `record`, and the libtest trials of `cargo test`.
//!
//! A backend comes from a [`BackendSource`]: a built-in reference model, a process speaking the
//! protocol (started now, or on the first trial that needs it), or a backend in this process
//! (an emulator or a codec written in Rust). [`assemble`] turns the sources into backends with
//! their known differences loaded into the project, and says which could not be set up. A new
//! kind of transport (a network connection to a CPU, say) is one more variant here and one
//! file of its own under `backend/`.
//!
//! [`RunOutcome`] is what a run ends with: its records and counts, the backends that ran
//! nothing, the changes against a baseline, and the exit status they make together.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use crate::backend::external::{ExternalBackend, ExternalError};
use crate::backend::slmp::{SlmpBackend, SlmpSettings};
use crate::backend::{Backend, Fault, Request, Response};
use crate::execute::Observation;
use crate::judge::lift::lift;
use crate::judge::{Effect, Verdict};
use crate::model::cross_vendor::CrossVendorCase;
use crate::model::cross_vendor::{CodecAbilities, OperationAbilities};
use crate::model::profile::Profiles;
use crate::model::project::ExternalSettings;
use crate::model::{Basis, Case, Citation, Expectation};
use crate::plan::{Check, Trial};
use crate::report::baseline::{self, SavedRun};
use crate::report::record::Record;
use crate::report::Summary;
use crate::runner::{check_name, Project, SetupError};

/// Where a backend comes from.
pub(crate) enum BackendSource {
    /// Every built-in reference model whose profile is loaded.
    References,
    /// A process speaking the protocol, started now (its handshake says what it implements).
    Process(ExternalSettings),
    /// A process speaking the protocol whose profile or codec level is declared: planned now,
    /// started by the first trial that runs it, so that listing or running one trial of another
    /// backend starts nothing.
    ProcessOnFirstUse(ExternalSettings),
    /// A backend in this process, with its known-differences file.
    InProcess(Arc<dyn Backend>, Option<PathBuf>),
    /// A live CPU over SLMP (`backend::slmp`): built without a socket, then connected and its
    /// read-only interlocks run, so that a bench that is not ready is an error before any case
    /// and before any write.
    Slmp(Box<SlmpSettings>),
}

/// The backends of a run, in the order of their sources.
#[derive(Default)]
pub(crate) struct Assembled {
    pub backends: Vec<Arc<dyn Backend>>,
    /// The sources that could not be set up, by backend name.
    pub failed: Vec<(String, SetupError)>,
    /// The backends started on first use: their trials start them through these.
    pub on_first_use: Vec<Arc<LazyStart>>,
}

/// Sets up every source: reference models as they are, processes started (or prepared to start
/// on first use), known-differences files loaded into `project.known`. `strict_known` makes a
/// known-differences entry for a case outside the corpus an error (see [`load_known`]).
pub(crate) fn assemble(
    project: &mut Project,
    sources: Vec<BackendSource>,
    strict_known: bool,
) -> Assembled {
    let mut out = Assembled::default();
    for source in sources {
        let name = source.name();
        if !matches!(source, BackendSource::References) {
            if let Err(e) = check_name(&name, &out.backends) {
                out.failed.push((name, e));
                continue;
            }
        }
        match source {
            BackendSource::References => out.backends.extend(project.backends.clone()),
            BackendSource::Process(settings) => {
                match project.add_external(settings, strict_known) {
                    Ok(b) => out.backends.push(b),
                    Err(e) => out.failed.push((name, e)),
                }
            }
            BackendSource::ProcessOnFirstUse(settings) => {
                let profile = settings.profile.clone();
                if let Some(file) = &settings.known_differences {
                    let p = profile.as_deref().unwrap_or("");
                    if let Err(e) = project.add_known(&name, p, file, strict_known) {
                        out.failed.push((name, e));
                        continue;
                    }
                }
                let lazy = Arc::new(LazyStart {
                    settings,
                    profiles: project.profiles.clone(),
                    started: OnceLock::new(),
                });
                out.backends
                    .push(Arc::new(Placeholder::new(name, profile, lazy.clone())));
                out.on_first_use.push(lazy);
            }
            BackendSource::Slmp(settings) => {
                let live = SlmpBackend::new(*settings, &project.profiles)
                    .and_then(|b| b.connect().map(|()| b));
                match live {
                    Ok(b) => out.backends.push(Arc::new(b)),
                    Err(source) => out.failed.push((
                        name.clone(),
                        SetupError::Live {
                            backend: name,
                            source,
                        },
                    )),
                }
            }
            BackendSource::InProcess(backend, known) => {
                if let Some(file) = known {
                    if let Err(e) = project.add_known(&name, backend.profile(), &file, strict_known)
                    {
                        out.failed.push((name, e));
                        continue;
                    }
                }
                out.backends.push(backend);
            }
        }
    }
    out
}

impl BackendSource {
    /// The backend's name (empty for the set of reference models).
    pub(crate) fn name(&self) -> String {
        match self {
            BackendSource::References => String::new(),
            BackendSource::Process(s) | BackendSource::ProcessOnFirstUse(s) => s.name.clone(),
            BackendSource::InProcess(b, _) => b.name().to_string(),
            BackendSource::Slmp(s) => s.name.clone(),
        }
    }
}

/// An external backend started on first use, once per process.
pub(crate) struct LazyStart {
    settings: ExternalSettings,
    profiles: Profiles,
    started: OnceLock<Result<Arc<dyn Backend>, Arc<ExternalError>>>,
}

impl LazyStart {
    pub(crate) fn name(&self) -> &str {
        &self.settings.name
    }

    /// The started backend, starting it the first time.
    pub(crate) fn get(&self) -> Result<Arc<dyn Backend>, Arc<ExternalError>> {
        self.started
            .get_or_init(|| {
                ExternalBackend::start(self.settings.clone(), &self.profiles)
                    .map(|b| Arc::new(b) as Arc<dyn Backend>)
                    .map_err(Arc::new)
            })
            .clone()
    }

    /// Makes a planned trial of the placeholder a trial of the started backend, with the
    /// started backend's own skip decision.
    pub(crate) fn bind(&self, trial: &mut Trial) -> Result<(), Arc<ExternalError>> {
        let real = self.get()?;
        trial.skip = crate::plan::skip_reason(trial, real.as_ref());
        trial.backend = real;
        Ok(())
    }
}

/// Stands in for a backend started on first use while planning: it claims everything its
/// profile has, and each trial asks the started backend ([`LazyStart::bind`]) before running.
struct Placeholder {
    name: String,
    profile: String,
    /// For a codec-level backend.
    codec: Option<CodecAbilities>,
    lazy: Arc<LazyStart>,
}

impl Placeholder {
    fn new(name: String, profile: Option<String>, lazy: Arc<LazyStart>) -> Self {
        Placeholder {
            name,
            // Planned as able to answer anything; the started backend's own capabilities
            // decide each trial's skip before it runs.
            codec: profile.is_none().then(|| {
                let any = OperationAbilities {
                    digits: Some((0..=16).collect()),
                    width: 64,
                    reading: None,
                    shape: Default::default(),
                };
                CodecAbilities {
                    hex_to_value: Some(any.clone()),
                    value_to_hex: Some(any),
                }
            }),
            profile: profile.unwrap_or_default(),
            lazy,
        }
    }
}

impl Backend for Placeholder {
    fn name(&self) -> &str {
        &self.name
    }
    fn profile(&self) -> &str {
        &self.profile
    }
    fn describe(&self) -> String {
        format!(
            "external, started on first use ({})",
            self.lazy.settings.launch
        )
    }
    fn claims(&self, _instruction: &str, _variant: &str) -> bool {
        true
    }
    fn execute(&self, _request: &Request<'_>) -> Result<Response, Fault> {
        Err(Fault::Unreachable("the backend was not started".into()))
    }
    fn codec(&self) -> Option<&CodecAbilities> {
        self.codec.as_ref()
    }
}

/// What a run ends with.
pub(crate) struct RunOutcome {
    pub records: Vec<Record>,
    pub summary: Summary,
    /// Backends the run was asked for that ran no trial, with why: they passed nothing.
    pub idle: Vec<(String, String)>,
    /// The comparison with a baseline, when one was given.
    pub baseline: Option<BaselineChanges>,
}

/// Counts of a baseline comparison, and one line per changed trial.
pub(crate) struct BaselineChanges {
    pub new: Vec<String>,
    pub fixed: Vec<String>,
    pub changed: Vec<String>,
    pub unchanged: usize,
}

impl RunOutcome {
    /// Compares the run with a saved one.
    pub(crate) fn against(&mut self, before: &SavedRun) {
        let changes = baseline::compare(&before.records, &self.records);
        self.baseline = Some(BaselineChanges {
            new: changes
                .new
                .iter()
                .map(|r| format!("{} ({}: {})", r.trial, r.label, r.shown))
                .collect(),
            fixed: changes
                .fixed
                .iter()
                .map(|(was, now)| format!("{} (was {}: {})", now.trial, was.label, was.shown))
                .collect(),
            changed: changes
                .changed
                .iter()
                .map(|(was, now)| format!("{} ({} -> {})", now.trial, was.shown, now.shown))
                .collect(),
            unchanged: changes.unchanged,
        });
    }

    /// 0 when everything asked of the run conforms, 1 otherwise: with a baseline, a new
    /// failure; without one, any failure; and always a backend that ran nothing.
    pub(crate) fn exit_code(&self) -> u8 {
        let differs = match &self.baseline {
            Some(b) => !b.new.is_empty(),
            None => self.summary.failed > 0,
        };
        u8::from(differs || !self.idle.is_empty())
    }
}

/// The backends among `asked` that ran no trial, with why: every trial of theirs skipped (the
/// most frequent reason is given), or, when no filter narrows the run, no trial at all.
pub(crate) fn idle_backends(
    trials: &[Trial],
    asked: &[&str],
    filtered: bool,
) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for name in asked {
        let theirs: Vec<&Trial> = trials
            .iter()
            .filter(|t| t.backend.name() == *name)
            .collect();
        if theirs.iter().any(|t| t.skip.is_none()) {
            continue;
        }
        if theirs.is_empty() {
            if !filtered {
                out.push((name.to_string(), "the corpus has no trial for it".into()));
            }
            continue;
        }
        let mut reasons: std::collections::BTreeMap<&str, usize> = Default::default();
        for t in &theirs {
            *reasons.entry(t.skip.as_deref().unwrap_or("")).or_default() += 1;
        }
        let (reason, _) = reasons
            .iter()
            .max_by_key(|(_, n)| **n)
            .map_or(("", &0), |(r, n)| (*r, n));
        out.push((
            name.to_string(),
            format!("all {} of its trials were skipped ({reason})", theirs.len()),
        ));
    }
    out
}

/// The second backend's trial with the first backend's answer as its expectation (`diff
/// --against`): judging it says where the second parts from the first, with the same diffs,
/// faults and reports as a run against the corpus. `Err` is the verdict on the first backend's
/// trial when it gives nothing to judge against: a fault, an unsupported answer, or an outcome
/// that depends on the fill.
pub(crate) fn judged_against(
    first: &Trial,
    did: &[Observation],
    second: &Trial,
) -> Result<Trial, Verdict> {
    let name = first.backend.name();
    let mut answers = Vec::new();
    let mut effects = Vec::new();
    for o in did {
        match &o.result {
            Err(fault) => {
                return Err(Verdict::Fault {
                    fill: o.fill,
                    fault: fault.clone(),
                })
            }
            Ok(Response::Unsupported(reason)) => {
                return Err(Verdict::Unsupported {
                    reason: reason.clone(),
                })
            }
            Ok(Response::Answer(a)) => answers.push(a.clone()),
            Ok(Response::Done(outcome)) => match (&first.check, &first.profile) {
                (Check::CrossVendor { lowering, case }, Some(profile)) => answers.push(lift(
                    profile,
                    lowering,
                    case.digits,
                    outcome,
                    &first.image(o.fill),
                )),
                _ => effects.push(Effect::of(&first.image(o.fill), outcome)),
            },
        }
    }
    let fill_dependent = |what: String| Verdict::Unsupported {
        reason: format!("{name}'s outcome depends on the fill ({what}): nothing to judge against"),
    };
    let citation = Citation {
        manual: format!("backend {name}"),
        page: String::new(),
        text: Some("its outcome on this trial".into()),
    };
    let check = match (&second.check, effects.as_slice(), answers.as_slice()) {
        (Check::Native { instruction, case }, [e, rest @ ..], []) => {
            if let Some(other) = rest.iter().find(|x| *x != e) {
                return Err(fill_dependent(format!("{e} / {other}")));
            }
            Check::Native {
                instruction: instruction.clone(),
                case: Arc::new(Case {
                    basis: Basis::Observed,
                    citation,
                    expect: Some(Expectation {
                        after: e.changed.clone(),
                        error: e.error.clone(),
                    }),
                    ..(**case).clone()
                }),
            }
        }
        (Check::CrossVendor { case, .. } | Check::Codec { case }, [], [a, rest @ ..]) => {
            if let Some(other) = rest.iter().find(|x| *x != a) {
                return Err(fill_dependent(format!("{a} / {other}")));
            }
            let case = Arc::new(CrossVendorCase {
                basis: Basis::Observed,
                citation,
                expect: Some(a.clone()),
                except: Default::default(),
                ..(**case).clone()
            });
            match &second.check {
                Check::CrossVendor { lowering, .. } => Check::CrossVendor {
                    lowering: lowering.clone(),
                    case,
                },
                _ => Check::Codec { case },
            }
        }
        _ => {
            return Err(Verdict::Unsupported {
                reason: format!(
                    "{name} answered another kind of question than {} asks",
                    second.backend.name()
                ),
            })
        }
    };
    Ok(Trial {
        check,
        known: None,
        ..second.clone()
    })
}
