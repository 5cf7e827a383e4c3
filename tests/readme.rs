//! The example outputs of the README and of `docs/` are real: each fenced `text` block whose
//! first line is `$ cargo run -q -- ARGS` (continued over lines ending in `\`) is run (the built binary with ARGS, from the repository root, without
//! colour and at the default width) and its output compared with the block. A line `...` in a
//! block stands for any number of lines, so a block may show an excerpt, and `[..]` within a
//! line for any text (a time, say).
//!
//! The exhaustive examples (a sweep of the whole space, or of ten thousand inputs or more) are a
//! test of their own, ignored under a plain `cargo test`: CI runs it with `-- --ignored`.
//!
//! Blocks that run the project's third-party backends need their installs (`.ci/run` makes
//! them); without `.venv-adapters` they are skipped with a note, unless
//! PLC_CONFORMANCE_REQUIRE_BACKENDS is set (as on CI).

mod common;

use common::{bin, root};

struct Example {
    line: usize,
    command: String,
    expected: Vec<String>,
}

fn examples(readme: &str) -> Vec<Example> {
    let lines: Vec<&str> = readme.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim_end() == "```text" {
            if let Some(first) = lines.get(i + 1).and_then(|l| l.strip_prefix("$ ")) {
                // A command may go on over lines ending in `\`, as in a shell.
                let mut command = first.to_string();
                let mut last = i + 1;
                while command.ends_with('\\') {
                    command.pop();
                    last += 1;
                    command.push_str(lines.get(last).map_or("", |l| l.trim_start()));
                }
                let start = last + 1;
                let end = (start..lines.len())
                    .find(|&j| lines[j].starts_with("```"))
                    .unwrap_or(lines.len());
                out.push(Example {
                    line: i + 2,
                    command,
                    expected: lines[start..end].iter().map(|l| l.to_string()).collect(),
                });
                i = end;
            }
        }
        i += 1;
    }
    out
}

/// Splits a command line as sh would for the simple quoting the README uses.
fn words(command: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut quote: Option<char> = None;
    let mut started = false;
    for c in command.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                started = true;
            }
            (None, ' ') => {
                if started || !word.is_empty() {
                    words.push(std::mem::take(&mut word));
                }
                started = false;
            }
            (None, c) => word.push(c),
        }
    }
    if started || !word.is_empty() {
        words.push(word);
    }
    words
}

/// Whether `actual` matches `expected`, where a `...` line stands for any lines.
fn matches(expected: &[String], actual: &[&str]) -> bool {
    let segments: Vec<&[String]> = expected.split(|l| l == "...").collect();
    let mut at = 0;
    for (i, segment) in segments.iter().enumerate() {
        let (first, last) = (i == 0, i == segments.len() - 1);
        if segment.is_empty() {
            continue;
        }
        let fits = |from: usize| {
            from + segment.len() <= actual.len()
                && segment
                    .iter()
                    .zip(&actual[from..])
                    .all(|(e, a)| line_matches(e.trim_end(), a.trim_end()))
        };
        let found = if first {
            fits(0).then_some(0)
        } else if last {
            let from = actual.len().checked_sub(segment.len());
            from.filter(|&f| f >= at && fits(f))
        } else {
            (at..actual.len()).find(|&f| fits(f))
        };
        match found {
            Some(f) => at = f + segment.len(),
            None => return false,
        }
        if first && last && at != actual.len() {
            return false;
        }
    }
    true
}

/// Whether `actual` is `expected`, where `[..]` stands for any text.
fn line_matches(expected: &str, actual: &str) -> bool {
    let pieces: Vec<&str> = expected.split("[..]").collect();
    let [first, middle @ .., last] = pieces.as_slice() else {
        return expected == actual;
    };
    let Some(mut rest) = actual.strip_prefix(first) else {
        return false;
    };
    for piece in middle {
        match rest.find(piece) {
            Some(i) => rest = &rest[i + piece.len()..],
            None => return false,
        }
    }
    rest.len() >= last.len() && rest.ends_with(last)
}

