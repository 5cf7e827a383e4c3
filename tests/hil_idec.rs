//! An IDEC MicroSmart on a bench over Modbus TCP, against the simulated IDEC CPU on 127.0.0.1
//! only: the FC4A corpus judged exactly as the built-in model judges it, each fault of a port
//! mapped to its kind, the write fence and the interlocks refusing before anything is written,
//! a dry run that opens no socket, and the simulated CPU never recorded as observed. The same
//! bench layer as the MELSEC tests (tests/hil.rs), over the other link.

mod common;

use std::collections::BTreeMap;
use std::net::TcpListener;
use std::sync::Arc;
use std::time::Duration;

use plc_conformance::testing::backend::bench::fence::{parse_ranges, WordRange};
use plc_conformance::testing::backend::bench::manifest::Manifest;
use plc_conformance::testing::backend::bench::sim::{FaultAction, FaultRule};
use plc_conformance::testing::backend::bench::BenchBackend;
use plc_conformance::testing::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use plc_conformance::testing::backend::modbus::{Map, ModbusBench};
use plc_conformance::testing::error_chain::chain;
use plc_conformance::testing::hil::{dry_run, generate, GenerateOptions};
use plc_conformance::testing::plan::Check;
use plc_conformance::testing::session::{BackendSource, Session};
use plc_conformance::verdicts;
use plc_conformance::Trial;
use plc_conformance::Verdict;

use common::bench::{execute_once, first_trial, key, rule};
use common::{reference, session};

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
        Ok(plc_conformance::Response::Unsupported(why)) => assert!(
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

fn scratch_copy() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let scratch = common::scratch();
    let dir = scratch.path().join("vectors");
    std::fs::create_dir_all(&dir).expect("mkdir");
    for entry in std::fs::read_dir(common::root().join("vectors/idec-fc4a")).expect("dir") {
        let entry = entry.expect("entry");
        std::fs::copy(entry.path(), dir.join(entry.file_name())).expect("copy");
    }
    let manifest_file = scratch.path().join("manifest.json");
    std::fs::write(
        &manifest_file,
        serde_json::to_string_pretty(idec_manifest()).expect("json"),
    )
    .expect("write");
    (scratch, dir, manifest_file)
}

fn count(dir: &std::path::Path, text: &str) -> usize {
    std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| std::fs::read_to_string(e.expect("entry").path()).expect("read"))
        .map(|s| s.matches(text).count())
        .sum()
}

