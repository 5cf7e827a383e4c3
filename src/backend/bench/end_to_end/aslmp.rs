//! A live run against aslmp's simulated CPUs (a third-party SLMP server, pinned in
//! adapters/python/requirements.txt), the doctor first; skipped with a note when `.venv-adapters`
//! is missing, and failing then when PLC_CONFORMANCE_REQUIRE_BACKENDS is set. All traffic stays
//! on 127.0.0.1. The bench is read from the same `--backend` text `hil doctor` and `run` read.

#[cfg(test)]
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::Duration;

use super::{adapters_python, reference, scratch, session};
use crate::backend::bench::doctor::doctor;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::{fence, BenchBackend};
use crate::backend::slmp::client::{ClientSettings, Code};
use crate::backend::slmp::frame::{DeviceForm, FrameKind};
use crate::backend::slmp::limits::{self, Family};
use crate::backend::slmp::sim::{RemoteProgram, SlmpSimSettings};
use crate::backend::slmp::{SlmpBench, ADDRESSING};
use crate::hil::{generate, GenerateOptions};
use crate::{verdicts, Backend, Trial};

/// The Python of `.venv-adapters` with virtual-plc, pymcprotocol, aslmp and plc-comm-slmp, or `None` (with a note).
fn venv_python() -> Option<PathBuf> {
    adapters_python(
        "virtual_plc, pymcprotocol, aslmp, slmp",
        "virtual-plc, pymcprotocol, aslmp and plc-comm-slmp",
    )
}

/// The manifest of the program generated for one variant of a profile.
fn generated(project: &crate::Project, profile: &str, variant: &str) -> Manifest {
    generate(
        project,
        &GenerateOptions {
            profile: profile.into(),
            variants: vec![variant.into()],
            ..GenerateOptions::default()
        },
    )
    .expect("generate")
    .manifest
}

/// aslmp's simulated CPU (`aslmp serve`) on 127.0.0.1, killed when dropped: its entries by name
/// (`tcp` 3E binary, `tcp-4e` 4E binary, `tcp-ascii` 3E ASCII code), as its banner lists them.
struct Aslmp {
    child: Child,
    entries: std::collections::BTreeMap<String, String>,
}

