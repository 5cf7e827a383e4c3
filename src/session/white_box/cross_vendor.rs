//! Cross-vendor cases: a wrong vendor model shows up as a difference in the cross-vendor cases
//! too, a different kind of error signal is never taken for the expected class, an outcome that
//! depends on memory the lowering does not set is caught, cross-vendor trials follow the same
//! rules as native ones (known differences, recorded cases, faults), and bad cross-vendor files
//! are load errors with file:line.

#[cfg(test)]
use std::path::Path;
use std::sync::Arc;

use super::{reference, root, session, Mutant};
use crate::load::CorpusBuilder;
use crate::model::known::Entry;
use crate::report::text::{render, Palette};
use crate::run_one;
use crate::session::Session;
use crate::Device;
use crate::ErrorSignal;
use crate::Fill;
use crate::KnownDifferences;
use crate::Trial;
use crate::{Backend, Fault, Outcome, Response};
use crate::{CrossVendorCase, Operation};
use crate::{Difference, Status, Verdict};
use rstest::rstest;

/// Every cross-vendor trial on one backend.
fn trials(session: &Session, backend: &Arc<dyn Backend>) -> Vec<Trial> {
    session
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| t.is_cross_vendor() && t.skip.is_none())
        .collect()
}

/// The verdicts of every cross-vendor trial on one backend, by trial name.
fn verdicts(session: &Session, backend: &Arc<dyn Backend>) -> Vec<(String, Verdict)> {
    trials(session, backend)
        .into_iter()
        .map(|t| (t.name(), run_one(&t)))
        .collect()
}

fn failing(session: &Session, backend: &Arc<dyn Backend>) -> Vec<String> {
    verdicts(session, backend)
        .into_iter()
        .filter(|(_, v)| v.is_failure())
        .map(|(n, _)| n)
        .collect()
}

#[test]
fn every_reference_model_answers_every_cross_vendor_case_as_expected() {
    let s = session();
    assert!(
        s.corpus.cross_vendor.len() >= 40,
        "the cross-vendor corpus has {} cases",
        s.corpus.cross_vendor.len()
    );
    for b in &s.backends {
        assert_eq!(failing(&s, b), Vec::<String>::new(), "{}", b.name());
    }
}

#[test]
fn a_model_ignoring_sm705_fails_the_terminated_lowering() {
    let s = session();
    let iqr = reference(&s, "mitsubishi-iqr");
    let mutant = Mutant::new("ignores-sm705", &iqr, |req, base| {
        let flags = req.flags.keys().map(|k| (k.clone(), false)).collect();
        base.execute(&crate::Request {
            flags: &flags,
            ..*req
        })
    });
    let fails = failing(&s, &mutant);
    assert!(
        fails.contains(
            &"cross-vendor::ignores-sm705::habin-terminated::xv-h2v-1-digit::rcpu".to_string()
        ),
        "{fails:?}"
    );
}

#[test]
fn an_idec_model_reporting_a_code_is_not_an_idec_error() {
    let s = session();
    let fc4a = reference(&s, "idec-fc4a");
    let mutant = Mutant::new("code-instead-of-m8004", &fc4a, |req, base| {
        base.execute(req).map(|r| match r {
            Response::Done(o) if o.error.is_some() => {
                Response::Done(Outcome::error(ErrorSignal::Code(0x3401)))
            }
            other => other,
        })
    });
    let trial = trials(&s, &mutant)
        .into_iter()
        .find(|t| t.name().contains("::atoh::xv-h2v-lowercase::"))
        .expect("the lowercase case runs on ATOH");
    let lowercase = run_one(&trial);
    assert!(lowercase.is_failure(), "{lowercase:?}");
    let text = render(&trial, &lowercase, Palette::plain());
    assert!(text.contains("actual error 3401H"), "{text}");
}

