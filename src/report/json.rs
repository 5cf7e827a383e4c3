//! The JSON report of `plc-conformance run --format json`.
//!
//! Shape: `{ "summary": {passed, failed, recorded, skipped}, "trials": [ {name, backend,
//! profile, variant, instruction, case, basis, file, line, skipped?, verdict?} ] }`, where a
//! verdict is `{"verdict": "conforms" | "differs" | "unsupported" | "fault" | "recorded" |
//! "known_difference" | "stale_entry", ...}`; the summary also counts `known` differences.
//! Cross-vendor trials follow in `"cross_vendor": [ {name, backend, lowering, variant, case,
//! basis, file, line, skipped?, verdict?} ]`, a verdict being `{"verdict": "matches" | "differs"
//! | "fill_dependent" | "unsupported" | "fault" | "recorded" | "known_difference" |
//! "stale_entry", ...}`; the summary counts them too.

use serde::Serialize;

use super::{Summary, TrialResult};
use crate::compare::Verdict;
use crate::model::Basis;
use crate::neutral::lower::{NeutralTrial, NeutralVerdict};

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
struct NeutralRecord<'a> {
    name: String,
    backend: &'a str,
    lowering: &'a str,
    variant: &'a str,
    case: &'a str,
    basis: Basis,
    file: String,
    line: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    skipped: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    verdict: Option<&'a NeutralVerdict>,
}

#[derive(Serialize)]
struct Report<'a> {
    summary: Summary,
    trials: Vec<Record<'a>>,
    cross_vendor: Vec<NeutralRecord<'a>>,
}

/// Renders a run as pretty-printed JSON.
pub fn render(
    results: &[TrialResult],
    neutral: &[(NeutralTrial, Option<NeutralVerdict>)],
) -> String {
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
    let cross_vendor = neutral
        .iter()
        .map(|(t, v)| NeutralRecord {
            name: t.name(),
            backend: t.backend.name(),
            lowering: &t.lowering.name,
            variant: t.variant(),
            case: &t.case.id,
            basis: t.case.basis,
            file: t.case.location.file.display().to_string(),
            line: t.case.location.line,
            skipped: t.skip.as_deref(),
            verdict: v.as_ref(),
        })
        .collect();
    let mut summary = Summary::of(results);
    summary.add(&Summary::of_neutral(
        neutral.iter().map(|(_, v)| v.as_ref()),
    ));
    let report = Report {
        summary,
        trials,
        cross_vendor,
    };
    serde_json::to_string_pretty(&report).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
