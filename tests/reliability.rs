//! What the harness guarantees under interruption, hostile backends and odd corpora
//! (docs/reliability.md): no false pass, no silent skip, bounded time, no orphan process, saves
//! that compare with the run before.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{root, scratch};

const BIN: &str = env!("CARGO_BIN_EXE_plc-conformance");

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs the binary on this project and kills it if it is still running after `limit`: a test
/// of bounded time must not hang itself.
fn cli_within(args: &[&str], limit: Duration) -> (Output, Duration) {
    let started = Instant::now();
    let mut child = Command::new(BIN)
        .args(["--root", root().to_str().unwrap_or(".")])
        .args(args)
        .env("NO_COLOR", "1")
        .env_remove("PLC_CONFORMANCE_CONFIG")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    while child.try_wait().ok().flatten().is_none() {
        if started.elapsed() > limit {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let took = started.elapsed();
    let out = child.wait_with_output().expect("the binary ends");
    (out, took)
}

fn cli(args: &[&str]) -> Output {
    cli_within(args, Duration::from_secs(300)).0
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap_or_default()
}

const ONE_CASE: &str = "\
instructions: [HABIN]
profiles: [mitsubishi-iqr]
source: {manual: iqr-instructions-ja, page: 478}
cases:
  - id: rel-example
    basis: manual
    cite: example on p.478
    operands: {s: D100, d: D200}
    before:
      D100: {ascii: \"5A8D\"}
    expect:
      after: {D200: 5A8DH}
";

fn mkfifo(at: &Path) {
    let status = Command::new("mkfifo")
        .arg(at)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", at.display());
}

// --- saved runs -------------------------------------------------------------------------------

/// `--save F --baseline F`: the baseline is the run saved before, so a new difference is new.
#[test]
fn saving_over_the_baseline_compares_with_the_previous_run() {
    let dir = scratch("rel-save-over-baseline");
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
    let dir = scratch("rel-fifo");
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    std::fs::write(vectors.join("good.yaml"), ONE_CASE).expect("write");
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
            "fifo: a FIFO (named pipe), not a regular file",
        ),
        (
            vec!["run", "--backend", "iqr", "--output", path(&fifo)],
            "cannot write",
        ),
        (
            vec!["diff", "--backend", "iqr", "--save", path(&fifo)],
            "a FIFO (named pipe), not a regular file",
        ),
    ];
    for (args, message) in cases {
        let (out, took) = cli_within(&args, limit);
        let err = text(&out.stderr);
        assert!(took < Duration::from_secs(5), "{args:?} took {took:?}");
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    assert!(fifo.exists(), "the FIFO is left where it was");
}

#[test]
fn invalid_utf8_and_deep_nesting_are_reported_with_their_line() {
    let dir = scratch("rel-bytes");
    let file = dir.join("case.yaml");
    let mut bytes = ONE_CASE.as_bytes().to_vec();
    let at = ONE_CASE.find("example on").expect("cite");
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
        ONE_CASE,
        "      D300: ".to_string() + &"[".repeat(100_000),
        "]".repeat(100_000)
    );
    std::fs::write(&file, deep).expect("write");
    let (out, took) = cli_within(&["validate", path(&file)], Duration::from_secs(60));
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(1), "took {took:?}");
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
    let dir = scratch("rel-links");
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).expect("dir");
    std::fs::write(elsewhere.join("linked.yaml"), ONE_CASE).expect("write");
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(&vectors).expect("dir");
    symlink(&elsewhere, vectors.join("family")).expect("link");
    let out = cli(&["validate", path(&vectors)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).starts_with("ok: 1 cases"),
        "{}",
        text(&out.stdout)
    );

    symlink(&vectors, elsewhere.join("back")).expect("link");
    let (out, took) = cli_within(&["validate", path(&vectors)], Duration::from_secs(60));
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(took < Duration::from_secs(5), "took {took:?}");
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
    let dir = scratch("rel-known");
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
                "--known-differences names `iqr`, which is not an `external:` backend of this run"
            ),
            "{err}"
        );
    }
}
