//! The corpus as libtest trials, for `cargo test` and `cargo nextest run`.
//!
//! One trial per (backend, instruction, case, variant) and per (backend, lowering, cross-vendor
//! case). `cargo test --test conformance -- habin` filters, `--list` lists, `--exact NAME` runs
//! one. A failing trial prints the vector's `file:line`, what ran and a word-by-word diff.
//!
//! Trials whose outcome is known when planning — skipped, `unspecified` (recorded only), listed
//! known differences — are marked ignored, so that `cargo test` and nextest count them as
//! skipped; `-- --include-ignored` runs them too (a recorded trial then shows what the backend
//! did, and a known difference that now conforms fails as a stale entry). A known difference run
//! alone by name, as `nextest --run-ignored all` runs it, fails with its difference: nextest
//! would show a trial that reports itself ignored as passed.
//!
//! The external backends of the project file run as extra trials, each started only when a
//! trial of it runs: `--list` starts none, and a process running one trial (as nextest does)
//! starts only that trial's backend. A backend started that way that cannot start fails its
//! `NAME::handshake` trial and every trial of it; one whose requirements are missing shows as
//! an ignored `NAME::setup` trial with the reason.
//!
//! A run never passes on nothing: a backend that is not set up (a profile the project does not
//! have, a known-differences file that does not load, a process started at once that refuses
//! the handshake) or that gets no trial to run makes the harness refuse to start, exit 2,
//! whatever filter libtest was given.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use libtest_mimic::{Arguments, Completion, Failed, Trial as Test};

use crate::backend::external::ExternalBackend;
use crate::backend::{Backend, Codec, Emulator};
use crate::judge::{Status, Verdict};
use crate::load::{load_project, locate_project};
use crate::model::project::{ExternalSettings, ProjectBackends};
use crate::plan::Trial;
use crate::project::{Paths, Project};
use crate::report::console;
use crate::report::text::{render, Palette};
use crate::session::{run_one, Asked, BackendSource, HelloCache, LazyStart, Session};

/// Names the file of [`Harness::hello_cache`] instead of the one the harness gives; empty, none.
const ENV_HELLO_CACHE: &str = "PLC_CONFORMANCE_HELLO_CACHE";

/// The corpus as libtest trials for a `harness = false` test of your own: an emulator written
/// in Rust implements [`crate::Emulator`], a library [`crate::Codec`], and gets one trial per
/// case it implements, with diffs and known differences, in process. Only the backends given
/// run: the built-in reference models too with [`Harness::with_builtin`].
///
/// ```no_run
/// # use std::sync::Arc;
/// # struct MyEmulator;
/// # impl plc_conformance::Emulator for MyEmulator {
/// #     fn name(&self) -> &str { "mine" }
/// #     fn profile(&self) -> &str { "mitsubishi-iqr" }
/// #     fn claims(&self, _: &str, _: &str) -> bool { true }
/// #     fn execute(&self, _: &plc_conformance::Request<'_>)
/// #         -> Result<plc_conformance::Outcome, plc_conformance::Unsupported> { unimplemented!() }
/// # }
/// use plc_conformance::Harness;
///
/// fn main() -> std::process::ExitCode {
///     Harness::embedded()                        // the corpus built into the crate
///         .emulator(MyEmulator, Some("my.known.yaml".into()))
///         .run()
/// }
/// ```
pub struct Harness {
    root: PathBuf,
    /// The plc-conformance binary, when the project file's backends take part.
    project_file: Option<PathBuf>,
    builtin: bool,
    extra: Vec<(Arc<dyn Backend>, Option<PathBuf>)>,
    /// Backends as the command line's `--backend` names them.
    asked: Vec<String>,
    hello_cache: Option<PathBuf>,
    /// How long one trial may take before it fails as hung.
    time_limit: Duration,
}

/// A trial's time limit unless [`Harness::time_limit`] says otherwise: a reference model takes
/// microseconds, a process backend has its own limit per case (5 s).
const TIME_LIMIT: Duration = Duration::from_secs(30);

impl Harness {
    /// The corpus and profiles under `root` (`vendors/`, `vectors/`).
    pub fn new(root: impl Into<PathBuf>) -> Self {
        Harness {
            root: root.into(),
            project_file: None,
            builtin: false,
            extra: Vec::new(),
            asked: Vec::new(),
            hello_cache: None,
            time_limit: TIME_LIMIT,
        }
    }

