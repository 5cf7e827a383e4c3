//! Judging: what a trial's observations mean, as one [`Verdict`].
//!
//! One judging function serves native and cross-vendor trials alike, and the known-differences
//! list of the trial's backend is applied here, once. A native case compares words and error
//! signals with its expectation; a cross-vendor case lifts each fill's outcome to an
//! [`Answer`] and compares that. The comparer knows nothing of vendors beyond what the profile
//! says.

pub(crate) mod lift;
pub(crate) mod words;

use serde::{Deserialize, Serialize};

use crate::backend::{Fault, Response};
use crate::execute::Observation;
use crate::memory::Fill;
use crate::model::cross_vendor::Answer;
use crate::model::known::Entry;
use crate::model::Basis;
use crate::plan::{Check, Trial};
pub use words::{Effect, Mismatch, RegisterRow, WordRow};

/// The verdict of one trial.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
#[non_exhaustive]
pub enum Verdict {
    /// The backend did what the case expects, under every fill.
    Conforms,
    /// The backend did something other than the case expects: a failure.
    Differs {
        /// What differed: the words or the error, or the cross-vendor answer.
        difference: Difference,
    },
    /// A backend that claimed the trial answered that it does not implement it.
    Unsupported {
        /// The backend's own explanation of what it does not implement.
        reason: String,
    },
    /// The backend gave no usable answer under this fill.
    Fault {
        /// The fill under which the backend gave no usable answer.
        fill: Fill,
        /// What went wrong: a crash, a hang, a garbled answer, a panic.
        fault: Fault,
    },
    /// An `unspecified` case (or one without an expectation): what the backend did, recorded,
    /// never a failure.
    Recorded {
        /// What the backend did (under fill A), as reports and baselines show it.
        observed: Observed,
        /// Whether the two fills gave different outcomes: the backend reads memory the case does
        /// not set.
        fill_dependent: bool,
    },
    /// Not run, with why (the backend does not claim it).
    Skipped {
        /// Why the trial was not run, as reports show it.
        reason: String,
    },
    /// Not run, or cut off, because a signal interrupted the run: counted with the skipped
    /// trials, never a failure, and never taken for a backend's skip.
    Cancelled,
    /// A difference the backend's known-differences file lists: reported, not a failure.
    KnownDifference {
        /// The known-differences entry that lists the trial.
        entry: KnownEntry,
        /// The verdict without the entry: [`Verdict::Differs`] or [`Verdict::Unsupported`].
        difference: Box<Verdict>,
    },
    /// A known-differences entry for a trial that conforms: a failure until the entry goes.
    StaleEntry {
        /// The entry that no longer matches a difference: remove it from the file.
        entry: KnownEntry,
    },
}

/// What a cancelled trial shows as its reason.
const CANCELLED: &str = "not run: the run was interrupted";

impl Verdict {
    /// Why the trial did not run (skipped or cancelled).
    pub fn not_run(&self) -> Option<&str> {
        match self {
            Verdict::Skipped { reason } => Some(reason),
            Verdict::Cancelled => Some(CANCELLED),
            _ => None,
        }
    }
}

/// How a trial differed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
#[non_exhaustive]
pub enum Difference {
    /// Native: the words or the error under one or more fills.
    Words {
        /// One per fill whose words, error or error registers differ.
        mismatches: Vec<Mismatch>,
    },
    /// Cross-vendor: another answer than the case expects of this lowering.
    Answer {
        /// The answer the case expects of this lowering.
        expected: Answer,
        /// The answer the backend gave.
        actual: Answer,
    },
    /// Cross-vendor: the answer depends on memory the case does not set.
    FillDependent {
        /// The answer under fill A.
        fill_a: Answer,
        /// The answer under fill B.
        fill_b: Answer,
    },
}

/// What a backend did on a recorded trial.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "value")]
pub enum Observed {
    /// Native: the words changed and the error (under fill A).
    Memory(Effect),
    /// Cross-vendor: the answer (under fill A).
    Answer(Answer),
}

impl std::fmt::Display for Observed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Observed::Memory(e) => write!(f, "{e}"),
            Observed::Answer(a) => write!(f, "{a}"),
        }
    }
}

/// A known-differences entry as a verdict cites it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct KnownEntry {
    /// The entry's reason, or its kind and cause: what a report shows.
    pub reason: String,
    /// `file:line` of the entry.
    pub location: String,
    /// The other entries that cover the trial too (`file:line: reason`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<String>,
}

