//! A self-contained HTML report: the matrices, the groups and each difference's explanation in
//! one file with inline styles, no scripts and no network access, so it can be attached to a CI
//! run and opened anywhere. The markup is well-formed XML, which keeps it checkable by a plain
//! XML parser as well as by a browser.

use std::fmt::Write;

use super::json::RunInfo;
use super::matrix::Section;
use super::record::Record;
use crate::judge::Status;

const STYLE: &str = "\
body{font-family:system-ui,sans-serif;margin:2em;color:#222}\
table.matrix{border-collapse:collapse;margin:1em 0}\
.matrix th,.matrix td{border:1px solid #ccc;padding:.3em .6em;text-align:left;vertical-align:top}\
.matrix th{background:#f3f3f3}\
.conforms{background:#e6f4ea}.fails{background:#fce8e6}.other{background:#e8f0fe}\
.legend span{padding:.1em .5em;margin-right:.5em;border:1px solid #ccc}\
td.count{text-align:right}.where{color:#666;font-size:.85em}\
table.meta td,table.meta th{text-align:left;padding:.1em .8em .1em 0;vertical-align:top}\
pre{background:#f8f8f8;padding:.6em;overflow:auto}\
summary{cursor:pointer}\
tr.differs td{background:#fce8e6}";

/// Text as markup: special characters as entities, and characters XML forbids or a terminal
/// would act on shown as escapes.
pub(crate) fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if super::sanitize::forbidden_in_xml(c)
                || c.is_control() && c != '\n' && c != '\t' =>
            {
                out.push_str(&super::sanitize::escaped(c));
            }
            c => out.push(c),
        }
    }
    out
}

/// ` file:line` of a row's case, as markup.
fn place(records: &[&Record], row: &str) -> String {
    records
        .iter()
        .find(|r| r.row == row)
        .map(|r| {
            format!(
                " <span class=\"where\">{}:{}</span>",
                escape(&r.file),
                r.line
            )
        })
        .unwrap_or_default()
}

fn class_of(status: Status) -> &'static str {
    match status {
        Status::Pass => "conforms",
        Status::Ignored | Status::Skipped => "other",
        Status::Fail => "fails",
    }
}

