//! Reporting trial results: text for people, JSON for tools.

pub mod html;
pub mod json;
pub mod junit;
pub mod matrix_text;
pub mod text;

use crate::compare::Verdict;
use crate::plan::Trial;

/// A trial and what became of it. A skipped trial has no verdict.
pub struct TrialResult {
    pub trial: Trial,
    pub verdict: Option<Verdict>,
}

/// Counts for a run's closing line.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Summary {
    pub passed: usize,
    pub failed: usize,
    pub recorded: usize,
    pub skipped: usize,
    /// Differences a known-differences file lists: neither passed nor failed.
    pub known: usize,
}

impl Summary {
    pub fn of<'a>(results: impl IntoIterator<Item = &'a TrialResult>) -> Self {
        let mut s = Summary::default();
        for r in results {
            match &r.verdict {
                None => s.skipped += 1,
                Some(Verdict::Recorded { .. }) => s.recorded += 1,
                Some(Verdict::KnownDifference { .. }) => s.known += 1,
                Some(v) if v.is_failure() => s.failed += 1,
                Some(_) => s.passed += 1,
            }
        }
        s
    }
}

impl Summary {
    /// Counts cross-vendor verdicts (`None` for a skipped trial) the same way.
    pub fn of_neutral<'a>(
        verdicts: impl IntoIterator<Item = Option<&'a crate::neutral::lower::NeutralVerdict>>,
    ) -> Self {
        use crate::neutral::lower::NeutralVerdict;
        let mut s = Summary::default();
        for v in verdicts {
            match v {
                None => s.skipped += 1,
                Some(NeutralVerdict::Recorded { .. }) => s.recorded += 1,
                Some(NeutralVerdict::KnownDifference { .. }) => s.known += 1,
                Some(v) if v.is_failure() => s.failed += 1,
                Some(_) => s.passed += 1,
            }
        }
        s
    }

    /// Adds another summary's counts to this one.
    pub fn add(&mut self, other: &Summary) {
        self.passed += other.passed;
        self.failed += other.failed;
        self.recorded += other.recorded;
        self.skipped += other.skipped;
        self.known += other.known;
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} passed, {} failed, {} skipped ({} unspecified recorded",
            self.passed, self.failed, self.skipped, self.recorded
        )?;
        if self.known > 0 {
            write!(f, ", {} known differences", self.known)?;
        }
        f.write_str(")")
    }
}
