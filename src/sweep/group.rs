//! Grouping: every input's answers, one per column, reduced to a behaviour signature (which
//! column answered which class of answer), and inputs with the same signature and features
//! counted together.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};

use serde::Serialize;

use super::input::Point;
use super::target::Column;
use crate::judge::{Effect, Observed, Verdict};
use crate::model::cross_vendor::Answer;

/// What one column did with one input, as the judge recorded it.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Reply {
    /// A cross-vendor answer.
    Answer {
        answer: Answer,
        fill_dependent: bool,
    },
    /// What an instruction did to memory.
    Memory {
        effect: Effect,
        fill_dependent: bool,
    },
    /// Not run: the backend does not implement this.
    Skipped { reason: String },
    /// No usable answer: a fault, or `unsupported` from a backend that claimed the input.
    Failed { label: String, detail: String },
}

impl Reply {
    pub fn of(verdict: &Verdict) -> Reply {
        match verdict {
            Verdict::Recorded {
                observed: Observed::Answer(answer),
                fill_dependent,
            } => Reply::Answer {
                answer: answer.clone(),
                fill_dependent: *fill_dependent,
            },
            Verdict::Recorded {
                observed: Observed::Memory(effect),
                fill_dependent,
            } => Reply::Memory {
                effect: effect.clone(),
                fill_dependent: *fill_dependent,
            },
            v @ (Verdict::Skipped { .. } | Verdict::Cancelled) => Reply::Skipped {
                reason: v.not_run().unwrap_or_default().to_string(),
            },
            Verdict::Fault { fault, .. } => Reply::failed(fault),
            Verdict::Unsupported { reason } => Reply::Failed {
                label: "unsupported".into(),
                detail: reason.clone(),
            },
            other => Reply::Failed {
                label: other.label().to_string(),
                detail: format!("{other:?}"),
            },
        }
    }

    /// No usable answer, for this fault.
    pub(crate) fn failed(fault: &crate::backend::Fault) -> Reply {
        Reply::Failed {
            label: fault.kind().to_string(),
            detail: fault.to_string(),
        }
    }

    pub fn is_skipped(&self) -> bool {
        matches!(self, Reply::Skipped { .. })
    }

    pub fn fill_dependent(&self) -> bool {
        matches!(
            self,
            Reply::Answer {
                fill_dependent: true,
                ..
            } | Reply::Memory {
                fill_dependent: true,
                ..
            }
        )
    }

    /// The class of the answer, before numbering equal values: `value`, `text`, an error
    /// class or signal, `writes`, `no change`, `skipped`, a fault kind. (Borrowed where it can
    /// be: grouping asks this of every reply of every input.)
    fn class(&self) -> (Cow<'_, str>, bool) {
        match self {
            Reply::Answer { answer, .. } => match answer {
                Answer::Value(_) => (Cow::Borrowed("value"), true),
                Answer::Text(_) => (Cow::Borrowed("text"), true),
                Answer::Error(c) => (Cow::Owned(c.to_string()), false),
                Answer::ErrorAndValue(c, _) => (Cow::Owned(format!("{c} and value")), true),
                Answer::OtherError(e) => (Cow::Owned(format!("error {e}")), false),
                Answer::Accepted => (Cow::Borrowed("accepted"), true),
            },
            Reply::Memory { effect, .. } => match (&effect.error, effect.changed.is_empty()) {
                (Some(e), true) => (Cow::Owned(format!("error {e}")), false),
                (Some(e), false) => (Cow::Owned(format!("error {e} and writes")), true),
                (None, true) => (Cow::Borrowed("no change"), false),
                (None, false) => (Cow::Borrowed("writes"), true),
            },
            Reply::Skipped { .. } => (Cow::Borrowed("skipped"), false),
            Reply::Failed { label, .. } => (Cow::Borrowed(label.as_str()), false),
        }
    }
}

impl std::fmt::Display for Reply {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reply::Answer { answer, .. } => write!(f, "{answer}")?,
            Reply::Memory { effect, .. } => write!(f, "{effect}")?,
            Reply::Skipped { .. } => f.write_str("skipped")?,
            Reply::Failed { label, .. } => f.write_str(label)?,
        }
        if self.fill_dependent() {
            f.write_str(" (fill-dependent)")?;
        }
        Ok(())
    }
}

/// The behaviour signature of one input: per column, the class of its answer, with equal
/// values numbered alike across columns (`value#1` twice means the same value).
pub fn labels(replies: &[Reply]) -> Vec<String> {
    labels_read(&[], 0, replies)
}

