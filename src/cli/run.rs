//! `run` and `diff`: plan, run and report, with the same report formats, saved runs and
//! baselines; `diff --against` judges one backend's trials against what another did.

use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use super::backends::{prepare, project_root, start, Prepared};
use super::output::{self, Sink};
use super::{
    BackendArgs, Cli, CliError, DiffArgs, Format, Outcome, ReportArgs, RunArgs, EXIT_DIFFERENCES,
    EXIT_OK,
};
use crate::backend::Backend;
use crate::plan::Trial;
use crate::report::baseline;
use crate::report::console;
use crate::report::document;
use crate::report::json::{BackendInfo, RunInfo};
use crate::report::matrix_text;
use crate::report::progress::ProgressReporter;
use crate::report::text::Palette;
use crate::report::text_reporter::TextReporter;
use crate::report::{All, Event, Reporter, Stopped};
use crate::session::{Against, RunOptions, RunOutcome, Session};

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
        session,
        file,
        backends,
    } = prepare(cli, backend_args)?;
    let mut trials = planned(&session, &backends, backend_args.filter.as_deref());
    if let Some(question) = probes {
        let cases = probe_cases(cli, &session, question)?;
        trials.retain(|t| cases.contains(t.case_id()));
    }
    if trials.is_empty() {
        return Err(CliError::input(
            "no trial matches (check --backend and --filter; `plc-conformance list` shows \
             what exists)",
        ));
    }
    let date = crate::clock::utc_now();
    // Backends left out are a fact about this machine, not a result: stderr, whatever the format.
    if backend_args.backends.is_empty() && !cli.quiet {
        for skipped in &file.skipped {
            console::note(&format!("skipped: {skipped}"));
        }
    }
    let options = RunOptions {
        jobs: backend_args.jobs(),
        fail_fast: backend_args.fail_fast,
        filtered: backend_args.filter.is_some(),
        allow_empty: backend_args.allow_empty,
    };
    let mut outcome = run_reported(
        cli,
        &session,
        &trials,
        &options,
        report,
        format,
        show_recorded,
    )?;
    let info = run_info(cli, &backends, date, &outcome);
    write_documents(report, format, &outcome, &info)?;
    notes(cli, &session, &outcome);
    if let Some(before) = before {
        outcome.against(&before);
        report_baseline(report.baseline.as_deref(), &outcome);
    }
    Ok(outcome.exit_code())
}

/// Runs the trials with the text report (when the format is text) and, unless quiet, the live
/// progress lines.
fn run_reported(
    cli: &Cli,
    session: &Session,
    trials: &[Trial],
    options: &RunOptions,
    report: &ReportArgs,
    format: Format,
    show_recorded: bool,
) -> Result<RunOutcome, CliError> {
    let mut text = None;
    if format == Format::Text {
        let sink = Sink::open(report.output.as_deref())?;
        let palette = if sink.is_stdout() {
            Palette::coloured()
        } else {
            Palette::plain()
        };
        text = Some(TextReporter::new(sink, palette, show_recorded).quiet(cli.quiet));
    }
    let stop = crate::interrupt::stop_flag();
    let ran = {
        let mut none = All(Vec::new());
        let reporter: &mut dyn Reporter = match &mut text {
            Some(text) => text,
            None => &mut none,
        };
        if cli.quiet {
            session.run(trials, options, stop, reporter)
        } else {
            let mut progress = ProgressReporter::new(trials, reporter);
            session.run(trials, options, stop, &mut progress)
        }
    };
    let outcome = ran.map_err(|e| {
        let path = report.output.as_deref().filter(|_| text.is_some());
        CliError::write(path, e)
    })?;
    if let Some(text) = text {
        text.into_inner().finish()?;
    }
    Ok(outcome)
}

/// What a report says of the run: the tool, the commit, the date, the backends, how it ended.
fn run_info(
    cli: &Cli,
    backends: &[Arc<dyn Backend>],
    date: String,
    outcome: &RunOutcome,
) -> RunInfo {
    RunInfo {
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
        interrupted: outcome.stopped == Some(Stopped::Interrupted),
        stopped: outcome.stopped,
        seconds: outcome.seconds,
    }
}

/// The report in a format other than text, and the saved run (`--save`), which an interrupted
/// run leaves as it was.
fn write_documents(
    report: &ReportArgs,
    format: Format,
    outcome: &RunOutcome,
    info: &RunInfo,
) -> Result<(), CliError> {
    let RunOutcome {
        records, summary, ..
    } = outcome;
    if format != Format::Text {
        let coloured = report.output.is_none()
            && anstream::AutoStream::choice(&std::io::stdout()) != anstream::ColorChoice::Never;
        let rendered = document::render(
            format,
            records,
            summary,
            info,
            coloured,
            text_width(report.output.is_none()),
        );
        output::write(report.output.as_deref(), &rendered)?;
    }
    match (&report.save, info.interrupted) {
        (Some(path), true) => console::note(&format!(
            "the run was interrupted; {} is left as it was",
            path.display()
        )),
        (Some(path), false) => {
            let saved = document::render(
                Format::Json,
                records,
                summary,
                info,
                false,
                matrix_text::DEFAULT_WIDTH,
            );
            output::write(Some(path), &saved)?;
        }
        (None, _) => {}
    }
    Ok(())
}

/// The notes and errors beside the report: known-differences entries not used, backends that
/// ran nothing.
fn notes(cli: &Cli, session: &Session, outcome: &RunOutcome) {
    for (name, known) in &session.known {
        if !known.ignored.is_empty() && !cli.quiet {
            console::note(&format!(
                "{} entr{} of {} (backend {name}) name cases not in this corpus and were not used",
                known.ignored.len(),
                if known.ignored.len() == 1 { "y" } else { "ies" },
                known.file.display()
            ));
        }
    }
    for (name, why) in &outcome.idle {
        console::status(&format!(
            "error: backend `{name}` ran no trial: {why} (--allow-empty accepts such a run)"
        ));
    }
}

/// The case ids that probe an open question (every question's when `question` is empty).
fn probe_cases(
    cli: &Cli,
    project: &Session,
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
fn planned(session: &Session, backends: &[Arc<dyn Backend>], filter: Option<&str>) -> Vec<Trial> {
    session
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
        mut session,
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
    let Some(b) = start(&mut session, cli, &file, &other_args)?
        .first()
        .cloned()
    else {
        return Err(CliError::input(format!(
            "no backend `{other}` to compare with"
        )));
    };
    let stop = crate::interrupt::stop_flag();
    let Against { paired, unpaired } =
        session.against(&a, &b, args.filter.as_deref(), args.jobs(), stop);
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
    // What the first backend gives nothing to judge against is reported first, with why.
    let options = RunOptions {
        jobs: 1,
        fail_fast: false,
        filtered: true,
        allow_empty: true,
    };
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
        .and_then(|()| session.run(&paired, &options, stop, &mut text));
    let outcome = written.map_err(|e| CliError::write(None, e))?;
    let differing = outcome.summary.failed + unpaired.len();
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
