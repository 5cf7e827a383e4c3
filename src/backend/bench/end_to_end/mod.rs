//! The bench end to end on 127.0.0.1: the SLMP and Modbus TCP clients, the simulated CPUs and
//! the bench backend held to the built-in models' verdicts, to each fault's kind, to the fence
//! and the interlocks, and to independent implementations of both protocols. White-box tests of
//! the crate's own parts, with no binary to run, so they live beside the code they reach into.

#[cfg(test)]
pub(super) use crate::test_support::{
    adapters_python, expects_a_code, reference, registers_alone, root, scratch, session,
};
use std::sync::Arc;

use crate::backend::bench::sim::{FaultAction, FaultRule};
use crate::backend::bench::BenchBackend;
use crate::execute::{images, requests};
use crate::session::Session;
use crate::{Backend, Fault, Response, Trial};

mod aslmp;
mod idec;
mod modbus;
mod slmp;
mod slmp_cross;

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
