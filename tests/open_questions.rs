//! `run --probes` runs exactly the probe cases of an open question, through the binary, so a
//! bench run settles them in one go. The questions' own checks (every probe a case, one that
//! decides between the readings, the reference model answering its reading) are white-box tests
//! beside the loader, in src/load/white_box/open_questions.rs.

mod common;

use std::collections::BTreeSet;

use common::{cli, root, session};
use plc_conformance::testing::load::{load_open_questions, OPEN_QUESTIONS};

#[test]
fn run_probes_runs_the_probes_of_a_question() {
    let s = session();
    let questions = load_open_questions(&root().join(OPEN_QUESTIONS), &s.profiles, &s.corpus)
        .unwrap_or_else(|e| panic!("{e}"));
    let q = &questions[0];
    let out = cli(&[
        "run",
        "--format",
        "json",
        "--backend",
        "fx5",
        "--probes",
        &q.id,
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let cases: BTreeSet<String> = report["records"]
        .as_array()
        .expect("records")
        .iter()
        .map(|r| {
            let trial = r["trial"].as_str().unwrap_or_default();
            trial.split("::").nth(2).unwrap_or_default().to_string()
        })
        .collect();
    let probes: BTreeSet<String> = q.probes.iter().cloned().collect();
    assert!(!cases.is_empty());
    assert!(cases.is_subset(&probes), "{cases:?} not within {probes:?}");
}
