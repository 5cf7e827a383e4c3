//! An IDEC MicroSmart bench through the binary, against the simulated IDEC CPU on 127.0.0.1
//! only: `hil generate`, `sim`, `doctor` and `dry-run` for FC4A, `run` with a `modbus:` backend
//! and `record` refusing to write what the simulated CPU answered as observed, and a spec whose
//! link disagrees with its profile refused. The bench's white-box tests over Modbus TCP, with no
//! binary, are in src/backend/bench/end_to_end/idec.rs.

mod common;

use std::sync::Arc;

use plc_conformance::testing::backend::bench::manifest::Manifest;
use plc_conformance::testing::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use plc_conformance::testing::backend::modbus::Map;
use plc_conformance::testing::error_chain::chain;
use plc_conformance::testing::hil::{generate, GenerateOptions};
use plc_conformance::testing::session::Session;

use common::{reference, session};

const PROFILE: &str = "idec-fc4a";
/// The variant the simulated CPU is: D0-D1299 and the expansion D2000-D7999.
const VARIANT: &str = "d40k3";
/// The type code the simulated CPU holds in D8002, and what `confirm=` names.
const TYPE_CODE: u16 = 6;

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
    let profile = project
        .profiles()
        .get(&m.profile)
        .cloned()
        .expect("profile");
    let mut s = ModbusSimSettings::idec(m.clone(), VARIANT, TYPE_CODE);
    change(&mut s);
    ModbusSimulator::start(s, profile, reference(project, PROFILE)).expect("simulator")
}

/// The FC4A profile's Modbus map.
fn map() -> Arc<Map> {
    let project = session();
    Arc::new(Map::of(project.profiles().get(PROFILE).expect("profile")).expect("a Modbus map"))
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
