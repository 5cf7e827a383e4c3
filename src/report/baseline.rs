//! Saved runs and run-to-run comparison, so that CI can fail only on new differences.
//!
//! A saved run is the JSON report (`{"format": "plc-conformance-results", "version": 2,
//! "records": [...], ...}`, see [`super::json`]) with one [`Record`] per trial. Records are
//! matched by trial name and compared by status and structured behaviour, never by the text
//! shown, so rewording a message does not change what counts as new.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::json::{FORMAT, VERSION};
use super::record::{Behaviour, Record};

/// The part of a JSON report a baseline needs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct SavedRun {
    pub format: String,
    pub version: u32,
    /// What ran (the backends and their versions): what the results table names.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<super::json::RunInfo>,
    pub records: Vec<Record>,
}

/// Why a saved run could not be read.
#[derive(Debug)]
pub(crate) struct BaselineError {
    pub path: String,
    pub message: String,
    /// The read or parse error underneath, when there is one.
    pub source: Option<Box<dyn std::error::Error + Send + Sync>>,
}

impl fmt::Display for BaselineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

impl std::error::Error for BaselineError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.source.as_deref().map(|e| e as _)
    }
}

pub(crate) fn load(path: &Path) -> Result<SavedRun, BaselineError> {
    let error = |message: String| BaselineError {
        path: path.display().to_string(),
        message,
        source: None,
    };
    let caused = |message: &str, e: Box<dyn std::error::Error + Send + Sync>| BaselineError {
        source: Some(e),
        ..error(message.to_string())
    };
    // A FIFO or a device given as a baseline is refused rather than read (it could block or
    // never end).
    let bytes = crate::load::read_regular(path).map_err(|e| caused("cannot be read", e.into()))?;
    let text = String::from_utf8(bytes).map_err(|e| caused("not a saved run", e.into()))?;
    // The format and version are read first, so that a run saved by another version is told
    // apart from a damaged file.
    let head: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        let at = format!("not a saved run (line {}, column {})", e.line(), e.column());
        caused(&at, e.into())
    })?;
    let format = head.get("format").and_then(|f| f.as_str()).unwrap_or("");
    let version = head.get("version").and_then(|v| v.as_u64()).unwrap_or(0);
    if format != FORMAT || version != u64::from(VERSION) {
        return Err(error(format!(
            "format `{format}` version {version} is not `{FORMAT}` version {VERSION}; save the \
             baseline again with this version (`--save FILE`)"
        )));
    }
    let run: SavedRun =
        serde_json::from_value(head).map_err(|e| caused("not a saved run", e.into()))?;
    Ok(run)
}

/// What changed between two runs.
#[derive(Debug, Default, Serialize)]
pub(crate) struct Changes<'a> {
    /// Failing now, and passing (or absent) before.
    pub new: Vec<&'a Record>,
    /// Failing before, passing now.
    pub fixed: Vec<(&'a Record, &'a Record)>,
    /// Differing both times (failing, or a listed known difference), but not in the same way:
    /// another status, behaviour or answer.
    pub changed: Vec<(&'a Record, &'a Record)>,
    /// Differing both times in the same way.
    pub unchanged: usize,
}

/// A trial that does not conform: it fails, or its difference is a known one.
fn differs(r: &Record) -> bool {
    r.status.is_failure() || matches!(r.behaviour, Behaviour::Known { .. })
}

/// The same outcome: status, behaviour, and the answer as shown and explained (`5A8DH` and
/// `508DH` are both wrong words, but not the same answer).
fn same(a: &Record, b: &Record) -> bool {
    a.status == b.status && a.behaviour == b.behaviour && a.shown == b.shown && a.detail == b.detail
}

pub(crate) fn compare<'a>(before: &'a [Record], now: &'a [Record]) -> Changes<'a> {
    let old: BTreeMap<&str, &Record> = before.iter().map(|r| (r.trial.as_str(), r)).collect();
    let mut changes = Changes::default();
    for r in now {
        let was = old.get(r.trial.as_str()).copied();
        let failed_before = was.is_some_and(|w| w.status.is_failure());
        match (failed_before, r.status.is_failure()) {
            (false, true) => changes.new.push(r),
            (true, false) => changes.fixed.push((was.unwrap_or(r), r)),
            (true, true) => match was {
                Some(w) if same(w, r) => changes.unchanged += 1,
                Some(w) => changes.changed.push((w, r)),
                None => changes.new.push(r),
            },
            // A known difference both times is still a difference: its answer may change.
            (false, false) => match was {
                Some(w) if differs(w) && differs(r) => {
                    if same(w, r) {
                        changes.unchanged += 1;
                    } else {
                        changes.changed.push((w, r));
                    }
                }
                _ => {}
            },
        }
    }
    changes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::judge::Status;
    use crate::model::Basis;

    fn r(trial: &str, status: Status, shown: &str) -> Record {
        let behaviour = match shown {
            "ok" => Behaviour::Conforms,
            "x" => Behaviour::WrongWords,
            "timeout" => Behaviour::Fault {
                kind: "timeout".into(),
            },
            _ => Behaviour::Unsupported,
        };
        Record {
            section: "s".into(),
            row: trial.into(),
            column: "c".into(),
            trial: trial.into(),
            file: "f".into(),
            line: 1,
            basis: Basis::Manual,
            status,
            label: shown.into(),
            behaviour,
            shown: shown.into(),
            detail: String::new(),
            seconds: std::time::Duration::ZERO,
            verdict: None,
        }
    }

    #[test]
    fn sorts_new_fixed_and_changed() {
        let before = vec![
            r("a", Status::Pass, "ok"),
            r("b", Status::Fail, "x"),
            r("c", Status::Fail, "x"),
            r("d", Status::Fail, "x"),
        ];
        let now = vec![
            r("a", Status::Fail, "x"),
            r("b", Status::Pass, "ok"),
            r("c", Status::Fail, "y"),
            r("d", Status::Fail, "x"),
            r("e", Status::Fail, "timeout"),
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

    #[test]
    fn another_answer_of_the_same_kind_is_a_change() {
        let known = |shown: &str| Record {
            status: Status::Ignored,
            behaviour: Behaviour::Known {
                difference: Box::new(Behaviour::WrongWords),
            },
            ..r("k", Status::Ignored, shown)
        };
        let before = vec![r("w", Status::Fail, "x"), known("5A8DH")];
        let mut wrong = r("w", Status::Fail, "x");
        wrong.detail = "D200 508DH".into();
        let now = vec![wrong, known("508DH")];
        let c = compare(&before, &now);
        let changed: Vec<&str> = c.changed.iter().map(|(_, r)| r.trial.as_str()).collect();
        assert_eq!(changed, ["w", "k"]);
        assert_eq!(c.unchanged, 0);
        assert!(compare(&before, &before).changed.is_empty());
        assert_eq!(compare(&before, &before).unchanged, 2);
    }
}
