//! Judging a native case: the units (words, or bytes in byte-addressed memory) an outcome
//! changed against the ones the case expects.
//!
//! The comparison is semantic: a unit counts as changed only if its value differs from before,
//! every change not in the expectation is a difference, and errors compare as signals (a code
//! never equals a flag).

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use crate::backend::Outcome;
use crate::device::Device;
use crate::memory::{Fill, Image, Unit, Value};
use crate::model::{ErrorSignal, Expectation};

/// One unit in a comparison: its value before, as expected after, and as found after.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WordRow {
    /// The device the unit is (`D200`).
    pub device: Device,
    /// Whether the device holds a byte or a word, which decides how its values are shown.
    pub unit: Unit,
    /// Its value before the instruction: the case's, or the fill's where the case sets none.
    pub before: Value,
    /// What the case expects it to hold after; its value before when no change is expected.
    pub expected: Value,
    /// What it holds after the backend ran; its value before when the backend wrote nothing.
    pub actual: Value,
}

/// Values appear in reports as the manuals write them (`5A8DH`, `5AH`), not as decimal numbers.
impl Serialize for WordRow {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut row = s.serialize_struct("WordRow", 5)?;
        row.serialize_field("device", &self.device)?;
        row.serialize_field("unit", &self.unit)?;
        row.serialize_field("before", &self.unit.hex(self.before))?;
        row.serialize_field("expected", &self.unit.hex(self.expected))?;
        row.serialize_field("actual", &self.unit.hex(self.actual))?;
        row.end()
    }
}

/// How one run (under one fill) differed from the expectation.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Mismatch {
    /// The fill (A or B) that the units the case does not set held during this run.
    pub fill: Fill,
    /// Every word the expectation or the backend touched, in device order.
    pub rows: Vec<WordRow>,
    /// The error the case expects; `None` for a success.
    pub expected_error: Option<ErrorSignal>,
    /// The error the backend signalled; `None` when it signalled none.
    pub actual_error: Option<ErrorSignal>,
    /// The error registers, when one of them does not hold the code (empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub registers: Vec<RegisterRow>,
}

impl Mismatch {
    /// Whether any unit holds another value than the case expects.
    pub fn words_differ(&self) -> bool {
        self.rows.iter().any(|r| r.expected != r.actual)
    }
    /// Whether the error signalled is not the one expected (an error against none counts).
    pub fn error_differs(&self) -> bool {
        self.expected_error != self.actual_error
    }
    /// Whether an error register does not hold the expected code.
    pub fn registers_differ(&self) -> bool {
        self.wrong_registers().next().is_some()
    }
    /// Whether the run differs in its error registers alone: the one rule by which every
    /// report and `record --known` call a trial "wrong register" rather than "wrong words".
    pub fn only_registers_differ(&self) -> bool {
        !self.words_differ() && self.registers_differ()
    }
    /// The error registers that do not hold the code.
    pub fn wrong_registers(&self) -> impl Iterator<Item = &RegisterRow> {
        self.registers.iter().filter(|r| r.differs())
    }
}

/// One register where the profile says the error code lands, against the code expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RegisterRow {
    /// The register (`SD0`).
    pub device: Device,
    /// The error code the case expects, which the register should hold.
    pub expected: Value,
    /// `None`: the backend reported other error registers but not this one.
    pub actual: Option<Value>,
}

impl RegisterRow {
    /// Whether the register does not hold the code, or was not reported.
    pub fn differs(&self) -> bool {
        self.actual != Some(self.expected)
    }
}

impl Serialize for RegisterRow {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut row = s.serialize_struct("RegisterRow", 3)?;
        row.serialize_field("device", &self.device)?;
        row.serialize_field("expected", &Unit::Word.hex(self.expected))?;
        row.serialize_field("actual", &self.actual.map(|a| Unit::Word.hex(a)))?;
        row.end()
    }
}

/// The error registers against the code the case expects. Only a backend that reports error
/// registers is held to them (one that models none is judged on the code alone), and only
/// after an expected error with a code: after a success the manuals say nothing of them.
pub(crate) fn register_rows(
    expect: &Expectation,
    outcome: &Outcome,
    registers: &[Device],
) -> Vec<RegisterRow> {
    let Some(ErrorSignal::Code(code)) = &expect.error else {
        return Vec::new();
    };
    if outcome.registers.is_empty() {
        return Vec::new();
    }
    let rows: Vec<RegisterRow> = registers
        .iter()
        .map(|d| RegisterRow {
            device: d.clone(),
            expected: Value::from(*code),
            actual: outcome.registers.get(d).copied(),
        })
        .collect();
    if rows.iter().any(RegisterRow::differs) {
        rows
    } else {
        Vec::new()
    }
}

/// What an outcome did to memory: the units it changed (written with a new value) and its error.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Effect {
    /// The units written with a new value, with that value.
    pub changed: BTreeMap<Device, Value>,
    /// The error signalled; `None` for a success.
    pub error: Option<ErrorSignal>,
    /// What the changed devices hold (absent in baselines of word-addressed families).
    #[serde(default, skip_serializing_if = "is_word")]
    pub unit: Unit,
}

fn is_word(unit: &Unit) -> bool {
    *unit == Unit::Word
}

impl Effect {
    /// No change and no error.
    pub fn none(unit: Unit) -> Effect {
        Effect {
            changed: BTreeMap::new(),
            error: None,
            unit,
        }
    }

    /// What `outcome` did to `before`: a write of a unit's old value is no change.
    pub fn of(before: &Image, outcome: &Outcome) -> Effect {
        Effect {
            unit: before.unit(),
            changed: outcome
                .writes
                .iter()
                .filter(|(d, v)| before.read(d) != **v)
                .map(|(d, v)| (d.clone(), *v))
                .collect(),
            error: outcome.error.clone(),
        }
    }
}

impl std::fmt::Display for Effect {
    /// One line: `error 3401H, no change` or `D200=0005H`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let words = if self.changed.is_empty() {
            "no change".to_string()
        } else {
            self.changed
                .iter()
                .map(|(d, v)| format!("{d}={}", self.unit.hex(*v)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        match &self.error {
            Some(e) => write!(f, "error {e}, {words}"),
            None => f.write_str(&words),
        }
    }
}

/// The rows of a comparison between an expectation and an outcome over the same image.
pub(crate) fn rows(before: &Image, expect: &Expectation, outcome: &Outcome) -> Vec<WordRow> {
    let devices: BTreeSet<&Device> = expect.after.keys().chain(outcome.writes.keys()).collect();
    devices
        .into_iter()
        .map(|d| {
            let was = before.read(d);
            WordRow {
                device: d.clone(),
                unit: before.unit(),
                before: was,
                expected: expect.after.get(d).copied().unwrap_or(was),
                actual: outcome.writes.get(d).copied().unwrap_or(was),
            }
        })
        .collect()
}

/// How an outcome under one fill differs from the expectation, if it does; `registers` are
/// where the profile says an error code lands.
pub(crate) fn mismatch(
    before: &Image,
    expect: &Expectation,
    outcome: &Outcome,
    fill: Fill,
    registers: &[Device],
) -> Option<Mismatch> {
    let m = Mismatch {
        fill,
        rows: rows(before, expect, outcome),
        expected_error: expect.error.clone(),
        actual_error: outcome.error.clone(),
        registers: register_rows(expect, outcome, registers),
    };
    (m.words_differ() || m.error_differs() || m.registers_differ()).then_some(m)
}
