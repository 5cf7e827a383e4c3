//! What each subcommand does. Errors are rendered here, once, at the edge.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anstream::{eprintln, println};

use super::{BackendArgs, Cli, Command, Format, RunArgs, SchemaKind};
use crate::backend::external::config::{self, valid_name, Configured, ENV_SELF};
use crate::backend::external::{serve, ExternalSpec, Launch};
use crate::backend::Backend;
use crate::compare::Verdict;
use crate::load::{load_corpus, load_profiles, LoadErrors};
use crate::neutral::lower::{plan_neutral, NeutralTrial, NeutralVerdict};
use crate::plan::{plan, Trial};
use crate::report::text::{case_line, render, Palette};
use crate::report::{json, Summary, TrialResult};
use crate::session::{project_backends, Paths, ProjectBackends, Session};

pub const EXIT_OK: u8 = 0;
pub const EXIT_DIFFERENCES: u8 = 1;
pub const EXIT_BAD_INPUT: u8 = 2;

pub fn dispatch(cli: &Cli) -> u8 {
    let mut paths = Paths::under(&cli.root);
    if let Some(v) = &cli.vendors {
        paths.vendors = v.clone();
    }
    match &cli.command {
        Command::Run(args) => {
            if !args.vectors.is_empty() {
                paths.vectors = args.vectors.clone();
            }
            run(cli, &paths, args)
        }
        Command::Validate { paths: given } => {
            if !given.is_empty() {
                paths.vectors = given.clone();
            }
            validate(&paths)
        }
        Command::Diff(args) => {
            if !args.vectors.is_empty() {
                paths.vectors = args.vectors.clone();
            }
            super::diff::diff(cli, &paths, args)
        }
        Command::List { filter } => list(cli, &paths, filter.as_deref()),
        Command::Serve { profile } => serve_profile(&paths, profile),
        Command::Schema { kind } => {
            let schema = match kind {
                SchemaKind::Vectors => crate::spec::vector_file_schema(),
                SchemaKind::Profile => crate::profile::profile_schema(),
                SchemaKind::CrossVendor => crate::neutral::spec::neutral_file_schema(),
                SchemaKind::Protocol => crate::backend::external::protocol::protocol_schema(),
                SchemaKind::Project => config::project_schema(),
                SchemaKind::Known => config::known_schema(),
            };
            println!(
                "{}",
                serde_json::to_string_pretty(&schema).unwrap_or_default()
            );
            EXIT_OK
        }
    }
}

fn report_load_errors(errors: &LoadErrors) -> u8 {
    eprintln!("{errors}");
    EXIT_BAD_INPUT
}

pub(super) fn load(paths: &Paths) -> Result<Session, u8> {
    Session::load(paths).map_err(|e| report_load_errors(&e))
}

fn validate(paths: &Paths) -> u8 {
    let profiles = match load_profiles(&paths.vendors) {
        Ok(p) => p,
        Err(e) => return report_load_errors(&e),
    };
    match load_corpus(&paths.vectors, &profiles) {
        Ok(corpus) => {
            let files: std::collections::BTreeSet<&PathBuf> =
                corpus.cases.iter().map(|c| &c.location.file).collect();
            let files: std::collections::BTreeSet<&PathBuf> = files
                .into_iter()
                .chain(corpus.neutral.iter().map(|c| &c.location.file))
                .collect();
            println!(
                "ok: {} cases and {} cross-vendor cases in {} files, {} profiles",
                corpus.cases.len(),
                corpus.neutral.len(),
                files.len(),
                profiles.iter().count()
            );
            EXIT_OK
        }
        Err(e) => report_load_errors(&e),
    }
}

/// The binary that backends see as `$PLC_CONFORMANCE`.
fn this_binary() -> PathBuf {
    std::env::current_exe().unwrap_or_else(|_| PathBuf::from("plc-conformance"))
}

/// The project file's backends; a bad file is reported here.
pub(super) fn project(cli: &Cli) -> Result<ProjectBackends, u8> {
    let (file, explicit) = match &cli.config {
        Some(f) => (f.clone(), true),
        None => config::locate(&cli.root),
    };
    project_backends(&file, explicit, &this_binary()).map_err(|e| report_load_errors(&e))
}

