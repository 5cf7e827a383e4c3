//! Results as a matrix: rows are cases, columns are backends (or, for cross-vendor cases, a
//! backend's lowering), and rows whose cells behave the same across every column are grouped, so
//! that hundreds of cases collapse into the handful of real behaviours.
//!
//! A [`Record`] is one cell with everything a report needs; records are also what a saved run
//! holds, so a later run can be compared with it (see [`crate::baseline`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::compare::Verdict;
use crate::model::{error_text, Basis};
use crate::neutral::lower::{NeutralTrial, NeutralVerdict};
use crate::neutral::NeutralOutcome;
use crate::plan::Trial;
use crate::report::text::{render, Palette};

/// How one cell came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    Conforms,
    Differs,
    Unsupported,
    Crashed,
    Timeout,
    ProtocolError,
    Unreachable,
    Recorded,
    Skipped,
    /// A difference the backend's known-differences file lists, with its reason.
    KnownDifference,
    /// A listed known difference that now conforms: the list is out of date.
    StaleEntry,
}

impl Status {
    /// Whether this cell fails a run.
    pub fn is_failure(self) -> bool {
        !matches!(
            self,
            Status::Conforms | Status::Recorded | Status::Skipped | Status::KnownDifference
        )
    }

    pub fn label(self) -> &'static str {
        match self {
            Status::Conforms => "conforms",
            Status::Differs => "differs",
            Status::Unsupported => "unsupported",
            Status::Crashed => "crashed",
            Status::Timeout => "timeout",
            Status::ProtocolError => "protocol-error",
            Status::Unreachable => "unreachable",
            Status::Recorded => "recorded",
            Status::Skipped => "skipped",
            Status::KnownDifference => "known-difference",
            Status::StaleEntry => "stale-entry",
        }
    }

    fn from_label(label: &str) -> Status {
        match label {
            "conforms" => Status::Conforms,
            "differs" => Status::Differs,
            "unsupported" => Status::Unsupported,
            "crashed" => Status::Crashed,
            "timeout" => Status::Timeout,
            "protocol-error" => Status::ProtocolError,
            "recorded" => Status::Recorded,
            "known-difference" => Status::KnownDifference,
            "stale-entry" => Status::StaleEntry,
            "unreachable" => Status::Unreachable,
            // Every verdict label is listed above; a new one shows as a failure until it is.
            _ => Status::Differs,
        }
    }
}

/// One cell of the matrix.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Record {
    /// A profile id for native cases, `cross-vendor <operation>` for neutral ones.
    pub section: String,
    /// The case (native: `instruction::case-id::variant`).
    pub row: String,
    /// The backend (cross-vendor: `backend/lowering`).
    pub column: String,
    /// The trial name, as `cargo test` shows it.
    pub trial: String,
    pub file: String,
    pub line: usize,
    pub basis: Basis,
    pub status: Status,
    /// What rows are grouped by: cells with the same behaviour in every column group together.
    pub behaviour: String,
    /// What the cell shows.
    pub shown: String,
    /// The full explanation of a failing or recorded cell (a diff, a fault, a reason).
    pub detail: String,
}

