//! The corpus as tests: one libtest trial per (backend, instruction, case, variant), and one per
//! (backend, lowering, cross-vendor case).
//!
//! `cargo test --test conformance -- habin` filters, `--list` lists, `--exact NAME` runs one;
//! `cargo nextest run` works too. A failing trial prints the vector's `file:line`, what ran and
//! a word-by-word diff. `unspecified` cases run and are reported as ignored with what the
//! backend did, so they never fail the run but are never silent.
//!
//! The external backends of the project file (`plc-conformance.yaml`, or the file named by
//! `PLC_CONFORMANCE_CONFIG`) run as extra trials. A backend that cannot start fails one trial,
//! `NAME::handshake`, and runs none; one whose requirements are missing shows as an ignored
//! `NAME::setup` trial with the reason. A listed known difference shows as ignored with its
//! reason; a listed trial that conforms fails as a stale entry.

use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use plc_conformance::backend::external::config;
use plc_conformance::compare::Verdict;
use plc_conformance::neutral::lower::{plan_neutral, NeutralVerdict};
use plc_conformance::plan::plan;
use plc_conformance::report::text::{render, Palette};
use plc_conformance::session::{project_backends, Paths, Session};

fn main() -> ExitCode {
    let args = Arguments::from_args();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut session = match Session::load(&Paths::under(root)) {
        Ok(s) => s,
        Err(errors) => {
            eprintln!("the corpus does not load:\n{errors}");
            return ExitCode::from(2);
        }
    };
    let (file, explicit) = config::locate(root);
    let project = match project_backends(
        &file,
        explicit,
        Path::new(env!("CARGO_BIN_EXE_plc-conformance")),
    ) {
        Ok(p) => p,
        Err(errors) => {
            eprintln!("the project file does not load:\n{errors}");
            return ExitCode::from(2);
        }
    };
    let mut tests = Vec::new();
    for why in project.skipped {
        let name = why
            .split('`')
            .nth(1)
            .map_or_else(|| "external::setup".to_string(), |n| format!("{n}::setup"));
        eprintln!("note: {why}");
        tests.push(Trial::ignorable_test(name, move || {
            Ok(Completion::ignored_with(why))
        }));
    }
    let mut externals = Vec::new();
    for c in project.configured {
        let name = c.spec.name.clone();
        match session.add_external(c.spec, true) {
            Ok(b) => externals.push(b),
            Err(e) => {
                let message = e.to_string();
                tests.push(Trial::test(format!("{name}::handshake"), move || {
                    Err(Failed::from(message))
                }));
            }
        }
    }
    let session = Arc::new(session);
    let trials = plan(&session.corpus, &session.profiles, &session.backends);
    tests.extend(trials.into_iter().map(|trial| {
        let (name, kind, skip) = (
            trial.name(),
            trial.case.basis.to_string(),
            trial.skip.clone(),
        );
        let session = session.clone();
        libtest_trial(name, kind, skip, move || match session.verdict(&trial) {
            Verdict::Conforms => Ok(Completion::Completed),
            Verdict::Recorded {
                observed,
                fill_dependent,
            } => Ok(Completion::ignored_with(format!(
                "unspecified, recorded: {observed}{}",
                if fill_dependent {
                    " (depends on the fill)"
                } else {
                    ""
                }
            ))),
            Verdict::KnownDifference { reason, entry, .. } => Ok(Completion::ignored_with(
                format!("known difference ({entry}): {reason}"),
            )),
            verdict => Err(Failed::from(render(&trial, &verdict, Palette::plain()))),
        })
    }));
    let neutral = plan_neutral(
        &session.corpus.neutral,
        &session.profiles,
        &session.backends,
    );
    tests.extend(neutral.into_iter().map(|trial| {
        let (name, kind, skip) = (
            trial.name(),
            trial.case.basis.to_string(),
            trial.skip.clone(),
        );
        let session = session.clone();
        libtest_trial(name, kind, skip, move || {
            match session.neutral_verdict(&trial) {
                NeutralVerdict::Matches { .. } => Ok(Completion::Completed),
                NeutralVerdict::KnownDifference { reason, entry, .. } => Ok(
                    Completion::ignored_with(format!("known difference ({entry}): {reason}")),
                ),
                NeutralVerdict::Recorded { outcome } => Ok(Completion::ignored_with(format!(
                    "unspecified, recorded: {outcome}"
                ))),
                verdict => Err(Failed::from(format!(
                    "{}: {} ({})\n  {}",
                    trial.case.location,
                    trial.name(),
                    trial.lowering.description,
                    verdict.describe()
                ))),
            }
        })
    }));
    let conclusion = libtest_mimic::run(&args, tests);
    // The processes get their shutdown message before the harness exits.
    for b in externals {
        b.shutdown();
    }
    conclusion.exit_code()
}

/// A libtest trial: skipped with its reason, or run.
fn libtest_trial(
    name: String,
    kind: String,
    skip: Option<String>,
    run: impl FnOnce() -> Result<Completion, Failed> + Send + 'static,
) -> Trial {
    match skip {
        Some(reason) => Trial::ignorable_test(name, move || Ok(Completion::ignored_with(reason))),
        None => Trial::ignorable_test(name, run),
    }
    .with_kind(kind)
}