/// Reads `external:NAME=COMMAND`.
fn command_line_external(text: &str, args: &BackendArgs) -> Result<Option<ExternalSpec>, String> {
    let Some(rest) = text.strip_prefix("external:") else {
        return Ok(None);
    };
    let Some((name, command)) = rest.split_once('=') else {
        return Err(format!(
            "`{text}`: expected `external:NAME=COMMAND`, e.g. `external:my-emu=./my-emu --serve`"
        ));
    };
    if !valid_name(name) {
        return Err(format!(
            "`{name}` is not a backend name: use lowercase letters, digits, `-` and `_`"
        ));
    }
    if command.trim().is_empty() {
        return Err(format!("external backend `{name}` has an empty command"));
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0 && args.timeout <= 86_400.0) {
        return Err(format!(
            "--timeout {}: give seconds above 0 and at most a day",
            args.timeout
        ));
    }
    let mut spec = ExternalSpec::new(name, Launch::Shell(command.to_string()));
    spec.timeout = std::time::Duration::from_secs_f64(args.timeout);
    spec.env = vec![(ENV_SELF.into(), this_binary().display().to_string())];
    Ok(Some(spec))
}

/// Starts the external backends a run asks for and picks its backends, in the order given.
/// `own_corpus` is false when the run reads another corpus (`--vectors`), which need not have
/// every case a known-differences file names.
pub(super) fn select_backends(
    session: &mut Session,
    project: &ProjectBackends,
    args: &BackendArgs,
    own_corpus: bool,
) -> Result<Vec<std::sync::Arc<dyn Backend>>, String> {
    let mut known_files: BTreeMap<&str, PathBuf> = BTreeMap::new();
    for entry in &args.known_differences {
        let Some((name, file)) = entry.split_once('=') else {
            return Err(format!("--known-differences `{entry}`: expected NAME=FILE"));
        };
        known_files.insert(name, PathBuf::from(file));
    }
    let strict = own_corpus;
    let start = |session: &mut Session, spec: ExternalSpec| {
        session
            .add_external(spec, strict)
            .map(|b| b as std::sync::Arc<dyn Backend>)
            .map_err(|e| e.to_string())
    };
    let configured = |c: &Configured| c.spec.clone();
    if args.backends.is_empty() {
        let mut chosen = session.backends.clone();
        for c in &project.configured {
            chosen.push(start(session, configured(c))?);
        }
        return Ok(chosen);
    }
    let mut chosen = Vec::new();
    for name in &args.backends {
        if let Some(mut spec) = command_line_external(name, args)? {
            spec.known_differences = known_files.remove(spec.name.as_str());
            chosen.push(start(session, spec)?);
        } else if let Some(b) = session.backends.iter().find(|b| b.name() == name) {
            chosen.push(b.clone());
        } else if let Some(c) = project.configured.iter().find(|c| c.spec.name == *name) {
            chosen.push(start(session, configured(c))?);
        } else if let Some(why) = project
            .skipped
            .iter()
            .find(|w| w.contains(&format!("`{name}`")))
        {
            return Err(why.clone());
        } else {
            let mut known: Vec<&str> = session.backends.iter().map(|b| b.name()).collect();
            known.extend(project.configured.iter().map(|c| c.spec.name.as_str()));
            return Err(format!(
                "unknown backend `{name}`; expected one of: {}, or external:NAME=COMMAND",
                known.join(", ")
            ));
        }
    }
    if let Some(name) = known_files.keys().next() {
        return Err(format!(
            "--known-differences names `{name}`, which is not an `external:` backend of this run"
        ));
    }
    Ok(chosen)
}

/// A loaded session with the chosen backends started, and the project file they came from.
pub(super) struct Prepared {
    pub session: Session,
    pub project: ProjectBackends,
    pub backends: Vec<std::sync::Arc<dyn Backend>>,
}

/// Loads the corpus and the project file and starts the backends a command asks for: every
/// external backend has agreed on the protocol before a case runs.
pub(super) fn prepare(
    cli: &Cli,
    paths: &Paths,
    args: &BackendArgs,
    own_corpus: bool,
) -> Result<Prepared, u8> {
    let mut session = load(paths)?;
    let project = project(cli)?;
    let backends = start_backends(&mut session, &project, args, own_corpus)?;
    Ok(Prepared {
        session,
        project,
        backends,
    })
}

