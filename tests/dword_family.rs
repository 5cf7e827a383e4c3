//! A family whose memory unit is a 32-bit word, end to end: a toy family in a test fixture
//! (`tests/fixtures/dword-family`: a profile with `memory_unit: dword`, vectors, and a Python
//! backend speaking protocol version 4) loads, runs, is judged, compared, swept and recorded
//! with values wider than a 16-bit word, and nothing outside its profile, vectors and backend
//! knows it is 32 bits wide.

mod common;

use std::path::{Path, PathBuf};

use plc_conformance::testing::session::Session;
use plc_conformance::Unit;
use plc_conformance::{Paths, Project};

fn fixture() -> PathBuf {
    common::root().join("tests/fixtures/dword-family")
}

/// The toy backend, with environment settings before its command (`TOY_WRONG=1`).
fn backend(name: &str, env: &str) -> String {
    let script = fixture().join("toy_hex8.py");
    format!("external:{name}={env} python3 {}", script.display())
}

/// The binary on a root with arguments; exit code, stdout, stderr.
fn cli(root: &Path, args: &[&str]) -> (i32, String, String) {
    let out = common::bin()
        .args(["--root", root.to_str().unwrap_or(".")])
        .args(args)
        .output()
        .expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_toy_family_loads_in_32_bit_units() {
    let project = match Project::load(&Paths::under(&fixture())) {
        Ok(p) => Session::with_references(p),
        Err(e) => panic!("the fixture does not load:\n{e}"),
    };
    let profile = project
        .profiles()
        .get("toy-dwords")
        .expect("the toy profile");
    assert_eq!(profile.unit, Unit::Dword);
    let eight = (project.corpus.cases.iter())
        .find(|c| c.id == "hex8-eight-characters")
        .expect("the case");
    let after: Vec<(String, u32)> = (eight.expect.as_ref().expect("expected").after.iter())
        .map(|(d, v)| (d.to_string(), *v))
        .collect();
    assert_eq!(after, [("DW30".to_string(), 0x89AB_CDEF)]);
}

#[test]
fn a_value_wider_than_32_bits_is_a_load_error() {
    let dir = common::scratch();
    common::copy_dir(&fixture(), dir.path());
    let file = dir.path().join("vectors/toy-dwords/hex8.yaml");
    let text = std::fs::read_to_string(&file)
        .expect("the fixture vectors")
        .replace("DW30: 89ABCDEFH", "DW30: 189ABCDEFH");
    std::fs::write(&file, text).expect("write");
    let err = match Project::load(&Paths::under(dir.path())) {
        Ok(_) => panic!("a 33-bit value in 32-bit memory loaded"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("`189ABCDEFH` is too wide for 32 bits"),
        "{err}"
    );
}

#[test]
fn run_judges_32_bit_values_and_shows_them_whole() {
    if !common::python() {
        return;
    }
    let (code, out, err) = cli(&fixture(), &["run", "--backend", &backend("toy", "")]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(out.contains("3 passed, 0 failed"), "{out}");
    let wrong = backend("toy", "TOY_WRONG=1");
    let (code, out, _) = cli(&fixture(), &["run", "--backend", &wrong]);
    assert_eq!(code, 1, "{out}");
    for line in [
        "-DW30     89ABCDEFH  \"\\xEF\\xCD\\xAB\\x89\"",
        "+DW30     FEDCBA98H  \"\\x98\\xBA\\xDC\\xFE\"",
        "1 passed, 2 failed",
    ] {
        assert!(out.contains(line), "missing `{line}` in:\n{out}");
    }
    let (code, json, _) = cli(
        &fixture(),
        &["run", "--backend", &wrong, "--format", "json"],
    );
    assert_eq!(code, 1);
    let doc: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(doc["summary"]["failed"], 2, "{json}");
    assert!(json.contains("\"unit\": \"dword\""), "{json}");
    assert!(json.contains("\"FEDCBA98H\""), "{json}");
}

#[test]
fn a_backend_of_protocol_3_is_refused_for_32_bit_memory() {
    if !common::python() {
        return;
    }
    let old = backend("toy", "TOY_PROTOCOL=3");
    let (code, _, err) = cli(&fixture(), &["run", "--backend", &old]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("its memory ranges carry `dwords`, which needs version 4"),
        "{err}"
    );
}

#[test]
fn diff_and_sweep_compare_32_bit_answers() {
    if !common::python() {
        return;
    }
    let (toy, wrong) = (backend("toy", ""), backend("wrong", "TOY_WRONG=1"));
    let (code, out, _) = cli(
        &fixture(),
        &["diff", "--backend", &toy, "--backend", &wrong],
    );
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("toy-dwords: 3 cases, 2 behaviours"), "{out}");
    assert!(out.contains("+DW30     FEDCBA98H"), "{out}");
    let (code, out, err) = cli(
        &fixture(),
        &[
            "sweep",
            "--instruction",
            "HEX8",
            "--backend",
            &toy,
            "--backend",
            &wrong,
            "--length",
            "2",
            "--alphabet",
            "1,A,G",
        ],
    );
    // A sweep explores: it reports what the columns disagree on and exits 0.
    assert_eq!(code, 0, "{out}\n{err}");
    for line in [
        "toy@toy and wrong@toy disagree on 2 of 12 texts, in 1 group(s)",
        "first: \"1A\" digits 2 -> toy@toy DW40=0000001AH, wrong@toy DW40=000000A1H",
    ] {
        assert!(out.contains(line), "missing `{line}` in:\n{out}");
    }
}

#[test]
fn record_writes_a_32_bit_outcome_that_loads_and_passes() {
    if !common::python() {
        return;
    }
    let dir = common::scratch();
    common::copy_dir(&fixture(), dir.path());
    let file = dir.path().join("vectors/toy-dwords/hex8.yaml");
    let mut text = std::fs::read_to_string(&file).expect("the fixture vectors");
    text.push_str(
        "  - id: hex8-seven-characters\n    basis: unspecified\n    cite: \"not described\"\n    \
         operands: {IN: DW10, N: 7, OUT: DW34}\n    before:\n      DW10: {ascii_words: \"FEDCBA9\"}\n",
    );
    std::fs::write(&file, text).expect("write");
    let toy = backend("toy", "");
    let (code, out, err) = cli(
        dir.path(),
        &["record", "--backend", &toy, "--date", "2026-11-26"],
    );
    assert_eq!(code, 0, "{out}\n{err}");
    let recorded = std::fs::read_to_string(&file).expect("recorded");
    assert!(recorded.contains("after: {DW34: 0FEDCBA9H}"), "{recorded}");
    assert!(recorded.contains("basis: observed"), "{recorded}");
    let (code, out, err) = cli(dir.path(), &["run", "--backend", &toy]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(out.contains("4 passed, 0 failed"), "{out}");
}
