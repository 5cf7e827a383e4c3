//! Running a neutral case through a profile's lowering and lifting the outcome back.

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;

use super::{ErrorClass, Lowering, NeutralCase, NeutralOutcome, Operation, TextLayout};
use crate::backend::{Backend, Fault, Outcome, Request, Response};
use crate::device::Device;
use crate::memory::{Fill, Image};
use crate::model::{Basis, ErrorSignal, Operand};
use crate::profile::Profile;
use crate::value::{parse_number, parse_word};

/// A neutral case on one backend through one lowering.
#[derive(Clone)]
pub struct NeutralTrial {
    pub backend: Arc<dyn Backend>,
    pub profile: Arc<Profile>,
    pub lowering: Lowering,
    pub case: Arc<NeutralCase>,
    /// Why the trial is not run, when the backend does not claim the lowering's instruction.
    pub skip: Option<String>,
}

/// The verdict of a neutral trial.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
pub enum NeutralVerdict {
    Matches {
        outcome: NeutralOutcome,
    },
    Differs {
        expected: NeutralOutcome,
        actual: NeutralOutcome,
    },
    /// The outcome depends on memory the lowering does not set: the lowering or the backend
    /// reads past what the case gives.
    FillDependent {
        fill_a: NeutralOutcome,
        fill_b: NeutralOutcome,
    },
    Unsupported {
        reason: String,
    },
    Fault {
        fault: Fault,
    },
    /// No expectation (or `basis: unspecified`): what the backend answered.
    Recorded {
        outcome: NeutralOutcome,
    },
    /// A difference the backend's known-differences file lists.
    KnownDifference {
        reason: String,
        entry: String,
        difference: Box<NeutralVerdict>,
    },
    /// A listed known difference that now matches: the list is out of date.
    StaleEntry {
        reason: String,
        entry: String,
    },
}

impl NeutralVerdict {
    pub fn is_failure(&self) -> bool {
        !matches!(
            self,
            NeutralVerdict::Matches { .. } | NeutralVerdict::Recorded { .. }
        )
    }

    /// What the backend answered, when it answered.
    pub fn outcome(&self) -> Option<&NeutralOutcome> {
        match self {
            NeutralVerdict::Matches { outcome } | NeutralVerdict::Recorded { outcome } => {
                Some(outcome)
            }
            NeutralVerdict::Differs { actual, .. } => Some(actual),
            NeutralVerdict::KnownDifference { difference, .. } => difference.outcome(),
            _ => None,
        }
    }

    /// One line for a report.
    pub fn describe(&self) -> String {
        match self {
            NeutralVerdict::Matches { outcome } => format!("{outcome} as expected"),
            NeutralVerdict::Differs { expected, actual } => {
                format!("expected {expected}, actual {actual}")
            }
            NeutralVerdict::FillDependent { fill_a, fill_b } => {
                format!("depends on memory the case does not set: {fill_a} under fill A, {fill_b} under fill B")
            }
            NeutralVerdict::Unsupported { reason } => format!("unsupported: {reason}"),
            NeutralVerdict::Fault { fault } => fault.to_string(),
            NeutralVerdict::Recorded { outcome } => format!("recorded: {outcome}"),
            NeutralVerdict::KnownDifference {
                reason,
                entry,
                difference,
            } => format!(
                "known difference ({entry}): {}; {}",
                reason.trim_end_matches('.'),
                difference.describe()
            ),
            NeutralVerdict::StaleEntry { reason, entry } => format!(
                "stale entry ({entry}): listed as a known difference ({reason}) but answers as expected"
            ),
        }
    }
}

impl NeutralTrial {
    /// `<profile short>/<lowering>`: how neutral cases name this lowering.
    pub fn lowering_key(&self) -> String {
        lowering_key(&self.profile, &self.lowering)
    }

    pub fn variant(&self) -> &str {
        variant_of(&self.profile, &self.lowering)
    }

    /// `cross-vendor::backend::lowering::case-id::variant`, like native trial names.
    pub fn name(&self) -> String {
        format!(
            "cross-vendor::{}::{}::{}::{}",
            self.backend.name(),
            self.lowering.name,
            self.case.id,
            self.variant()
        )
    }

