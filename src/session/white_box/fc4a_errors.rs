//! An IDEC error expectation is the flag M8004, and only the flag satisfies it.
//!
//! The FC4A shows a user program execution error as M8004 turning on; no code is relied on.
//! A backend that answers with a Mitsubishi-style code, or with no error at all, must fail every
//! case that expects M8004 and still pass the cases that expect none; and a vector cannot write
//! a code for a profile that signals with a flag.

#[cfg(test)]
use std::path::Path;
use std::sync::Arc;

use super::{reference, root, session, Mutant};
use crate::load::{load_profiles, CorpusBuilder};
use crate::plan::Check;
use crate::{run_one, Backend, Basis, Difference, ErrorSignal, Project, Response, Trial, Verdict};

const PROFILE: &str = "idec-fc4a";

/// Replaces the reference's error signal.
fn signalling(
    name: &'static str,
    error: Option<ErrorSignal>,
    base: &Arc<dyn Backend>,
) -> Arc<dyn Backend> {
    Mutant::new(name, base, move |req, base| {
        base.execute(req).map(|r| match r {
            Response::Done(mut o) => {
                if o.error.is_some() {
                    o.error = error.clone();
                }
                Response::Done(o)
            }
            other => other,
        })
    })
}

/// Runs the FC4A corpus on a backend; checks every trial that expects M8004 fails on the error
/// alone and every other asserted trial conforms; returns the names of the failing trials.
/// The native trials of the corpus on a backend.
fn native(session: &Project, backend: &Arc<dyn Backend>) -> Vec<Trial> {
    session
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| !t.is_cross_vendor())
        .collect()
}

fn failing_on_error_only(session: &Project, backend: &Arc<dyn Backend>) -> Vec<String> {
    let m8004 = ErrorSignal::Flag("M8004".parse().expect("a device name"));
    let mut failing = Vec::new();
    for trial in native(session, backend) {
        assert!(trial.skip.is_none(), "{} is skipped", trial.name());
        let Check::Native { case, .. } = &trial.check else {
            continue;
        };
        if case.basis == Basis::Unspecified {
            continue;
        }
        let expects_flag = case
            .expect
            .as_ref()
            .is_some_and(|e| e.error.as_ref() == Some(&m8004));
        let verdict = run_one(&trial);
        if expects_flag {
            assert!(verdict.is_failure(), "{} passes: {verdict:?}", trial.name());
            let Verdict::Differs {
                difference: Difference::Words { mismatches },
            } = &verdict
            else {
                panic!("{}: expected a difference, got {verdict:?}", trial.name());
            };
            assert!(
                mismatches
                    .iter()
                    .all(|m| m.error_differs() && !m.words_differ()),
                "{}: the difference should be the error alone: {mismatches:?}",
                trial.name()
            );
            failing.push(trial.name());
        } else {
            assert_eq!(verdict, Verdict::Conforms, "{}", trial.name());
        }
    }
    failing
}

/// A code in place of M8004, or no error at all: every case that expects M8004 fails.
#[rstest::rstest]
#[case::a_code(
    "fc4a-reports-3401h",
    Some(ErrorSignal::Code(0x3401)),
    &[
        "fc4a-reports-3401h::atoh::atoh-invalid-2fh::c10r2",
        "fc4a-reports-3401h::atoh::atoh-s2-zero::d40k3",
        "fc4a-reports-3401h::atoh::atoh-s1-past-d399-small::c16r2",
        "fc4a-reports-3401h::htoa::htoa-s2-five::c24r2",
    ]
)]
#[case::no_error(
    "fc4a-reports-nothing",
    None,
    &[
        "fc4a-reports-nothing::atoh::atoh-lowercase-a-61h::d20rk1",
        "fc4a-reports-nothing::atoh::atoh-s2-from-data-register-zero::c24r2",
        "fc4a-reports-nothing::htoa::htoa-d1-across-slim-gap::d20k3",
    ]
)]
fn only_m8004_satisfies_m8004(
    #[case] name: &'static str,
    #[case] signal: Option<ErrorSignal>,
    #[case] must_fail: &[&str],
) {
    let session = session();
    let base = reference(&session, PROFILE);
    let wrong = signalling(name, signal, &base);
    let failing = failing_on_error_only(&session, &wrong);
    for name in must_fail {
        assert!(failing.iter().any(|t| t == name), "{name} does not fail");
    }
    assert!(failing.len() >= 100, "only {} trials fail", failing.len());
}

/// The flag itself, from the reference, passes: the checks above fail for the signal, not for
/// something else about the trials.
#[test]
fn the_reference_signals_m8004() {
    let session = session();
    let base = reference(&session, PROFILE);
    let m8004 = signalling(
        "fc4a-reports-m8004",
        Some(ErrorSignal::Flag("M8004".parse().expect("a device name"))),
        &base,
    );
    for trial in session.plan(std::slice::from_ref(&m8004)) {
        assert!(!run_one(&trial).is_failure(), "{} fails", trial.name());
    }
}

#[test]
fn a_vector_cannot_expect_a_code_from_fc4a() {
    let profiles = load_profiles(&root().join("vendors")).expect("the profiles load");
    let text = r#"
instructions: [ATOH]
profiles: [idec-fc4a]
source: {manual: fc4a-user, page: "14-5"}
cases:
  - id: atoh-code-instead-of-flag
    basis: manual
    cite: "p.14-5"
    operands: {S1: D100, S2: 4, D1: D200}
    before:
      D100: {ascii_words: "123a"}
    expect:
      error: 3401H
"#;
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("code.yaml"), text, &profiles);
    let errors = builder
        .finish()
        .expect_err("a code is rejected")
        .to_string();
    assert!(
        errors.contains("code.yaml:13: cases[0].expect.error")
            && errors.contains("signals errors with M8004 only"),
        "{errors}"
    );
}
