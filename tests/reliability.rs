//! What the harness guarantees under interruption, hostile backends and odd corpora
//! (docs/reliability.md): no false pass, no silent skip, bounded time, no orphan process, saves
//! that compare with the run before.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{interpreter, python, root, scratch};
use plc_conformance::testing::load::ENV_SELF;
use plc_conformance::testing::model::project::{ExternalSettings, Launch};
use plc_conformance::testing::session::{BackendSource, Session};
use plc_conformance::Backend;
use plc_conformance::Verdict;
use plc_conformance::{run_one, verdicts as run_all, Paths, Project};

const BIN: &str = env!("CARGO_BIN_EXE_plc-conformance");

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Starts the binary on this project, its stdout and stderr piped.
fn spawn_cli(args: &[&str]) -> std::process::Child {
    Command::new(BIN)
        .args(["--root", root().to_str().unwrap_or(".")])
        .args(args)
        .env("NO_COLOR", "1")
        .env_remove("PLC_CONFORMANCE_CONFIG")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts")
}

/// Runs the binary on this project and kills it if it is still running after `limit`: a
/// watchdog, far above what the command takes, so that a test of a hang does not hang itself.
/// A killed command has no exit status, which the callers' checks of it catch.
fn cli_within(args: &[&str], limit: Duration) -> Output {
    let started = Instant::now();
    let mut child = spawn_cli(args);
    while child.try_wait().ok().flatten().is_none() {
        if started.elapsed() > limit {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().expect("the binary ends")
}

fn cli(args: &[&str]) -> Output {
    cli_within(args, Duration::from_secs(300))
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap_or_default()
}

fn mkfifo(at: &Path) {
    let status = Command::new("mkfifo")
        .arg(at)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", at.display());
}

/// The HABIN example of p.478, as the manual gives it.
fn one_case() -> String {
    common::habin_example("rel-example", "5A8DH")
}

// --- saved runs -------------------------------------------------------------------------------

/// `--save F --baseline F`: the baseline is the run saved before, so a new difference is new.
#[test]
fn saving_over_the_baseline_compares_with_the_previous_run() {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let saved = dir.join("run.json");
    let filter = "habin-fixed-4-digits-example";
    let first = cli(&[
        "diff",
        "--backend",
        "iqr",
        "--filter",
        filter,
        "--save",
        path(&saved),
        "--baseline",
        path(&saved),
        "--output",
        path(&dir.join("a.txt")),
    ]);
    assert_eq!(
        first.status.code(),
        Some(2),
        "no baseline yet is bad input: {}",
        text(&first.stderr)
    );
    let first = cli(&[
        "diff",
        "--backend",
        "iqr",
        "--filter",
        filter,
        "--save",
        path(&saved),
        "--output",
        path(&dir.join("a.txt")),
    ]);
    assert_eq!(first.status.code(), Some(0), "{}", text(&first.stderr));

    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    let habin = std::fs::read_to_string(root().join("vectors/mitsubishi-iqr/habin.yaml"))
        .expect("habin.yaml");
    std::fs::write(
        vectors.join("habin.yaml"),
        habin.replacen("after: {D200: 5A8DH}", "after: {D200: 5A8EH}", 1),
    )
    .expect("write");
    let again = |out: &str| {
        cli(&[
            "diff",
            "--backend",
            "iqr",
            "--vectors",
            path(&vectors),
            "--filter",
            filter,
            "--save",
            path(&saved),
            "--baseline",
            path(&saved),
            "--output",
            path(&dir.join(out)),
        ])
    };
    let second = again("b.txt");
    let err = text(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{err}");
    assert!(
        err.contains(": 4 new, 0 fixed, 0 changed, 0 unchanged"),
        "{err}"
    );
    // The save of the second run is now the baseline: nothing is new any more.
    let third = again("c.txt");
    let err = text(&third.stderr);
    assert_eq!(third.status.code(), Some(0), "{err}");
    assert!(
        err.contains(": 0 new, 0 fixed, 0 changed, 4 unchanged"),
        "{err}"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

// --- files that are not files ---------------------------------------------------------------

#[test]
fn a_fifo_is_refused_in_bounded_time_wherever_a_file_is_read_or_written() {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    std::fs::write(vectors.join("good.yaml"), one_case()).expect("write");
    mkfifo(&vectors.join("pipe.yaml"));
    let fifo = dir.join("fifo");
    mkfifo(&fifo);
    let limit = Duration::from_secs(20);
    let cases: [(Vec<&str>, &str); 5] = [
        (
            vec!["validate", path(&vectors)],
            "pipe.yaml: a FIFO (named pipe), not a regular file",
        ),
        (
            vec!["--config", path(&fifo), "list"],
            "fifo: a FIFO (named pipe), not a regular file",
        ),
        (
            vec!["diff", "--backend", "iqr", "--baseline", path(&fifo)],
            "fifo: cannot be read: a FIFO (named pipe), not a regular file",
        ),
        // An output FIFO that no process reads is refused rather than waited for.
        (
            vec!["run", "--backend", "iqr", "--output", path(&fifo)],
            "a FIFO (named pipe) that no process is reading",
        ),
        (
            vec!["diff", "--backend", "iqr", "--save", path(&fifo)],
            "a FIFO (named pipe) that no process is reading",
        ),
    ];
    for (args, message) in cases {
        // A FIFO read or written in place would block until the watchdog's limit: refused, the
        // command ends with its message instead.
        let out = cli_within(&args, limit);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    assert!(fifo.exists(), "the FIFO is left where it was");
}

/// A link planted where any command writes — a report, a saved run, a sweep's results and
/// vectors, a bench program, a scaffold, a recorded vector file — is refused with exit 2, and
/// the file it leads to is left as it was.
#[cfg(unix)]
#[test]
fn a_link_planted_at_any_output_leaves_its_decoy_unchanged() {
    use std::os::unix::fs::symlink;
    let scratch_dir = scratch();
    let dir = scratch_dir.path();
    let decoy = dir.join("decoy");
    std::fs::write(&decoy, "keep").expect("write");
    let plant = |name: &str| {
        let at = dir.join(name);
        std::fs::create_dir_all(at.parent().expect("parent")).expect("dir");
        symlink(&decoy, &at).expect("link");
        at
    };
    // `record` writes the vector files it reads: one linked in a folder of its own.
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    // A file with `unspecified` cases, which `record` would write observations into.
    let recorded = std::fs::read_to_string(root().join("vectors/mitsubishi-iqr/binha.yaml"))
        .expect("vector file");
    std::fs::write(dir.join("real.yaml"), &recorded).expect("write");
    symlink(dir.join("real.yaml"), vectors.join("case.yaml")).expect("link");
    let (report, saved, results, emitted) = (
        plant("report.txt"),
        plant("saved.json"),
        plant("sweep.txt"),
        plant("emitted.yaml"),
    );
    plant("bench/manifest.json");
    plant("scaffold/test_mylib_conformance.py");
    let (bench, scaffold) = (dir.join("bench"), dir.join("scaffold"));
    // An emulator that is no built-in model (which `record` refuses for another reason).
    let emulator = format!(
        "external:emulator=\"{}\" serve --profile mitsubishi-iqr",
        env!("CARGO_BIN_EXE_plc-conformance")
    );
    // Each refused with what it found: a link where an output goes, or (`init`, which writes
    // only where no file is) a file already there.
    let link = "a symbolic link";
    let commands: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["run", "--backend", "iqr", "--output", path(&report)],
            link,
        ),
        (
            vec!["run", "--backend", "iqr", "--save", path(&saved)],
            link,
        ),
        (
            vec!["diff", "--backend", "iqr", "--output", path(&report)],
            link,
        ),
        (
            vec![
                "sweep",
                "--operation",
                "value-to-hex",
                "--output",
                path(&results),
            ],
            link,
        ),
        (
            vec![
                "sweep",
                "--operation",
                "value-to-hex",
                "--emit",
                path(&emitted),
            ],
            link,
        ),
        (
            vec![
                "hil",
                "generate",
                "--profile",
                "mitsubishi-iqr",
                "--out",
                path(&bench),
            ],
            link,
        ),
        (
            vec!["init", "codec", "--python", "--dir", path(&scaffold)],
            "init writes only where no file is",
        ),
        (
            vec![
                "record",
                "--backend",
                &emulator,
                "--vectors",
                path(&vectors),
            ],
            link,
        ),
    ];
    for (args, message) in commands {
        let out = cli_within(&args, LIMIT);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert_eq!(
            std::fs::read_to_string(&decoy).expect("decoy"),
            "keep",
            "{args:?} wrote through the link"
        );
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("real.yaml")).expect("vector file"),
        recorded,
        "record wrote through the linked vector file"
    );
}

#[test]
fn a_device_or_a_read_fifo_is_written_in_place() {
    let out = cli_within(&["run", "--backend", "iqr", "--output", "/dev/null"], LIMIT);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let null = std::fs::metadata("/dev/null").expect("/dev/null");
    assert!(!null.is_file(), "/dev/null is still a device");

    let scratch_dir = scratch();
    let fifo = scratch_dir.path().join("report");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).expect("the FIFO reads"))
    };
    // The reader opens the FIFO on its own time: the report waits for it.
    let mut args = vec!["run", "--backend", "iqr", "--format", "json", "--output"];
    args.push(path(&fifo));
    let mut tries = 0;
    let out = loop {
        let out = cli_within(&args, LIMIT);
        let refused = text(&out.stderr).contains("no process is reading");
        if !refused || tries == 50 {
            break out;
        }
        tries += 1;
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&reader.join().expect("reader")).expect("the report is JSON");
    assert!(
        json["summary"]["passed"].as_u64().unwrap_or(0) > 0,
        "{json}"
    );
    assert!(fifo.exists(), "the FIFO is left where it was");
}

