//! The live CPU backend against the simulated CPU, on 127.0.0.1 only: the whole corpus judged
//! exactly as the built-in models judge it, each fault of a port mapped to its kind, the write
//! fence and the interlocks refusing before anything is written, and a dry run that opens no
//! socket. What goes through the binary (`hil sim`, `hil doctor`, `record`) is in tests/hil.rs.

#[cfg(test)]
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::backend::bench::fence::{parse_ranges, WordRange};
use crate::backend::bench::mailbox;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::sim::FaultAction;
use crate::backend::bench::BenchBackend;
use crate::backend::slmp::frame::{command, DeviceForm, FrameKind};
use crate::backend::slmp::sim::{FaultRule, SlmpSimSettings, SlmpSimulator};
use crate::backend::slmp::{SlmpBench, ADDRESSING};
use crate::error_chain::chain;
use crate::execute::{images, requests};
use crate::hil::{dry_run, generate, GenerateOptions};
use crate::session::Session;
use crate::{verdicts, Backend, Device, Trial, Verdict};

use super::{
    assert_dry_run_opens_no_socket, assert_fault_reported, assert_interlock_refuses,
    assert_refused_by_the_fence, assert_unreachable, bench, connected, execute_once, first_trial,
    free_address, idle_listener, live, model_verdicts, ran_as_the_model, reference,
    refused_at_build, rule, runnable, session, slmp_simulator,
};

fn manifest(project: &Session, profile: &str) -> Manifest {
    generate(
        project,
        &GenerateOptions {
            profile: profile.into(),
            ..GenerateOptions::default()
        },
    )
    .unwrap_or_else(|e| panic!("generate {profile}: {e}"))
    .manifest
}

fn type_name(profile: &str) -> &'static str {
    if profile == "mitsubishi-fx5" {
        "FX5U-32MT/DS"
    } else {
        "R04CPU"
    }
}

fn simulator(
    project: &Session,
    manifest: &Manifest,
    variant: &str,
    faults: Vec<FaultRule>,
) -> SlmpSimulator {
    let name = type_name(&manifest.profile);
    slmp_simulator(project, manifest, variant, name, |s| s.faults = faults)
}

fn settings(manifest: &Manifest, variant: &str, sim: &SlmpSimulator) -> SlmpBench {
    let sandbox = parse_ranges(&manifest.writes.join(","), &ADDRESSING).expect("writes");
    let mut s = SlmpBench::new(
        "live",
        sim.address().to_string(),
        manifest.clone(),
        variant,
        type_name(&manifest.profile),
        sandbox,
    );
    s.first_poll = Duration::from_micros(300);
    s.max_poll = Duration::from_millis(2);
    s.link.reply_timeout = Duration::from_millis(500);
    s.case_timeout = Duration::from_millis(800);
    s
}

/// Runs every trial of one variant through the live backend and compares each verdict with the
/// built-in model's; returns how many ran.
fn same_verdicts(profile: &str, variant: &str) -> usize {
    let mut project = session();
    let manifest = manifest(&project, profile);
    let sim = simulator(&project, &manifest, variant, vec![]);
    let model = reference(&project, profile);
    let backend = live(&mut project, settings(&manifest, variant, &sim));
    let expected = model_verdicts(&project, &model, variant);
    let trials = project.plan(std::slice::from_ref(&backend));
    let started = Instant::now();
    let got = verdicts(&trials);
    let elapsed = started.elapsed();
    let skip_reasons = ["no program can hold", "program cannot hold the case"];
    let ran = ran_as_the_model(&trials, &got, &expected, variant, &skip_reasons).len();
    let audit = sim.audit();
    assert!(
        audit.stray_writes.is_empty(),
        "stray writes: {:?}",
        audit.stray_writes
    );
    assert!(audit.anomalies.is_empty(), "{:?}", audit.anomalies);
    let sent: Vec<u16> = audit.commands.keys().copied().collect();
    assert!(
        sent.iter().all(|c| [
            command::READ_TYPE_NAME,
            command::READ,
            command::RANDOM_READ,
            command::WRITE
        ]
        .contains(c)),
        "only 0101, 0401, 0403 and 1401 are ever sent: {sent:04X?}"
    );
    eprintln!(
        "{profile} {variant}: {ran} trials, {} executions, {} requests in {:.2} s",
        audit.executions,
        audit.commands.values().sum::<usize>(),
        elapsed.as_secs_f64()
    );
    assert!(ran > 0);
    ran
}

