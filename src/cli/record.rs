//! `record`: what a backend did, written into the vectors as `observed` expectations.

use std::path::PathBuf;

use std::fmt::Write as _;

use super::backends::{prepare, Prepared};
use super::{output, BackendArgs, Cli, CliError, Outcome, EXIT_DIFFERENCES, EXIT_OK};
use crate::record::{record, today, Change, Provenance};

/// What `record` takes.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
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
    #[arg(long, value_name = "SECONDS", default_value_t = 5.0)]
    pub timeout: f64,
    /// The date written in the provenance [default: today, UTC].
    #[arg(long, value_name = "YYYY-MM-DD")]
    pub date: Option<String>,
    /// Show what would change without writing.
    #[arg(long)]
    pub dry_run: bool,
}

pub fn record_command(cli: &Cli, args: &RecordArgs) -> Outcome {
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
        project, backends, ..
    } = prepare(cli, &backend_args)?;
    let Some(backend) = backends.first() else {
        return Err(CliError::input("record needs a --backend"));
    };
    // Recording edits vector files in place: the copies built into the binary are not files.
    if !args.dry_run {
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
    }
    let provenance = Provenance {
        backend: backend.name().to_string(),
        version: backend.describe(),
        date: args.date.clone().unwrap_or_else(today),
    };
    let recording = record(&project, backend, args.filter.as_deref(), &provenance)
        .map_err(|e| CliError::input(e.to_string()))?;
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
                        e.case.id, provenance.backend
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
