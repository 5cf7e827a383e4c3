//! A sweep's results for people (text, HTML) and for tools (a JSON document of groups).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use super::group::{Class, Found, Group};
use super::{ColumnInfo, Results, Settings, Shrunk};
use crate::report::html::{escape, head, FOOT};

/// How many inputs two columns disagree on.
#[derive(Debug, Clone, Serialize)]
pub struct Pair {
    pub a: String,
    pub b: String,
    pub inputs: u64,
    pub groups: usize,
}

/// Every pair of columns that disagree somewhere, in column order. Columns that did not run an
/// input (skipped) do not count as disagreeing on it.
pub fn pairs(results: &Results) -> Vec<Pair> {
    let n = results.columns.len();
    let mut out = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            let mut inputs = 0;
            let mut groups = 0;
            for g in results.groups.by_key.values() {
                let (x, y) = (&g.key.signature[a], &g.key.signature[b]);
                if x != y && x != "skipped" && y != "skipped" {
                    inputs += g.inputs;
                    groups += 1;
                }
            }
            if groups > 0 {
                out.push(Pair {
                    a: results.columns[a].name.clone(),
                    b: results.columns[b].name.clone(),
                    inputs,
                    groups,
                });
            }
        }
    }
    out
}

/// Groups shown as one, each with its index among the results' groups.
type Shown<'a> = Vec<(usize, &'a Group)>;

/// A column judged against an oracle, and where it parts from it.
#[derive(Debug, Clone, Serialize)]
pub struct Judged {
    pub column: String,
    pub oracle: String,
    /// Inputs on which the column differs from its oracle.
    pub inputs: u64,
    pub groups: usize,
    /// Where it differs as its known-differences file says, by entry.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub known: Vec<KnownTally>,
}

/// The groups of a judged column one known-differences entry covers.
#[derive(Debug, Clone, Serialize)]
pub struct KnownTally {
    pub reason: String,
    pub location: String,
    pub inputs: u64,
    pub groups: usize,
}

/// Every column that has an oracle, in column order; its groups are counted as the text
/// shows them (groups that only columns not shown tell apart are one).
pub fn judged(results: &Results) -> Vec<Judged> {
    let shown = shown_columns(results);
    results
        .columns
        .iter()
        .filter_map(|c| {
            let oracle = c.oracle.clone()?;
            let mut inputs = 0;
            let mut keys = std::collections::BTreeSet::new();
            for g in results
                .groups
                .by_key
                .values()
                .filter(|g| g.differing.contains(&c.name))
            {
                inputs += g.inputs;
                keys.insert(shown_key(g, &shown));
            }
            let mut known: Vec<KnownTally> = Vec::new();
            for g in results.groups.by_key.values() {
                for k in g.known.iter().filter(|k| k.column == c.name) {
                    match known.iter_mut().find(|t| t.location == k.location) {
                        Some(t) => {
                            t.inputs += g.inputs;
                            t.groups += 1;
                        }
                        None => known.push(KnownTally {
                            reason: k.reason.clone(),
                            location: k.location.clone(),
                            inputs: g.inputs,
                            groups: 1,
                        }),
                    }
                }
            }
            known.sort_by(|a, b| a.location.cmp(&b.location));
            Some(Judged {
                column: c.name.clone(),
                oracle,
                inputs,
                groups: keys.len(),
                known,
            })
        })
        .collect()
}

/// What tells groups apart in the columns shown: their labels there, and their features.
fn shown_key(g: &Group, shown: &[usize]) -> Vec<String> {
    let mut key = shown_labels(&g.key.signature, shown);
    key.extend(g.key.features.iter().cloned());
    key
}

/// The columns a judged sweep shows: those judged and their oracles (every column when none
/// is judged).
fn shown_columns(results: &Results) -> Vec<usize> {
    let judged: Vec<usize> = (0..results.columns.len())
        .filter(|&i| {
            let c = &results.columns[i];
            c.oracle.is_some()
                || results
                    .columns
                    .iter()
                    .any(|o| o.oracle.as_deref() == Some(c.name.as_str()))
        })
        .collect();
    if judged.is_empty() {
        (0..results.columns.len()).collect()
    } else {
        judged
    }
}

