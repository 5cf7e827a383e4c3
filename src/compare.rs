//! Comparing what a backend did with what a case expects.
//!
//! The comparison is semantic: a word counts as changed only if its value differs from before,
//! every change not in the expectation is a difference, and errors compare as signals (a code
//! never equals a flag). The comparer knows nothing of vendors.

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use crate::backend::{Fault, Outcome, Response};
use crate::device::Device;
use crate::memory::{Fill, Image};
use crate::model::{Basis, Case, ErrorSignal, Expectation};

/// One word in a comparison: its value before, as expected after, and as found after.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct WordRow {
    pub device: Device,
    pub before: u16,
    pub expected: u16,
    pub actual: u16,
}

/// How one run (under one fill) differed from the expectation.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Mismatch {
    pub fill: Fill,
    /// Every word the expectation or the backend touched, in device order.
    pub rows: Vec<WordRow>,
    pub expected_error: Option<ErrorSignal>,
    pub actual_error: Option<ErrorSignal>,
}

impl Mismatch {
    pub fn words_differ(&self) -> bool {
        self.rows.iter().any(|r| r.expected != r.actual)
    }
    pub fn error_differs(&self) -> bool {
        self.expected_error != self.actual_error
    }
}

/// What one backend did under one fill.
#[derive(Debug, Clone, Serialize)]
pub struct Observation {
    pub fill: Fill,
    pub result: Result<Response, Fault>,
}

/// The verdict of one trial.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
pub enum Verdict {
    Conforms,
    Differs {
        mismatches: Vec<Mismatch>,
    },
    /// A backend that claimed the trial answered that it does not implement it.
    Unsupported {
        reason: String,
    },
    /// The backend gave no usable answer.
    Fault {
        fill: Fill,
        fault: Fault,
    },
    /// An `unspecified` case: what the backend did, recorded, never a failure.
    Recorded {
        observed: String,
        fill_dependent: bool,
    },
    /// A difference the backend's known-differences file lists: reported, not a failure.
    KnownDifference {
        reason: String,
        /// `file:line` of the entry.
        entry: String,
        difference: Box<Verdict>,
    },
    /// A known-differences entry for a trial that conforms: a failure until the entry goes.
    StaleEntry {
        reason: String,
        entry: String,
    },
}

impl Verdict {
    /// Whether this verdict fails a run.
    pub fn is_failure(&self) -> bool {
        matches!(
            self,
            Verdict::Differs { .. }
                | Verdict::Unsupported { .. }
                | Verdict::Fault { .. }
                | Verdict::StaleEntry { .. }
        )
    }

    /// A short label: what a matrix cell or summary line shows.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Conforms => "conforms",
            Verdict::Differs { .. } => "differs",
            Verdict::Unsupported { .. } => "unsupported",
            Verdict::Fault { fault, .. } => match fault {
                Fault::Crashed(_) => "crashed",
                Fault::Timeout(_) => "timeout",
                Fault::Protocol(_) => "protocol-error",
                Fault::Unreachable(_) => "unreachable",
            },
            Verdict::Recorded { .. } => "recorded",
            Verdict::KnownDifference { .. } => "known-difference",
            Verdict::StaleEntry { .. } => "stale-entry",
        }
    }
}

/// The rows of a comparison between an expectation and an outcome over the same image.
pub fn rows(before: &Image, expect: &Expectation, outcome: &Outcome) -> Vec<WordRow> {
    let devices: BTreeSet<&Device> = expect.after.keys().chain(outcome.writes.keys()).collect();
    devices
        .into_iter()
        .map(|d| {
            let was = before.read(d);
            WordRow {
                device: d.clone(),
                before: was,
                expected: expect.after.get(d).copied().unwrap_or(was),
                actual: outcome.writes.get(d).copied().unwrap_or(was),
            }
        })
        .collect()
}

/// Judges a case from its observations (one per fill, in [`Fill::ALL`] order).
pub fn judge(case: &Case, observations: &[Observation]) -> Verdict {
    let mut mismatches = Vec::new();
    let mut outcomes = Vec::new();
    for obs in observations {
        let outcome = match &obs.result {
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
            Ok(Response::Done(outcome)) => outcome,
        };
        let image = Image::new(case.before.clone(), obs.fill);
        outcomes.push(changes(&image, outcome));
        if let Some(expect) = &case.expect {
            let rows = rows(&image, expect, outcome);
            let m = Mismatch {
                fill: obs.fill,
                rows,
                expected_error: expect.error.clone(),
                actual_error: outcome.error.clone(),
            };
            if m.words_differ() || m.error_differs() {
                mismatches.push(m);
            }
        }
    }
    if case.basis == Basis::Unspecified {
        let observed = outcomes
            .first()
            .map(|(w, e)| describe(w, e.as_ref()))
            .unwrap_or_default();
        let fill_dependent = outcomes.windows(2).any(|p| p[0] != p[1]);
        return Verdict::Recorded {
            observed,
            fill_dependent,
        };
    }
    if mismatches.is_empty() {
        Verdict::Conforms
    } else {
        Verdict::Differs { mismatches }
    }
}

