//! `record`: what a backend did, written into the vectors as `observed` expectations.

use std::path::PathBuf;

use std::fmt::Write as _;

use super::backends::{prepare, Prepared};
use super::{output, BackendArgs, Cli, CliError, Outcome, EXIT_DIFFERENCES, EXIT_OK};
use crate::clock::today;
use crate::record::{record, Change, Provenance, Recording};

/// What `record` takes.
#[derive(Debug, clap::Args)]
pub(crate) struct RecordArgs {
    /// The backend whose behaviour is recorded: a name (see `list`) or `external:NAME=COMMAND`.
    #[arg(long = "backend", value_name = "NAME")]
    pub backend: String,
    /// Only trials whose name (`backend::instruction::case::variant`) contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// Vector files or folders [default: ROOT/vectors].
    #[arg(long = "vectors", value_name = "PATH")]
    pub vectors: Vec<PathBuf>,
    /// Seconds an `external:` backend may take to answer one case.
    #[arg(long, value_name = "SECONDS", default_value = "5", value_parser = super::seconds)]
    pub timeout: std::time::Duration,
    /// The date written in the provenance [default: today, UTC].
    #[arg(long, value_name = "YYYY-MM-DD")]
    pub date: Option<String>,
    /// Show what would change without writing.
    #[arg(long)]
    pub dry_run: bool,
    /// Instead of recording into the vectors, write a starting known-differences file of what
    /// the backend gets wrong (run without its own file): an entry by input class where every
    /// case of the class differs, else a case at a time. An existing file is never replaced.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["dry_run", "date"])]
    pub known: Option<PathBuf>,
}

pub(super) fn record_command(cli: &Cli, args: &RecordArgs) -> Outcome {
    let backend_args = BackendArgs {
        backends: vec![args.backend.clone()],
        timeout: args.timeout,
        known_differences: Vec::new(),
        filter: args.filter.clone(),
        vectors: args.vectors.clone(),
        jobs: Some(1),
        max_faults: crate::model::project::DEFAULT_MAX_CONSECUTIVE_FAULTS,
        allow_empty: false,
        fail_fast: false,
    };
    let Prepared {
        session, backends, ..
    } = prepare(cli, &backend_args)?;
    let project = &session.project;
    let Some(backend) = backends.first() else {
        return Err(CliError::input("record needs a --backend"));
    };
    if let Some(path) = &args.known {
        return known_file(backend, project, args.filter.as_deref(), path);
    }
    if !args.dry_run {
        refuse_embedded(project)?;
    }
    let provenance = Provenance {
        backend: backend.name().to_string(),
        version: backend.describe(),
        date: args.date.clone().unwrap_or_else(today),
    };
    // A live backend reads it from the mailbox when it connects, and again after a
    // reconnection: asked before anything runs, and before anything is written.
    let simulated = || match backend.simulated_by() {
        Some(simulator) => Err(CliError::input(format!(
            "{simulator} answers for `{}`: a model, or a simulator running one, answers with \
             the harness's own reading of the manuals, which is no observation of a CPU or an \
             implementation, so record writes nothing",
            provenance.backend
        ))),
        None => Ok(()),
    };
    simulated()?;
    let recording = record(
        project,
        backend,
        args.filter.as_deref(),
        &provenance,
        crate::interrupt::stop_flag(),
    )?;
    simulated()?;
    let (mut out, [filled, replaced, kept, skipped, faulted]) =
        listing(&recording, &provenance.backend);
    if !args.dry_run {
        output::write_every(
            recording
                .files
                .iter()
                .map(|(path, text)| (path.as_path(), text.as_str())),
        )?;
    }
    let _ = write!(
        out,
        "{}{filled} unspecified case(s) filled in, {replaced} expectation(s) replaced, {kept} manual \
         kept, {skipped} not recorded, {faulted} faulted, in {} file(s)",
        if args.dry_run { "dry run: " } else { "" },
        recording.files.len()
    );
    output::write(None, &out)?;
    // A backend that faulted did not answer: the recording is incomplete.
    Ok(if faulted > 0 {
        EXIT_DIFFERENCES
    } else {
        EXIT_OK
    })
}