pub(crate) fn render(sections: &[Section<'_>], records: &[Record], run: &RunInfo) -> String {
    let failing = records.iter().filter(|r| r.status.is_failure()).count();
    let mut out = String::new();
    out.push_str(&head("plc-conformance report"));
    let _ = writeln!(
        out,
        "<p id=\"summary\">{} cells in {} matrices; {failing} failing.</p>",
        records.len(),
        sections.len()
    );
    out.push_str("<table class=\"meta\" id=\"run\">\n");
    let mut meta = |key: &str, value: &str| {
        let _ = writeln!(
            out,
            "<tr><th>{}</th><td>{}</td></tr>",
            escape(key),
            escape(value)
        );
    };
    meta(
        "tool",
        &format!(
            "{}{}",
            run.tool,
            match run.stopped {
                Some(super::Stopped::Interrupted) => " (interrupted: incomplete)",
                Some(super::Stopped::FailFast) => " (stopped at the first failure: incomplete)",
                None => "",
            }
        ),
    );
    if let Some(commit) = &run.commit {
        meta("commit", commit);
    }
    meta("date", &run.date);
    for b in &run.backends {
        meta(
            &format!("backend {}", b.name),
            &match &b.version {
                Some(v) => format!("{v} — {}", b.description),
                None => b.description.clone(),
            },
        );
    }
    out.push_str("</table>\n");
    out.push_str(
        "<p class=\"legend\"><span class=\"conforms\">conforms</span> \
         <span class=\"other\">recorded, known difference or skipped</span> \
         <span class=\"fails\">fails (marked !)</span> \
         a count is how many cases behave like the one shown; the others are under the table</p>\n",
    );
    if failing > 0 {
        out.push_str("<h2>Failures</h2>\n<ul id=\"failures\">\n");
        for (i, r) in failures(records) {
            let _ = writeln!(
                out,
                "<li><a href=\"#failure-{i}\">{}</a> — {} ({}:{})</li>",
                escape(&r.trial),
                escape(&r.label),
                escape(&r.file),
                r.line
            );
        }
        out.push_str("</ul>\n");
    }
    for (i, section) in sections.iter().enumerate() {
        let section_records: Vec<&Record> = records
            .iter()
            .filter(|r| r.section == section.name)
            .collect();
        let _ = write!(
            out,
            "<h2>{}</h2>\n<p>{} cases, {} behaviours. Cells marked ! fail.</p>\n\
             <table class=\"matrix\" id=\"matrix-{i}\">\n<thead><tr><th>cases</th><th>representative</th>",
            escape(section.name),
            section.rows,
            section.groups.len()
        );
        for c in &section.columns {
            let _ = write!(out, "<th>{}</th>", escape(c));
        }
        out.push_str("</tr></thead>\n<tbody>\n");
        for g in &section.groups {
            let _ = write!(
                out,
                "<tr><td class=\"count\">{}</td><td>{}{}</td>",
                g.rows.len(),
                escape(g.rows[0]),
                place(&section_records, g.rows[0])
            );
            for cell in &g.cells {
                match cell {
                    Some(r) => {
                        let mark = if r.status.is_failure() { " !" } else { "" };
                        let _ = write!(
                            out,
                            "<td class=\"{}\" title=\"{}\">{}{mark}</td>",
                            class_of(r.status),
                            escape(&r.label),
                            escape(&r.shown)
                        );
                    }
                    None => out.push_str("<td>n/a</td>"),
                }
            }
            out.push_str("</tr>\n");
        }
        out.push_str("</tbody>\n</table>\n");
        for g in &section.groups {
            let failing: Vec<&&Record> = g
                .cells
                .iter()
                .flatten()
                .filter(|r| r.status.is_failure())
                .collect();
            if failing.is_empty() && g.rows.len() == 1 {
                continue;
            }
            let _ = write!(
                out,
                "<details><summary>{} — {} case(s)</summary>\n<ul class=\"members\">\n",
                escape(g.rows[0]),
                g.rows.len(),
            );
            for row in &g.rows {
                let _ = writeln!(
                    out,
                    "<li>{}{}</li>",
                    escape(row),
                    place(&section_records, row)
                );
            }
            out.push_str("</ul>\n");
            for r in failing {
                let _ = writeln!(out, "<pre>{}</pre>", escape(&r.detail));
            }
            out.push_str("</details>\n");
        }
    }
    if failing > 0 {
        out.push_str("<h2>Failure details</h2>\n");
        for (i, r) in failures(records) {
            let _ = writeln!(
                out,
                "<section id=\"failure-{i}\"><h3>{}</h3><p>{}:{}</p><pre>{}</pre></section>",
                escape(&r.trial),
                escape(&r.file),
                r.line,
                escape(&r.detail)
            );
        }
    }
    out.push_str(FOOT);
    out
}

/// The start of a report page, up to its heading: every page of the tool (a run's report, a
/// sweep's) has the same look and is well-formed XHTML with no scripts and no network access.
pub(crate) fn head(title: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html xmlns=\"http://www.w3.org/1999/xhtml\" lang=\"en\">\n<head>\n\
         <meta charset=\"utf-8\" />\n<title>{t}</title>\n<style>{STYLE}</style>\n</head>\n\
         <body>\n<h1>{t}</h1>\n",
        t = escape(title)
    )
}

/// The end of a report page.
pub(crate) const FOOT: &str = "</body>\n</html>\n";

/// The failing records with their index, which anchors their explanation in the page.
fn failures(records: &[Record]) -> impl Iterator<Item = (usize, &Record)> {
    records
        .iter()
        .enumerate()
        .filter(|(_, r)| r.status.is_failure())
}
