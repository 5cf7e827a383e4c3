//! The matrix as text: one table per section, one line per group of rows that behave alike,
//! then what a reader needs to act on each group that fails.

use std::fmt::Write;

use anstyle::{AnsiColor, Style};

use super::matrix::Section;
use crate::judge::Status;

/// How many row ids a group line lists before it says "+N more".
const LISTED_ROWS: usize = 4;

pub fn render(sections: &[Section<'_>], coloured: bool) -> String {
    let mut out = String::new();
    for section in sections {
        render_section(&mut out, section, coloured);
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

fn render_section(out: &mut String, section: &Section<'_>, coloured: bool) {
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
    // Cell texts: the representative's answer, marked `!` where it fails.
    let texts: Vec<Vec<(String, Status)>> = section
        .groups
        .iter()
        .map(|g| {
            g.cells
                .iter()
                .map(|c| match c {
                    Some(r) if r.status.is_failure() => (format!("{} !", r.shown), r.status),
                    Some(r) => (r.shown.clone(), r.status),
                    None => ("n/a".to_string(), Status::Skipped),
                })
                .collect()
        })
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
        .map(|g| g.rows[0].len())
        .max()
        .unwrap_or(0)
        .max(10);
    let widths: Vec<usize> = section
        .columns
        .iter()
        .enumerate()
        .map(|(i, c)| {
            texts
                .iter()
                .map(|row| row[i].0.chars().count())
                .max()
                .unwrap_or(0)
                .max(c.len())
        })
        .collect();
    let mut line = format!("  {:>count_width$}  {:<row_width$}", "#", "case");
    for (c, w) in section.columns.iter().zip(&widths) {
        let _ = write!(line, "  {c:<w$}");
    }
    let _ = writeln!(out, "{}", line.trim_end());
    for (g, row) in section.groups.iter().zip(&texts) {
        let mut line = format!(
            "  {:>count_width$}  {:<row_width$}",
            g.rows.len(),
            g.rows[0]
        );
        for ((text, status), w) in row.iter().zip(&widths) {
            let style = cell_style(*status, coloured);
            let pad = w.saturating_sub(text.chars().count());
            let _ = write!(line, "  {style}{text}{style:#}{}", " ".repeat(pad));
        }
        let _ = writeln!(out, "{}", line.trim_end());
    }
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