/// Native trials and their verdicts (`None` for a skipped trial, as
/// [`crate::session::Session::run_all`] gives them) as records.
pub fn native_records(trials: &[Trial], verdicts: Vec<Option<Verdict>>) -> Vec<Record> {
    trials
        .iter()
        .zip(verdicts)
        .map(|(t, verdict)| {
            let base = |status: Status, behaviour: String, shown: String, detail: String| Record {
                section: t.profile.id.clone(),
                row: format!(
                    "{}::{}::{}",
                    t.instruction.to_lowercase(),
                    t.case.id,
                    t.variant
                ),
                column: t.backend.name().to_string(),
                trial: t.name(),
                file: t.case.location.file.display().to_string(),
                line: t.case.location.line,
                basis: t.case.basis,
                status,
                behaviour,
                shown,
                detail,
            };
            let Some(verdict) = verdict else {
                let reason = t.skip.clone().unwrap_or_default();
                return base(Status::Skipped, "skipped".into(), "skipped".into(), reason);
            };
            let detail = match verdict {
                Verdict::Conforms => String::new(),
                ref v => render(t, v, Palette::plain()),
            };
            let (behaviour, shown) = match &verdict {
                Verdict::Conforms => ("conforms".to_string(), "ok".to_string()),
                Verdict::Differs { mismatches } => {
                    let m = &mismatches[0];
                    let what = if m.error_differs() {
                        format!(
                            "error {} instead of {}",
                            error_text(m.actual_error.as_ref()),
                            error_text(m.expected_error.as_ref())
                        )
                    } else {
                        "wrong words".to_string()
                    };
                    (format!("differs: {what}"), what)
                }
                Verdict::Recorded { observed, .. } => {
                    (format!("recorded: {observed}"), observed.clone())
                }
                other => (other.label().to_string(), other.label().to_string()),
            };
            base(
                Status::from_label(verdict.label()),
                behaviour,
                shown,
                detail,
            )
        })
        .collect()
}

/// Cross-vendor trials and their verdicts (`None` for a skipped trial) as records.
pub fn neutral_records(
    trials: &[NeutralTrial],
    verdicts: Vec<Option<NeutralVerdict>>,
) -> Vec<Record> {
    trials
        .iter()
        .zip(verdicts)
        .map(|(t, verdict)| {
            let column = format!("{}/{}", t.backend.name(), t.lowering.name);
            let mut record = Record {
                section: format!("cross-vendor {}", t.case.operation),
                row: t.case.id.clone(),
                column,
                trial: t.name(),
                file: t.case.location.file.display().to_string(),
                line: t.case.location.line,
                basis: t.case.basis,
                status: Status::Skipped,
                behaviour: "skipped".into(),
                shown: "skipped".into(),
                detail: t.skip.clone().unwrap_or_default(),
            };
            let Some(verdict) = verdict else {
                return record;
            };
            record.status = match &verdict {
                NeutralVerdict::Matches { .. } => Status::Conforms,
                NeutralVerdict::Differs { .. } | NeutralVerdict::FillDependent { .. } => {
                    Status::Differs
                }
                NeutralVerdict::Unsupported { .. } => Status::Unsupported,
                NeutralVerdict::Recorded { .. } => Status::Recorded,
                NeutralVerdict::KnownDifference { .. } => Status::KnownDifference,
                NeutralVerdict::StaleEntry { .. } => Status::StaleEntry,
                NeutralVerdict::Fault { fault } => Status::from_label(
                    Verdict::Fault {
                        fill: crate::memory::Fill::A,
                        fault: fault.clone(),
                    }
                    .label(),
                ),
            };
            match verdict.outcome() {
                Some(outcome) => {
                    record.behaviour = behaviour_of(outcome, t.case.expect.as_ref());
                    record.shown = outcome.to_string();
                }
                None => {
                    record.behaviour = record.status.label().to_string();
                    record.shown = record.status.label().to_string();
                }
            }
            if record.status != Status::Conforms {
                record.detail = format!(
                    "{}:{}: {} ({})\n  {}",
                    record.file,
                    record.line,
                    record.trial,
                    t.lowering.description,
                    verdict.describe()
                );
            }
            record
        })
        .collect()
}

/// A neutral outcome as a behaviour: the plain answer, another answer, or an error class.
fn behaviour_of(outcome: &NeutralOutcome, plain: Option<&NeutralOutcome>) -> String {
    match outcome {
        NeutralOutcome::Error(class) => class.to_string(),
        NeutralOutcome::OtherError(e) => format!("error {e}"),
        o if Some(o) == plain => "plain answer".to_string(),
        NeutralOutcome::Value(_) => "other value".to_string(),
        NeutralOutcome::Text(_) => "other text".to_string(),
    }
}

