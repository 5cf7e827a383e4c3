//! An IDEC MicroSmart on a bench over Modbus TCP, against the simulated IDEC CPU on 127.0.0.1
//! only: the FC4A corpus judged exactly as the built-in model judges it, each fault of a port
//! mapped to its kind, the write fence and the interlocks refusing before anything is written,
//! and a dry run that opens no socket. The same bench layer as the MELSEC tests (slmp.rs), over
//! the other link.

#[cfg(test)]
use std::collections::BTreeMap;
use std::net::TcpListener;
use std::sync::Arc;
use std::time::Duration;

use crate::backend::bench::fence::{parse_ranges, WordRange};
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::sim::{FaultAction, FaultRule};
use crate::backend::bench::BenchBackend;
use crate::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use crate::backend::modbus::{Map, ModbusBench};
use crate::error_chain::chain;
use crate::hil::{dry_run, generate, GenerateOptions};
use crate::plan::Check;
use crate::session::{BackendSource, Session};
use crate::{verdicts, Trial, Verdict};

use super::{execute_once, first_trial, key, reference, rule, session};

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

fn idec_backend(
    project: &Session,
    sim: &ModbusSimulator,
    change: impl FnOnce(&mut ModbusBench),
) -> Arc<BenchBackend> {
    let mut s = settings(sim.address().to_string());
    change(&mut s);
    Arc::new(BenchBackend::new(s, &project.profiles).expect("backend"))
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
    let backend = project
        .add(
            BackendSource::Bench(Box::new(settings(sim.address().to_string()).erased())),
            true,
        )
        .unwrap_or_else(|e| panic!("interlocks: {}", chain(&e)))[0]
        .clone();
    let expected: BTreeMap<_, _> = {
        let trials: Vec<Trial> = project
            .plan(std::slice::from_ref(&model))
            .into_iter()
            .filter(|t| t.variant == VARIANT)
            .collect();
        let v = verdicts(&trials);
        trials.iter().map(key).zip(v).collect()
    };
    let trials = project.plan(std::slice::from_ref(&backend));
    let got = verdicts(&trials);
    let (mut ran, mut errors) = (0, 0);
    for (t, v) in trials.iter().zip(&got) {
        if t.variant != VARIANT {
            assert!(t.skip.is_some(), "{}: run on another variant", t.name());
            continue;
        }
        let want = expected.get(&key(t));
        match (&t.skip, want) {
            (_, None) => panic!("{}: no such trial on the built-in model", t.name()),
            (Some(why), Some(w)) => assert!(
                matches!(w, Verdict::Skipped { .. }) || why.contains("no program can hold"),
                "{}: skipped ({why}) where the model ran it",
                t.name()
            ),
            (None, Some(w)) => {
                ran += 1;
                assert_eq!(v, w, "{}", t.name());
                errors += usize::from(expects_an_error(t));
            }
        }
    }
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
    let project = session();
    let sim = idec_sim(&project, |_| {});
    let backend = idec_backend(&project, &sim, |_| {});
    backend.connect().expect("interlocks");
    let trial = first_trial(&project, &backend, "ATOH");
    execute_once(&backend, &trial).expect("a case before the fault runs");
    sim.add_fault(fault);
    let e = execute_once(&backend, &trial).expect_err("the fault shows");
    assert_eq!(e.kind(), kind, "{e}");
    assert!(e.to_string().contains(expected), "{e}");
}

#[test]
fn no_connection_is_unreachable() {
    let project = session();
    let address = {
        let l = TcpListener::bind("127.0.0.1:0").expect("bind");
        l.local_addr().expect("addr").to_string()
    };
    let mut s = settings(address);
    s.link.client.read_retries = 0;
    let backend = Arc::new(BenchBackend::new(s, &project.profiles).expect("backend"));
    assert!(chain(&backend.connect().expect_err("refused")).contains("no connection to"));
    let trial = first_trial(&project, &backend, "ATOH");
    assert_eq!(
        execute_once(&backend, &trial).expect_err("down").kind(),
        "unreachable"
    );
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
    let project = session();
    let sim = idec_sim(&project, change);
    let backend = idec_backend(&project, &sim, |_| {});
    let e = chain(&backend.connect().expect_err("refused"));
    assert!(e.contains(expected), "{e}");
    let trial = first_trial(&project, &backend, "ATOH");
    assert!(execute_once(&backend, &trial).is_err());
    assert_eq!(writes_sent(&sim), 0, "a write went out");
}

/// A case whose window lies outside the sandbox is refused while it is still a plan: nothing
/// reaches the simulated CPU, which audits every request.
#[test]
fn a_write_outside_the_sandbox_is_refused_before_any_byte_is_sent() {
    let project = session();
    let sim = idec_sim(&project, |_| {});
    let backend = idec_backend(&project, &sim, |s| {
        s.sandbox = vec![WordRange::new("D", 0, 5)]
    });
    backend.connect().expect("interlocks");
    let trial = first_trial(&project, &backend, "ATOH");
    match execute_once(&backend, &trial) {
        Ok(crate::Response::Unsupported(why)) => assert!(
            why.contains("is refused: it lies outside the words the harness may write"),
            "{why}"
        ),
        other => panic!("not refused: {other:?}"),
    }
    assert_eq!(writes_sent(&sim), 0);
}

/// A sandbox of relays (bit devices) is refused when the backend is built.
#[test]
fn a_sandbox_of_relays_is_refused() {
    let project = session();
    let mut s = settings("127.0.0.1:9".into());
    s.sandbox = vec![WordRange::new("M", 0, 17)];
    let e = chain(
        &BenchBackend::new(s, &project.profiles)
            .err()
            .expect("refused"),
    );
    assert!(e.contains("word devices only"), "{e}");
}

#[test]
fn a_dry_run_opens_no_socket() {
    let project = session();
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
    listener.set_nonblocking(true).expect("nonblocking");
    let s = settings(listener.local_addr().expect("addr").to_string());
    let backend = Arc::new(BenchBackend::new(s, &project.profiles).expect("backend"));
    let found = dry_run(&project, &backend);
    assert!(found.trials > 20, "{found:?}");
    assert_eq!(found.executions, 2 * found.trials);
    assert!(found.refused.is_empty(), "{:?}", found.refused);
    assert!(listener.accept().is_err(), "the dry run connected");
    assert_eq!(backend.requests(), 0);
}

/// The program resets M8004 itself before each case; on a CPU where the flag stays on, the case
/// is not executed and says so (never a result).
#[test]
fn an_error_flag_that_stays_on_fails_the_case_as_not_executed() {
    let project = session();
    let sim = idec_sim(&project, |_| {});
    let backend = idec_backend(&project, &sim, |_| {});
    backend.connect().expect("interlocks");
    let trial = first_trial(&project, &backend, "ATOH");
    sim.hold_error_flag(true);
    let e = execute_once(&backend, &trial).expect_err("not executed");
    assert!(
        e.to_string()
            .contains("the error flag M8004 stayed on after the error reset"),
        "{e}"
    );
}