    /// How long one trial (both fills) may take before it fails as hung (30 s unless set): an
    /// in-process backend that never answers fails its trial, and the run goes on without
    /// waiting for it.
    pub fn time_limit(mut self, limit: Duration) -> Self {
        self.time_limit = limit;
        self
    }

    /// The corpus and profiles built into this crate: what a dependent checks an emulator or a
    /// codec against without a checkout of this repository (`--exact` narrows it to the file of
    /// the one trial named, as for a folder).
    ///
    /// ```no_run
    /// # use std::sync::Arc;
    /// # fn my_backend() -> Arc<dyn plc_conformance::Backend> { unimplemented!() }
    /// fn main() -> std::process::ExitCode {
    ///     plc_conformance::Harness::embedded()
    ///         .backend(my_backend(), Some("my.known.yaml".into()))
    ///         .run()
    /// }
    /// ```
    pub fn embedded() -> Self {
        Harness::new(crate::load::EMBEDDED)
    }

    /// Also runs the external backends of the project file under the root; `binary` is what
    /// their commands see as `$PLC_CONFORMANCE`.
    pub fn project_file(mut self, binary: &Path) -> Self {
        self.project_file = Some(binary.to_path_buf());
        self
    }

    /// Keeps the project file's backends' answers to `hello` in `file` between processes, so
    /// that listing the trials (`--list`, which nextest runs before every run) plans with them
    /// instead of starting every backend; a trial run alone starts its backend and fails if the
    /// answer changed since (see `docs/performance.md`, "Start-up of the test binary").
    /// `PLC_CONFORMANCE_HELLO_CACHE` names another file, or, empty, none.
    pub fn hello_cache(mut self, file: impl Into<PathBuf>) -> Self {
        self.hello_cache = Some(file.into());
        self
    }

    /// Also runs the ten built-in reference models (this repository's own test does): each
    /// vendor profile's cases against the model of its manual.
    pub fn with_builtin(mut self) -> Self {
        self.builtin = true;
        self
    }

    /// Adds a backend, with its known-differences file.
    pub fn backend(mut self, backend: Arc<dyn Backend>, known: Option<PathBuf>) -> Self {
        self.extra.push((backend, known));
        self
    }

    /// Adds an emulator written in Rust, run in process, with its known-differences file.
    pub fn emulator(self, emulator: impl Emulator + 'static, known: Option<PathBuf>) -> Self {
        self.backend(crate::emulator_backend(emulator), known)
    }

    /// Adds a codec written in Rust, run in process, with its known-differences file.
    pub fn codec(self, codec: impl Codec + 'static, known: Option<PathBuf>) -> Self {
        self.backend(crate::codec_backend(codec), known)
    }

    /// Adds a backend as the command line's `--backend` names it: `external:NAME=COMMAND` (a
    /// process speaking the protocol, started by `sh -c`, 5 s a case), a bench over a link
    /// (`slmp:...`, `modbus:...`), or a backend of the project file by name. The text is read by
    /// the code that reads the command line's, so a wrong one is refused the same way, before
    /// any trial runs.
    pub fn backend_spec(mut self, text: impl Into<String>) -> Self {
        self.asked.push(text.into());
        self
    }

    /// Whether a backend may run in a process of its own (a `--backend` text, the project
    /// file's backends): only then does the harness handle SIGINT and SIGTERM.
    pub(crate) fn may_start_processes(&self) -> bool {
        self.project_file.is_some() || !self.asked.is_empty()
    }

    /// Parses libtest's arguments, plans, runs and reports; the exit code libtest gives. A
    /// harness given a `--backend` text or the project file handles SIGINT and SIGTERM (its
    /// backend processes, in process groups of their own, are killed before it exits; with
    /// the `signals` feature, on by default); one whose backends all run in process leaves the
    /// test process's signals alone.
    pub fn run(self) -> ExitCode {
        let args = Arguments::from_args();
        // Ctrl-C reaches this process but not the backends in process groups of their own.
        if self.may_start_processes() {
            if let Err(e) = crate::interrupt::install(crate::interrupt::OnSignal::Exit) {
                console::warning(&format!("SIGINT and SIGTERM are not handled: {e}"));
            }
        } else {
            crate::interrupt::install_panic_hook(false);
        }
        match self.conclude(&args) {
            Ok(conclusion) => conclusion.exit_code(),
            Err(refused) => {
                for line in &refused.0 {
                    console::error(line);
                }
                ExitCode::from(2)
            }
        }
    }

