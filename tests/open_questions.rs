//! `run --probes` runs exactly the probe cases of an open question, through the binary, so a
//! bench run settles them in one go. The questions' own checks (every probe a case, one that
//! decides between the readings, the reference model answering its reading) are white-box tests
//! beside the loader, in src/load/white_box/open_questions.rs.

mod common;

use std::collections::BTreeSet;

use common::{cli, root};

#[test]
fn run_probes_runs_the_probes_of_a_question() {
    // The first question as the file states it (its own checks are the loader's).
    let file = std::fs::read_to_string(root().join("docs/open-questions.yaml")).expect("read");
    let questions: serde_yaml::Value = serde_yaml::from_str(&file).expect("YAML");
    let q = &questions["questions"][0];
    let id = q["id"].as_str().expect("an id");
    let probes: BTreeSet<String> = q["probes"]
        .as_sequence()
        .expect("probes")
        .iter()
        .filter_map(|p| p.as_str().map(str::to_string))
        .collect();
    let out = cli(&[
        "run",
        "--format",
        "json",
        "--backend",
        "fx5",
        "--probes",
        id,
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
    assert!(!cases.is_empty());
    assert!(cases.is_subset(&probes), "{cases:?} not within {probes:?}");
}
