//! Every citation in the repository points at something in it: a manual a profile lists, with
//! a page (`iqr-instructions-ja p.478`), or a section of the project's own evidence,
//! `docs/semantics.md#anchor`. Nothing cites material outside the repository.

#[cfg(test)]
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::{root, session};
use crate::load::load_profiles;

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
    // The vendor profiles' manuals and the protocol profiles' (vendors/protocols/).
    (profiles.iter().flat_map(|p| p.manuals.keys().cloned()))
        .chain((profiles.protocols.iter()).flat_map(|p| p.manuals.keys().cloned()))
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
    // The white-box tests beside the code, as those in tests/, plant citations that point
    // nowhere and name the evidence they read: they cite nothing.
    all.retain(|f| !f.components().any(|c| c.as_os_str() == "white_box"));
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

/// A paragraph or list item of docs/semantics.md, with the anchor of the section it is in.
struct Block {
    anchor: String,
    text: String,
}

/// docs/semantics.md cut into paragraphs and list items; tables count as one block per row.
fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut anchor = String::new();
    let mut current = String::new();
    let flush = |current: &mut String, anchor: &str, out: &mut Vec<Block>| {
        if !current.trim().is_empty() {
            out.push(Block {
                anchor: anchor.to_string(),
                text: std::mem::take(current),
            });
        }
        current.clear();
    };
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("<a id=\"") {
            flush(&mut current, &anchor, &mut out);
            anchor = rest.split('"').next().unwrap_or_default().to_string();
            continue;
        }
        let starts = line.trim().is_empty()
            || line.starts_with("- ")
            || line.starts_with('#')
            || line.starts_with('|');
        if starts {
            flush(&mut current, &anchor, &mut out);
        }
        current.push_str(line);
        current.push('\n');
        if line.starts_with('|') || line.starts_with('#') {
            flush(&mut current, &anchor, &mut out);
        }
    }
    flush(&mut current, &anchor, &mut out);
    out
}

/// Whether a block quotes a page: words of the manual in quotation marks (at least six
/// characters: a label such as "(Zero padding)" counts, a lone `"0"` does not).
fn quotes(text: &str) -> bool {
    let flat = text.replace('\n', " ");
    let straight = flat
        .split('"')
        .skip(1)
        .step_by(2)
        .any(|q| q.chars().count() >= 6)
        && flat.matches('"').count() >= 2;
    let japanese = flat
        .split('「')
        .skip(1)
        .any(|q| q.find('」').is_some_and(|end| end >= 3));
    straight || japanese
}

/// Whether a `manual` claim of a block stands on something the reader can check: a quote, or a
/// table, figure or example of the page described (they cannot be quoted in words), or a link to
/// the section that quotes it.
fn supported(text: &str) -> bool {
    let lower = text.to_lowercase();
    quotes(text)
        || ["table", "figure", "example", "](#"]
            .iter()
            .any(|w| lower.contains(w))
}

/// The `manual` claims of docs/semantics.md that stand on nothing quoted, as `anchor: claim`.
fn unquoted_manual_claims(text: &str) -> Vec<String> {
    blocks(text)
        .into_iter()
        .filter(|b| b.anchor != "evidence" && b.anchor != "cites")
        .filter(|b| b.text.contains("`manual`") && !supported(&b.text))
        .map(|b| format!("{}: {}", b.anchor, b.text.trim()))
        .collect()
}

/// The manual id (or any id) a text ends with.
fn id_before(text: &str) -> String {
    let start = text
        .char_indices()
        .rev()
        .take_while(|(_, c)| is_id_char(*c))
        .last()
        .map_or(text.len(), |(i, _)| i);
    text[start..].to_string()
}

/// `<manual-id> p.<page>` cites in a text.
fn pages(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (at, _) in text.match_indices(" p.") {
        let id = id_before(&text[..at]);
        let page: String = text[at + 3..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '(' | ')' | '_'))
            .collect();
        let page = page.trim_end_matches(')').to_string();
        let page = if page.ends_with("(P") {
            format!("{page})")
        } else {
            page
        };
        if !id.is_empty() && !page.is_empty() {
            out.push((id, page));
        }
    }
    // A manual known by its topic rather than by pages (`fpwin-f72: "..."`) is cited whole.
    for (at, _) in text.match_indices(": \"") {
        let id = id_before(&text[..at]);
        if id.contains('-') {
            out.push((id, "*".to_string()));
        }
    }
    out
}

