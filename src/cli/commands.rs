//! What each subcommand does. Errors are rendered here, once, at the edge.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anstream::{eprintln, println};

use super::{Cli, Command, Format, RunArgs, SchemaKind};
use crate::load::{load_corpus, load_profiles, LoadErrors};
use crate::plan::plan;
use crate::report::text::{case_line, render, Palette};
use crate::report::{json, Summary, TrialResult};
use crate::session::{Paths, Session};

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
            run(&paths, args)
        }
        Command::Validate { paths: given } => {
            if !given.is_empty() {
                paths.vectors = given.clone();
            }
            validate(&paths)
        }
        Command::List { filter } => list(&paths, filter.as_deref()),
        Command::Diff(args) => {
            if !args.vectors.is_empty() {
                paths.vectors = args.vectors.clone();
            }
            super::diff::diff(&paths, args)
        }
        Command::Schema { kind } => {
            let schema = match kind {
                SchemaKind::Vectors => crate::spec::vector_file_schema(),
                SchemaKind::Profile => crate::profile::profile_schema(),
                SchemaKind::CrossVendor => crate::neutral::spec::neutral_file_schema(),
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

fn load(paths: &Paths) -> Result<Session, u8> {
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

fn run(paths: &Paths, args: &RunArgs) -> u8 {
    let session = match load(paths) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let backends = if args.backends.is_empty() {
        session.backends.clone()
    } else {
        let mut chosen = Vec::new();
        for name in &args.backends {
            match session.backends.iter().find(|b| b.name() == name) {
                Some(b) => chosen.push(b.clone()),
                None => {
                    let known: Vec<&str> = session.backends.iter().map(|b| b.name()).collect();
                    eprintln!(
                        "error: unknown backend `{name}`; expected one of: {}",
                        known.join(", ")
                    );
                    return EXIT_BAD_INPUT;
                }
            }
        }
        chosen
    };
    let trials: Vec<_> = plan(&session.corpus, &session.profiles, &backends)
        .into_iter()
        .filter(|t| {
            args.filter
                .as_ref()
                .is_none_or(|f| t.name().contains(f.as_str()))
        })
        .collect();
    if trials.is_empty() {
        eprintln!("error: no trial matches (check --backend and --filter; `plc-conformance list` shows what exists)");
        return EXIT_BAD_INPUT;
    }
    let results: Vec<TrialResult> = trials
        .into_iter()
        .map(|trial| {
            let verdict = trial.skip.is_none().then(|| trial.run());
            TrialResult { trial, verdict }
        })
        .collect();
    let summary = Summary::of(&results);
    match args.format {
        Format::Json => println!("{}", json::render(&results)),
        Format::Text => print_text(&results, &summary, args.show_recorded),
    }
    if summary.failed > 0 {
        EXIT_DIFFERENCES
    } else {
        EXIT_OK
    }
}

fn print_text(results: &[TrialResult], summary: &Summary, show_recorded: bool) {
    let palette = Palette::coloured();
    let mut skipped: BTreeMap<&str, usize> = BTreeMap::new();
    let mut per_backend: BTreeMap<&str, Vec<&TrialResult>> = BTreeMap::new();
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
            Some(v @ crate::compare::Verdict::Recorded { .. }) if show_recorded => {
                println!("{}", render(&r.trial, v, palette))
            }
            Some(_) => {}
        }
    }
    for (reason, count) in &skipped {
        println!("skipped {count} trial(s): {reason}");
    }
    for (backend, rs) in &per_backend {
        println!("{backend}: {}", Summary::of(rs.iter().copied()));
    }
    println!("{summary}");
    let _ = std::io::stdout().flush();
}

fn list(paths: &Paths, filter: Option<&str>) -> u8 {
    let session = match load(paths) {
        Ok(s) => s,
        Err(code) => return code,
    };
    println!("backends:");
    for b in &session.backends {
        println!(
            "  {:<10} profile {:<18} {}",
            b.name(),
            b.profile(),
            b.describe()
        );
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