/// [`labels`], a codec's answer numbered as the answer its field gives for (see
/// [`reads_alike`]): `"7F"` from a field without leading zeros is the `"007F"` of a 4-digit
/// reading. `columns` may be empty (every reply read as it is).
pub(crate) fn labels_read(columns: &[Column], digits: u32, replies: &[Reply]) -> Vec<String> {
    let same = |i: usize, x: &Reply, y: &Reply| match (x, y) {
        (Reply::Answer { answer: a, .. }, Reply::Answer { answer: b, .. }) => {
            a == b || columns.get(i).is_some_and(|c| reads_alike(c, digits, x, y))
        }
        (Reply::Memory { effect: a, .. }, Reply::Memory { effect: b, .. }) => a == b,
        _ => false,
    };
    // Per class, the distinct numbered replies seen so far: a reply's number is its place there.
    let mut seen: Vec<(Cow<'_, str>, Vec<&Reply>)> = Vec::new();
    replies
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let (class, numbered) = r.class();
            let mut label = if numbered {
                let n = match seen.iter_mut().find(|(c, _)| *c == class) {
                    Some((_, distinct)) => match distinct.iter().position(|x| same(i, r, x)) {
                        Some(i) => i + 1,
                        None => {
                            distinct.push(r);
                            distinct.len()
                        }
                    },
                    None => {
                        seen.push((class.clone(), vec![r]));
                        1
                    }
                };
                format!("{class}#{n}")
            } else {
                class.into_owned()
            };
            if r.fill_dependent() {
                label.push_str(" (fill-dependent)");
            }
            label
        })
        .collect()
}

/// Whether `mine`, the reply of `column` to an input of `digits` digits, is `theirs` as the
/// column's field gives it: the same reply, or for a codec with a declared field shape, the
/// answer `theirs` written or read the field's way (`OperationAbilities::shaped`). A codec that
/// follows its shape then differs nowhere, in a sweep as in a run.
pub(crate) fn reads_alike(column: &Column, digits: u32, mine: &Reply, theirs: &Reply) -> bool {
    if mine == theirs {
        return true;
    }
    match (&column.field, mine, theirs) {
        (
            Some((operation, field)),
            Reply::Answer {
                answer: a,
                fill_dependent: x,
            },
            Reply::Answer {
                answer: b,
                fill_dependent: y,
            },
        ) => x == y && field.shaped(*operation, digits, b) == *a,
        _ => false,
    }
}

/// The columns that differ from their oracle on this input (neither side skipped).
pub(crate) fn differing(columns: &[Column], digits: u32, replies: &[Reply]) -> Vec<usize> {
    columns
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let o = c.oracle?;
            let (mine, theirs) = (&replies[i], &replies[o]);
            (!mine.is_skipped() && !theirs.is_skipped() && !reads_alike(c, digits, mine, theirs))
                .then_some(i)
        })
        .collect()
}

/// Whether the columns that ran do not all answer alike (a codec's answer read as its field
/// gives it).
pub(crate) fn disagree(columns: &[Column], digits: u32, replies: &[Reply]) -> bool {
    let mut ran = replies.iter().enumerate().filter(|(_, r)| !r.is_skipped());
    match ran.next() {
        Some((f, first)) => ran.any(|(i, r)| {
            let alike = match columns.get(i) {
                Some(c) => reads_alike(c, digits, r, first),
                None => r == first,
            } || columns
                .get(f)
                .is_some_and(|c| reads_alike(c, digits, first, r));
            !alike
        }),
        None => false,
    }
}

/// What inputs of one group share.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Key {
    /// Per column, the class of its answer.
    pub signature: Vec<String>,
    /// The inputs' features: the first character that is not a hex digit, the count against
    /// the data, flags on, operands moved.
    pub features: Vec<String>,
}

/// An input found while sweeping, with its answers.
#[derive(Debug, Clone, Serialize)]
pub struct Found {
    /// Its number in the generator's space.
    pub index: u64,
    pub point: Point,
    pub replies: Vec<Reply>,
}

/// A finer class of a group: one shape of input.
#[derive(Debug, Clone, Serialize)]
pub struct Class {
    pub name: String,
    pub inputs: u64,
    pub first: Found,
}

/// A judged column whose difference in a group an entry covers.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct KnownColumn {
    pub column: String,
    pub reason: String,
    /// `file:line` of the entry.
    pub location: String,
}

/// Inputs with the same behaviour and features.
#[derive(Debug, Clone, Serialize)]
pub struct Group {
    pub key: Key,
    pub inputs: u64,
    /// The columns that differ from their oracle (by name), on the first input.
    pub differing: Vec<String>,
    /// Judged columns whose difference here a known-differences entry covers (moved out of
    /// `differing` by `sweep::known::apply`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub known: Vec<KnownColumn>,
    /// Whether the columns do not all answer alike.
    pub disagree: bool,
    /// The first input found.
    pub representative: Found,
    /// Its classes, by name.
    #[serde(skip)]
    pub classes: BTreeMap<String, Class>,
}

