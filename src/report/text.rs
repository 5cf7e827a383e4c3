//! Human-readable rendering of a trial's result: where the case is, what ran, and a word-by-word
//! diff of expected against actual memory.

use std::fmt::Write;

use anstyle::{AnsiColor, Style};

use super::sanitize::terminal;
use crate::judge::{Difference, Mismatch, Verdict, WordRow};
use crate::memory::{Unit, Value};
use crate::model::cross_vendor::Operation;
use crate::model::{error_text, Case};
use crate::plan::{Check, Trial};
use crate::value::hex_word;

/// Styles for the text report; all plain unless colour is on, so the same renderer serves a
/// terminal, a log file and libtest's captured output.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Palette {
    pub removed: Style,
    pub added: Style,
    pub heading: Style,
    pub note: Style,
}

impl Palette {
    pub(crate) fn plain() -> Self {
        Palette::default()
    }
    pub(crate) fn coloured() -> Self {
        Palette {
            removed: AnsiColor::Red.on_default(),
            added: AnsiColor::Green.on_default(),
            heading: Style::new().bold(),
            note: AnsiColor::Cyan.on_default(),
        }
    }
}

/// A unit as a report line shows it: device, hex value, and its bytes as characters in memory
/// order (a word's low byte first).
pub(crate) fn word_line(device: &impl std::fmt::Display, value: Value, unit: Unit) -> String {
    let bytes = (unit.bits() / 8) as usize;
    let chars: String = value.to_le_bytes()[..bytes]
        .iter()
        .map(|b| show_byte(*b))
        .collect();
    format!("{:<8} {}  \"{chars}\"", device.to_string(), unit.hex(value))
}

fn show_byte(b: u8) -> String {
    match b {
        0 => "\\0".to_string(),
        0x20..=0x7E if b != b'"' && b != b'\\' => (b as char).to_string(),
        _ => format!("\\x{b:02X}"),
    }
}

/// The trial's setting: what ran, with which flags, operands and memory.
pub(crate) fn describe_setting(trial: &Trial) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  case:        {} (basis: {}; {})",
        trial.case_id(),
        trial.basis(),
        trial.citation()
    );
    if let Some(case) = trial.cross_vendor_case() {
        let question = match case.operation {
            Operation::HexToValue | Operation::Check | Operation::Verify => format!(
                "{} {}, {} digit(s)",
                case.operation,
                crate::model::cross_vendor::Answer::Text(case.text.clone()),
                case.digits
            ),
            Operation::ValueToHex => format!(
                "{} {}, {} digit(s)",
                case.operation,
                crate::model::cross_vendor::Answer::Value(case.value),
                case.digits
            ),
        };
        let _ = writeln!(out, "  question:    {question}");
        if let Some(from) = &case.protocol {
            let _ = writeln!(
                out,
                "  field:       {} of {}\n  rule:        {}",
                from.field, from.protocol, from.rule
            );
        } else if let Some(p) = (trial.backend.codec()).and_then(|c| c.protocol.as_ref()) {
            let _ = writeln!(
                out,
                "  view:        cross-vendor: an instruction manual decides this case, no rule \
                 of {}",
                p.id
            );
        }
        match &trial.check {
            Check::CrossVendor { lowering, .. } => {
                let _ = writeln!(
                    out,
                    "  lowering:    {}: {}",
                    lowering.key, lowering.description
                );
            }
            _ => {
                let _ = writeln!(
                    out,
                    "  run:         the codec of backend {} (no memory, devices or fills)",
                    trial.backend.name()
                );
                return out;
            }
        }
    }
    let Some(profile) = &trial.profile else {
        return out;
    };
    let input = &trial.input;
    let _ = writeln!(
        out,
        "  run:         {} on {} variant {} via backend {}",
        input.instruction,
        profile.id,
        trial.variant,
        trial.backend.name()
    );
    let _ = writeln!(out, "  flags:       {}", flags_text(trial, profile));
    let operands: Vec<String> = input
        .operands
        .iter()
        .map(|(k, v)| match input.indirect.get(k) {
            Some(pointer) => format!("{k}=@{pointer} ({v})"),
            None => format!("{k}={v}"),
        })
        .collect();
    let _ = writeln!(out, "  operands:    {}", operands.join(" "));
    let before: Vec<String> = input
        .before
        .iter()
        .map(|(d, v)| format!("{d}={}", profile.unit.hex(*v)))
        .collect();
    let _ = writeln!(
        out,
        "  memory set:  {}",
        if before.is_empty() {
            "(none; all fill)".to_string()
        } else {
            before.join(" ")
        }
    );
    out
}

