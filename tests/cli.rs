//! The command line as a user meets it: exit codes, messages with file:line, output formats.

mod common;

use common::{cli, scratch};
use tempfile::TempDir;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A scratch folder holding one vector file.
fn scratch_vectors(yaml: &str) -> TempDir {
    let dir = scratch();
    std::fs::write(dir.path().join("case.yaml"), yaml).expect("write vector");
    dir
}

#[test]
fn validate_accepts_the_corpus() {
    let out = cli(&["validate"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).starts_with("ok: "),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn validate_rejects_a_bad_vector_with_file_and_line() {
    let dir = scratch_vectors(&common::habin_example("cli-example", "15A8DH"));
    let out = cli(&["validate", dir.path().to_str().unwrap_or_default()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("case.yaml:12: cases[0].expect.after.D200: `15A8DH` is too wide for 16 bits"),
        "{err}"
    );
    assert!(err.trim_end().ends_with("1 error found"), "{err}");
}

#[test]
fn validate_reports_a_missing_path() {
    let out = cli(&["validate", "/nonexistent/vectors"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("/nonexistent/vectors"));
}

#[test]
fn run_exits_zero_when_everything_conforms() {
    let out = cli(&["run"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout
            .lines()
            .last()
            .is_some_and(|l| l.contains(" passed, 0 failed")),
        "{stdout}"
    );
}

#[test]
fn run_exits_one_and_shows_a_diff_on_a_difference() {
    let dir = scratch_vectors(&common::habin_example("cli-example", "5A8EH"));
    let out = cli(&["run", "--vectors", dir.path().to_str().unwrap_or_default()]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("case.yaml:5: iqr::habin::cli-example::rcpu differs"),
        "{stdout}"
    );
    assert!(stdout.contains("-D200     5A8EH  \"\\x8EZ\""), "{stdout}");
    assert!(stdout.contains("+D200     5A8DH  \"\\x8DZ\""), "{stdout}");
}

#[test]
fn run_json_reports_every_trial() {
    let out = cli(&[
        "run",
        "--format",
        "json",
        "--filter",
        "habin-fixed-4-digits-example",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON output");
    assert_eq!(report["format"], "plc-conformance-results");
    assert_eq!(report["version"], 2);
    let trials = report["records"].as_array().expect("records");
    assert!(!trials.is_empty());
    assert_eq!(
        report["summary"]["passed"].as_u64(),
        Some(trials.len() as u64)
    );
    for t in trials {
        assert_eq!(t["status"], "pass");
        assert_eq!(t["verdict"]["verdict"], "conforms");
        assert!(t["line"].as_u64().is_some_and(|l| l > 0));
    }
}

#[test]
fn run_rejects_an_unknown_backend_and_an_empty_selection() {
    let out = cli(&["run", "--backend", "siemens"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unknown backend `siemens`; expected one of: "));
    let out = cli(&["run", "--filter", "no-such-case"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("no trial matches"));
}

#[test]
fn list_shows_backends_variants_and_cases() {
    let out = cli(&["list"]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    for needle in [
        "backends:",
        "iqr",
        "variant rcpu-no-sm705",
        "habin-fixed-4-digits-example",
    ] {
        assert!(stdout.contains(needle), "list lacks {needle}:\n{stdout}");
    }
}

#[test]
fn schema_prints_json() {
    let out = cli(&["schema"]);
    assert_eq!(out.status.code(), Some(0));
    let schema: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON schema");
    assert_eq!(schema["$schema"], "http://json-schema.org/draft-07/schema#");
}

#[test]
fn usage_errors_exit_two_with_help() {
    let out = cli(&["frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
    let out = cli(&["run", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stdout).contains("--backend <NAME>"));
}

#[test]
fn run_reports_cross_vendor_trials_too() {
    let out = cli(&[
        "run",
        "--backend",
        "fc4a",
        "--format",
        "json",
        "--filter",
        "xv-h2v-4-digits",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON output");
    let xv = report["records"].as_array().expect("records");
    assert_eq!(xv.len(), 1, "{xv:?}");
    assert_eq!(
        xv[0]["trial"],
        "cross-vendor::fc4a::atoh::xv-h2v-4-digits::c10r2"
    );
    assert_eq!(xv[0]["section"], "cross-vendor hex-to-value");
    assert_eq!(xv[0]["verdict"]["verdict"], "conforms");
    assert_eq!(report["summary"]["passed"], 1);
}

#[test]
fn quiet_prints_only_failures_and_the_counts() {
    let out = cli(&["-q", "run", "--backend", "iqr"]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
    let dir = scratch_vectors(&common::habin_example("cli-example", "5A8EH"));
    let out = cli(&[
        "run",
        "--quiet",
        "--vectors",
        dir.path().to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("iqr::habin::cli-example::rcpu differs"),
        "{stdout}"
    );
    assert!(
        stdout
            .lines()
            .last()
            .is_some_and(|l| l.starts_with("0 passed, ") && l.contains(" failed")),
        "{stdout}"
    );
    assert!(!stdout.contains("iqr: "), "no per-backend counts: {stdout}");
}

#[test]
fn fail_fast_stops_after_the_first_failing_batch() {
    // The iQ-R and FX5 corpus with the first ASCI case wrong: without --fail-fast every trial
    // runs; with it, no batch starts after the first failure (with one job, fx5 runs first).
    let scratch = scratch();
    let vectors = scratch.path().join("vectors");
    for family in ["mitsubishi-iqr", "mitsubishi-fx5"] {
        std::fs::create_dir_all(vectors.join(family)).expect("dir");
        for entry in std::fs::read_dir(common::root().join("vectors").join(family)).expect("dir") {
            let path = entry.expect("entry").path();
            let text = std::fs::read_to_string(&path).expect("read");
            let name = path.file_name().expect("name");
            std::fs::write(
                vectors.join(family).join(name),
                text.replacen("D200: {ascii: \"CZ\"}", "D200: {ascii: \"DZ\"}", 1),
            )
            .expect("write");
        }
    }
    let counted = |args: &[&str]| {
        let mut all = vec![
            "-q",
            "run",
            "-j",
            "1",
            "--backend",
            "iqr",
            "--backend",
            "fx5",
            "--vectors",
            vectors.to_str().unwrap_or_default(),
        ];
        all.extend(args);
        let out = cli(&all);
        assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
        let stdout = text(&out.stdout);
        let last = stdout.lines().last().unwrap_or_default().to_string();
        let numbers: Vec<usize> = last
            .split(|c: char| !c.is_ascii_digit())
            .filter_map(|n| n.parse().ok())
            .collect();
        (numbers.iter().take(4).sum::<usize>(), stdout)
    };
    let (all, _) = counted(&[]);
    let saved = scratch.path().join("saved.json");
    let saved_arg = saved.to_str().unwrap_or_default();
    let (stopped, stdout) = counted(&["--fail-fast", "--save", saved_arg]);
    assert!(stopped < all, "{stopped} of {all} trials:\n{stdout}");
    // A fail-fast stop is the run's own decision, not an interruption: it says so, exits 1
    // (checked by `counted`) and saves what it ran.
    assert!(
        stdout.contains("stopped at the first failure (--fail-fast): "),
        "{stdout}"
    );
    assert!(!stdout.contains("interrupted"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&saved).expect("--save written"))
            .expect("json");
    assert_eq!(json["run"]["stopped"], "fail-fast", "{}", json["run"]);
    assert_eq!(json["run"]["interrupted"], false, "{}", json["run"]);
    let failed = json["summary"]["failed"].as_u64().unwrap_or_default();
    assert!(failed >= 1, "{}", json["summary"]);
}

#[test]
fn progress_lines_show_on_a_terminal_and_nothing_when_piped() {
    let out = cli(&["run", "--backend", "iqr", "--backend", "fx5"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stderr.is_empty(), "piped: {}", text(&out.stderr));
    // `script` gives the command a terminal and records what it shows.
    let dir = scratch();
    let typescript = dir.path().join("typescript");
    let command = format!(
        "{} --root {} run --backend iqr --backend fx5 >/dev/null",
        env!("CARGO_BIN_EXE_plc-conformance"),
        common::root().display()
    );
    let Ok(recorded) = std::process::Command::new("script")
        .args(["-qec", &command])
        .arg(&typescript)
        .env("TERM", "xterm")
        .output()
    else {
        eprintln!("`script` is not installed: the terminal half is skipped");
        return;
    };
    assert!(recorded.status.success(), "{}", text(&recorded.stderr));
    let shown = std::fs::read_to_string(&typescript).unwrap_or_default();
    for line in ["iqr ", "fx5 ", " cases, 0 failed"] {
        assert!(
            shown.contains(line),
            "no {line:?} on the terminal:\n{shown}"
        );
    }
}

/// A backend left out because its program is missing is said on stderr, whatever the format:
/// stdout is the report, which a pipe or a file takes whole.
#[test]
fn a_backend_left_out_is_a_note_on_stderr_not_in_the_report() {
    let dir = common::scratch();
    std::fs::write(
        dir.path().join("plc-conformance.yaml"),
        "backends:\n  - name: absent\n    command: [missing/python, adapter.py]\n    \
         profile: mitsubishi-iqr\n    requires: [missing/python]\n",
    )
    .expect("write");
    for format in ["text", "json"] {
        let out = common::bin()
            .current_dir(dir.path())
            // Where backends are required, a missing one is an error, not a note.
            .env_remove(plc_conformance::testing::load::ENV_REQUIRE)
            .args([
                "run",
                "--filter",
                "habin-fixed-4-digits-example",
                "--format",
                format,
            ])
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(0));
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(!stdout.contains("absent"), "{format}: {stdout}");
        assert!(
            stderr.contains("note: skipped: external backend `absent`"),
            "{format}: {stderr}"
        );
    }
}

/// An error that wraps another shows every cause once, in order, on the one line the edge
/// renders: here a baseline that cannot be read, and the operating system's reason under it.
#[test]
fn an_error_is_shown_with_its_causes() {
    let dir = scratch();
    let missing = dir.path().join("before.json");
    let os = std::fs::read(&missing).expect_err("absent").to_string();
    let out = cli(&["run", "--baseline", missing.to_str().expect("utf-8 path")]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    let expected = format!("{}: cannot be read: {os}", missing.display());
    assert!(
        stderr
            .lines()
            .any(|l| l.ends_with(&expected) && l.contains("error")),
        "{stderr}"
    );
}

/// A name given to two backends is refused before either runs, whatever kind each is: here a
/// process named like a built-in reference model, which is never started.
#[test]
fn two_backends_of_one_name_are_refused_before_anything_starts() {
    let dir = scratch();
    let marker = dir.path().join("started");
    let command = format!("external:iqr=touch {}", marker.display());
    let out = cli(&["run", "--backend", "iqr", "--backend", &command]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("there are two backends named `iqr`"),
        "{stderr}"
    );
    assert!(!marker.exists(), "the second backend was started");
}

/// `list --backend` shows each trial a backend would run, and for the others why not: skipped
/// (what the backend does not implement) or ignored (recorded only, a known difference).
#[test]
fn list_shows_which_trials_a_backend_runs_and_why_not_the_others() {
    let out = cli(&[
        "list",
        "--backend",
        "iqr",
        "--filter",
        "habin-fixed-4-digits-example",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = text(&out.stdout);
    assert!(
        stdout.starts_with("iqr: 4 trials, 4 run, 0 skipped or ignored\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("\n  run     iqr::habin::habin-fixed-4-digits-example::rcpu\n"),
        "{stdout}"
    );
    let out = cli(&[
        "list",
        "--backend",
        "iqr",
        "--filter",
        "binha-destination-range-end-sm701-on::rcpu-no",
    ]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains(
            "  ignore  iqr::binha::binha-destination-range-end-sm701-on::rcpu-no-sm705: \
             unspecified: what the backend does is recorded, never judged"
        ),
        "{stdout}"
    );
    if !common::python() {
        return;
    }
    let script = common::root().join("tests/fixtures/external/habin_adapter.py");
    let backend = format!("external:py=python3 {}", script.display());
    let out = cli(&[
        "list",
        "--backend",
        &backend,
        "--filter",
        "binha-fixed-0abc",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains(
            "  skip    py::binha::binha-fixed-0abc-example::rcpu: py does not implement BINHA on rcpu\n"
        ),
        "{stdout}"
    );
    assert!(!stdout.contains("  run "), "{stdout}");
}

/// One wrong expectation fails on every FX5 variant and pulse form the same way: the first
/// failing trial shows the whole report, each other is one line naming the trial it matches.
#[test]
fn the_same_failure_on_other_variants_is_named_not_repeated() {
    let scratch = scratch();
    let vectors = scratch.path().join("vectors");
    let family = vectors.join("mitsubishi-fx5");
    std::fs::create_dir_all(&family).expect("dir");
    let asci = std::fs::read_to_string(common::root().join("vectors/mitsubishi-fx5/asci.yaml"))
        .expect("read");
    std::fs::write(
        family.join("asci.yaml"),
        asci.replacen("D200: {ascii: \"CZ\"}", "D200: {ascii: \"DZ\"}", 1),
    )
    .expect("write");
    let out = cli(&[
        "run",
        "--backend",
        "fx5",
        "--vectors",
        vectors.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = text(&out.stdout);
    let full = stdout.lines().filter(|l| l.ends_with(" differs")).count();
    let named: Vec<&str> = stdout
        .lines()
        .filter(|l| l.contains(" differs: as "))
        .collect();
    assert_eq!(full, 1, "{stdout}");
    assert_eq!(named.len(), 7, "{stdout}");
    assert!(
        named
            .iter()
            .all(|l| l.ends_with("::asci::asci-16bit-sm701-on-k1::fx5s above")),
        "{stdout}"
    );
    assert!(
        stdout.contains("0 passed, 8 failed") || stdout.contains(" 8 failed"),
        "{stdout}"
    );
}