/// Whether page `cited` of a manual takes in page `quoted`: the same, or a range `a-b` of a few
/// pages holding it (`654-658` holds `655`; `14-5` is a chapter and a page, not a range), or any
/// page of a manual quoted as a whole (`*`).
fn holds(cited: &str, quoted: &str) -> bool {
    if cited == quoted || quoted == "*" {
        return true;
    }
    let range = |p: &str| -> Option<(u32, u32)> {
        let (a, b) = p.split_once('-')?;
        let (a, b) = (a.parse::<u32>().ok()?, b.parse::<u32>().ok()?);
        (a < b && b - a <= 20).then_some((a, b))
    };
    let single = |p: &str| -> Option<(u32, u32)> { p.parse::<u32>().ok().map(|n| (n, n)) };
    match (range(cited), range(quoted).or_else(|| single(quoted))) {
        (Some((a, b)), Some((c, d))) => c <= b && a <= d,
        _ => false,
    }
}

/// The `manual` cases whose cite reaches no quote in docs/semantics.md: neither a section it
/// names (`docs/semantics.md#anchor`) nor a page it names (or its file's source) is quoted
/// there in a `manual` claim.
fn manual_cases_without_quotes(semantics: &str, cases: &[(String, String)]) -> Vec<String> {
    let blocks = blocks(semantics);
    let quoted: Vec<&Block> = blocks
        .iter()
        .filter(|b| b.text.contains("`manual`") && quotes(&b.text))
        .collect();
    // A section's quotes count for the sections above it: `iqr-binha` holds `iqr-binha-sm705-off`.
    let quoted_anchor = |a: &str| quoted.iter().any(|b| b.anchor == a);
    let mut pages_quoted: Vec<(String, String)> = Vec::new();
    for b in &quoted {
        pages_quoted.extend(pages(&b.text));
        // A block that quotes without naming its page quotes its section's page(s).
        let head = blocks
            .iter()
            .filter(|h| h.anchor == b.anchor)
            .flat_map(|h| pages(&h.text))
            .collect::<Vec<_>>();
        pages_quoted.extend(head);
    }
    cases
        .iter()
        .filter(|(_, cite)| {
            let anchors: Vec<&str> = cite
                .match_indices("semantics.md#")
                .map(|(at, m)| {
                    let rest = &cite[at + m.len()..];
                    let end = rest.find(|c: char| !is_id_char(c)).unwrap_or(rest.len());
                    &rest[..end]
                })
                .collect();
            let by_anchor = anchors.iter().any(|a| quoted_anchor(a));
            let by_page = pages(cite)
                .iter()
                .any(|(m, p)| pages_quoted.iter().any(|(qm, qp)| qm == m && holds(p, qp)));
            !(by_anchor || by_page)
        })
        .map(|(id, cite)| format!("{id}: {cite}"))
        .collect()
}

/// Every `manual` claim of docs/semantics.md quotes the page it rests on (or describes its table,
/// figure or example, or links the section that quotes it), and every `manual` case cites a
/// section or a page quoted there: a `manual` basis the repository cannot show is `inferred`.
#[test]
fn every_manual_basis_rests_on_a_quote() {
    let semantics =
        std::fs::read_to_string(root().join("docs/semantics.md")).expect("semantics.md");
    let claims = unquoted_manual_claims(&semantics);
    assert!(claims.is_empty(), "`manual` without a quote: {claims:#?}");
    let project = session();
    let corpus = &project.corpus;
    let mut cases: Vec<(String, String)> = corpus
        .cases
        .iter()
        .filter(|c| c.basis == crate::Basis::Manual)
        .map(|c| (c.id.clone(), cite_of(&c.citation)))
        .collect();
    cases.extend(
        corpus
            .cross_vendor
            .iter()
            .filter(|c| c.basis == crate::Basis::Manual)
            .map(|c| (c.id.clone(), cite_of(&c.citation))),
    );
    assert!(cases.len() > 200, "{} manual cases", cases.len());
    let bare = manual_cases_without_quotes(&semantics, &cases);
    assert!(
        bare.is_empty(),
        "`manual` cases citing nothing quoted: {bare:#?}"
    );
}

/// A citation's manual, page and text as one string: `iqr-instructions p.654-658: ...`.
fn cite_of(c: &crate::model::Citation) -> String {
    if c.page.is_empty() {
        format!("{} {}", c.manual, c.text.as_deref().unwrap_or_default())
    } else {
        format!(
            "{} p.{}: {}",
            c.manual,
            c.page,
            c.text.as_deref().unwrap_or_default()
        )
    }
}