/// Recording edits vector files in place: the copies built into the binary are not files.
fn refuse_embedded(project: &crate::project::Project) -> Result<(), CliError> {
    if let Some(case) = project
        .corpus
        .cases
        .iter()
        .find(|c| c.location.file.starts_with(crate::load::EMBEDDED))
    {
        return Err(CliError::input(format!(
            "record writes into the vector files, and {} is built into the binary: run it in \
             a project folder (one with vendors/ and vectors/), give --vectors FOLDER, or \
             add --dry-run",
            case.location.file.display()
        )));
    }
    Ok(())
}

/// One line per case the recording changed, kept or could not record, and the counts: filled,
/// replaced, manual kept, not recorded, faulted.
fn listing(recording: &Recording, backend: &str) -> (String, [usize; 5]) {
    let (mut filled, mut replaced, mut kept, mut skipped, mut faulted) = (0, 0, 0, 0, 0);
    let mut out = String::new();
    for e in &recording.entries {
        let at = &e.case.location;
        match &e.change {
            Change::Filled { effect } => {
                filled += 1;
                let _ = writeln!(
                    out,
                    "{at}: {}: unspecified -> observed: {effect}",
                    e.case.id
                );
            }
            Change::Replaced { was, effect, same } => {
                replaced += 1;
                let _ = writeln!(
                    out,
                    "{at}: {}: {was} -> observed: {effect}{}",
                    e.case.id,
                    if *same {
                        " (as expected before)"
                    } else {
                        " (the expectation changed)"
                    }
                );
            }
            Change::KeptManual { effect, differs } => {
                kept += 1;
                if *differs {
                    let _ = writeln!(
                        out,
                        "{at}: {}: manual, kept; {} did otherwise: {effect}",
                        e.case.id, backend
                    );
                }
            }
            Change::NotRecorded(why) => {
                skipped += 1;
                let _ = writeln!(out, "{at}: {}: not recorded: {why}", e.case.id);
            }
            Change::Faulted(why) => {
                faulted += 1;
                let _ = writeln!(
                    out,
                    "{at}: {}: not recorded, the backend faulted: {why}",
                    e.case.id
                );
            }
        }
    }
    (out, [filled, replaced, kept, skipped, faulted])
}

/// Whether a known-differences file lists no difference (`differences: []`, as `init` writes
/// it): a draft may take its place, since nothing written by hand is lost.
fn lists_nothing(path: &std::path::Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else {
        return false;
    };
    match serde_yaml::from_str::<serde_yaml::Value>(&text) {
        Ok(serde_yaml::Value::Mapping(file)) => {
            file.len() == 1
                && match file.get("differences") {
                    Some(serde_yaml::Value::Sequence(entries)) => entries.is_empty(),
                    Some(serde_yaml::Value::Null) => true,
                    _ => false,
                }
        }
        _ => false,
    }
}

/// `record --known FILE`: the starting known-differences file (`crate::known_draft`).
fn known_file(
    backend: &std::sync::Arc<dyn crate::backend::Backend>,
    project: &crate::project::Project,
    filter: Option<&str>,
    path: &std::path::Path,
) -> Outcome {
    output::check(path)?;
    if path.exists() && !lists_nothing(path) {
        return Err(CliError::input(format!(
            "--known {}: the file exists and lists differences; a starting file is written only \
             where none is, or over one that lists nothing (as `init` writes it): a \
             known-differences file is edited by hand, so remove it or give another path",
            path.display()
        )));
    }
    let draft = crate::known_draft::draft(project, backend, filter);
    for fault in &draft.faults {
        crate::report::console::status(&format!(
            "not listed: {fault} faulted, and a fault is never a known difference"
        ));
    }
    output::write(Some(path), &draft.text)?;
    crate::report::console::status(&format!(
        "wrote {}: {} entr{} by input class, {} by case; put each cause in words before keeping it",
        path.display(),
        draft.causes,
        if draft.causes == 1 { "y" } else { "ies" },
        draft.cases
    ));
    Ok(if draft.faults.is_empty() {
        EXIT_OK
    } else {
        EXIT_DIFFERENCES
    })
}
