//! Results as a matrix: rows are cases, columns are backends (or, for cross-vendor cases, a
//! backend's lowering), and rows whose cells behave the same across every column are grouped, so
//! that hundreds of cases collapse into the handful of real behaviours.

use std::collections::BTreeMap;

use serde::Serialize;

use super::record::{Behaviour, Record};
use crate::judge::Status;

/// Rows that behave alike: one representative, and how many rows share its behaviour.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Group<'a> {
    /// The behaviour in each column (`None` where the row has no cell).
    pub behaviour: Vec<Option<&'a Behaviour>>,
    /// The status in each column: rows that behave alike but of which one fails and another
    /// only records (an `unspecified` case) are not one group, so a failure is never hidden
    /// behind a representative that cannot fail.
    pub status: Vec<Option<Status>>,
    pub rows: Vec<&'a str>,
    /// The representative row's cells, by column.
    pub cells: Vec<Option<&'a Record>>,
}

/// One matrix.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Section<'a> {
    pub name: &'a str,
    pub columns: Vec<&'a str>,
    pub groups: Vec<Group<'a>>,
    pub rows: usize,
}

/// Arranges records into matrices, grouping rows by identical behaviour. Sections, columns and
/// groups keep the order in which they first appear.
pub(crate) fn sections(records: &[Record]) -> Vec<Section<'_>> {
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
                let behaviour: Vec<Option<&Behaviour>> =
                    row_cells.iter().map(|c| c.map(|r| &r.behaviour)).collect();
                let status: Vec<Option<Status>> =
                    row_cells.iter().map(|c| c.map(|r| r.status)).collect();
                match groups
                    .iter_mut()
                    .find(|g| g.behaviour == behaviour && g.status == status)
                {
                    Some(g) => g.rows.push(row),
                    None => groups.push(Group {
                        behaviour,
                        status,
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
    use crate::judge::Status;
    use crate::model::cross_vendor::ErrorClass;
    use crate::model::Basis;
    use crate::report::record::AnswerClass;

    fn record(row: &str, column: &str, behaviour: &str) -> Record {
        let class = match behaviour {
            "plain answer" => AnswerClass::Plain,
            _ => AnswerClass::Error(ErrorClass::InvalidDigit),
        };
        Record {
            section: "s".into(),
            row: row.into(),
            column: column.into(),
            trial: format!("{column}::{row}"),
            file: "f.yaml".into(),
            line: 1,
            basis: Basis::Manual,
            status: Status::Pass,
            label: "conforms".into(),
            behaviour: Behaviour::Answer { class },
            shown: behaviour.into(),
            detail: String::new(),
            seconds: std::time::Duration::ZERO,
            verdict: None,
        }
    }

    #[test]
    fn a_failing_row_is_not_grouped_behind_one_that_cannot_fail() {
        let mut recorded = record("r1", "a", "invalid-digit");
        recorded.status = Status::Ignored;
        let mut failing = record("r2", "a", "invalid-digit");
        failing.status = Status::Fail;
        let records = vec![recorded, failing];
        let s = sections(&records);
        assert_eq!(s[0].groups.len(), 2);
        let failing_group = &s[0].groups[1];
        assert_eq!(failing_group.rows, ["r2"]);
        assert_eq!(failing_group.cells[0].map(|r| r.status), Some(Status::Fail));
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
            .map(|g| {
                let shown = g
                    .behaviour
                    .iter()
                    .map(|b| b.map_or_else(|| "n/a".to_string(), ToString::to_string))
                    .collect();
                (g.rows.clone(), shown)
            })
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
