//! `record`: what a backend did, written into the vectors as `observed` expectations.

use std::path::PathBuf;

use anstream::{eprintln, println};

use super::backends::{prepare, Prepared};
use super::{BackendArgs, Cli, EXIT_BAD_INPUT, EXIT_OK};
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

pub fn record_command(cli: &Cli, args: &RecordArgs) -> u8 {
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
    } = match prepare(cli, &backend_args) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let Some(backend) = backends.first() else {
        return EXIT_BAD_INPUT;
    };
    let provenance = Provenance {
        backend: backend.name().to_string(),
        version: backend.describe(),
        date: args.date.clone().unwrap_or_else(today),
    };
    let recording = match record(&project, backend, args.filter.as_deref(), &provenance) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let (mut filled, mut replaced, mut kept, mut skipped) = (0, 0, 0, 0);
    for e in &recording.entries {
        let at = &e.case.location;
        match &e.change {
            Change::Filled { effect } => {
                filled += 1;
                println!("{at}: {}: unspecified -> observed: {effect}", e.case.id);
            }
            Change::Replaced { was, effect, same } => {
                replaced += 1;
                println!(
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
                    println!(
                        "{at}: {}: manual, kept; {} did otherwise: {effect}",
                        e.case.id, provenance.backend
                    );
                }
            }
            Change::NotRecorded(why) => {
                skipped += 1;
                println!("{at}: {}: not recorded: {why}", e.case.id);
            }
        }
    }
    if !args.dry_run {
        for (path, text) in &recording.files {
            if let Err(e) = std::fs::write(path, text) {
                eprintln!("error: cannot write {}: {e}", path.display());
                return EXIT_BAD_INPUT;
            }
        }
    }
    println!(
        "{}{filled} unspecified case(s) filled in, {replaced} expectation(s) replaced, {kept} manual \
         kept, {skipped} not recorded, in {} file(s)",
        if args.dry_run { "dry run: " } else { "" },
        recording.files.len()
    );
    EXIT_OK
}
