//! The `hil` commands through the binary, against the simulated CPU on 127.0.0.1 only:
//! `generate`, `doctor`, `dry-run`, `probe` and `sim`, a bad manifest refused before any socket,
//! and `record` writing observed vectors through a CPU but never through the simulator. The live
//! backend's white-box tests, with no binary, are in src/backend/bench/end_to_end/slmp.rs.

mod common;

use std::net::TcpListener;

use plc_conformance::testing::backend::bench::manifest::Manifest;
use plc_conformance::testing::backend::slmp::frame::command;
use plc_conformance::testing::backend::slmp::sim::{FaultRule, SlmpSimSettings, SlmpSimulator};
use plc_conformance::testing::backend::slmp::ADDRESSING;
use plc_conformance::testing::hil::{generate, GenerateOptions};
use plc_conformance::testing::session::Session;

use common::{reference, session};

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
    let profile = project
        .profile(&manifest.profile)
        .cloned()
        .expect("profile");
    let mut settings =
        SlmpSimSettings::new(manifest.clone(), variant, type_name(&manifest.profile));
    settings.faults = faults;
    SlmpSimulator::start(settings, profile, reference(project, &manifest.profile))
        .unwrap_or_else(|e| panic!("simulator: {e}"))
}

/// The iQ-R manifest, generated once for every test of this file.
fn iqr_manifest() -> &'static Manifest {
    static M: std::sync::OnceLock<Manifest> = std::sync::OnceLock::new();
    M.get_or_init(|| manifest(&session(), "mitsubishi-iqr"))
}

/// A simulated iQ-R CPU (4E frames, long device form) set up by `change`.
fn iqr_sim(project: &Session, change: impl FnOnce(&mut SlmpSimSettings)) -> SlmpSimulator {
    let m = iqr_manifest();
    let profile = project.profile(&m.profile).cloned().expect("profile");
    let mut s = SlmpSimSettings::new(m.clone(), "rcpu", "R04CPU");
    change(&mut s);
    SlmpSimulator::start(s, profile, reference(project, &m.profile)).expect("simulator")
}

fn writes_sent(sim: &SlmpSimulator) -> usize {
    sim.audit()
        .commands
        .get(&command::WRITE)
        .copied()
        .unwrap_or(0)
}

/// A copy of the iQ-R vectors and the manifest in a scratch folder, for `record`.
fn record_scratch() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let scratch_dir = common::scratch();
    let dir = scratch_dir.path().join("vectors");
    std::fs::create_dir_all(&dir).expect("mkdir");
    for entry in std::fs::read_dir(common::root().join("vectors/mitsubishi-iqr")).expect("dir") {
        let entry = entry.expect("entry");
        std::fs::copy(entry.path(), dir.join(entry.file_name())).expect("copy");
    }
    let m = iqr_manifest();
    let manifest_file = scratch_dir.path().join("manifest.json");
    std::fs::write(
        &manifest_file,
        serde_json::to_string_pretty(m).expect("json"),
    )
    .expect("write");
    (scratch_dir, dir, manifest_file)
}

/// `record` through a live backend, as a bench user would run it, with the simulated CPU
/// standing in for a real one (it does not say it is the simulator): the unspecified cases of a
/// copy of the corpus become observed with the CPU, program and transport in the provenance,
/// manual ones are untouched, and the copy still validates.
#[test]
fn record_through_a_cpu_writes_observed_vectors_with_provenance() {
    let project = session();
    let (_scratch, dir, manifest_file) = record_scratch();
    let m = iqr_manifest();
    let sim = iqr_sim(&project, |s| s.identifies = false);
    let spec = format!(
        "slmp:bench={}?manifest={}&confirm=R04CPU&sandbox=manifest&variant=rcpu",
        sim.address(),
        manifest_file.display()
    );
    let manual_before = count(&dir, "basis: manual");
    let out = common::cli(&[
        "record",
        "--backend",
        &spec,
        "--vectors",
        dir.to_str().expect("utf-8"),
        "--date",
        "2026-11-25",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("unspecified -> observed"), "{stdout}");
    assert_eq!(
        count(&dir, "basis: manual"),
        manual_before,
        "a manual expectation was replaced"
    );
    let habin = std::fs::read_to_string(dir.join("habin.yaml")).expect("habin.yaml");
    let wanted = format!("live CPU R04CPU (4800H), mitsubishi-iqr variant rcpu, program {} (mailbox layout 2), SLMP 4E binary TCP", m.hash);
    assert!(habin.contains("backend: bench"), "{habin}");
    assert!(habin.contains(&wanted), "{habin}");
    let valid = common::cli(&["validate", dir.to_str().expect("utf-8")]);
    assert!(
        valid.status.success(),
        "{}",
        String::from_utf8_lossy(&valid.stderr)
    );
    assert_eq!(sim.audit().stray_writes, Vec::<String>::new());
}

fn count(dir: &std::path::Path, text: &str) -> usize {
    std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| {
            std::fs::read_to_string(e.expect("entry").path())
                .expect("read")
                .matches(text)
                .count()
        })
        .sum()
}

