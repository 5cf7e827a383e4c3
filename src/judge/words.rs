//! Judging a native case: the words an outcome changed against the words the case expects.
//!
//! The comparison is semantic: a word counts as changed only if its value differs from before,
//! every change not in the expectation is a difference, and errors compare as signals (a code
//! never equals a flag).

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use crate::backend::Outcome;
use crate::device::Device;
use crate::memory::{Fill, Image};
use crate::model::{ErrorSignal, Expectation};
use crate::value::hex_word;

/// One word in a comparison: its value before, as expected after, and as found after.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct WordRow {
    pub device: Device,
    #[serde(serialize_with = "hex")]
    pub before: u16,
    #[serde(serialize_with = "hex")]
    pub expected: u16,
    #[serde(serialize_with = "hex")]
    pub actual: u16,
}

/// Words appear in reports as the manuals write them (`5A8DH`), not as decimal numbers.
fn hex<S: serde::Serializer>(word: &u16, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&hex_word(*word))
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

/// What an outcome did to memory: the words it changed (written with a new value) and its error.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Effect {
    pub changed: BTreeMap<Device, u16>,
    pub error: Option<ErrorSignal>,
}

impl Effect {
    pub fn of(before: &Image, outcome: &Outcome) -> Effect {
        Effect {
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
                .map(|(d, v)| format!("{d}={}", hex_word(*v)))
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

/// How an outcome under one fill differs from the expectation, if it does.
pub fn mismatch(
    before: &Image,
    expect: &Expectation,
    outcome: &Outcome,
    fill: Fill,
) -> Option<Mismatch> {
    let m = Mismatch {
        fill,
        rows: rows(before, expect, outcome),
        expected_error: expect.error.clone(),
        actual_error: outcome.error.clone(),
    };
    (m.words_differ() || m.error_differs()).then_some(m)
}
