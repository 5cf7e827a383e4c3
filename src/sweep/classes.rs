//! Byte classes: how the full generator covers all 2^32 four-byte texts without asking each.
//!
//! Two bytes belong to one class when no column can tell them apart: put either at any place
//! of a text, and every column gives the same reply. Then a text's replies depend only on the
//! classes of its four bytes, and one text per tuple of classes — its *representative*, made
//! of each class's lowest byte — answers for all the texts of that tuple (their number is the
//! product of the class sizes). With the built-in models that is 26 classes, 456,976 texts
//! asked for 4,294,967,296 covered.
//!
//! The classes are not assumed; they are found and then checked:
//!
//! 1. **Start** from the grouping's byte kinds (`super::input::kind`), with every hex digit a
//!    class of its own: texts of one tuple then also share their features and shape, so the
//!    groups are counted exactly.
//! 2. **Split** each class by what the columns do: every byte of it is put at each of the four
//!    places, with the other three taken from [`CONTEXT`] in every combination, and bytes whose
//!    replies differ anywhere are parted.
//! 3. **Check** after the sweep: random texts of the whole space are asked as they are, and
//!    each must get exactly the replies of its tuple's representative. A text that does not is
//!    reported ([`Report::mismatch`]) and the sweep's counts are not to be trusted: the CLI
//!    says so and fails, and `--each-text` runs every text instead.

use std::collections::BTreeMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::atomic::AtomicBool;

use serde::Serialize;

use super::group::{Found, Reply};
use super::input::{kind, Kind, Point};
use super::rng::Rng;
use super::Sweep;
use crate::text::digit_value;

/// The bytes the other three places take while a class is split: a digit at each end of the
/// digit range, the terminator 00H, a letter that is not a digit, lowercase, a blank.
pub(crate) const CONTEXT: [u8; 6] = [b'0', b'F', 0x00, b'G', b'a', b' '];

/// Text numbers for the splitting and checking texts, apart from the generator's.
const PROBE_BASE: u64 = 1 << 62;

/// A partition of the 256 bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ByteClasses {
    /// Each class's bytes, ascending; classes ordered by their lowest byte.
    classes: Vec<Vec<u8>>,
    /// The class of each byte.
    of: [u8; 256],
}

impl ByteClasses {
    /// A partition from its classes; `None` unless every byte is in exactly one.
    pub fn new(mut classes: Vec<Vec<u8>>) -> Option<ByteClasses> {
        for c in &mut classes {
            c.sort_unstable();
        }
        classes.retain(|c| !c.is_empty());
        classes.sort();
        let mut of = [0u8; 256];
        let mut seen = [false; 256];
        if classes.len() > 256 {
            return None;
        }
        for (i, c) in classes.iter().enumerate() {
            for &b in c {
                if std::mem::replace(&mut seen[b as usize], true) {
                    return None;
                }
                of[b as usize] = i as u8;
            }
        }
        seen.iter()
            .all(|s| *s)
            .then_some(ByteClasses { classes, of })
    }

    /// Every hex digit alone, the other bytes by kind: where the splitting starts.
    pub fn by_kind() -> ByteClasses {
        let mut by: BTreeMap<(Kind, u8), Vec<u8>> = BTreeMap::new();
        for b in 0..=255u8 {
            let digit = digit_value(b).map_or(0xFF, |_| b);
            by.entry((kind(b), digit)).or_default().push(b);
        }
        ByteClasses::new(by.into_values().collect()).unwrap_or_else(ByteClasses::each)
    }

    /// Every byte alone.
    fn each() -> ByteClasses {
        ByteClasses {
            classes: (0..=255u8).map(|b| vec![b]).collect(),
            of: std::array::from_fn(|i| i as u8),
        }
    }

    pub fn len(&self) -> usize {
        self.classes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.classes.is_empty()
    }

    pub fn classes(&self) -> &[Vec<u8>] {
        &self.classes
    }

    /// Tuples of four classes: the points a by-class sweep asks.
    pub fn tuples(&self) -> u64 {
        (self.len() as u64).pow(4)
    }

    /// The representative text of tuple `index` (first place most significant).
    pub fn representative(&self, index: u64) -> [u8; 4] {
        let k = self.len() as u64;
        let mut out = [0u8; 4];
        let mut n = index;
        for slot in out.iter_mut().rev() {
            *slot = self.classes[(n % k) as usize][0];
            n /= k;
        }
        out
    }