/// What a verdict means for a run: the one place where verdicts become pass or fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Status {
    /// The trial conforms.
    Pass,
    /// Differs, unsupported though claimed, faulted, or a stale entry: the run fails.
    Fail,
    /// Ran, but cannot fail: recorded, or a listed known difference.
    Ignored,
    /// Did not run.
    Skipped,
}

impl Status {
    /// Whether this status fails the run (exit code 1).
    pub fn is_failure(self) -> bool {
        self == Status::Fail
    }
}

impl Verdict {
    /// What the verdict means for the run: pass, fail, ignored or skipped.
    pub fn status(&self) -> Status {
        match self {
            Verdict::Conforms => Status::Pass,
            Verdict::Differs { .. }
            | Verdict::Unsupported { .. }
            | Verdict::Fault { .. }
            | Verdict::StaleEntry { .. } => Status::Fail,
            Verdict::Recorded { .. } | Verdict::KnownDifference { .. } => Status::Ignored,
            Verdict::Skipped { .. } | Verdict::Cancelled => Status::Skipped,
        }
    }

    /// Whether the verdict fails the run: its [`Verdict::status`] is [`Status::Fail`].
    pub fn is_failure(&self) -> bool {
        self.status() == Status::Fail
    }

    /// A short label: what a summary or a matrix legend shows.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Conforms => "conforms",
            Verdict::Differs { .. } => "differs",
            Verdict::Unsupported { .. } => "unsupported",
            Verdict::Fault { fault, .. } => fault.kind(),
            Verdict::Recorded { .. } => "recorded",
            Verdict::Skipped { .. } => "skipped",
            Verdict::Cancelled => "cancelled",
            Verdict::KnownDifference { .. } => "known-difference",
            Verdict::StaleEntry { .. } => "stale-entry",
        }
    }
}

/// Judges a trial from its observations (one per fill, in [`Fill::ALL`] order) and applies the
/// known-differences entry the plan found for it.
pub(crate) fn judge(trial: &Trial, observations: &[Observation]) -> Verdict {
    apply_known(trial.known.as_ref(), judge_unlisted(trial, observations))
}

/// The verdict of a trial that is not run.
pub(crate) fn skipped(reason: &str) -> Verdict {
    Verdict::Skipped {
        reason: reason.to_string(),
    }
}

