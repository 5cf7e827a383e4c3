//! The rules `docs/architecture.md` states for the source, checked on `src/` itself: no
//! `Result<_, String>` outside test modules (errors are types with context), no printing outside
//! the console reporter (`src/report/console.rs` and the reporters' sinks) and test modules, no
//! `.unwrap()` outside test modules (input is never unwrapped), and no import cycle between
//! top-level modules. Each violation is reported with its file and line; the checker is shown
//! failing on a fixture that plants one of each (`tests/fixtures/rules`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

mod common;

/// One broken rule, where.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Violation {
    file: String,
    line: usize,
    rule: &'static str,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.rule)
    }
}

/// The one file allowed to write to the terminal directly.
const CONSOLE: &str = "report/console.rs";
const PRINTING: [&str; 5] = ["println!", "eprintln!", "print!(", "eprint!(", "dbg!("];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|x| x == "rs") {
            out.push(path);
        }
    }
}

/// A line's code: without a trailing `//` comment, and nothing for a comment line. String
/// literals are kept (a rule's text inside a string is rare enough to be renamed).
fn code(line: &str) -> &str {
    let trimmed = line.trim_start();
    if trimmed.starts_with("//") {
        return "";
    }
    match line.find("//") {
        // `"http://..."`: a `//` inside a string is not a comment.
        Some(at) if line[..at].matches('"').count() % 2 == 0 => &line[..at],
        _ => line,
    }
}

/// The top-level module a file of `src/` belongs to (`backend` for `src/backend/slmp/sim.rs`),
/// or `None` for the crate root and the binary.
fn top_module(relative: &str) -> Option<String> {
    let first = relative.split('/').next()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (!matches!(name, "lib" | "main")).then(|| name.to_string())
}

/// Every violation in the source tree at `src`.
fn check(src: &Path) -> Vec<Violation> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut found = Vec::new();
    // Top-level module -> the modules it names, with the first place it does.
    let mut uses: BTreeMap<String, BTreeMap<String, (String, usize)>> = BTreeMap::new();
    for path in files {
        let relative = path
            .strip_prefix(src)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(&path).expect("source");
        let module = top_module(&relative);
        let mut in_tests = false;
        for (n, line) in text.lines().enumerate() {
            let line_no = n + 1;
            if line.trim() == "#[cfg(test)]" {
                // Test modules sit at the end of a file: the rest is tests.
                in_tests = true;
            }
            let code = code(line);
            let mut violation = |rule| {
                found.push(Violation {
                    file: format!("src/{relative}"),
                    line: line_no,
                    rule,
                })
            };
            if !in_tests && code.contains("Result<") && code.replace(' ', "").contains(",String>") {
                violation("Result<_, String>: an error is a type with context");
            }
            if relative != CONSOLE && !in_tests && PRINTING.iter().any(|p| code.contains(p)) {
                violation("printing outside the console reporter");
            }
            if !in_tests && code.contains(".unwrap()") {
                violation(".unwrap() outside a test module");
            }
            if let Some(module) = &module {
                for (at, _) in code.match_indices("crate::") {
                    let name: String = code[at + "crate::".len()..]
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() && name != *module && !in_tests {
                        uses.entry(module.clone())
                            .or_default()
                            .entry(name)
                            .or_insert_with(|| (format!("src/{relative}"), line_no));
                    }
                }
            }
        }
    }
    for (file, line) in cycles(&uses) {
        found.push(Violation {
            file,
            line,
            rule: "an import cycle between top-level modules",
        });
    }
    found.sort();
    found
}

/// For every edge that closes a cycle (a module naming one that reaches back to it), where.
fn cycles(uses: &BTreeMap<String, BTreeMap<String, (String, usize)>>) -> Vec<(String, usize)> {
    let reaches = |from: &str, to: &str| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(m) = stack.pop() {
            if m == to {
                return true;
            }
            if seen.insert(m.clone()) {
                if let Some(next) = uses.get(&m) {
                    stack.extend(next.keys().cloned());
                }
            }
        }
        false
    };
    let mut out = Vec::new();
    for (module, named) in uses {
        for (other, at) in named {
            if reaches(other, module) {
                out.push(at.clone());
            }
        }
    }
    out
}

#[test]
fn the_source_keeps_the_rules_the_docs_state() {
    let violations = check(&common::root().join("src"));
    let listed: Vec<String> = violations.iter().map(ToString::to_string).collect();
    assert!(listed.is_empty(), "{}", listed.join("\n"));
}

#[test]
fn a_planted_violation_of_each_rule_is_found_with_its_file_and_line() {
    let fixture = common::root().join("tests/fixtures/rules/src");
    let listed: Vec<String> = check(&fixture).iter().map(ToString::to_string).collect();
    assert_eq!(
        listed,
        [
            "src/alpha.rs:4: Result<_, String>: an error is a type with context",
            "src/alpha.rs:5: printing outside the console reporter",
            "src/alpha.rs:6: .unwrap() outside a test module",
            "src/alpha.rs:9: an import cycle between top-level modules",
            "src/beta/mod.rs:3: an import cycle between top-level modules",
        ],
        "{}",
        listed.join("\n")
    );
}