#[test]
fn a_write_error_ends_the_run_with_a_clear_error() {
    // A full disk.
    let out = cli_within(&["run", "--backend", "iqr", "--output", "/dev/full"], LIMIT);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("cannot write /dev/full"), "{err}");
    // A closed pipe on stdout: the reader has gone before the counts are written.
    let mut child = spawn_cli(&["run", "--backend", "iqr"]);
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("the binary ends");
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("error: cannot write stdout"), "{err}");
}

const LIMIT: Duration = Duration::from_secs(120);

#[test]
fn invalid_utf8_and_deep_nesting_are_reported_with_their_line() {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let file = dir.join("case.yaml");
    let one_case = one_case();
    let mut bytes = one_case.as_bytes().to_vec();
    let at = one_case.find("example on").expect("cite");
    bytes.insert(at, 0xFF);
    std::fs::write(&file, bytes).expect("write");
    let out = cli(&["validate", path(&file)]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("{}:7: invalid UTF-8 (byte FFH)", file.display())),
        "{err}"
    );

    let deep = format!(
        "{}{}1{}\n",
        one_case,
        "      D300: ".to_string() + &"[".repeat(100_000),
        "]".repeat(100_000)
    );
    std::fs::write(&file, deep).expect("write");
    let out = cli_within(&["validate", path(&file)], Duration::from_secs(60));
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{}:13: nested more than 64 levels deep",
            file.display()
        )),
        "{err}"
    );
}

