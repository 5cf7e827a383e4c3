//! `run` and `diff`: plan, run and report, with the same report formats, saved runs and
//! baselines; `diff --against` judges one backend's trials against what another did.

use std::io::Write;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::backends::{prepare, project_root, start, Prepared};
use super::output::{self, Sink};
use super::{
    BackendArgs, Cli, CliError, DiffArgs, Format, Outcome, ReportArgs, RunArgs, EXIT_DIFFERENCES,
    EXIT_OK,
};
use crate::backend::Backend;
use crate::execute::{execute_all, Observation, Pace, Progress};
use crate::judge::Verdict;
use crate::plan::Trial;
use crate::report::baseline;
use crate::report::console;
use crate::report::document::{self, Collector};
use crate::report::json::{BackendInfo, RunInfo};
use crate::report::matrix_text;
use crate::report::progress::ProgressReporter;
use crate::report::text::Palette;
use crate::report::text_reporter::TextReporter;
use crate::report::{All, Event, Reporter};
use crate::runner::{self, Project};
use crate::session::{idle_backends, judged_against, RunOutcome};

pub(super) fn run(cli: &Cli, args: &RunArgs) -> Outcome {
    execute_command(
        cli,
        &args.backends,
        &args.report,
        args.format,
        args.show_recorded,
        args.probes.as_deref(),
    )
}

pub(super) fn diff(cli: &Cli, args: &DiffArgs) -> Outcome {
    if let Some(other) = &args.against {
        return against(cli, &args.backends, other);
    }
    let format = match args.format {
        Format::Text => Format::Matrix,
        f => f,
    };
    execute_command(cli, &args.backends, &args.report, format, false, None)
}

fn execute_command(
    cli: &Cli,
    backend_args: &BackendArgs,
    report: &ReportArgs,
    format: Format,
    show_recorded: bool,
    probes: Option<&str>,
) -> Outcome {
    for path in [&report.output, &report.save].into_iter().flatten() {
        output::check(path)?;
    }
    // The baseline is read before anything is written, so that `--save F --baseline F`
    // compares with the run saved before, not with this one.
    let before = match &report.baseline {
        Some(path) => Some(baseline::load(path)?),
        None => None,
    };
    let Prepared {
        project,
        file,
        backends,
    } = prepare(cli, backend_args)?;
    let mut trials = planned(&project, &backends, backend_args.filter.as_deref());
    if let Some(question) = probes {
        let cases = probe_cases(cli, &project, question)?;
        trials.retain(|t| cases.contains(t.case_id()));
    }
    if trials.is_empty() {
        return Err(CliError::input(
            "no trial matches (check --backend and --filter; `plc-conformance list` shows \
             what exists)",
        ));
    }
    let jobs = backend_args.jobs();
    let date = utc_now();
    let stop = crate::interrupt::stop_flag();
    let mut collector = Collector::default();
    let mut stopper = StopAtFailure { stop };
    let mut text = None;
    // Backends left out are a fact about this machine, not a result: stderr, whatever the format.
    if backend_args.backends.is_empty() && !cli.quiet {
        for skipped in &file.skipped {
            console::note(&format!("skipped: {skipped}"));
        }
    }
    if format == Format::Text {
        let sink = Sink::open(report.output.as_deref())?;
        let palette = if sink.is_stdout() {
            Palette::coloured()
        } else {
            Palette::plain()
        };
        text = Some(TextReporter::new(sink, palette, show_recorded).quiet(cli.quiet));
    }
    let started = std::time::Instant::now();
    let ran = {
        let mut reporters: Vec<&mut dyn Reporter> = vec![&mut collector];
        if let Some(text) = &mut text {
            reporters.push(text);
        }
        if backend_args.fail_fast {
            reporters.push(&mut stopper);
        }
        let mut all = All(reporters);
        // `--fail-fast` holds every chunk back until the one before is judged: a run that
        // executes faster than it reports would otherwise finish before the first failure
        // is seen.
        let pace = match backend_args.fail_fast {
            true => Pace::Judged,
            false => Pace::Ahead,
        };
        if cli.quiet {
            runner::run(&trials, jobs, stop, pace, &mut all)
        } else {
            let mut progress = ProgressReporter::new(&trials, &mut all);
            runner::run(&trials, jobs, stop, pace, &mut progress)
        }
    };
    if let Err(e) = ran {
        let path = report.output.as_deref().filter(|_| text.is_some());
        return Err(CliError::write(path, e));
    }
    if let Some(text) = text {
        text.into_inner().finish()?;
    }
    let (records, summary, interrupted) = collector.finish();
    let info = RunInfo {
        tool: format!("plc-conformance {}", env!("CARGO_PKG_VERSION")),
        commit: project_root(cli)
            .ok()
            .flatten()
            .and_then(|r| git_commit(&r)),
        date,
        backends: backends
            .iter()
            .map(|b| BackendInfo {
                name: b.name().to_string(),
                description: b.describe(),
                version: b.version(),
            })
            .collect(),
        interrupted,
        seconds: started.elapsed().as_secs_f64(),
    };
    if format != Format::Text {
        let coloured = report.output.is_none()
            && anstream::AutoStream::choice(&std::io::stdout()) != anstream::ColorChoice::Never;
        let rendered = document::render(
            format,
            &records,
            &summary,
            &info,
            coloured,
            text_width(report.output.is_none()),
        );
        output::write(report.output.as_deref(), &rendered)?;
    }
    for (name, known) in &project.known {
        if !known.ignored.is_empty() && !cli.quiet {
            console::note(&format!(
                "{} entr{} of {} (backend {name}) name cases not in this corpus and were not used",
                known.ignored.len(),
                if known.ignored.len() == 1 { "y" } else { "ies" },
                known.file.display()
            ));
        }
    }
    if let (Some(path), true) = (&report.save, interrupted) {
        console::note(&format!(
            "the run was interrupted; {} is left as it was",
            path.display()
        ));
    } else if let Some(path) = &report.save {
        let saved = document::render(
            Format::Json,
            &records,
            &summary,
            &info,
            false,
            matrix_text::DEFAULT_WIDTH,
        );
        output::write(Some(path), &saved)?;
    }
    // A backend the run was asked for that ran nothing passed nothing: that is no pass.
    let idle = if interrupted || backend_args.allow_empty {
        Vec::new()
    } else {
        let asked: Vec<&str> = if backend_args.backends.is_empty() {
            file.configured
                .iter()
                .filter(|c| !c.on_request)
                .map(|c| c.settings.name.as_str())
                .collect()
        } else {
            backends.iter().map(|b| b.name()).collect()
        };
        idle_backends(&trials, &asked, backend_args.filter.is_some())
    };
    let mut outcome = RunOutcome {
        records,
        summary,
        idle,
        baseline: None,
    };
    for (name, why) in &outcome.idle {
        console::status(&format!(
            "error: backend `{name}` ran no trial: {why} (--allow-empty accepts such a run)"
        ));
    }
    if let Some(before) = before {
        outcome.against(&before);
        report_baseline(report.baseline.as_deref(), &outcome);
    }
    Ok(outcome.exit_code())
}

