//! `record`: a backend's behaviour written into a copy of the corpus as `observed`
//! expectations, `unspecified` cases filled in, `manual` ones untouched.

mod common;

use std::path::Path;

use common::{cli, root, scratch};
use plc_conformance::load::{load_corpus, load_profiles};
use plc_conformance::model::{Basis, Corpus};

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).expect("copy");
        }
    }
}

fn corpus(dir: &Path) -> Corpus {
    let profiles = load_profiles(&root().join("vendors")).expect("profiles");
    load_corpus(&[dir.to_path_buf()], &profiles).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn recording_a_backend_fills_in_unspecified_cases_and_keeps_manual_ones() {
    let scratch_dir = scratch();
    let dir = scratch_dir.path().join("vectors");
    copy_dir(&root().join("vectors/mitsubishi-iqr"), &dir);
    let before = corpus(&dir);
    let out = cli(&[
        "record",
        "--backend",
        "iqr",
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
                assert!(cite.starts_with("observed on iqr"), "{cite}");
                assert!(cite.contains("2026-01-02"), "{cite}");
            }
        }
    }
    let text = std::fs::read_to_string(dir.join("habin.yaml")).expect("habin.yaml");
    assert!(text.contains("provenance:\n      backend: iqr"), "{text}");
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
