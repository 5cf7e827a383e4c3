//! A judged codec's differences read for a field shape: when they cluster where only the shape
//! of the protocol's field matters — text past the digit count, a blank between byte pairs,
//! bytes in the other order, no leading zeros — the sweep says which shape would describe them,
//! since a codec wired without its shape (`docs/protocol.md#field-shapes`) otherwise shows
//! mostly its adapter's artefacts.

use serde::Serialize;

use super::group::Reply;
use super::input::{Data, Point};
use super::target::Ask;
use super::{Results, Sweep};
use crate::model::cross_vendor::{
    blank_between_pairs, Answer, FieldShape, Operation, OperationAbilities,
};

/// A field shape that would describe most of a judged codec's differences.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Hint {
    pub column: String,
    /// The shape, as the codec's hello declares it (`"whole-frame": true`).
    pub shape: String,
    /// Differing inputs it describes, of `of`.
    pub inputs: u64,
    pub of: u64,
    /// What those inputs have in common.
    pub why: String,
}

/// The share of a codec's differing inputs a shape must describe to be named.
const SHARE: f64 = 0.5;
/// How many times more often than among all swept inputs.
const ENRICHED: f64 = 2.0;
/// A share of the differing inputs that names a shape whatever its share among all inputs.
const NEARLY_ALL: f64 = 0.95;

/// A candidate shape: what it is declared as, what its inputs share, and how it is read off a
/// differing input.
struct Candidate {
    shape: &'static str,
    why: &'static str,
    /// Not suggested when the codec declares it already.
    declared: fn(&OperationAbilities) -> bool,
    reads: Reads,
}

enum Reads {
    /// A trait of the input (the shape would not have asked it).
    Input(fn(Operation, &Point) -> bool),
    /// The codec's answer is the oracle's as a field of this shape (a fixed field with this
    /// change) writes or reads it.
    Answer(fn(&mut FieldShape)),
}

const CANDIDATES: &[Candidate] = &[
    Candidate {
        shape: "\"whole-frame\": true",
        why: "texts with characters after the digit count: a codec that checks its field as part \
              of a frame (a trailing character, a checksum) refuses them",
        declared: |a| a.shape.whole_frame,
        reads: Reads::Input(|op, p| {
            op == Operation::HexToValue && text(p).len() > p.digits as usize
        }),
    },
    Candidate {
        shape: "\"variable\": true",
        why:
            "texts shorter or longer than the digit count: a codec that reads a token of whatever \
              length reads them all",
        declared: |a| a.shape.variable,
        reads: Reads::Input(|op, p| {
            op == Operation::HexToValue && text(p).len() != p.digits as usize
        }),
    },
    Candidate {
        shape: "\"blanks-between-pairs\": true",
        why: "texts with a blank where a byte pair could start: a codec that reads its field with \
              bytes.fromhex skips it",
        declared: |a| a.shape.blanks_between_pairs,
        reads: Reads::Input(|op, p| op == Operation::HexToValue && blank_between_pairs(text(p))),
    },
    Candidate {
        shape: "\"byte-order\": \"low-first\"",
        why: "answers that are the oracle's with the bytes in the other order",
        declared: |a| a.shape.low_byte_first,
        reads: Reads::Answer(|s| s.low_byte_first = true),
    },
    Candidate {
        shape: "\"leading-zeros\": false",
        why: "answers that are the oracle's text without its leading zeros",
        declared: |a| !a.shape.leading_zeros,
        reads: Reads::Answer(|s| s.leading_zeros = false),
    },
];

impl Reads {
    /// Whether it describes a differing input: the point, and the codec's answer and the
    /// oracle's when both are answers.
    fn describe(&self, op: Operation, p: &Point, answers: Option<(&Answer, &Answer)>) -> bool {
        match (self, answers) {
            (Reads::Input(trait_of), _) => trait_of(op, p),
            (Reads::Answer(change), Some((mine, theirs))) => {
                let mut field = OperationAbilities::default();
                change(&mut field.shape);
                // An odd count holds no whole bytes: a low-first field does not take it.
                mine != theirs
                    && (p.digits % 2 == 0 || !field.shape.low_byte_first)
                    && field.shaped(op, p.digits, theirs) == *mine
            }
            (Reads::Answer(_), None) => false,
        }
    }
}

fn text(p: &Point) -> &[u8] {
    match &p.data {
        Data::Text(t) => t,
        Data::Value(_) => &[],
    }
}

/// The shapes that describe each judged codec column's differing inputs (what known
/// differences cover aside): nearly all of them, or most and far more often than all inputs;
/// the most first, and a shape read off the answers before one read off the input.
pub(crate) fn hints(sweep: &Sweep, results: &Results) -> Vec<Hint> {
    let mut out = Vec::new();
    for (c, column) in sweep.columns.iter().enumerate() {
        let (Ask::Codec, Some(o), Some((operation, field))) =
            (&column.ask, column.oracle, column.field.as_ref())
        else {
            continue;
        };
        let described = |k: &Candidate, g: &super::group::Group| {
            let r = &g.representative;
            let answers = match (&r.replies[c], &r.replies[o]) {
                (Reply::Answer { answer: mine, .. }, Reply::Answer { answer: theirs, .. }) => {
                    Some((mine, theirs))
                }
                // A fault or an `unsupported` is no matter of shape.
                (Reply::Failed { .. }, _) => return false,
                _ => None,
            };
            k.reads.describe(*operation, &r.point, answers)
        };
        let all: Vec<&super::group::Group> = results.groups.by_key.values().collect();
        let swept: u64 = all.iter().map(|g| g.inputs).sum();
        let of: u64 = (all.iter())
            .filter(|g| g.differing.contains(&column.name))
            .map(|g| g.inputs)
            .sum();
        if of == 0 {
            continue;
        }
        let mut found: Vec<(bool, Hint)> = CANDIDATES
            .iter()
            .filter(|k| !(k.declared)(field))
            .filter_map(|k| {
                let (mut inputs, mut anywhere) = (0u64, 0u64);
                for g in all.iter().filter(|g| described(k, g)) {
                    anywhere += g.inputs;
                    if g.differing.contains(&column.name) {
                        inputs += g.inputs;
                    }
                }
                // Nearly all of the differences; or most of them, and far more often there
                // than among all inputs (a trait most inputs share explains little).
                let share = inputs as f64 / of as f64;
                let base = anywhere as f64 / swept.max(1) as f64;
                let named = share >= NEARLY_ALL || (share >= SHARE && share >= ENRICHED * base);
                named.then(|| {
                    let hint = Hint {
                        column: column.name.clone(),
                        shape: k.shape.to_string(),
                        inputs,
                        of,
                        why: k.why.to_string(),
                    };
                    (matches!(k.reads, Reads::Answer(_)), hint)
                })
            })
            .collect();
        // An answer the shape would have written is a closer reading than a trait of the
        // input: when one describes the differences, the input's traits are not named.
        if found.iter().any(|(answered, _)| *answered) {
            found.retain(|(answered, _)| *answered);
        }
        found.sort_by_key(|(_, h)| std::cmp::Reverse(h.inputs));
        out.extend(found.into_iter().map(|(_, h)| h));
    }
    out
}