fn judge_unlisted(trial: &Trial, observations: &[Observation]) -> Verdict {
    let answers_expected = match trial.check {
        Check::Codec { .. } => 1,
        _ => Fill::ALL.len(),
    };
    if observations.len() != answers_expected {
        return Verdict::Fault {
            fill: observations.first().map_or(Fill::A, |o| o.fill),
            fault: Fault::Protocol(format!(
                "{} answer(s) where {answers_expected} were due",
                observations.len()
            )),
        };
    }
    // A fault or an `unsupported` answer under any fill is the verdict.
    for obs in observations {
        match &obs.result {
            Err(fault) => {
                return Verdict::Fault {
                    fill: obs.fill,
                    fault: fault.clone(),
                }
            }
            Ok(Response::Unsupported(reason)) => {
                return Verdict::Unsupported {
                    reason: reason.clone(),
                }
            }
            Ok(_) => {}
        }
    }
    let wrong_kind = |obs: &Observation| Verdict::Fault {
        fill: obs.fill,
        fault: Fault::Protocol(match trial.check {
            Check::Codec { .. } => "an instruction's outcome answered a codec question".into(),
            _ => "a codec answer answered an instruction request".into(),
        }),
    };
    match &trial.check {
        Check::Native { case, .. } => {
            let mut outcomes = Vec::new();
            for obs in observations {
                match &obs.result {
                    Ok(Response::Done(o)) => outcomes.push((trial.image(obs.fill), o)),
                    _ => return wrong_kind(obs),
                }
            }
            let effects: Vec<Effect> = outcomes.iter().map(|(i, o)| Effect::of(i, o)).collect();
            let fill_dependent = effects.windows(2).any(|p| p[0] != p[1]);
            let expect = match &case.expect {
                Some(e) if case.basis != Basis::Unspecified => e,
                _ => {
                    return Verdict::Recorded {
                        observed: Observed::Memory(
                            effects
                                .into_iter()
                                .next()
                                .unwrap_or_else(|| Effect::none(trial.image(Fill::A).unit())),
                        ),
                        fill_dependent,
                    }
                }
            };
            let registers = trial
                .profile
                .as_ref()
                .map_or_else(Vec::new, |p| p.errors.code_registers());
            let mismatches: Vec<Mismatch> = outcomes
                .iter()
                .filter_map(|(image, outcome)| {
                    words::mismatch(image, expect, outcome, image.fill(), &registers)
                })
                .collect();
            if mismatches.is_empty() {
                Verdict::Conforms
            } else {
                Verdict::Differs {
                    difference: Difference::Words { mismatches },
                }
            }
        }
        Check::CrossVendor { lowering, case } => {
            let Some(profile) = &trial.profile else {
                return Verdict::Unsupported {
                    reason: "a lowering needs its profile".into(),
                };
            };
            let mut answers = Vec::new();
            for obs in observations {
                match &obs.result {
                    Ok(Response::Done(o)) => {
                        let image = trial.image(obs.fill);
                        answers.push(lift::lift(profile, lowering, case.digits, o, &image));
                    }
                    _ => return wrong_kind(obs),
                }
            }
            compare_answers(case.basis, case.expected_for(&lowering.key), answers)
        }
        Check::Codec { case } => match &observations[0].result {
            // A codec answers the case's plain reading: it has no vendor's exceptions.
            // Read as the codec's field writes it (its byte order, its leading zeros).
            Ok(Response::Answer(a)) => {
                let ability = trial.backend.codec().and_then(|c| c.of(case.operation));
                // A protocol's field is the protocol's: its order and width are not the codec's
                // to declare.
                let expected = match (ability, &case.expect, &case.protocol) {
                    (Some(ab), Some(e), None) => Some(ab.shaped(case.operation, case.digits, e)),
                    (_, e, _) => e.clone(),
                };
                // A protocol names one answer to data it refuses (C050H, NAK 07H, no response):
                // which class a codec gives its refusal is its own.
                let expected = match (&case.protocol, expected, a) {
                    (Some(_), Some(Answer::Error(_)), Answer::Error(_)) => Some(a.clone()),
                    (_, e, _) => e,
                };
                compare_answers(case.basis, expected.as_ref(), vec![a.clone()])
            }
            _ => wrong_kind(&observations[0]),
        },
    }
}

/// Judges cross-vendor answers (one per fill, or one for a codec) against the expected one.
fn compare_answers(basis: Basis, expected: Option<&Answer>, answers: Vec<Answer>) -> Verdict {
    let fill_dependent = answers.windows(2).any(|p| p[0] != p[1]);
    let Some(first) = answers.first().cloned() else {
        return Verdict::Unsupported {
            reason: "no answer".into(),
        };
    };
    let expected = match expected {
        Some(e) if basis != Basis::Unspecified => e,
        _ => {
            return Verdict::Recorded {
                observed: Observed::Answer(first),
                fill_dependent,
            }
        }
    };
    if fill_dependent {
        return Verdict::Differs {
            difference: Difference::FillDependent {
                fill_a: first,
                fill_b: answers[1].clone(),
            },
        };
    }
    if first == *expected {
        Verdict::Conforms
    } else {
        Verdict::Differs {
            difference: Difference::Answer {
                expected: expected.clone(),
                actual: first,
            },
        }
    }
}

