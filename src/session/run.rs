//! Running trials: each backend's batched, judged as they come in, every verdict sent to a
//! reporter; and what a run ends with.

use std::io;
use std::ops::ControlFlow;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use super::Session;
use crate::execute::{execute, execute_all, Observation, Pace, Progress, Stop, Stopped};
use crate::judge::{judge, skipped, Verdict};
use crate::plan::Trial;
use crate::report::baseline::{self, SavedRun};
use crate::report::document::Collector;
use crate::report::record::Record;
use crate::report::{All, Event, Reporter, Summary};

/// How a session runs its trials.
pub(crate) struct RunOptions {
    /// Backends running side by side at most.
    pub jobs: usize,
    /// Stop at the first failing trial: no further batch starts.
    pub fail_fast: bool,
    /// A filter narrowed the run: a backend left with no trial is not idle for want of one.
    pub filtered: bool,
    /// A backend that ran nothing is accepted.
    pub allow_empty: bool,
}

impl Session {
    /// Runs `trials` (planned from this session's backends) and reports each verdict to
    /// `reporter` as it is judged. When `interrupt` is set, or with `fail_fast` once a trial
    /// fails, no further batch starts and the run ends with what it has, saying which of the two
    /// stopped it. Ends with the records and counts, and the backends the
    /// session was asked for that ran nothing (they passed nothing); or with the reporter's
    /// first write error, since a report that cannot be written would only be truncated.
    pub(crate) fn run(
        &self,
        trials: &[Trial],
        options: &RunOptions,
        interrupt: &AtomicBool,
        reporter: &mut dyn Reporter,
    ) -> io::Result<RunOutcome> {
        let started = Instant::now();
        let stop = Stop::new(interrupt);
        let mut collector = Collector::default();
        let mut stopper = StopAtFailure { stop: &stop };
        let mut reporters: Vec<&mut dyn Reporter> = vec![&mut collector, reporter];
        // `fail_fast` holds every batch back until the one before is judged: a run that
        // executes faster than it reports would otherwise finish before the first failure is
        // seen.
        let pace = match options.fail_fast {
            true => {
                reporters.push(&mut stopper);
                Pace::Judged
            }
            false => Pace::Ahead,
        };
        run_trials(trials, options.jobs, &stop, pace, &mut All(reporters))?;
        let (records, summary, stopped) = collector.finish();
        let idle = match stopped.is_some() || options.allow_empty {
            true => Vec::new(),
            false => self.idle(trials, options.filtered),
        };
        Ok(RunOutcome {
            records,
            summary,
            idle,
            stopped,
            seconds: started.elapsed().as_secs_f64(),
            baseline: None,
        })
    }
}

/// Stops the run at the first failing trial: no further batch starts.
struct StopAtFailure<'a, 'b> {
    stop: &'a Stop<'b>,
}

impl Reporter for StopAtFailure<'_, '_> {
    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let Event::TrialFinished { verdict, .. } = event {
            if verdict.is_failure() {
                self.stop.at_failure();
            }
        }
        Ok(())
    }
}

/// Runs one trial: skipped, or executed under every fill and judged.
pub fn run_one(trial: &Trial) -> Verdict {
    match &trial.skip {
        Some(reason) => skipped(reason),
        None => judge(trial, &execute(trial)),
    }
}

/// Executes trials (each backend's batched, at most `jobs` backends at once) without judging
/// them: what a recording writes and what `diff --against` judges the other backend against.
/// A trial left out when `stop` was set is `None`.
pub(crate) fn observe(
    trials: &[Trial],
    jobs: usize,
    stop: &AtomicBool,
) -> Vec<Option<Vec<Observation>>> {
    let indices: Vec<usize> = (0..trials.len()).collect();
    let mut observed: Vec<Option<Vec<Observation>>> = (0..trials.len()).map(|_| None).collect();
    execute_all(trials, &indices, jobs, stop, Pace::Ahead, |p| {
        if let Progress::Observed(i, observations, _) = p {
            observed[i] = Some(observations);
        }
        ControlFlow::Continue(())
    });
    observed
}

