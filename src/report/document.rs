//! Reports written as one document at the end of a run: JSON, JUnit XML, HTML and the matrix.
//! A [`Collector`] keeps every trial's [`Record`] in plan order; [`render`] writes them in the
//! chosen format.

use super::matrix::sections;
use super::record::Record;
use super::{Event, Reporter, Stopped, Summary};

/// The report formats, as `--format` names them: text is written as the run goes, the others
/// as one document at its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub(crate) enum Format {
    /// For `run`: failures as they happen, then counts. For `diff`: the grouped matrices.
    Text,
    /// The grouped matrices as text.
    Matrix,
    /// The versioned JSON report (usable as a `--baseline`).
    Json,
    /// JUnit XML, one test case per trial.
    Junit,
    /// One self-contained HTML file.
    Html,
}

/// Collects records as trials finish.
#[derive(Default)]
pub(crate) struct Collector {
    records: Vec<(usize, Record)>,
    summary: Summary,
    stopped: Option<Stopped>,
}

impl Collector {
    /// The records in plan order, the counts, and why the run stopped early, if it did.
    pub(crate) fn finish(mut self) -> (Vec<Record>, Summary, Option<Stopped>) {
        self.records.sort_by_key(|(i, _)| *i);
        (
            self.records.into_iter().map(|(_, r)| r).collect(),
            self.summary,
            self.stopped,
        )
    }
}

impl Reporter for Collector {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        match event {
            Event::TrialFinished {
                index,
                trial,
                verdict,
                elapsed,
            } => self.records.push((
                *index,
                Record {
                    seconds: *elapsed,
                    ..Record::of(trial, verdict)
                },
            )),
            Event::RunFinished { summary, stopped } => {
                self.summary = **summary;
                self.stopped = *stopped;
            }
            Event::RunStarted { .. }
            | Event::BackendRestarted { .. }
            | Event::BackendAnswering { .. } => {}
        }
        Ok(())
    }
}

/// Renders records in a document format; `coloured` and `width` (columns of text) apply to the
/// matrix text only.
#[cfg(feature = "cli")]
pub(crate) fn render(
    format: Format,
    records: &[Record],
    summary: &Summary,
    meta: &super::json::RunInfo,
    coloured: bool,
    width: usize,
) -> String {
    let matrices = sections(records);
    match format {
        // As a document, text is the matrices (what `diff` shows).
        Format::Matrix | Format::Text => super::matrix_text::render(&matrices, coloured, width),
        Format::Json => super::json::render(records, &matrices, summary, meta),
        Format::Junit => super::junit::render(records, meta),
        Format::Html => super::html::render(&matrices, records, meta),
    }
}
