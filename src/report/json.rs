//! The JSON report of `plc-conformance run --format json`.
//!
//! Shape: `{ "summary": {passed, failed, recorded, skipped}, "trials": [ {name, backend,
//! profile, variant, instruction, case, basis, file, line, skipped?, verdict?} ] }`, where a
//! verdict is `{"verdict": "conforms" | "differs" | "unsupported" | "fault" | "recorded" |
//! "known_difference" | "stale_entry", ...}`; the summary also counts `known` differences.

use serde::Serialize;

use super::{Summary, TrialResult};
use crate::compare::Verdict;
use crate::model::Basis;

#[derive(Serialize)]
struct Record<'a> {
    name: String,
    backend: &'a str,
    profile: &'a str,
    variant: &'a str,
    instruction: &'a str,
    case: &'a str,
    basis: Basis,
    file: String,
    line: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    skipped: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    verdict: Option<&'a Verdict>,
}

#[derive(Serialize)]
struct Report<'a> {
    summary: Summary,
    trials: Vec<Record<'a>>,
}

/// Renders a run as pretty-printed JSON.
pub fn render(results: &[TrialResult]) -> String {
    let trials = results
        .iter()
        .map(|r| Record {
            name: r.trial.name(),
            backend: r.trial.backend.name(),
            profile: &r.trial.profile.id,
            variant: &r.trial.variant,
            instruction: &r.trial.instruction,
            case: &r.trial.case.id,
            basis: r.trial.case.basis,
            file: r.trial.case.location.file.display().to_string(),
            line: r.trial.case.location.line,
            skipped: r.trial.skip.as_deref(),
            verdict: r.verdict.as_ref(),
        })
        .collect();
    let report = Report {
        summary: Summary::of(results),
        trials,
    };
    serde_json::to_string_pretty(&report).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
