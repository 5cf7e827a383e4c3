//! A starting known-differences file for a backend: what `record --known` writes.
//!
//! A library's author meets its differences all at once, dozens of them, most from a few causes.
//! The draft runs the backend's trials without its known-differences file and lists what differs,
//! grouped the way a cause is written: an input class of the cross-vendor cases (lowercase,
//! signs, ...) becomes one entry when every trial with text of that class differs, and what no
//! class explains is listed case by case. Each entry still needs its cause put in words and its
//! kind checked: the draft says so in the text it writes, and it loads and covers exactly the
//! trials that differ, so the run is green with it until the author edits it.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::sync::Arc;

use crate::backend::Backend;
use crate::corpus_yaml::{folded, name_of, quote_str};
use crate::judge::{Difference, Verdict};
use crate::model::known::InputClass;
use crate::plan::Trial;
use crate::project::Project;
use crate::session::verdicts;
use crate::value::hex_word;

/// Every input class, in the order the draft tries them. The coarse classes first: a finer one (a blank's position) only where a coarse one does not
/// differ on every case it holds.
const CLASSES: [InputClass; 15] = [
    InputClass::Lowercase,
    InputClass::OtherLowercase,
    InputClass::OtherUppercase,
    InputClass::Punctuation,
    InputClass::Blank,
    InputClass::Sign,
    InputClass::HexPrefix,
    InputClass::Underscore,
    InputClass::Above7fh,
    InputClass::Nul,
    InputClass::Control,
    InputClass::Empty,
    InputClass::BlankLeading,
    InputClass::BlankTrailing,
    InputClass::BlankInside,
];

/// The draft and what it holds.
#[derive(Debug)]
pub struct Draft {
    /// The file's text (YAML).
    pub text: String,
    /// Entries by input class.
    pub causes: usize,
    /// Entries of one case.
    pub cases: usize,
    /// Trials that faulted: a fault is never a known difference, so they are not listed.
    pub faults: Vec<String>,
}

/// What one trial did, as the draft sorts it.
struct Seen<'a> {
    trial: &'a Trial,
    differs: bool,
    what: String,
}