/// [`select_backends`], with its error reported here.
pub(super) fn start_backends(
    session: &mut Session,
    project: &ProjectBackends,
    args: &BackendArgs,
    own_corpus: bool,
) -> Result<Vec<std::sync::Arc<dyn Backend>>, u8> {
    select_backends(session, project, args, own_corpus).map_err(|message| {
        let message = message.strip_prefix("error: ").unwrap_or(&message);
        eprintln!("error: {message}");
        EXIT_BAD_INPUT
    })
}

/// The native and cross-vendor trials of the chosen backends whose names contain `filter`.
pub(super) fn plan_trials(
    session: &Session,
    backends: &[std::sync::Arc<dyn Backend>],
    filter: Option<&str>,
) -> (Vec<Trial>, Vec<NeutralTrial>) {
    let keep = |name: String| filter.is_none_or(|f| name.contains(f));
    let trials = plan(&session.corpus, &session.profiles, backends)
        .into_iter()
        .filter(|t| keep(t.name()))
        .collect();
    let neutral = plan_neutral(&session.corpus.neutral, &session.profiles, backends)
        .into_iter()
        .filter(|t| keep(t.name()))
        .collect();
    (trials, neutral)
}

fn run(cli: &Cli, paths: &Paths, args: &RunArgs) -> u8 {
    let Prepared {
        session,
        project,
        backends,
    } = match prepare(cli, paths, &args.backends, args.vectors.is_empty()) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let (trials, neutral) = plan_trials(&session, &backends, args.filter.as_deref());
    if trials.is_empty() && neutral.is_empty() {
        eprintln!("error: no trial matches (check --backend and --filter; `plc-conformance list` shows what exists)");
        return EXIT_BAD_INPUT;
    }
    let verdicts = session.run_all(&trials);
    let results: Vec<TrialResult> = trials
        .into_iter()
        .zip(verdicts)
        .map(|(trial, verdict)| TrialResult { trial, verdict })
        .collect();
    let neutral_verdicts = session.run_neutral(&neutral);
    let neutral_results: Vec<(NeutralTrial, Option<NeutralVerdict>)> =
        neutral.into_iter().zip(neutral_verdicts).collect();
    let mut summary = Summary::of(&results);
    let neutral_summary = Summary::of_neutral(neutral_results.iter().map(|(_, v)| v.as_ref()));
    summary.add(&neutral_summary);
    match args.format {
        Format::Json => println!("{}", json::render(&results, &neutral_results)),
        Format::Text => {
            let notes = if args.backends.backends.is_empty() {
                project.skipped.as_slice()
            } else {
                &[]
            };
            print_text(
                &results,
                &summary,
                args.show_recorded,
                notes,
                &neutral_results,
                &neutral_summary,
            )
        }
    }
    for b in &backends {
        if let Some(known) = session.known.get(b.name()) {
            if !known.ignored.is_empty() {
                eprintln!(
                    "note: {} entr{} of {} name cases not in this corpus and were not used",
                    known.ignored.len(),
                    if known.ignored.len() == 1 { "y" } else { "ies" },
                    known.file.display()
                );
            }
        }
    }
    if summary.failed > 0 {
        EXIT_DIFFERENCES
    } else {
        EXIT_OK
    }
}

