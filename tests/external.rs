//! External backends: each way a backend can fail is an outcome with its own label, never a pass
//! and never a harness crash; the protocol path itself conforms; known differences cannot rot.
//!
//! The faulty backend (`tests/fixtures/external/faulty_adapter.py`) forwards to the reference
//! model served by the binary and sabotages one case, `ext-target`, of a three-case corpus:
//! the case before it and the one after it must still conform.
//!
//! These tests need the binary: a backend that forwards to `plc-conformance serve`, the command
//! line, the corpus's own test binary. The white-box tests with no binary to run (the adapters
//! and codecs written with the helpers, a command that does not exist, the protocol schema) are
//! unit tests beside the code, in `src/backend/external/white_box.rs`.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use common::{interpreter, python};
use std::time::Duration;

use plc_conformance::testing::backend::external::ExternalErrorKind;
use plc_conformance::testing::load::{load_project, ENV_SELF, FILE_NAME};
use plc_conformance::testing::model::project::{ExternalSettings, Launch};
use plc_conformance::testing::session::{BackendSource, Session, SetupError};
use plc_conformance::Backend;
use plc_conformance::Trial;
use plc_conformance::Verdict;
use plc_conformance::{run_one, verdicts as run_all, Paths, Project};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn fixtures() -> PathBuf {
    root().join("tests/fixtures/external")
}

const BIN: &str = env!("CARGO_BIN_EXE_plc-conformance");

fn fixture_session() -> Session {
    let paths = Paths {
        vendors: root().join("vendors"),
        vectors: vec![fixtures().join("vectors")],
    };
    Session::with_references(
        Project::load(&paths).unwrap_or_else(|e| panic!("fixture corpus: {e}")),
    )
}

fn corpus_session() -> Session {
    Session::with_references(
        Project::load(&Paths::under(root())).unwrap_or_else(|e| panic!("corpus: {e}")),
    )
}

fn python_backend(name: &str, script: &Path, args: &[&str]) -> ExternalSettings {
    let python = interpreter().unwrap_or("python3").to_string();
    let mut argv = vec![python, script.display().to_string()];
    argv.extend(args.iter().map(|a| a.to_string()));
    let mut spec = ExternalSettings::new(name, Launch::Exec(argv));
    spec.env = vec![(ENV_SELF.into(), BIN.into())];
    spec.profile = Some("mitsubishi-iqr".into());
    spec.timeout = Duration::from_secs(3);
    spec.startup_timeout = Duration::from_secs(10);
    spec
}

fn faulty(mode: &str) -> ExternalSettings {
    python_backend(
        "faulty",
        &fixtures().join("faulty_adapter.py"),
        &[mode, "ext-target"],
    )
}

/// The trials of the one external backend in a session.
fn trials_of(session: &Session, name: &str) -> Vec<Trial> {
    let backend: Vec<Arc<dyn Backend>> = session
        .backends
        .iter()
        .filter(|b| b.name() == name)
        .cloned()
        .collect();
    session.plan(&backend)
}

/// Verdicts by case id, run one trial at a time (as `cargo test` does) or in one batch (as
/// `plc-conformance run` does).
fn verdicts(session: &Session, name: &str, batched: bool) -> Vec<(String, Verdict)> {
    let trials = trials_of(session, name);
    assert!(
        trials.iter().all(|t| t.skip.is_none()),
        "no trial of the fixture corpus is skipped"
    );
    let verdicts: Vec<Verdict> = if batched {
        run_all(&trials)
    } else {
        trials.iter().map(run_one).collect()
    };
    trials
        .iter()
        .map(|t| t.case_id().to_string())
        .zip(verdicts)
        .collect()
}

fn with_faulty(mode: &str) -> Session {
    let mut session = fixture_session();
    session
        .add(BackendSource::Process(faulty(mode)), true)
        .unwrap_or_else(|e| panic!("faulty backend in mode {mode} does not start: {e}"));
    session
}