/// Runs trials and reports each verdict as it is judged: skipped trials first, then each
/// backend's results as they come in (backends side by side, at most `jobs` at once). When
/// `stop` is set, no further chunk is started and the run finishes with what it has, its end
/// event saying why. Returns the counts, or the reporter's first write error: the run ends
/// there, since a report that cannot be written would only be truncated.
pub(crate) fn run_trials(
    trials: &[Trial],
    jobs: usize,
    stop: &Stop<'_>,
    pace: Pace,
    reporter: &mut dyn Reporter,
) -> std::io::Result<Summary> {
    let mut summary = Summary::default();
    reporter.event(&Event::RunStarted {
        trials: trials.len(),
    })?;
    for (i, t) in trials.iter().enumerate() {
        if let Some(reason) = &t.skip {
            finished(
                reporter,
                &mut summary,
                trials,
                i,
                skipped(reason),
                Duration::ZERO,
            )?;
        }
    }
    let indices: Vec<usize> = (0..trials.len()).collect();
    let mut failed = None;
    execute_all(trials, &indices, jobs, stop, pace, |progress| {
        let written = match progress {
            Progress::Observed(i, observations, elapsed) => {
                let mut verdict = judge(&trials[i], &observations);
                // Once the run is interrupted, its backends are killed: a trial that then
                // faults was cancelled, not failed. A fail-fast stop kills nothing, so a fault
                // after it is the backend's own.
                if stop.interrupted() && matches!(verdict, Verdict::Fault { .. }) {
                    verdict = Verdict::Cancelled;
                }
                finished(reporter, &mut summary, trials, i, verdict, elapsed)
            }
            Progress::Restarted { backend, restarts } => reporter.event(&Event::BackendRestarted {
                backend: &backend,
                restarts,
            }),
            Progress::Answering {
                backend,
                answered,
                of,
            } => reporter.event(&Event::BackendAnswering {
                backend: &backend,
                answered,
                of,
            }),
        };
        match written {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                failed = Some(e);
                ControlFlow::Break(())
            }
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    reporter.event(&Event::RunFinished {
        summary: &summary,
        stopped: stop.reason(),
    })?;
    Ok(summary)
}

/// Runs trials (each backend's batched) and returns their verdicts in plan order.
pub fn verdicts(trials: &[Trial]) -> Vec<Verdict> {
    struct Keep(Vec<Option<Verdict>>);
    impl Reporter for Keep {
        fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
            if let Event::TrialFinished { index, verdict, .. } = event {
                self.0[*index] = Some((*verdict).clone());
            }
            Ok(())
        }
    }
    let mut keep = Keep(vec![None; trials.len()]);
    // Keep writes nothing, so it cannot fail.
    let never = AtomicBool::new(false);
    let _ = run_trials(trials, 1, &Stop::new(&never), Pace::Ahead, &mut keep);
    keep.0
        .into_iter()
        .map(|v| v.unwrap_or_else(|| skipped("not run")))
        .collect()
}

fn finished(
    reporter: &mut dyn Reporter,
    summary: &mut Summary,
    trials: &[Trial],
    index: usize,
    verdict: Verdict,
    elapsed: Duration,
) -> std::io::Result<()> {
    summary.add(&verdict);
    reporter.event(&Event::TrialFinished {
        index,
        trial: &trials[index],
        verdict: &verdict,
        elapsed,
    })
}

/// What a run ends with.
pub(crate) struct RunOutcome {
    pub records: Vec<Record>,
    pub summary: Summary,
    /// Backends the run was asked for that ran no trial, with why: they passed nothing.
    pub idle: Vec<(String, String)>,
    /// Why the run stopped before its end, if it did: it reports what it did until then.
    pub stopped: Option<Stopped>,
    /// How long the run took, in seconds.
    pub seconds: f64,
    /// The comparison with a baseline, when one was given.
    pub baseline: Option<BaselineChanges>,
}

/// Counts of a baseline comparison, and one line per changed trial.
pub(crate) struct BaselineChanges {
    pub new: Vec<String>,
    pub fixed: Vec<String>,
    pub changed: Vec<String>,
    pub unchanged: usize,
}

impl RunOutcome {
    /// Compares the run with a saved one.
    pub(crate) fn against(&mut self, before: &SavedRun) {
        let changes = baseline::compare(&before.records, &self.records);
        self.baseline = Some(BaselineChanges {
            new: changes
                .new
                .iter()
                .map(|r| format!("{} ({}: {})", r.trial, r.label, r.shown))
                .collect(),
            fixed: changes
                .fixed
                .iter()
                .map(|(was, now)| format!("{} (was {}: {})", now.trial, was.label, was.shown))
                .collect(),
            changed: changes
                .changed
                .iter()
                .map(|(was, now)| format!("{} ({} -> {})", now.trial, was.shown, now.shown))
                .collect(),
            unchanged: changes.unchanged,
        });
    }

    /// 0 when everything asked of the run conforms, 1 otherwise: with a baseline, a new
    /// failure; without one, any failure; and always a backend that ran nothing.
    pub(crate) fn exit_code(&self) -> u8 {
        let differs = match &self.baseline {
            Some(b) => !b.new.is_empty(),
            None => self.summary.failed > 0,
        };
        u8::from(differs || !self.idle.is_empty())
    }
}

impl Session {
    /// The backends this session was asked for that `trials` give nothing to run, with why:
    /// they would pass having checked nothing.
    pub(crate) fn idle(&self, trials: &[Trial], filtered: bool) -> Vec<(String, String)> {
        let asked: Vec<&str> = self.asked.iter().map(String::as_str).collect();
        idle_backends(trials, &asked, filtered)
    }
}

/// The backends among `asked` that ran no trial, with why: every trial of theirs skipped (the
/// most frequent reason is given), or, when no filter narrows the run, no trial at all.
fn idle_backends(trials: &[Trial], asked: &[&str], filtered: bool) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for name in asked {
        let theirs: Vec<&Trial> = trials
            .iter()
            .filter(|t| t.backend.name() == *name)
            .collect();
        if theirs.iter().any(|t| t.skip.is_none()) {
            continue;
        }
        if theirs.is_empty() {
            if !filtered {
                out.push((name.to_string(), "the corpus has no trial for it".into()));
            }
            continue;
        }
        let mut reasons: std::collections::BTreeMap<&str, usize> = Default::default();
        for t in &theirs {
            *reasons.entry(t.skip.as_deref().unwrap_or("")).or_default() += 1;
        }
        let (reason, _) = reasons
            .iter()
            .max_by_key(|(_, n)| **n)
            .map_or(("", &0), |(r, n)| (*r, n));
        out.push((
            name.to_string(),
            format!("all {} of its trials were skipped ({reason})", theirs.len()),
        ));
    }
    out
}
