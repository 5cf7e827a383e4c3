//! `plc-conformance diff`: each report format parses or loads, the matrix groups rows, and a
//! saved run makes a later run fail only on new differences.

mod common;

use common::{cli, root, scratch, xml_elements};

#[test]
fn text_matrix_groups_rows_by_behaviour() {
    let out = cli(&["diff"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let header = text
        .lines()
        .find(|l| l.starts_with("mitsubishi-iqr: "))
        .expect("an iQ-R matrix");
    // Hundreds of cases collapse into a handful of behaviours.
    let numbers: Vec<usize> = header
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|n| n.parse().ok())
        .collect();
    assert!(numbers[0] >= 60 && numbers[1] < 20, "{header}");
    assert!(text.contains("cross-vendor hex-to-value: "), "{text}");
}

#[test]
fn json_report_has_matrices_and_records() {
    let out = cli(&["diff", "--format", "json"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["format"], "plc-conformance-results");
    assert_eq!(report["version"], 2);
    let records = report["records"].as_array().expect("records");
    let sections = report["sections"].as_array().expect("sections");
    assert!(!sections.is_empty());
    let grouped: u64 = sections
        .iter()
        .flat_map(|s| s["groups"].as_array().into_iter().flatten())
        .map(|g| g["rows"].as_array().map_or(0, |r| r.len() as u64))
        .sum();
    let rows: u64 = sections
        .iter()
        .map(|s| s["rows"].as_u64().unwrap_or(0))
        .sum();
    assert_eq!(grouped, rows, "every row is in exactly one group");
    for r in records {
        for key in [
            "section",
            "row",
            "column",
            "trial",
            "file",
            "line",
            "status",
            "behaviour",
            "shown",
        ] {
            assert!(r.get(key).is_some(), "record lacks {key}: {r}");
        }
    }
}

#[test]
fn junit_report_has_a_test_case_per_cell() {
    let json = cli(&["diff", "--format", "json"]);
    let report: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON");
    let records = report["records"].as_array().expect("records").len();
    let out = cli(&["diff", "--format", "junit"]);
    let elements = xml_elements(&String::from_utf8_lossy(&out.stdout));
    let cases = elements.iter().filter(|(n, _)| n == "testcase").count();
    assert_eq!(cases, records);
    assert!(elements.iter().any(|(n, _)| n == "testsuites"));
    assert!(
        elements.iter().any(|(n, _)| n == "skipped"),
        "recorded unspecified cells are skipped, not passed"
    );
}

#[test]
fn html_report_is_one_well_formed_file_with_the_matrices() {
    let scratch = scratch();
    let dir = scratch.path();
    let file = dir.join("report.html");
    let out = cli(&[
        "diff",
        "--format",
        "html",
        "--output",
        file.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let html = std::fs::read_to_string(&file).expect("report written");
    let body = html.trim_start_matches("<!DOCTYPE html>\n");
    let elements = xml_elements(body);
    let tables = elements
        .iter()
        .filter(|(n, a)| n == "table" && a.iter().any(|(k, v)| k == "class" && v == "matrix"))
        .count();
    assert!(tables >= 3, "one matrix per section");
    for (name, attrs) in &elements {
        assert!(
            !matches!(name.as_str(), "script" | "link" | "img" | "iframe"),
            "external or active content: {name}"
        );
        assert!(
            attrs.iter().all(|(k, _)| k != "src"),
            "a src attribute would load something"
        );
    }
}

#[test]
fn a_saved_run_fails_only_on_new_differences() {
    let scratch = scratch();
    let dir = scratch.path();
    let saved = dir.join("run.json");
    let out = cli(&[
        "diff",
        "--save",
        saved.to_str().unwrap_or_default(),
        "--output",
        dir.join("x.txt").to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let out = cli(&[
        "diff",
        "--baseline",
        saved.to_str().unwrap_or_default(),
        "--output",
        dir.join("y.txt").to_str().unwrap_or_default(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains(": 0 new, 0 fixed, 0 changed"));

    // A corpus in which one vector now disagrees with the model.
    let vectors = dir.join("vectors");
    std::fs::create_dir_all(vectors.join("mitsubishi-iqr")).expect("dir");
    let habin = std::fs::read_to_string(root().join("vectors/mitsubishi-iqr/habin.yaml"))
        .expect("habin.yaml");
    std::fs::write(
        vectors.join("mitsubishi-iqr/habin.yaml"),
        habin.replacen("after: {D200: 5A8DH}", "after: {D200: 5A8EH}", 1),
    )
    .expect("write");
    let out = cli(&[
        "diff",
        "--vectors",
        vectors.to_str().unwrap_or_default(),
        "--baseline",
        saved.to_str().unwrap_or_default(),
        "--output",
        dir.join("z.txt").to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "  new:     iqr::habin::habin-fixed-4-digits-example::rcpu (differs: wrong words)"
        ),
        "{err}"
    );
}

#[test]
fn against_finds_no_difference_between_a_model_and_itself_served() {
    let out = cli(&[
        "diff",
        "--backend",
        "iqr",
        "--against",
        "selfcheck-iqr",
        "--filter",
        "habin",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.trim_end().ends_with("trials compared, 0 differ"),
        "{text}"
    );
    assert!(!text.contains(" 0 trials compared"), "{text}");
}

#[test]
fn against_shows_the_word_diff_where_two_backends_differ() {
    if !root().join(".venv-adapters/bin/python").exists() {
        // CI sets PLC_CONFORMANCE_REQUIRE_BACKENDS after creating the environment.
        assert!(
            std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
            "pymcprotocol's virtual environment is required but missing"
        );
        eprintln!("skipped: pymcprotocol's virtual environment is missing (.ci/run creates it)");
        return;
    }
    let out = cli(&[
        "diff",
        "--backend",
        "iqr",
        "--against",
        "pymcprotocol",
        "--filter",
        "habin-fixed-minus-sign",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("pymcprotocol::habin::habin-fixed-minus-sign-is-invalid::rcpu differs"),
        "{text}"
    );
    assert!(text.contains("+D200     FA58H  \"X\\xFA\""), "{text}");
    assert!(
        text.contains("(basis: observed; backend iqr: its outcome on this trial)"),
        "{text}"
    );
    assert!(
        text.contains("error: expected 3401H, actual none"),
        "{text}"
    );
}

#[test]
fn a_bad_baseline_is_bad_input() {
    let scratch = scratch();
    let dir = scratch.path();
    let file = dir.join("run.json");
    std::fs::write(
        &file,
        "{\"format\": \"something-else\", \"version\": 1, \"records\": []}",
    )
    .expect("write");
    let out = cli(&["diff", "--baseline", file.to_str().unwrap_or_default()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("is not `plc-conformance-results`"));
}

/// Cross-vendor cells show each vendor's answer, conforming or not: the matrix is where the
/// vendors' differences are read.
#[test]
fn cross_vendor_cells_show_the_answers() {
    let out = cli(&[
        "diff",
        "--filter",
        "xv-h2v-5-digits",
        "--backend",
        "iqr",
        "--backend",
        "fx5",
        "--backend",
        "fc4a",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    let row = text
        .lines()
        .find(|l| l.contains("xv-h2v-5-digits"))
        .unwrap_or_else(|| panic!("{text}"));
    for answer in ["5A8DH", "5A8D1H", "error"] {
        assert!(row.contains(answer), "{row}");
    }
}