// --- links in the corpus ----------------------------------------------------------------------

#[cfg(unix)]
#[test]
fn a_linked_folder_of_vectors_is_followed_and_a_loop_is_an_error() {
    use std::os::unix::fs::symlink;
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).expect("dir");
    std::fs::write(elsewhere.join("linked.yaml"), one_case()).expect("write");
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    symlink(&elsewhere, vectors.join("family")).expect("link");
    let out = cli(&["validate", path(&vectors)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).starts_with("ok: 1 case, 0 cross-vendor cases and"),
        "{}",
        text(&out.stdout)
    );

    symlink(&vectors, elsewhere.join("back")).expect("link");
    let out = cli_within(&["validate", path(&vectors)], Duration::from_secs(60));
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("a symbolic link loop"), "{err}");

    std::fs::remove_file(elsewhere.join("back")).expect("unlink");
    symlink(dir.join("nowhere"), vectors.join("dangling.yaml")).expect("link");
    let out = cli(&["validate", path(&vectors)]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("dangling.yaml: a symbolic link to nothing"),
        "{err}"
    );
}

// --- names that name nothing ------------------------------------------------------------------

#[test]
fn known_differences_for_a_backend_that_is_not_an_external_one_of_the_run_is_an_error() {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let file = dir.join("known.yaml");
    std::fs::write(&file, "differences: []\n").expect("write");
    for backend in [
        "iqr",
        "external:other=\"$PLC_CONFORMANCE\" serve --profile mitsubishi-iqr",
    ] {
        let out = cli(&[
            "run",
            "--backend",
            backend,
            "--known-differences",
            &format!("iqr={}", file.display()),
            "--filter",
            "habin-fixed-4-digits-example",
        ]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(
                "--known-differences names `iqr`, which is not an `external:` or in-process \
                 backend of this run"
            ),
            "{err}"
        );
    }
}

