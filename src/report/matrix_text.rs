//! The matrix as text: one table per section, one line per group of rows that behave alike,
//! then what a reader needs to act on each group that fails.
//!
//! A table fits the width it is given: a column in which every case was skipped is left out
//! (and named below the table, with the reason), column names are split over two header lines
//! at their `/` when that narrows the table, and a table still too wide is printed in blocks of
//! columns, each repeating the count and the case. A legend under each section explains the
//! marks its cells use.

use std::fmt::Write;

use anstyle::{AnsiColor, Style};

use super::matrix::{Group, Section};
use super::record::Behaviour;
use crate::judge::{Status, Verdict};

/// How many row ids a group line lists before it says "+N more".
const LISTED_ROWS: usize = 4;

/// The width used when none is known (output to a pipe or a file, `COLUMNS` unset).
pub(crate) const DEFAULT_WIDTH: usize = 100;

/// What a skipped cell shows.
const SKIPPED: &str = "-";
/// The mark of a known difference.
const KNOWN: &str = "*";
/// What a cell shows where the row has no trial in that column.
const ABSENT: &str = "n/a";

pub(crate) fn render(sections: &[Section<'_>], coloured: bool, width: usize) -> String {
    let mut out = String::new();
    for section in sections {
        render_section(&mut out, section, coloured, width);
    }
    out
}

fn cell_style(status: Status, coloured: bool) -> Style {
    if !coloured {
        return Style::new();
    }
    match status {
        Status::Pass => AnsiColor::Green.on_default(),
        Status::Ignored | Status::Skipped => AnsiColor::Cyan.on_default(),
        Status::Fail => AnsiColor::Red.on_default(),
    }
}

/// A cell's text and status.
fn cell_text(group: &Group<'_>, column: usize) -> (String, Status) {
    match group.cells[column] {
        Some(r) if r.status.is_failure() => (format!("{} !", r.shown), r.status),
        Some(r) if r.status == Status::Skipped => (SKIPPED.to_string(), r.status),
        Some(r)
            if matches!(r.behaviour, Behaviour::Known { .. })
                || matches!(r.verdict, Some(Verdict::KnownDifference { .. })) =>
        {
            (format!("{} {KNOWN}", r.shown), r.status)
        }
        Some(r) => (r.shown.clone(), r.status),
        None => (ABSENT.to_string(), Status::Skipped),
    }
}

/// A column's header: its name on one line, or split at its first `/` over two.
fn header(name: &str, split: bool) -> [&str; 2] {
    match name.split_once('/') {
        Some((backend, rest)) if split => [backend, rest],
        _ => [name, ""],
    }
}

fn render_section(out: &mut String, section: &Section<'_>, coloured: bool, width: usize) {
    let bold = if coloured {
        Style::new().bold()
    } else {
        Style::new()
    };
    let _ = writeln!(
        out,
        "{bold}{}: {} case{}, {} behaviour{}{bold:#}",
        section.name,
        section.rows,
        if section.rows == 1 { "" } else { "s" },
        section.groups.len(),
        if section.groups.len() == 1 { "" } else { "s" },
    );
    // Columns in which every case was skipped (or has no trial) say nothing: left out, named
    // below with the reason.
    let mut shown: Vec<usize> = Vec::new();
    let mut left_out: Vec<String> = Vec::new();
    for (i, name) in section.columns.iter().enumerate() {
        let skipped = section
            .groups
            .iter()
            .all(|g| g.cells[i].is_none_or(|r| r.status == Status::Skipped));
        if skipped {
            let reason = section
                .groups
                .iter()
                .find_map(|g| g.cells[i].map(|r| r.detail.as_str()))
                .unwrap_or("no case");
            left_out.push(format!("{name} ({reason})"));
        } else {
            shown.push(i);
        }
    }
    let texts: Vec<Vec<(String, Status)>> = section
        .groups
        .iter()
        .map(|g| shown.iter().map(|&i| cell_text(g, i)).collect())
        .collect();
    let count_width = section
        .groups
        .iter()
        .map(|g| g.rows.len().to_string().len())
        .max()
        .unwrap_or(1);
    let row_width = section
        .groups
        .iter()
        .map(|g| g.rows[0].chars().count())
        .max()
        .unwrap_or(0)
        .max(10);
    let cells_width = |j: usize| {
        texts
            .iter()
            .map(|row| row[j].0.chars().count())
            .max()
            .unwrap_or(0)
    };
    let widths_for = |split: bool| -> Vec<usize> {
        shown
            .iter()
            .enumerate()
            .map(|(j, &i)| {
                let [a, b] = header(section.columns[i], split);
                cells_width(j).max(a.chars().count()).max(b.chars().count())
            })
            .collect()
    };
    let lead = 2 + count_width + 2 + row_width;
    let total = |widths: &[usize]| lead + widths.iter().map(|w| w + 2).sum::<usize>();
    let mut split = false;
    let mut widths = widths_for(false);
    if total(&widths) > width {
        let narrower = widths_for(true);
        if total(&narrower) < total(&widths) {
            split = true;
            widths = narrower;
        }
    }
    // Blocks of columns that fit, each with at least one column.
    let mut blocks: Vec<Vec<usize>> = vec![Vec::new()];
    let mut used = lead;
    for (j, w) in widths.iter().enumerate() {
        let block = blocks.last_mut().expect("one block");
        if !block.is_empty() && used + w + 2 > width {
            blocks.push(vec![j]);
            used = lead + w + 2;
        } else {
            block.push(j);
            used += w + 2;
        }
    }
    for (b, block) in blocks.iter().enumerate() {
        if b > 0 {
            out.push('\n');
        }
        for line in 0..if split { 2 } else { 1 } {
            let (count, case) = if line == 0 { ("#", "case") } else { ("", "") };
            let mut text = format!("  {count:>count_width$}  {case:<row_width$}");
            for &j in block {
                let name = header(section.columns[shown[j]], split)[line];
                let w = widths[j];
                let _ = write!(text, "  {name:<w$}");
            }
            let _ = writeln!(out, "{}", text.trim_end());
        }
        for (g, row) in section.groups.iter().zip(&texts) {
            let mut line = format!(
                "  {:>count_width$}  {:<row_width$}",
                g.rows.len(),
                g.rows[0]
            );
            for &j in block {
                let (text, status) = &row[j];
                let style = cell_style(*status, coloured);
                let pad = widths[j].saturating_sub(text.chars().count());
                let _ = write!(line, "  {style}{text}{style:#}{}", " ".repeat(pad));
            }
            let _ = writeln!(out, "{}", line.trim_end());
        }
    }
    legend(out, section, &texts, &left_out, width);
    // What to act on: every group with a failing cell, with its rows and the representative's
    // explanation.
    for g in &section.groups {
        let failing: Vec<_> = g
            .cells
            .iter()
            .flatten()
            .filter(|r| r.status.is_failure())
            .collect();
        if failing.is_empty() {
            continue;
        }
        let mut rows = g
            .rows
            .iter()
            .take(LISTED_ROWS)
            .copied()
            .collect::<Vec<_>>()
            .join(", ");
        if g.rows.len() > LISTED_ROWS {
            let _ = write!(rows, " (+{} more)", g.rows.len() - LISTED_ROWS);
        }
        let _ = writeln!(out, "\n  group of {} ({rows}):", g.rows.len());
        for r in failing {
            for line in r.detail.lines() {
                let _ = writeln!(out, "    {line}");
            }
        }
    }
    out.push('\n');
}

/// The marks the section's cells use, and the columns left out, wrapped to `width`.
fn legend(
    out: &mut String,
    section: &Section<'_>,
    texts: &[Vec<(String, Status)>],
    left_out: &[String],
    width: usize,
) {
    let cells = || texts.iter().flatten();
    let mut marks = vec!["#: cases that behave alike, shown by the first"];
    if section.name.starts_with("cross-vendor") || section.name.starts_with("protocol ") {
        marks.push("cells are the answers");
    }
    if cells().any(|(_, s)| s.is_failure()) {
        marks.push("!: fails");
    }
    if cells().any(|(t, _)| t.ends_with(&format!(" {KNOWN}"))) {
        marks.push("*: a known difference of the backend");
    }
    if cells().any(|(t, _)| t == SKIPPED) {
        marks.push("-: skipped, the backend does not implement the case");
    }
    if cells().any(|(t, _)| t == ABSENT) {
        marks.push("n/a: not asked of that column");
    }
    wrap(out, &format!("({})", marks.join("; ")), width);
    for column in left_out {
        wrap(
            out,
            &format!("not shown, every case skipped: {column}"),
            width,
        );
    }
}

/// Writes `text` indented by two spaces, wrapped at spaces to fit `width`.
fn wrap(out: &mut String, text: &str, width: usize) {
    let mut line = String::new();
    for word in text.split(' ') {
        if !line.is_empty() && 2 + line.chars().count() + 1 + word.chars().count() > width {
            let _ = writeln!(out, "  {line}");
            line.clear();
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        let _ = writeln!(out, "  {line}");
    }
}