/// `1234567` as `1,234,567`.
pub fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn found_line(columns: &[ColumnInfo], shown: &[usize], f: &Found) -> String {
    let answers: Vec<String> = shown
        .iter()
        .filter_map(|&i| Some(format!("{} {}", columns.get(i)?.name, f.replies.get(i)?)))
        .collect();
    format!("{} -> {}", f.point, answers.join(", "))
}

fn what(results: &Results) -> &'static str {
    if results.settings.generator.makes_text() && results.settings.generator.name() != "random" {
        "texts"
    } else {
        "inputs"
    }
}

/// The results as text: the settings, the disagreements between columns, then every group
/// with its classes and shrunk inputs. Where columns are judged against an oracle, the
/// disagreements are theirs alone, and only the groups where one differs are shown, with the
/// judged columns and their oracles: what the author of the judged code acts on.
pub fn text(results: &Results) -> String {
    let mut out = String::new();
    let s = &results.settings;
    let _ = writeln!(
        out,
        "sweep of {}: {} generator{}, shard {}/{}",
        s.target,
        s.generator.name(),
        s.generator.seed_text(s.seed),
        s.shard.0,
        s.shard.1
    );
    for c in &results.columns {
        match &c.oracle {
            Some(o) => {
                let _ = writeln!(out, "  column {} (judged against {o})", c.name);
            }
            None => {
                let _ = writeln!(out, "  column {}", c.name);
            }
        }
    }
    let groups = results.ordered();
    let _ = writeln!(
        out,
        "{} of {} {} swept{} in {:.1} s: {} behaviour(s)",
        thousands(results.swept),
        thousands(results.shard_inputs),
        what(results),
        if results.interrupted {
            " (interrupted)"
        } else {
            ""
        },
        results.elapsed.as_secs_f64(),
        groups.len()
    );
    if results.swept < results.space {
        let _ = writeln!(
            out,
            "  (the whole space has {} {}; the counts below are of those swept)",
            thousands(results.space),
            what(results)
        );
    }
    for f in results.faulted() {
        let _ = writeln!(
            out,
            "  FAULTED: {} {} on {} {}: those were never answered",
            f.column,
            f.label,
            thousands(f.inputs),
            what(results)
        );
    }
    if let Some(c) = &results.classes {
        class_text(&mut out, c);
    }
    if let Some(e) = &results.exhaustive {
        exhaustive_text(&mut out, e);
    }
    let swept = thousands(results.swept);
    let judged = judged(results);
    for j in &judged {
        let _ = writeln!(
            out,
            "  {} against {}: differs on {} of {swept} {}, in {} group(s)",
            j.column,
            j.oracle,
            thousands(j.inputs),
            what(results),
            j.groups
        );
        for k in &j.known {
            let _ = writeln!(
                out,
                "    and on {} {} in {} group(s) as its known differences say ({}): {}",
                thousands(k.inputs),
                what(results),
                k.groups,
                k.location,
                crate::report::sanitize::terminal(&k.reason)
            );
        }
        for h in results.hints.iter().filter(|h| h.column == j.column) {
            let _ = writeln!(
                out,
                "    {} of those {} are {}; if that is how the protocol's field works, the codec \
                 declares {} (docs/protocol.md#field-shapes)",
                thousands(h.inputs),
                thousands(h.of),
                h.why,
                h.shape
            );
        }
    }
    if judged.is_empty() {
        for p in pairs(results) {
            let _ = writeln!(
                out,
                "  {} and {} disagree on {} of {swept} {}, in {} group(s)",
                p.a,
                p.b,
                thousands(p.inputs),
                what(results),
                p.groups
            );
        }
    }
    let shown = shown_columns(results);
    let shrunk = shrunk_by_group(&results.shrunk);
    let mut agreeing = (0, 0u64);
    // Judged, the groups that look alike in the columns shown are shown as one.
    let mut merged: Vec<(Vec<String>, Shown<'_>)> = Vec::new();
    for (i, g) in groups.iter().enumerate() {
        if judged.is_empty() {
            merged.push((Vec::new(), vec![(i, g)]));
            continue;
        }
        if g.differing.is_empty() {
            if g.known.is_empty() {
                agreeing = (agreeing.0 + 1, agreeing.1 + g.inputs);
            }
            continue;
        }
        let key = shown_key(g, &shown);
        match merged.iter_mut().find(|(k, _)| *k == key) {
            Some((_, those)) => those.push((i, g)),
            None => merged.push((key, vec![(i, g)])),
        }
    }
    for (n, (_, those)) in merged.iter().enumerate() {
        let _ = writeln!(out);
        group_text(&mut out, results, &shown, n + 1, those, &shrunk);
    }
    if agreeing.0 > 0 {
        let _ = writeln!(
            out,
            "\n{} more group(s) of {} {} where every judged column agrees with its oracle \
             (--format json lists every group)",
            agreeing.0,
            thousands(agreeing.1),
            what(results)
        );
    }
    out
}

/// How a sweep by class covered its texts, and whether the check held.
fn class_text(out: &mut String, c: &super::classes::Report) {
    let _ = writeln!(
        out,
        "  by class: {} texts asked, one per tuple of {} byte classes (found with {} texts)",
        thousands(c.tuples),
        c.classes.len(),
        thousands(c.split_texts),
    );
    let _ = writeln!(out, "  byte classes: {}", c.classes.join(", "));
    match &c.mismatch {
        None => {
            let _ = writeln!(
                out,
                "  checked: {} random texts asked as they are, each answered as its class representative",
                thousands(c.checked)
            );
        }
        Some(m) => {
            let _ = writeln!(
                out,
                "  CHECK FAILED after {} random texts: {} answers unlike its representative {}; \
                 the counts are not exact",
                thousands(c.checked),
                m.text.point,
                m.representative.point
            );
        }
    }
}

/// How every text was asked through the lowerings' rules, and whether the models agreed.
fn exhaustive_text(out: &mut String, e: &super::exhaustive::Report) {
    let _ = writeln!(
        out,
        "  each text: {} texts asked through every lowering's rule in {:.1} s, tallied by {} \
         tuples of {} byte classes; {} answered unlike their tuple and were asked on their own",
        thousands(e.texts),
        e.seconds,
        thousands(e.tuples),
        e.classes.len(),
        thousands(e.apart)
    );
    match &e.disagreement {
        None => {
            let _ = writeln!(
                out,
                "  checked: the first text of each tuple asked through the models too, each \
                 answered as the rules said"
            );
        }
        Some(f) => {
            let _ = writeln!(
                out,
                "  CHECK FAILED: the models answer {} unlike the rules; the counts are not exact",
                f.point
            );
        }
    }
}

fn shrunk_by_group(shrunk: &[Shrunk]) -> BTreeMap<usize, Vec<&Shrunk>> {
    let mut by: BTreeMap<usize, Vec<&Shrunk>> = BTreeMap::new();
    for s in shrunk {
        by.entry(s.group).or_default().push(s);
    }
    by
}

/// The labels of `shown` columns, with equal answers numbered again among them alone
/// (`value#2` where another column took `value#1` reads `value#1`).
fn shown_labels(signature: &[String], shown: &[usize]) -> Vec<String> {
    let mut numbers: Vec<&str> = Vec::new();
    shown
        .iter()
        .filter_map(|&c| signature.get(c))
        .map(|label| match label.rsplit_once('#') {
            Some((head, n)) => {
                let k = numbers.iter().position(|m| *m == n).unwrap_or_else(|| {
                    numbers.push(n);
                    numbers.len() - 1
                });
                format!("{head}#{}", k + 1)
            }
            None => label.clone(),
        })
        .collect()
}

/// One group as text; `merged` are the groups shown as one (the first gives the answers): a
/// judged sweep shows groups that only columns it does not show tell apart as one.
fn group_text(
    out: &mut String,
    results: &Results,
    shown: &[usize],
    number: usize,
    merged: &[(usize, &Group)],
    shrunk: &BTreeMap<usize, Vec<&Shrunk>>,
) {
    let Some((_, g)) = merged.first() else {
        return;
    };
    let classes: usize = merged.iter().map(|(_, g)| g.classes.len()).sum();
    let full = merged
        .iter()
        .any(|(_, g)| g.classes.len() >= results.groups.max_classes);
    let _ = writeln!(
        out,
        "#{number} {} input(s) in {classes}{} class(es) [{}]",
        thousands(merged.iter().map(|(_, g)| g.inputs).sum()),
        if full { "+" } else { "" },
        g.key.features.join("; ")
    );
    if !g.differing.is_empty() {
        let _ = writeln!(
            out,
            "   differs from its oracle: {}",
            g.differing.join(", ")
        );
    }
    let sig: Vec<String> = shown
        .iter()
        .zip(shown_labels(&g.key.signature, shown))
        .filter_map(|(&c, label)| Some(format!("{}={label}", results.columns.get(c)?.name)))
        .collect();
    let _ = writeln!(out, "   {}", sig.join("  "));
    let _ = writeln!(
        out,
        "   first: {}",
        found_line(&results.columns, shown, &g.representative)
    );
    // Two classes may shrink to the same input: it is shown once.
    let mut seen = std::collections::HashSet::new();
    for s in merged.iter().filter_map(|(i, _)| shrunk.get(i)).flatten() {
        if !seen.insert(&s.to.point) {
            continue;
        }
        let _ = writeln!(
            out,
            "   shrunk ({}): {}",
            s.class,
            found_line(&results.columns, shown, &s.to)
        );
    }
}

/// The JSON document: settings, columns, counts, every group with its classes, the pairs of
/// columns that disagree, and the shrunk inputs.
#[derive(Serialize)]
pub struct Document<'a> {
    pub tool: String,
    pub settings: &'a Settings,
    pub columns: &'a [ColumnInfo],
    pub space: u64,
    pub shard_inputs: u64,
    pub swept: u64,
    pub interrupted: bool,
    pub elapsed_seconds: f64,
    /// The columns whose backend faulted: a failure of the sweep.
    pub faulted: Vec<super::Faulted>,
    /// The columns judged against an oracle, and where each parts from it.
    pub judged: Vec<Judged>,
    pub pairs: Vec<Pair>,
    pub groups: Vec<GroupDoc<'a>>,
    /// The full generator by class: the byte classes and their check.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub byte_classes: Option<&'a super::classes::Report>,
    /// Every text asked through the built-in lowerings' rules, and the models' check of them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub each_text: Option<&'a super::exhaustive::Report>,
    /// Field shapes that would describe most of a judged codec's differences.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub hints: &'a [super::explain::Hint],
}