    /// Plans, runs and reports under `args`: libtest's conclusion, or why the harness refuses
    /// to run at all (a corpus that does not load, a backend not set up or given no trial).
    pub(crate) fn conclude(self, args: &Arguments) -> Result<libtest_mimic::Conclusion, Refused> {
        let mut paths = Paths::under(&self.root);
        // A corpus cut down to one trial's file need not hold every case a known-differences
        // file names.
        let mut whole_corpus = true;
        if let Some(files) = exact_files(args, &paths) {
            paths.vectors = files;
            whole_corpus = false;
        }
        let project = match Project::load(&paths) {
            Ok(p) => p,
            Err(errors) => {
                return Err(Refused::one(format!("the corpus does not load:\n{errors}")))
            }
        };
        let mut tests = Vec::new();
        let mut sources = Vec::new();
        // The environment may name another file, or none (empty: every backend is started).
        let cache_file = match std::env::var_os(ENV_HELLO_CACHE) {
            Some(file) if file.is_empty() => None,
            Some(file) => Some(PathBuf::from(file)),
            None => self.hello_cache,
        };
        let mut cache = cache_file.as_deref().map(HelloCache::load);
        let mut by_settings = BTreeMap::new();
        if self.builtin {
            sources.push(BackendSource::References);
        }
        for (backend, known) in self.extra {
            sources.push(BackendSource::InProcess(backend, known));
        }
        let mut configured = ProjectBackends::default();
        if let Some(binary) = &self.project_file {
            let (file, explicit) = locate_project(&self.root);
            configured = match load_project(&file, explicit, binary) {
                Ok(p) => p,
                Err(errors) => {
                    return Err(Refused::one(format!(
                        "the project file does not load:\n{errors}"
                    )))
                }
            };
            for skipped in &configured.skipped {
                let name = format!("{}::setup", skipped.name);
                let why = skipped.to_string();
                tests.push(
                    Test::ignorable_test(name, move || Ok(Completion::ignored_with(why)))
                        .with_ignored_flag(true),
                );
            }
            // Backends run on request only (self-checks of the harness) have tests of their own.
            // One whose level (a profile, or codec) is declared is planned without starting it,
            // except when the trials are listed: nextest lists once, then runs each trial in a
            // process of its own and shows a trial that returns "ignored" as passed, so what a
            // backend declines is decided from its handshake when listing and marked ignored.
            // A trial run alone by name (`--exact`, as nextest runs one) starts its own backend
            // the same way, so that it is ignored or not as it was listed.
            let alone = args
                .exact
                .then(|| args.filter.as_deref().map(backend_of))
                .flatten();
            for c in configured
                .configured
                .iter()
                .filter(|c| !c.on_request)
                .cloned()
            {
                let declared = c.settings.profile.is_some() || c.settings.codec;
                let now = args.list || alone == Some(c.settings.name.as_str());
                // Listing plans a backend from its cached answer to `hello` when it has one.
                let planned = (args.list.then_some(cache.as_ref()).flatten())
                    .and_then(|cache| cache.get(&c.settings))
                    .and_then(|hello| {
                        ExternalBackend::planned(c.settings.clone(), hello, &project.profiles).ok()
                    });
                by_settings.insert(c.settings.name.clone(), c.settings.clone());
                sources.push(match planned {
                    Some(planned) => BackendSource::InProcess(
                        Arc::new(planned),
                        c.settings.known_differences.clone(),
                    ),
                    None if declared && !now => BackendSource::ProcessOnFirstUse(c.settings),
                    None => BackendSource::Process(c.settings),
                });
            }
        }
        if !self.asked.is_empty() {
            let binary = (self.project_file.clone())
                .or_else(|| std::env::current_exe().ok())
                .unwrap_or_default();
            let asked = Asked {
                texts: &self.asked,
                known_differences: &[],
                in_process: &[],
                file: &configured,
                timeout: crate::model::project::DEFAULT_TIMEOUT,
                max_faults: crate::model::project::DEFAULT_MAX_CONSECUTIVE_FAULTS,
                binary: &binary,
                references: false,
            };
            match asked.sources(&project) {
                Ok(chosen) => sources.extend(chosen.sources),
                Err(e) => return Err(Refused::one(crate::error_chain::chain(&e))),
            }
        }
        let (session, failed) = Session::assemble(project, sources, whole_corpus);
        // A backend that is not set up (its profile unknown, its known differences unreadable,
        // its process refusing the handshake) would check nothing: the harness refuses to
        // start, whatever filter would have left its failing trial out.
        if !failed.is_empty() {
            let mut lines: Vec<String> = (failed.iter())
                .map(|(name, error)| format!("{name}: {}", crate::error_chain::chain(error)))
                .collect();
            lines.push("no trial runs while a backend is not set up".into());
            return Err(Refused(lines));
        }
        // The built-in models are opt-in: a harness given no backend checks nothing.
        if session.backends.is_empty() && session.on_first_use.is_empty() {
            return Err(Refused::one(
                "no backend to check: give the harness one (`.emulator`, `.codec`, `.backend`, \
                 `.backend_spec`), or `.with_builtin()` for the reference models"
                    .into(),
            ));
        }
        let changed = match &mut cache {
            Some(cache) => remember(cache, &session, &by_settings, args.exact),
            None => BTreeMap::new(),
        };
        for lazy in &session.on_first_use {
            let handshake = lazy.clone();
            tests.push(Test::test(
                format!("{}::handshake", lazy.name()),
                move || {
                    handshake
                        .get()
                        .map(|_| ())
                        .map_err(|e| Failed::from(e.to_string()))
                },
            ));
        }
        let by_name: BTreeMap<String, Arc<LazyStart>> = (session.on_first_use.iter())
            .map(|l| (l.name().to_string(), l.clone()))
            .collect();
        let trials = session.plan(&session.backends);
        // A backend that gets no trial to run passes having checked nothing: refused, before
        // any filter (a corpus cut to one trial's file, as `--exact` reads it, may hold none of
        // another backend's).
        let idle = match whole_corpus {
            true => session.idle(&trials, false),
            false => Vec::new(),
        };
        if !idle.is_empty() {
            return Err(Refused(
                (idle.iter())
                    .map(|(name, why)| format!("backend `{name}` gets no trial to run: {why}"))
                    .collect(),
            ));
        }
        let shown = Shown::default();
        tests.extend(trials.into_iter().map(|t| {
            if let Some(why) = changed.get(t.backend.name()) {
                let why = why.clone();
                return Test::test(t.name(), move || Err(Failed::from(why)));
            }
            let lazy = by_name.get(t.backend.name()).cloned();
            test(t, lazy, args, self.time_limit, shown.clone())
        }));
        let conclusion = libtest_mimic::run(args, tests);
        // Started processes get their shutdown message before the harness exits.
        drop(by_name);
        drop(session);
        Ok(conclusion)
    }
}