impl Group {
    /// The classes, the most inputs first (ties in the order found).
    pub fn classes_by_size(&self) -> Vec<&Class> {
        let mut v: Vec<&Class> = self.classes.values().collect();
        v.sort_by(|a, b| {
            b.inputs
                .cmp(&a.inputs)
                .then(a.first.index.cmp(&b.first.index))
        });
        v
    }
}

/// Groups being counted.
#[derive(Debug, Default)]
pub struct Groups {
    pub by_key: HashMap<Key, Group>,
    /// Cap on classes kept per group (the rest are counted in the group only).
    pub max_classes: usize,
}

impl Groups {
    pub fn new(max_classes: usize) -> Self {
        Groups {
            by_key: HashMap::new(),
            max_classes,
        }
    }

    /// Counts one input, standing for `weight` inputs (more than 1 for the representative of
    /// a tuple of byte classes).
    pub fn add(
        &mut self,
        columns: &[Column],
        counted: bool,
        index: u64,
        point: &Point,
        replies: Vec<Reply>,
        weight: u64,
    ) {
        let key = Key {
            signature: labels_read(columns, point.digits, &replies),
            features: point.features(counted),
        };
        let class = point.class(counted);
        let max = self.max_classes;
        let found = |replies: &[Reply]| Found {
            index,
            point: point.clone(),
            replies: replies.to_vec(),
        };
        let names = |replies: &[Reply]| -> Vec<String> {
            differing(columns, point.digits, replies)
                .into_iter()
                .map(|i| columns[i].name.clone())
                .collect()
        };
        let group = match self.by_key.get_mut(&key) {
            Some(g) => g,
            None => self.by_key.entry(key.clone()).or_insert_with(|| Group {
                key,
                inputs: 0,
                differing: names(&replies),
                known: Vec::new(),
                disagree: disagree(columns, point.digits, &replies),
                representative: found(&replies),
                classes: BTreeMap::new(),
            }),
        };
        group.inputs += weight;
        if index < group.representative.index {
            group.representative = found(&replies);
            group.differing = names(&replies);
        }
        if let Some(c) = group.classes.get_mut(&class) {
            c.inputs += weight;
            if index < c.first.index {
                c.first = found(&replies);
            }
        } else if group.classes.len() < max {
            let first = found(&replies);
            group.classes.insert(
                class.clone(),
                Class {
                    name: class,
                    inputs: weight,
                    first,
                },
            );
        }
    }

    /// Adds another shard's groups.
    pub fn merge(&mut self, other: Groups) {
        for (key, g) in other.by_key {
            match self.by_key.get_mut(&key) {
                None => {
                    self.by_key.insert(key, g);
                }
                Some(mine) => {
                    mine.inputs += g.inputs;
                    if g.representative.index < mine.representative.index {
                        mine.representative = g.representative;
                        mine.differing = g.differing;
                    }
                    for (name, c) in g.classes {
                        let room = mine.classes.len() < self.max_classes;
                        match mine.classes.get_mut(&name) {
                            Some(m) => {
                                m.inputs += c.inputs;
                                if c.first.index < m.first.index {
                                    m.first = c.first;
                                }
                            }
                            None if room => {
                                mine.classes.insert(name, c);
                            }
                            None => {}
                        }
                    }
                }
            }
        }
    }

    /// The groups in a stable order: those that differ from an oracle first, then those whose
    /// columns disagree, then the rest; within each, the most inputs first, then by key.
    pub fn sorted(&self) -> Vec<&Group> {
        let mut v: Vec<&Group> = self.by_key.values().collect();
        v.sort_by(|a, b| {
            (
                a.differing.is_empty(),
                !a.disagree,
                std::cmp::Reverse(a.inputs),
                &a.key,
            )
                .cmp(&(
                    b.differing.is_empty(),
                    !b.disagree,
                    std::cmp::Reverse(b.inputs),
                    &b.key,
                ))
        });
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::cross_vendor::ErrorClass;

    fn value(v: u64) -> Reply {
        Reply::Answer {
            answer: Answer::Value(v),
            fill_dependent: false,
        }
    }

    #[test]
    fn equal_values_share_a_number() {
        let err = Reply::Answer {
            answer: Answer::Error(ErrorClass::InvalidDigit),
            fill_dependent: false,
        };
        assert_eq!(
            labels(&[value(5), value(6), err, value(5)]),
            vec!["value#1", "value#2", "invalid-digit", "value#1"]
        );
        assert!(disagree(&[], 4, &[value(1), value(2)]));
        assert!(!disagree(
            &[],
            4,
            &[value(1), Reply::Skipped { reason: "x".into() }, value(1)]
        ));
    }
}