/// The `hil` commands through the binary: `generate` writes the three files, `doctor` reads a
/// running simulated CPU without writing, `dry-run` plans every case without a socket, and a
/// live backend that is not ready stops `run` before any case (exit 2).
#[test]
fn the_hil_commands_through_the_binary() {
    let project = session();
    let dir = common::scratch();
    let out_dir = dir.path().join("bench");
    let out = common::cli(&[
        "hil",
        "generate",
        "--profile",
        "mitsubishi-iqr",
        "--variant",
        "rcpu",
        "--mailbox",
        "D18000",
        "--out",
        out_dir.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("mailbox D18000"), "{stdout}");
    for f in ["executive.st", "manifest.json", "SETUP.md"] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let manifest_file = out_dir.join("manifest.json");
    let m = Manifest::load(&manifest_file, &ADDRESSING).expect("the written manifest loads");
    // The same program as the one generated for both variants (the variants are not hashed).
    assert_eq!(m.hash, iqr_manifest().hash, "generate is deterministic");
    assert_eq!(m.rungs, iqr_manifest().rungs);
    let sim = iqr_sim(&project, |_| {});
    let spec = format!(
        "slmp:bench={}?manifest={}&confirm=R04CPU&sandbox=manifest",
        sim.address(),
        manifest_file.display()
    );
    let doctor = common::cli(&["hil", "doctor", "--backend", &spec]);
    let shown = String::from_utf8_lossy(&doctor.stdout);
    assert!(doctor.status.success(), "{shown}");
    assert!(shown.contains("ok    program signature"), "{shown}");
    assert!(shown.contains("nothing written"), "{shown}");
    assert_eq!(writes_sent(&sim), 0);
    let connections = sim.audit().connections;
    let dry = common::cli(&["hil", "dry-run", "--backend", &spec]);
    let shown = String::from_utf8_lossy(&dry.stdout);
    assert!(dry.status.success(), "{shown}");
    assert!(
        shown.contains("no socket opened") && shown.contains("0 refused"),
        "{shown}"
    );
    assert_eq!(
        sim.audit().connections,
        connections,
        "the dry run connected"
    );
    sim.set_running(false);
    let run = common::cli(&["run", "--backend", &spec]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("live CPU backend `bench` not started") && err.contains("STOP"),
        "{err}"
    );
    assert_eq!(writes_sent(&sim), 0);
}

/// `hil sim` serves until it is ended, on 127.0.0.1, and a live backend runs against it.
#[test]
fn hil_sim_serves_a_simulated_cpu_on_loopback() {
    let dir = common::scratch();
    let manifest_file = dir.path().join("manifest.json");
    std::fs::write(
        &manifest_file,
        serde_json::to_string_pretty(iqr_manifest()).expect("json"),
    )
    .expect("write");
    let (mut child, address) = hil_sim(&manifest_file, &["--variant", "rcpu"]);
    assert!(address.starts_with("127.0.0.1:"), "{address}");
    let spec = format!(
        "slmp:bench={address}?manifest={}&confirm=R04CPU&sandbox=manifest&variant=rcpu",
        manifest_file.display()
    );
    let run = common::cli(&["run", "--backend", &spec, "--filter", "binha"]);
    let _ = child.kill();
    let _ = child.wait();
    let shown = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{shown}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(shown.contains(" 0 failed"), "{shown}");
}

/// `record` against the simulated CPU writes no `observed` vector: the mailbox says a
/// simulator runs the program, and the command refuses, naming it, with the files untouched.
#[test]
fn record_through_the_simulated_cpu_writes_nothing() {
    let project = session();
    let (_scratch, dir, manifest_file) = record_scratch();
    let sim = iqr_sim(&project, |_| {});
    let before = count(&dir, "basis: observed");
    let spec = format!(
        "slmp:bench={}?manifest={}&confirm=R04CPU&sandbox=manifest&variant=rcpu",
        sim.address(),
        manifest_file.display()
    );
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
    assert_eq!(
        count(&dir, "basis: observed"),
        before,
        "an observed vector was written"
    );
}

/// Starts `hil sim` with `args` on a manifest file; the child and the address it serves.
fn hil_sim(manifest_file: &std::path::Path, args: &[&str]) -> (std::process::Child, String) {
    use std::io::{BufRead, BufReader};
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin!("plc-conformance"))
        .args([
            "--root",
            common::root().to_str().expect("utf-8"),
            "hil",
            "sim",
        ])
        .args(["--manifest", manifest_file.to_str().expect("utf-8")])
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("hil sim starts");
    let stdout = child.stdout.take().expect("stdout");
    let line = BufReader::new(stdout)
        .lines()
        .next()
        .expect("a line")
        .expect("text");
    let address = line
        .strip_prefix("listening on ")
        .unwrap_or_else(|| panic!("{line}"))
        .to_string();
    (child, address)
}