/// Whether a command runs backends of the project file (which need their installs).
fn needs_adapters(args: &[String]) -> bool {
    if !matches!(
        args.first().map(String::as_str),
        Some("run" | "diff" | "sweep")
    ) {
        return false;
    }
    let named: Vec<&String> = args
        .windows(2)
        .filter(|w| w[0] == "--backend" || w[0] == "--against")
        .map(|w| &w[1])
        .collect();
    (named.is_empty() && args[0] != "sweep")
        || named
            .iter()
            .any(|n| !matches!(n.as_str(), "iqr" | "fx5" | "fc4a"))
}

/// The README and every page of `docs/`: the files whose examples must be real.
fn documents() -> Vec<(String, String)> {
    let mut files = vec!["README.md".to_string()];
    let mut docs: Vec<String> = std::fs::read_dir(root().join("docs"))
        .expect("docs")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter_map(|p| Some(format!("docs/{}", p.file_name()?.to_str()?)))
        .collect();
    docs.sort();
    files.extend(docs);
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(root().join(&f)).expect("document");
            (f, text)
        })
        .collect()
}

/// Whether an example's command is one of the exhaustive ones: a sweep of the whole space, or
/// of ten thousand inputs or more (tens of seconds of CPU in the debug build).
fn exhaustive(args: &[String]) -> bool {
    let value = |flag: &str| {
        args.windows(2)
            .find(|w| w[0] == flag)
            .map(|w| w[1].as_str())
    };
    value("--generator") == Some("full")
        || value("--count").and_then(|c| c.parse::<u64>().ok()) >= Some(10_000)
}

#[test]
fn readme_examples_show_the_real_output() {
    check_examples(false);
}

#[test]
#[ignore = "exhaustive: the docs' whole-space and 20,000-input sweeps (CI runs it: -- --ignored)"]
fn the_exhaustive_examples_show_the_real_output() {
    check_examples(true);
}

/// Runs the examples that are `exhaustive` (or the others) and compares their output.
fn check_examples(exhaustive_ones: bool) {
    let documents = documents();
    let examples: Vec<(&str, Example)> = documents
        .iter()
        .flat_map(|(file, text)| examples(text).into_iter().map(move |e| (file.as_str(), e)))
        .collect();
    assert!(examples.len() >= 3, "the README has its examples");
    let adapters = root().join(".venv-adapters/bin/python").exists();
    let required = std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_some();
    let mut runnable = Vec::new();
    for (file, example) in &examples {
        let Some(rest) = example.command.strip_prefix("cargo run -q -- ") else {
            panic!(
                "{file}:{}: an example command starts with `cargo run -q -- `",
                example.line
            );
        };
        let args = words(rest);
        if exhaustive(&args) != exhaustive_ones {
            continue;
        }
        if needs_adapters(&args) && !adapters && !required {
            eprintln!(
                "skipped {file}:{} (`{}`): .venv-adapters is missing (.ci/run creates it)",
                example.line, example.command
            );
            continue;
        }
        runnable.push((*file, example, args));
    }
    assert!(
        !runnable.is_empty(),
        "no example to run (exhaustive: {exhaustive_ones})"
    );
    // The examples run side by side, each taking the next: the exhaustive ones are sweeps of
    // seconds.
    let next = std::sync::atomic::AtomicUsize::new(0);
    let stale = std::sync::Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some((file, example, args)) = runnable.get(i) else {
                    break;
                };
                let out = bin()
                    .current_dir(root())
                    .env_remove("COLUMNS")
                    .args(args)
                    .output()
                    .expect("the binary runs");
                let stdout = String::from_utf8_lossy(&out.stdout);
                let actual: Vec<&str> = stdout.trim_end_matches('\n').lines().collect();
                if !matches(&example.expected, &actual) {
                    stale.lock().expect("not poisoned").push((
                        i,
                        format!(
                            "{file}:{}: `{}` now prints:\n{stdout}",
                            example.line, example.command
                        ),
                    ));
                }
            });
        }
    });
    let mut stale = stale.into_inner().expect("not poisoned");
    stale.sort();
    let stale: Vec<String> = stale.into_iter().map(|(_, s)| s).collect();
    assert!(
        stale.is_empty(),
        "README examples differ from the real output:\n\n{}",
        stale.join("\n")
    );
}