/// Why the harness runs no trial at all, a line each: shown on stderr, exit status 2.
#[derive(Debug)]
pub(crate) struct Refused(pub Vec<String>);

impl Refused {
    fn one(line: String) -> Self {
        Refused(vec![line])
    }
}

/// Records the answers to `hello` of the processes the session started. Run alone (`exact`, as
/// nextest runs each trial after listing them), a backend whose answer differs from the one
/// cached under the same key fails its trials: the listing may have marked them by the old
/// answer. Returns why, by backend name.
fn remember(
    cache: &mut HelloCache,
    session: &Session,
    settings: &BTreeMap<String, ExternalSettings>,
    exact: bool,
) -> BTreeMap<String, String> {
    let mut changed = BTreeMap::new();
    for (name, hello) in &session.hellos {
        let Some(s) = settings.get(name) else {
            continue;
        };
        if let Some(old) = cache.put(s, hello).filter(|_| exact) {
            changed.insert(
                name.clone(),
                format!(
                    "the external backend `{name}` now answers hello differently from the answer \
                     cached in {}, which listing the trials planned with, so this trial may \
                     have been listed wrongly; the cache now holds the new answer: run again\n\
                     cached: {old}\nnow:    {}",
                    cache.path().display(),
                    String::from_utf8_lossy(hello)
                ),
            );
        }
    }
    if let Err(e) = cache.save() {
        console::warning(&format!(
            "the answers to hello are not kept in {}: {e}",
            cache.path().display()
        ));
    }
    changed
}

/// The backend of a trial's name: `backend::...`, `cross-vendor::backend::...` or
/// `protocol::backend::...`.
fn backend_of(name: &str) -> &str {
    let mut parts = name.split("::");
    match parts.next() {
        Some("cross-vendor" | "protocol") => parts.next().unwrap_or_default(),
        first => first.unwrap_or_default(),
    }
}