/// Applies a known-differences entry: a listed difference (or `unsupported` answer) is a known
/// difference, a listed trial that conforms is a stale entry, and a fault stays a fault.
pub(crate) fn apply_known(entry: Option<&Entry>, verdict: Verdict) -> Verdict {
    let Some(entry) = entry else {
        return verdict;
    };
    let cited = KnownEntry {
        reason: entry.reason.clone(),
        location: entry.location.clone(),
        also: entry.also.clone(),
    };
    match verdict {
        Verdict::Differs { .. } | Verdict::Unsupported { .. } => Verdict::KnownDifference {
            entry: cited,
            difference: Box::new(verdict),
        },
        Verdict::Conforms => Verdict::StaleEntry { entry: cited },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::path::Path;
    use std::sync::Arc;

    use super::*;
    use crate::backend::{Backend, Outcome, Request};
    use crate::device::Device;
    use crate::memory::Value;
    use crate::model::{Case, ErrorSignal, Expectation};
    use crate::plan::Input;

    /// A backend that is never asked anything: these tests judge given observations.
    struct Idle;

    impl Backend for Idle {
        fn name(&self) -> &str {
            "idle"
        }
        fn profile(&self) -> &str {
            "p"
        }
        fn describe(&self) -> String {
            "idle".into()
        }
        fn claims(&self, _: &str, _: &str) -> bool {
            true
        }
        fn execute(&self, _: &Request<'_>) -> Result<Response, Fault> {
            Err(Fault::Unreachable("idle".into()))
        }
    }

    fn trial(case: Case) -> Trial {
        let mut errors = Vec::new();
        let profile = crate::load::parse_profile(
            Path::new("p.yaml"),
            "id: p\nname: P\nshort: p\nmanuals: {}\nerrors: {signal: code, flag: SM0, register: SD0, also: [SD8067]}\n\
             devices: {D: {first: 0, last: 1000}}\ninstructions: {}\n\
             variants: [{id: v, description: v}]\n",
            &mut errors,
        )
        .expect("profile");
        Trial {
            backend: Arc::new(Idle),
            profile: Some(Arc::new(profile)),
            variant: "v".into(),
            input: Arc::new(Input {
                instruction: "HABIN".into(),
                flags: BTreeMap::new(),
                operands: BTreeMap::new(),
                indirect: Default::default(),
                before: case.before.clone(),
            }),
            check: Check::Native {
                instruction: "HABIN".into(),
                case: Arc::new(case),
            },
            skip: None,
            known: None,
        }
    }

    fn d(i: u32) -> Device {
        Device::new("D", i)
    }

    fn case(basis: Basis, expect: Option<Expectation>) -> Case {
        Case {
            before: BTreeMap::from([(d(100), 0x4135)]),
            expect,
            ..crate::test_support::habin_case("c", basis)
        }
    }

    fn done(writes: &[(u32, u16)], error: Option<ErrorSignal>) -> Vec<Observation> {
        Fill::ALL
            .iter()
            .map(|&fill| Observation {
                fill,
                result: Ok(Response::Done(Outcome {
                    writes: writes
                        .iter()
                        .map(|(i, v)| (d(*i), Value::from(*v)))
                        .collect(),
                    error: error.clone(),
                    registers: BTreeMap::new(),
                })),
            })
            .collect()
    }

    fn expect(after: &[(u32, u16)], error: Option<ErrorSignal>) -> Option<Expectation> {
        Some(Expectation {
            after: after
                .iter()
                .map(|(i, v)| (d(*i), Value::from(*v)))
                .collect(),
            error,
        })
    }

    /// Judged on the change: what was expected, a stray write, a word rewritten with its own
    /// value (no change), a change missing.
    #[rstest::rstest]
    #[case::the_expected_change_conforms(&[(200, 0x5A8D)], &[(200, 0x5A8D)], true)]
    #[case::a_stray_write_differs(&[(200, 0x5A8D)], &[(200, 0x5A8D), (201, 0)], false)]
    #[case::rewriting_a_word_with_its_value_is_no_change(&[], &[(100, 0x4135)], true)]
    #[case::a_missing_change_differs(&[(200, 0x5A8D)], &[], false)]
    fn the_change_is_judged(
        #[case] expected: &[(u32, u16)],
        #[case] written: &[(u32, u16)],
        #[case] conforms: bool,
    ) {
        let c = case(Basis::Manual, expect(expected, None));
        let v = judge(&trial(c), &done(written, None));
        if conforms {
            assert_eq!(v, Verdict::Conforms);
        } else {
            assert!(v.is_failure(), "{v:?}");
        }
    }

    #[test]
    fn a_code_never_satisfies_a_flag() {
        let flag = ErrorSignal::Flag(Device::new("M", 8004));
        let c = case(Basis::Manual, expect(&[], Some(flag)));
        assert!(judge(
            &trial(c.clone()),
            &done(&[], Some(ErrorSignal::Code(0x3401)))
        )
        .is_failure());
        assert!(judge(&trial(c.clone()), &done(&[], None)).is_failure());
    }

    /// The same observations with the error registers reported as given.
    fn with_registers(mut obs: Vec<Observation>, registers: &[(&str, u16)]) -> Vec<Observation> {
        for o in &mut obs {
            if let Ok(Response::Done(outcome)) = &mut o.result {
                outcome.registers = registers
                    .iter()
                    .map(|(r, v)| (r.parse().expect("device"), Value::from(*v)))
                    .collect();
            }
        }
        obs
    }

    #[test]
    fn every_error_register_must_hold_the_code_when_the_backend_reports_them() {
        let code = Some(ErrorSignal::Code(0x3401));
        let c = case(Basis::Manual, expect(&[], code.clone()));
        let both = with_registers(
            done(&[], code.clone()),
            &[("SD0", 0x3401), ("SD8067", 0x3401)],
        );
        assert_eq!(judge(&trial(c.clone()), &both), Verdict::Conforms);
        // A backend that models no register is judged on the code alone.
        assert_eq!(
            judge(&trial(c.clone()), &done(&[], code.clone())),
            Verdict::Conforms
        );
        let stale = with_registers(done(&[], code.clone()), &[("SD0", 0x3401), ("SD8067", 0)]);
        let Verdict::Differs {
            difference: Difference::Words { mismatches },
        } = judge(&trial(c.clone()), &stale)
        else {
            panic!("a stale SD8067 must differ");
        };
        assert!(!mismatches[0].error_differs() && mismatches[0].only_registers_differ());
        // With a stray word too, the trial is one of wrong words (in every report and draft).
        let also_a_word = with_registers(
            done(&[(300, 1)], code.clone()),
            &[("SD0", 0x3401), ("SD8067", 0)],
        );
        let Verdict::Differs {
            difference: Difference::Words { mismatches: both },
        } = judge(&trial(c.clone()), &also_a_word)
        else {
            panic!("a stray word must differ");
        };
        assert!(both[0].registers_differ() && !both[0].only_registers_differ());
        let wrong = &mismatches[0].registers;
        assert_eq!(
            (wrong[1].device.to_string(), wrong[1].actual),
            ("SD8067".to_string(), Some(0))
        );
        let missing = with_registers(done(&[], code.clone()), &[("SD0", 0x3401)]);
        assert!(judge(&trial(c.clone()), &missing).is_failure());
    }

    #[test]
    fn error_registers_are_not_judged_after_a_success() {
        let c = case(Basis::Manual, expect(&[(200, 1)], None));
        let obs = with_registers(done(&[(200, 1)], None), &[("SD0", 0x1234)]);
        assert_eq!(judge(&trial(c.clone()), &obs), Verdict::Conforms);
    }

    #[test]
    fn faults_and_unsupported_fail() {
        let c = case(Basis::Manual, expect(&[], None));
        let mut fault = done(&[], None);
        fault[0].result = Err(Fault::Timeout("5 s".into()));
        assert_eq!(judge(&trial(c.clone()), &fault).label(), "timeout");
        assert!(judge(&trial(c.clone()), &fault).is_failure());
        let mut unsupported = done(&[], None);
        unsupported[0].result = Ok(Response::Unsupported("no".into()));
        assert!(judge(&trial(c.clone()), &unsupported).is_failure());
    }

    #[test]
    fn unspecified_records_and_notes_fill_dependence() {
        let c = case(Basis::Unspecified, None);
        let mut obs = done(&[(200, 1)], None);
        let v = judge(&trial(c.clone()), &obs);
        assert!(
            matches!(&v, Verdict::Recorded { observed, fill_dependent: false } if observed.to_string() == "D200=0001H"),
            "{v:?}"
        );
        obs[1].result = Ok(Response::Done(Outcome::default()));
        assert!(matches!(
            judge(&trial(c.clone()), &obs),
            Verdict::Recorded {
                fill_dependent: true,
                ..
            }
        ));
    }
}

#[cfg(test)]
mod known_tests {
    use super::*;

    fn entry() -> Entry {
        Entry {
            covers: crate::model::known::Covers::Case("c".into()),
            instruction: None,
            variant: None,
            kind: None,
            rule: None,
            reason: "r".into(),
            location: "k.yaml:2".into(),
            also: Vec::new(),
        }
    }

    #[test]
    fn a_listed_difference_is_known_and_a_listed_pass_is_stale() {
        let differs = Verdict::Unsupported { reason: "u".into() };
        let known = apply_known(Some(&entry()), differs);
        assert_eq!(known.status(), Status::Ignored);
        assert!(!known.is_failure());
        let stale = apply_known(Some(&entry()), Verdict::Conforms);
        assert!(matches!(stale, Verdict::StaleEntry { .. }));
        assert!(stale.is_failure());
        let fault = Verdict::Fault {
            fill: Fill::B,
            fault: Fault::Crashed("x".into()),
        };
        assert_eq!(apply_known(Some(&entry()), fault.clone()), fault);
    }
}
