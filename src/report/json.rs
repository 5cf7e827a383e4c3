//! The JSON report of `run` and `diff`: one versioned document for both.
//!
//! Shape: `{"format": "plc-conformance-results", "version": 2, "run": {tool, backends,
//! interrupted, stopped}, "summary": {passed, failed, skipped, recorded, known}, "records": [Record],
//! "sections": [matrix]}`. Each record carries the trial's status, its structured behaviour and,
//! where it ran, its verdict (words in hex, as the manuals write them). The document is also a
//! saved run: `--baseline` reads its records.

use serde::{Deserialize, Serialize};

use super::matrix::Section;
use super::record::Record;
use super::Summary;

pub(crate) const FORMAT: &str = "plc-conformance-results";
pub(crate) const VERSION: u32 = 2;

/// What ran: shown in reports so a saved result says where it came from.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(crate) struct RunInfo {
    /// `plc-conformance 0.1.0`.
    pub tool: String,
    /// The project's git commit (`git describe --always --dirty`) when it is in a repository.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commit: Option<String>,
    /// When the run started, UTC, RFC 3339 (`2026-11-22T13:24:34Z`).
    #[serde(default)]
    pub date: String,
    /// Each backend of the run, with what it says of itself.
    pub backends: Vec<BackendInfo>,
    /// Whether a signal stopped the run before every trial finished.
    pub interrupted: bool,
    /// Why the run stopped before every trial finished (`interrupted`, `fail-fast`), when it
    /// did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<super::Stopped>,
    /// How long the run took, wall clock, in seconds (the trials' own times add up to less
    /// when backends run side by side, and to nothing measurable for the built-in models).
    #[serde(default)]
    pub seconds: f64,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(crate) struct BackendInfo {
    pub name: String,
    pub description: String,
    /// What the backend is and its version, when it says (`pymcprotocol 0.3.0`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub version: Option<String>,
}

#[derive(Serialize)]
struct Document<'a> {
    format: &'static str,
    version: u32,
    run: &'a RunInfo,
    summary: &'a Summary,
    records: &'a [Record],
    sections: &'a [Section<'a>],
}

pub(crate) fn render(
    records: &[Record],
    sections: &[Section<'_>],
    summary: &Summary,
    run: &RunInfo,
) -> String {
    serde_json::to_string_pretty(&Document {
        format: FORMAT,
        version: VERSION,
        run,
        summary,
        records,
        sections,
    })
    .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