#[test]
fn an_outcome_that_depends_on_unset_memory_is_caught() {
    let s = session();
    let mutant = reads_unset_memory(&s);
    let v = verdicts(&s, &mutant);
    assert!(
        v.iter().any(|(_, v)| matches!(
            v,
            Verdict::Differs {
                difference: Difference::FillDependent { .. }
            }
        )),
        "no trial noticed the fill dependence"
    );
}

/// The FX5 model, except that after converting it copies a word the lowering never sets into
/// the result: its answer depends on the fill.
fn reads_unset_memory(s: &Session) -> Arc<dyn Backend> {
    let fx5 = reference(s, "mitsubishi-fx5");
    Mutant::new("reads-unset-memory", &fx5, |req, base| {
        base.execute(req).map(|r| match r {
            Response::Done(mut o) if o.error.is_none() => {
                let stray = req.memory.read(&Device::new("D", 150));
                o.writes.insert(Device::new("D", 200), stray);
                Response::Done(o)
            }
            other => other,
        })
    })
}

/// Native and cross-vendor trials once disagreed here: a listed known difference is not a
/// failure on either side.
#[test]
fn a_listed_cross_vendor_difference_is_a_known_difference_not_a_failure() {
    let mut s = session();
    let mutant = reads_unset_memory(&s);
    let (name, _) = verdicts(&s, &mutant)
        .into_iter()
        .find(|(_, v)| v.is_failure())
        .expect("the mutant fails a cross-vendor trial");
    let trial = trials(&s, &mutant)
        .into_iter()
        .find(|t| t.name() == name)
        .expect("planned");
    s.project.known.insert(
        "reads-unset-memory".into(),
        KnownDifferences {
            file: "known.yaml".into(),
            entries: vec![Entry {
                covers: crate::model::known::Covers::Case(trial.case_id().to_string()),
                instruction: Some(trial.check_name().to_string()),
                variant: None,
                kind: None,
                rule: None,
                reason: "reads D150".into(),
                location: "known.yaml:2".into(),
                also: Vec::new(),
            }],
            ignored: Vec::new(),
        },
    );
    let listed = trials(&s, &mutant)
        .into_iter()
        .find(|t| t.name() == name)
        .expect("planned");
    assert!(listed.ignored_because().is_some(), "known at planning time");
    let v = run_one(&listed);
    assert!(matches!(v, Verdict::KnownDifference { .. }), "{v:?}");
    assert_eq!(v.status(), Status::Ignored);
    assert!(!v.is_failure());
}

/// Native and cross-vendor trials once disagreed here: an `unspecified` case whose answer
/// depends on the fill is recorded (with that noted), not a failure.
#[test]
fn an_unspecified_cross_vendor_case_that_depends_on_the_fill_is_recorded() {
    let mut s = session();
    let text = format!(
        "{HEADER}  - id: xv-open\n    basis: unspecified\n    text: \"5A8D\"\n    digits: 4\n"
    );
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("xv.yaml"), &text, &s.profiles);
    s.project.corpus = builder.finish().expect("loads");
    let mutant = reads_unset_memory(&s);
    let v = verdicts(&s, &mutant);
    assert!(!v.is_empty());
    assert!(
        v.iter().any(|(_, v)| matches!(
            v,
            Verdict::Recorded {
                fill_dependent: true,
                ..
            }
        )),
        "{v:?}"
    );
    assert!(v.iter().all(|(_, v)| !v.is_failure()), "{v:?}");
}

/// Native and cross-vendor trials once disagreed here: a cross-vendor fault says which fill it
/// happened under.
#[test]
fn a_cross_vendor_fault_keeps_its_fill() {
    let s = session();
    let iqr = reference(&s, "mitsubishi-iqr");
    let mutant = Mutant::new("fails-under-fill-b", &iqr, |req, base| {
        if req.memory.fill() == Fill::B {
            Err(Fault::Crashed("exited with status 3".into()))
        } else {
            base.execute(req)
        }
    });
    let v = verdicts(&s, &mutant);
    assert!(!v.is_empty());
    for (name, v) in &v {
        assert!(
            matches!(v, Verdict::Fault { fill: Fill::B, .. }),
            "{name}: {v:?}"
        );
    }
}