/// Runs the faulty backend both ways and checks that only `ext-target` fails, with `label`;
/// returns the failure's text.
fn assert_only_target_fails(mode: &str, label: &str) -> String {
    let session = with_faulty(mode);
    let mut text = String::new();
    for batched in [false, true] {
        let verdicts = verdicts(&session, "faulty", batched);
        assert_eq!(verdicts.len(), 3, "{verdicts:?}");
        for (case, verdict) in &verdicts {
            if case == "ext-target" {
                assert_eq!(verdict.label(), label, "{mode}: {verdict:?}");
                assert!(verdict.is_failure());
                text = format!("{verdict:?}");
            } else {
                assert_eq!(
                    verdict,
                    &Verdict::Conforms,
                    "{mode} (batched: {batched}): {case} must conform once the backend restarts"
                );
            }
        }
    }
    text
}

#[test]
fn a_crash_fails_the_case_shows_stderr_and_the_run_goes_on() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("crash", "crashed");
    assert!(text.contains("exited with status 3"), "{text}");
    assert!(
        text.contains("| faulty adapter: crash on ext-target"),
        "stderr is shown with the case: {text}"
    );
}

#[test]
fn a_backend_that_cannot_restart_leaves_the_rest_unreachable() {
    if !python() {
        return;
    }
    let scratch = tempfile::tempdir().expect("temp dir");
    let marker = scratch.path().join("marker");
    let mut spec = faulty("crash-for-good");
    spec.env
        .push(("FAULTY_MARKER".into(), marker.display().to_string()));
    let mut session = fixture_session();
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let v = verdicts(&session, "faulty", true);
    assert_eq!(v[0].1, Verdict::Conforms);
    assert_eq!(v[1].1.label(), "crashed");
    assert_eq!(v[2].1.label(), "unreachable", "{:?}", v[2].1);
    let text = format!("{:?}", v[2].1);
    assert!(text.contains("could not be started again"), "{text}");
    assert!(text.contains("refusing to start after the crash"), "{text}");
}

#[test]
fn a_killed_backend_is_a_crash() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("kill", "crashed");
    assert!(text.contains("killed by signal 9 (SIGKILL)"), "{text}");
}

#[test]
fn a_hung_backend_times_out_and_is_replaced() {
    if !python() {
        return;
    }
    let mut session = fixture_session();
    let mut spec = faulty("hang");
    spec.timeout = Duration::from_millis(1500);
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let verdicts = verdicts(&session, "faulty", true);
    let target = &verdicts[1];
    assert_eq!(target.0, "ext-target");
    assert_eq!(target.1.label(), "timeout", "{:?}", target.1);
    let text = format!("{:?}", target.1);
    assert!(text.contains("within 1.5 s"), "{text}");
    assert!(
        text.contains("faulty adapter: hang on ext-target"),
        "{text}"
    );
    assert_eq!(verdicts[2].1, Verdict::Conforms);
}

#[test]
fn a_line_that_is_not_json_is_a_protocol_error_quoting_it() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("garbage", "protocol-error");
    assert!(
        text.contains("`Segmentation fault? no, just not JSON`"),
        "{text}"
    );
}

#[test]
fn json_that_is_not_a_protocol_message_is_a_protocol_error() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("wrong-shape", "protocol-error");
    assert!(text.contains("not a protocol message"), "{text}");
    assert!(text.contains(r#"\"writes\": \"D200\""#), "{text}");
}

#[test]
fn an_answer_for_another_request_is_a_protocol_error() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("wrong-id", "protocol-error");
    assert!(text.contains("an answer for request"), "{text}");
}

#[test]
fn an_oversized_line_is_cut_and_reported() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("oversized", "protocol-error");
    assert!(text.contains("over the 1024 KiB limit"), "{text}");
    assert!(
        text.len() < 4096,
        "the quote of a 2 MiB line is short: {} bytes",
        text.len()
    );
}

#[test]
fn unsupported_for_a_claimed_case_is_a_difference() {
    if !python() {
        return;
    }
    let text = assert_only_target_fails("unsupported", "unsupported");
    assert!(text.contains("not today"), "{text}");
}

#[test]
fn a_wrong_value_differs() {
    if !python() {
        return;
    }
    assert_only_target_fails("differ", "differs");
}

fn start_error(spec: ExternalSettings) -> (ExternalErrorKind, String) {
    let mut session = fixture_session();
    match session.add(BackendSource::Process(spec), true) {
        Err(SetupError::External(e)) => (e.kind.clone(), e.to_string()),
        Err(other) => panic!("unexpected error: {other}"),
        Ok(_) => panic!("the backend started"),
    }
}