    /// How many texts tuple `index` stands for.
    pub fn weight(&self, index: u64) -> u64 {
        let k = self.len() as u64;
        let mut n = index;
        let mut w = 1;
        for _ in 0..4 {
            w *= self.classes[(n % k) as usize].len() as u64;
            n /= k;
        }
        w
    }

    /// The tuple a text belongs to.
    pub fn tuple_of(&self, text: [u8; 4]) -> u64 {
        let k = self.len() as u64;
        text.iter()
            .fold(0, |n, b| n * k + u64::from(self.of[*b as usize]))
    }

    /// The classes for people: `'0'`, `blank (09H-0DH, 20H)`.
    pub fn describe(&self) -> Vec<String> {
        self.classes
            .iter()
            .map(|c| {
                let k = kind(c[0]);
                if c.len() == 1 && k == Kind::Digit {
                    format!("'{}'", c[0] as char)
                } else {
                    format!("{k} ({})", ranges(c))
                }
            })
            .collect()
    }
}

/// `[9, 10, 11, 12, 13, 32]` as `09H-0DH, 20H`.
fn ranges(bytes: &[u8]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let mut j = i;
        while j + 1 < bytes.len() && bytes[j + 1] == bytes[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            format!("{:02X}H", bytes[i])
        } else {
            format!("{:02X}H-{:02X}H", bytes[i], bytes[j])
        });
        i = j + 1;
    }
    parts.join(", ")
}

/// What the classes were and how they were checked, as the results tell it.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The classes, described.
    pub classes: Vec<String>,
    /// Texts asked to split the classes.
    pub split_texts: u64,
    /// Texts asked for the sweep: one per tuple of classes in this shard.
    pub tuples: u64,
    /// Random texts asked as they are and compared with their representative.
    pub checked: u64,
    /// The first checked text whose replies are not its representative's.
    pub mismatch: Option<Mismatch>,
}

/// A text the classes do not describe.
#[derive(Debug, Clone, Serialize)]
pub struct Mismatch {
    pub text: Found,
    pub representative: Found,
}

/// `text` with setting `pick` of the sweep's space (its digit count and flags).
fn point(sweep: &Sweep, text: [u8; 4], pick: u64) -> Point {
    sweep
        .space
        .with_setting(super::input::Data::Text(text.to_vec()), pick)
}

/// Splits [`ByteClasses::by_kind`] by what the sweep's columns do (step 2 above), under every
/// setting of the space (digit counts, flags). Returns the classes and the number of texts
/// asked; `None` if stopped.
pub(crate) fn derive(sweep: &Sweep, stop: &AtomicBool) -> Option<(ByteClasses, u64)> {
    let start = ByteClasses::by_kind();
    let contexts: Vec<[u8; 3]> = CONTEXT
        .iter()
        .flat_map(|&a| {
            CONTEXT
                .iter()
                .flat_map(move |&b| CONTEXT.iter().map(move |&c| [a, b, c]))
        })
        .collect();
    let mut points = Vec::new();
    let mut owners = Vec::new();
    for class in start.classes().iter().filter(|c| c.len() > 1) {
        for &b in class {
            for place in 0..4 {
                for ctx in &contexts {
                    let mut text = [0u8; 4];
                    let mut rest = ctx.iter();
                    for (i, slot) in text.iter_mut().enumerate() {
                        *slot = if i == place {
                            b
                        } else {
                            rest.next().copied().unwrap_or(b'0')
                        };
                    }
                    for pick in 0..sweep.space.settings() {
                        points.push((PROBE_BASE + points.len() as u64, point(sweep, text, pick)));
                        owners.push(b);
                    }
                }
            }
        }
    }
    let asked = points.len() as u64;
    let answers = sweep.answers(&points, stop);
    let mut signature: BTreeMap<u8, DefaultHasher> = BTreeMap::new();
    for (b, replies) in owners.iter().zip(answers) {
        replies?.hash(signature.entry(*b).or_default());
    }
    let mut split: BTreeMap<(usize, u64), Vec<u8>> = BTreeMap::new();
    for (i, class) in start.classes().iter().enumerate() {
        for &b in class {
            let sig = signature.get(&b).map_or(0, Hasher::finish);
            split.entry((i, sig)).or_default().push(b);
        }
    }
    Some((ByteClasses::new(split.into_values().collect())?, asked))
}