/// The case ids that probe an open question (every question's when `question` is empty).
fn probe_cases(
    cli: &Cli,
    project: &Project,
    question: &str,
) -> Result<std::collections::BTreeSet<String>, CliError> {
    let Some(root) = super::backends::project_root(cli)? else {
        return Err(CliError::input(format!(
            "--probes: the open questions are a project's {}, and no project was found \
             (pass --root, or run inside a checkout)",
            crate::load::OPEN_QUESTIONS
        )));
    };
    let file = root.join(crate::load::OPEN_QUESTIONS);
    let questions = crate::load::load_open_questions(&file, &project.profiles, &project.corpus)?;
    let chosen: Vec<_> = questions
        .iter()
        .filter(|q| question.is_empty() || q.id == question)
        .collect();
    if chosen.is_empty() {
        let ids: Vec<&str> = questions.iter().map(|q| q.id.as_str()).collect();
        return Err(CliError::input(format!(
            "no open question `{question}` in {}; the questions are: {}",
            file.display(),
            ids.join(", ")
        )));
    }
    Ok(chosen
        .into_iter()
        .flat_map(|q| q.probes.iter().cloned())
        .collect())
}

/// Stops the run at the first failing trial (`--fail-fast`): no further batch starts.
struct StopAtFailure<'a> {
    stop: &'a AtomicBool,
}

impl Reporter for StopAtFailure<'_> {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        if let Event::TrialFinished { verdict, .. } = event {
            if verdict.is_failure() {
                self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        }
        Ok(())
    }
}

/// The project's commit when its folder is in a git repository (`git describe --always
/// --dirty`: the abbreviated hash, `-dirty` when files changed).
fn git_commit(root: &Path) -> Option<String> {
    let dir = if root.as_os_str().is_empty() {
        Path::new(".")
    } else {
        root
    };
    let out = std::process::Command::new("git")
        .args(["describe", "--always", "--dirty", "--abbrev=12"])
        .current_dir(dir)
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    (out.status.success() && !text.trim().is_empty()).then(|| text.trim().to_string())
}

/// The current time, UTC, as RFC 3339 (`2026-11-22T13:24:34Z`).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rest) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

/// The width text reports fit: the terminal's when writing to one, else `COLUMNS`, else
/// [`matrix_text::DEFAULT_WIDTH`].
fn text_width(to_stdout: bool) -> usize {
    if to_stdout {
        if let Some((terminal_size::Width(w), _)) = terminal_size::terminal_size() {
            return usize::from(w);
        }
    }
    std::env::var("COLUMNS")
        .ok()
        .and_then(|c| c.parse().ok())
        .filter(|&c: &usize| c >= 20)
        .unwrap_or(matrix_text::DEFAULT_WIDTH)
}

/// The planned trials whose names contain `filter`.
fn planned(project: &Project, backends: &[Arc<dyn Backend>], filter: Option<&str>) -> Vec<Trial> {
    project
        .plan(backends)
        .into_iter()
        .filter(|t| filter.is_none_or(|f| t.name().contains(f)))
        .collect()
}