#[test]
fn iqr_through_the_simulated_cpu_judges_like_the_model() {
    let ran =
        same_verdicts("mitsubishi-iqr", "rcpu") + same_verdicts("mitsubishi-iqr", "rcpu-no-sm705");
    assert!(ran > 300, "{ran}");
}

#[test]
fn fx5_through_the_simulated_cpu_judges_like_the_model() {
    let project = session();
    let profile = project
        .profiles
        .get("mitsubishi-fx5")
        .cloned()
        .expect("fx5");
    for v in &profile.variants {
        assert!(same_verdicts("mitsubishi-fx5", &v.id) > 200, "{}", v.id);
    }
}

/// A CPU that signals the code in SD0 but leaves SD8067 alone: every FX5 error trial differs,
/// on that register only, and nothing else changes (no fault: the CPU answered).
#[test]
fn an_fx5_that_leaves_sd8067_alone_differs_on_every_error() {
    let mut project = session();
    let manifest = manifest(&project, "mitsubishi-fx5");
    let profile = project
        .profiles
        .get("mitsubishi-fx5")
        .cloned()
        .expect("fx5");
    let mut sim_settings =
        SlmpSimSettings::new(manifest.clone(), "fx5u", type_name("mitsubishi-fx5"));
    sim_settings.untouched_registers = vec!["SD8067".parse().expect("SD8067")];
    let sim = SlmpSimulator::start(sim_settings, profile, reference(&project, "mitsubishi-fx5"))
        .expect("simulator");
    let backend = live(&mut project, settings(&manifest, "fx5u", &sim));
    let trials: Vec<Trial> = runnable(&project, &backend)
        .filter(|t| t.variant == "fx5u")
        .collect();
    let mut errors = 0;
    for (t, v) in trials.iter().zip(verdicts(&trials)) {
        if !super::expects_a_code(t) {
            assert!(!v.is_failure(), "{}: {v:?}", t.name());
            continue;
        }
        errors += 1;
        let wrong = super::registers_alone(&v);
        assert_eq!(
            wrong
                .as_ref()
                .map(|w| w.iter().map(|(d, _)| d.as_str()).collect::<Vec<_>>()),
            Some(vec!["SD8067"]),
            "{}: {v:?}",
            t.name()
        );
    }
    assert!(errors > 20, "{errors} error trials");
}

// --- One case at a time: faults, interlocks, the fence, the dry run ------------------------------

/// The iQ-R manifest, generated once for every test of this file.
fn iqr_manifest() -> &'static Manifest {
    static M: std::sync::OnceLock<Manifest> = std::sync::OnceLock::new();
    M.get_or_init(|| manifest(&session(), "mitsubishi-iqr"))
}

/// A simulated iQ-R CPU (4E frames, long device form) set up by `change`.
fn iqr_sim(project: &Session, change: impl FnOnce(&mut SlmpSimSettings)) -> SlmpSimulator {
    let m = iqr_manifest();
    let profile = project.profiles.get(&m.profile).cloned().expect("profile");
    let mut s = SlmpSimSettings::new(m.clone(), "rcpu", "R04CPU");
    change(&mut s);
    SlmpSimulator::start(s, profile, reference(project, &m.profile)).expect("simulator")
}

fn iqr_backend(
    project: &Session,
    sim: &SlmpSimulator,
    change: impl FnOnce(&mut SlmpBench),
) -> Arc<BenchBackend> {
    let mut s = settings(iqr_manifest(), "rcpu", sim);
    change(&mut s);
    bench(project, s)
}

/// A simulated iQ-R CPU set up by `change`, and a backend on it.
fn iqr_bench(
    project: &Session,
    change: impl FnOnce(&mut SlmpSimSettings),
) -> (SlmpSimulator, Arc<BenchBackend>) {
    let sim = iqr_sim(project, change);
    let backend = iqr_backend(project, &sim, |_| {});
    (sim, backend)
}

/// Settings for the iQ-R program at `address`, with the default timings, writing `sandbox`.
fn iqr_settings_at(address: impl Into<String>, sandbox: Vec<WordRange>) -> SlmpBench {
    SlmpBench::new(
        "live",
        address,
        iqr_manifest().clone(),
        "rcpu",
        "R04CPU",
        sandbox,
    )
}

/// The words of the iQ-R manifest's windows.
fn iqr_sandbox() -> Vec<WordRange> {
    parse_ranges(&iqr_manifest().writes.join(","), &ADDRESSING).expect("writes")
}

fn writes_sent(sim: &SlmpSimulator) -> usize {
    sim.audit()
        .commands
        .get(&command::WRITE)
        .copied()
        .unwrap_or(0)
}

