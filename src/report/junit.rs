//! JUnit XML for CI dashboards: one test suite per backend, one test case per trial with
//! `classname` = `backend.instruction` (or `backend.cross-vendor`), so that dashboards group
//! results by backend and instruction; the test's name is the case and variant, and `file` and
//! `line` point at the vector. Failing trials carry their explanation; skipped and recorded
//! trials are skipped with a reason, never reported as passing.

use std::time::Duration;

use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};

use super::record::Record;
use super::sanitize::xml;
use crate::judge::Status;

/// The backend, the class (`backend.instruction` or `backend.cross-vendor`) and the test name
/// of a record, from its trial name (`backend::instruction::case::variant`,
/// `cross-vendor::backend::lowering::case::variant` or `cross-vendor::backend::codec::case`).
fn names(record: &Record) -> (String, String, String) {
    let parts: Vec<&str> = record.trial.split("::").collect();
    match parts.as_slice() {
        ["protocol", backend, protocol, rest @ ..] => (
            backend.to_string(),
            format!("{backend}.protocol.{protocol}"),
            rest.join("::"),
        ),
        ["cross-vendor", backend, rest @ ..] => {
            // The case first, then how it was asked: `case::lowering::variant`.
            let name = match rest {
                [lowering, case, tail @ ..] => {
                    let mut n = vec![*case, *lowering];
                    n.extend(tail);
                    n.join("::")
                }
                _ => rest.join("::"),
            };
            (backend.to_string(), format!("{backend}.cross-vendor"), name)
        }
        [backend, instruction, rest @ ..] => (
            backend.to_string(),
            format!("{backend}.{instruction}"),
            rest.join("::"),
        ),
        _ => (
            record.column.clone(),
            record.column.clone(),
            record.trial.clone(),
        ),
    }
}

/// A record with its class and test name.
type Named<'a> = (&'a Record, String, String);

/// `meta.seconds`, the run's wall time, is the report's time: the trials' own times are their
/// batches' shares, and the built-in models answer in microseconds.
pub(crate) fn render(records: &[Record], meta: &super::json::RunInfo) -> String {
    // Suites keep the order in which their backends first appear.
    let mut suites: Vec<(String, Vec<Named<'_>>)> = Vec::new();
    for r in records {
        let (backend, class, name) = names(r);
        match suites.iter_mut().find(|(b, _)| *b == backend) {
            Some((_, cases)) => cases.push((r, class, name)),
            None => suites.push((backend, vec![(r, class, name)])),
        }
    }
    let mut report = Report::new("plc-conformance");
    for (backend, cases) in suites {
        let mut suite = TestSuite::new(xml(&backend).into_owned());
        let mut time = Duration::ZERO;
        for (r, class, name) in cases {
            let status = match r.status {
                Status::Pass => TestCaseStatus::success(),
                Status::Skipped | Status::Ignored => {
                    let mut s = TestCaseStatus::skipped();
                    s.set_message(xml(&format!("{}: {}", r.label, r.shown)).into_owned());
                    s
                }
                Status::Fail => {
                    let mut s = TestCaseStatus::non_success(NonSuccessKind::Failure);
                    s.set_message(xml(&format!("{}: {}", r.label, r.shown)).into_owned());
                    s.set_type(xml(&r.label).into_owned());
                    s.set_description(xml(&r.detail).into_owned());
                    s
                }
            };
            let mut case = TestCase::new(xml(&name).into_owned(), status);
            case.set_classname(xml(&class).into_owned());
            case.set_time(r.seconds);
            // A vector built into the binary is no file a dashboard can open.
            if !r.file.starts_with(crate::load::EMBEDDED) {
                case.extra
                    .insert("file".into(), xml(&r.file).into_owned().into());
            }
            case.extra.insert("line".into(), r.line.to_string().into());
            time += r.seconds;
            suite.add_test_case(case);
        }
        suite.set_time(time);
        report.add_test_suite(suite);
    }
    report.set_time(Duration::from_secs_f64(meta.seconds.max(0.0)));
    report
        .to_string()
        .unwrap_or_else(|e| format!("<!-- cannot write JUnit XML: {e} -->"))
}