/// With `--exact NAME` (how nextest runs each trial in a process of its own), only the vector
/// files that can hold the trial's case are read: the case id is the name's last part but the
/// variant, and a file holds it if its text has `id: CASE`. `None` reads everything (no exact
/// name, or no file matches, so that libtest reports the name as unknown as usual).
fn exact_files(args: &Arguments, paths: &Paths) -> Option<Vec<std::path::PathBuf>> {
    if !args.exact {
        return None;
    }
    let name = args.filter.as_deref()?;
    let parts: Vec<&str> = name.split("::").collect();
    let case = parts.len().checked_sub(2).and_then(|i| parts.get(i))?;
    let needle = format!("id: {case}");
    let mut files = Vec::new();
    for dir in &paths.vectors {
        for file in crate::load::yaml_files(dir).ok()? {
            // A file shipped in the binary reads as one on disk does.
            let text = crate::load::read_file(&file).ok()?;
            let holds = text.match_indices(&needle).any(|(at, _)| {
                text[at + needle.len()..]
                    .chars()
                    .next()
                    .is_none_or(|c| c.is_whitespace() || c == ',' || c == '}')
            });
            if holds {
                files.push(file);
            }
        }
    }
    (!files.is_empty()).then_some(files)
}

/// One planned trial as a libtest trial; `lazy` starts its backend when the backend is only
/// planned so far; `exact` when the trial runs alone (`--exact`, as under nextest).
/// A trial as a libtest test. A trial recorded rather than judged (an `unspecified` case, a
/// listed known difference) is flagged ignored where libtest's flag is what a reader or a
/// runner sees — listing (nextest lists, then runs each trial by name), a trial run by exact
/// name, `--ignored` — and otherwise runs and reports itself ignored with its reason (what the
/// backend did, or the entry), which a flagged trial, never run, could not give.
fn test(
    trial: Trial,
    lazy: Option<Arc<LazyStart>>,
    args: &Arguments,
    limit: Duration,
    shown: Shown,
) -> Test {
    let name = trial.name();
    let flagged = args.list || args.exact || args.ignored || args.include_ignored;
    let ignored = flagged && trial.ignored_because().is_some();
    let exact = args.exact;
    Test::ignorable_test(name, move || outcome(trial, lazy, exact, limit, &shown))
        .with_ignored_flag(ignored)
}

/// The differences already reported in full, each with the trial that reported it. A case runs
/// on every variant of its profile and in every call form (HABIN, HABINP), and a backend that
/// gets it wrong usually gets it wrong the same way in each: its report is shown once, and each
/// other trial with the same difference says which trial shows it (its own verdict stays a
/// failure).
#[derive(Clone, Default)]
struct Shown(Arc<std::sync::Mutex<BTreeMap<String, String>>>);

impl Shown {
    /// The trial that already shows this trial's difference, or `None` (and this trial is
    /// recorded as showing it) when it is the first.
    fn first_with(&self, trial: &Trial, verdict: &Verdict) -> Option<String> {
        let Verdict::Differs { difference } = verdict else {
            return None;
        };
        let key = format!(
            "{}\u{0}{}\u{0}{difference:?}",
            trial.backend.name(),
            trial.case_id()
        );
        let mut shown = match self.0.lock() {
            Ok(shown) => shown,
            Err(poisoned) => poisoned.into_inner(),
        };
        match shown.get(&key) {
            Some(first) => Some(first.clone()),
            None => {
                shown.insert(key, trial.name());
                None
            }
        }
    }
}

/// Runs a trial on a thread of its own and waits at most `limit` for its verdict: a backend
/// that never answers cannot be stopped in process, so its trial fails and its thread is left
/// behind; one that panics fails with the panic's message.
fn run_within(trial: Trial, limit: Duration) -> Result<(Trial, Verdict), Failed> {
    let (sender, receiver) = std::sync::mpsc::channel();
    let worker = std::thread::Builder::new()
        .name(trial.name())
        .spawn(move || {
            let verdict = run_one(&trial);
            let _ = sender.send((trial, verdict));
        })
        .map_err(|e| Failed::from(format!("no thread for the trial: {e}")))?;
    match receiver.recv_timeout(limit) {
        Ok(done) => Ok(done),
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => Err(Failed::from(format!(
            "the backend did not answer within {} s (Harness::time_limit): the trial is taken \
             as hung and left behind",
            limit.as_secs_f64()
        ))),
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            let why = match worker.join() {
                Err(panic) => crate::backend::panic_message(panic.as_ref())
                    .unwrap_or_else(|| "a panic without a message".into()),
                Ok(()) => "the trial's thread ended without a verdict".into(),
            };
            Err(Failed::from(format!("the backend panicked: {why}")))
        }
    }
}

