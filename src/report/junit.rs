//! JUnit XML for CI dashboards: one test suite per matrix section and column, one test case per
//! cell. Failing cells carry their explanation; skipped and recorded cells are skipped with a
//! reason, never reported as passing.

use std::collections::BTreeMap;

use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};

use super::record::Record;
use super::sanitize::xml;
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
        let mut suite = TestSuite::new(xml(&format!("{section} / {column}")).into_owned());
        for r in cells {
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
            let mut case = TestCase::new(xml(&r.trial).into_owned(), status);
            case.set_classname(xml(&format!("{}:{}", r.file, r.line)).into_owned());
            suite.add_test_case(case);
        }
        report.add_test_suite(suite);
    }
    report
        .to_string()
        .unwrap_or_else(|e| format!("<!-- cannot write JUnit XML: {e} -->"))
}
