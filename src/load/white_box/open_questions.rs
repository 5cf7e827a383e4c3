//! The open questions are data: every question loads, names readings and probes that exist, and
//! has a probe that decides between its readings, whose outcome on the reference model is the
//! reading the model takes. That `run --probes` runs exactly the probe cases is checked through
//! the binary, in tests/open_questions.rs.

#[cfg(test)]
use super::{root, scratch, session};
use crate::load::{load_open_questions, OPEN_QUESTIONS};

/// The project's open questions, loaded against its profiles and corpus.
fn questions(s: &crate::session::Session) -> Vec<crate::model::open_questions::OpenQuestion> {
    load_open_questions(&root().join(OPEN_QUESTIONS), &s.profiles, &s.corpus)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// What loading a questions file of `text` reports; `loaded` is the panic if it loads.
fn load_errors(text: &str, loaded: &str) -> String {
    let s = session();
    let dir = scratch();
    let file = dir.path().join("q.yaml");
    std::fs::write(&file, text).expect("write");
    load_open_questions(&file, &s.profiles, &s.corpus)
        .expect_err(loaded)
        .to_string()
}

/// `cases`, each changed by `change` (each a copy: the cases are shared).
fn changed<T: Clone>(
    cases: &[std::sync::Arc<T>],
    change: impl Fn(&mut T),
) -> Vec<std::sync::Arc<T>> {
    cases
        .iter()
        .map(|c| {
            let mut c = (**c).clone();
            change(&mut c);
            std::sync::Arc::new(c)
        })
        .collect()
}

#[test]
fn every_open_question_has_probes_in_the_corpus() {
    let questions = questions(&session());
    assert!(questions.len() >= 10, "{} questions", questions.len());
    for q in &questions {
        assert!(!q.probes.is_empty(), "{} has no probe", q.id);
        assert!(q.readings.len() >= 2, "{}", q.id);
    }
}

#[test]
fn a_probe_that_is_not_a_case_is_a_load_error() {
    let errors = load_errors(
        "questions:\n  - id: q\n    title: t\n    profile: mitsubishi-iqr\n    instructions: [HABIN]\n    \
         readings: [{id: a, text: a}, {id: b, text: b}]\n    model_takes: a\n    evidence: [x]\n    \
         probes: [habin-fixed-4-digits-example, no-such-case]\n",
        "an unknown probe loaded",
    );
    assert!(
        errors.contains(":9: questions[0].probes[1]: `no-such-case` is not a case id"),
        "{errors}"
    );
}

/// Every question names a probe that tells its readings apart (each reading predicts another
/// outcome, which the loader checks), and the reference model's outcome on that probe is the
/// one its own reading predicts, under every variant the question is about: the reading the
/// model takes is asserted even where the probe is `unspecified`.
#[test]
fn every_question_has_a_probe_that_decides_and_the_model_answers_its_reading() {
    use crate::plan::Check;
    use crate::Basis;
    use crate::Verdict;

    let mut s = session();
    let questions = questions(&s);
    // Every case recorded rather than judged, so that the verdict says what the model did.
    s.project.corpus.cases = changed(&s.corpus.cases, |c: &mut crate::Case| {
        c.basis = Basis::Unspecified
    });
    s.project.corpus.cross_vendor =
        changed(&s.corpus.cross_vendor, |c: &mut crate::CrossVendorCase| {
            c.basis = Basis::Unspecified
        });
    let mut problems = Vec::new();
    for q in &questions {
        let Some(decides) = &q.decides else {
            problems.push(format!("{}: no probe decides between its readings", q.id));
            continue;
        };
        let Some((_, predicted)) = decides.outcomes.iter().find(|(r, _)| *r == q.model_takes)
        else {
            continue; // `model_takes: none`: the model does not represent the fact.
        };
        let backends: Vec<_> = s
            .backends
            .iter()
            .filter(|b| b.profile() == q.profile)
            .cloned()
            .collect();
        let variants = q.variants.clone();
        let trials: Vec<_> = s
            .plan(&backends)
            .into_iter()
            .filter(|t| match &t.check {
                Check::Native { case, .. } => case.id == decides.probe,
                Check::CrossVendor { case, .. } | Check::Codec { case } => case.id == decides.probe,
            })
            .filter(|t| match &t.check {
                Check::Native { .. } => true,
                // A cross-vendor probe through the question's profile only.
                _ => t.profile.as_ref().is_some_and(|p| p.id == q.profile),
            })
            .filter(|t| variants.as_ref().is_none_or(|v| v.contains(&t.variant)))
            .filter(|t| t.skip.is_none())
            .collect();
        if trials.is_empty() {
            problems.push(format!("{}: probe {} runs nowhere", q.id, decides.probe));
        }
        for t in &trials {
            match crate::run_one(t) {
                Verdict::Recorded {
                    observed,
                    fill_dependent: false,
                } if observed.to_string() == *predicted => {}
                other => problems.push(format!(
                    "{}: {} predicts `{predicted}` of {}, the model ({}) gives {}",
                    q.id,
                    q.model_takes,
                    decides.probe,
                    t.name(),
                    match other {
                        Verdict::Recorded { observed, .. } => format!("`{observed}`"),
                        v => format!("{v:?}"),
                    }
                )),
            }
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
}

/// A probe that "decides" but predicts one outcome under two readings, or leaves a reading out,
/// is refused at load: it could not tell them apart.
#[test]
fn a_deciding_probe_that_cannot_tell_two_readings_apart_is_a_load_error() {
    let errors = load_errors(
        "questions:\n  - id: q\n    title: t\n    profile: mitsubishi-iqr\n    instructions: [HABIN]\n    \
         readings: [{id: a, text: a}, {id: b, text: b}, {id: c, text: c}]\n    model_takes: a\n    \
         evidence: [x]\n    probes: [habin-fixed-4-digits-example]\n    decides:\n      \
         probe: habin-fixed-4-digits-example\n      outcomes: {a: \"D200=5A8DH\", b: \"D200=5A8DH\"}\n",
        "a probe that decides nothing loaded",
    );
    assert!(
        errors.contains("readings `a` and `b` predict the same outcome `D200=5A8DH`"),
        "{errors}"
    );
    assert!(errors.contains("reading `c` has no outcome"), "{errors}");
}
