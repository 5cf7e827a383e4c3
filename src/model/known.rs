//! Known differences: the trials a backend is expected to get wrong, each with its reason.
//!
//! An implementation under test rarely conforms everywhere on day one, and its authors need a
//! green run that still catches regressions. The list is loaded by [`crate::load`] and applied
//! by [`crate::judge`]: a listed trial that differs is a known difference, a listed trial that
//! conforms is a stale entry (a failure, so the list cannot rot), a fault is never excused.
//!
//! One cause ("accepts lowercase") usually shows in many cases, so an entry names either one
//! case or one cause with the cases it covers: by id pattern, or by a class of their input text.
//! Every trial an entry covers must differ, so a cause is narrowed to the inputs it explains.

use std::path::PathBuf;

pub(crate) use crate::spec::known::{InputClass, Kind};

/// Whether `id` matches `pattern`, where `*` stands for any run of characters.
pub(crate) fn id_matches(pattern: &str, id: &str) -> bool {
    let mut parts = pattern.split('*');
    let first = parts.next().unwrap_or_default();
    let Some(mut rest) = id.strip_prefix(first) else {
        return false;
    };
    let parts: Vec<&str> = parts.collect();
    let Some((last, middle)) = parts.split_last() else {
        return rest.is_empty();
    };
    for p in middle {
        match rest.find(p) {
            Some(at) => rest = &rest[at + p.len()..],
            None => return false,
        }
    }
    rest.len() >= last.len() && rest.ends_with(last)
}

/// What an entry covers.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum Covers {
    /// One case, by id.
    Case(String),
    /// The cases of one cause: those whose id matches a pattern or whose text has a class.
    Cause {
        patterns: Vec<String>,
        inputs: Vec<InputClass>,
    },
}

/// One validated entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Entry {
    pub covers: Covers,
    /// Only this instruction of the case (for a cross-vendor case: only this lowering).
    pub instruction: Option<String>,
    pub variant: Option<String>,
    pub kind: Option<Kind>,
    /// The protocol rule it breaks (`modbus-ascii/B3`), for protocol-field cases.
    pub rule: Option<String>,
    /// What a report shows: the reason, or the kind and the cause.
    pub reason: String,
    /// `file:line` of the entry, to point at when it goes stale.
    pub location: String,
    /// The other entries that cover the same trial (`file:line: reason`): one cause shadowing
    /// another is shown, never silent.
    pub also: Vec<String>,
}

/// The case a trial checks, as an entry looks at it.
#[derive(Debug, Clone, Copy)]
pub struct Subject<'a> {
    /// The case id, matched against an entry's case or its cause's id patterns.
    pub case: &'a str,
    /// A cross-vendor case's text; `None` for a case of an instruction's own corpus.
    pub text: Option<&'a [u8]>,
    /// The instruction of a native case, or the lowering of a cross-vendor one.
    pub instruction: &'a str,
    /// The variant (CPU model) the trial runs on.
    pub variant: &'a str,
}

impl Entry {
    /// Whether the entry covers a trial of this case, instruction (or lowering) and variant.
    pub(crate) fn matches(&self, s: &Subject<'_>) -> bool {
        let covered = match &self.covers {
            Covers::Case(c) => c == s.case,
            Covers::Cause { patterns, inputs } => {
                patterns.iter().any(|p| id_matches(p, s.case))
                    || s.text.is_some_and(|t| inputs.iter().any(|i| i.holds(t)))
            }
        };
        covered
            && self.instruction.as_ref().is_none_or(|i| i == s.instruction)
            && self.variant.as_ref().is_none_or(|v| v == s.variant)
    }

    /// The one case the entry lists, if it lists one.
    pub(crate) fn case(&self) -> Option<&str> {
        match &self.covers {
            Covers::Case(c) => Some(c),
            Covers::Cause { .. } => None,
        }
    }
}

/// A backend's validated known differences.
#[derive(Debug, Clone, Default)]
pub struct KnownDifferences {
    /// The known-differences file the entries were read from.
    pub file: PathBuf,
    pub(crate) entries: Vec<Entry>,
    /// Entries naming cases that are not in the corpus being run, when the corpus is not the
    /// project's own (`--vectors`): they are set aside rather than errors.
    pub(crate) ignored: Vec<Entry>,
}

impl KnownDifferences {
    /// Whether an entry of the file covers a trial: its case listed, or a cause it has.
    pub fn covers(&self, s: &Subject<'_>) -> bool {
        self.entries.iter().any(|e| e.matches(s))
    }

    /// The entry covering a trial, if any: the entry of its own case first, else the first cause
    /// that covers it.
    pub(crate) fn entry(&self, s: &Subject<'_>) -> Option<&Entry> {
        self.entries
            .iter()
            .find(|e| e.case().is_some() && e.matches(s))
            .or_else(|| self.entries.iter().find(|e| e.matches(s)))
    }

