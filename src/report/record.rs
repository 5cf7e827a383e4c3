//! One trial's result as every report shows it: a [`Record`] is a cell of the matrix, a test
//! case of JUnit, an entry of the JSON report and of a saved baseline.
//!
//! A record keeps the verdict's [`Status`] and a structured [`Behaviour`] — what rows are
//! grouped by and what a baseline compares — beside the texts shown to people, so rewording a
//! message changes no grouping and churns no baseline.

use std::fmt;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::text::{render, Palette};
use crate::judge::{Difference, Observed, Status, Verdict};
use crate::model::cross_vendor::{Answer, ErrorClass};
use crate::model::{error_text, Basis, ErrorSignal};
use crate::plan::{Check, Trial};

/// One cell of the matrix.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct Record {
    /// A profile id for native cases, `cross-vendor <operation>` for cross-vendor ones.
    pub section: String,
    /// The case (native: `instruction::case-id::variant`).
    pub row: String,
    /// The backend (cross-vendor: `backend/lowering`).
    pub column: String,
    /// The trial name, as `cargo test` shows it.
    pub trial: String,
    pub file: String,
    pub line: usize,
    pub basis: Basis,
    pub status: Status,
    /// The verdict's label (`conforms`, `differs`, `timeout`, ...).
    pub label: String,
    /// What rows are grouped by: cells with the same behaviour in every column group together.
    pub behaviour: Behaviour,
    /// What the cell shows.
    pub shown: String,
    /// The full explanation of a cell that did not conform (a diff, a fault, a reason).
    pub detail: String,
    /// How long the trial took, in seconds: its batch's time shared equally among the batch's
    /// trials (0 for a trial that did not run).
    #[serde(default, with = "seconds")]
    pub seconds: Duration,
    /// The verdict itself, for tools (words in hex). Not read back from a saved run: a
    /// baseline compares statuses and behaviours.
    #[serde(default, skip_deserializing, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<Verdict>,
}

/// A verdict as a behaviour to compare and group by.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "behaviour")]
pub(crate) enum Behaviour {
    Conforms,
    /// Native: other words than expected (the error as expected).
    WrongWords,
    /// Native: another error signal than expected.
    WrongError {
        expected: Option<ErrorSignal>,
        actual: Option<ErrorSignal>,
    },
    /// Native: the words and the code as expected, but an error register (SD0, SD8067) that
    /// does not hold the code.
    WrongRegister {
        registers: Vec<String>,
    },
    /// Cross-vendor: what kind of answer the lowering gave.
    Answer {
        class: AnswerClass,
    },
    /// Cross-vendor: an answer that depends on the fill.
    FillDependent,
    Recorded {
        observed: Observed,
    },
    Unsupported,
    Fault {
        kind: String,
    },
    Skipped,
    StaleEntry,
    Known {
        difference: Box<Behaviour>,
    },
}

/// The kind of a cross-vendor answer, relative to the case's plain reading.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "class", content = "value")]
pub(crate) enum AnswerClass {
    /// The plain reading every vendor gives unless the case lists it as an exception.
    Plain,
    OtherValue,
    OtherText,
    Error(ErrorClass),
    OtherError(String),
}

impl fmt::Display for Behaviour {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Behaviour::Conforms => f.write_str("conforms"),
            Behaviour::WrongWords => f.write_str("differs: wrong words"),
            Behaviour::WrongError { expected, actual } => write!(
                f,
                "differs: error {} instead of {}",
                error_text(actual.as_ref()),
                error_text(expected.as_ref())
            ),
            Behaviour::WrongRegister { registers } => write!(
                f,
                "differs: {} not holding the error code",
                registers.join(", ")
            ),
            Behaviour::Answer { class } => write!(f, "{class}"),
            Behaviour::FillDependent => f.write_str("fill-dependent"),
            Behaviour::Recorded { observed } => write!(f, "recorded: {observed}"),
            Behaviour::Unsupported => f.write_str("unsupported"),
            Behaviour::Fault { kind } => f.write_str(kind),
            Behaviour::Skipped => f.write_str("skipped"),
            Behaviour::StaleEntry => f.write_str("stale-entry"),
            Behaviour::Known { difference } => write!(f, "known: {difference}"),
        }
    }
}

impl fmt::Display for AnswerClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AnswerClass::Plain => f.write_str("plain answer"),
            AnswerClass::OtherValue => f.write_str("other value"),
            AnswerClass::OtherText => f.write_str("other text"),
            AnswerClass::Error(c) => write!(f, "{c}"),
            AnswerClass::OtherError(e) => write!(f, "error {e}"),
        }
    }
}

/// A duration as seconds, a number.
mod seconds {
    use std::time::Duration;

    use serde::{Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64((d.as_secs_f64() * 1e6).round() / 1e6)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
        let s = f64::deserialize(d)?;
        Ok(Duration::try_from_secs_f64(s).unwrap_or_default())
    }
}