/// Each fault of a port, injected on the first request of its command in a case, is reported
/// as its kind; `expected` is a part of the message.
#[rstest::rstest]
#[case::connection_dropped_during_a_write(
    rule(command::WRITE, 1, FaultAction::Drop),
    "crashed",
    "closed by the other side"
)]
#[case::reply_past_the_timeout(
    rule(command::WRITE, 1, FaultAction::Delay(Duration::from_millis(900))),
    "timeout",
    "no reply to 1401"
)]
#[case::error_end_code(
    rule(command::WRITE, 1, FaultAction::EndCode(0xC056)),
    "protocol-error",
    "end code C056H"
)]
#[case::garbage_bytes(
    rule(command::RANDOM_READ, 1, FaultAction::Garbage),
    "protocol-error",
    "not a valid SLMP response"
)]
#[case::wrong_serial_on_4e(
    rule(command::RANDOM_READ, 1, FaultAction::WrongSerial),
    "protocol-error",
    "carries serial"
)]
#[case::cpu_leaves_run(
    rule(command::RANDOM_READ, 1, FaultAction::Stop),
    "unreachable",
    "left RUN"
)]
fn a_port_fault_is_reported_as_its_kind(
    #[case] fault: FaultRule,
    #[case] kind: &str,
    #[case] expected: &str,
) {
    assert_fault_reported(|p| iqr_bench(p, |_| {}), "BINHA", fault, kind, expected);
}

#[test]
fn a_read_past_the_timeout_is_sent_again_and_the_case_completes() {
    let project = session();
    let (sim, backend) = connected(iqr_bench(&project, |_| {}));
    sim.add_fault(rule(
        command::RANDOM_READ,
        1,
        FaultAction::Delay(Duration::from_millis(900)),
    ));
    let trial = first_trial(&project, &backend, "BINHA");
    let r = execute_once(&backend, &trial).expect("the read is retried on a new connection");
    assert!(matches!(r, crate::Response::Done(_)), "{r:?}");
    assert_eq!(sim.audit().connections, 2);
}

#[test]
fn the_circuit_breaker_stops_asking_after_max_faults_in_a_row() {
    let project = session();
    let sim = iqr_sim(&project, |s| {
        s.faults = vec![
            rule(command::WRITE, 1, FaultAction::EndCode(0xC051)),
            rule(command::WRITE, 2, FaultAction::EndCode(0xC051)),
        ]
    });
    let backend = iqr_backend(&project, &sim, |s| s.max_consecutive_faults = 2);
    backend.connect().expect("interlocks");
    let trial = first_trial(&project, &backend, "BINHA");
    assert_eq!(
        execute_once(&backend, &trial).expect_err("1").kind(),
        "protocol-error"
    );
    assert_eq!(
        execute_once(&backend, &trial).expect_err("2").kind(),
        "protocol-error"
    );
    let before = sim.audit().commands.values().sum::<usize>();
    let e = execute_once(&backend, &trial).expect_err("tripped");
    assert_eq!(e.kind(), "unreachable");
    assert!(e.to_string().contains("failed 2 requests in a row"), "{e}");
    assert_eq!(
        sim.audit().commands.values().sum::<usize>(),
        before,
        "nothing sent once tripped"
    );
}

#[test]
fn no_connection_is_unreachable() {
    let project = session();
    let mut s = iqr_settings_at(free_address(), iqr_sandbox());
    s.link.read_retries = 0;
    assert_unreachable(&project, &bench(&project, s), "BINHA");
}

/// Nothing is written before the type name, the operating status and the program's signature
/// match: each interlock refuses on its own.
#[rstest::rstest]
#[case::another_cpu(|s: &mut SlmpSimSettings| s.link.type_name = "R08CPU".into(), "`confirm` says `R04CPU`")]
#[case::cpu_in_stop(|s: &mut SlmpSimSettings| s.run = false, "STOP")]
#[case::no_program(|s: &mut SlmpSimSettings| s.program = false, "no test program signature")]
#[case::another_program(|s: &mut SlmpSimSettings| { s.manifest = manifest_for("habin"); }, "another one than the manifest's")]
fn an_interlock_refuses_before_any_write(
    #[case] change: fn(&mut SlmpSimSettings),
    #[case] expected: &str,
) {
    assert_interlock_refuses(|p| iqr_bench(p, change), "BINHA", expected, writes_sent);
}

/// A manifest generated for a part of the corpus only: another program.
fn manifest_for(filter: &str) -> Manifest {
    generate(
        &session(),
        &GenerateOptions {
            profile: "mitsubishi-iqr".into(),
            variants: vec!["rcpu".into()],
            mailbox: None,
            filter: Some(filter.into()),
        },
    )
    .expect("generate")
    .manifest
}