    pub fn run(&self) -> NeutralVerdict {
        let mut outcomes = Vec::new();
        for fill in Fill::ALL {
            match self.run_once(fill) {
                Ok(o) => outcomes.push(o),
                Err(v) => return v,
            }
        }
        if let [a, b] = outcomes.as_slice() {
            if a != b {
                return NeutralVerdict::FillDependent {
                    fill_a: a.clone(),
                    fill_b: b.clone(),
                };
            }
        }
        let Some(actual) = outcomes.into_iter().next() else {
            return NeutralVerdict::Unsupported {
                reason: "no fill ran".into(),
            };
        };
        match self.case.expected_for(&self.lowering_key()) {
            Some(expected) if self.case.basis != Basis::Unspecified => {
                if *expected == actual {
                    NeutralVerdict::Matches { outcome: actual }
                } else {
                    NeutralVerdict::Differs {
                        expected: expected.clone(),
                        actual,
                    }
                }
            }
            _ => NeutralVerdict::Recorded { outcome: actual },
        }
    }

    fn run_once(&self, fill: Fill) -> Result<NeutralOutcome, NeutralVerdict> {
        let l = &self.lowering;
        let unsupported = |reason: String| NeutralVerdict::Unsupported { reason };
        let variant = self
            .profile
            .variant(self.variant())
            .ok_or_else(|| unsupported(format!("no variant {}", self.variant())))?;
        let mut operands: BTreeMap<String, Operand> = BTreeMap::new();
        for (name, text) in &l.operands {
            operands.insert(name.clone(), parse_operand(text).map_err(unsupported)?);
        }
        if let Some(count) = &l.count {
            operands.insert(
                count.clone(),
                Operand::Constant(i64::from(self.case.digits)),
            );
        }
        let device = |name: &str| match operands.get(name) {
            Some(Operand::Device(d)) => Ok(d.clone()),
            _ => Err(unsupported(format!(
                "lowering operand `{name}` is not a device"
            ))),
        };
        let source = device(&l.source)?;
        let destination = device(&l.destination)?;
        let words: Vec<u16> = match l.operation {
            Operation::HexToValue => {
                let mut chars = self.case.text.clone();
                chars.push(0);
                layout_words(l.text, &chars)
            }
            Operation::ValueToHex => {
                // As many words as the value needs or the digits read, the upper ones zero, so
                // that an instruction reading past the value reads zeros, not the fill.
                let v = self.case.value;
                let digits = l.width.unwrap_or(self.case.digits);
                let needed = if v > 0xFFFF { 2 } else { 1 };
                let count = digits.div_ceil(4).clamp(needed, 4);
                (0..count).map(|i| (v >> (16 * i)) as u16).collect()
            }
        };
        let before: BTreeMap<Device, u16> = words
            .into_iter()
            .enumerate()
            .filter_map(|(i, w)| source.offset(i as u32).map(|d| (d, w)))
            .collect();
        let memory = Image::new(before, fill);
        let request = Request {
            profile: &self.profile,
            variant,
            instruction: &l.instruction,
            case_id: &self.case.id,
            flags: &l.flags,
            operands: &operands,
            memory: &memory,
        };
        let outcome = match self.backend.execute(&request) {
            Err(fault) => return Err(NeutralVerdict::Fault { fault }),
            Ok(Response::Unsupported(reason)) => return Err(unsupported(reason)),
            Ok(Response::Done(outcome)) => outcome,
        };
        Ok(self.lift(&outcome, &memory, &destination))
    }

