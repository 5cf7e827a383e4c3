//! Saved runs and run-to-run comparison, so that CI can fail only on new differences.
//!
//! A saved run is the JSON document `{"format": "plc-conformance-results", "version": 1,
//! "records": [...]}` with one [`Record`] per cell. Records are matched by trial name.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::matrix::Record;

pub const FORMAT: &str = "plc-conformance-results";
pub const VERSION: u32 = 1;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SavedRun {
    pub format: String,
    pub version: u32,
    pub records: Vec<Record>,
}

impl SavedRun {
    pub fn new(records: Vec<Record>) -> Self {
        SavedRun {
            format: FORMAT.into(),
            version: VERSION,
            records,
        }
    }
}

/// Why a saved run could not be read.
#[derive(Debug)]
pub struct BaselineError {
    pub path: String,
    pub message: String,
}

impl fmt::Display for BaselineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

impl std::error::Error for BaselineError {}

pub fn load(path: &Path) -> Result<SavedRun, BaselineError> {
    let error = |message: String| BaselineError {
        path: path.display().to_string(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| error(e.to_string()))?;
    let run: SavedRun = serde_json::from_str(&text).map_err(|e| {
        error(format!(
            "not a saved run (line {}, column {}): {e}",
            e.line(),
            e.column()
        ))
    })?;
    if run.format != FORMAT || run.version != VERSION {
        return Err(error(format!(
            "format `{}` version {} is not `{FORMAT}` version {VERSION}",
            run.format, run.version
        )));
    }
    Ok(run)
}

/// What changed between two runs.
#[derive(Debug, Default, Serialize)]
pub struct Changes<'a> {
    /// Failing now, and passing (or absent) before.
    pub new: Vec<&'a Record>,
    /// Failing before, passing now.
    pub fixed: Vec<(&'a Record, &'a Record)>,
    /// Failing both times, but not in the same way.
    pub changed: Vec<(&'a Record, &'a Record)>,
    /// Failing both times in the same way.
    pub unchanged: usize,
}

pub fn compare<'a>(before: &'a [Record], now: &'a [Record]) -> Changes<'a> {
    let old: BTreeMap<&str, &Record> = before.iter().map(|r| (r.trial.as_str(), r)).collect();
    let mut changes = Changes::default();
    for r in now {
        let was = old.get(r.trial.as_str()).copied();
        let failed_before = was.is_some_and(|w| w.status.is_failure());
        match (failed_before, r.status.is_failure()) {
            (false, true) => changes.new.push(r),
            (true, false) => changes.fixed.push((was.unwrap_or(r), r)),
            (true, true) => match was {
                Some(w)
                    if w.status == r.status && w.behaviour == r.behaviour && w.shown == r.shown =>
                {
                    changes.unchanged += 1
                }
                Some(w) => changes.changed.push((w, r)),
                None => changes.new.push(r),
            },
            (false, false) => {}
        }
    }
    changes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrix::Status;
    use crate::model::Basis;

    fn r(trial: &str, status: Status, shown: &str) -> Record {
        Record {
            section: "s".into(),
            row: trial.into(),
            column: "c".into(),
            trial: trial.into(),
            file: "f".into(),
            line: 1,
            basis: Basis::Manual,
            status,
            behaviour: shown.into(),
            shown: shown.into(),
            detail: String::new(),
        }
    }

    #[test]
    fn sorts_new_fixed_and_changed() {
        let before = vec![
            r("a", Status::Conforms, "ok"),
            r("b", Status::Differs, "x"),
            r("c", Status::Differs, "x"),
            r("d", Status::Differs, "x"),
        ];
        let now = vec![
            r("a", Status::Differs, "x"),
            r("b", Status::Conforms, "ok"),
            r("c", Status::Differs, "y"),
            r("d", Status::Differs, "x"),
            r("e", Status::Timeout, "timeout"),
        ];
        let c = compare(&before, &now);
        let names = |v: &[&Record]| v.iter().map(|r| r.trial.clone()).collect::<Vec<_>>();
        assert_eq!(names(&c.new), vec!["a", "e"]);
        assert_eq!(c.fixed.len(), 1);
        assert_eq!(c.fixed[0].1.trial, "b");
        assert_eq!(c.changed.len(), 1);
        assert_eq!(c.changed[0].1.trial, "c");
        assert_eq!(c.unchanged, 1);
    }
}
