//! An IDEC MicroSmart on a bench over Modbus TCP, against the simulated IDEC CPU on 127.0.0.1
//! only: the FC4A corpus judged exactly as the built-in model judges it, each fault of a port
//! mapped to its kind, the write fence and the interlocks refusing before anything is written,
//! and a dry run that opens no socket. The same bench layer as the MELSEC tests (slmp.rs), over
//! the other link.

#[cfg(test)]
use std::sync::Arc;
use std::time::Duration;

use crate::backend::bench::fence::{parse_ranges, WordRange};
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::sim::{FaultAction, FaultRule};
use crate::backend::bench::BenchBackend;
use crate::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use crate::backend::modbus::{Map, ModbusBench};
use crate::error_chain::chain;
use crate::hil::{generate, GenerateOptions};
use crate::plan::Check;
use crate::session::Session;
use crate::{verdicts, Trial};

use super::{
    assert_dry_run_opens_no_socket, assert_fault_reported, assert_interlock_refuses,
    assert_refused_by_the_fence, assert_unreachable, bench, connected, execute_once, first_trial,
    free_address, live, model_verdicts, ran_as_the_model, reference, refused_at_build, rule,
    session,
};

const PROFILE: &str = "idec-fc4a";
/// The variant the simulated CPU is: D0-D1299 and the expansion D2000-D7999.
const VARIANT: &str = "d40k3";
/// The type code the simulated CPU holds in D8002, and what `confirm=` names.
const TYPE_CODE: u16 = 6;

/// Modbus function codes, as the simulated CPU counts requests.
const READ_COILS: u16 = 0x01;
const READ_HOLDING: u16 = 0x03;
const WRITE_SINGLE: u16 = 0x06;
const WRITE_MULTIPLE: u16 = 0x10;

/// The FC4A manifest of one variant, generated once for every test of this file.
fn idec_manifest() -> &'static Manifest {
    static M: std::sync::OnceLock<Manifest> = std::sync::OnceLock::new();
    M.get_or_init(|| {
        generate(
            &session(),
            &GenerateOptions {
                profile: PROFILE.into(),
                variants: vec![VARIANT.into()],
                ..GenerateOptions::default()
            },
        )
        .unwrap_or_else(|e| panic!("generate: {}", chain(&e)))
        .manifest
    })
}

/// A simulated FC4A set up by `change`.
fn idec_sim(project: &Session, change: impl FnOnce(&mut ModbusSimSettings)) -> ModbusSimulator {
    let m = idec_manifest();
    let profile = project.profiles.get(&m.profile).cloned().expect("profile");
    let mut s = ModbusSimSettings::idec(m.clone(), VARIANT, TYPE_CODE);
    change(&mut s);
    ModbusSimulator::start(s, profile, reference(project, PROFILE)).expect("simulator")
}

/// The FC4A profile's Modbus map.
fn map() -> Arc<Map> {
    let project = session();
    Arc::new(Map::of(project.profiles.get(PROFILE).expect("profile")).expect("a Modbus map"))
}

fn settings(address: String) -> ModbusBench {
    let m = idec_manifest();
    let map = map();
    let sandbox = parse_ranges(&m.writes.join(","), map.as_ref()).expect("writes");
    let mut s = ModbusBench::modbus(
        "live",
        address,
        map,
        m.clone(),
        VARIANT,
        TYPE_CODE.to_string(),
        sandbox,
    );
    s.first_poll = Duration::from_micros(300);
    s.max_poll = Duration::from_millis(2);
    s.link.client.reply_timeout = Duration::from_millis(500);
    s.case_timeout = Duration::from_millis(800);
    s
}

/// A simulated FC4A set up by `change_sim`, and a backend on it set up by `change`.
fn idec_bench(
    project: &Session,
    change_sim: impl FnOnce(&mut ModbusSimSettings),
    change: impl FnOnce(&mut ModbusBench),
) -> (ModbusSimulator, Arc<BenchBackend>) {
    let sim = idec_sim(project, change_sim);
    let mut s = settings(sim.address().to_string());
    change(&mut s);
    (sim, bench(project, s))
}

fn writes_sent(sim: &ModbusSimulator) -> usize {
    let commands = sim.audit().commands;
    [WRITE_SINGLE, WRITE_MULTIPLE]
        .iter()
        .map(|c| commands.get(c).copied().unwrap_or(0))
        .sum()
}

/// Whether the trial's case expects M8004.
fn expects_an_error(t: &Trial) -> bool {
    match &t.check {
        Check::Native { case, .. } => case.expect.as_ref().is_some_and(|e| e.error.is_some()),
        _ => false,
    }
}

