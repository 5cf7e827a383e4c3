//! The live CPU backend against the simulated CPU, on 127.0.0.1 only: the whole corpus judged
//! exactly as the built-in models judge it, each fault of a port mapped to its kind, the write
//! fence and the interlocks refusing before anything is written, and a dry run that opens no
//! socket.

mod common;

use std::collections::BTreeMap;
use std::net::TcpListener;
use std::sync::Arc;
use std::time::{Duration, Instant};

use plc_conformance::backend::slmp::fence::{parse_ranges, WordRange};
use plc_conformance::backend::slmp::frame::command;
use plc_conformance::backend::slmp::manifest::Manifest;
use plc_conformance::backend::slmp::sim::{FaultAction, FaultRule, SimSettings, Simulator};
use plc_conformance::backend::slmp::{SlmpBackend, SlmpSettings};
use plc_conformance::backend::{Backend, Fault};
use plc_conformance::device::Device;
use plc_conformance::hil::{dry_run, generate, GenerateOptions};
use plc_conformance::judge::Verdict;
use plc_conformance::plan::Trial;
use plc_conformance::runner::{verdicts, Project};

use common::{reference, session};

fn manifest(project: &Project, profile: &str) -> Manifest {
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
    project: &Project,
    manifest: &Manifest,
    variant: &str,
    faults: Vec<FaultRule>,
) -> Simulator {
    let profile = project
        .profiles
        .get(&manifest.profile)
        .cloned()
        .expect("profile");
    let mut settings = SimSettings::new(manifest.clone(), variant, type_name(&manifest.profile));
    settings.faults = faults;
    Simulator::start(settings, profile, reference(project, &manifest.profile))
        .unwrap_or_else(|e| panic!("simulator: {e}"))
}

fn settings(manifest: &Manifest, variant: &str, sim: &Simulator) -> SlmpSettings {
    let sandbox = parse_ranges(&manifest.writes.join(",")).expect("writes");
    let mut s = SlmpSettings::new(
        "live",
        sim.address().to_string(),
        manifest.clone(),
        variant,
        type_name(&manifest.profile),
        sandbox,
    );
    s.first_poll = Duration::from_micros(300);
    s.max_poll = Duration::from_millis(2);
    s.client.reply_timeout = Duration::from_millis(500);
    s.case_timeout = Duration::from_millis(800);
    s
}

fn live(project: &mut Project, settings: SlmpSettings) -> Arc<dyn Backend> {
    let backend = Arc::new(SlmpBackend::new(settings, &project.profiles).expect("backend"));
    backend
        .connect()
        .unwrap_or_else(|e| panic!("interlocks: {e}"));
    let backend: Arc<dyn Backend> = backend;
    project.backends.push(backend.clone());
    backend
}

/// A trial's identity across backends.
fn key(t: &Trial) -> (String, String, String) {
    (
        t.check_name().to_string(),
        t.case_id().to_string(),
        t.variant.clone(),
    )
}

/// Runs every trial of one variant through the live backend and compares each verdict with the
/// built-in model's; returns how many ran.
fn same_verdicts(profile: &str, variant: &str) -> usize {
    let mut project = session();
    let manifest = manifest(&project, profile);
    let sim = simulator(&project, &manifest, variant, vec![]);
    let model = reference(&project, profile);
    let backend = live(&mut project, settings(&manifest, variant, &sim));
    let expected: BTreeMap<_, _> = {
        let trials: Vec<Trial> = project
            .plan(std::slice::from_ref(&model))
            .into_iter()
            .filter(|t| t.variant == variant)
            .collect();
        let v = verdicts(&trials);
        trials.iter().map(key).zip(v).collect()
    };
    let trials = project.plan(std::slice::from_ref(&backend));
    let started = Instant::now();
    let got = verdicts(&trials);
    let elapsed = started.elapsed();
    let mut ran = 0;
    for (t, v) in trials.iter().zip(&got) {
        if t.variant != variant {
            assert!(t.skip.is_some(), "{}: run on another variant", t.name());
            continue;
        }
        let want = expected.get(&key(t));
        match (&t.skip, want) {
            (_, None) => panic!("{}: no such trial on the built-in model", t.name()),
            (Some(why), Some(w)) => {
                assert!(
                    matches!(w, Verdict::Skipped { .. }) || why.contains("no program can hold"),
                    "{}: skipped ({why}) where the model ran it",
                    t.name()
                );
            }
            (None, Some(w)) => {
                ran += 1;
                assert_eq!(v, w, "{}", t.name());
            }
        }
    }
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
        "{profile} {variant}: {ran} trials, {} executions in {:.2} s",
        audit.executions,
        elapsed.as_secs_f64()
    );
    assert!(ran > 0);
    ran
}

#[test]
fn iqr_rcpu_through_the_simulated_cpu_judges_like_the_model() {
    same_verdicts("mitsubishi-iqr", "rcpu");
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
        same_verdicts("mitsubishi-fx5", &v.id);
    }
}