fn flags_text(trial: &Trial, profile: &crate::model::profile::Profile) -> String {
    let Some(def) = profile.instructions.get(&trial.input.instruction) else {
        return String::new();
    };
    let variant = profile.variant(&trial.variant);
    def.flags
        .iter()
        .map(|f| {
            let on = trial
                .input
                .flags
                .get(f)
                .copied()
                .unwrap_or_else(|| profile.flag_default(f));
            let ignored = variant.is_some_and(|v| v.ignores_flags.contains(f));
            format!(
                "{f}={}{}",
                if on { "on" } else { "off" },
                if ignored {
                    " (not supported by this variant)"
                } else {
                    ""
                }
            )
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The full report of one trial that did not conform, or of a recorded `unspecified` case.
pub(crate) fn render(trial: &Trial, verdict: &Verdict, palette: Palette) -> String {
    let mut out = String::new();
    let h = palette.heading;
    let _ = writeln!(
        out,
        "{h}{}: {} {}{h:#}",
        terminal(&trial.location().to_string()),
        trial.name(),
        verdict.label()
    );
    // A cite, a note or a backend's output may hold escape sequences: none reaches a terminal.
    out.push_str(&terminal(&describe_setting(trial)));
    // A codec reads no memory: its one answer has no fill to name.
    let fills = !matches!(trial.check, Check::Codec { .. });
    render_body(&mut out, verdict, palette, fills);
    out
}

fn render_body(out: &mut String, verdict: &Verdict, palette: Palette, fills: bool) {
    match verdict {
        Verdict::Conforms => {}
        Verdict::KnownDifference { entry, difference } => {
            let _ = writeln!(
                out,
                "  known difference ({}): {}",
                terminal(&entry.location.to_string()),
                terminal(&entry.reason)
            );
            for other in &entry.also {
                let _ = writeln!(out, "  also covered by {}", terminal(other));
            }
            render_body(out, difference, palette, fills);
        }
        Verdict::StaleEntry { entry } => {
            let _ = writeln!(
                out,
                "  listed as a known difference at {} ({}), but conforms: remove the entry",
                terminal(&entry.location.to_string()),
                terminal(&entry.reason)
            );
        }
        Verdict::Differs {
            difference: Difference::Words { mismatches },
        } => {
            // Fills that went wrong the same way are shown once.
            let mut shown: Vec<(String, Vec<&str>)> = Vec::new();
            for m in mismatches {
                let body = render_mismatch(m, palette);
                match shown.iter_mut().find(|(b, _)| *b == body) {
                    Some((_, fills)) => fills.push(m.fill.name()),
                    None => shown.push((body, vec![m.fill.name()])),
                }
            }
            for (body, fills) in shown {
                let fill = match fills.as_slice() {
                    ["A"] => "with fill A (words the vector does not set hold bytes A0H-A7H)",
                    ["B"] => {
                        "with fill B (words the vector does not set hold hex digit characters)"
                    }
                    _ => "with either fill",
                };
                let _ = writeln!(out, "  {fill}:");
                out.push_str(&body);
            }
        }
        Verdict::Differs {
            difference: Difference::Answer { expected, actual },
        } => {
            let _ = writeln!(
                out,
                "  answer: expected {}{expected}{:#}, actual {}{actual}{:#}",
                palette.removed, palette.removed, palette.added, palette.added
            );
        }
        Verdict::Differs {
            difference: Difference::FillDependent { fill_a, fill_b },
        } => {
            let _ = writeln!(
                out,
                "  the answer depends on memory the case does not set: {fill_a} under fill A, \
                 {fill_b} under fill B"
            );
        }
        Verdict::Unsupported { reason } => {
            let _ = writeln!(
                out,
                "  the backend claims this trial but answered unsupported: {}",
                terminal(reason)
            );
        }
        Verdict::Fault { fault, .. } if !fills => {
            let _ = writeln!(out, "  {}", terminal(&fault.to_string()));
        }
        Verdict::Fault { fill, fault } => {
            let _ = writeln!(
                out,
                "  fill {}: {}",
                fill.name(),
                terminal(&fault.to_string())
            );
        }
        Verdict::Skipped { .. } | Verdict::Cancelled => {
            let reason = verdict.not_run().unwrap_or_default();
            let _ = writeln!(out, "  skipped: {}", terminal(reason));
        }
        Verdict::Recorded {
            observed,
            fill_dependent,
        } => {
            let _ = writeln!(
                out,
                "  {}observed:{:#} {}",
                palette.note,
                palette.note,
                terminal(&observed.to_string())
            );
            if *fill_dependent {
                let _ = writeln!(
                    out,
                    "  the outcome depends on the fill (it reads memory the vector does not set)"
                );
            }
        }
    }
}

fn render_mismatch(m: &Mismatch, palette: Palette) -> String {
    let mut out = String::new();
    if m.words_differ() {
        let _ = writeln!(
            out,
            "  memory ({}- expected{:#}, {}+ actual{:#}):",
            palette.removed, palette.removed, palette.added, palette.added
        );
        out.push_str(&memory_diff(&m.rows, palette));
    }
    if m.error_differs() {
        let _ = writeln!(
            out,
            "  error: expected {}{}{:#}, actual {}{}{:#}",
            palette.removed,
            error_text(m.expected_error.as_ref()),
            palette.removed,
            palette.added,
            error_text(m.actual_error.as_ref()),
            palette.added
        );
    }
    for r in m.wrong_registers() {
        let _ = writeln!(
            out,
            "  {} (where the error code lands): expected {}{}{:#}, actual {}{}{:#}",
            r.device,
            palette.removed,
            hex_word(r.expected),
            palette.removed,
            palette.added,
            r.actual.map_or("not reported".to_string(), hex_word),
            palette.added
        );
    }
    out
}

/// Lines of a memory diff shown at most: a mismatch over thousands of words shows its first and
/// last lines and says how many it leaves out.
const MAX_DIFF_LINES: usize = 64;

/// A unified diff of expected against actual words, one word per line. The rows are aligned by
/// device already, so it is made in one pass (no line-matching diff, whose time grows with the
/// square of a long listing): each run of differing words shows its expected lines, then its
/// actual ones, as a unified diff would.
pub(crate) fn memory_diff(rows: &[WordRow], palette: Palette) -> String {
    let mut lines: Vec<String> = Vec::new();
    let mut run: Vec<&WordRow> = Vec::new();
    let flush = |run: &mut Vec<&WordRow>, lines: &mut Vec<String>| {
        for r in run.iter() {
            let line = word_line(&r.device, r.expected, r.unit);
            lines.push(format!("    {0}-{line}{0:#}", palette.removed));
        }
        for r in run.drain(..) {
            let line = word_line(&r.device, r.actual, r.unit);
            lines.push(format!("    {0}+{line}{0:#}", palette.added));
        }
    };
    for row in rows {
        if row.expected == row.actual {
            flush(&mut run, &mut lines);
            let line = word_line(&row.device, row.expected, row.unit);
            lines.push(format!("    {0} {line}{0:#}", Style::new()));
        } else {
            run.push(row);
        }
    }
    flush(&mut run, &mut lines);
    let mut out = String::new();
    let shown = MAX_DIFF_LINES / 2;
    for (i, line) in lines.iter().enumerate() {
        if lines.len() > MAX_DIFF_LINES && i >= shown && i < lines.len() - shown {
            if i == shown {
                let _ = writeln!(
                    out,
                    "    ... {} more lines of {} words ({} differ) ...",
                    lines.len() - 2 * shown,
                    rows.len(),
                    rows.iter().filter(|r| r.expected != r.actual).count()
                );
            }
            continue;
        }
        let _ = writeln!(out, "{line}");
    }
    out
}

/// One line for a case in `list`.
pub(crate) fn case_line(case: &Case) -> String {
    format!(
        "{:<44} {:<11} {}  [{}]",
        case.id,
        case.basis.to_string(),
        case.location,
        case.instructions.join(",")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::judge::words::RegisterRow;
    use crate::memory::Fill;
    use crate::model::ErrorSignal;

    fn rows(values: &[(u32, u32)]) -> Vec<WordRow> {
        values
            .iter()
            .enumerate()
            .map(|(i, &(expected, actual))| WordRow {
                device: format!("D{}", 200 + i).parse().expect("device"),
                unit: crate::memory::Unit::Word,
                before: 0,
                expected,
                actual,
            })
            .collect()
    }

    #[test]
    fn a_run_of_differing_words_shows_its_expected_lines_then_its_actual_ones() {
        let diff = memory_diff(&rows(&[(1, 1), (2, 3), (4, 5), (6, 6)]), Palette::plain());
        let signs: Vec<char> = diff
            .lines()
            .map(|l| l.chars().nth(4).unwrap_or('?'))
            .collect();
        assert_eq!(signs, [' ', '-', '-', '+', '+', ' '], "{diff}");
        assert!(
            diff.lines().nth(1).is_some_and(|l| l.contains("D201")),
            "{diff}"
        );
        assert!(
            diff.lines().nth(3).is_some_and(|l| l.contains("D201")),
            "{diff}"
        );
    }

    #[test]
    fn a_mismatch_over_thousands_of_words_is_listed_bounded() {
        let values: Vec<(u32, u32)> = (0..32_767).map(|i| (i % 7, (i + 1) % 7)).collect();
        let diff = memory_diff(&rows(&values), Palette::plain());
        assert_eq!(diff.lines().count(), MAX_DIFF_LINES + 1, "{diff}");
        assert!(
            diff.contains("more lines of 32767 words (32767 differ)"),
            "{diff}"
        );
    }

    #[test]
    fn a_register_that_does_not_hold_the_code_is_shown_alone() {
        let row = |device: &str, actual| RegisterRow {
            device: device.parse().expect("device"),
            expected: 0x3401,
            actual,
        };
        let m = Mismatch {
            fill: Fill::A,
            rows: Vec::new(),
            expected_error: Some(ErrorSignal::Code(0x3401)),
            actual_error: Some(ErrorSignal::Code(0x3401)),
            registers: vec![row("SD0", Some(0x3401)), row("SD8067", None)],
        };
        assert_eq!(
            render_mismatch(&m, Palette::plain()),
            "  SD8067 (where the error code lands): expected 3401H, actual not reported\n"
        );
    }

    /// An operand given by indirect specification is shown as the vector writes it, with the
    /// device it addresses: `s=@D150 (D100)`.
    #[test]
    fn the_setting_shows_an_indirect_operand_with_what_it_addresses() {
        let project = crate::test_support::session();
        let model = crate::test_support::reference(&project, "mitsubishi-fx5");
        let trials = project.plan(&[model]);
        let trial = trials
            .iter()
            .find(|t| t.case_id() == "asci-indirect-source")
            .expect("the indirect case is planned");
        let text = describe_setting(trial);
        assert!(
            text.contains("operands:    d=D200 n=K4 s=@D150 (D100)"),
            "{text}"
        );
    }
}
