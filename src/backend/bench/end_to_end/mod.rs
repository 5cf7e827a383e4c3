//! The bench end to end on 127.0.0.1: the SLMP and Modbus TCP clients, the simulated CPUs and
//! the bench backend held to the built-in models' verdicts, to each fault's kind, to the fence
//! and the interlocks, and to independent implementations of both protocols. White-box tests of
//! the crate's own parts, with no binary to run, so they live beside the code they reach into.

#[cfg(test)]
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use crate::backend::bench::sim::{FaultAction, FaultRule};
use crate::backend::bench::BenchBackend;
use crate::execute::{images, requests};
use crate::plan::Check;
use crate::session::Session;
use crate::{Backend, Basis, Difference, ErrorSignal, Fault, Response, Trial, Value, Verdict};
use crate::{Paths, Project};

mod idec;
mod modbus;
mod slmp;
mod slmp_cross;

/// The project root: its `vendors/`, `vectors/` and project file.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// An empty scratch folder for one test, removed when dropped.
fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("plc-conformance-")
        .tempdir()
        .expect("temp dir")
}

fn session() -> Session {
    match Project::load(&Paths::under(root())) {
        Ok(s) => Session::with_references(s),
        Err(e) => panic!("the corpus does not load:\n{e}"),
    }
}

/// The reference backend of a profile.
fn reference(session: &Session, profile: &str) -> Arc<dyn Backend> {
    session
        .backends
        .iter()
        .find(|b| b.profile() == profile)
        .cloned()
        .unwrap_or_else(|| panic!("no reference backend for {profile}"))
}

/// Whether a trial's case expects an operation error with a code, and is judged on it (not
/// `unspecified`).
fn expects_a_code(t: &Trial) -> bool {
    match &t.check {
        Check::Native { case, .. } => {
            case.basis != Basis::Unspecified
                && case
                    .expect
                    .as_ref()
                    .is_some_and(|e| matches!(e.error, Some(ErrorSignal::Code(_))))
        }
        _ => false,
    }
}

/// The error registers that do not hold the code, with what they held, when a verdict differs
/// on them alone (the words and the error signal as expected); `None` for any other verdict.
fn registers_alone(v: &Verdict) -> Option<Vec<(String, Option<Value>)>> {
    let Verdict::Differs {
        difference: Difference::Words { mismatches },
    } = v
    else {
        return None;
    };
    let m = mismatches.first()?;
    (!m.words_differ() && !m.error_differs()).then(|| {
        m.wrong_registers()
            .map(|r| (r.device.to_string(), r.actual))
            .collect()
    })
}

/// The Python of `.venv-adapters` when it imports `modules` (an import list, `a, b`), or `None`
/// with a note saying how to install `packages`; with PLC_CONFORMANCE_REQUIRE_BACKENDS set (as
/// in CI) a missing one fails the test instead of skipping it.
fn adapters_python(modules: &str, packages: &str) -> Option<std::path::PathBuf> {
    let python = root().join(".venv-adapters/bin/python");
    let ok = python.exists()
        && Command::new(&python)
            .args(["-c", &format!("import {modules}")])
            .output()
            .is_ok_and(|o| o.status.success());
    assert!(
        ok || std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
        "required from .venv-adapters: {packages}"
    );
    if !ok {
        eprintln!(
            "skipped: not installed: {packages}; install them with `python3 -m venv \
             .venv-adapters && .venv-adapters/bin/pip install -r adapters/python/requirements.txt`"
        );
    }
    ok.then_some(python)
}

/// The first trial the live backend would run whose instruction is `instruction`.
fn first_trial(project: &Session, backend: &Arc<BenchBackend>, instruction: &str) -> Trial {
    let b: Arc<dyn Backend> = backend.clone();
    project
        .plan(&[b])
        .into_iter()
        .find(|t| t.skip.is_none() && t.input.instruction == instruction)
        .unwrap_or_else(|| panic!("no {instruction} trial"))
}

/// Executes the trial's first request (fill A) once.
fn execute_once(backend: &BenchBackend, trial: &Trial) -> Result<Response, Fault> {
    let imgs = images(trial);
    let reqs = requests(trial, &imgs);
    backend.execute(&reqs[0])
}

/// A fault on the `nth` request of a command, whatever its device.
fn rule(command: u16, nth: usize, action: FaultAction) -> FaultRule {
    FaultRule {
        command,
        head: None,
        nth,
        action,
    }
}

/// A trial's identity across backends.
fn key(t: &Trial) -> (String, String, String) {
    (
        t.check_name().to_string(),
        t.case_id().to_string(),
        t.variant.clone(),
    )
}