#[test]
fn handshake_failures_are_errors_before_any_case() {
    if !python() {
        return;
    }
    let (kind, text) = start_error(faulty("exit-at-start"));
    assert!(matches!(kind, ExternalErrorKind::Handshake(_)), "{text}");
    assert!(
        text.contains("exited with status 1 before answering hello"),
        "{text}"
    );
    assert!(
        text.contains("| faulty adapter: cannot open the emulator image"),
        "{text}"
    );

    let mut spec = faulty("hang-at-start");
    spec.startup_timeout = Duration::from_secs(1);
    let (kind, text) = start_error(spec);
    assert!(matches!(kind, ExternalErrorKind::Handshake(_)), "{text}");
    assert!(text.contains("no answer to hello within 1 s"), "{text}");

    let (_, text) = start_error(faulty("bad-hello"));
    assert!(text.contains("`HELLO, this is not JSON`"), "{text}");

    let (kind, text) = start_error(faulty("version"));
    assert_eq!(kind, ExternalErrorKind::Version { theirs: 99 });
    assert!(
        text.contains("speaks protocol version 99; this harness speaks versions 1 to 5"),
        "{text}"
    );

    let (kind, text) = start_error(faulty("profile"));
    assert!(matches!(kind, ExternalErrorKind::Capabilities(_)), "{text}");
    assert!(
        text.contains("configured as implementing profile `mitsubishi-iqr` but its handshake claims `mitsubishi-fx5`"),
        "{text}"
    );

    let (_, text) = start_error(faulty("claims-unknown"));
    assert!(text.contains("claims instruction `FROB`"), "{text}");
}

fn served(profile: &str) -> ExternalSettings {
    let mut spec = ExternalSettings::new(
        format!("served-{profile}"),
        Launch::Shell(format!("\"$PLC_CONFORMANCE\" serve --profile {profile}")),
    );
    spec.env = vec![(ENV_SELF.into(), BIN.into())];
    spec.cwd = Some(root().to_path_buf());
    spec
}

fn served_reference() -> ExternalSettings {
    served("mitsubishi-iqr")
}

/// Every built-in model through the protocol must judge exactly like the model called
/// directly, on every trial of the corpus and both ways of running.
#[test]
fn every_served_reference_model_matches_the_built_in_one_everywhere() {
    let mut session = corpus_session();
    let builtin: Vec<Arc<dyn Backend>> = session.backends.clone();
    assert!(!builtin.is_empty());
    for model in builtin {
        let served = session
            .add(BackendSource::Process(served(model.profile())), true)
            .unwrap_or_else(|e| panic!("serve {} starts: {e}", model.profile()))[0]
            .clone();
        let direct: Vec<Verdict> = run_all(&session.plan(std::slice::from_ref(&model)));
        let served_trials = trials_of(&session, served.name());
        assert_eq!(direct.len(), served_trials.len(), "{}", model.name());
        let batched = run_all(&served_trials);
        for ((trial, d), b) in served_trials.iter().zip(&direct).zip(&batched) {
            assert_eq!(d, b, "{} batched", trial.name());
            let single = run_one(trial);
            assert_eq!(d, &single, "{} one at a time", trial.name());
            assert!(!d.is_failure(), "{}: {d:?}", trial.name());
        }
    }
}

/// A wrong SD0 is its own behaviour in the reports, not "wrong words": the JSON record names
/// the register, and the text shows it alone.
#[test]
fn a_wrong_error_register_is_reported_as_such() {
    if !python() {
        return;
    }
    let script = fixtures().join("habin_adapter.py");
    let backend = format!("external:habin-py=python3 {} sd0-stale", script.display());
    let filter = "habin-py::habin::habin-fixed-lowercase-is-invalid::rcpu-no-sm705";
    let out = common::cli(&["run", "--backend", &backend, "--filter", filter]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("  SD0 (where the error code lands): expected 3401H, actual 0000H\n"),
        "{text}"
    );
    assert!(!text.contains("memory (- expected"), "{text}");
    let out = common::cli(&[
        "run",
        "--backend",
        &backend,
        "--filter",
        filter,
        "--format",
        "json",
    ]);
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let behaviour = &doc["records"][0]["behaviour"];
    assert_eq!(behaviour["behaviour"], "wrong-register", "{behaviour}");
    assert_eq!(behaviour["registers"][0], "SD0", "{behaviour}");
    assert_eq!(doc["records"][0]["shown"], "SD0 not the code");
}

