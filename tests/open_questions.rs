//! The open questions are data: every question loads, names readings and probes that exist, and
//! `run --probes` runs exactly the probe cases, so a bench run settles them in one go.

mod common;

use std::collections::BTreeSet;

use common::{cli, root, session};
use plc_conformance::load::{load_open_questions, OPEN_QUESTIONS};

#[test]
fn every_open_question_has_probes_in_the_corpus() {
    let s = session();
    let questions = load_open_questions(&root().join(OPEN_QUESTIONS), &s.profiles, &s.corpus)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(questions.len() >= 10, "{} questions", questions.len());
    for q in &questions {
        assert!(!q.probes.is_empty(), "{} has no probe", q.id);
        assert!(q.readings.len() >= 2, "{}", q.id);
    }
}

#[test]
fn a_probe_that_is_not_a_case_is_a_load_error() {
    let s = session();
    let dir = common::scratch();
    let file = dir.path().join("q.yaml");
    std::fs::write(
        &file,
        "questions:\n  - id: q\n    title: t\n    profile: mitsubishi-iqr\n    instructions: [HABIN]\n    \
         readings: [{id: a, text: a}, {id: b, text: b}]\n    model_takes: a\n    evidence: [x]\n    \
         probes: [habin-fixed-4-digits-example, no-such-case]\n",
    )
    .expect("write");
    let errors = load_open_questions(&file, &s.profiles, &s.corpus)
        .expect_err("an unknown probe loaded")
        .to_string();
    assert!(
        errors.contains(":9: questions[0].probes[1]: `no-such-case` is not a case id"),
        "{errors}"
    );
}

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