fn print_text(
    results: &[TrialResult],
    summary: &Summary,
    show_recorded: bool,
    notes: &[String],
    neutral: &[(NeutralTrial, Option<NeutralVerdict>)],
    neutral_summary: &Summary,
) {
    let palette = Palette::coloured();
    let mut skipped: BTreeMap<&str, usize> = BTreeMap::new();
    let mut per_backend: BTreeMap<&str, Vec<&TrialResult>> = BTreeMap::new();
    // Known differences by entry: (entry, reason, trials), in order of first appearance.
    let mut known: Vec<(String, String, Vec<&TrialResult>)> = Vec::new();
    for r in results {
        per_backend
            .entry(r.trial.backend.name())
            .or_default()
            .push(r);
        match &r.verdict {
            None => {
                *skipped
                    .entry(r.trial.skip.as_deref().unwrap_or(""))
                    .or_default() += 1
            }
            Some(v) if v.is_failure() => println!("{}", render(&r.trial, v, palette)),
            Some(Verdict::KnownDifference { reason, entry, .. }) => {
                match known.iter_mut().find(|(e, _, _)| e == entry) {
                    Some((_, _, trials)) => trials.push(r),
                    None => known.push((entry.clone(), reason.clone(), vec![r])),
                }
            }
            Some(v @ Verdict::Recorded { .. }) if show_recorded => {
                println!("{}", render(&r.trial, v, palette))
            }
            Some(_) => {}
        }
    }
    for (entry, reason, trials) in &known {
        println!("known difference ({entry}): {reason}");
        for r in trials {
            println!("  {} ({})", r.trial.name(), r.trial.case.location);
        }
    }
    for (reason, count) in &skipped {
        println!("skipped {count} trial(s): {reason}");
    }
    for note in notes {
        println!("skipped: {note}");
    }
    for (trial, verdict) in neutral {
        let Some(v) = verdict else { continue };
        let show = v.is_failure()
            || matches!(v, NeutralVerdict::KnownDifference { .. })
            || (show_recorded && matches!(v, NeutralVerdict::Recorded { .. }));
        if show {
            println!(
                "{}: {} ({})\n  {}\n",
                trial.case.location,
                trial.name(),
                trial.lowering.description,
                v.describe()
            );
        }
    }
    for (backend, rs) in &per_backend {
        println!("{backend}: {}", Summary::of(rs.iter().copied()));
    }
    if !neutral.is_empty() {
        println!("cross-vendor: {neutral_summary}");
    }
    println!("{summary}");
    let _ = std::io::stdout().flush();
}

fn list(cli: &Cli, paths: &Paths, filter: Option<&str>) -> u8 {
    let session = match load(paths) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let project = match project(cli) {
        Ok(p) => p,
        Err(code) => return code,
    };
    println!("backends:");
    let width = session
        .backends
        .iter()
        .map(|b| b.name().len())
        .chain(project.configured.iter().map(|c| c.spec.name.len()))
        .max()
        .unwrap_or(0)
        .max(10);
    for b in &session.backends {
        println!(
            "  {:<width$} profile {:<18} {}",
            b.name(),
            b.profile(),
            b.describe()
        );
    }
    for c in &project.configured {
        println!(
            "  {:<width$} profile {:<18} external, configured at {} (`{}`)",
            c.spec.name,
            c.spec.profile.as_deref().unwrap_or("(from its handshake)"),
            c.location,
            c.spec.launch
        );
    }
    for note in &project.skipped {
        println!("  (skipped: {note})");
    }
    println!("profiles:");
    for p in session.profiles.iter() {
        println!(
            "  {:<18} {} — instructions: {}",
            p.id,
            p.name,
            p.instructions
                .keys()
                .cloned()
                .collect::<Vec<_>>()
                .join(", ")
        );
        for v in &p.variants {
            println!("    variant {:<22} {}", v.id, v.description);
        }
    }
    println!("cases:");
    let mut shown = 0;
    for case in &session.corpus.cases {
        let line = case_line(case);
        if filter.is_none_or(|f| line.contains(f)) {
            println!("  {line}");
            shown += 1;
        }
    }
    println!("{shown} of {} cases", session.corpus.cases.len());
    EXIT_OK
}

/// `serve`: the reference model of a profile, over the protocol on stdin/stdout.
fn serve_profile(paths: &Paths, profile_id: &str) -> u8 {
    let profiles = match load_profiles(&paths.vendors) {
        Ok(p) => p,
        Err(e) => return report_load_errors(&e),
    };
    let Some(profile) = profiles.get(profile_id) else {
        eprintln!(
            "error: unknown profile `{profile_id}`; expected one of: {}",
            profiles.ids().join(", ")
        );
        return EXIT_BAD_INPUT;
    };
    let backends = crate::backend::reference_backends(&profiles);
    let Some(backend) = backends.iter().find(|b| b.profile() == profile_id) else {
        eprintln!("error: profile `{profile_id}` has no built-in reference model");
        return EXIT_BAD_INPUT;
    };
    let stdin = std::io::stdin().lock();
    let stdout = std::io::BufWriter::with_capacity(64 * 1024, std::io::stdout().lock());
    match serve::serve(backend.as_ref(), profile, stdin, stdout) {
        Ok(()) => EXIT_OK,
        Err(message) => {
            eprintln!("error: {message}");
            EXIT_BAD_INPUT
        }
    }
}