/// Runs a trial and maps its verdict onto libtest: a pass, an ignored trial with its reason, or
/// a failure with the full report.
fn outcome(
    mut trial: Trial,
    lazy: Option<Arc<LazyStart>>,
    exact: bool,
    limit: Duration,
    shown: &Shown,
) -> Result<Completion, Failed> {
    if let Some(lazy) = lazy {
        lazy.bind(&mut trial)
            .map_err(|e| Failed::from(e.to_string()))?;
    }
    let (trial, verdict) = run_within(trial, limit)?;
    match verdict.status() {
        Status::Pass => Ok(Completion::Completed),
        Status::Fail => Err(Failed::from(match shown.first_with(&trial, &verdict) {
            Some(first) => format!(
                "the same difference as {first}, whose report shows it in full (case {}, {})",
                trial.case_id(),
                trial.location()
            ),
            None => render(&trial, &verdict, Palette::plain()),
        })),
        // Run alone (`--exact`, as nextest runs a trial), a trial skipped only now would show as
        // passed: listing marks such trials ignored, so reaching one here means it was asked for
        // by name, and it fails rather than pass without running.
        Status::Skipped if exact => Err(Failed::from(format!(
            "not run: {}; the listing marks this trial ignored",
            ignored_text(&verdict)
        ))),
        // Nor does a known difference pass when run alone (`nextest --run-ignored all` runs it
        // by name): it is the difference it is, shown with its entry.
        Status::Ignored if exact => match &verdict {
            Verdict::KnownDifference { difference, .. } => Err(Failed::from(format!(
                "{}; run alone it still differs:\n{}",
                ignored_text(&verdict),
                render(&trial, difference, Palette::plain())
            ))),
            _ => Ok(Completion::ignored_with(ignored_text(&verdict))),
        },
        Status::Skipped | Status::Ignored => Ok(Completion::ignored_with(ignored_text(&verdict))),
    }
}

fn ignored_text(verdict: &Verdict) -> String {
    match verdict {
        Verdict::Recorded {
            observed,
            fill_dependent,
        } => format!(
            "unspecified, recorded: {observed}{}",
            if *fill_dependent {
                " (depends on the fill)"
            } else {
                ""
            }
        ),
        Verdict::KnownDifference { entry, .. } => {
            format!("known difference ({}): {}", entry.location, entry.reason)
        }
        other => match other.not_run() {
            Some(reason) => reason.to_string(),
            None => other.label().to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--exact` with one trial's name reads only the file that holds its case, in the corpus
    /// built into the crate as in a folder.
    #[test]
    fn exact_narrows_the_embedded_corpus_to_the_case_s_file() {
        let args = Arguments::from_iter([
            "test",
            "--exact",
            "iqr::habin::habin-fixed-4-digits-example::rcpu",
        ]);
        let files = exact_files(&args, &Paths::under(Path::new(crate::load::EMBEDDED)));
        assert_eq!(
            files,
            Some(vec![PathBuf::from(
                "<embedded>/vectors/mitsubishi-iqr/habin.yaml"
            )])
        );
        let all = Arguments::from_iter(["test", "habin-fixed-4-digits-example"]);
        assert_eq!(exact_files(&all, &Paths::embedded()), None, "not --exact");
    }

    /// An emulator's or codec's own `cargo test` keeps its signals: only a harness that may
    /// start a backend process (a `--backend` text, the project file) handles them.
    #[test]
    fn only_a_harness_that_may_start_processes_handles_signals() {
        let model =
            crate::test_support::reference(&crate::test_support::session(), "mitsubishi-fx5");
        let in_process = Harness::embedded().backend(model, None);
        assert!(!in_process.may_start_processes());
        assert!(
            !Harness::embedded().may_start_processes(),
            "the built-in models"
        );
        let asked = Harness::embedded().backend_spec("external:emu=./emu");
        assert!(asked.may_start_processes());
        let configured = Harness::embedded().project_file(Path::new("plc-conformance"));
        assert!(configured.may_start_processes());
    }
}
