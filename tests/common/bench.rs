//! Shared by the tests of a bench backend (tests/hil.rs over SLMP, tests/hil_idec.rs over Modbus
//! TCP): picking a trial, running it once, a fault rule, a trial's identity across backends.

use std::sync::Arc;

use plc_conformance::testing::backend::bench::sim::{FaultAction, FaultRule};
use plc_conformance::testing::backend::bench::BenchBackend;
use plc_conformance::testing::execute::{images, requests};
use plc_conformance::testing::session::Session;
use plc_conformance::Trial;
use plc_conformance::{Backend, Fault, Response};

/// The first trial the live backend would run whose instruction is `instruction`.
pub fn first_trial(project: &Session, backend: &Arc<BenchBackend>, instruction: &str) -> Trial {
    let b: Arc<dyn Backend> = backend.clone();
    project
        .plan(&[b])
        .into_iter()
        .find(|t| t.skip.is_none() && t.input.instruction == instruction)
        .unwrap_or_else(|| panic!("no {instruction} trial"))
}

/// Executes the trial's first request (fill A) once.
pub fn execute_once(backend: &BenchBackend, trial: &Trial) -> Result<Response, Fault> {
    let imgs = images(trial);
    let reqs = requests(trial, &imgs);
    backend.execute(&reqs[0])
}

/// A fault on the `nth` request of a command, whatever its device.
pub fn rule(command: u16, nth: usize, action: FaultAction) -> FaultRule {
    FaultRule {
        command,
        head: None,
        nth,
        action,
    }
}

/// A trial's identity across backends.
pub fn key(t: &Trial) -> (String, String, String) {
    (
        t.check_name().to_string(),
        t.case_id().to_string(),
        t.variant.clone(),
    )
}