#[test]
fn an_excerpt_matches_lines_in_order() {
    let e = |s: &str| s.lines().map(String::from).collect::<Vec<_>>();
    let actual = ["a", "b", "c", "d"];
    assert!(matches(&e("a\nb\nc\nd"), &actual));
    assert!(!matches(&e("a\nb\nc"), &actual));
    assert!(matches(&e("a\n...\nd"), &actual));
    assert!(matches(&e("...\nc\n...\n"), &actual));
    assert!(matches(&e("a\n...\nc\n..."), &actual));
    assert!(!matches(&e("a\n...\nb\n...\nb\n..."), &actual));
    assert!(!matches(&e("b\n..."), &actual));
    assert!(line_matches("swept in [..] s: 12", "swept in 4.5 s: 12"));
    assert!(line_matches("[..]", "anything"));
    assert!(!line_matches("swept in [..] s: 12", "swept in 4.5 s: 13"));
    assert!(!line_matches("a[..]a", "a"));
    assert_eq!(
        words(r#"run --backend 'external:x="$P" serve' --filter a"#),
        [
            "run",
            "--backend",
            r#"external:x="$P" serve"#,
            "--filter",
            "a"
        ]
    );
}

/// The corpus's case count by vector folder (`cross-vendor` included).
fn cases_by_folder() -> std::collections::BTreeMap<String, usize> {
    let project = common::session();
    let mut counted = std::collections::BTreeMap::<String, usize>::new();
    for case in &project.corpus.cases {
        let folder = case.location.file.parent().map(|p| p.to_path_buf());
        if let Some(name) = folder.as_ref().and_then(|p| p.file_name()) {
            *counted
                .entry(name.to_string_lossy().into_owned())
                .or_default() += 1;
        }
    }
    counted.insert("cross-vendor".into(), project.corpus.cross_vendor.len());
    counted.insert("protocols".into(), project.corpus.protocol_fields.len());
    counted
}

/// A count the docs give in prose ("`vectors/cross-vendor/` (57 cases)") is the corpus's.
#[test]
fn every_case_count_in_the_docs_is_the_corpus_s() {
    let counted = cases_by_folder();
    let mut seen = 0;
    for entry in std::fs::read_dir(root().join("docs")).expect("docs") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "md") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("doc");
        for (at, _) in text.match_indices("`vectors/") {
            let rest = &text[at + "`vectors/".len()..];
            let Some((folder, after)) = rest.split_once("/` (") else {
                continue;
            };
            if folder.contains(['`', ' ', '\n']) {
                continue; // another mention of a folder, with no count after it
            }
            let Some(count) = after
                .split_once(" cases)")
                .and_then(|(n, _)| n.parse::<usize>().ok())
            else {
                continue;
            };
            seen += 1;
            assert_eq!(
                Some(&count),
                counted.get(folder),
                "{}: `vectors/{folder}/` ({count} cases)",
                path.display()
            );
        }
    }
    assert!(seen > 0, "no case count found in docs/");
}

/// Each folder's cases by basis, as the families table writes them: `80 manual, 40 inferred,
/// 4 unspecified` (a basis no case has is left out).
fn bases_by_folder() -> std::collections::BTreeMap<String, String> {
    use plc_conformance::Basis;
    let project = common::session();
    let mut by = std::collections::BTreeMap::<String, [usize; 4]>::new();
    let slot = |b: Basis| match b {
        Basis::Manual => 0,
        Basis::Inferred => 1,
        Basis::Unspecified => 2,
        Basis::Observed => 3,
    };
    for case in &project.corpus.cases {
        let folder = case.location.file.parent().and_then(|p| p.file_name());
        if let Some(name) = folder {
            by.entry(name.to_string_lossy().into_owned()).or_default()[slot(case.basis)] += 1;
        }
    }
    for case in &project.corpus.cross_vendor {
        by.entry("cross-vendor".into()).or_default()[slot(case.basis)] += 1;
    }
    for case in &project.corpus.protocol_fields {
        by.entry("protocols".into()).or_default()[slot(case.basis)] += 1;
    }
    by.into_iter()
        .map(|(folder, n)| {
            let text = ["manual", "inferred", "unspecified", "observed"]
                .iter()
                .zip(n)
                .filter(|(_, n)| *n > 0)
                .map(|(name, n)| format!("{n} {name}"))
                .collect::<Vec<_>>()
                .join(", ");
            (folder, text)
        })
        .collect()
}