/// A case whose window lies outside the sandbox is refused while it is still a plan: no
/// connection is even made, let alone a byte written.
#[test]
fn a_write_outside_the_sandbox_is_refused_before_any_byte_is_sent() {
    let project = session();
    let listener = idle_listener();
    let s = iqr_settings_at(
        listener.local_addr().expect("addr").to_string(),
        vec![WordRange::new("D", 0, 150)],
    );
    let backend = bench(&project, s);
    let trial = first_trial(&project, &backend, "BINHA");
    assert_refused_by_the_fence(&backend, &trial);
    assert!(listener.accept().is_err(), "the backend connected");
    // The same with a simulated CPU that audits every byte it receives.
    let sim = iqr_sim(&project, |_| {});
    let backend = iqr_backend(&project, &sim, |s| {
        s.sandbox = vec![WordRange::new("D", 0, 150)]
    });
    backend.connect().expect("interlocks");
    assert!(matches!(
        execute_once(&backend, &trial),
        Ok(crate::Response::Unsupported(_))
    ));
    assert_eq!(writes_sent(&sim), 0);
}

/// The FX5U program of the whole corpus in a simulated CPU, and a live backend past its
/// interlocks.
fn fx5u_live(project: &Session) -> (SlmpSimulator, Arc<BenchBackend>) {
    let m = manifest(project, "mitsubishi-fx5");
    let sim = simulator(project, &m, "fx5u", vec![]);
    let backend = bench(project, settings(&m, "fx5u", &sim));
    connected((sim, backend))
}

/// A case that sets a word the client cannot address (16 points of M, as `K4M0`) is not run,
/// with the reason, and nothing of it is written.
#[test]
fn a_case_setting_words_the_client_cannot_address_is_not_run() {
    let project = session();
    let (sim, backend) = fx5u_live(&project);
    let mut trial = first_trial(&project, &backend, "ASCI");
    let written = writes_sent(&sim);
    assert!(matches!(
        execute_once(&backend, &trial),
        Ok(crate::Response::Done(_))
    ));
    assert!(writes_sent(&sim) > written, "the case as it is runs");
    std::sync::Arc::make_mut(&mut trial.input)
        .before
        .insert(Device::new("K4M", 0), 0x1234);
    let written = writes_sent(&sim);
    match execute_once(&backend, &trial) {
        Ok(crate::Response::Unsupported(why)) => {
            assert!(why.contains("K4M words"), "{why}");
        }
        other => panic!("run: {other:?}"),
    }
    assert_eq!(writes_sent(&sim), written);
}

/// Runs the FX5U trials `which` picks through the simulated CPU: each must run and conform, the
/// rungs must fire and the simulated CPU see nothing amiss. Returns the project.
fn fx5u_trials_conform(which: impl Fn(&Trial) -> bool, count: usize) -> Session {
    let project = session();
    let (sim, backend) = fx5u_live(&project);
    let b: Arc<dyn Backend> = backend.clone();
    let trials: Vec<Trial> = project
        .plan(&[b])
        .into_iter()
        .filter(|t| t.variant == "fx5u" && which(t))
        .collect();
    assert_eq!(trials.len(), count, "trials picked");
    let executions = sim.audit().executions;
    for (t, v) in trials.iter().zip(verdicts(&trials)) {
        assert_eq!(t.skip, None, "{}", t.name());
        assert!(matches!(v, Verdict::Conforms), "{}: {v:?}", t.name());
    }
    let audit = sim.audit();
    assert!(audit.executions > executions, "the rungs ran");
    assert!(audit.anomalies.is_empty(), "{:?}", audit.anomalies);
    project
}

/// A case with operands given by indirect specification runs: its rung stores each address
/// (ADRSET) before the instruction, the simulated CPU reads the operand through it, and the
/// pointer's words, which the program writes among the case's words (D150 of
/// asci-indirect-source), are not judged.
#[test]
fn a_case_with_an_indirect_operand_runs_after_adrset() {
    // 4 cases as ASCI and ASCIP.
    fx5u_trials_conform(|t| !t.input.indirect.is_empty(), 8);
}

/// The link registers, numbered in hexadecimal (`W9`, then `WA`), run as MELSEC numbers them:
/// the rung, the manifest's windows and the frames carry `WA`, and what the CPU did is judged
/// against the case's `W` words.
#[test]
fn a_case_on_hexadecimal_numbered_devices_runs() {
    // 3 cases as ASCI and ASCIP.
    let project = fx5u_trials_conform(
        |t| t.case_id().starts_with("asci-devices-") && t.case_id().contains("link"),
        6,
    );
    let writes: Vec<String> = manifest(&project, "mitsubishi-fx5").writes;
    assert!(writes.iter().any(|w| w.starts_with("SWF-")), "{writes:?}");
}