/// `hil sim --stop` starts a CPU in STOP, and `--fault` injects a port fault from the command
/// line: doctor sees the STOP, and a type-name request answered with an end code fails the
/// connection check with that code.
#[test]
fn hil_sim_starts_in_stop_or_with_a_fault_from_the_command_line() {
    let dir = common::scratch();
    let manifest_file = dir.path().join("manifest.json");
    std::fs::write(
        &manifest_file,
        serde_json::to_string_pretty(iqr_manifest()).expect("json"),
    )
    .expect("write");
    let spec = |address: &str| {
        format!(
            "slmp:bench={address}?manifest={}&confirm=R04CPU&sandbox=manifest&variant=rcpu",
            manifest_file.display()
        )
    };
    let (mut child, address) = hil_sim(&manifest_file, &["--variant", "rcpu", "--stop"]);
    let doctor = common::cli(&["hil", "doctor", "--backend", &spec(&address)]);
    let _ = child.kill();
    let _ = child.wait();
    let shown = String::from_utf8_lossy(&doctor.stdout);
    assert_eq!(doctor.status.code(), Some(1), "{shown}");
    assert!(shown.contains("FAIL  operating status: STOP"), "{shown}");
    assert!(shown.contains("R04CPU (4800H)"), "{shown}");
    let (mut child, address) = hil_sim(
        &manifest_file,
        &["--variant", "rcpu", "--fault", "0101:1:end=C059"],
    );
    let doctor = common::cli(&["hil", "doctor", "--backend", &spec(&address)]);
    let _ = child.kill();
    let _ = child.wait();
    let shown = String::from_utf8_lossy(&doctor.stdout);
    assert!(shown.contains("end code C059H"), "{shown}");
    let bad = common::cli(&[
        "hil",
        "sim",
        "--manifest",
        manifest_file.to_str().expect("utf-8"),
        "--fault",
        "1401:0:drop",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--fault"));
}

/// A manifest that is no regular file (a FIFO, /dev/zero), or whose mailbox lies where no
/// sandbox may be or where its words would run past the device numbers (hash recomputed), is
/// refused by every command that reads one, before any socket is opened.
#[test]
fn a_bad_manifest_is_refused_before_any_socket() {
    let dir = common::scratch();
    let fifo = dir.path().join("fifo.json");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    let mut files = vec![
        (fifo, "not a regular file".to_string()),
        (
            std::path::PathBuf::from("/dev/zero"),
            "not a regular file".to_string(),
        ),
    ];
    for (mailbox, says) in [
        ("SD0", "not a data or link register"),
        ("Y0", "not a data or link register"),
        ("D16777200", "leaves no room"),
        ("D4294967290", "leaves no room"),
    ] {
        let mut m = iqr_manifest().clone();
        m.mailbox = mailbox.into();
        m.hash = m.compute_hash();
        let file = dir.path().join(format!("{mailbox}.json"));
        std::fs::write(&file, serde_json::to_string_pretty(&m).expect("json")).expect("write");
        files.push((file, says.to_string()));
    }
    // Nothing listens here: a command that got as far as a socket would say so instead.
    let unused = TcpListener::bind("127.0.0.1:0").expect("port");
    let address = unused.local_addr().expect("address");
    drop(unused);
    for (file, says) in &files {
        let spec = format!(
            "slmp:bench={address}?manifest={}&confirm=R04CPU&sandbox=manifest&variant=rcpu",
            file.display()
        );
        for args in [
            vec!["hil", "dry-run", "--backend", &spec],
            vec!["hil", "doctor", "--backend", &spec],
            vec!["run", "--backend", &spec],
            vec!["hil", "sim", "--manifest", file.to_str().expect("utf-8")],
        ] {
            let out = common::cli(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(stderr.contains(says.as_str()), "{args:?}: {stderr}");
        }
    }
}

/// `hil probe` against the simulated CPU's ASCII port: the requests as the manual writes them
/// are read (0000H, a device number's leading blanks included), a character that is no hex
/// digit is C050H, and the lowercase ones get the simulator's strict reading (C050H), which the
/// output says settles nothing. A closed port is an error with the address.
#[test]
fn a_protocol_probe_reads_the_end_codes_of_an_ascii_port() {
    let project = session();
    let m = manifest(&project, "mitsubishi-iqr");
    let sim = simulator(&project, &m, "rcpu", Vec::new());
    let address = sim.address().to_string();
    let out = common::cli(&["hil", "probe", "--address", &address, "--timeout", "5"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let answer = |id: &str| {
        (stdout.lines())
            .find(|l| l.starts_with(&format!("{id} ")))
            .unwrap_or_else(|| panic!("no line for {id}: {stdout}"))
            .to_string()
    };
    for id in [
        "as-written",
        "points-capital",
        "number-capital",
        "number-leading-blanks",
    ] {
        assert!(answer(id).contains(" 0000H "), "{}", answer(id));
    }
    assert!(answer("points-not-hex").contains(" C050H "), "{stdout}");
    assert!(
        answer("points-not-hex").contains("(mc-ascii/M4)"),
        "{stdout}"
    );
    for id in ["points-lowercase", "number-lowercase"] {
        assert!(answer(id).contains(" C050H "), "{}", answer(id));
        assert!(
            answer(id).contains("open question mc-ascii-lowercase"),
            "{}",
            answer(id)
        );
    }
    assert!(
        stdout.contains("5 of 5 answers as the manual states"),
        "{stdout}"
    );
    assert!(stdout.contains("never an observation"), "{stdout}");
    drop(sim);
    let closed = TcpListener::bind("127.0.0.1:0").expect("port");
    let port = closed.local_addr().expect("address").to_string();
    drop(closed);
    let out = common::cli(&["hil", "probe", "--address", &port, "--timeout", "1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(&port));
}

/// `hil probe` against virtual-plc's MC protocol server (its Q profile, ASCII code): the
/// requests it decodes judged by the MC protocol's rules. It reads the request as written and
/// a lowercase point count (codec.py:54 takes a-f), but refuses a hexadecimal device number
/// and a device number's leading blanks (codec.py:131, decimal digits only: mc-ascii/M10, M11),
/// and answers C05CH, not C050H, to a point count that is not hex (commands.py:221).
#[test]
fn virtual_plc_s_server_is_judged_by_the_mc_protocol() {
    use std::io::BufRead;
    let Some(python) = common::adapters_python("virtual_plc", "virtual-plc") else {
        return;
    };
    let script = common::root().join("adapters/python/tools/virtual_plc_server.py");
    let mut server = std::process::Command::new(python)
        .arg(script)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("the server starts");
    let mut line = String::new();
    std::io::BufReader::new(server.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("its address");
    let address = line
        .trim()
        .strip_prefix("listening on ")
        .expect(&line)
        .to_string();
    let out = common::cli(&["hil", "probe", "--address", &address, "--timeout", "5"]);
    drop(server.stdin.take());
    let _ = server.wait();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("2 of 5 answers as the manual states"),
        "{stdout}"
    );
    for (id, end_code) in [
        ("as-written", "0000H"),
        ("points-lowercase", "0000H"),
        ("number-capital", "C05CH"),
        ("number-leading-blanks", "C05CH"),
        ("points-not-hex", "C05CH"),
    ] {
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{id} ")))
            .unwrap_or("");
        assert!(line.contains(&format!(" {end_code} ")), "{id}: {stdout}");
    }
}
