//! The text report of `plc-conformance run`: each failure as soon as its trial is judged, then
//! known differences grouped by entry, skips grouped by reason, and the counts.

use std::collections::BTreeMap;
use std::io::Write;

use super::sanitize::terminal;
use super::text::{render, Palette};
use super::{Event, Reporter, Stopped, Summary};
use crate::judge::Verdict;

/// A known-differences entry and the trials it covers, in plan order.
struct KnownGroup {
    first: usize,
    reason: String,
    trials: Vec<(usize, String)>,
}

pub(crate) struct TextReporter<W: Write> {
    out: W,
    palette: Palette,
    show_recorded: bool,
    /// Only failures and the closing counts.
    quiet: bool,
    known: BTreeMap<String, KnownGroup>,
    skipped: BTreeMap<String, usize>,
    /// Counts per backend; cross-vendor trials, and each protocol's, count apart.
    per_backend: BTreeMap<String, Summary>,
    cross_vendor: Option<Summary>,
    /// Protocol-field trials, by protocol.
    protocols: BTreeMap<String, Summary>,
    restarts: BTreeMap<String, usize>,
    /// A failure's report without its trial's name and run line, with the trial it was shown
    /// for: the same failure under another variant or pulse form is named, not repeated.
    shown: std::collections::HashMap<String, String>,
}

impl<W: Write> TextReporter<W> {
    pub(crate) fn new(out: W, palette: Palette, show_recorded: bool) -> Self {
        TextReporter {
            out,
            palette,
            show_recorded,
            quiet: false,
            known: BTreeMap::new(),
            skipped: BTreeMap::new(),
            per_backend: BTreeMap::new(),
            cross_vendor: None,
            protocols: BTreeMap::new(),
            restarts: BTreeMap::new(),
            shown: std::collections::HashMap::new(),
        }
    }

    /// The writer, for a caller that must finish it (a staged file put in place).
    pub(crate) fn into_inner(self) -> W {
        self.out
    }

    /// Prints only failures and the closing counts (no known differences, skips or
    /// per-backend counts).
    pub(crate) fn quiet(mut self, quiet: bool) -> Self {
        self.quiet = quiet;
        self
    }

    fn finish(&mut self, summary: &Summary, stopped: Option<Stopped>) -> std::io::Result<()> {
        // Quiet: only whether the run was cut short, and the summary.
        if !self.quiet {
            self.details()?;
        }
        let out = &mut self.out;
        match stopped {
            Some(Stopped::Interrupted) => writeln!(
                out,
                "interrupted: the counts cover the trials that finished"
            )?,
            Some(Stopped::FailFast) => writeln!(
                out,
                "stopped at the first failure (--fail-fast): the counts cover the trials that \
                 finished"
            )?,
            None => {}
        }
        writeln!(out, "{summary}")?;
        out.flush()
    }

    /// The known differences met, the skips, restarts and per-backend counts.
    fn details(&mut self) -> std::io::Result<()> {
        let out = &mut self.out;
        let mut known: Vec<(&String, &KnownGroup)> = self.known.iter().collect();
        known.sort_by_key(|(_, g)| g.first);
        for (entry, group) in known {
            writeln!(
                out,
                "known difference ({}): {}",
                terminal(entry),
                terminal(&group.reason)
            )?;
            let mut trials = group.trials.clone();
            trials.sort();
            for (_, line) in trials {
                writeln!(out, "  {}", terminal(&line))?;
            }
        }
        for (reason, count) in &self.skipped {
            writeln!(out, "skipped {count} trial(s): {}", terminal(reason))?;
        }
        for (backend, n) in &self.restarts {
            writeln!(
                out,
                "note: {backend} was started again {n} time(s) after a fault"
            )?;
        }
        for (backend, s) in &self.per_backend {
            writeln!(out, "{backend}: {s}")?;
        }
        if let Some(s) = &self.cross_vendor {
            writeln!(out, "cross-vendor: {s}")?;
        }
        for (protocol, s) in &self.protocols {
            writeln!(out, "protocol {protocol}: {s}")?;
        }
        Ok(())
    }
}

impl<W: Write> Reporter for TextReporter<W> {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        match event {
            Event::RunStarted { .. } => {}
            Event::TrialFinished {
                index,
                trial,
                verdict,
                ..
            } => {
                let protocol = (trial.cross_vendor_case()).and_then(|c| c.protocol.as_ref());
                let counts = if let Some(from) = protocol {
                    self.protocols.entry(from.protocol.clone()).or_default()
                } else if trial.is_cross_vendor() {
                    self.cross_vendor.get_or_insert_with(Summary::default)
                } else {
                    self.per_backend
                        .entry(trial.backend.name().to_string())
                        .or_default()
                };
                counts.add(verdict);
                match verdict {
                    v if v.is_failure() => {
                        let report = render(trial, v, self.palette);
                        match self.shown.entry(same_failure(&report)) {
                            std::collections::hash_map::Entry::Occupied(first) => {
                                let h = self.palette.heading;
                                writeln!(
                                    self.out,
                                    "{h}{}: {} {}{h:#}: as {} above\n",
                                    terminal(&trial.location().to_string()),
                                    trial.name(),
                                    v.label(),
                                    first.get()
                                )?;
                            }
                            std::collections::hash_map::Entry::Vacant(slot) => {
                                slot.insert(trial.name());
                                writeln!(self.out, "{report}")?;
                            }
                        }
                        self.out.flush()?;
                    }
                    Verdict::KnownDifference { entry, .. } => {
                        let group = self.known.entry(entry.location.clone()).or_insert_with(|| {
                            KnownGroup {
                                first: *index,
                                reason: entry.reason.clone(),
                                trials: Vec::new(),
                            }
                        });
                        group.first = group.first.min(*index);
                        group
                            .trials
                            .push((*index, format!("{} ({})", trial.name(), trial.location())));
                    }
                    v @ (Verdict::Skipped { .. } | Verdict::Cancelled) => {
                        let reason = v.not_run().unwrap_or_default().to_string();
                        *self.skipped.entry(reason).or_default() += 1;
                    }
                    v @ Verdict::Recorded { .. } if self.show_recorded => {
                        writeln!(self.out, "{}", render(trial, v, self.palette))?;
                    }
                    _ => {}
                }
            }
            Event::BackendRestarted { backend, restarts } => {
                self.restarts.insert(backend.to_string(), *restarts);
            }
            // The live progress line shows it; the report does not.
            Event::BackendAnswering { .. } => {}
            Event::RunFinished { summary, stopped } => self.finish(summary, *stopped)?,
        }
        Ok(())
    }
}

/// What makes two failure reports the same failure: every line but the heading (which names
/// the trial) and the `run:` line (its instruction form and variant).
fn same_failure(report: &str) -> String {
    report
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with("  run:"))
        .collect::<Vec<_>>()
        .join("\n")
}