/// Every FC4A trial of the variant through the Modbus link and the simulated CPU gets the
/// verdict the built-in model gives it; a trial the program cannot hold (an operand the Modbus
/// map does not reach) is skipped with that reason, and nothing outside the manifest's words
/// is written.
#[test]
fn fc4a_through_the_simulated_idec_cpu_judges_like_the_model() {
    let mut project = session();
    let sim = idec_sim(&project, |_| {});
    let model = reference(&project, PROFILE);
    let backend = live(&mut project, settings(sim.address().to_string()));
    let expected = model_verdicts(&project, &model, VARIANT);
    let trials = project.plan(std::slice::from_ref(&backend));
    let got = verdicts(&trials);
    let ran = ran_as_the_model(&trials, &got, &expected, VARIANT, &["no program can hold"]);
    let errors = ran.iter().filter(|t| expects_an_error(t)).count();
    let ran = ran.len();
    let audit = sim.audit();
    assert!(audit.stray_writes.is_empty(), "{:?}", audit.stray_writes);
    assert!(audit.anomalies.is_empty(), "{:?}", audit.anomalies);
    let sent: Vec<u16> = audit.commands.keys().copied().collect();
    assert!(
        sent.iter()
            .all(|c| [READ_COILS, READ_HOLDING, WRITE_SINGLE, WRITE_MULTIPLE].contains(c)),
        "only 01, 03, 06 and 16 are ever sent: {sent:02X?}"
    );
    eprintln!(
        "{PROFILE} {VARIANT}: {ran} trials ({errors} with M8004), {} executions, {} requests",
        audit.executions,
        audit.commands.values().sum::<usize>()
    );
    assert!(ran > 20, "{ran} trials ran");
    assert!(errors > 0, "no case raised M8004 through the link");
}

/// Each fault of a Modbus port, injected on the next request of its function, is reported as
/// its kind; `expected` is a part of the message.
#[rstest::rstest]
#[case::connection_dropped_during_a_write(
    rule(WRITE_MULTIPLE, 1, FaultAction::Drop),
    "crashed",
    "connection was lost"
)]
#[case::reply_past_the_timeout(
    rule(WRITE_MULTIPLE, 1, FaultAction::Delay(Duration::from_millis(900))),
    "timeout",
    "no reply to FC16"
)]
#[case::exception(
    rule(WRITE_MULTIPLE, 1, FaultAction::EndCode(4)),
    "protocol-error",
    "exception 04 (SERVER DEVICE FAILURE)"
)]
#[case::garbage_bytes(
    rule(READ_HOLDING, 1, FaultAction::Garbage),
    "protocol-error",
    "not a valid Modbus TCP response"
)]
#[case::another_transaction(
    rule(READ_HOLDING, 1, FaultAction::WrongSerial),
    "protocol-error",
    "transaction"
)]
#[case::cpu_leaves_run(rule(READ_COILS, 1, FaultAction::Stop), "unreachable", "left RUN")]
fn a_port_fault_is_reported_as_its_kind(
    #[case] fault: FaultRule,
    #[case] kind: &str,
    #[case] expected: &str,
) {
    assert_fault_reported(
        |p| idec_bench(p, |_| {}, |_| {}),
        "ATOH",
        fault,
        kind,
        expected,
    );
}

#[test]
fn no_connection_is_unreachable() {
    let project = session();
    let mut s = settings(free_address());
    s.link.client.read_retries = 0;
    assert_unreachable(&project, &bench(&project, s), "ATOH");
}

/// Nothing is written before the type code, the start control relay and the program's
/// signature match: each interlock refuses on its own.
#[rstest::rstest]
#[case::another_cpu(|s: &mut ModbusSimSettings| s.link.type_code = 3, "`confirm` says `6`")]
#[case::cpu_in_stop(|s: &mut ModbusSimSettings| s.run = false, "STOP (M8000 off)")]
#[case::no_program(|s: &mut ModbusSimSettings| s.program = false, "no test program signature")]
fn an_interlock_refuses_before_any_write(
    #[case] change: fn(&mut ModbusSimSettings),
    #[case] expected: &str,
) {
    assert_interlock_refuses(
        |p| idec_bench(p, change, |_| {}),
        "ATOH",
        expected,
        writes_sent,
    );
}

/// A case whose window lies outside the sandbox is refused while it is still a plan: nothing
/// reaches the simulated CPU, which audits every request.
#[test]
fn a_write_outside_the_sandbox_is_refused_before_any_byte_is_sent() {
    let project = session();
    let (sim, backend) = connected(idec_bench(
        &project,
        |_| {},
        |s| s.sandbox = vec![WordRange::new("D", 0, 5)],
    ));
    let trial = first_trial(&project, &backend, "ATOH");
    assert_refused_by_the_fence(&backend, &trial);
    assert_eq!(writes_sent(&sim), 0);
}

/// A sandbox of relays (bit devices) is refused when the backend is built.
#[test]
fn a_sandbox_of_relays_is_refused() {
    let project = session();
    let mut s = settings("127.0.0.1:9".into());
    s.sandbox = vec![WordRange::new("M", 0, 17)];
    let e = refused_at_build(&project, s);
    assert!(e.contains("word devices only"), "{e}");
}

#[test]
fn a_dry_run_opens_no_socket() {
    assert_dry_run_opens_no_socket(20, settings);
}

/// The program resets M8004 itself before each case; on a CPU where the flag stays on, the case
/// is not executed and says so (never a result).
#[test]
fn an_error_flag_that_stays_on_fails_the_case_as_not_executed() {
    let project = session();
    let (sim, backend) = connected(idec_bench(&project, |_| {}, |_| {}));
    let trial = first_trial(&project, &backend, "ATOH");
    sim.hold_error_flag(true);
    let e = execute_once(&backend, &trial).expect_err("not executed");
    assert!(
        e.to_string()
            .contains("the error flag M8004 stayed on after the error reset"),
        "{e}"
    );
}