/// A digest of one text's replies, to compare a checked text with its representative.
pub(crate) fn digest(replies: &[Reply]) -> u64 {
    let mut h = DefaultHasher::new();
    replies.hash(&mut h);
    h.finish()
}

/// Step 3: `count` random texts of the tuples in this shard, each with a random setting (drawn
/// from the seed), asked as they are and compared with the digest of their representative's
/// replies (`digests`, by point of the space, for the points swept). Returns how many were checked and the first that differed.
pub(crate) fn check(
    sweep: &Sweep,
    classes: &ByteClasses,
    digests: &std::collections::HashMap<u64, u64>,
    count: u64,
    stop: &AtomicBool,
) -> (u64, Option<Mismatch>) {
    let settings = sweep.space.settings();
    // Each drawn text with its setting, and the point of the space it belongs to.
    let mut points = Vec::new();
    let mut at = Vec::new();
    let mut draw = 0u64;
    // A shard holds 1/N of the tuples; draws outside it are passed over (bounded, so that a
    // very fine shard still ends).
    while (points.len() as u64) < count && draw < count.saturating_mul(64) {
        let mut r = Rng::for_input(sweep.settings.seed ^ PROBE_BASE, draw);
        draw += 1;
        let text = [r.byte(), r.byte(), r.byte(), r.byte()];
        let pick = r.below(settings);
        let index = classes.tuple_of(text) * settings + pick;
        if digests.contains_key(&index) {
            points.push((PROBE_BASE + draw, point(sweep, text, pick)));
            at.push((index, pick));
        }
    }
    let mut checked = 0;
    for (block, at) in points.chunks(1 << 16).zip(at.chunks(1 << 16)) {
        let answers = sweep.answers(block, stop);
        for (((number, p), replies), &(index, pick)) in block.iter().zip(answers).zip(at) {
            let Some(replies) = replies else {
                return (checked, None);
            };
            checked += 1;
            if digests.get(&index) == Some(&digest(&replies)) {
                continue;
            }
            let rep = (
                index,
                point(sweep, classes.representative(index / settings), pick),
            );
            let theirs = sweep
                .answers(std::slice::from_ref(&rep), stop)
                .pop()
                .flatten()
                .unwrap_or_default();
            return (
                checked,
                Some(Mismatch {
                    text: Found {
                        index: *number,
                        point: p.clone(),
                        replies,
                    },
                    representative: Found {
                        index: rep.0,
                        point: rep.1,
                        replies: theirs,
                    },
                }),
            );
        }
    }
    (checked, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_starting_partition_keeps_digits_apart_and_kinds_together() {
        let c = ByteClasses::by_kind();
        assert_eq!(c.len(), 26);
        let d = c.describe();
        assert!(d.contains(&"'7'".to_string()));
        assert!(d.contains(&"blank (09H-0DH, 20H)".to_string()), "{d:?}");
        assert!(d.contains(&"00H (00H)".to_string()), "{d:?}");
        assert_eq!(c.tuples(), 456_976);
        let all: u64 = (0..c.tuples()).map(|t| c.weight(t)).sum();
        assert_eq!(all, 1 << 32);
    }

    #[test]
    fn tuples_and_texts_correspond() {
        let c = ByteClasses::by_kind();
        for text in [*b"0000", *b"5a8G", [0, 0xFF, b' ', b'-'], *b"\t+_z"] {
            let t = c.tuple_of(text);
            let rep = c.representative(t);
            assert_eq!(c.tuple_of(rep), t);
            for (a, b) in text.iter().zip(rep) {
                assert_eq!(kind(*a), kind(b));
            }
        }
        assert_eq!(c.representative(c.tuple_of(*b"\x0B+Zq")), *b"\x09+Gg");
    }

    #[test]
    fn a_partition_must_cover_every_byte_once() {
        assert!(ByteClasses::new(vec![(0..=255).collect()]).is_some());
        assert!(ByteClasses::new(vec![(0..=254).collect()]).is_none());
        assert!(ByteClasses::new(vec![(0..=255).collect(), vec![7]]).is_none());
    }
}