/// `run` through the command line with a `modbus:` backend, and `record` refusing to write
/// what the simulated CPU answered as observed.
#[test]
fn run_and_record_through_the_simulated_idec_cpu() {
    let project = session();
    let (_scratch, dir, manifest_file) = scratch_copy();
    let sim = idec_sim(&project, |_| {});
    let spec = format!(
        "modbus:bench={}?manifest={}&confirm={TYPE_CODE}&sandbox=manifest&variant={VARIANT}",
        sim.address(),
        manifest_file.display()
    );
    let out = common::cli(&[
        "run",
        "--backend",
        &spec,
        "--vectors",
        dir.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("bench"), "{stdout}");
    let before = count(&dir, "basis: observed");
    let out = common::cli(&[
        "record",
        "--backend",
        &spec,
        "--vectors",
        dir.to_str().expect("utf-8"),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the simulated CPU (plc-conformance hil sim)"),
        "{stderr}"
    );
    assert_eq!(count(&dir, "basis: observed"), before);
}

/// The `hil` commands through the binary for IDEC: `generate` writes the rung list, the manifest
/// and the checklist; `hil sim` serves the manifest over Modbus TCP; `doctor` reads it without
/// writing; `dry-run` plans every case without a socket; and `run` judges through it.
#[test]
fn the_hil_commands_through_the_binary() {
    use std::io::{BufRead, BufReader};
    let dir = common::scratch();
    let out_dir = dir.path().join("bench");
    let out = generate_bench(&out_dir);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in ["executive.txt", "manifest.json", "SETUP.md"] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let program = std::fs::read_to_string(out_dir.join("executive.txt")).expect("program");
    assert!(
        program.contains("ATOH(W) S1=D100 S2=4 D1=D200"),
        "{program}"
    );
    assert!(program.contains("RST M8004"), "{program}");
    let manifest_file = out_dir.join("manifest.json");
    let m = Manifest::load(&manifest_file, map().as_ref()).expect("the written manifest loads");
    assert_eq!(m.hash, idec_manifest().hash, "generate is deterministic");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin!("plc-conformance"))
        .args([
            "--root",
            common::root().to_str().expect("utf-8"),
            "hil",
            "sim",
        ])
        .args(["--manifest", manifest_file.to_str().expect("utf-8")])
        .args(["--type-code", &TYPE_CODE.to_string()])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("hil sim starts");
    let line = BufReader::new(child.stdout.take().expect("stdout"))
        .lines()
        .next()
        .expect("a line")
        .expect("text");
    let address = line
        .strip_prefix("listening on ")
        .unwrap_or_else(|| panic!("{line}"))
        .to_string();
    let spec = format!(
        "modbus:bench={address}?manifest={}&confirm={TYPE_CODE}&sandbox=manifest",
        manifest_file.display()
    );
    let doctor = common::cli(&["hil", "doctor", "--backend", &spec]);
    let self_test = common::cli(&["hil", "doctor", "--self-test", "--backend", &spec]);
    let dry = common::cli(&["hil", "dry-run", "--backend", &spec]);
    let run = common::cli(&["run", "--backend", &spec]);
    let _ = child.kill();
    let _ = child.wait();
    let shown = String::from_utf8_lossy(&doctor.stdout);
    assert!(doctor.status.success(), "{shown}");
    for line in [
        "ok    type name: type code 6 (D8002=0006H), as confirmed",
        "ok    operating status: RUN (M8000 on)",
        "ok    program signature",
        "ok    answered by: the simulated CPU",
    ] {
        assert!(shown.contains(line), "{line}: {shown}");
    }
    // The FC4A has no pulse form: a good bench passes the self-test, with the reason.
    let shown = String::from_utf8_lossy(&self_test.stdout);
    assert!(self_test.status.success(), "{shown}");
    assert!(
        shown.contains("ok    pulse self-test: nothing to fire twice: idec-fc4a has no pulse-form"),
        "{shown}"
    );
    let shown = String::from_utf8_lossy(&dry.stdout);
    assert!(dry.status.success(), "{shown}");
    assert!(
        shown.contains("no socket opened") && shown.contains("0 refused"),
        "{shown}"
    );
    let shown = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{shown}{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// A bench backend's link is its manifest's profile's: an IDEC CPU's manifest over SLMP is
/// refused before anything is planned, naming the link its profile benches over.
#[test]
fn a_bench_spec_whose_link_disagrees_with_its_profile_is_refused() {
    let dir = common::scratch();
    let out_dir = dir.path().join("bench");
    let generated = generate_bench(&out_dir);
    assert!(generated.status.success(), "{generated:?}");
    let manifest = out_dir.join("manifest.json");
    let over = |scheme: &str, confirm: &str| {
        common::cli(&[
            "hil",
            "dry-run",
            "--backend",
            &format!(
                "{scheme}:bench=127.0.0.1:5000?manifest={}&confirm={confirm}&sandbox=manifest",
                manifest.display()
            ),
        ])
    };
    let refused = over("slmp", "R04CPU");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("benched over Modbus TCP (`modbus:`), not SLMP (`slmp:`)"),
        "{stderr}"
    );
    // The same manifest over its own link plans.
    let planned = over("modbus", &TYPE_CODE.to_string());
    assert!(planned.status.success(), "{planned:?}");
}

/// `hil generate` for the FC4A variant of these tests, into `out_dir`.
fn generate_bench(out_dir: &std::path::Path) -> std::process::Output {
    common::cli(&[
        "hil",
        "generate",
        "--profile",
        PROFILE,
        "--variant",
        VARIANT,
        "--out",
        out_dir.to_str().expect("utf-8"),
    ])
}

/// A simulated CPU serves only what the backend would run against: the manifest's mailbox on a
/// variant without those words (D6000 on the C10R2) is refused before anything listens.
#[test]
fn a_simulated_cpu_refuses_a_mailbox_its_variant_does_not_have() {
    let dir = common::scratch();
    let out_dir = dir.path().join("bench");
    assert!(generate_bench(&out_dir).status.success());
    let manifest = out_dir.join("manifest.json");
    let out = common::cli(&[
        "hil",
        "sim",
        "--manifest",
        manifest.to_str().expect("utf-8"),
        "--variant",
        "c10r2",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("does not exist on variant c10r2 of idec-fc4a"),
        "{stderr}"
    );
}