const HEADER: &str = "operation: hex-to-value\nsource: test\ncases:\n";
const GOOD: &str = "  - id: xv-good
    basis: inferred
    cite: a reading
    text: \"5A8D\"
    digits: 4
    expect: {value: 5A8DH}
    except:
      iqr/habin-fixed: {value: 5A8DH, why: same}
";

#[rstest]
#[case::unknown_lowering(
    "iqr/habin-fixed",
    "iqr/habin-fast",
    11,
    "cases[0].except.iqr/habin-fast",
    "unknown lowering for this operation `iqr/habin-fast`"
)]
#[case::value_in_text_operation(
    "    text: \"5A8D\"\n",
    "    value: 5A8DH\n",
    7,
    "cases[0].value",
    "hex-to-value cases give `text`, not `value`"
)]
#[case::two_answers(
    "expect: {value: 5A8DH}",
    "expect: {value: 5A8DH, text: \"5A8D\"}",
    9,
    "cases[0].expect",
    "give `value`, `error`, or both"
)]
#[case::text_answer_for_value(
    "expect: {value: 5A8DH}",
    "expect: {text: \"5A8D\"}",
    9,
    "cases[0].expect",
    "give `value`, `error`, or both"
)]
#[case::empty_why(
    "why: same",
    "why: \" \"",
    11,
    "cases[0].except.iqr/habin-fixed",
    "missing why"
)]
#[case::too_many_digits("digits: 4", "digits: 17", 8, "cases[0].digits", "at most 16 digits")]
#[case::unknown_class(
    "expect: {value: 5A8DH}",
    "expect: {error: overflow}",
    9,
    "cases[0].expect.error",
    "unknown variant `overflow`"
)]
#[case::no_cite("    cite: a reading\n", "", 4, "cases[0]", "missing cite")]
fn bad_cross_vendor_case_is_reported(
    #[case] find: &str,
    #[case] replace: &str,
    #[case] line: usize,
    #[case] key: &str,
    #[case] message: &str,
) {
    let s = session();
    assert!(GOOD.contains(find));
    let text = format!("{HEADER}{}", GOOD.replacen(find, replace, 1));
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("xv.yaml"), &text, &s.profiles);
    let errors = builder.finish().expect_err("the bad case loaded").0;
    let e = errors
        .iter()
        .find(|e| e.to_string().contains(message))
        .unwrap_or_else(|| panic!("no error says `{message}`: {errors:#?}"));
    assert_eq!(e.line, Some(line), "{e}");
    assert_eq!(e.key.as_deref().unwrap_or(""), key, "{e}");
}

/// The behaviours where the families part, one question of the cross-vendor corpus each: what
/// the row is about; its example (the text or value, and the count) is the case's own
/// ([`example`]), never written by hand.
const BEHAVIOURS: &[(&str, &str)] = &[
    ("four hex digits", "xv-h2v-4-digits"),
    ("an odd count", "xv-h2v-3-digits"),
    ("more digits than a word", "xv-h2v-5-digits"),
    ("8 digits", "xv-h2v-8-digits"),
    ("a count of 0", "xv-h2v-count-0"),
    (
        "a count that hides an invalid character",
        "xv-h2v-count-hides-invalid-character",
    ),
    ("an invalid character", "xv-h2v-3ah-second"),
    ("a blank", "xv-h2v-space"),
    ("lowercase", "xv-h2v-lowercase"),
    ("00H after the first digit", "xv-h2v-nul-second"),
    ("a word", "xv-v2h-0abc"),
    ("a count below a word", "xv-v2h-0abc-3-digits"),
    ("more characters than a word", "xv-v2h-5-digits"),
    ("a 32-bit value", "xv-v2h-32-bit-8-digits"),
    ("a count of 0 (value to text)", "xv-v2h-count-0"),
];

