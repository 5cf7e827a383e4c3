//! A live line per backend while a run goes on: cases done of the backend's total and failures
//! so far, on standard error when it is a terminal (nothing at all when it is not). It wraps the
//! run's other reporters, pausing the lines while they print.

use std::collections::BTreeMap;
use std::time::Duration;

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::{Event, Reporter};
use crate::plan::Trial;

pub struct ProgressReporter<'a> {
    multi: MultiProgress,
    /// Each backend's line and its failures so far.
    lines: BTreeMap<String, (ProgressBar, usize)>,
    inner: &'a mut dyn Reporter,
}

impl<'a> ProgressReporter<'a> {
    /// Lines for the backends of `trials` (counting the trials that run), drawn on standard
    /// error when it is a terminal; `inner` gets every event.
    pub fn new(trials: &[Trial], inner: &'a mut dyn Reporter) -> Self {
        Self::with_target(trials, inner, ProgressDrawTarget::stderr())
    }

    /// The same, drawn on `target`.
    pub fn with_target(
        trials: &[Trial],
        inner: &'a mut dyn Reporter,
        target: ProgressDrawTarget,
    ) -> Self {
        let mut totals: BTreeMap<&str, u64> = BTreeMap::new();
        for t in trials.iter().filter(|t| t.skip.is_none()) {
            *totals.entry(t.backend.name()).or_default() += 1;
        }
        let width = totals.keys().map(|n| n.len()).max().unwrap_or(0);
        let style = ProgressStyle::with_template(&format!(
            "{{spinner}} {{prefix:<{width}}} [{{bar:24}}] {{pos}}/{{len}} cases, {{msg}} {{elapsed}}"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        let multi = MultiProgress::with_draw_target(target);
        let lines = totals
            .into_iter()
            .map(|(name, total)| {
                let bar = multi.add(ProgressBar::new(total));
                bar.set_style(style.clone());
                bar.set_prefix(name.to_string());
                bar.set_message("0 failed");
                (name.to_string(), (bar, 0))
            })
            .collect();
        ProgressReporter {
            multi,
            lines,
            inner,
        }
    }

    /// What a backend's line says after its bar.
    pub fn message(&self, backend: &str) -> Option<String> {
        self.lines.get(backend).map(|(bar, _)| bar.message())
    }

    /// Cases done and failures so far of a backend's line.
    pub fn position(&self, backend: &str) -> Option<(u64, usize)> {
        self.lines
            .get(backend)
            .map(|(bar, failed)| (bar.position(), *failed))
    }
}

impl Reporter for ProgressReporter<'_> {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        match event {
            Event::RunStarted { .. } => {
                for (bar, _) in self.lines.values() {
                    // Keeps a line moving while a slow backend answers.
                    bar.enable_steady_tick(Duration::from_millis(120));
                }
            }
            Event::TrialFinished { trial, verdict, .. } if trial.skip.is_none() => {
                if let Some((bar, failed)) = self.lines.get_mut(trial.backend.name()) {
                    bar.inc(1);
                    if verdict.is_failure() {
                        *failed += 1;
                    }
                    bar.set_message(format!("{failed} failed"));
                    if bar.position() == bar.length().unwrap_or(0) {
                        bar.finish();
                    }
                }
            }
            Event::BackendAnswering {
                backend,
                answered,
                of,
            } => {
                if let Some((bar, failed)) = self.lines.get(*backend) {
                    bar.set_message(format!(
                        "{failed} failed, answering: {answered} of {of} requests"
                    ));
                }
            }
            Event::RunFinished { .. } => {
                for (bar, _) in self.lines.values() {
                    bar.finish_and_clear();
                }
                let _ = self.multi.clear();
            }
            _ => {}
        }
        let inner = &mut self.inner;
        self.multi.suspend(|| inner.event(event))
    }
}
