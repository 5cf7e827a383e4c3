//! The external backends' white-box tests, with no binary to run: an adapter written with the
//! Python helper conforms where it claims to and is held to the error code it writes to SD0, a
//! codec written with each helper (Python and JavaScript) is judged by the harness, a command
//! that does not exist cannot be started, and the checked-in protocol schema is what the message
//! types generate. The tests whose backend forwards to `plc-conformance serve` (the faulty
//! adapter, the served reference models) or that run the command line stay in
//! `tests/external.rs`.

#[cfg(test)]
use crate::test_support::{expects_a_code, interpreter, python, registers_alone, root};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::Duration;

use crate::backend::external::ExternalErrorKind;
use crate::model::project::{ExternalSettings, Launch};
use crate::session::{BackendSource, Session, SetupError};
use crate::{verdicts as run_all, Paths, Project};
use crate::{Backend, Trial, Verdict};

fn fixtures() -> PathBuf {
    root().join("tests/fixtures/external")
}

fn fixture_session() -> Session {
    let paths = Paths {
        vendors: root().join("vendors"),
        vectors: vec![fixtures().join("vectors")],
    };
    Session::with_references(
        Project::load(&paths).unwrap_or_else(|e| panic!("fixture corpus: {e}")),
    )
}

fn corpus_session() -> Session {
    Session::with_references(
        Project::load(&Paths::under(root())).unwrap_or_else(|e| panic!("corpus: {e}")),
    )
}

/// A Python adapter of the iQ-R profile. The adapters started here answer by themselves (none
/// forwards to `plc-conformance serve`), so no `$PLC_CONFORMANCE` is set.
fn python_backend(name: &str, script: &Path, args: &[&str]) -> ExternalSettings {
    let python = interpreter().unwrap_or("python3").to_string();
    let mut argv = vec![python, script.display().to_string()];
    argv.extend(args.iter().map(|a| a.to_string()));
    let mut spec = ExternalSettings::new(name, Launch::Exec(argv));
    spec.profile = Some("mitsubishi-iqr".into());
    spec.timeout = Duration::from_secs(3);
    spec.startup_timeout = Duration::from_secs(10);
    spec
}

/// The trials of the one external backend in a session.
fn trials_of(session: &Session, name: &str) -> Vec<Trial> {
    let backend: Vec<Arc<dyn Backend>> = session
        .backends
        .iter()
        .filter(|b| b.name() == name)
        .cloned()
        .collect();
    session.plan(&backend)
}

fn start_error(spec: ExternalSettings) -> (ExternalErrorKind, String) {
    let mut session = fixture_session();
    match session.add(BackendSource::Process(spec), true) {
        Err(SetupError::External(e)) => (e.kind.clone(), e.to_string()),
        Err(other) => panic!("unexpected error: {other}"),
        Ok(_) => panic!("the backend started"),
    }
}

#[test]
fn a_command_that_does_not_exist_cannot_be_started() {
    let spec = ExternalSettings::new(
        "nothing",
        Launch::Exec(vec!["/nonexistent/emulator".into()]),
    );
    let (kind, text) = start_error(spec);
    assert!(matches!(kind, ExternalErrorKind::Spawn(_)), "{text}");
    assert!(text.contains("`/nonexistent/emulator`"), "{text}");
}

/// The Python helper end to end: an adapter written with it conforms where it claims to, and a
/// flag setting it does not implement skips the case with a reason.
#[test]
fn an_adapter_written_with_the_python_helper_conforms() {
    if !python() {
        return;
    }
    let mut session = corpus_session();
    let spec = python_backend("habin-py", &fixtures().join("habin_adapter.py"), &[]);
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let trials = trials_of(&session, "habin-py");
    let verdicts = run_all(&trials);
    let mut ran = 0;
    for (t, v) in trials.iter().zip(&verdicts) {
        match v {
            Verdict::Skipped { .. } => {
                let unclaimed = format!(
                    "habin-py does not implement {} on {}",
                    t.input.instruction, t.variant
                );
                let reason = t.skip.as_deref().unwrap_or_default();
                assert!(
                    reason == "habin-py does not implement SM705 on" || reason == unclaimed,
                    "{}: {reason}",
                    t.name()
                );
            }
            v => {
                ran += 1;
                assert!(!v.is_failure(), "{}: {v:?}", t.name());
            }
        }
    }
    assert!(ran > 0, "no trial ran");
    assert!(
        trials
            .iter()
            .any(|t| t.input.instruction == "HABIN" && t.skip.is_some()),
        "the corpus has SM705-on HABIN cases, which must be skipped"
    );
}