    /// [`KnownDifferences::entry`], with the other entries that cover the trial too: one pass
    /// over the entries (a sweep's file may hold tens of thousands).
    pub(crate) fn covering(&self, s: &Subject<'_>) -> Option<Entry> {
        let matching: Vec<&Entry> = self.entries.iter().filter(|e| e.matches(s)).collect();
        let first = (matching.iter().copied())
            .find(|e| e.case().is_some())
            .or_else(|| matching.first().copied())?;
        let mut entry = first.clone();
        entry.also = (matching.iter())
            .filter(|e| !std::ptr::eq(**e, first))
            .map(|e| format!("{}: {}", e.location, e.reason))
            .collect();
        Some(entry)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two entries covering one trial (a class and a list of cases): the case's own entry
    /// first, the other named beside it rather than never shown.
    #[test]
    fn an_entry_shadowed_by_another_is_named_beside_it() {
        let entry = |covers, location: &str| Entry {
            covers,
            instruction: None,
            variant: None,
            kind: None,
            rule: None,
            reason: format!("cause at {location}"),
            location: location.into(),
            also: Vec::new(),
        };
        let known = KnownDifferences {
            file: "k.yaml".into(),
            entries: vec![
                entry(
                    Covers::Cause {
                        patterns: Vec::new(),
                        inputs: vec![InputClass::Blank],
                    },
                    "k.yaml:2",
                ),
                entry(Covers::Case("xv-h2v-space".into()), "k.yaml:9"),
            ],
            ignored: Vec::new(),
        };
        let subject = Subject {
            case: "xv-h2v-space",
            text: Some(b"5A8 "),
            instruction: "codec",
            variant: "",
        };
        let covering = known.covering(&subject).expect("covered");
        assert_eq!(covering.location, "k.yaml:9");
        assert_eq!(covering.also, ["k.yaml:2: cause at k.yaml:2"]);
        let alone = Subject {
            case: "xv-h2v-tab",
            text: Some(b"5A8\t"),
            ..subject
        };
        let covering = known.covering(&alone).expect("covered by the class");
        assert_eq!(
            (covering.location.as_str(), covering.also.len()),
            ("k.yaml:2", 0)
        );
    }

    #[test]
    fn patterns_take_any_run_of_characters_for_a_star() {
        for (p, id, m) in [
            ("xv-h2v-6*h", "xv-h2v-61h", true),
            ("xv-h2v-6*h", "xv-h2v-66h", true),
            ("xv-h2v-6*h", "xv-h2v-60h-x", false),
            ("habin-*-is-invalid", "habin-fixed-61h-is-invalid", true),
            ("habin-*", "dhabin-x", false),
            ("*", "anything", true),
            ("exact", "exact", true),
            ("exact", "exactly", false),
            ("a*b*c", "abc", true),
            ("a*b*c", "acb", false),
        ] {
            assert_eq!(id_matches(p, id), m, "{p} {id}");
        }
    }

    #[test]
    fn each_class_holds_for_its_characters_only() {
        for (class, text, holds) in [
            (InputClass::Lowercase, &b"5a8D"[..], true),
            (InputClass::Lowercase, &b"5A8D"[..], false),
            // A reader's classes: the x of a prefix is no lowercase digit, nor another letter.
            (InputClass::Lowercase, &b"0x5A"[..], false),
            (InputClass::OtherLowercase, &b"0x5A"[..], false),
            (InputClass::OtherLowercase, &b"5A8g"[..], true),
            (InputClass::OtherLowercase, &b"x5A8"[..], true),
            (InputClass::OtherLowercase, &b"5a8f"[..], false),
            (InputClass::Blank, &b"5A\t8"[..], true),
            (InputClass::Sign, &b"-5A8"[..], true),
            (InputClass::HexPrefix, &b"0X5A"[..], true),
            (InputClass::HexPrefix, &b"05A8"[..], false),
            (InputClass::Underscore, &b"5_A8"[..], true),
            (InputClass::Above7fh, &b"5A\x80D"[..], true),
            (InputClass::Nul, &b"1\x0034"[..], true),
            (InputClass::Control, &b"1\x1F34"[..], true),
            (InputClass::Control, &b"1\t34"[..], false),
            (InputClass::Empty, &b""[..], true),
            (InputClass::OtherUppercase, &b"5AG8"[..], true),
            (InputClass::OtherUppercase, &b"5A8F"[..], false),
            (InputClass::Punctuation, &b"5A:8"[..], true),
            (InputClass::Punctuation, &b"5A8."[..], true),
            (InputClass::Punctuation, &b"-5A_8"[..], false),
            (InputClass::BlankLeading, &b" 5A8"[..], true),
            (InputClass::BlankLeading, &b"5A8 "[..], false),
            (InputClass::BlankTrailing, &b"5A8\t"[..], true),
            (InputClass::BlankInside, &b" 5A 8 "[..], true),
            (InputClass::BlankInside, &b" 5A8 "[..], false),
            (InputClass::BlankInside, &b"   "[..], false),
        ] {
            assert_eq!(
                class.holds(text),
                holds,
                "{class:?} {:?}",
                text.escape_ascii().to_string()
            );
        }
    }
}