#[test]
fn the_quote_check_catches_a_manual_claim_or_case_without_a_quote() {
    let semantics = "<a id=\"a\"></a>\n### a: quoted\n\n`m p.10`.\n\n\
                     - A rule. `manual`: \"the page's own words\".\n\
                     - A bare rule. `manual`.\n\n\
                     <a id=\"b\"></a>\n### b: not quoted\n\n- Another rule. `inferred`.\n";
    let claims = unquoted_manual_claims(semantics);
    assert_eq!(claims.len(), 1, "{claims:?}");
    assert!(claims[0].starts_with("a: - A bare rule."), "{claims:?}");
    let cases = [
        ("by-anchor", "docs/semantics.md#a: the rule"),
        ("by-page", "m p.10: the rule"),
        ("by-range", "m p.8-12: the rule"),
        ("other-anchor", "docs/semantics.md#b: the rule"),
        ("other-page", "m p.11: the rule"),
        ("other-manual", "n p.10: the rule"),
        ("nothing", "the rule"),
    ]
    .map(|(id, cite)| (id.to_string(), cite.to_string()));
    let bare = manual_cases_without_quotes(semantics, &cases);
    let ids: Vec<&str> = bare
        .iter()
        .map(|b| b.split(':').next().unwrap_or_default())
        .collect();
    assert_eq!(
        ids,
        ["other-anchor", "other-page", "other-manual", "nothing"]
    );
}

/// The quotes a `manual` cite carries: a `"..."` of four words or more that opens the cite or
/// follows `: `, `(`, `; ` or `, `, and ends before a space or punctuation.
fn cite_quotes(cite: &str) -> Vec<String> {
    let cite: String = cite.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(open) = cite[at..].find('"').map(|i| at + i) {
        let Some(close) = cite[open + 1..].find('"').map(|i| open + 1 + i) else {
            break;
        };
        let opens = cite[..open].is_empty()
            || [": ", "(", "; ", ", "]
                .iter()
                .any(|p| cite[..open].ends_with(p));
        let ends = cite[close + 1..]
            .chars()
            .next()
            .is_none_or(|c| matches!(c, ' ' | ',' | ';' | ')' | '.' | ':'));
        let quote = &cite[open + 1..close];
        if opens && ends && quote.len() >= 20 && quote.split(' ').count() >= 4 {
            out.push(quote.to_string());
            at = close + 1;
        } else {
            at = open + 1;
        }
    }
    out
}

/// Every quote a `manual` vector rests on is carried in docs/semantics.md, the project's own
/// evidence, so that a reader can check it without the vector files.
#[test]
fn every_quote_a_manual_vector_uses_is_in_the_semantics() {
    let semantics = std::fs::read_to_string(root().join("docs/semantics.md")).expect("semantics");
    let semantics = semantics
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace(['“', '”'], "\"");
    let mut vector_files = Vec::new();
    files(&root().join("vectors"), &["yaml"], &mut vector_files);
    let mut missing = Vec::new();
    let mut checked = 0;
    for file in vector_files {
        let text = std::fs::read_to_string(&file).expect("vector file");
        let doc: serde_yaml::Value = serde_yaml::from_str(&text).expect("yaml");
        let Some(cases) = doc.get("cases").and_then(|c| c.as_sequence()) else {
            continue;
        };
        for case in cases {
            if case.get("basis").and_then(|b| b.as_str()) != Some("manual") {
                continue;
            }
            let cite = case
                .get("cite")
                .and_then(|c| c.as_str())
                .unwrap_or_default();
            for quote in cite_quotes(&cite.replace(['“', '”'], "\"")) {
                checked += 1;
                if !semantics.contains(&quote) {
                    let id = case.get("id").and_then(|i| i.as_str()).unwrap_or("?");
                    missing.push(format!("{} {id}: \"{quote}\"", file.display()));
                }
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} quotes found: the extraction broke"
    );
    assert!(
        missing.is_empty(),
        "not in docs/semantics.md:\n{}",
        missing.join("\n")
    );
}

#[test]
fn quotes_are_taken_where_a_cite_quotes() {
    assert_eq!(
        cite_quotes(
            "p.478: \"The quick brown fox jumps\" and \"AB\", (\"one two three four five\")"
        ),
        ["The quick brown fox jumps", "one two three four five"]
    );
}