/// Every row of the README's families table names a vector folder, its case count and the
/// count of each basis (so that a reader sees each family's footing), and every vector folder
/// has a row: a count that goes stale, or a family left out, fails here.
#[test]
fn the_families_table_counts_every_family_s_cases() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let counted = cases_by_folder();
    let bases = bases_by_folder();
    let mut footing = std::collections::BTreeMap::<String, String>::new();
    let mut rows = std::collections::BTreeMap::<String, usize>::new();
    for line in readme.lines().filter(|l| l.starts_with("| ")) {
        let Some(at) = line.find("`vectors/") else {
            continue;
        };
        let rest = &line[at + "`vectors/".len()..];
        let Some((folder, after)) = rest.split_once("/`, ") else {
            continue;
        };
        let count: usize = after
            .split_whitespace()
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no case count in: {line}"));
        rows.insert(folder.to_string(), count);
        let basis = after
            .split_once(" cases (")
            .and_then(|(_, b)| b.split_once(')'))
            .map(|(b, _)| b.to_string())
            .unwrap_or_else(|| panic!("no count by basis in: {line}"));
        footing.insert(folder.to_string(), basis);
    }
    assert_eq!(
        rows, counted,
        "the README's families table (left) against the corpus (right)"
    );
    assert_eq!(
        footing, bases,
        "the README's families table's counts by basis (left) against the corpus (right)"
    );
}

/// How each family is named where the families are listed, by profile id.
const FAMILY_NAMES: &[(&str, &str)] = &[
    ("mitsubishi-iqr", "iQ-R"),
    ("mitsubishi-fx5", "FX5"),
    ("mitsubishi-fx3", "FX3"),
    ("idec-fc4a", "FC4A"),
    ("siemens-s7-1200", "S7-1200"),
    ("siemens-s7-200", "S7-200"),
    ("delta-dvp", "Delta DVP"),
    ("panasonic-fp", "Panasonic FP"),
    ("keyence-kv", "KEYENCE KV"),
    ("omron-cs-cj", "Omron"),
];

/// The first paragraph after a document's title.
fn first_paragraph(text: &str) -> String {
    (text
        .lines()
        .skip_while(|l| l.starts_with('#') || l.trim().is_empty()))
    .take_while(|l| !l.trim().is_empty())
    .collect::<Vec<_>>()
    .join(" ")
}

/// Wherever the families are listed — the README's opening, `--help`, the library guide's
/// opening, the families page — every family of `vendors/` is named.
#[test]
fn every_family_is_named_wherever_families_are_listed() {
    let ids: std::collections::BTreeSet<String> = std::fs::read_dir(root().join("vendors"))
        .expect("vendors")
        .filter_map(|e| {
            let path = e.ok()?.path();
            // vendors/protocols/ holds the communication protocols, no family.
            (!path.is_dir()).then_some(())?;
            Some(path.file_stem()?.to_str()?.to_string())
        })
        .collect();
    let named: std::collections::BTreeSet<String> =
        FAMILY_NAMES.iter().map(|(id, _)| id.to_string()).collect();
    assert_eq!(
        ids, named,
        "a family of vendors/ without its name here (left)"
    );
    let read = |f: &str| std::fs::read_to_string(root().join(f)).expect(f);
    let help = bin().arg("--help").output().expect("--help runs");
    let places = [
        ("the README's opening", first_paragraph(&read("README.md"))),
        (
            "plc-conformance --help",
            String::from_utf8_lossy(&help.stdout).replace('\n', " "),
        ),
        (
            "docs/check-your-library.md's opening",
            first_paragraph(&read("docs/check-your-library.md")),
        ),
        ("docs/families.md", read("docs/families.md")),
    ];
    for (place, text) in &places {
        let missing: Vec<&str> = (FAMILY_NAMES.iter())
            .filter(|(_, name)| !text.contains(name))
            .map(|(_, name)| *name)
            .collect();
        assert!(
            missing.is_empty(),
            "{place} does not name {missing:?}:\n{text}"
        );
    }
}
