//! Shrinking: a group's input replaced, step by step, by a simpler one that still behaves the
//! same — the same answer classes in every column and the same features — until no simpler
//! neighbour does. Each class of a group starts from its own first input, so inputs whose
//! simplest forms differ (a blank before the digits, a blank after them) stay apart. "Simpler" is [`Point::simplicity`]: the shortest text, then the
//! fewest characters other than '0', then the lowest bytes; the value with the fewest set bits,
//! then the lowest; then the smallest count, the fewest flags on, operands in their usual place.
//! A step asks its candidates simplest first, in batches that double from [`FIRST_BATCH`]: the
//! first that behaves the same is the step (the simplest of all that do), and an external
//! backend answers a batch in one exchange.

use std::sync::atomic::AtomicBool;

use super::group::{labels_read, Found, Key, Reply};
use super::input::{Data, Point};
use super::{Results, Shrunk, Sweep};

/// The most steps one input takes.
const MAX_STEPS: usize = 64;
/// Candidates asked in a step's first batch; each next batch is twice the last.
const FIRST_BATCH: usize = 8;
/// Numbers given to candidates (their case ids), apart from any generator's.
const CANDIDATE_BASE: u64 = 1 << 63;

/// Shrinks the largest classes of every group that differs from an oracle, or, when no column
/// has an oracle, of every group whose columns disagree.
pub(crate) fn shrink_groups(sweep: &Sweep, results: &Results, stop: &AtomicBool) -> Vec<Shrunk> {
    let any_oracle = sweep.columns.iter().any(|c| c.oracle.is_some());
    let mut out = Vec::new();
    if sweep.settings.shrink == 0 {
        return out;
    }
    for (gi, g) in results.ordered().into_iter().enumerate() {
        let wanted = if any_oracle {
            !g.differing.is_empty()
        } else {
            g.disagree
        };
        if !wanted {
            continue;
        }
        for class in g.classes_by_size().into_iter().take(sweep.settings.shrink) {
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                return out;
            }
            let to = shrink(sweep, &class.first, stop);
            out.push(Shrunk {
                group: gi,
                class: class.name.clone(),
                from: class.first.clone(),
                to,
            });
        }
    }
    out
}

/// The simplest input reachable from `found` by single steps that keep its behaviour.
pub(crate) fn shrink(sweep: &Sweep, found: &Found, stop: &AtomicBool) -> Found {
    let counted = sweep.counted();
    let key = Key {
        signature: labels_read(&sweep.columns, found.point.digits, &found.replies),
        features: found.point.features(counted),
    };
    let keeps = |p: &Point, replies: &[Reply]| {
        labels_read(&sweep.columns, p.digits, replies) == key.signature
            && p.features(counted) == key.features
    };
    let mut current = found.clone();
    for _ in 0..MAX_STEPS {
        let here = current.point.simplicity();
        let mut candidates: Vec<(u64, Point)> = candidates(&current.point, counted)
            .into_iter()
            .filter(|p| p.simplicity() < here)
            .enumerate()
            .map(|(k, p)| (CANDIDATE_BASE + k as u64, p))
            .collect();
        // The simplest first (stable: of equals, the first made), so the first that keeps the
        // behaviour is the step. They are asked in batches that double, and the step ends at
        // the first batch that holds one: most steps are found among the first few.
        candidates.sort_by_cached_key(|(_, p)| p.simplicity());
        let mut step = None;
        let mut rest = &candidates[..];
        let mut batch = FIRST_BATCH;
        while step.is_none() && !rest.is_empty() {
            let (asked, later) = rest.split_at(batch.min(rest.len()));
            let answers = sweep.answers(asked, stop);
            step = (asked.iter().zip(answers))
                .filter_map(|((_, p), r)| r.map(|r| (p, r)))
                .find(|(p, r)| keeps(p, r))
                .map(|(p, r)| (p.clone(), r));
            rest = later;
            batch *= 2;
        }
        match step {
            Some((point, replies)) => {
                current = Found {
                    index: found.index,
                    point,
                    replies,
                }
            }
            None => break,
        }
    }
    current
}

/// The bytes a character may step down to: '0', the class boundaries below it, and a ladder
/// of distances below it (so a step can go a long way, and repeated steps reach the lowest).
fn lower_bytes(b: u8) -> Vec<u8> {
    let mut out: Vec<u8> = super::generate::BOUNDARIES
        .iter()
        .copied()
        .chain([b'0', 0, b / 2])
        .chain(
            [1u8, 2, 3, 5, 9, 17, 33, 65]
                .iter()
                .filter_map(|d| b.checked_sub(*d)),
        )
        .filter(|x| *x < b || (*x == b'0' && b != b'0'))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Every input one step simpler than `p` (and some that are not; the caller filters).
pub fn candidates(p: &Point, counted: bool) -> Vec<Point> {
    let mut out = Vec::new();
    let with = |data: Data| Point { data, ..p.clone() };
    match &p.data {
        Data::Text(t) => {
            for i in 0..t.len() {
                let mut shorter = t.clone();
                shorter.remove(i);
                out.push(with(Data::Text(shorter)));
                for b in lower_bytes(t[i]) {
                    let mut lower = t.clone();
                    lower[i] = b;
                    out.push(with(Data::Text(lower)));
                }
            }
        }
        Data::Value(v) => {
            for bit in 0..64 {
                if v >> bit & 1 == 1 {
                    out.push(with(Data::Value(v & !(1 << bit))));
                    if bit > 0 && v >> (bit - 1) & 1 == 0 {
                        out.push(with(Data::Value((v & !(1 << bit)) | 1 << (bit - 1))));
                    }
                }
            }
        }
    }
    if counted {
        for d in 0..p.digits {
            out.push(Point {
                digits: d,
                ..p.clone()
            });
        }
    }
    for (flag, on) in &p.flags {
        if *on {
            let mut q = p.clone();
            q.flags.insert(flag.clone(), false);
            out.push(q);
        }
    }
    if p.source.is_some() {
        out.push(Point {
            source: None,
            ..p.clone()
        });
    }
    if p.destination.is_some() {
        out.push(Point {
            destination: None,
            ..p.clone()
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_include_the_obvious_steps() {
        let p = Point::text(b"5a", 2);
        let c = candidates(&p, true);
        assert!(c.contains(&Point::text(b"a", 2)));
        assert!(c.contains(&Point::text(b"0a", 2)));
        assert!(c.contains(&Point::text(b"5a", 1)));
        assert!(c.contains(&Point::text(b"5\0", 2)));
        let v = candidates(&Point::value(0b110, 4), false);
        assert!(v.contains(&Point::value(0b100, 4)));
        assert!(v.contains(&Point::value(0b101, 4)));
    }
}