/// The words an outcome changed (written with a new value) and its error.
fn changes(before: &Image, outcome: &Outcome) -> (BTreeMap<Device, u16>, Option<ErrorSignal>) {
    let changed = outcome
        .writes
        .iter()
        .filter(|(d, v)| before.read(d) != **v)
        .map(|(d, v)| (d.clone(), *v))
        .collect();
    (changed, outcome.error.clone())
}

/// One line for an outcome: `error 3401H, no change` or `D200=0005H`.
pub fn describe(changed: &BTreeMap<Device, u16>, error: Option<&ErrorSignal>) -> String {
    let words = if changed.is_empty() {
        "no change".to_string()
    } else {
        changed
            .iter()
            .map(|(d, v)| format!("{d}={}", crate::value::hex_word(*v)))
            .collect::<Vec<_>>()
            .join(" ")
    };
    match error {
        Some(e) => format!("error {e}, {words}"),
        None => words,
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;
    use std::sync::Arc;

    use super::*;
    use crate::model::{Citation, Location};

    fn d(i: u32) -> Device {
        Device::new("D", i)
    }

    fn case(basis: Basis, expect: Option<Expectation>) -> Case {
        Case {
            id: "c".into(),
            basis,
            citation: Citation {
                manual: "m".into(),
                page: "1".into(),
                text: None,
            },
            location: Location {
                file: PathBuf::from("f.yaml"),
                line: 1,
            },
            instructions: Arc::from(vec!["HABIN".to_string()]),
            profiles: Arc::from(vec!["p".to_string()]),
            variants: None,
            flags: BTreeMap::new(),
            operands: BTreeMap::new(),
            before: BTreeMap::from([(d(100), 0x4135)]),
            expect,
            note: None,
        }
    }

    fn done(writes: &[(u32, u16)], error: Option<ErrorSignal>) -> Vec<Observation> {
        Fill::ALL
            .iter()
            .map(|&fill| Observation {
                fill,
                result: Ok(Response::Done(Outcome {
                    writes: writes.iter().map(|(i, v)| (d(*i), *v)).collect(),
                    error: error.clone(),
                })),
            })
            .collect()
    }

    fn expect(after: &[(u32, u16)], error: Option<ErrorSignal>) -> Option<Expectation> {
        Some(Expectation {
            after: after.iter().map(|(i, v)| (d(*i), *v)).collect(),
            error,
        })
    }

    #[test]
    fn the_expected_change_conforms() {
        let c = case(Basis::Manual, expect(&[(200, 0x5A8D)], None));
        assert_eq!(judge(&c, &done(&[(200, 0x5A8D)], None)), Verdict::Conforms);
    }

    #[test]
    fn a_stray_write_differs() {
        let c = case(Basis::Manual, expect(&[(200, 0x5A8D)], None));
        let v = judge(&c, &done(&[(200, 0x5A8D), (201, 0)], None));
        assert!(v.is_failure(), "{v:?}");
    }

    #[test]
    fn rewriting_a_word_with_its_value_is_no_change() {
        let c = case(Basis::Manual, expect(&[], None));
        assert_eq!(judge(&c, &done(&[(100, 0x4135)], None)), Verdict::Conforms);
    }

    #[test]
    fn a_missing_change_differs() {
        let c = case(Basis::Manual, expect(&[(200, 0x5A8D)], None));
        assert!(judge(&c, &done(&[], None)).is_failure());
    }

    #[test]
    fn a_code_never_satisfies_a_flag() {
        let flag = ErrorSignal::Flag(Device::new("M", 8004));
        let c = case(Basis::Manual, expect(&[], Some(flag)));
        assert!(judge(&c, &done(&[], Some(ErrorSignal::Code(0x3401)))).is_failure());
        assert!(judge(&c, &done(&[], None)).is_failure());
    }

    #[test]
    fn faults_and_unsupported_fail() {
        let c = case(Basis::Manual, expect(&[], None));
        let fault = vec![Observation {
            fill: Fill::A,
            result: Err(Fault::Timeout("5 s".into())),
        }];
        assert_eq!(judge(&c, &fault).label(), "timeout");
        assert!(judge(&c, &fault).is_failure());
        let unsupported = vec![Observation {
            fill: Fill::A,
            result: Ok(Response::Unsupported("no".into())),
        }];
        assert!(judge(&c, &unsupported).is_failure());
    }

    #[test]
    fn unspecified_records_and_notes_fill_dependence() {
        let c = case(Basis::Unspecified, None);
        let mut obs = done(&[(200, 1)], None);
        assert_eq!(
            judge(&c, &obs),
            Verdict::Recorded {
                observed: "D200=0001H".into(),
                fill_dependent: false
            }
        );
        obs[1].result = Ok(Response::Done(Outcome::default()));
        assert!(matches!(
            judge(&c, &obs),
            Verdict::Recorded {
                fill_dependent: true,
                ..
            }
        ));
    }
}