fn known_file(dir: &Path, name: &str, yaml: &str) -> PathBuf {
    let file = dir.join(name);
    std::fs::write(&file, yaml).expect("write known file");
    file
}

#[test]
fn known_differences_pass_stale_entries_fail_and_faults_stay_faults() {
    if !python() {
        return;
    }
    let scratch = tempfile::tempdir().expect("temp dir");
    let listing = |case: &str| {
        format!("differences:\n  - case: {case}\n    reason: \"the emulator rounds D200 down\"\n")
    };
    // Listed and differs: a known difference, not a failure.
    let mut session = fixture_session();
    let mut spec = faulty("differ");
    spec.known_differences = Some(known_file(
        scratch.path(),
        "differ.yaml",
        &listing("ext-target"),
    ));
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let v = verdicts(&session, "faulty", true);
    assert_eq!(v[1].1.label(), "known-difference");
    assert!(!v[1].1.is_failure());
    assert!(format!("{:?}", v[1].1).contains("differ.yaml:2"));

    // Listed but conforms: a stale entry, a failure.
    let mut session = fixture_session();
    let mut spec = faulty("differ");
    spec.known_differences = Some(known_file(
        scratch.path(),
        "stale.yaml",
        &listing("ext-before"),
    ));
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let v = verdicts(&session, "faulty", false);
    assert_eq!(v[0].1.label(), "stale-entry");
    assert!(v[0].1.is_failure());
    assert_eq!(
        v[1].1.label(),
        "differs",
        "an unlisted difference still fails"
    );

    // A crash on a listed case is still a crash.
    let mut session = fixture_session();
    let mut spec = faulty("crash");
    spec.known_differences = Some(known_file(
        scratch.path(),
        "crash.yaml",
        &listing("ext-target"),
    ));
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let v = verdicts(&session, "faulty", true);
    assert_eq!(v[1].1.label(), "crashed");
}

#[test]
fn a_known_differences_file_naming_an_unknown_case_is_an_error_with_its_line() {
    let scratch = tempfile::tempdir().expect("temp dir");
    let mut session = fixture_session();
    let mut spec = served_reference();
    let file = known_file(
        scratch.path(),
        "unknown.yaml",
        "differences:\n  - case: ext-target\n    reason: fine\n  - case: no-such-case\n    reason: typo\n    variant: rcpu\n",
    );
    spec.known_differences = Some(file.clone());
    match session.add(BackendSource::Process(spec), true) {
        Err(SetupError::Load(e)) => {
            let text = e.to_string();
            assert!(
                text.contains(&format!(
                    "{}:4: differences[1].case: unknown case id `no-such-case`",
                    file.display()
                )),
                "{text}"
            );
        }
        Err(other) => panic!("unexpected error: {other}"),
        Ok(_) => panic!("an unknown case id was accepted"),
    }
}

/// The project file's pymcprotocol backend, run on the corpus: every difference it shows must be
/// in its known-differences file, and every entry there must still differ.
#[test]
fn pymcprotocol_differs_exactly_where_its_known_differences_say() {
    let (file, explicit) = (root().join(FILE_NAME), true);
    let project = load_project(&file, explicit, Path::new(BIN)).expect("project file loads");
    let Some(pymc) = project
        .configured
        .iter()
        .find(|c| c.settings.name == "pymcprotocol")
    else {
        let why = project
            .skipped
            .iter()
            .find(|w| w.name == "pymcprotocol")
            .expect("plc-conformance.yaml configures pymcprotocol");
        eprintln!(
            "skipped: {why}; install it with `python3 -m venv .venv-adapters && \
             .venv-adapters/bin/pip install -r adapters/python/requirements.txt` (CI does)"
        );
        return;
    };
    let mut session = corpus_session();
    session
        .add(BackendSource::Process(pymc.settings.clone()), true)
        .expect("pymcprotocol adapter starts");
    let trials = trials_of(&session, "pymcprotocol");
    let verdicts = run_all(&trials);
    let failures: Vec<String> = trials
        .iter()
        .zip(&verdicts)
        .filter(|(_, v)| v.is_failure())
        .map(|(t, v)| format!("{}: {v:?}", t.name()))
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
    let count = |label: &str| verdicts.iter().filter(|v| v.label() == label).count();
    assert!(count("conforms") > 0, "pymcprotocol conforms nowhere");
    assert!(
        count("known-difference") > 0,
        "the lowercase-digit finding is gone"
    );
}

