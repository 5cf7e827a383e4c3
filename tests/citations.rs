//! Every citation in the repository points at something in it: a manual a profile lists, with
//! a page (`iqr-instructions-ja p.478`), or a section of the project's own evidence,
//! `docs/semantics.md#anchor`. Nothing cites material outside the repository.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use plc_conformance::load::load_profiles;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The anchors `<a id="..."></a>` of docs/semantics.md.
fn anchors() -> BTreeSet<String> {
    let text = std::fs::read_to_string(root().join("docs/semantics.md")).expect("semantics.md");
    text.match_indices("<a id=\"")
        .filter_map(|(at, m)| {
            let rest = &text[at + m.len()..];
            rest.find('"').map(|end| rest[..end].to_string())
        })
        .collect()
}

fn manuals() -> BTreeSet<String> {
    let profiles = load_profiles(&root().join("vendors")).expect("profiles load");
    profiles
        .iter()
        .flat_map(|p| p.manuals.keys().cloned())
        .collect()
}

fn is_id_char(c: char) -> bool {
    c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'
}

/// Every citation in `text` that points nowhere, as `line: what`.
fn dangling(text: &str, anchors: &BTreeSet<String>, manuals: &BTreeSet<String>) -> Vec<String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        if line.contains("shared/") {
            out.push(format!(
                "{n}: cites material outside the repository: {line}"
            ));
        }
        for (at, m) in line.match_indices("semantics.md") {
            let rest = &line[at + m.len()..];
            if rest.starts_with("#<") {
                // The grammar itself, as the docs explain it: `docs/semantics.md#<anchor>`.
                continue;
            }
            let anchor: String = rest
                .strip_prefix('#')
                .map(|r| r.chars().take_while(|c| is_id_char(*c)).collect())
                .unwrap_or_default();
            if anchor.is_empty() {
                // A link to the file as a whole (`[docs/semantics.md](docs/semantics.md)`) is
                // not a citation; a citation names its section.
                let linked =
                    rest.starts_with(')') || rest.starts_with('`') || rest.starts_with(']');
                if !linked {
                    out.push(format!(
                        "{n}: `semantics.md` without a section anchor: {line}"
                    ));
                }
            } else if !anchors.contains(&anchor) {
                out.push(format!("{n}: no anchor `{anchor}` in docs/semantics.md"));
            }
        }
        let bytes: Vec<char> = line.chars().collect();
        for i in 0..bytes.len().saturating_sub(2) {
            let page_start = bytes[i] == 'p'
                && bytes[i + 1] == '.'
                && (bytes[i + 2].is_ascii_digit() || bytes[i + 2].is_ascii_uppercase())
                && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric());
            if !page_start {
                continue;
            }
            let before: String = bytes[..i].iter().collect();
            let manual: String = before
                .strip_suffix(' ')
                .map(|b| {
                    let id: String = b.chars().rev().take_while(|c| is_id_char(*c)).collect();
                    id.chars().rev().collect()
                })
                .unwrap_or_default();
            if !manuals.contains(&manual) {
                out.push(format!(
                    "{n}: a page without a manual a profile lists (`{manual}`): {line}"
                ));
            }
        }
    }
    out
}

fn files(dir: &Path, ext: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            if !matches!(name, "node_modules" | "target" | ".venv-adapters" | ".git") {
                files(&p, ext, out);
            }
        } else if ext.iter().any(|x| name.ends_with(x)) {
            out.push(p);
        }
    }
}

#[test]
fn every_citation_points_inside_the_repository() {
    let (anchors, manuals) = (anchors(), manuals());
    assert!(anchors.len() > 10 && !manuals.is_empty());
    let mut all = Vec::new();
    for dir in [
        "vectors", "vendors", "docs", "adapters", "examples", "src", "schema",
    ] {
        files(
            &root().join(dir),
            &[".yaml", ".md", ".rs", ".json"],
            &mut all,
        );
    }
    all.push(root().join("README.md"));
    all.push(root().join("plc-conformance.yaml"));
    assert!(all.len() > 20);
    let mut problems = Vec::new();
    for file in &all {
        let text = std::fs::read_to_string(file).unwrap_or_default();
        for p in dangling(&text, &anchors, &manuals) {
            problems.push(format!("{}:{p}", file.display()));
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
}

#[test]
fn the_check_catches_each_kind_of_dangling_citation() {
    let anchors = BTreeSet::from(["iqr-habin".to_string()]);
    let manuals = BTreeSet::from(["iqr-instructions-ja".to_string()]);
    let fine = "iqr-instructions-ja p.478 and docs/semantics.md#iqr-habin";
    assert!(dangling(fine, &anchors, &manuals).is_empty());
    for bad in [
        "semantics.md section 4",
        "docs/semantics.md#no-such-section",
        "see p.478",
        "fxcpu p.400",
        "../shared/manuals/melsec-fx5-asci.txt",
    ] {
        assert_eq!(dangling(bad, &anchors, &manuals).len(), 1, "{bad}");
    }
}
