//! Reporting: every output of the tool is a [`Reporter`] fed by [`Event`]s.
//!
//! The runner emits events as trials finish — run started, trial finished with its verdict,
//! backend restarted, run finished — and a reporter turns them into text for people, a JSON
//! document for tools, JUnit XML for CI dashboards, an HTML page or a matrix. Reporters do all
//! the printing; nothing before this stage writes to the terminal.

pub(crate) mod baseline;
pub(crate) mod console;
pub(crate) mod document;
pub(crate) mod html;
pub(crate) mod json;
#[cfg(feature = "cli")]
pub(crate) mod junit;
pub(crate) mod matrix;
pub(crate) mod matrix_text;
#[cfg(feature = "cli")]
pub(crate) mod progress;
pub(crate) mod record;
pub(crate) mod results;
pub(crate) mod sanitize;
pub(crate) mod text;
pub(crate) mod text_reporter;

use std::time::Duration;

pub(crate) use crate::execute::Stopped;
use crate::judge::{Status, Verdict};
use crate::plan::Trial;

/// What happens during a run, in order.
pub enum Event<'a> {
    /// The plan is made: how many trials will be reported.
    RunStarted { trials: usize },
    /// One trial is judged. `index` is its place in the plan, so reporters that list results
    /// can keep plan order while results arrive backend by backend.
    TrialFinished {
        index: usize,
        trial: &'a Trial,
        verdict: &'a Verdict,
        /// How long the trial took (zero for a trial that did not run).
        elapsed: Duration,
    },
    /// A backend's process was started again after a fault.
    BackendRestarted { backend: &'a str, restarts: usize },
    /// A backend is still answering the requests it was handed: `answered` of `of` so far.
    BackendAnswering {
        backend: &'a str,
        answered: usize,
        of: usize,
    },
    /// Every trial is reported; `stopped` says why the run ended early, when it did.
    RunFinished {
        summary: &'a Summary,
        stopped: Option<Stopped>,
    },
}

/// Something that turns a run's events into output. A write that fails (a closed pipe, a full
/// disk) is returned, and the run ends with it rather than going on with a truncated report.
pub trait Reporter {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()>;
}

/// Any number of reporters fed the same events, in order.
pub(crate) struct All<'a>(pub Vec<&'a mut dyn Reporter>);

impl Reporter for All<'_> {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        for r in &mut self.0 {
            r.event(event)?;
        }
        Ok(())
    }
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
    /// Counts one verdict.
    pub fn add(&mut self, verdict: &Verdict) {
        match verdict.status() {
            Status::Pass => self.passed += 1,
            Status::Fail => self.failed += 1,
            Status::Skipped => self.skipped += 1,
            Status::Ignored => match verdict {
                Verdict::KnownDifference { .. } => self.known += 1,
                _ => self.recorded += 1,
            },
        }
    }

    pub fn of<'a>(verdicts: impl IntoIterator<Item = &'a Verdict>) -> Self {
        let mut s = Summary::default();
        for v in verdicts {
            s.add(v);
        }
        s
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