impl Aslmp {
    fn start(python: &PathBuf, target: &str) -> Aslmp {
        let mut child = Command::new(python)
            .args(["-m", "aslmp.tools", "serve", "--target", target])
            .args(["--host", "127.0.0.1"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("aslmp serve starts");
        let stdout = child.stdout.take().expect("stdout");
        let mut lines = BufReader::new(stdout).lines();
        let mut entries = std::collections::BTreeMap::new();
        for line in lines.by_ref() {
            let line = line.expect("a line");
            if line.starts_with("Ctrl-C") {
                break;
            }
            let mut words = line.split_whitespace();
            if let (Some(name), Some(address)) = (words.next(), words.next()) {
                if address.starts_with("127.0.0.1:") {
                    entries.insert(name.to_string(), address.to_string());
                }
            }
        }
        std::thread::spawn(move || for _ in lines {});
        assert!(entries.contains_key("tcp-ascii"), "{entries:?}");
        Aslmp { child, entries }
    }

    fn address(&self, entry: &str) -> &str {
        &self.entries[entry]
    }
}

impl Drop for Aslmp {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A client for a port of the family, with the limits of its code.
fn family_client(address: &str, family: Family, frame: FrameKind, code: Code) -> ClientSettings {
    let mut s = ClientSettings::new(address);
    s.frame = frame;
    s.code = code;
    s.form = match family {
        Family::Fx5 => DeviceForm::Short,
        Family::Iqr => DeviceForm::Long,
    };
    s.timer = limits::monitoring_timer(family);
    s.limits = limits::limits(family, code, s.form);
    s.reply_timeout = Duration::from_millis(1500);
    s
}

/// A live run against aslmp's simulated CPUs, with the test program's behaviour scanning their
/// memory over a second port ([`RemoteProgram`]): the live backend talks to the third-party
/// server in binary and in ASCII code, in its frames and within its limits, and every trial it
/// runs gets the built-in model's verdict; `hil doctor` through the binary finds the bench
/// ready in the same codes.
#[rstest::rstest]
#[case::fx5u_binary(
    "fx5u-32mt-ds",
    "mitsubishi-fx5",
    "fx5u",
    "tcp",
    Code::Binary,
    FrameKind::E3,
    "tcp-4e"
)]
#[case::fx5u_ascii(
    "fx5u-32mt-ds",
    "mitsubishi-fx5",
    "fx5u",
    "tcp-ascii",
    Code::Ascii,
    FrameKind::E3,
    "tcp-4e"
)]
#[case::r04cpu_binary(
    "r04cpu",
    "mitsubishi-iqr",
    "rcpu",
    "tcp-4e",
    Code::Binary,
    FrameKind::E4,
    "tcp"
)]
#[case::r04cpu_ascii(
    "r04cpu",
    "mitsubishi-iqr",
    "rcpu",
    "tcp-ascii",
    Code::Ascii,
    FrameKind::E3,
    "tcp"
)]
fn a_live_run_against_aslmps_simulated_cpu(
    #[case] target: &str,
    #[case] profile: &str,
    #[case] variant: &str,
    #[case] entry: &str,
    #[case] code: Code,
    #[case] frame: FrameKind,
    #[case] program_entry: &str,
) {
    let Some(python) = venv_python() else { return };
    let server = Aslmp::start(&python, target);
    let mut project = session();
    let manifest = generated(&project, profile, variant);
    let family = Family::of_profile(profile);
    let (type_name, model_code) = match family {
        Family::Fx5 => ("FX5U-32MT/DS", 0x4A49),
        Family::Iqr => ("R04CPU", 0x4800),
    };
    let model = reference(&project, profile);
    let program = RemoteProgram::start(
        SlmpSimSettings::new(manifest.clone(), variant, type_name),
        project.profiles.get(profile).cloned().expect("profile"),
        model.clone(),
        family_client(
            server.address(program_entry),
            family,
            if program_entry == "tcp-4e" {
                FrameKind::E4
            } else {
                FrameKind::E3
            },
            Code::Binary,
        ),
    )
    .expect("the program scans");
    let dir = scratch();
    let file = dir.path().join("manifest.json");
    std::fs::write(
        &file,
        serde_json::to_string_pretty(&manifest).expect("json"),
    )
    .expect("write");
    let code_key = match code {
        Code::Binary => "binary",
        Code::Ascii => "ascii",
    };
    let frame_key = match frame {
        FrameKind::E3 => "3e",
        FrameKind::E4 => "4e",
    };
    let spec = format!(
        "slmp:aslmp={}?manifest={}&confirm={type_name}&sandbox=manifest&code={code_key}&frame={frame_key}",
        server.address(entry),
        file.display()
    );
    // The doctor first (an FX5U takes one connection a port at a time), on the bench the
    // `--backend` text names, as `hil doctor` reads it.
    let settings = crate::backend::bench_settings(&spec, Path::new("."), &project.profiles)
        .unwrap_or_else(|e| panic!("{spec}: {e}"))
        .expect("a live backend");
    let (findings, _) = doctor(&settings);
    for f in &findings {
        assert!(f.result.is_ok(), "{}: {:?}", f.what, f.result);
    }
    assert!(
        findings.iter().any(|f| f.what == "program signature"),
        "{:?}",
        findings.iter().map(|f| f.what).collect::<Vec<_>>()
    );
    let sandbox = fence::parse_ranges(&manifest.writes.join(","), &ADDRESSING).expect("writes");
    let mut s = SlmpBench::new(
        "aslmp",
        server.address(entry),
        manifest.clone(),
        variant,
        type_name,
        sandbox,
    );
    s.link.frame = frame;
    s.link.code = code;
    s.fit_limits();
    s.case_timeout = Duration::from_secs(5);
    let backend = Arc::new(BenchBackend::new(s, &project.profiles).expect("backend"));
    backend
        .connect()
        .unwrap_or_else(|e| panic!("interlocks: {e}"));
    assert!(
        backend.describe().contains(&format!("({model_code:04X}H)")),
        "{}",
        backend.describe()
    );
    let live: Arc<dyn Backend> = backend.clone();
    project.backends.push(live.clone());
    // Every 12th trial the program can hold: pulse forms, errors and both fills among them.
    let trials: Vec<Trial> = project
        .plan(std::slice::from_ref(&live))
        .into_iter()
        .filter(|t| t.skip.is_none())
        .step_by(12)
        .collect();
    assert!(trials.len() > 8, "{}", trials.len());
    let expected: Vec<Trial> = project
        .plan(std::slice::from_ref(&model))
        .into_iter()
        .filter(|t| t.variant == variant)
        .collect();
    let want = verdicts(&expected);
    let got = verdicts(&trials);
    for (t, v) in trials.iter().zip(&got) {
        let i = expected
            .iter()
            .position(|e| e.check_name() == t.check_name() && e.case_id() == t.case_id())
            .unwrap_or_else(|| panic!("{}: not a model trial", t.name()));
        assert_eq!(v, &want[i], "{} ({code})", t.name());
    }
    assert!(program.audit().executions > 0);
}
