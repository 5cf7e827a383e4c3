//! The results table (`plc-conformance results`, `docs/results.md`): made from saved runs of
//! real codecs (a strict and a lenient Modbus ASCII codec here), each deviating cell linked to
//! its reproduction; refused when a listed library has no run; checked for staleness; and the
//! README's numbers are the committed table's own.

mod common;

use common::{cli, root, scratch};

/// Saves the run of the fixture Modbus ASCII codec in `mode` as `NAME.json` under `dir`.
fn saved_run(dir: &std::path::Path, name: &str, mode: &str) -> std::path::PathBuf {
    let script = root().join("tests/fixtures/external/modbus_ascii_codec.py");
    let backend = format!("external:{name}=python3 {} {mode}", script.display());
    let path = dir.join(format!("{name}.json"));
    let out = cli(&[
        "-q",
        "run",
        "--backend",
        &backend,
        "--format",
        "json",
        "--output",
        path.to_str().unwrap_or_default(),
    ]);
    // The lenient codec differs (1); nothing may go wrong beyond that.
    assert!(out.status.code().is_some_and(|c| c <= 1), "{out:?}");
    path
}

const LIBRARIES: &str = "libraries:
  - backend: strict
    package: strict-codec
    language: Python
    licence: MIT
    protocol: modbus-ascii
    wired: \"decode (modbus_ascii_codec.py)\"
  - backend: lenient
    package: lenient-codec
    language: Python
    licence: MIT
    protocol: modbus-ascii
    wired: \"bytes.fromhex (modbus_ascii_codec.py)\"
";

/// The table row of a library, split into its cells.
fn row<'a>(markdown: &'a str, package: &str) -> Vec<&'a str> {
    let line = markdown
        .lines()
        .find(|l| l.starts_with(&format!("| [{package}]")))
        .unwrap_or_else(|| panic!("no row for {package}:\n{markdown}"));
    line.split(" | ").collect()
}

#[test]
fn a_table_is_made_from_saved_runs_with_a_reproduction_per_deviation() {
    if !common::python() {
        return;
    }
    let dir = scratch();
    let strict = saved_run(dir.path(), "strict", "strict");
    let lenient = saved_run(dir.path(), "lenient", "fromhex");
    let list = dir.path().join("libraries.yaml");
    std::fs::write(&list, LIBRARIES).expect("write");
    let markdown = dir.path().join("results.md");
    let html = dir.path().join("results.html");
    let args = [
        "results",
        strict.to_str().unwrap_or_default(),
        lenient.to_str().unwrap_or_default(),
        "--libraries",
        list.to_str().unwrap_or_default(),
        "--markdown",
        markdown.to_str().unwrap_or_default(),
        "--html",
        html.to_str().unwrap_or_default(),
    ];
    let out = cli(&args);
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let text = std::fs::read_to_string(&markdown).expect("markdown written");
    // Columns: library, language, version, protocol, then digits, case written, case read,
    // blanks, sign and prefix, bytes above 7FH, short and long fields, order, check, answer.
    let strict_row = row(&text, "strict-codec");
    let lenient_row = row(&text, "lenient-codec");
    assert!(
        strict_row[4..].iter().all(|c| !c.contains('✗')),
        "{strict_row:?}"
    );
    assert!(strict_row[6].starts_with("? refuses"), "{strict_row:?}");
    assert!(lenient_row[6].starts_with("? accepts"), "{lenient_row:?}");
    // Blanks between pairs: bytes.fromhex skips them, against B3; not in a known-differences
    // file, so starred.
    assert!(
        lenient_row[7].starts_with("✗ ") && lenient_row[7].contains("[B3](#lenient-"),
        "{lenient_row:?}"
    );
    assert!(lenient_row[7].ends_with('*'), "{lenient_row:?}");
    let anchor = lenient_row[7]
        .split("](#")
        .nth(1)
        .and_then(|a| a.split(')').next())
        .unwrap_or_default();
    let reproduction = text
        .split(&format!("<a id=\"{anchor}\"></a>"))
        .nth(1)
        .unwrap_or_else(|| panic!("no reproduction {anchor}:\n{text}"));
    assert!(
        reproduction.contains("question:    hex-to-value"),
        "{reproduction}"
    );
    assert!(reproduction.contains("rule:        modbus-ascii/B3 (mbsl p.17"));
    assert!(
        text.contains("**2 libraries** (2 Python) in 2 rows: **1 deviate"),
        "{text}"
    );
    let page = std::fs::read_to_string(&html).expect("html written");
    assert!(page.contains(&format!("<pre id=\"{anchor}\">")), "{page}");

    // The files are what the runs give: --check passes, and fails once one is edited.
    let mut checking = args.to_vec();
    checking.push("--check");
    assert_eq!(cli(&checking).status.code(), Some(0));
    std::fs::write(&markdown, text.replacen("✓", "✗", 1)).expect("write");
    let stale = cli(&checking);
    assert_eq!(stale.status.code(), Some(1));
    let said = String::from_utf8_lossy(&stale.stderr);
    assert!(said.contains("is stale"), "{said}");
    assert!(
        said.contains("\n-") && said.contains("\n+"),
        "a diff: {said}"
    );

    // A listed library without a run is refused, not left out.
    let only_strict = cli(&[
        "results",
        strict.to_str().unwrap_or_default(),
        "--libraries",
        list.to_str().unwrap_or_default(),
        "--markdown",
        markdown.to_str().unwrap_or_default(),
    ]);
    assert_eq!(only_strict.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&only_strict.stderr).contains("no run given has backend `lenient`")
    );
}

#[test]
fn the_readme_counts_the_libraries_as_the_committed_table_does() {
    let table = std::fs::read_to_string(root().join("docs/results.md")).expect("docs/results.md");
    let summary = table
        .lines()
        .find(|l| l.starts_with("**") && l.contains(" libraries**"))
        .expect("the table's summary line");
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README");
    assert!(
        readme.contains(summary),
        "README.md does not carry the table's summary:\n{summary}"
    );
    // Every library of the list has its row.
    let list = std::fs::read_to_string(root().join("libraries.yaml")).expect("libraries.yaml");
    for backend in list
        .lines()
        .filter_map(|l| l.trim().strip_prefix("- backend: "))
    {
        assert!(
            table.contains(&format!("](#{backend}) |")),
            "no row for {backend} in docs/results.md"
        );
    }
}