impl Record {
    /// The record of a trial and its verdict.
    pub(crate) fn of(trial: &Trial, verdict: &Verdict) -> Record {
        let (section, row, column) = match &trial.check {
            Check::Native { instruction, case } => (
                trial
                    .profile
                    .as_ref()
                    .map_or_else(String::new, |p| p.id.clone()),
                format!(
                    "{}::{}::{}",
                    instruction.to_lowercase(),
                    case.id,
                    trial.variant
                ),
                trial.backend.name().to_string(),
            ),
            Check::CrossVendor { lowering, case } => (
                format!("cross-vendor {}", case.operation),
                case.id.clone(),
                format!("{}/{}", trial.backend.name(), lowering.name),
            ),
            Check::Codec { case } => match &case.protocol {
                Some(from) => (
                    format!("protocol {} {}", from.protocol, case.operation),
                    case.id.clone(),
                    format!("{}/{}", trial.backend.name(), from.field),
                ),
                None => (
                    format!("cross-vendor {}", case.operation),
                    case.id.clone(),
                    format!("{}/codec", trial.backend.name()),
                ),
            },
        };
        let shown = match (cross_vendor_answer(trial, verdict), verdict) {
            (Some(a), _) => a.to_string(),
            (None, Verdict::Conforms) => "ok".to_string(),
            (None, v) => behaviour(trial, v).short(v),
        };
        let detail = match verdict {
            Verdict::Conforms => String::new(),
            v => match v.not_run() {
                Some(reason) => reason.to_string(),
                None => render(trial, v, Palette::plain()),
            },
        };
        Record {
            section,
            row,
            column,
            trial: trial.name(),
            file: trial.location().file.display().to_string(),
            line: trial.location().line,
            basis: trial.basis(),
            status: verdict.status(),
            label: verdict.label().to_string(),
            behaviour: behaviour(trial, verdict),
            shown,
            detail,
            seconds: Duration::ZERO,
            verdict: Some(verdict.clone()),
        }
    }
}

impl Behaviour {
    /// What a native cell shows for a verdict that is not a plain pass.
    fn short(&self, verdict: &Verdict) -> String {
        match self {
            Behaviour::WrongWords => "wrong words".to_string(),
            Behaviour::WrongRegister { registers } => {
                format!("{} not the code", registers.join(", "))
            }
            Behaviour::WrongError { expected, actual } => format!(
                "error {} instead of {}",
                error_text(actual.as_ref()),
                error_text(expected.as_ref())
            ),
            Behaviour::Recorded { observed } => observed.to_string(),
            Behaviour::Known { difference } => match verdict {
                Verdict::KnownDifference {
                    difference: inner, ..
                } => difference.short(inner),
                _ => verdict.label().to_string(),
            },
            _ => verdict.label().to_string(),
        }
    }
}

/// The answer a cross-vendor verdict carries, when the backend answered.
fn answer_of(verdict: &Verdict) -> Option<&Answer> {
    match verdict {
        Verdict::Differs {
            difference: Difference::Answer { actual, .. },
        } => Some(actual),
        Verdict::Recorded {
            observed: Observed::Answer(a),
            ..
        } => Some(a),
        Verdict::KnownDifference { difference, .. } => answer_of(difference),
        _ => None,
    }
}

/// What a cross-vendor trial answered: the answer a verdict carries, or for a trial that
/// conforms, the answer it was expected to give.
fn cross_vendor_answer<'a>(trial: &'a Trial, verdict: &'a Verdict) -> Option<&'a Answer> {
    let case = trial.cross_vendor_case()?;
    match (verdict, &trial.check) {
        (Verdict::Conforms, Check::CrossVendor { lowering, .. }) => {
            case.expected_for(&lowering.key)
        }
        (Verdict::Conforms, _) => case.expect.as_ref(),
        (v, _) => answer_of(v),
    }
}

fn behaviour(trial: &Trial, verdict: &Verdict) -> Behaviour {
    if let Some(case) = trial.cross_vendor_case() {
        if let Some(a) = cross_vendor_answer(trial, verdict) {
            let class = match a {
                Answer::Error(c) | Answer::ErrorAndValue(c, _) => AnswerClass::Error(c.clone()),
                Answer::OtherError(e) => AnswerClass::OtherError(e.clone()),
                a if Some(a) == case.expect.as_ref() => AnswerClass::Plain,
                Answer::Value(_) => AnswerClass::OtherValue,
                Answer::Text(_) => AnswerClass::OtherText,
                Answer::Accepted => AnswerClass::OtherValue,
            };
            return Behaviour::Answer { class };
        }
    }
    match verdict {
        Verdict::Conforms => Behaviour::Conforms,
        Verdict::Differs { difference } => match difference {
            Difference::Words { mismatches } => match mismatches.first() {
                Some(m) if m.error_differs() => Behaviour::WrongError {
                    expected: m.expected_error.clone(),
                    actual: m.actual_error.clone(),
                },
                Some(m) if m.only_registers_differ() => Behaviour::WrongRegister {
                    registers: m.wrong_registers().map(|r| r.device.to_string()).collect(),
                },
                _ => Behaviour::WrongWords,
            },
            Difference::Answer { .. } => Behaviour::WrongWords,
            Difference::FillDependent { .. } => Behaviour::FillDependent,
        },
        Verdict::Unsupported { .. } => Behaviour::Unsupported,
        Verdict::Fault { fault, .. } => Behaviour::Fault {
            kind: fault.kind().to_string(),
        },
        Verdict::Recorded { observed, .. } => Behaviour::Recorded {
            observed: observed.clone(),
        },
        Verdict::Skipped { .. } | Verdict::Cancelled => Behaviour::Skipped,
        Verdict::StaleEntry { .. } => Behaviour::StaleEntry,
        Verdict::KnownDifference { difference, .. } => Behaviour::Known {
            difference: Box::new(behaviour(trial, difference)),
        },
    }
}
