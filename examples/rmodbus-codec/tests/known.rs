//! Without its known-differences file, rmodbus fails exactly the trials the file lists: the list
//! neither hides a difference nor excuses a trial that conforms.

use std::path::Path;

use plc_conformance::{codec_backend, verdicts, Paths, Project, Subject};
use rmodbus_codec::Rmodbus;

#[test]
fn rmodbus_fails_exactly_its_known_differences() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let project = Project::load(&Paths::embedded()).unwrap_or_else(|e| panic!("{e}"));
    let backend = codec_backend(Rmodbus);
    let trials = project.plan(std::slice::from_ref(&backend));
    assert!(trials.iter().any(|t| t.skip.is_none()), "no trial runs");
    let failing: Vec<String> = trials
        .iter()
        .zip(verdicts(&trials))
        .filter(|(_, v)| v.is_failure())
        .map(|(t, _)| t.case_id().to_string())
        .collect();
    let known = project
        .known_differences(backend.as_ref(), &here.join("rmodbus.known.yaml"))
        .unwrap_or_else(|e| panic!("{e}"));
    // The cases the entries cover, each listed or covered by a cause.
    let mut listed: Vec<String> = (project.corpus.cross_vendor.iter())
        .chain(&project.corpus.protocol_fields)
        .filter(|c| {
            known.covers(&Subject {
                case: &c.id,
                text: Some(&c.text),
                instruction: "codec",
                variant: "",
            })
        })
        .map(|c| c.id.clone())
        .collect();
    let mut failing_sorted = failing.clone();
    listed.sort();
    failing_sorted.sort();
    assert_eq!(failing_sorted, listed);
}