/// A case's question as a row shows it: the text (or the value) and the count asked.
fn example(case: &CrossVendorCase) -> String {
    let shown = match case.operation {
        Operation::HexToValue => crate::Answer::Text(case.text.clone()).to_string(),
        _ => crate::Answer::Value(case.value).to_string(),
    };
    format!("`{}`, {} digit(s)", shown.replace('`', "\\`"), case.digits)
}

/// The table of `docs/cross-vendor-behaviours.md`: one row per behaviour, one column per
/// family, each cell the answers of the family's lowerings (by lowering where they differ),
/// as the reference models give them.
fn behaviour_table(project: &Session) -> String {
    let trials: Vec<Trial> = project
        .plan(&project.backends)
        .into_iter()
        .filter(|t| t.is_cross_vendor())
        .collect();
    let verdicts = crate::verdicts(&trials);
    let mut families: Vec<&str> = Vec::new();
    for t in &trials {
        let name = t.backend.name();
        if !families.contains(&name) {
            families.push(name);
        }
    }
    let mut out = String::from("| behaviour | case |");
    for f in &families {
        out.push_str(&format!(" {f} |"));
    }
    out.push_str("\n|---|---|");
    out.push_str(&"---|".repeat(families.len()));
    out.push('\n');
    for (behaviour, case) in BEHAVIOURS {
        let asked = (project.corpus.cross_vendor.iter())
            .find(|c| c.id == *case)
            .unwrap_or_else(|| panic!("no cross-vendor case {case}"));
        out.push_str(&format!("| {behaviour}: {} | `{case}` |", example(asked)));
        for f in &families {
            let mut answers: Vec<(String, String)> = Vec::new();
            for (t, v) in trials.iter().zip(&verdicts) {
                if t.backend.name() != *f || t.case_id() != *case || t.variant.is_empty() {
                    continue;
                }
                let mut shown = crate::report::record::Record::of(t, v).shown;
                if t.basis() == crate::Basis::Unspecified {
                    shown.push_str(" (unspecified)");
                }
                let lowering = t.check_name().to_string();
                if !answers.iter().any(|(l, _)| *l == lowering) {
                    answers.push((lowering, shown));
                }
            }
            let alike = answers.windows(2).all(|w| w[0].1 == w[1].1);
            let cell = match answers.as_slice() {
                [] => "—".to_string(),
                [(_, one), ..] if alike => one.clone(),
                many => many
                    .iter()
                    .map(|(l, a)| format!("{l}: {a}"))
                    .collect::<Vec<_>>()
                    .join("<br>"),
            };
            out.push_str(&format!(" {} |", cell.replace('|', "\\|")));
        }
        out.push('\n');
    }
    out
}

/// `docs/cross-vendor-behaviours.md` is what the models answer today. With
/// PLC_CONFORMANCE_BLESS set the file is written anew.
#[test]
fn the_cross_vendor_behaviour_table_is_current() {
    let project = session();
    let table = behaviour_table(&project);
    let path = root().join("docs/cross-vendor-behaviours.md");
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    let start = "<!-- table: generated by src/session/white_box/cross_vendor.rs -->\n";
    let end = "<!-- end of table -->";
    let (head, tail) = match (text.find(start), text.find(end)) {
        (Some(a), Some(b)) if a < b => (&text[..a + start.len()], &text[b..]),
        _ => panic!("{} lacks its table markers", path.display()),
    };
    let fresh = format!("{head}{table}{tail}");
    if std::env::var_os("PLC_CONFORMANCE_BLESS").is_some() {
        std::fs::write(&path, &fresh).expect("write the table");
        return;
    }
    assert!(
        fresh == text,
        "docs/cross-vendor-behaviours.md is stale: run \
         `PLC_CONFORMANCE_BLESS=1 cargo test --lib cross_vendor::the_cross_vendor_behaviour_table`"
    );
}
