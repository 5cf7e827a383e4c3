//! The corpus as tests: one libtest trial per (backend, instruction, case, variant).
//!
//! `cargo test --test conformance -- habin` filters, `--list` lists, `--exact NAME` runs one;
//! `cargo nextest run` works too. A failing trial prints the vector's `file:line`, what ran and
//! a word-by-word diff. `unspecified` cases run and are reported as ignored with what the
//! backend did, so they never fail the run but are never silent.

use std::path::Path;
use std::process::ExitCode;

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use plc_conformance::compare::Verdict;
use plc_conformance::neutral::lower::{plan_neutral, NeutralVerdict};
use plc_conformance::plan::plan;
use plc_conformance::report::text::{render, Palette};
use plc_conformance::session::{Paths, Session};

fn main() -> ExitCode {
    let args = Arguments::from_args();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let session = match Session::load(&Paths::under(root)) {
        Ok(s) => s,
        Err(errors) => {
            eprintln!("the corpus does not load:\n{errors}");
            return ExitCode::from(2);
        }
    };
    let mut trials: Vec<Trial> = plan(&session.corpus, &session.profiles, &session.backends)
        .into_iter()
        .map(|trial| {
            let name = trial.name();
            let kind = trial.case.basis.to_string();
            match trial.skip.clone() {
                Some(reason) => {
                    Trial::ignorable_test(name, move || Ok(Completion::ignored_with(reason)))
                }
                None => Trial::ignorable_test(name, move || match trial.run() {
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
                    verdict => Err(Failed::from(render(&trial, &verdict, Palette::plain()))),
                }),
            }
            .with_kind(kind)
        })
        .collect();
    let neutral = plan_neutral(
        &session.corpus.neutral,
        &session.profiles,
        &session.backends,
    );
    trials.extend(neutral.into_iter().map(|trial| {
        let name = trial.name();
        let kind = trial.case.basis.to_string();
        match trial.skip.clone() {
            Some(reason) => {
                Trial::ignorable_test(name, move || Ok(Completion::ignored_with(reason)))
            }
            None => Trial::ignorable_test(name, move || match trial.run() {
                NeutralVerdict::Matches { .. } => Ok(Completion::Completed),
                NeutralVerdict::Recorded { outcome } => Ok(Completion::ignored_with(format!(
                    "unspecified, recorded: {outcome}"
                ))),
                verdict => Err(Failed::from(format!(
                    "{}: {} {}\n  {}",
                    trial.case.location,
                    trial.name(),
                    trial.lowering.description,
                    verdict.describe()
                ))),
            }),
        }
        .with_kind(kind)
    }));
    libtest_mimic::run(&args, trials).exit_code()
}
