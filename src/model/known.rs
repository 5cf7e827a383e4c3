//! Known differences: the trials a backend is expected to get wrong, each with its reason.
//!
//! An implementation under test rarely conforms everywhere on day one, and its authors need a
//! green run that still catches regressions. The list is loaded by [`crate::load`] and applied
//! by [`crate::judge`]: a listed trial that differs is a known difference, a listed trial that
//! conforms is a stale entry (a failure, so the list cannot rot), a fault is never excused.

use std::path::PathBuf;

/// One validated entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    pub case: String,
    /// Only this instruction of the case (for a cross-vendor case: only this lowering).
    pub instruction: Option<String>,
    pub variant: Option<String>,
    pub reason: String,
    /// `file:line` of the entry, to point at when it goes stale.
    pub location: String,
}

impl Entry {
    /// Whether the entry covers a trial of this case, instruction (or lowering) and variant.
    pub fn matches(&self, case: &str, instruction: &str, variant: &str) -> bool {
        self.case == case
            && self.instruction.as_ref().is_none_or(|i| i == instruction)
            && self.variant.as_ref().is_none_or(|v| v == variant)
    }
}

/// A backend's validated known differences.
#[derive(Debug, Clone, Default)]
pub struct KnownDifferences {
    pub file: PathBuf,
    pub entries: Vec<Entry>,
    /// Entries naming cases that are not in the corpus being run, when the corpus is not the
    /// project's own (`--vectors`): they are set aside rather than errors.
    pub ignored: Vec<Entry>,
}

impl KnownDifferences {
    /// The entry covering a trial, if any (the first that matches).
    pub fn entry(&self, case: &str, instruction: &str, variant: &str) -> Option<&Entry> {
        self.entries
            .iter()
            .find(|e| e.matches(case, instruction, variant))
    }
}
