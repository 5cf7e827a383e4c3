//! Every report format from both `run` and `diff`, checked the way its readers check it: JUnit
//! XML against a JUnit schema, grouped by backend and instruction.

mod common;

use std::collections::BTreeSet;
use std::path::Path;

use common::{cli, root, scratch};
use quick_xml::events::Event;
use quick_xml::Reader;

/// Test cases as (classname, name, attributes, child element names).
type Case = (String, String, Vec<(String, String)>, Vec<String>);

fn junit_cases(xml: &str) -> Vec<Case> {
    let mut reader = Reader::from_str(xml);
    let mut cases: Vec<Case> = Vec::new();
    let mut inside = false;
    loop {
        let event = reader.read_event().expect("well-formed XML");
        let (element, empty) = match &event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) if e.name().as_ref() == b"testcase" => {
                inside = false;
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = String::from_utf8_lossy(element.name().as_ref()).into_owned();
        let attrs = common::xml_attributes(element);
        let get = |k: &str| {
            attrs
                .iter()
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
                .unwrap_or_default()
        };
        if name == "testcase" {
            cases.push((get("classname"), get("name"), attrs.clone(), Vec::new()));
            inside = !empty;
        } else if inside {
            if let Some(last) = cases.last_mut() {
                last.3.push(name);
            }
        }
    }
    cases
}

/// Validates with `xmllint` against the JUnit schema; CI has xmllint, elsewhere the check is
/// skipped with a note.
fn validate_with_xmllint(xml: &Path) {
    let schema = root().join("tests/fixtures/junit/junit.xsd");
    let out = std::process::Command::new("xmllint")
        .args(["--noout", "--schema"])
        .arg(&schema)
        .arg(xml)
        .output();
    match out {
        Ok(out) => assert!(
            out.status.success(),
            "the JUnit report does not validate:\n{}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(_) if std::env::var_os("CI").is_none() => {
            eprintln!("xmllint is not installed: the JUnit schema check is skipped");
        }
        Err(e) => panic!("CI must have xmllint (libxml2-utils): {e}"),
    }
}