/// An emulator that models SD0 reports it among its writes: held to the error code, apart from
/// the case's memory (never a stray write), and a wrong SD0 is a difference on SD0 alone.
#[rstest::rstest]
#[case::right("sd0", false)]
#[case::stale("sd0-stale", true)]
fn an_emulator_that_writes_sd0_is_held_to_the_error_code(
    #[case] mode: &str,
    #[case] errors_differ: bool,
) {
    if !python() {
        return;
    }
    let mut session = corpus_session();
    let spec = python_backend("habin-py", &fixtures().join("habin_adapter.py"), &[mode]);
    session
        .add(BackendSource::Process(spec), true)
        .expect("starts");
    let trials: Vec<Trial> = trials_of(&session, "habin-py")
        .into_iter()
        .filter(|t| t.skip.is_none())
        .collect();
    let mut errors = 0;
    for (t, v) in trials.iter().zip(run_all(&trials)) {
        let code = expects_a_code(t);
        errors += usize::from(code);
        if !code || !errors_differ {
            assert!(!v.is_failure(), "{}: {v:?}", t.name());
            continue;
        }
        assert_eq!(
            registers_alone(&v),
            Some(vec![("SD0".to_string(), Some(0))]),
            "{}: {v:?}",
            t.name()
        );
    }
    assert!(errors > 5, "{errors} error trials ran");
}

/// The checked-in protocol schema is what the message types generate.
#[test]
fn protocol_schema_is_current() {
    let path = root().join("schema/protocol.schema.json");
    let text = std::fs::read_to_string(&path).expect("schema/protocol.schema.json");
    let checked_in: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert!(
        checked_in == crate::backend::external::protocol::protocol_schema(),
        "schema/protocol.schema.json is stale: run \
         `cargo run -- schema --kind protocol > schema/protocol.schema.json`"
    );
}

/// A codec written with each helper (Python and JavaScript), run by the harness over the
/// cross-vendor corpus: the strict one conforms wherever it answers, the deliberately wrong one
/// (lowercase accepted) differs on the lowercase case, and an exception the adapter does not map
/// is a crash of that trial only.
#[test]
fn codecs_written_with_the_helpers_are_judged_by_the_harness() {
    if !python() {
        return;
    }
    let node = Command::new("node").arg("--version").output().is_ok();
    let mut helpers = vec![(
        "py",
        interpreter().unwrap_or("python3").to_string(),
        root().join("adapters/python/tests/fixtures/codec.py"),
    )];
    if node {
        helpers.push((
            "js",
            "node".to_string(),
            root().join("adapters/js/examples/codec.js"),
        ));
    } else {
        assert!(
            std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
            "node is required for the JavaScript helper"
        );
        eprintln!("skipped: node is not installed; the JavaScript helper needs it");
    }
    for (lang, program, script) in helpers {
        let verdicts = |mode: &str| {
            let mut s = corpus_session();
            let name = format!("{lang}-{mode}");
            let launch = Launch::Exec(vec![
                program.clone(),
                script.display().to_string(),
                mode.to_string(),
            ]);
            let mut settings = ExternalSettings::new(name.clone(), launch);
            settings.timeout = Duration::from_secs(5);
            s.add(BackendSource::Process(settings), true)
                .unwrap_or_else(|e| panic!("{name} starts: {e}"));
            let trials = trials_of(&s, &name);
            assert!(
                trials.iter().all(|t| t.is_cross_vendor()),
                "a codec runs cross-vendor cases only"
            );
            trials
                .iter()
                .map(|t| t.case_id().to_string())
                .zip(run_all(&trials))
                .collect::<Vec<_>>()
        };
        let strict = verdicts("strict");
        assert!(
            strict.iter().any(|(_, v)| v.label() == "conforms"),
            "{lang}"
        );
        let lowercase = |vs: &[(String, Verdict)]| {
            vs.iter()
                .find(|(c, _)| c == "xv-h2v-lowercase")
                .map(|(_, v)| v.clone())
                .expect("the lowercase case runs")
        };
        assert_eq!(lowercase(&strict).label(), "conforms", "{lang} strict");
        let wrong = verdicts("lowercase");
        let v = lowercase(&wrong);
        assert!(
            matches!(&v, Verdict::Differs { .. }),
            "{lang}: the wrong codec passes the lowercase case: {v:?}"
        );
    }
}
