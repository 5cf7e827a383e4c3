//! `plc-conformance diff`: where do the backends disagree, and how.

use std::path::PathBuf;

use anstream::{eprintln, print, println};
use clap::ValueEnum;
use serde::Serialize;

use super::commands::{
    plan_trials, prepare, start_backends, Prepared, EXIT_BAD_INPUT, EXIT_DIFFERENCES, EXIT_OK,
};
use super::{BackendArgs, Cli};
use crate::backend::Backend;
use crate::backend::Response;
use crate::baseline::{self, SavedRun};
use crate::compare::{rows, Observation};
use crate::matrix::{native_records, neutral_records, sections, Record, Section};
use crate::model::{error_text, Expectation};
use crate::neutral::lower::plan_neutral;
use crate::plan::plan;
use crate::report::text::{memory_diff, Palette};
use crate::session::{Paths, Session};

#[derive(Debug, clap::Args)]
pub struct DiffArgs {
    #[command(flatten)]
    pub backends: BackendArgs,
    /// Compare the (first) chosen backend directly with this one, word by word.
    #[arg(long, value_name = "NAME")]
    pub against: Option<String>,
    /// Only trials whose name contains this text (`cross-vendor` selects the cross-vendor cases).
    #[arg(long)]
    pub filter: Option<String>,
    /// Vector files or folders [default: ROOT/vectors].
    #[arg(long = "vectors", value_name = "PATH")]
    pub vectors: Vec<PathBuf>,
    /// Report format.
    #[arg(long, value_enum, default_value_t = DiffFormat::Text)]
    pub format: DiffFormat,
    /// Write the report to this file instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also save the results (JSON) for a later `--baseline`.
    #[arg(long, value_name = "FILE")]
    pub save: Option<PathBuf>,
    /// Compare with a saved run: list new, fixed and changed differences, and fail only on new
    /// ones.
    #[arg(long, value_name = "FILE")]
    pub baseline: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DiffFormat {
    /// Grouped matrices, coloured on a terminal (honours NO_COLOR).
    Text,
    /// The records and matrices as JSON (stable, versioned; usable as a `--baseline`).
    Json,
    /// JUnit XML, one test case per cell.
    Junit,
    /// One self-contained HTML file.
    Html,
}

/// The JSON report: a saved run plus the matrices.
#[derive(Serialize)]
struct JsonReport<'a> {
    format: &'static str,
    version: u32,
    sections: &'a [Section<'a>],
    records: &'a [Record],
}

pub fn diff(cli: &Cli, paths: &Paths, args: &DiffArgs) -> u8 {
    let own_corpus = args.vectors.is_empty();
    let Prepared {
        mut session,
        project,
        backends: chosen,
    } = match prepare(cli, paths, &args.backends, own_corpus) {
        Ok(p) => p,
        Err(code) => return code,
    };
    if let Some(other) = &args.against {
        let Some(first) = chosen.first().cloned() else {
            return EXIT_BAD_INPUT;
        };
        let other = BackendArgs {
            backends: vec![other.clone()],
            known_differences: Vec::new(),
            ..args.backends.clone()
        };
        return match start_backends(&mut session, &project, &other, own_corpus) {
            Ok(b) => against(&session, &first, &b[0], args.filter.as_deref()),
            Err(code) => code,
        };
    }
    let (trials, neutral) = plan_trials(&session, &chosen, args.filter.as_deref());
    if trials.is_empty() && neutral.is_empty() {
        eprintln!("error: no trial matches (check --backend and --filter)");
        return EXIT_BAD_INPUT;
    }
    let verdicts = session.run_all(&trials);
    let mut records = neutral_records(&neutral, session.run_neutral(&neutral));
    records.extend(native_records(&trials, verdicts));
    let matrices = sections(&records);
    let rendered = match args.format {
        DiffFormat::Text => crate::report::matrix_text::render(
            &matrices,
            args.output.is_none()
                && anstream::AutoStream::choice(&std::io::stdout()) != anstream::ColorChoice::Never,
        ),
        DiffFormat::Json => serde_json::to_string_pretty(&JsonReport {
            format: baseline::FORMAT,
            version: baseline::VERSION,
            sections: &matrices,
            records: &records,
        })
        .unwrap_or_default(),
        DiffFormat::Junit => crate::report::junit::render(&records),
        DiffFormat::Html => crate::report::html::render(&matrices, &records),
    };
    if let Err(code) = write_out(args.output.as_ref(), &rendered) {
        return code;
    }
    if let Some(path) = &args.save {
        let saved =
            serde_json::to_string_pretty(&SavedRun::new(records.clone())).unwrap_or_default();
        if let Err(e) = std::fs::write(path, saved) {
            eprintln!("error: cannot save the run to {}: {e}", path.display());
            return EXIT_BAD_INPUT;
        }
    }
    if let Some(path) = &args.baseline {
        let before = match baseline::load(path) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        };
        let changes = baseline::compare(&before.records, &records);
        eprintln!(
            "against {}: {} new, {} fixed, {} changed, {} unchanged difference(s)",
            path.display(),
            changes.new.len(),
            changes.fixed.len(),
            changes.changed.len(),
            changes.unchanged
        );
        for r in &changes.new {
            eprintln!("  new:     {} ({}: {})", r.trial, r.status.label(), r.shown);
        }
        for (was, now) in &changes.fixed {
            eprintln!(
                "  fixed:   {} (was {}: {})",
                now.trial,
                was.status.label(),
                was.shown
            );
        }
        for (was, now) in &changes.changed {
            eprintln!("  changed: {} ({} -> {})", now.trial, was.shown, now.shown);
        }
        return if changes.new.is_empty() {
            EXIT_OK
        } else {
            EXIT_DIFFERENCES
        };
    }
    if records.iter().any(|r| r.status.is_failure()) {
        EXIT_DIFFERENCES
    } else {
        EXIT_OK
    }
}