/// Rows that behave alike: one representative, and how many rows share its behaviour.
#[derive(Debug, Clone, Serialize)]
pub struct Group<'a> {
    /// The behaviour in each column (`n/a` where the row has no cell).
    pub behaviour: Vec<String>,
    pub rows: Vec<&'a str>,
    /// The representative row's cells, by column.
    pub cells: Vec<Option<&'a Record>>,
}

/// One matrix.
#[derive(Debug, Clone, Serialize)]
pub struct Section<'a> {
    pub name: &'a str,
    pub columns: Vec<&'a str>,
    pub groups: Vec<Group<'a>>,
    pub rows: usize,
}

/// Arranges records into matrices, grouping rows by identical behaviour. Sections, columns and
/// groups keep the order in which they first appear.
pub fn sections(records: &[Record]) -> Vec<Section<'_>> {
    let mut names: Vec<&str> = Vec::new();
    for r in records {
        if !names.contains(&r.section.as_str()) {
            names.push(&r.section);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mine: Vec<&Record> = records.iter().filter(|r| r.section == name).collect();
            let mut columns: Vec<&str> = Vec::new();
            let mut rows: Vec<&str> = Vec::new();
            let mut cells: BTreeMap<(&str, &str), &Record> = BTreeMap::new();
            for r in &mine {
                if !columns.contains(&r.column.as_str()) {
                    columns.push(&r.column);
                }
                if !rows.contains(&r.row.as_str()) {
                    rows.push(&r.row);
                }
                cells.insert((r.row.as_str(), r.column.as_str()), r);
            }
            let mut groups: Vec<Group> = Vec::new();
            for row in &rows {
                let row_cells: Vec<Option<&Record>> = columns
                    .iter()
                    .map(|c| cells.get(&(*row, *c)).copied())
                    .collect();
                let behaviour: Vec<String> = row_cells
                    .iter()
                    .map(|c| c.map_or_else(|| "n/a".to_string(), |r| r.behaviour.clone()))
                    .collect();
                match groups.iter_mut().find(|g| g.behaviour == behaviour) {
                    Some(g) => g.rows.push(row),
                    None => groups.push(Group {
                        behaviour,
                        rows: vec![row],
                        cells: row_cells,
                    }),
                }
            }
            Section {
                name,
                columns,
                rows: rows.len(),
                groups,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(row: &str, column: &str, behaviour: &str) -> Record {
        Record {
            section: "s".into(),
            row: row.into(),
            column: column.into(),
            trial: format!("{column}::{row}"),
            file: "f.yaml".into(),
            line: 1,
            basis: Basis::Manual,
            status: Status::Conforms,
            behaviour: behaviour.into(),
            shown: behaviour.into(),
            detail: String::new(),
        }
    }

    #[test]
    fn rows_with_the_same_behaviour_in_every_column_group_together() {
        let records = vec![
            record("r1", "a", "plain answer"),
            record("r1", "b", "invalid-digit"),
            record("r2", "a", "plain answer"),
            record("r2", "b", "invalid-digit"),
            record("r3", "a", "plain answer"),
            record("r3", "b", "plain answer"),
            record("r4", "a", "plain answer"),
        ];
        let s = sections(&records);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].columns, vec!["a", "b"]);
        assert_eq!(s[0].rows, 4);
        let groups: Vec<(Vec<&str>, Vec<String>)> = s[0]
            .groups
            .iter()
            .map(|g| (g.rows.clone(), g.behaviour.clone()))
            .collect();
        assert_eq!(
            groups,
            vec![
                (
                    vec!["r1", "r2"],
                    vec!["plain answer".into(), "invalid-digit".into()]
                ),
                (
                    vec!["r3"],
                    vec!["plain answer".into(), "plain answer".into()]
                ),
                (vec!["r4"], vec!["plain answer".into(), "n/a".into()]),
            ]
        );
    }
}