/// A mailbox in link registers is numbered as MELSEC numbers W: `--mailbox W100` is W 256, the
/// program writes its trigger as `W108`, and the PC finds the signature and runs a case there.
/// A mailbox the client cannot address is refused when the program is generated.
#[test]
fn a_mailbox_in_link_registers_is_numbered_in_hexadecimal() {
    let project = session();
    let options = |at: &str| GenerateOptions {
        profile: "mitsubishi-fx5".into(),
        variants: vec!["fx5u".into()],
        mailbox: Some(mailbox::head(at, &ADDRESSING).expect("a device")),
        ..GenerateOptions::default()
    };
    let generated = generate(&project, &options("W100")).expect("generate");
    let m = generated.manifest;
    assert_eq!(m.mailbox, "W100");
    assert_eq!(m.mailbox_head(&ADDRESSING).expect("head").index, 0x100);
    assert!(generated.program.contains("W108"), "the trigger is W108");
    let sim = simulator(&project, &m, "fx5u", vec![]);
    let backend = bench(&project, settings(&m, "fx5u", &sim));
    backend.connect().expect("the signature is found at W100");
    let trial = first_trial(&project, &backend, "ASCI");
    let verdict = verdicts(std::slice::from_ref(&trial)).remove(0);
    assert!(matches!(verdict, Verdict::Conforms), "{verdict:?}");
    let e = chain(&generate(&project, &options("T100")).expect_err("T100 refused"));
    assert!(
        e.contains("the mailbox cannot be at T100: T has no SLMP device code"),
        "{e}"
    );
}

#[test]
fn a_sandbox_over_the_mailbox_is_refused() {
    let project = session();
    let s = iqr_settings_at("127.0.0.1:1", vec![WordRange::new("D", 0, 18431)]);
    let e = refused_at_build(&project, s);
    assert!(e.contains("overlaps the mailbox"), "{e}");
}

#[test]
fn a_dry_run_opens_no_socket() {
    assert_dry_run_opens_no_socket(300, |address| iqr_settings_at(address, iqr_sandbox()));
}

/// A pulse form executes on each case, not only the first: its enable falls between two cases
/// because every rung is evaluated every scan.
#[test]
fn a_pulse_rung_fires_on_every_case() {
    let project = session();
    let (sim, backend) = connected(iqr_bench(&project, |_| {}));
    let trial = first_trial(&project, &backend, "BINHAP");
    let first = execute_once(&backend, &trial).expect("first");
    let before = sim.audit().executions;
    let second = execute_once(&backend, &trial).expect("second");
    assert_eq!(sim.audit().executions, before + 1);
    assert_eq!(first, second);
    assert!(
        matches!(first, crate::Response::Done(ref o) if !o.writes.is_empty()),
        "{first:?}"
    );
}

#[test]
fn every_generated_rung_sits_outside_if_and_case() {
    let g = generate(
        &session(),
        &GenerateOptions {
            profile: "mitsubishi-fx5".into(),
            ..GenerateOptions::default()
        },
    )
    .expect("generate");
    let mut depth = 0i32;
    let (mut rungs, mut adrsets) = (0, 0);
    for line in g.program.lines() {
        let t = line.trim_start();
        let closes_itself = t.contains("END_IF") || t.contains("END_CASE");
        if (t.starts_with("IF ") || t.starts_with("CASE ")) && !closes_itself {
            depth += 1;
        }
        if !(t.starts_with("IF ") || t.starts_with("CASE ")) && closes_itself {
            depth -= 1;
        }
        if t.contains("(bExec AND ") {
            if t.contains(":= ADRSET(") {
                adrsets += 1;
            } else {
                rungs += 1;
            }
            assert_eq!(depth, 0, "a rung inside IF or CASE: {line}");
            assert!(!line.starts_with(' '), "{line}");
        }
    }
    assert_eq!(rungs, g.manifest.rungs.len());
    let addresses: usize = g.manifest.rungs.iter().map(|r| r.addresses.len()).sum();
    assert!(addresses > 0, "the corpus has indirect operands");
    assert_eq!(adrsets, addresses, "one ADRSET per pointer, in its rung");
    assert!(g
        .manifest
        .rungs
        .iter()
        .any(|r| r.instruction.ends_with('P')));
    // FX5 captures SD8067 beside SD0.
    assert_eq!(g.manifest.error.extra.as_deref(), Some("SD8067"));
    assert!(g.program.contains(":= SD8067;"));
}