/// The baseline comparison, on stderr beside the report.
fn report_baseline(path: Option<&Path>, outcome: &RunOutcome) {
    let Some(changes) = &outcome.baseline else {
        return;
    };
    console::status(&format!(
        "against {}: {} new, {} fixed, {} changed, {} unchanged difference(s)",
        path.map(|p| p.display().to_string()).unwrap_or_default(),
        changes.new.len(),
        changes.fixed.len(),
        changes.changed.len(),
        changes.unchanged
    ));
    for line in &changes.new {
        console::status(&format!("  new:     {line}"));
    }
    for line in &changes.fixed {
        console::status(&format!("  fixed:   {line}"));
    }
    for line in &changes.changed {
        console::status(&format!("  changed: {line}"));
    }
}

/// Two backends side by side: every trial both run, and where their outcomes differ, the
/// per-word diff of one against the other. Backends of different families share only the
/// cross-vendor cases, compared as answers.
fn against(cli: &Cli, args: &BackendArgs, other: &str) -> Outcome {
    let Prepared {
        mut project,
        file,
        backends,
    } = prepare(cli, args)?;
    let Some(a) = backends.first().cloned() else {
        return Err(CliError::input(
            "diff --against needs a --backend to compare",
        ));
    };
    let other_args = BackendArgs {
        backends: vec![other.to_string()],
        known_differences: Vec::new(),
        ..args.clone()
    };
    let Some(b) = start(&mut project, &file, &other_args)?.first().cloned() else {
        return Err(CliError::input(format!(
            "no backend `{other}` to compare with"
        )));
    };
    let filter = args.filter.as_deref();
    let trials_a = planned(&project, std::slice::from_ref(&a), filter);
    let trials_b = planned(&project, std::slice::from_ref(&b), None);
    let key = |t: &Trial| {
        (
            t.is_cross_vendor(),
            t.input.instruction.clone(),
            t.case_id().to_string(),
            t.check_name().to_string(),
            t.variant.clone(),
        )
    };
    let same_family = a.profile() == b.profile();
    let stop = crate::interrupt::stop_flag();
    // The questions both answer: A's trial and B's.
    let pairs: Vec<(&Trial, &Trial)> = (trials_a.iter().filter(|t| t.skip.is_none()))
        .filter_map(|ta| {
            let tb = if same_family {
                (trials_b.iter()).find(|t| t.skip.is_none() && key(t) == key(ta))
            } else {
                // Different families meet on the cross-vendor cases, through their own
                // lowerings.
                trials_b.iter().find(|t| {
                    t.skip.is_none()
                        && t.is_cross_vendor()
                        && ta.is_cross_vendor()
                        && t.case_id() == ta.case_id()
                })
            };
            tb.map(|tb| (ta, tb))
        })
        .collect();
    // A's side runs as any run does, batched per backend; B's trials are then judged against
    // what A did, and where A gives nothing to judge against, A's trial is reported with why.
    let asked: Vec<Trial> = pairs.iter().map(|(ta, _)| (*ta).clone()).collect();
    let indices: Vec<usize> = (0..asked.len()).collect();
    let jobs = args.jobs();
    let mut observed: Vec<Option<Vec<Observation>>> = (0..asked.len()).map(|_| None).collect();
    execute_all(&asked, &indices, jobs, stop, Pace::Ahead, |p| {
        if let Progress::Observed(i, observations, _) = p {
            observed[i] = Some(observations);
        }
        std::ops::ControlFlow::Continue(())
    });
    let mut paired: Vec<Trial> = Vec::new();
    let mut unpaired: Vec<(Trial, Verdict)> = Vec::new();
    // An interrupted run compares what it observed.
    for ((ta, tb), observations) in pairs.iter().zip(observed) {
        let Some(observations) = observations else {
            continue;
        };
        match judged_against(ta, &observations, tb) {
            Ok(t) => paired.push(t),
            Err(verdict) => unpaired.push(((*ta).clone(), verdict)),
        }
    }
    let compared = paired.len() + unpaired.len();
    if compared == 0 {
        return Err(CliError::input(format!(
            "{} and {} share no trial that both run",
            a.name(),
            b.name()
        )));
    }
    let mut text =
        TextReporter::new(Sink::open(None)?, Palette::coloured(), false).quiet(cli.quiet);
    let written = unpaired
        .iter()
        .enumerate()
        .try_for_each(|(index, (trial, verdict))| {
            text.event(&Event::TrialFinished {
                index,
                trial,
                verdict,
                elapsed: std::time::Duration::ZERO,
            })
        })
        .and_then(|()| runner::run(&paired, 1, stop, Pace::Ahead, &mut text));
    let summary = written.map_err(|e| CliError::write(None, e))?;
    let differing = summary.failed + unpaired.len();
    let mut out = text.into_inner();
    writeln!(
        out,
        "{} vs {}: {compared} trials compared, {differing} differ",
        a.name(),
        b.name()
    )
    .map_err(|e| out.error(e))?;
    out.finish()?;
    Ok(if differing == 0 {
        EXIT_OK
    } else {
        EXIT_DIFFERENCES
    })
}