// --- hostile backends -------------------------------------------------------------------------

fn fixtures() -> PathBuf {
    root().join("tests/fixtures/external")
}

fn faulty_command(mode: &str, trigger: &str) -> String {
    format!(
        "{} {} {mode} '{trigger}'",
        interpreter().unwrap_or("python3"),
        fixtures().join("faulty_adapter.py").display()
    )
}

/// The faulty adapter started through `sh -c`, as a project file or `--backend` starts it.
fn faulty(mode: &str, trigger: &str) -> ExternalSettings {
    let mut spec = ExternalSettings::new("faulty", Launch::Shell(faulty_command(mode, trigger)));
    spec.env = vec![(ENV_SELF.into(), BIN.into())];
    spec.profile = Some("mitsubishi-iqr".into());
    spec.timeout = Duration::from_secs(3);
    spec.startup_timeout = Duration::from_secs(10);
    spec
}

fn fixture_session(spec: ExternalSettings) -> Session {
    let paths = Paths {
        vendors: root().join("vendors"),
        vectors: vec![fixtures().join("vectors")],
    };
    let mut session = Session::with_references(
        Project::load(&paths).unwrap_or_else(|e| panic!("fixture corpus: {e}")),
    );
    session
        .add(BackendSource::Process(spec), true)
        .unwrap_or_else(|e| panic!("the faulty adapter does not start: {e}"));
    session
}

/// The fixture corpus's three verdicts on the faulty backend, batched or one at a time.
fn verdicts(session: &Session, batched: bool) -> Vec<Verdict> {
    let backend: Vec<std::sync::Arc<dyn Backend>> = session
        .backends
        .iter()
        .filter(|b| b.name() == "faulty")
        .cloned()
        .collect();
    let trials = session.plan(&backend);
    assert_eq!(trials.len(), 3);
    if batched {
        run_all(&trials)
    } else {
        trials.iter().map(run_one).collect()
    }
}

#[test]
fn blank_lines_and_a_byte_order_mark_are_tolerated() {
    if !python() {
        return;
    }
    let session = fixture_session(faulty("blank-lines", "*"));
    for batched in [true, false] {
        let v = verdicts(&session, batched);
        assert!(v.iter().all(|v| *v == Verdict::Conforms), "{v:?}");
    }
}

