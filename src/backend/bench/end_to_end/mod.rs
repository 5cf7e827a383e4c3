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

mod idec;
mod modbus;
mod slmp;
mod slmp_cross;

/// The trials the backend would run (not skipped), in plan order.
fn runnable(project: &Session, backend: &Arc<dyn Backend>) -> impl Iterator<Item = Trial> {
    let planned = project.plan(std::slice::from_ref(backend));
    planned.into_iter().filter(|t| t.skip.is_none())
}

/// The first trial the live backend would run whose instruction is `instruction`.
fn first_trial(project: &Session, backend: &Arc<BenchBackend>, instruction: &str) -> Trial {
    let b: Arc<dyn Backend> = backend.clone();
    runnable(project, &b)
        .find(|t| t.input.instruction == instruction)
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

/// The backend built from `settings`, checked against the session's profiles; no connection.
fn bench<L: crate::backend::bench::LinkSettings + Clone + 'static>(
    project: &Session,
    settings: crate::backend::bench::BenchSettings<L>,
) -> Arc<BenchBackend> {
    Arc::new(BenchBackend::new(settings, &project.profiles).expect("backend"))
}

/// Why a backend of `settings` is refused when it is built.
fn refused_at_build<L: crate::backend::bench::LinkSettings + Clone + 'static>(
    project: &Session,
    settings: crate::backend::bench::BenchSettings<L>,
) -> String {
    crate::error_chain::chain(
        &BenchBackend::new(settings, &project.profiles)
            .err()
            .expect("refused"),
    )
}

/// The live backend of `settings` added to the session, past its interlocks.
fn live<L: crate::backend::bench::LinkSettings + Clone + 'static>(
    project: &mut Session,
    settings: crate::backend::bench::BenchSettings<L>,
) -> Arc<dyn Backend> {
    project
        .add(
            crate::session::BackendSource::Bench(Box::new(settings.erased())),
            true,
        )
        .unwrap_or_else(|e| panic!("interlocks: {}", crate::error_chain::chain(&e)))[0]
        .clone()
}

/// A port on 127.0.0.1 that was free a moment ago: nothing listens there.
fn free_address() -> String {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    l.local_addr().expect("addr").to_string()
}

/// A listener on 127.0.0.1 that never blocks: `accept` tells whether anything connected.
fn idle_listener() -> std::net::TcpListener {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    listener.set_nonblocking(true).expect("nonblocking");
    listener
}

/// The built-in model's verdict on every trial of `variant`, by the trial's identity.
fn model_verdicts(
    project: &Session,
    model: &Arc<dyn Backend>,
    variant: &str,
) -> std::collections::BTreeMap<(String, String, String), crate::Verdict> {
    let trials: Vec<Trial> = project
        .plan(std::slice::from_ref(model))
        .into_iter()
        .filter(|t| t.variant == variant)
        .collect();
    let v = crate::verdicts(&trials);
    trials.iter().map(key).zip(v).collect()
}

/// Holds each verdict `got` on `trials` to the model's in `expected`: a trial of another
/// variant than `variant` is skipped, one skipped here is skipped by the model too or for one of
/// `skip_reasons`, and one that ran gets the model's verdict. Returns the trials that ran.
fn ran_as_the_model<'a>(
    trials: &'a [Trial],
    got: &[crate::Verdict],
    expected: &std::collections::BTreeMap<(String, String, String), crate::Verdict>,
    variant: &str,
    skip_reasons: &[&str],
) -> Vec<&'a Trial> {
    let mut ran = Vec::new();
    for (t, v) in trials.iter().zip(got) {
        if t.variant != variant {
            assert!(t.skip.is_some(), "{}: run on another variant", t.name());
            continue;
        }
        let want = expected.get(&key(t));
        match (&t.skip, want) {
            (_, None) => panic!("{}: no such trial on the built-in model", t.name()),
            (Some(why), Some(w)) => assert!(
                matches!(w, crate::Verdict::Skipped { .. })
                    || skip_reasons.iter().any(|r| why.contains(*r)),
                "{}: skipped ({why}) where the model ran it",
                t.name()
            ),
            (None, Some(w)) => {
                assert_eq!(v, w, "{}", t.name());
                ran.push(t);
            }
        }
    }
    ran
}

/// A simulated CPU, and a backend on it.
type OnSim<L> = (crate::backend::bench::sim::Running<L>, Arc<BenchBackend>);

/// The simulated CPU and the backend on it, past the backend's interlocks.
fn connected<L>((sim, backend): OnSim<L>) -> OnSim<L> {
    backend.connect().expect("interlocks");
    (sim, backend)
}