/// The pitfall the generator avoids, simulated: with its rungs inside a CASE a pulse rung fires
/// on its first case only, and the corpus run through the live backend shows it.
#[test]
fn a_program_with_its_rungs_in_a_case_is_caught() {
    let project = session();
    let sim = iqr_sim(&project, |s| s.rungs_in_case = true);
    let backend = iqr_backend(&project, &sim, |s| s.max_consecutive_faults = usize::MAX);
    backend.connect().expect("interlocks");
    let trial = first_trial(&project, &backend, "BINHAP");
    execute_once(&backend, &trial).expect("first");
    let second = execute_once(&backend, &trial).expect_err("the second run cannot pass");
    assert!(
        second.to_string().contains("ENO FALSE and no error"),
        "the rung's proof says it did not execute: {second}"
    );
    let b: Arc<dyn Backend> = backend.clone();
    let trials: Vec<Trial> = runnable(&project, &b).collect();
    let failed: Vec<(String, String)> = trials
        .iter()
        .zip(verdicts(&trials))
        .filter(|(_, v)| v.is_failure())
        .map(|(t, _)| (t.input.instruction.clone(), t.name()))
        .collect();
    assert!(!failed.is_empty(), "no trial failed");
    assert!(
        failed.iter().all(|(i, _)| i.ends_with('P')),
        "a trial of a non-pulse form failed: {failed:?}"
    );
}

/// An FX5 refuses the long device form (C059H), which the FX5 default avoids: asked for anyway,
/// the interlocks stop on the end code, before any write.
#[test]
fn the_long_device_form_on_an_fx5_is_refused_before_any_write() {
    let project = session();
    let m = manifest(&project, "mitsubishi-fx5");
    let variant = m.variants[0].clone();
    let sim = simulator(&project, &m, &variant, vec![]);
    let mut s = settings(&m, &variant, &sim);
    assert_eq!(
        (s.link.frame, s.link.form),
        (FrameKind::E3, DeviceForm::Short),
        "the FX5 default"
    );
    s.link.form = DeviceForm::Long;
    let backend = BenchBackend::new(s, &project.profiles).expect("backend");
    let e = chain(&backend.connect().expect_err("C059H"));
    assert!(e.contains("end code C059H"), "{e}");
    assert_eq!(writes_sent(&sim), 0);
}

/// `hil doctor --self-test` runs one pulse case twice: it passes on a program that evaluates
/// every rung every scan and fails on one with its rungs inside a CASE.
#[rstest::rstest]
#[case::every_rung_every_scan(false, true)]
#[case::rungs_in_a_case(true, false)]
fn the_pulse_self_test(#[case] rungs_in_case: bool, #[case] passes: bool) {
    let project = session();
    let (sim, backend) = connected(iqr_bench(&project, |s| s.rungs_in_case = rungs_in_case));
    let check = crate::hil::pulse_self_test(&project, &backend).expect("ran");
    assert_eq!(check.fired_twice, passes, "{check:?}");
    assert!(check.trial.contains("p::"), "{check:?}");
    assert!(sim.audit().stray_writes.is_empty());
}

/// The trials of a rung, and the backend on a simulated CPU changed by `change`.
fn rung_trials(
    project: &Session,
    change: impl FnOnce(&mut SlmpSimSettings, u16),
) -> (SlmpSimulator, Arc<BenchBackend>, Trial, u16) {
    let (probe, probe_backend) = iqr_bench(project, |_| {});
    let trial = first_trial(project, &probe_backend, "HABIN");
    let imgs = images(&trial);
    let rung = probe_backend
        .plan(&requests(&trial, &imgs)[0])
        .expect("plan")
        .rung;
    drop(probe);
    let (sim, backend) = connected(iqr_bench(project, |s| change(s, rung)));
    (sim, backend, trial, rung)
}

/// A rung missing from the program, or whose call never executes, is a fault that names the
/// rung, never a verdict: the program acknowledges the trigger either way, and "no change, no
/// error" would otherwise read as a result.
#[rstest::rstest]
#[case::missing(true, "did not run for case")]
#[case::disabled(false, "ENO FALSE and no error")]
fn a_rung_that_did_not_execute_is_a_fault(#[case] missing: bool, #[case] says: &str) {
    let project = session();
    let (sim, backend, trial, rung) = rung_trials(&project, |s, rung| {
        if missing {
            s.missing_rungs.insert(rung);
        } else {
            s.disabled_rungs.insert(rung);
        }
    });
    let fault = execute_once(&backend, &trial).expect_err("not a verdict");
    let text = fault.to_string();
    assert_eq!(fault.kind(), "protocol-error", "{text}");
    assert!(text.contains(&format!("rung {rung} ")), "{text}");
    assert!(text.contains(says), "{text}");
    assert_eq!(
        sim.audit().executions,
        0,
        "the simulated CPU executed the rung"
    );
}