#[test]
fn the_command_line_reports_a_failed_handshake_before_any_case() {
    if !python() {
        return;
    }
    let script = fixtures().join("faulty_adapter.py");
    let backend = format!("external:broken=python3 {} version", script.display());
    let out = common::cli(&["run", "--backend", &backend]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("error: external backend `broken`"),
        "{stderr}"
    );
    assert!(stderr.contains("speaks protocol version 99"), "{stderr}");
    assert!(out.stdout.is_empty(), "no case ran");
}

#[test]
fn the_command_line_runs_an_external_backend_and_labels_its_crash() {
    if !python() {
        return;
    }
    let script = fixtures().join("faulty_adapter.py");
    let backend = format!(
        "external:faulty=python3 {} crash ext-target",
        script.display()
    );
    let vectors = fixtures().join("vectors");
    let out = common::cli(&[
        "run",
        "--vectors",
        vectors.to_str().unwrap_or_default(),
        "--backend",
        &backend,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("faulty::habin::ext-target::rcpu crashed"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| faulty adapter: crash on ext-target"),
        "{stdout}"
    );
    assert!(stdout.contains("faulty: 2 passed, 1 failed"), "{stdout}");
}

#[test]
fn the_command_line_takes_a_known_differences_file_and_fails_a_stale_entry() {
    let scratch = tempfile::tempdir().expect("temp dir");
    let file = known_file(
        scratch.path(),
        "cli-stale.yaml",
        "differences:\n  - case: habin-fixed-text-form\n    reason: \"was wrong once\"\n",
    );
    let out = common::cli(&[
        "run",
        "--backend",
        r#"external:served="$PLC_CONFORMANCE" serve --profile mitsubishi-iqr"#,
        "--known-differences",
        &format!("served={}", file.display()),
        "--filter",
        "habin-fixed-text-form",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("served::habin::habin-fixed-text-form::rcpu stale-entry"),
        "{stdout}"
    );
    assert!(
        stdout.contains("(was wrong once), but conforms: remove the entry"),
        "{stdout}"
    );
}

#[test]
fn serve_speaks_the_protocol() {
    let mut child = Command::new(BIN)
        .args([
            "--root",
            root().to_str().unwrap_or("."),
            "serve",
            "--profile",
            "mitsubishi-iqr",
        ])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("serve starts");
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().expect("stdin");
        let messages = concat!(
            r#"{"type":"hello","protocol":1,"harness":"test"}"#,
            "\n",
            r#"{"type":"run","cases":[{"id":7,"case":"c","instruction":"HABIN","profile":"mitsubishi-iqr","variant":"rcpu","flags":{"SM705":false},"operands":{"s":"D100","d":"D200"},"fill":"A","memory":[{"start":"D100","words":[16693,17464]}]}]}"#,
            "\n",
            r#"{"type":"shutdown"}"#,
            "\n"
        );
        stdin.write_all(messages.as_bytes()).expect("write");
    }
    let out = child.wait_with_output().expect("serve ends");
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(
        lines[0].starts_with(r#"{"type":"hello","protocol":1,"#),
        "{text}"
    );
    assert_eq!(
        lines[1],
        r#"{"type":"result","id":7,"writes":{"D200":23181},"error":null}"#
    );
}

/// Every backend of the project file, with its known-differences file, is green; without the
/// file, exactly the listed trials fail: no entry excuses a trial that conforms, and no
/// difference hides outside the list.
#[test]
fn each_project_backend_fails_exactly_its_known_differences_without_the_file() {
    let (file, explicit) = (root().join(FILE_NAME), true);
    let project = load_project(&file, explicit, Path::new(BIN)).expect("project file loads");
    for skipped in &project.skipped {
        assert!(
            std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
            "{skipped}"
        );
        eprintln!("skipped: {skipped}");
    }
    let mut checked = 0;
    for c in project.configured.iter().filter(|c| !c.on_request) {
        let Some(_) = c.settings.known_differences else {
            continue;
        };
        let mut with = corpus_session();
        with.add(BackendSource::Process(c.settings.clone()), true)
            .unwrap_or_else(|e| panic!("{} starts: {e}", c.settings.name));
        let listed: Vec<String> = trials_of(&with, &c.settings.name)
            .iter()
            .zip(run_all(&trials_of(&with, &c.settings.name)))
            .filter(|(_, v)| {
                assert!(!v.is_failure(), "{v:?}");
                matches!(v, Verdict::KnownDifference { .. })
            })
            .map(|(t, _)| t.name())
            .collect();
        let mut without = corpus_session();
        let mut bare = c.settings.clone();
        bare.known_differences = None;
        without
            .add(BackendSource::Process(bare), true)
            .expect("starts");
        let trials = trials_of(&without, &c.settings.name);
        let failing: Vec<String> = trials
            .iter()
            .zip(run_all(&trials))
            .filter(|(_, v)| v.is_failure())
            .map(|(t, _)| t.name())
            .collect();
        assert!(!listed.is_empty(), "{}: nothing listed", c.settings.name);
        assert_eq!(failing, listed, "{}", c.settings.name);
        checked += 1;
    }
    assert!(
        checked > 0 || std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
        "no project backend with a known-differences file ran"
    );
}

/// A backend that declares what it really implements — no device ranges of its own, `s` only
/// as a D device — is not failed for what it never claimed: those trials are skipped with the
/// reason, and every trial it does claim still runs and conforms.
#[test]
fn capabilities_skip_what_a_backend_does_not_model() {
    if !python() {
        return;
    }
    let mut session = corpus_session();
    let spec = python_backend(
        "limited",
        &fixtures().join("faulty_adapter.py"),
        &["limited", "none"],
    );
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let trials = trials_of(&session, "limited");
    let reasons: Vec<&str> = trials.iter().filter_map(|t| t.skip.as_deref()).collect();
    assert!(
        reasons
            .iter()
            .any(|r| r.contains("does not check device ranges")),
        "{reasons:?}"
    );
    assert!(
        reasons
            .iter()
            .any(|r| r.contains("does not implement operand s as K")),
        "{reasons:?}"
    );
    let verdicts = run_all(&trials);
    let ran = verdicts.iter().filter(|v| v.label() != "skipped").count();
    assert!(ran > 0);
    for (t, v) in trials.iter().zip(&verdicts) {
        assert!(!v.is_failure(), "{}: {v:?}", t.name());
    }
}

/// The corpus's own test binary (`tests/conformance.rs`), built beside this one.
fn conformance_binary() -> Option<std::path::PathBuf> {
    let deps = std::env::current_exe().ok()?.parent()?.to_path_buf();
    // The workspace's example crates have a `conformance` test of their own: the newest binary
    // that lists this corpus's iQ-R trials is this crate's.
    let lists_the_corpus = |p: &std::path::Path| {
        std::process::Command::new(p)
            .args(["--list", "--format", "terse"])
            .output()
            .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("iqr::habin::"))
    };
    std::fs::read_dir(deps)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("conformance-") && !n.contains('.'))
        })
        .filter(|p| lists_the_corpus(p))
        .max_by_key(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
}