#[derive(Serialize)]
pub struct GroupDoc<'a> {
    pub number: usize,
    pub inputs: u64,
    pub features: &'a [String],
    /// Per column, the class of its answer.
    pub signature: BTreeMap<&'a str, &'a str>,
    pub differing: &'a [String],
    /// Judged columns that differ here as their known-differences file says.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub known: &'a [super::group::KnownColumn],
    pub disagree: bool,
    pub representative: &'a Found,
    pub classes: Vec<&'a Class>,
    pub shrunk: Vec<&'a Shrunk>,
}

pub fn document(results: &Results) -> Document<'_> {
    let shrunk = shrunk_by_group(&results.shrunk);
    Document {
        tool: format!("plc-conformance {}", env!("CARGO_PKG_VERSION")),
        settings: &results.settings,
        columns: &results.columns,
        space: results.space,
        shard_inputs: results.shard_inputs,
        swept: results.swept,
        interrupted: results.interrupted,
        elapsed_seconds: results.elapsed.as_secs_f64(),
        faulted: results.faulted(),
        judged: judged(results),
        pairs: pairs(results),
        groups: results
            .ordered()
            .into_iter()
            .enumerate()
            .map(|(i, g)| GroupDoc {
                number: i + 1,
                inputs: g.inputs,
                features: &g.key.features,
                signature: results
                    .columns
                    .iter()
                    .map(|c| c.name.as_str())
                    .zip(g.key.signature.iter().map(String::as_str))
                    .collect(),
                differing: &g.differing,
                known: &g.known,
                disagree: g.disagree,
                representative: &g.representative,
                classes: g.classes_by_size(),
                shrunk: shrunk.get(&i).cloned().unwrap_or_default(),
            })
            .collect(),
        byte_classes: results.classes.as_ref(),
        each_text: results.exhaustive.as_ref(),
        hints: &results.hints,
    }
}

