//! `record`: a backend's behaviour written into a copy of the corpus as `observed`
//! expectations, `unspecified` cases filled in, `manual` ones untouched.

mod common;

use std::path::Path;

use common::{cli, root, scratch};
use plc_conformance::testing::load::{load_corpus, load_profiles};
use plc_conformance::{Basis, Corpus};

/// A copy of the iQ-R vectors in a scratch folder (kept while the first value lives).
fn iqr_copy() -> (tempfile::TempDir, std::path::PathBuf) {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().join("vectors");
    common::copy_dir(&root().join("vectors/mitsubishi-iqr"), &dir);
    (scratch_dir, dir)
}

fn corpus(dir: &Path) -> Corpus {
    let profiles = load_profiles(&root().join("vendors")).expect("profiles");
    load_corpus(&[dir.to_path_buf()], &profiles).unwrap_or_else(|e| panic!("{e}"))
}

/// An emulator of the iQ-R CPU as an external backend: the reference model served through the
/// protocol, which the harness cannot tell from any other implementation.
fn emulator() -> String {
    format!(
        "external:emulator=\"{}\" serve --profile mitsubishi-iqr",
        assert_cmd::cargo::cargo_bin!("plc-conformance").display()
    )
}

/// A built-in reference model is the harness's own reading of the manuals: `record` refuses to
/// write what it answers as `observed`, and the files stay as they were.
#[test]
fn recording_a_reference_model_is_refused() {
    let (_scratch, dir) = iqr_copy();
    let before = corpus(&dir);
    let out = cli(&[
        "record",
        "--backend",
        "iqr",
        "--vectors",
        dir.to_str().expect("utf-8"),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the built-in reference model of MELSEC iQ-R CPU answers for `iqr`"),
        "{stderr}"
    );
    let after = corpus(&dir);
    assert!(before
        .cases
        .iter()
        .zip(&after.cases)
        .all(|(b, a)| b.basis == a.basis && b.citation == a.citation));
}

#[test]
fn recording_a_backend_fills_in_unspecified_cases_and_keeps_manual_ones() {
    let (_scratch, dir) = iqr_copy();
    let before = corpus(&dir);
    let emulator = emulator();
    let out = cli(&[
        "record",
        "--backend",
        &emulator,
        "--vectors",
        dir.to_str().expect("utf-8"),
        "--date",
        "2026-01-02",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("unspecified -> observed"), "{stdout}");
    let after = corpus(&dir);
    assert_eq!(before.cases.len(), after.cases.len());
    for (b, a) in before.cases.iter().zip(&after.cases) {
        assert_eq!(b.id, a.id);
        match b.basis {
            Basis::Manual => {
                assert_eq!(a.basis, Basis::Manual, "{}", a.id);
                assert_eq!(a.expect, b.expect, "{}", a.id);
                assert_eq!(a.citation, b.citation, "{}", a.id);
            }
            _ => {
                assert_eq!(a.basis, Basis::Observed, "{}", a.id);
                assert!(a.expect.is_some(), "{}", a.id);
                let cite = a.citation.text.clone().unwrap_or_default();
                assert!(cite.starts_with("observed on emulator"), "{cite}");
                assert!(cite.contains("2026-01-02"), "{cite}");
            }
        }
    }
    let text = std::fs::read_to_string(dir.join("habin.yaml")).expect("habin.yaml");
    assert!(
        text.contains("provenance:\n      backend: emulator"),
        "{text}"
    );
    assert!(
        text.contains("# --- SM705 OFF: fixed 4 digits"),
        "comments are kept"
    );
    // What was recorded is what the backend does: the copy conforms, nothing recorded only.
    let run = cli(&[
        "run",
        "--backend",
        "iqr",
        "--vectors",
        dir.to_str().expect("utf-8"),
    ]);
    let shown = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{shown}");
    assert!(
        shown.contains("0 failed") && shown.contains("(0 unspecified recorded"),
        "{shown}"
    );
}

/// Recording twice keeps what the expectation rested on before it was first observed: the cite
/// does not grow a "before, observed" each time.
#[test]
fn recording_again_keeps_one_before_in_every_cite() {
    let (_scratch, dir) = iqr_copy();
    let emulator = emulator();
    let record = || {
        let out = cli(&[
            "record",
            "--backend",
            &emulator,
            "--vectors",
            dir.to_str().expect("utf-8"),
            "--date",
            "2026-01-02",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        corpus(&dir)
    };
    let once = record();
    let twice = record();
    let mut observed = 0;
    for (a, b) in once.cases.iter().zip(&twice.cases) {
        assert_eq!(a.citation, b.citation, "{}", a.id);
        if a.basis == Basis::Observed {
            observed += 1;
            let cite = a.citation.text.as_deref().unwrap_or_default();
            assert_eq!(cite.matches("; before, ").count(), 1, "{}: {cite}", a.id);
            assert!(!cite.contains("before, observed"), "{}: {cite}", a.id);
        }
    }
    assert!(observed > 0);
}

/// A backend that faults on every case records nothing and fails the command; the files stay
/// as they were.
#[test]
fn a_backend_that_faults_records_nothing_and_fails() {
    if !common::python() {
        return;
    }
    let scratch_dir = scratch();
    let dir = scratch_dir.path().join("vectors");
    let fixtures = root().join("tests/fixtures/external");
    common::copy_dir(&fixtures.join("vectors"), &dir);
    let before: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| std::fs::read_to_string(e.expect("entry").path()).expect("read"))
        .collect();
    let backend = format!(
        "external:faulty=python3 {} garbage '*'",
        fixtures.join("faulty_adapter.py").display()
    );
    let out = cli(&[
        "record",
        "--backend",
        &backend,
        "--vectors",
        dir.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("the backend faulted"), "{stdout}");
    assert!(stdout.contains(" 0 expectation(s) replaced"), "{stdout}");
    let after: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| std::fs::read_to_string(e.expect("entry").path()).expect("read"))
        .collect();
    assert_eq!(before, after);
}

/// Outside a project the vectors are the binary's own copies, which record cannot edit: it
/// says so before it runs anything.
#[test]
fn record_outside_a_project_says_where_to_run_it() {
    let empty = scratch();
    let out = common::bin()
        .current_dir(empty.path())
        .args(["record", "--backend", "iqr"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("built into the binary"), "{stderr}");
    assert!(out.stdout.is_empty());
}

/// `record --known`'s draft for an implementation that reads a byte above 7FH as "0": one entry
/// by input class for the cross-vendor cases, the iQ-R cases one by one, and the draft,
/// loaded as the backend's known differences, covers exactly what differs (no failure, no
/// stale entry).
#[test]
fn the_known_draft_loads_and_covers_exactly_the_differences() {
    use plc_conformance::Status;
    let mut project = common::session();
    let iqr = common::reference(&project, "mitsubishi-iqr");
    let mutant = common::Mutant::new("high-bytes-as-zero", &iqr, |req, base| {
        common::with_memory(req, base, |w| {
            let [lo, hi] = w.to_le_bytes();
            let zero = |b: u8| if b > 0x7F { b'0' } else { b };
            u16::from_le_bytes([zero(lo), zero(hi)])
        })
    });
    let draft = plc_conformance::testing::known_draft::draft(&project, &mutant, None);
    assert!(draft.text.contains("input: [above-7fh]"), "{}", draft.text);
    assert!(draft.causes >= 1 && draft.cases >= 1, "{}", draft.text);
    assert!(draft.faults.is_empty());
    let dir = scratch();
    let file = dir.path().join("high-bytes-as-zero.known.yaml");
    std::fs::write(&file, &draft.text).expect("write");
    let profile = project
        .profiles()
        .get("mitsubishi-iqr")
        .expect("profile")
        .clone();
    let known =
        plc_conformance::testing::load::load_known(&file, Some(&profile), &project.corpus, true)
            .unwrap_or_else(|e| panic!("the draft does not load: {e}\n{}", draft.text));
    project
        .project
        .known
        .insert("high-bytes-as-zero".into(), known);
    let trials = project.plan(std::slice::from_ref(&mutant));
    let verdicts = plc_conformance::verdicts(&trials);
    let failing: Vec<String> = trials
        .iter()
        .zip(&verdicts)
        .filter(|(_, v)| v.status() == Status::Fail)
        .map(|(t, v)| format!("{}: {v:?}", t.name()))
        .collect();
    assert!(failing.is_empty(), "{failing:#?}\n{}", draft.text);
    assert!(verdicts
        .iter()
        .any(|v| matches!(v, plc_conformance::Verdict::KnownDifference { .. })));
}

/// `record --known` never replaces a file that lists differences (a known-differences file is
/// edited by hand), but takes the place of one that lists nothing, as `init` writes it.
#[test]
fn record_known_replaces_only_a_file_that_lists_nothing() {
    let dir = scratch();
    let record = |file: &std::path::Path| {
        cli(&[
            "record",
            "--backend",
            "iqr",
            "--known",
            file.to_str().expect("utf-8"),
        ])
    };
    let listed = dir.path().join("listed.yaml");
    let entries = "differences:\n  - {case: habin-fixed-4-digits-example, reason: by hand}\n";
    std::fs::write(&listed, entries).expect("write");
    let out = record(&listed);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("the file exists and lists differences"));
    assert_eq!(std::fs::read_to_string(&listed).expect("read"), entries);

    let empty = dir.path().join("empty.yaml");
    std::fs::write(&empty, "# written by init\ndifferences: []\n").expect("write");
    let out = record(&empty);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let drafted = std::fs::read_to_string(&empty).expect("read");
    assert!(!drafted.contains("written by init"), "{drafted}");
}