/// The draft for `backend` (its trials whose name contains `filter`), run without its
/// known-differences file.
pub fn draft(project: &Project, backend: &Arc<dyn Backend>, filter: Option<&str>) -> Draft {
    let mut known = project.known.clone();
    known.remove(backend.name());
    let trials: Vec<Trial> = crate::plan::plan(
        &project.corpus,
        &project.profiles,
        std::slice::from_ref(backend),
        &known,
    )
    .into_iter()
    .filter(|t| t.skip.is_none())
    .filter(|t| filter.is_none_or(|f| t.name().contains(f)))
    .collect();
    let mut faults = Vec::new();
    let mut seen = Vec::new();
    for (t, v) in trials.iter().zip(verdicts(&trials)) {
        match &v {
            Verdict::Differs { difference } => seen.push(Seen {
                trial: t,
                differs: true,
                what: describe(difference),
            }),
            Verdict::Unsupported { reason } => seen.push(Seen {
                trial: t,
                differs: true,
                what: format!("answers that it does not implement it ({reason})"),
            }),
            Verdict::Fault { .. } => faults.push(t.name()),
            _ => seen.push(Seen {
                trial: t,
                differs: false,
                what: String::new(),
            }),
        }
    }
    let text_of = |t: &Trial| t.cross_vendor_case().map(|case| case.text.clone());
    let mut explained: BTreeSet<usize> = BTreeSet::new();
    let mut out = String::from(HEADER);
    let mut causes = 0;
    for class in CLASSES {
        let with: Vec<usize> = (0..seen.len())
            .filter(|&i| text_of(seen[i].trial).is_some_and(|t| class.holds(&t)))
            .collect();
        let new = with.iter().filter(|i| !explained.contains(i)).count();
        if with.len() < 2 || new == 0 || !with.iter().all(|&i| seen[i].differs) {
            continue;
        }
        let ids: BTreeSet<&str> = with.iter().map(|&i| seen[i].trial.case_id()).collect();
        let name = name_of(&class);
        let cause = format!(
            "differs on every case whose text has {name}: say what the implementation does"
        );
        let ids = ids.into_iter().collect::<Vec<_>>().join(", ");
        let _ = write!(
            out,
            "  - cause: {}\n    kind: bug\n    input: [{name}]\n    reason: {}\n",
            quote_str(&cause),
            folded("    ", &ids)
        );
        explained.extend(with);
        causes += 1;
    }
    // What no class explains, case by case: the case alone when every trial of it differs,
    // else each differing instruction and variant.
    let mut by_case: BTreeMap<&str, Vec<&Seen<'_>>> = BTreeMap::new();
    for s in &seen {
        by_case.entry(s.trial.case_id()).or_default().push(s);
    }
    let mut cases = 0;
    let mut listed: BTreeSet<&str> = BTreeSet::new();
    for (i, s) in seen.iter().enumerate() {
        if !s.differs || explained.contains(&i) {
            continue;
        }
        let whole = by_case[s.trial.case_id()].iter().all(|o| o.differs);
        if whole && !listed.insert(s.trial.case_id()) {
            continue;
        }
        let _ = writeln!(out, "  - case: {}", s.trial.case_id());
        // A protocol's case is judged by one of its manual's rules, which the entry names.
        if let Some(rule) = rule_of(s.trial) {
            let _ = writeln!(out, "    rule: {rule}");
        }
        if !whole {
            let _ = write!(
                out,
                "    instruction: {}\n    variant: {}\n",
                s.trial.check_name(),
                s.trial.variant
            );
        }
        let reason = format!(
            "{} (say what the implementation does and the manual rule it breaks)",
            s.what
        );
        let _ = writeln!(out, "    reason: {}", folded("    ", &reason));
        cases += 1;
    }
    Draft {
        text: out,
        causes,
        cases,
        faults,
    }
}

/// The protocol rule a trial's case rests on (`mc-ascii/M4`), for a protocol-field case.
fn rule_of(trial: &Trial) -> Option<&str> {
    let protocol = trial.cross_vendor_case()?.protocol.as_ref()?;
    Some(protocol.rule.key.as_str())
}

/// One line on what a trial did.
fn describe(difference: &Difference) -> String {
    match difference {
        Difference::Answer { expected, actual } => {
            format!("answers {actual} where the case expects {expected}")
        }
        Difference::FillDependent { fill_a, fill_b } => {
            format!("answers {fill_a} or {fill_b}, depending on memory the case does not set")
        }
        Difference::Words { mismatches } => match mismatches.first() {
            Some(m) if m.error_differs() => format!(
                "ends in {} where the case expects {}",
                m.actual_error
                    .as_ref()
                    .map_or("no error".to_string(), |e| format!("error {e}")),
                m.expected_error
                    .as_ref()
                    .map_or("no error".to_string(), |e| format!("error {e}"))
            ),
            Some(m) if m.only_registers_differ() => m
                .wrong_registers()
                .map(|r| {
                    format!(
                        "leaves {} {} after error {}",
                        r.device,
                        r.actual.map_or("unreported".to_string(), hex_word),
                        hex_word(r.expected)
                    )
                })
                .collect::<Vec<_>>()
                .join(", "),
            _ => "writes other words than the case expects".to_string(),
        },
    }
}

const HEADER: &str = "\
# A starting known-differences file, written by `plc-conformance record --known`: what the
# backend does differently from the corpus, an entry by input class where every case of the
# class differs, else a case at a time. Before keeping it, put each cause in words (what the
# implementation does), say whether it is a `bug` or `by-design`, and add the manual rule it
# breaks: docs/check-your-library.md, section 4. Schema: `plc-conformance schema --kind known`.
differences:
";