/// nextest lists the trials once, then runs each alone and shows one that returns "ignored" as
/// passed. So what a backend declines is known when listing (its handshake), listed ignored,
/// and a declined trial run alone by name fails rather than pass without running.
#[test]
fn trials_a_backend_declines_are_listed_ignored_and_never_pass_alone() {
    let project = load_project(&root().join(FILE_NAME), true, Path::new(BIN)).expect("loads");
    if !project
        .configured
        .iter()
        .any(|c| c.settings.name == "pymcprotocol")
    {
        eprintln!("skipped: pymcprotocol is not installed (.ci/run installs it)");
        return;
    }
    let Some(binary) = conformance_binary() else {
        panic!("the conformance test binary is built with the tests");
    };
    let list = |ignored: bool| {
        let mut command = std::process::Command::new(&binary);
        command.args(["--list", "--format", "terse"]);
        if ignored {
            command.arg("--ignored");
        }
        let out = command.output().expect("the test binary lists");
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| l.strip_suffix(": test"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    // pymcprotocol does not implement SM705 on: those trials are declined.
    let declined = "pymcprotocol::binha::binha-sm705-on-0abc-example::rcpu";
    assert!(list(false).iter().any(|t| t == declined), "not listed");
    assert!(
        list(true).iter().any(|t| t == declined),
        "not listed ignored"
    );
    let out = std::process::Command::new(&binary)
        .args(["--exact", declined, "--ignored"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{stdout}");
    assert!(stdout.contains("1 failed"), "{stdout}");
}

/// Listing plans each external backend from its answer to hello kept in the cache file, without
/// starting it, and marks what that answer declines; a trial run alone then starts its backend,
/// and fails when the answer differs from the cached one (the listing may have marked it
/// wrongly), putting the new answer in the cache so that the next listing is right.
#[test]
fn listing_plans_from_cached_hellos_and_a_changed_answer_fails_the_trial() {
    let project = load_project(&root().join(FILE_NAME), true, Path::new(BIN)).expect("loads");
    if !project
        .configured
        .iter()
        .any(|c| c.settings.name == "aslmp")
    {
        eprintln!("skipped: aslmp is not installed (.ci/run installs it)");
        return;
    }
    let Some(binary) = conformance_binary() else {
        panic!("the conformance test binary is built with the tests");
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let cache = dir.path().join("hellos.json");
    let run = |args: &[&str], cache: &Path| {
        let out = std::process::Command::new(&binary)
            .args(args)
            .env("PLC_CONFORMANCE_HELLO_CACHE", cache)
            .output()
            .expect("the test binary runs");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    let ignored = |cache: &Path| run(&["--list", "--format", "terse", "--ignored"], cache).1;
    let started = ignored(Path::new(""));
    assert_eq!(
        ignored(&cache),
        started,
        "a listing that starts every backend"
    );
    let text = std::fs::read_to_string(&cache).expect("the listing wrote the cache");
    assert!(text.contains("\"aslmp\""), "{text}");
    // A cached aslmp that reads 2 and 8 digits, not 4: the listing believes it.
    let trial = "cross-vendor::aslmp::codec::xv-h2v-4-digits";
    assert!(!started.contains(&format!("{trial}: test")), "{started}");
    let before = r#"\"hex-to-value\":{\"width\":32,\"digits\":[2,4,8]}"#;
    assert!(text.contains(before), "{text}");
    let after = r#"\"hex-to-value\":{\"width\":32,\"digits\":[2,8]}"#;
    std::fs::write(&cache, text.replace(before, after)).expect("write");
    assert!(ignored(&cache).contains(&format!("{trial}: test")));
    // Run alone, the trial starts aslmp, sees the answer changed, and fails.
    let (passed, stdout) = run(&["--exact", trial], &cache);
    assert!(!passed, "{stdout}");
    assert!(stdout.contains("now answers hello differently"), "{stdout}");
    // The cache holds the real answer again: the listing is the one that starts everything.
    assert_eq!(ignored(&cache), started);
    let (passed, stdout) = run(&["--exact", trial], &cache);
    assert!(passed, "{stdout}");
    assert!(stdout.contains("1 passed"), "{stdout}");
}

/// A backend that answers slowly is seen working while it answers its batch: the executor
/// reports how many of the batch's requests are answered, several times before the batch's
/// first trial is judged, and the live progress line shows it.
#[test]
fn a_slow_batch_reports_its_answers_as_they_come() {
    use plc_conformance::testing::execute::{execute_all, Pace, Progress};
    use plc_conformance::testing::report::progress::ProgressReporter;
    use plc_conformance::testing::report::{Event, Reporter};
    use std::sync::atomic::AtomicBool;

    let mut session = fixture_session();
    let slow = python_backend(
        "slow",
        &fixtures().join("faulty_adapter.py"),
        &["slow", "*"],
    );
    session
        .add(BackendSource::Process(slow), true)
        .unwrap_or_else(|e| panic!("the slow backend does not start: {e}"));
    let trials = trials_of(&session, "slow");
    let indices: Vec<usize> = (0..trials.len()).collect();
    let mut answering = Vec::new();
    let mut observed = 0;
    execute_all(
        &trials,
        &indices,
        1,
        &AtomicBool::new(false),
        Pace::Ahead,
        |p| {
            match p {
                Progress::Answering { answered, of, .. } if observed == 0 => {
                    answering.push((answered, of))
                }
                Progress::Observed(..) => observed += 1,
                _ => {}
            }
            std::ops::ControlFlow::Continue(())
        },
    );
    assert_eq!(observed, trials.len());
    // 3 trials under 2 fills, 0.15 s an answer: about 0.9 s, reported every 0.25 s.
    assert!(answering.len() >= 2, "{answering:?}");
    assert!(
        answering
            .windows(2)
            .all(|w| w[0].0 < w[1].0 && w[1].0 < w[1].1),
        "{answering:?}"
    );

    let mut sink = Keep;
    let mut progress =
        ProgressReporter::with_target(&trials, &mut sink, indicatif::ProgressDrawTarget::hidden());
    progress
        .event(&Event::BackendAnswering {
            backend: "slow",
            answered: 4,
            of: 6,
        })
        .expect("event");
    assert_eq!(
        progress.message("slow").as_deref(),
        Some("0 failed, answering: 4 of 6 requests")
    );
}

struct Keep;

impl plc_conformance::testing::report::Reporter for Keep {
    fn event(&mut self, _: &plc_conformance::testing::report::Event<'_>) -> std::io::Result<()> {
        Ok(())
    }
}

/// A codec of 2-digit byte fields checked with their frame, and one of variable-length tokens
/// without leading zeros, each declaring its field's shape: run on the corpus with no
/// known-differences file, neither differs anywhere, and what a shape cannot be asked is skipped
/// with the shape's reason.
#[rstest::rstest]
#[case::byte_fields("byte_field_codec", "checks its field as part of a whole frame", 5)]
#[case::tokens("token_codec", "reads a token of whatever length", 40)]
fn a_codec_that_declares_its_field_shape_differs_nowhere(
    #[case] script: &str,
    #[case] reason: &str,
    #[case] at_least: usize,
) {
    if interpreter().is_none() {
        eprintln!("skipped: no python3");
        return;
    }
    let path = root().join(format!("tests/fixtures/external/{script}.py"));
    let backend = format!("external:{script}=python3 {}", path.display());
    let out = common::cli(&["run", "--backend", &backend]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    let last = stdout.lines().last().unwrap_or_default();
    let passed: usize = last
        .split_once(" passed, 0 failed")
        .and_then(|(n, _)| n.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    // The corpus asks each shape enough to mean something: a byte field's 2-digit cases too.
    assert!(passed >= at_least, "{passed} passed: {stdout}");
    assert!(
        stdout.contains(reason) || stderr.contains(reason),
        "{stdout}{stderr}"
    );
}

/// An entry by the class `lowercase` covers the lowercase hex digits a-f, as a reader means
/// it: a codec that takes a-f and refuses every other letter conforms on `0x5A` (whose `x`
/// is a prefix, not a lowercase digit), so the entry does not go stale there.
#[test]
fn an_entry_by_lowercase_covers_the_digits_a_f_and_not_the_x_of_a_prefix() {
    if !python() {
        return;
    }
    let dir = common::scratch();
    let known = dir.path().join("known.yaml");
    std::fs::write(
        &known,
        "differences:\n  - cause: takes the lowercase hex digits a-f\n    kind: bug\n    input: [lowercase]\n",
    )
    .expect("write");
    let script = fixtures().join("judged_codec.py");
    let backend = format!("external:lc=python3 {} lowercase", script.display());
    let known_arg = format!("lc={}", known.display());
    let out = common::cli(&[
        "run",
        "--backend",
        &backend,
        "--known-differences",
        &known_arg,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("0 failed"), "{stdout}");
    assert!(stdout.contains("known differences)"), "{stdout}");
}

/// Under plain `cargo test` a trial recorded rather than judged runs and shows why it is
/// ignored (what the backend did on an `unspecified` case); listed, it is flagged ignored as
/// nextest needs.
#[test]
fn an_ignored_trial_shows_its_reason_under_plain_cargo_test() {
    let Some(binary) = conformance_binary() else {
        panic!("the conformance test binary is built with the tests");
    };
    let trial = "iqr::binha::binha-sm705-on-short-at-last-word::rcpu";
    let out = std::process::Command::new(&binary)
        .arg(trial)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains(&format!("{trial} ... ignored (unspecified, recorded: ")),
        "{stdout}"
    );
    let listed = std::process::Command::new(&binary)
        .args(["--list", "--format", "terse", "--ignored", trial])
        .output()
        .expect("lists");
    let stdout = String::from_utf8_lossy(&listed.stdout);
    assert!(stdout.contains(&format!("{trial}: test")), "{stdout}");
}
