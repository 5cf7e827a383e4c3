//! JUnit XML for CI dashboards: one test suite per matrix section and column, one test case per
//! cell. Failing cells carry their explanation; skipped and recorded cells are skipped with a
//! reason, never reported as passing.

use std::collections::BTreeMap;

use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};

use super::record::Record;
use crate::judge::Status;

pub fn render(records: &[Record]) -> String {
    let mut suites: BTreeMap<(String, String), Vec<&Record>> = BTreeMap::new();
    for r in records {
        suites
            .entry((r.section.clone(), r.column.clone()))
            .or_default()
            .push(r);
    }
    let mut report = Report::new("plc-conformance");
    for ((section, column), cells) in suites {
        let mut suite = TestSuite::new(format!("{section} / {column}"));
        for r in cells {
            let status = match r.status {
                Status::Pass => TestCaseStatus::success(),
                Status::Skipped | Status::Ignored => {
                    let mut s = TestCaseStatus::skipped();
                    s.set_message(format!("{}: {}", r.label, r.shown));
                    s
                }
                Status::Fail => {
                    let mut s = TestCaseStatus::non_success(NonSuccessKind::Failure);
                    s.set_message(format!("{}: {}", r.label, r.shown));
                    s.set_type(r.label.clone());
                    s.set_description(r.detail.clone());
                    s
                }
            };
            let mut case = TestCase::new(r.trial.clone(), status);
            case.set_classname(format!("{}:{}", r.file, r.line));
            suite.add_test_case(case);
        }
        report.add_test_suite(suite);
    }
    report
        .to_string()
        .unwrap_or_else(|e| format!("<!-- cannot write JUnit XML: {e} -->"))
}