/// A proxy that keeps every trigger after the first from the CPU and answers the polls with
/// ack = trigger in state 1: the acknowledgement alone is never taken for a case done, so no
/// trial after the first passes, and every one of them is a fault.
#[test]
fn an_acknowledgement_without_the_program_done_is_a_fault() {
    let mut project = session();
    let m = iqr_manifest();
    let sim = iqr_sim(&project, |s| s.premature_ack = true);
    let mut s = settings(m, "rcpu", &sim);
    s.max_consecutive_faults = usize::MAX;
    let backend = live(&mut project, s);
    let trials: Vec<Trial> = runnable(&project, &backend).take(6).collect();
    assert_eq!(trials.len(), 6);
    let verdicts = verdicts(&trials);
    let passed = verdicts
        .iter()
        .filter(|v| matches!(v, Verdict::Conforms))
        .count();
    // Each trial runs fill A then fill B: only the very first execution reached the program.
    assert_eq!(passed, 0, "{verdicts:?}");
    let faults = verdicts
        .iter()
        .filter(|v| format!("{v:?}").contains("while the program's state says 1"))
        .count();
    assert_eq!(faults, 6, "{verdicts:?}");
}

/// Every generated call, in both programs, passes its operands in the order the manual's
/// structured-text form prints them, with exactly its operands. The forms are written out here
/// from the manual pages (docs/semantics.md#structured-text-calls), independently of the
/// profiles' tables the generator reads.
#[test]
fn every_call_takes_the_operands_in_the_manuals_order() {
    let quoted: BTreeMap<&str, &[&str]> = BTreeMap::from([
        // fx5-instructions p.ASCI(P): "ENO:=ASCI(EN,s,n,d); ENO:=ASCIP(EN,s,n,d);"
        ("ASCI", &["s", "n", "d"][..]),
        ("ASCIP", &["s", "n", "d"][..]),
        // Inferred (docs/semantics.md#structured-text-calls), unconfirmed on a CPU.
        ("HEXA", &["s", "n", "d"][..]),
        ("HEXAP", &["s", "n", "d"][..]),
        ("ADRSET", &["s", "d"][..]),
        ("HABIN", &["s", "d"][..]),
        ("HABINP", &["s", "d"][..]),
        ("DHABIN", &["s", "d"][..]),
        ("DHABINP", &["s", "d"][..]),
        ("BINHA", &["s", "d"][..]),
        ("BINHAP", &["s", "d"][..]),
        ("DBINHA", &["s", "d"][..]),
        ("DBINHAP", &["s", "d"][..]),
    ]);
    let project = session();
    for profile in ["mitsubishi-iqr", "mitsubishi-fx5"] {
        let g = generate(
            &project,
            &GenerateOptions {
                profile: profile.into(),
                ..GenerateOptions::default()
            },
        )
        .expect("generate");
        let mut instructions = std::collections::BTreeSet::new();
        for rung in &g.manifest.rungs {
            let enable = format!("(bExec AND {} = {}, ", rung_word(&g.manifest), rung.id);
            let calls: Vec<&str> = g.program.lines().filter(|l| l.contains(&enable)).collect();
            assert_eq!(calls.len(), 1 + rung.addresses.len(), "rung {}", rung.id);
            let mut addresses = rung.addresses.iter();
            for line in calls {
                let (head, args) = line.split_once(&enable).expect("call");
                let name = head.trim_start_matches("bEno := ").trim_end_matches('(');
                assert!(head.starts_with("bEno := "), "{line}");
                let args: Vec<&str> = args.trim_end_matches(");").split(", ").collect();
                let order = quoted
                    .get(name)
                    .unwrap_or_else(|| panic!("no quoted form: {line}"));
                assert_eq!(args.len(), order.len(), "{line}");
                // One ADRSET per pointer, in the order of the manifest's `addresses`.
                let (pointer, target) = match name {
                    "ADRSET" => addresses.next().expect("an ADRSET per pointer"),
                    _ => (&String::new(), &String::new()),
                };
                for (arg, operand) in args.iter().zip(order.iter()) {
                    let wanted = match name {
                        "ADRSET" if *operand == "s" => target.to_string(),
                        "ADRSET" => pointer.to_string(),
                        _ => as_written(&rung.operands[*operand]),
                    };
                    assert_eq!(*arg, wanted, "operand {operand} of {line}");
                }
                instructions.insert(name.to_string());
            }
        }
        let expected: Vec<&str> = match profile {
            "mitsubishi-iqr" => vec![
                "BINHA", "BINHAP", "DBINHA", "DBINHAP", "DHABIN", "DHABINP", "HABIN", "HABINP",
            ],
            _ => vec!["ADRSET", "ASCI", "ASCIP", "HEXA", "HEXAP"],
        };
        assert_eq!(
            instructions.iter().map(String::as_str).collect::<Vec<_>>(),
            expected,
            "{profile}"
        );
    }
}