    fn lift(&self, outcome: &Outcome, memory: &Image, destination: &Device) -> NeutralOutcome {
        if let Some(signal) = &outcome.error {
            return classify(&self.profile, signal);
        }
        let read = |d: &Device| {
            outcome
                .writes
                .get(d)
                .copied()
                .unwrap_or_else(|| memory.read(d))
        };
        let digits = self.lowering.width.unwrap_or(self.case.digits);
        match self.lowering.operation {
            Operation::HexToValue => {
                let words = digits.div_ceil(4).clamp(1, 4);
                let value = (0..words)
                    .filter_map(|i| destination.offset(i))
                    .enumerate()
                    .fold(0u64, |acc, (i, d)| acc | u64::from(read(&d)) << (16 * i));
                NeutralOutcome::Value(value)
            }
            Operation::ValueToHex => {
                let mut text = Vec::new();
                for k in 0..digits {
                    let ch = match self.lowering.text {
                        TextLayout::Packed => destination.offset(k / 2).map(|d| {
                            let w = read(&d);
                            if k % 2 == 0 {
                                w as u8
                            } else {
                                (w >> 8) as u8
                            }
                        }),
                        TextLayout::Words => destination.offset(k).map(|d| read(&d) as u8),
                    };
                    match ch {
                        Some(0) | None => break,
                        Some(c) => text.push(c),
                    }
                }
                NeutralOutcome::Text(text)
            }
        }
    }
}

/// `<profile short>/<lowering>`.
pub fn lowering_key(profile: &Profile, lowering: &Lowering) -> String {
    format!("{}/{}", profile.short, lowering.name)
}

/// The variant a lowering runs on.
pub fn variant_of<'a>(profile: &'a Profile, lowering: &'a Lowering) -> &'a str {
    lowering
        .variant
        .as_deref()
        .or_else(|| profile.variants.first().map(|v| v.id.as_str()))
        .unwrap_or("")
}

/// Reads a lowering's operand: a device or a constant.
pub fn parse_operand(text: &str) -> Result<Operand, String> {
    if let Ok(k) = parse_number(text) {
        return Ok(Operand::Constant(k));
    }
    text.parse::<Device>()
        .map(Operand::Device)
        .map_err(|e| e.to_string())
}

fn layout_words(layout: TextLayout, chars: &[u8]) -> Vec<u16> {
    match layout {
        TextLayout::Packed => crate::backend::text::pack_low_first(chars),
        TextLayout::Words => chars.iter().map(|c| u16::from(*c)).collect(),
    }
}

/// A vendor's error signal as a neutral class, by the profile's table.
pub fn classify(profile: &Profile, signal: &ErrorSignal) -> NeutralOutcome {
    let table = profile.neutral.as_ref().map(|n| &n.errors);
    let class: Option<&ErrorClass> = table.and_then(|t| {
        t.iter()
            .find(|(key, _)| match signal {
                ErrorSignal::Code(c) => parse_word(key) == Ok(*c),
                ErrorSignal::Flag(d) => **key == d.to_string(),
            })
            .map(|(_, class)| class)
    });
    match class {
        Some(c) => NeutralOutcome::Error(c.clone()),
        None => NeutralOutcome::OtherError(signal.to_string()),
    }
}

/// Every neutral trial: each case on each backend whose profile lowers its operation.
pub fn plan_neutral(
    cases: &[Arc<NeutralCase>],
    profiles: &crate::profile::Profiles,
    backends: &[Arc<dyn Backend>],
) -> Vec<NeutralTrial> {
    let mut trials = Vec::new();
    for backend in backends {
        let Some(profile) = profiles.get(backend.profile()) else {
            continue;
        };
        let Some(section) = &profile.neutral else {
            continue;
        };
        for case in cases {
            for lowering in section
                .lowerings
                .iter()
                .filter(|l| l.operation == case.operation)
            {
                let variant = variant_of(profile, lowering);
                let skip = if !backend.claims(&lowering.instruction, variant) {
                    Some(format!(
                        "{} does not implement {} on {variant}",
                        backend.name(),
                        lowering.instruction
                    ))
                } else {
                    profile
                        .variant(variant)
                        .and_then(|v| backend.declines(&lowering.flags, &lowering.instruction, v))
                };
                trials.push(NeutralTrial {
                    backend: backend.clone(),
                    profile: profile.clone(),
                    lowering: lowering.clone(),
                    case: case.clone(),
                    skip,
                });
            }
        }
    }
    trials
}