#[test]
fn one_word_given_two_values_in_one_answer_is_a_protocol_error() {
    if !python() {
        return;
    }
    for (mode, says) in [
        (
            "two-names",
            "`D0200` and `D200` in `writes` are the same word, D200",
        ),
        ("two-ranges", "D201 is given twice in `memory`"),
        ("repeated-key", "`D200` is given twice in `writes`"),
    ] {
        let session = fixture_session(faulty(mode, "ext-target"));
        let v = verdicts(&session, true);
        assert_eq!(v[0], Verdict::Conforms, "{mode}");
        assert_eq!(v[1].label(), "protocol-error", "{mode}: {:?}", v[1]);
        assert!(format!("{:?}", v[1]).contains(says), "{mode}: {:?}", v[1]);
        assert_eq!(v[2], Verdict::Conforms, "{mode}");
    }
}

#[test]
fn a_backend_under_sh_that_closes_its_stdout_has_crashed() {
    if !python() {
        return;
    }
    let session = fixture_session(faulty("close-stdout", "ext-target"));
    let v = verdicts(&session, true);
    assert_eq!(v[1].label(), "crashed", "{:?}", v[1]);
    assert!(
        format!("{:?}", v[1]).contains("closed its stdout but did not exit"),
        "{:?}",
        v[1]
    );
    assert_eq!(v[2], Verdict::Conforms);
}

#[test]
fn the_circuit_breaker_stops_asking_a_backend_that_fails_every_case() {
    if !python() {
        return;
    }
    for (mode, label) in [("hang", "timeout"), ("crash", "crashed")] {
        for batched in [true, false] {
            let mut spec = faulty(mode, "*");
            spec.timeout = Duration::from_millis(500);
            // Each trial is two requests, one per fill: the third fault in a row is the
            // second trial's first.
            spec.max_consecutive_faults = 3;
            let session = fixture_session(spec);
            let v = verdicts(&session, batched);
            assert_eq!(v[0].label(), label, "{mode}: {:?}", v[0]);
            assert_eq!(v[1].label(), label, "{mode}: {:?}", v[1]);
            assert_eq!(v[2].label(), "unreachable", "{mode}: {:?}", v[2]);
            assert!(v[2].is_failure(), "not run is a failure, never a pass");
            let text = format!("{:?}", v[2]);
            assert!(
                text.contains(&format!(
                    "not run: faulty failed 3 requests in a row (the last: {label})"
                )),
                "{text}"
            );
        }
    }
}

#[test]
fn a_fault_while_the_next_message_is_queued_loses_no_case() {
    if !python() {
        return;
    }
    for (mode, label) in [("crash", "crashed"), ("hang", "timeout")] {
        let mut spec = faulty(mode, "ext-target");
        // One request per message: while one is answered the next is already queued, and the
        // process it was queued to is the one that fails.
        spec.batch = 1;
        spec.timeout = Duration::from_millis(500);
        let session = fixture_session(spec);
        let v = verdicts(&session, true);
        assert_eq!(v[0], Verdict::Conforms, "{mode}: {:?}", v[0]);
        assert_eq!(v[1].label(), label, "{mode}: {:?}", v[1]);
        assert_eq!(v[2], Verdict::Conforms, "{mode}: {:?}", v[2]);
    }
}

/// Whether a process is still there (a zombie is not: it has ended and waits to be reaped).
fn alive(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(stat) => stat
            .rsplit_once(") ")
            .and_then(|(_, rest)| rest.chars().next())
            .is_some_and(|state| state != 'Z' && state != 'X'),
        Err(_) => false,
    }
}

fn pids(file: &Path) -> Vec<i32> {
    std::fs::read_to_string(file)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.trim().parse().ok())
        .collect()
}