/// The mailbox word that selects the rung, as the program writes it.
fn rung_word(m: &Manifest) -> String {
    let head = mailbox::head(&m.mailbox, &ADDRESSING).expect("mailbox");
    mailbox::at(&head, mailbox::off::RUNG).to_string()
}

/// A manifest operand as the program writes it: a constant `K4` as `4`.
fn as_written(text: &str) -> String {
    match text.strip_prefix('K').map(str::parse::<i64>) {
        Some(Ok(k)) => k.to_string(),
        _ => text.to_string(),
    }
}

/// `sandbox=manifest` takes the data and link registers of the manifest's writes and leaves
/// special registers out: an FX5 case that sets SD words is refused by the fence with how to
/// name them, and runs once they are named.
#[test]
fn special_registers_are_written_only_when_named() {
    let project = session();
    let m = manifest(&project, "mitsubishi-fx5");
    let dir = super::scratch();
    let file = dir.path().join("manifest.json");
    std::fs::write(&file, serde_json::to_string_pretty(&m).expect("json")).expect("write");
    let special: Vec<&String> = m.writes.iter().filter(|w| w.starts_with("SD")).collect();
    assert!(!special.is_empty(), "the FX5 corpus sets SD words");
    let spec = |sandbox: &str| {
        format!(
            "slmp:bench=127.0.0.1:1?manifest={}&confirm=FX5U-32MT/DS&sandbox={sandbox}&variant=fx5u",
            file.display()
        )
    };
    let parsed = |sandbox: &str| {
        SlmpBench::parse(&spec(sandbox), std::path::Path::new("."))
            .expect("parses")
            .expect("a live backend")
    };
    let backend = bench(&project, parsed("manifest"));
    assert!(backend
        .fence()
        .allowed()
        .iter()
        .all(|r| r.code != "SD" && r.code != "SW"));
    let found = dry_run(&project, &backend);
    let sd: Vec<&(String, String)> = found
        .refused
        .iter()
        .filter(|(_, why)| why.contains("special register"))
        .collect();
    assert!(!sd.is_empty(), "{:?}", found.refused);
    assert!(sd[0].1.contains("sandbox=manifest,SD"), "{}", sd[0].1);
    let named = format!(
        "manifest,{}",
        m.writes
            .iter()
            .filter(|w| w.starts_with("SD") || w.starts_with("SW"))
            .cloned()
            .collect::<Vec<_>>()
            .join(",")
    );
    let backend = bench(&project, parsed(&named));
    let found = dry_run(&project, &backend);
    assert_eq!(found.refused, Vec::<(String, String)>::new());
    let bits = SlmpBench::parse(&spec("manifest,Y0-Y17"), std::path::Path::new("."))
        .expect("parses")
        .expect("a live backend");
    let e = refused_at_build(&project, bits);
    assert!(e.contains("word devices only"), "{e}");
}

/// The simulated iQ-R CPU holds link registers (W, SW) like a CPU, though the iQ-R profile
/// names only D: a client writes W1F0 and reads it back.
#[test]
fn the_simulated_iqr_cpu_serves_link_registers() {
    use crate::backend::bench::fence::WriteFence;
    use crate::backend::slmp::client::{Client, ClientSettings};
    let project = session();
    let sim = iqr_sim(&project, |_| {});
    let mut c = Client::new(ClientSettings::new(sim.address().to_string()));
    let w = Device::hexadecimal("W", 0x1F0);
    let fence = WriteFence::new(vec![WordRange::new("W", 0x1F0, 0x1F1)]);
    for write in fence.writes(960, &w, &[0x1234, 0x5678]).expect("inside") {
        c.write(&write).expect("W is served");
    }
    assert_eq!(c.read_words(&w, 2).expect("read"), [0x1234, 0x5678]);
    assert_eq!(
        c.read_words(&Device::hexadecimal("SW", 0x7FF), 1)
            .expect("SW"),
        [0]
    );
}
