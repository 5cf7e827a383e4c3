//! A run that checks nothing is never green: the harness a Rust dependent runs from its own
//! `cargo test` refuses to start when a backend names a profile it does not know, when a
//! known-differences file cannot load — whatever filter would have left a failing trial out —
//! and when a backend gets no trial to run.

mod common;

use std::sync::Arc;

use common::root;
use plc_conformance::testing::libtest::conclude;
use plc_conformance::{Backend, Fault, Harness, Outcome, Request, Response};

/// An emulator of `profile` named `name` that claims `instruction` and answers with `answer`.
struct Emulator {
    name: &'static str,
    profile: &'static str,
    instruction: &'static str,
    answer: fn(&Request<'_>) -> Result<Response, Fault>,
}

impl Backend for Emulator {
    fn name(&self) -> &str {
        self.name
    }
    fn profile(&self) -> &str {
        self.profile
    }
    fn describe(&self) -> String {
        "a test emulator".into()
    }
    fn claims(&self, instruction: &str, _variant: &str) -> bool {
        instruction == self.instruction
    }
    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        (self.answer)(request)
    }
}

/// An emulator of FX5 HEXA named `name` that answers with `answer`.
fn hexa(
    name: &'static str,
    answer: fn(&Request<'_>) -> Result<Response, Fault>,
) -> Arc<dyn Backend> {
    Arc::new(Emulator {
        name,
        profile: "mitsubishi-fx5",
        instruction: "HEXA",
        answer,
    })
}

/// Answers nothing useful.
fn nothing(_: &Request<'_>) -> Result<Response, Fault> {
    Ok(Response::Unsupported("nothing".into()))
}

/// Writes nothing, whatever it is asked.
fn writes_nothing(_: &Request<'_>) -> Result<Response, Fault> {
    Ok(Response::Done(Outcome::default()))
}

fn harness(profile: &'static str, instruction: &'static str) -> Harness {
    let emu: Arc<dyn Backend> = Arc::new(Emulator {
        name: "emu",
        profile,
        instruction,
        answer: nothing,
    });
    Harness::new(root()).backend(emu, None)
}

/// A scratch folder and the path of a log file in it, where a harness run by a test writes what
/// it would print (its own failures are what the test expects, not the suite's).
fn logfile() -> (tempfile::TempDir, String) {
    let dir = common::scratch();
    let log = dir.path().join("log").to_string_lossy().into_owned();
    (dir, log)
}

fn refused(result: Result<libtest_mimic::Conclusion, Vec<String>>) -> String {
    match result {
        Ok(c) => panic!(
            "the harness ran: {} passed, {} failed, {} ignored",
            c.num_passed, c.num_failed, c.num_ignored
        ),
        Err(lines) => lines.join("\n"),
    }
}

#[test]
fn a_profile_s_short_name_is_refused_with_its_id() {
    let why = refused(conclude(harness("fx5", "HEXA"), &["--list"]));
    assert!(
        why.contains("names profile `fx5`, which is not loaded"),
        "{why}"
    );
    assert!(why.contains("did you mean `mitsubishi-fx5`"), "{why}");
}

#[test]
fn a_misspelt_profile_is_refused_whatever_the_filter() {
    let why = refused(conclude(harness("mitsubishi-fx55", "HEXA"), &["hexa"]));
    assert!(why.contains("The profiles are: "), "{why}");
    assert!(why.contains("mitsubishi-fx5"), "{why}");
}

#[test]
fn a_known_differences_file_that_does_not_load_is_refused_whatever_the_filter() {
    let dir = common::scratch();
    let known = dir.path().join("broken.known.yaml");
    std::fs::write(&known, "differences: [{case: no-such-case}]\n").expect("write");
    let emu = hexa("emu", nothing);
    for args in [&["hexa"][..], &["--exact", "emu::hexa::no-such::fx5u"], &[]] {
        let h = Harness::new(root()).backend(emu.clone(), Some(known.clone()));
        let why = refused(conclude(h, args));
        assert!(why.contains("broken.known.yaml"), "{args:?}: {why}");
        assert!(
            why.contains("no trial runs while a backend is not set up"),
            "{why}"
        );
    }
}

#[test]
fn a_backend_with_no_trial_is_refused() {
    let why = refused(conclude(harness("mitsubishi-fx5", "NOSUCH"), &[]));
    assert!(why.contains("backend `emu` gets no trial to run"), "{why}");
}

/// The built-in models are opt-in: a harness given no backend has nothing to check, and says so
/// instead of reporting 0 tests, ok.
#[test]
fn a_harness_with_no_backend_is_refused() {
    let why = refused(conclude(Harness::new(root()), &[]));
    assert!(why.contains("no backend"), "{why}");
}

/// And a backend set up right runs: the same harness with a known instruction plans trials
/// (listed, not run).
#[test]
fn a_backend_set_up_right_runs() {
    let c = conclude(harness("mitsubishi-fx5", "HEXA"), &["--list"]).expect("runs");
    assert_eq!(c.num_failed, 0);
}

/// A backend given as the command line's `--backend` text is read by the same code: a wrong
/// text is refused before any trial with the command line's words, a right one runs.
#[test]
fn a_backend_spec_is_read_as_the_command_line_reads_it() {
    let spec = |text: &str| Harness::new(root()).backend_spec(text);
    let why = refused(conclude(spec("external:Bad=./emu"), &["--list"]));
    assert!(why.contains("`Bad` is not a backend name"), "{why}");
    let why = refused(conclude(spec("no-such"), &["--list"]));
    assert!(why.contains("unknown backend `no-such`"), "{why}");
    assert!(why.contains("external:NAME=COMMAND"), "{why}");
    let why = refused(conclude(spec("slmp:bench=127.0.0.1"), &["--list"]));
    assert!(why.contains("has no port"), "{why}");

    let served = format!(
        "external:served=\"{}\" serve --profile mitsubishi-iqr",
        env!("CARGO_BIN_EXE_plc-conformance")
    );
    let (_dir, log) = logfile();
    let c = conclude(spec(&served), &["served::habin::", "--logfile", &log]).expect("runs");
    assert!(c.num_passed > 0, "no trial ran: {c:?}");
    assert_eq!(c.num_failed, 0, "{c:?}");
}

/// A misspelt flag is never read as off: every trial of the emulator that reads it fails.
#[test]
fn a_misspelt_flag_fails_every_trial_that_reads_it() {
    // It reads a flag the profile does not have (a typo: `SM7O1`).
    let emu = hexa("misspelt", |request| {
        let _ = request.flag("SM7O1");
        Ok(Response::Unsupported("unreachable".into()))
    });
    let h = Harness::new(root()).backend(emu, None);
    let (dir, log) = logfile();
    let c = conclude(h, &["misspelt::hexa::hexa-16bit-k1::", "--logfile", &log]).expect("runs");
    assert!(c.num_failed > 0, "{c:?}");
    assert_eq!(c.num_passed, 0, "{c:?}");
    let shown = std::fs::read_to_string(dir.path().join("log")).expect("the log");
    assert!(shown.contains("(did you mean `SM701`?)"), "{shown}");
}

/// A difference the same on every variant is reported in full once; each other trial with it
/// fails too, naming the trial that shows it.
#[test]
fn the_same_difference_is_shown_once() {
    // On every FX5 variant alike.
    let lazy = hexa("lazy", writes_nothing);
    let (dir, log) = logfile();
    let c = conclude(
        Harness::new(root()).backend(lazy, None),
        &["lazy::hexa::hexa-16bit-k1::", "--logfile", &log],
    )
    .expect("runs");
    assert!(c.num_failed > 1, "one variant only: {c:?}");
    assert_eq!(c.num_passed, 0, "{c:?}");
    let shown = std::fs::read_to_string(dir.path().join("log")).expect("the log");
    let full = shown.matches("with fill A").count();
    let same = shown
        .matches("the same difference as lazy::hexa::hexa-16bit-k1::")
        .count();
    assert_eq!(full, 1, "{shown}");
    assert_eq!(same as u64, c.num_failed - 1, "{shown}");
}

/// A known difference is ignored with its entry when the trials run together, and fails with
/// its difference when run alone by name, as `nextest --run-ignored all` runs it: nextest would
/// show a trial that reports itself ignored as passed.
#[test]
fn a_known_difference_run_alone_is_no_pass() {
    let dir = common::scratch();
    let known = dir.path().join("lazy.known.yaml");
    std::fs::write(
        &known,
        "differences:\n  - {case: hexa-16bit-k1, reason: writes nothing}\n",
    )
    .expect("write");
    let harness = || {
        let lazy = hexa("lazy", writes_nothing);
        Harness::new(root()).backend(lazy, Some(known.clone()))
    };
    let (log_dir, log) = logfile();
    let together = conclude(
        harness(),
        &["lazy::hexa::hexa-16bit-k1::", "--logfile", &log],
    )
    .expect("runs");
    assert_eq!(together.num_failed, 0, "{together:?}");
    assert!(together.num_ignored > 0, "{together:?}");
    let name = "lazy::hexa::hexa-16bit-k1::fx5u";
    let args = ["--exact", name, "--include-ignored", "--logfile", &log];
    let alone = conclude(harness(), &args).expect("runs");
    assert_eq!((alone.num_failed, alone.num_passed), (1, 0), "{alone:?}");
    let shown = std::fs::read_to_string(log_dir.path().join("log")).expect("the log");
    assert!(shown.contains("known difference ("), "{shown}");
    assert!(
        shown.contains("writes nothing; run alone it still differs"),
        "{shown}"
    );
}

/// A hung in-process backend fails its trial at the harness's time limit, and the run ends.
#[test]
fn a_hung_backend_fails_its_trial_at_the_time_limit() {
    // It never answers.
    let hung = hexa("hung", |_| loop {
        std::thread::sleep(std::time::Duration::from_secs(1));
    });
    let h = Harness::new(root())
        .backend(hung, None)
        .time_limit(std::time::Duration::from_millis(300));
    let (dir, log) = logfile();
    let name = "hung::hexa::hexa-16bit-k1::fx5u";
    let c = conclude(h, &["--exact", name, "--logfile", &log]).expect("runs");
    assert_eq!((c.num_failed, c.num_passed), (1, 0), "{c:?}");
    let shown = std::fs::read_to_string(dir.path().join("log")).expect("the log");
    assert!(shown.contains("did not answer within 0.3 s"), "{shown}");
}