fn all_ended(pids: &[i32], within: Duration) -> Vec<i32> {
    let until = Instant::now() + within;
    loop {
        let left: Vec<i32> = pids.iter().copied().filter(|p| alive(*p)).collect();
        if left.is_empty() || Instant::now() > until {
            return left;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_crashed_adapters_helpers_are_killed_with_it() {
    if !python() {
        return;
    }
    let scratch_dir = scratch();
    let file = scratch_dir.path().join("pids");
    let mut spec = faulty("crash", "ext-target");
    spec.env
        .push(("FAULTY_PIDS".into(), file.display().to_string()));
    let session = fixture_session(spec);
    let v = verdicts(&session, true);
    assert_eq!(v[1].label(), "crashed");
    assert_eq!(v[2], Verdict::Conforms, "started again");
    let all = pids(&file);
    // The target crashes under each fill: three starts, three processes each.
    assert_eq!(all.len(), 9, "{all:?}");
    let crashed = &all[..6];
    assert_eq!(
        all_ended(crashed, Duration::from_secs(5)),
        Vec::<i32>::new(),
        "the crashed adapter's helper and model outlive it"
    );
    drop(session);
    assert_eq!(
        all_ended(&all, Duration::from_secs(5)),
        Vec::<i32>::new(),
        "a process of the backend outlives the harness's shutdown"
    );
}

/// Runs `diff` with an adapter that starts helpers, signals it once the adapter has started
/// them (and `settle` more), and returns its output with the adapter's processes.
#[cfg(target_os = "linux")]
fn interrupted_run(
    mode: &str,
    trigger: &str,
    signal: i32,
    settle: Duration,
) -> (Output, Vec<i32>, String) {
    let vectors = fixtures().join("vectors");
    interrupted(
        &["diff", "--vectors", path(&vectors)],
        mode,
        trigger,
        signal,
        settle,
    )
}

/// Runs the command `what` (with `--format json --output REPORT`, the adapter as its backend)
/// and interrupts it as [`interrupted_run`] does.
#[cfg(target_os = "linux")]
fn interrupted(
    what: &[&str],
    mode: &str,
    trigger: &str,
    signal: i32,
    settle: Duration,
) -> (Output, Vec<i32>, String) {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let file = dir.join("pids");
    let report = dir.join("report.json");
    let backend = format!("external:slow={}", faulty_command(mode, trigger));
    let mut child = Command::new(BIN)
        .args(["--root", path(root())])
        .args(what)
        .args(["--format", "json", "--output", path(&report)])
        .args(["--backend", &backend, "--timeout", "60"])
        .env("NO_COLOR", "1")
        .env("FAULTY_PIDS", &file)
        .env_remove("PLC_CONFORMANCE_CONFIG")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let want = if mode == "hang-at-start" { 2 } else { 3 };
    let until = Instant::now() + Duration::from_secs(30);
    while pids(&file).len() < want && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(settle);
    let pid = i32::try_from(child.id()).expect("pid");
    // SAFETY: kill(2) takes no pointers; the child has not been waited for.
    unsafe {
        libc::kill(pid, signal);
    }
    // A watchdog, not a measure: the run ends by itself on the signal, or is killed here.
    let started = Instant::now();
    let mut ended = false;
    while !ended && started.elapsed() < Duration::from_secs(20) {
        ended = child.try_wait().ok().flatten().is_some();
        std::thread::sleep(Duration::from_millis(10));
    }
    let _ = child.kill();
    let out = child.wait_with_output().expect("the binary ends");
    assert!(ended, "the interrupted run did not end by itself");
    let report = std::fs::read_to_string(&report).unwrap_or_default();
    (out, pids(&file), report)
}

#[cfg(target_os = "linux")]
#[test]
fn sigint_ends_a_run_with_what_it_has_and_no_backend_process_survives() {
    if !python() {
        return;
    }
    let (out, pids, report) = interrupted_run(
        "hang",
        "ext-target",
        libc::SIGINT,
        Duration::from_millis(1500),
    );
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert_eq!(pids.len(), 3, "{pids:?}");
    assert_eq!(all_ended(&pids, Duration::from_secs(5)), Vec::<i32>::new());
    assert!(report.contains("\"interrupted\": true"), "{report}");
    assert!(report.contains("slow::habin::ext-before::rcpu"), "{report}");
    // The trial the interruption killed and those after it were not run: none failed.
    let report: serde_json::Value = serde_json::from_str(&report).expect("JSON");
    assert_eq!(report["summary"]["failed"], 0, "{report}");
    assert!(report["summary"]["skipped"].as_u64() > Some(0), "{report}");
}

#[cfg(target_os = "linux")]
#[test]
fn sigterm_during_the_handshake_kills_the_backend_and_its_helpers() {
    if !python() {
        return;
    }
    let (out, pids, _) = interrupted_run(
        "hang-at-start",
        "ext-target",
        libc::SIGTERM,
        Duration::from_millis(200),
    );
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(143), "{err}");
    assert_eq!(pids.len(), 2, "{pids:?}");
    assert_eq!(all_ended(&pids, Duration::from_secs(5)), Vec::<i32>::new());
}

#[cfg(target_os = "linux")]
#[test]
fn sigterm_ends_a_sweep_whose_backend_hangs_and_no_backend_process_survives() {
    if !python() {
        return;
    }
    let sweep = [
        "sweep",
        "--operation",
        "hex-to-value",
        "--generator",
        "random",
        "--count",
        "50",
        "--seed",
        "1",
        "--digits",
        "4",
    ];
    for signal in [libc::SIGTERM, libc::SIGINT] {
        let (out, pids, report) =
            interrupted(&sweep, "hang", "*", signal, Duration::from_millis(500));
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(128 + signal), "{err}");
        assert_eq!(pids.len(), 3, "{pids:?}");
        assert_eq!(all_ended(&pids, Duration::from_secs(5)), Vec::<i32>::new());
        assert!(report.contains("\"interrupted\": true"), "{report}");
    }
}

// --- exit statuses that do not lie ------------------------------------------------------------

#[test]
fn a_backend_that_runs_no_trial_fails_the_run_unless_allowed() {
    if !python() {
        return;
    }
    let backend = format!("external:idle={}", faulty_command("claims-nothing", "-"));
    let vectors = fixtures().join("vectors");
    let args = ["run", "--vectors", path(&vectors), "--backend", &backend];
    let out = cli(&args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        text(&out.stdout).contains("idle: 0 passed, 0 failed, 3 skipped"),
        "{}",
        text(&out.stdout)
    );
    assert!(
        err.contains(
            "error: backend `idle` ran no trial: all 3 of its trials were skipped (idle does not \
             implement HABIN on rcpu)"
        ),
        "{err}"
    );
    let out = cli(&[&args[..], &["--allow-empty"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

#[test]
fn against_a_backend_of_another_family_answering_garbage_fails() {
    if !python() {
        return;
    }
    let backend = format!("external:garbage={}", faulty_command("garbage", "*"));
    let out = cli(&[
        "diff",
        "--backend",
        "fx5",
        "--against",
        &backend,
        "--filter",
        "cross-vendor::fx5::hexa-16bit::xv-h2v-4",
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("protocol error"), "{stdout}");
    assert!(!stdout.contains(", 0 differ"), "{stdout}");
}

// --- hostile text -----------------------------------------------------------------------------

#[test]
fn hostile_text_never_reaches_a_terminal_or_breaks_xml() {
    if !python() {
        return;
    }
    let scratch_dir = scratch();
    let dir = scratch_dir.path().to_path_buf();
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    let fixture = std::fs::read_to_string(fixtures().join("vectors/habin.yaml")).expect("read");
    // A cite with a terminal escape and a character XML forbids, on a case that fails.
    let hostile = fixture.replacen(
        "cite: \"the same example at other devices\"",
        "cite: \"\\e[2J\\e]0;owned\\a \\uFFFE cleared\"",
        1,
    );
    assert_ne!(hostile, fixture, "the fixture changed");
    std::fs::write(vectors.join("habin.yaml"), hostile).expect("write");
    let backend = format!(
        "external:hostile={}",
        faulty_command("hostile-text", "ext-target")
    );
    let base = ["--vectors", path(&vectors), "--backend", &backend];
    let out = cli(&[&["run"][..], &base[..]].concat());
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("hostile::habin::ext-target::rcpu crashed"),
        "{stdout}"
    );
    assert!(
        !stdout.contains('\u{1b}') && !stdout.contains('\u{7}'),
        "{stdout:?}"
    );
    assert!(stdout.contains("\\x1B[31mred"), "{stdout}");
    assert!(stdout.contains("\\x1B[2J"), "{stdout}");
    for format in ["junit", "html"] {
        let file = dir.join(format!("report.{format}"));
        let out = cli(&[
            &["diff", "--format", format, "--output", path(&file)][..],
            &base[..],
        ]
        .concat());
        assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
        let xml = std::fs::read_to_string(&file).expect("report");
        let bad: Vec<char> = xml
            .chars()
            .filter(|c| forbidden_in_xml_1_0(*c) || *c == '\u{1b}')
            .collect();
        assert!(bad.is_empty(), "{format}: {bad:?}");
        let mut reader = quick_xml::Reader::from_str(&xml);
        loop {
            match reader.read_event() {
                Ok(quick_xml::events::Event::Eof) => break,
                Ok(_) => {}
                Err(e) => panic!("{format} is not well-formed: {e}"),
            }
        }
        assert!(xml.contains("\\u{FFFE}"), "{format}");
    }
}

/// Temporary folders come from `tempfile`, which removes them when the test ends, passes or
/// fails: a folder named by hand under the temporary directory outlives every run.
#[test]
fn tests_make_temporary_folders_only_through_tempfile() {
    let mut named_by_hand = Vec::new();
    for entry in std::fs::read_dir(root().join("tests")).expect("tests/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|x| x == "rs") {
            let text = std::fs::read_to_string(&path).expect("readable");
            let needle = ["std::env::", "temp_dir()"].concat();
            if text.contains(&needle) {
                named_by_hand.push(path.display().to_string());
            }
        }
    }
    assert!(named_by_hand.is_empty(), "{named_by_hand:?}");
}

/// A backend that starts a helper in a session of its own (`setsid`, so neither its process
/// group nor its session ends with it) and then exits: the helper, which still holds the
/// backend's stdout, is adopted by the command and ended with the backend.
#[cfg(target_os = "linux")]
#[test]
fn a_helper_that_leaves_the_backend_s_session_does_not_outlive_the_run() {
    if !python() {
        return;
    }
    let scratch_dir = scratch();
    let file = scratch_dir.path().join("pids");
    let backend = format!(
        "external:orphaning={}",
        faulty_command("orphan", "ext-target")
    );
    let out = Command::new(BIN)
        .args(["--root", path(root())])
        .args(["run", "--vectors", path(&fixtures().join("vectors"))])
        .args(["--backend", &backend, "--timeout", "10"])
        .env("NO_COLOR", "1")
        .env("FAULTY_PIDS", &file)
        .env_remove("PLC_CONFORMANCE_CONFIG")
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs");
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("crashed"), "{stdout}");
    let helpers = pids(&file);
    assert!(!helpers.is_empty(), "the adapter started no helper");
    assert_eq!(
        all_ended(&helpers, Duration::from_secs(5)),
        Vec::<i32>::new()
    );
}

/// XML 1.0's Char production leaves out these code points (a document may not hold them, even
/// as references), written here from the specification rather than taken from the writer.
fn forbidden_in_xml_1_0(c: char) -> bool {
    let allowed = matches!(c, '\t' | '\n' | '\r')
        || ('\u{20}'..='\u{d7ff}').contains(&c)
        || ('\u{e000}'..='\u{fffd}').contains(&c)
        || c >= '\u{10000}';
    !allowed
}