pub fn json(results: &Results) -> String {
    serde_json::to_string_pretty(&document(results)).unwrap_or_default()
}

/// The results as a page of the HTML report (`crate::report::html`, the same look and the same
/// guarantees): the pairs that disagree, and a table of the groups in which those that differ
/// from their oracle are marked as a run's report marks failures.
pub fn html(results: &Results) -> String {
    let s = &results.settings;
    let mut out = head(&format!("plc-conformance sweep of {}", s.target));
    let _ = writeln!(
        out,
        "<p id=\"summary\">{} generator{}, shard {}/{}: {} of {} inputs{}.</p>",
        s.generator.name(),
        s.generator.seed_text(s.seed),
        s.shard.0,
        s.shard.1,
        thousands(results.swept),
        thousands(results.shard_inputs),
        if results.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    if let Some(c) = &results.classes {
        let check = match &c.mismatch {
            None => format!(
                "{} random texts checked, each answered as its class representative",
                thousands(c.checked)
            ),
            Some(m) => format!(
                "<strong>check failed</strong>: {} answers unlike its representative {}; the \
                 counts are not exact",
                escape(&m.text.point.to_string()),
                escape(&m.representative.point.to_string())
            ),
        };
        let _ = writeln!(
            out,
            "<p>By class: {} texts asked, one per tuple of {} byte classes ({}); {check}.</p>",
            thousands(c.tuples),
            c.classes.len(),
            escape(&c.classes.join(", "))
        );
    }
    out.push_str("<h2>Disagreements</h2>\n<ul>\n");
    for p in pairs(results) {
        let _ = writeln!(
            out,
            "<li>{} and {}: {} of {} inputs, {} group(s)</li>",
            escape(&p.a),
            escape(&p.b),
            thousands(p.inputs),
            thousands(results.swept),
            p.groups
        );
    }
    out.push_str(
        "</ul>\n<h2>Groups</h2>\n<p class=\"legend\"><span class=\"fails\">differs from its \
         oracle</span></p>\n<table class=\"matrix\" id=\"groups\">\n<tr><th>#</th><th>inputs</th>\
         <th>features</th>",
    );
    for c in &results.columns {
        let _ = write!(out, "<th>{}</th>", escape(&c.name));
    }
    out.push_str("<th>first input</th></tr>\n");
    for (i, g) in results.ordered().into_iter().enumerate() {
        let _ = write!(
            out,
            "<tr{}><td>{}</td><td>{}</td><td>{}</td>",
            if g.differing.is_empty() {
                ""
            } else {
                " class=\"differs\""
            },
            i + 1,
            thousands(g.inputs),
            escape(&g.key.features.join("; "))
        );
        for r in &g.representative.replies {
            let _ = write!(out, "<td>{}</td>", escape(&r.to_string()));
        }
        let _ = writeln!(
            out,
            "<td>{}</td></tr>",
            escape(&g.representative.point.to_string())
        );
    }
    out.push_str("</table>\n");
    out.push_str(FOOT);
    out
}