fn write_out(path: Option<&PathBuf>, text: &str) -> Result<(), u8> {
    match path {
        Some(p) => std::fs::write(p, text).map_err(|e| {
            eprintln!("error: cannot write {}: {e}", p.display());
            EXIT_BAD_INPUT
        }),
        None => {
            println!("{text}");
            Ok(())
        }
    }
}

/// Two backends side by side: every case both run, and where their outcomes differ, the
/// per-word diff of one against the other.
fn against(
    session: &Session,
    a: &std::sync::Arc<dyn Backend>,
    b: &std::sync::Arc<dyn Backend>,
    filter: Option<&str>,
) -> u8 {
    if a.profile() != b.profile() {
        // Different families share only the cross-vendor cases.
        let trials = plan_neutral(
            &session.corpus.neutral,
            &session.profiles,
            &[a.clone(), b.clone()],
        );
        let records = neutral_records(&trials, session.run_neutral(&trials));
        println!(
            "{}",
            crate::report::matrix_text::render(&sections(&records), false)
        );
        return EXIT_OK;
    }
    let trials_a = plan(&session.corpus, &session.profiles, std::slice::from_ref(a));
    let trials_b = plan(&session.corpus, &session.profiles, std::slice::from_ref(b));
    let palette = Palette::coloured();
    let (mut compared, mut differing) = (0, 0);
    for ta in trials_a.iter().filter(|t| t.skip.is_none()) {
        let row =
            |t: &crate::plan::Trial| (t.instruction.clone(), t.case.id.clone(), t.variant.clone());
        if filter.is_some_and(|f| !ta.name().contains(f)) {
            continue;
        }
        let Some(tb) = trials_b
            .iter()
            .find(|t| t.skip.is_none() && row(t) == row(ta))
        else {
            continue;
        };
        compared += 1;
        let (Ok(oa), Ok(ob)) = (ta.observe(), tb.observe()) else {
            continue;
        };
        let text = compare_outcomes(ta, &oa, &ob, palette);
        if !text.is_empty() {
            differing += 1;
            println!(
                "{}: {}::{}::{} — {} vs {}",
                ta.case.location,
                ta.instruction.to_lowercase(),
                ta.case.id,
                ta.variant,
                a.name(),
                b.name()
            );
            print!("{text}");
        }
    }
    println!(
        "{} vs {}: {compared} trials compared, {differing} differ",
        a.name(),
        b.name()
    );
    if differing == 0 {
        EXIT_OK
    } else {
        EXIT_DIFFERENCES
    }
}

/// The per-word diff of B's outcome against A's, under each fill; empty when they agree.
fn compare_outcomes(
    trial: &crate::plan::Trial,
    a: &[Observation],
    b: &[Observation],
    palette: Palette,
) -> String {
    let mut out = String::new();
    for (oa, ob) in a.iter().zip(b) {
        let image = crate::memory::Image::new(trial.case.before.clone(), oa.fill);
        match (&oa.result, &ob.result) {
            (Ok(Response::Done(x)), Ok(Response::Done(y))) => {
                let expect = Expectation {
                    after: x
                        .writes
                        .iter()
                        .filter(|(d, v)| image.read(d) != **v)
                        .map(|(d, v)| (d.clone(), *v))
                        .collect(),
                    error: x.error.clone(),
                };
                let rows = rows(&image, &expect, y);
                let words = rows.iter().any(|r| r.expected != r.actual);
                if words || x.error != y.error {
                    out.push_str(&format!(
                        "  fill {} (- first backend, + second):\n",
                        oa.fill.name()
                    ));
                    if words {
                        out.push_str(&memory_diff(&rows, palette));
                    }
                    if x.error != y.error {
                        out.push_str(&format!(
                            "  error: {} vs {}\n",
                            error_text(x.error.as_ref()),
                            error_text(y.error.as_ref())
                        ));
                    }
                }
            }
            (x, y) if format!("{x:?}") != format!("{y:?}") => {
                out.push_str(&format!("  fill {}: {x:?} vs {y:?}\n", oa.fill.name()));
            }
            _ => {}
        }
    }
    out
}