/// On the simulated CPU and the backend `setup` gives, past its interlocks: after a first run
/// of the trial of `instruction`, `fault` is reported as its `kind`, with `expected` a part of
/// the message.
fn assert_fault_reported<L: Send + Sync + 'static>(
    setup: impl FnOnce(&Session) -> OnSim<L>,
    instruction: &str,
    fault: FaultRule,
    kind: &str,
    expected: &str,
) {
    let project = session();
    let (sim, backend) = connected(setup(&project));
    let trial = first_trial(&project, &backend, instruction);
    execute_once(&backend, &trial).expect("a case before the fault runs");
    // A rule counts the requests from when it is added: 1 is the next one.
    sim.add_fault(fault);
    let e = execute_once(&backend, &trial).expect_err("the fault shows");
    assert_eq!(e.kind(), kind, "{e}");
    assert!(e.to_string().contains(expected), "{e}");
}

/// With nothing listening at the backend's address, the interlocks find no connection and the
/// trial of `instruction` is unreachable.
fn assert_unreachable(project: &Session, backend: &Arc<BenchBackend>, instruction: &str) {
    assert!(
        crate::error_chain::chain(&backend.connect().expect_err("refused"))
            .contains("no connection to")
    );
    let trial = first_trial(project, backend, instruction);
    assert_eq!(
        execute_once(backend, &trial).expect_err("down").kind(),
        "unreachable"
    );
}

/// On the simulated CPU and the backend `setup` gives, an interlock refuses with `expected` in
/// its message, the trial of `instruction` does not run, and `writes_sent` counts no write on
/// the simulated CPU.
fn assert_interlock_refuses<L>(
    setup: impl FnOnce(&Session) -> OnSim<L>,
    instruction: &str,
    expected: &str,
    writes_sent: impl Fn(&crate::backend::bench::sim::Running<L>) -> usize,
) {
    let project = session();
    let (sim, backend) = setup(&project);
    let e = crate::error_chain::chain(&backend.connect().expect_err("refused"));
    assert!(e.contains(expected), "{e}");
    let trial = first_trial(&project, &backend, instruction);
    assert!(execute_once(&backend, &trial).is_err());
    assert_eq!(writes_sent(&sim), 0, "a write went out");
}

/// The trial's first request is refused by the fence while it is still a plan.
fn assert_refused_by_the_fence(backend: &BenchBackend, trial: &Trial) {
    match execute_once(backend, trial) {
        Ok(Response::Unsupported(why)) => assert!(
            why.contains("is refused: it lies outside the words the harness may write"),
            "{why}"
        ),
        other => panic!("not refused: {other:?}"),
    }
}

/// A dry run of the backend `settings` makes for a listener's address plans more than
/// `more_than` trials, two executions each, none refused, and opens no socket.
fn assert_dry_run_opens_no_socket<L: crate::backend::bench::LinkSettings + Clone + 'static>(
    more_than: usize,
    settings: impl FnOnce(String) -> crate::backend::bench::BenchSettings<L>,
) {
    let project = session();
    let listener = idle_listener();
    let backend = bench(
        &project,
        settings(listener.local_addr().expect("addr").to_string()),
    );
    let found = crate::hil::dry_run(&project, &backend);
    assert!(found.trials > more_than, "{found:?}");
    assert_eq!(found.executions, 2 * found.trials);
    assert!(found.refused.is_empty(), "{:?}", found.refused);
    assert!(listener.accept().is_err(), "the dry run connected");
    assert_eq!(backend.requests(), 0);
}

/// The stdout of a process that must have succeeded; if it failed, the message is `context`,
/// then all it printed.
fn succeeded(out: &std::process::Output, context: &str) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{context}{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout.into_owned()
}

/// A simulated SLMP CPU of `manifest`'s profile running its program as `variant`, named
/// `type_name`, its settings changed by `change`.
fn slmp_simulator(
    project: &Session,
    manifest: &crate::backend::bench::manifest::Manifest,
    variant: &str,
    type_name: &str,
    change: impl FnOnce(&mut crate::backend::slmp::sim::SlmpSimSettings),
) -> crate::backend::slmp::sim::SlmpSimulator {
    let profile = project
        .profiles
        .get(&manifest.profile)
        .cloned()
        .expect("profile");
    let mut settings =
        crate::backend::slmp::sim::SlmpSimSettings::new(manifest.clone(), variant, type_name);
    change(&mut settings);
    crate::backend::slmp::sim::SlmpSimulator::start(
        settings,
        profile,
        reference(project, &manifest.profile),
    )
    .unwrap_or_else(|e| panic!("simulator: {e}"))
}