#[test]
fn junit_from_run_validates_and_groups_by_backend_and_instruction() {
    let dir = scratch();
    let file = dir.path().join("run.xml");
    let out = cli(&[
        "run",
        "--backend",
        "iqr",
        "--backend",
        "fx5",
        "--format",
        "junit",
        "--output",
        file.to_str().unwrap_or_default(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    validate_with_xmllint(&file);
    let xml = std::fs::read_to_string(&file).expect("written");
    let cases = junit_cases(&xml);
    let classes: BTreeSet<&str> = cases.iter().map(|c| c.0.as_str()).collect();
    for class in [
        "iqr.habin",
        "iqr.dbinha",
        "iqr.cross-vendor",
        "fx5.hexa",
        "fx5.asci",
        "fx5.cross-vendor",
    ] {
        assert!(classes.contains(class), "no class {class} in {classes:?}");
    }
    assert!(
        classes.iter().all(|c| c.split('.').count() == 2),
        "{classes:?}"
    );
    let habin = cases
        .iter()
        .find(|c| c.0 == "iqr.habin" && c.1 == "habin-fixed-4-digits-example::rcpu")
        .expect("the HABIN example on rcpu");
    let attr = |k: &str| {
        habin
            .2
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.as_str())
    };
    assert!(
        attr("file").is_some_and(|f| f.ends_with("/vectors/mitsubishi-iqr/habin.yaml")),
        "{habin:?}"
    );
    assert!(attr("line").is_some_and(|l| l.parse::<usize>().is_ok_and(|l| l > 1)));
    assert!(attr("time").is_some_and(|t| t.parse::<f64>().is_ok()));
    let suites = xml.matches("<testsuite ").count();
    assert_eq!(suites, 2, "one suite per backend");
    // Unspecified cases are skipped with what was recorded, never passed.
    assert!(cases.iter().any(|c| c.3 == ["skipped"]));
}

#[test]
fn a_failing_trial_is_a_junit_failure_with_its_explanation() {
    let dir = scratch();
    std::fs::write(
        dir.path().join("wrong.yaml"),
        common::habin_example("report-wrong", "5A8EH"),
    )
    .expect("write");
    let file = dir.path().join("run.xml");
    for command in ["run", "diff"] {
        let out = cli(&[
            command,
            "--backend",
            "iqr",
            "--vectors",
            dir.path().join("wrong.yaml").to_str().unwrap_or_default(),
            "--format",
            "junit",
            "--output",
            file.to_str().unwrap_or_default(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{command}");
        validate_with_xmllint(&file);
        let xml = std::fs::read_to_string(&file).expect("written");
        let cases = junit_cases(&xml);
        assert_eq!(cases.len(), 2, "{command}: rcpu and rcpu-no-sm705");
        for case in &cases {
            assert_eq!(case.0, "iqr.habin");
            assert_eq!(case.3, ["failure"], "{command}: {case:?}");
        }
        assert!(xml.contains("-D200     5A8EH"), "{xml}");
        assert!(xml.contains("line=\"5\""), "{xml}");
    }
}

/// Errors of a JSON report against `schema/results.schema.json`, made strict: the schema lets
/// readers accept fields added later, but a field the report writes into an object marked
/// `x-closed` is a schema to update.
fn schema_errors(report: &serde_json::Value) -> Vec<String> {
    fn closed(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(map) => {
                if map.get("x-closed") == Some(&serde_json::Value::Bool(true)) {
                    map.insert("additionalProperties".into(), false.into());
                }
                map.values_mut().for_each(closed);
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(closed),
            _ => {}
        }
    }
    let text =
        std::fs::read_to_string(root().join("schema/results.schema.json")).expect("the schema");
    let mut schema: serde_json::Value = serde_json::from_str(&text).expect("the schema is JSON");
    closed(&mut schema);
    let validator = jsonschema::validator_for(&schema).expect("a valid draft-07 schema");
    validator
        .iter_errors(report)
        .map(|e| format!("{}: {e}", e.instance_path()))
        .take(10)
        .collect()
}

fn json_of(args: &[&str]) -> serde_json::Value {
    let out = cli(args);
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

#[test]
fn json_from_run_and_diff_follows_the_shipped_schema() {
    let dir = scratch();
    std::fs::write(
        dir.path().join("wrong.yaml"),
        common::habin_example("report-wrong", "5A8EH"),
    )
    .expect("write");
    let wrong = dir.path().join("wrong.yaml");
    let reports = [
        json_of(&["run", "--format", "json"]),
        json_of(&["diff", "--format", "json"]),
        json_of(&[
            "run",
            "--backend",
            "iqr",
            "--vectors",
            wrong.to_str().unwrap_or_default(),
            "--format",
            "json",
        ]),
    ];
    for report in &reports {
        let errors = schema_errors(report);
        assert!(errors.is_empty(), "{errors:#?}");
        assert_eq!(report["run"]["backends"][0]["name"], "iqr");
        assert!(report["run"]["backends"][0]["version"]
            .as_str()
            .is_some_and(|v| v.starts_with("plc-conformance ")));
    }
    // The failing run's words are in hex, and the schema holds them to it.
    let row = &reports[2]["records"][0]["verdict"]["difference"]["mismatches"][0]["rows"][0];
    assert_eq!(row["expected"], "5A8EH");
    assert_eq!(row["actual"], "5A8DH");
    let mut decimal = reports[2].clone();
    decimal["records"][0]["verdict"]["difference"]["mismatches"][0]["rows"][0]["actual"] =
        serde_json::json!(23181);
    assert!(!schema_errors(&decimal).is_empty());
}

#[test]
fn html_from_run_lists_failures_with_links_metadata_and_places() {
    let dir = scratch();
    std::fs::write(
        dir.path().join("wrong.yaml"),
        common::habin_example("report-wrong", "5A8EH"),
    )
    .expect("write");
    let file = dir.path().join("report.html");
    let out = cli(&[
        "run",
        "--backend",
        "iqr",
        "--vectors",
        dir.path().join("wrong.yaml").to_str().unwrap_or_default(),
        "--format",
        "html",
        "--output",
        file.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let html = std::fs::read_to_string(&file).expect("written");
    // The failures at the top, each linking to its explanation.
    let list = html
        .find("<ul id=\"failures\">")
        .expect("a list of failures");
    let first = html.find("<table class=\"matrix\"").expect("a matrix");
    assert!(list < first, "the failures come before the matrices");
    for i in 0..2 {
        assert!(
            html.contains(&format!("<a href=\"#failure-{i}\">")),
            "{html}"
        );
        assert!(
            html.contains(&format!("<section id=\"failure-{i}\">")),
            "{html}"
        );
    }
    // Run metadata, the legend, file:line of the cases, folded group members.
    for needle in [
        "<th>tool</th><td>plc-conformance ",
        "<th>date</th><td>",
        "<th>backend iqr</th><td>plc-conformance ",
        "<p class=\"legend\">",
        "wrong.yaml:5</span>",
        "<details><summary>",
        "<ul class=\"members\">",
    ] {
        assert!(html.contains(needle), "the report lacks {needle}:\n{html}");
    }
    // The project is a git checkout only where the repository is; then its commit shows.
    if root().join(".git").exists() {
        assert!(html.contains("<th>commit</th><td>"), "{html}");
    }
}

/// The shipped results schema is what `schema --kind results` prints, and it lets a reader of a
/// later report of the same version accept the fields added since.
#[test]
fn the_results_schema_is_printed_and_open_to_added_fields() {
    let out = cli(&["schema", "--kind", "results"]);
    assert_eq!(out.status.code(), Some(0));
    let printed: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let text =
        std::fs::read_to_string(root().join("schema/results.schema.json")).expect("the schema");
    let shipped: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(printed, shipped);
    let mut report = json_of(&[
        "run",
        "--backend",
        "iqr",
        "--format",
        "json",
        "--filter",
        "habin-fixed-4-digits-example",
    ]);
    report["added_later"] = serde_json::json!(1);
    report["records"][0]["added_later"] = serde_json::json!("x");
    let validator = jsonschema::validator_for(&shipped).expect("draft-07");
    assert!(validator.is_valid(&report));
    assert!(
        !schema_errors(&report).is_empty(),
        "the strict check sees the added field"
    );
}
