//! Known differences: the cases a backend is expected to get wrong, each with its reason.
//!
//! An implementation under test rarely conforms everywhere on day one, and its authors need a
//! green run that still catches regressions. A listed trial that differs passes as a "known
//! difference"; a listed trial that conforms fails as a "stale entry", so the list shrinks as
//! the implementation improves and can never rot; an unlisted difference fails as usual. A
//! fault is never excused by the list: a crash is not a difference of semantics.
//!
//! ```yaml
//! differences:
//!   - case: habin-fixed-lowercase-is-invalid
//!     instruction: HABIN        # optional: every instruction of the case when absent
//!     variant: rcpu             # optional: every variant when absent
//!     reason: "int(text, 16) accepts lowercase digits"
//! ```

use std::path::Path;

use super::{FileContext, LoadErrorKind, LoadErrors};
use crate::model::cross_vendor::CrossVendorCase;
use crate::model::known::{id_matches, Covers, Entry, KnownDifferences};
use crate::model::profile::Profile;
use crate::model::{Basis, Corpus};
use crate::spec::known::KnownFileSpec;

/// The entries read so far, for the duplicate check: where each was, by what it covers and by
/// its cause, each within its instruction and variant. Maps, so that a file of tens of
/// thousands of entries (a sweep's, written by `record --known`) loads in linear time.
#[derive(Default)]
struct Seen {
    by_covers: std::collections::HashMap<(Covers, Option<String>, Option<String>), String>,
    by_cause: std::collections::HashMap<(String, Option<String>, Option<String>), String>,
}

/// Loads and checks a known-differences file against the backend's profile (`None` for a
/// codec-level backend, which runs the cross-vendor cases only) and the corpus. With `strict`,
/// an entry for a case the corpus does not have is an error (a typo would otherwise excuse
/// nothing and go unnoticed); without it, such entries are set aside.
pub fn load_known(
    file: &Path,
    profile: Option<&Profile>,
    corpus: &Corpus,
    strict: bool,
) -> Result<KnownDifferences, LoadErrors> {
    super::load_document(file, |spec: KnownFileSpec, cx| {
        let mut known = KnownDifferences {
            file: file.to_path_buf(),
            ..KnownDifferences::default()
        };
        // What each entry so far covers, for the duplicate check.
        let mut seen = Seen::default();
        for (i, e) in spec.differences.into_iter().enumerate() {
            let key = |k: &str| format!("differences[{i}].{k}");
            let location = cx.location(&format!("differences[{i}]")).to_string();
            let by_cause = !e.cases.is_empty() || !e.input.is_empty();
            let reason = e.reason.as_deref().map(str::trim).unwrap_or_default();
            let covers = match (&e.case, by_cause) {
                (Some(_), true) => {
                    cx.error(
                        key("case"),
                        LoadErrorKind::Invalid(
                            "an entry lists one `case`, or one cause's `cases`/`input`, not both"
                                .into(),
                        ),
                    );
                    continue;
                }
                (None, false) => {
                    cx.error(
                        key("case"),
                        LoadErrorKind::Invalid(
                            "an entry needs the `case` it lists, or the `cases` (id patterns) or \
                             `input` (classes of text) of its cause"
                                .into(),
                        ),
                    );
                    continue;
                }
                (Some(_), false) if e.cause.is_some() => {
                    cx.error(
                        key("cause"),
                        LoadErrorKind::Invalid(
                            "an entry of one `case` gives its `reason`; a `cause` (with its `kind`) \
                             covers `cases` (id patterns) or `input` (classes of text): for a cause \
                             seen on one case, write `cases: [ID]`"
                                .into(),
                        ),
                    );
                    continue;
                }
                (Some(c), false) => Covers::Case(c.clone()),
                (None, true) => Covers::Cause {
                    patterns: e.cases.clone(),
                    inputs: e.input.clone(),
                },
            };
            let shown = match (&covers, e.cause.as_deref().map(str::trim)) {
                (Covers::Cause { .. }, None | Some("")) => {
                    cx.error(
                        key("cause"),
                        LoadErrorKind::Invalid(
                            "an entry by cause needs its `cause`: what the implementation does"
                                .into(),
                        ),
                    );
                    continue;
                }
                (Covers::Cause { .. }, Some(cause)) => {
                    if e.kind.is_none() {
                        cx.error(
                            key("kind"),
                            LoadErrorKind::Invalid(
                                "an entry by cause needs its `kind`: `bug` or `by-design`".into(),
                            ),
                        );
                    }
                    let kind = e.kind.map(|k| format!(" ({k})")).unwrap_or_default();
                    if reason.is_empty() {
                        format!("{cause}{kind}")
                    } else {
                        format!("{cause}{kind}: {reason}")
                    }
                }
                (Covers::Case(_), _) => match (e.kind, reason.is_empty()) {
                    (_, true) => String::new(),
                    (None, false) => reason.to_string(),
                    (Some(kind), false) => format!("{reason} ({kind})"),
                },
            };
            let shown = match &e.rule {
                Some(rule) => format!("{shown} [{rule}]"),
                None => shown,
            };
            let entry = Entry {
                covers,
                instruction: e.instruction,
                variant: e.variant,
                kind: e.kind,
                rule: e.rule,
                reason: shown,
                location,
                also: Vec::new(),
            };
            check_rule(&entry, corpus, strict, cx, &key);
            if entry.reason.is_empty() {
                cx.error(
                    key("reason"),
                    LoadErrorKind::Invalid("a known difference needs its reason".into()),
                );
            }
            // Two entries for the same trials, or two naming one cause for the same instruction
            // and variant, would say the same thing twice, or two things about one trial.
            let cause = e.cause.as_deref().map(str::trim).map(str::to_string);
            let (instruction, variant) = (entry.instruction.clone(), entry.variant.clone());
            let covers_key = (entry.covers.clone(), instruction.clone(), variant.clone());
            let cause_key = cause.map(|c| (c, instruction, variant));
            let twin = (seen.by_covers.get(&covers_key))
                .or_else(|| cause_key.as_ref().and_then(|k| seen.by_cause.get(k)));
            if let Some(first) = twin {
                cx.error(
                    key(if entry.case().is_some() {
                        "case"
                    } else {
                        "cause"
                    }),
                    LoadErrorKind::Invalid(format!(
                        "the same {} already listed at {first}: one entry says it once",
                        match entry.covers {
                            Covers::Case(_) => "trials are",
                            Covers::Cause { .. } => "cause is",
                        },
                    )),
                );
                continue;
            }
            seen.by_covers.insert(covers_key, entry.location.clone());
            if let Some(k) = cause_key {
                seen.by_cause.insert(k, entry.location.clone());
            }
            if let Covers::Cause { patterns, .. } = &entry.covers {
                check_cause(&entry, patterns, profile, corpus, strict, cx, &key);
                known.entries.push(entry);
                continue;
            }
            let case_id = entry.case().unwrap_or_default().to_string();
            let cross_vendor = (corpus.cross_vendor.iter())
                .chain(&corpus.protocol_fields)
                .find(|c| c.id == case_id);
            let Some(profile) = profile else {
                // A codec has neither instructions nor variants, and answers cross-vendor cases only.
                codec_has_no_instruction(&entry, cx, &key);
                match cross_vendor {
                    Some(cv) => {
                        check_not_unspecified(&entry, cv.basis, cx, &key);
                        known.entries.push(entry);
                    }
                    None if strict => cx.error(
                        key("case"),
                        LoadErrorKind::Invalid(format!(
                            "unknown cross-vendor case id `{}`: a codec-level backend runs only the \
                             cross-vendor cases",
                            case_id
                        )),
                    ),
                    None => known.ignored.push(entry),
                }
                continue;
            };
            if let Some(cv) = cross_vendor {
                check_cross_vendor_entry(&entry, cv, profile, cx, &key);
                known.entries.push(entry);
                continue;
            }
            let Some(case) = corpus
                .cases
                .iter()
                .find(|c| c.id == case_id && c.profiles.contains(&profile.id))
            else {
                if strict {
                    cx.error(
                        key("case"),
                        LoadErrorKind::Invalid(format!(
                            "unknown case id `{}`: no case of profile {} has it",
                            case_id, profile.id
                        )),
                    );
                } else {
                    known.ignored.push(entry);
                }
                continue;
            };
            check_not_unspecified(&entry, case.basis, cx, &key);
            if let Some(i) = &entry.instruction {
                if !case.instructions.contains(i) {
                    cx.error(
                        key("instruction"),
                        LoadErrorKind::Unknown {
                            what: "instruction of this case",
                            name: i.clone(),
                            expected: case.instructions.to_vec(),
                        },
                    );
                }
            }
            if let Some(v) = &entry.variant {
                let runs: Vec<String> = profile
                    .variants
                    .iter()
                    .filter(|pv| case.runs_on(&pv.id))
                    .map(|pv| pv.id.clone())
                    .collect();
                if !runs.contains(v) {
                    cx.error(
                        key("variant"),
                        LoadErrorKind::Unknown {
                            what: "variant of this case",
                            name: v.clone(),
                            expected: runs,
                        },
                    );
                }
            }
            known.entries.push(entry);
        }
        known
    })
}

/// An entry by cause: each id pattern must cover a case the backend can run (against the
/// project's own corpus, `strict`), and the instruction and variant it narrows to must exist (a
/// typo would excuse nothing and go unnoticed).
fn check_cause(
    entry: &Entry,
    patterns: &[String],
    profile: Option<&Profile>,
    corpus: &Corpus,
    strict: bool,
    cx: &mut FileContext<'_>,
    key: &dyn Fn(&str) -> String,
) {
    let ids: Vec<&str> = match profile {
        None => (corpus.cross_vendor.iter())
            .chain(&corpus.protocol_fields)
            .map(|c| c.id.as_str())
            .collect(),
        Some(p) => corpus
            .cases
            .iter()
            .filter(|c| c.profiles.contains(&p.id))
            .map(|c| c.id.as_str())
            .chain(corpus.cross_vendor.iter().map(|c| c.id.as_str()))
            .collect(),
    };
    for (j, p) in patterns.iter().enumerate() {
        if strict && !ids.iter().any(|id| id_matches(p, id)) {
            cx.error(
                format!("{}[{j}]", key("cases")),
                LoadErrorKind::Invalid(format!("`{p}` matches no case this backend runs")),
            );
        }
    }
    match profile {
        None => {
            codec_has_no_instruction(entry, cx, key);
        }
        Some(p) => variant_exists(entry, p, cx, key),
    }
}

/// An entry that names protocol-field cases only (by id or pattern) names the protocol rule
/// they break, one of theirs; an entry that names none names no rule. An entry by input class
/// covers whatever text holds the class, in either view, and names no rule it must break.
fn check_rule(
    entry: &Entry,
    corpus: &Corpus,
    strict: bool,
    cx: &mut FileContext<'_>,
    key: &dyn Fn(&str) -> String,
) {
    // By id or pattern only: no text, so no input class matches.
    let names = |c: &CrossVendorCase| {
        entry.matches(&crate::model::known::Subject {
            case: &c.id,
            text: None,
            instruction: "codec",
            variant: "",
        })
    };
    let rules: std::collections::BTreeSet<&str> = (corpus.protocol_fields.iter())
        .filter(|c| names(c))
        .filter_map(|c| c.protocol.as_ref().map(|p| p.rule.key.as_str()))
        .collect();
    let listed = || rules.iter().copied().collect::<Vec<_>>().join(", ");
    // An entry that also covers cases of no protocol (`cases: ['*']`) is about the codec, not
    // a protocol's rule.
    let beyond = corpus.cross_vendor.iter().any(|c| names(c));
    match &entry.rule {
        None if !rules.is_empty() && !beyond => cx.error(
            key("rule"),
            LoadErrorKind::Invalid(format!(
                "an entry for protocol-field cases names the rule it breaks: `rule: {}`",
                listed()
            )),
        ),
        // A corpus narrowed to some files (`--vectors`) may hold none of the entry's cases.
        Some(rule) if rules.is_empty() && strict => cx.error(
            key("rule"),
            LoadErrorKind::Invalid(format!(
                "`{rule}` is a protocol rule, and the entry covers no protocol-field case"
            )),
        ),
        Some(rule) if !rules.is_empty() && !rules.contains(rule.as_str()) => cx.error(
            key("rule"),
            LoadErrorKind::Invalid(format!(
                "the cases this entry covers test {}, not `{rule}`",
                listed()
            )),
        ),
        _ => {}
    }
}

/// An entry's `variant` names a variant of the profile.
fn variant_exists(
    entry: &Entry,
    profile: &Profile,
    cx: &mut FileContext<'_>,
    key: &dyn Fn(&str) -> String,
) {
    if let Some(v) = &entry.variant {
        if profile.variant(v).is_none() {
            let known: Vec<String> = profile.variants.iter().map(|v| v.id.clone()).collect();
            cx.error(
                key("variant"),
                LoadErrorKind::Unknown {
                    what: "variant",
                    name: v.clone(),
                    expected: known,
                },
            );
        }
    }
}

/// A codec-level backend has neither instructions nor variants: an entry naming one is an error.
fn codec_has_no_instruction(entry: &Entry, cx: &mut FileContext<'_>, key: &dyn Fn(&str) -> String) {
    for (k, given) in [
        ("instruction", entry.instruction.is_some()),
        ("variant", entry.variant.is_some()),
    ] {
        if given {
            cx.error(
                key(k),
                LoadErrorKind::Invalid(format!(
                    "a codec-level backend has no {k}: leave `{k}` out"
                )),
            );
        }
    }
}

/// An `unspecified` case is recorded and never fails: there is no difference to list.
fn check_not_unspecified(
    entry: &Entry,
    basis: Basis,
    cx: &mut FileContext<'_>,
    key: &dyn Fn(&str) -> String,
) {
    if basis == Basis::Unspecified {
        cx.error(
            key("case"),
            LoadErrorKind::Invalid(format!(
                "case `{}` is unspecified: it is recorded and never fails, so there is no \
                 difference to list",
                entry.case().unwrap_or_default()
            )),
        );
    }
}

/// An entry for a cross-vendor case: `instruction` names one of the profile's lowerings of the
/// case's operation.
fn check_cross_vendor_entry(
    entry: &Entry,
    case: &CrossVendorCase,
    profile: &Profile,
    cx: &mut FileContext<'_>,
    key: &dyn Fn(&str) -> String,
) {
    let lowerings: Vec<String> = profile
        .cross_vendor
        .lowerings
        .iter()
        .filter(|l| l.operation == case.operation)
        .map(|l| l.name.clone())
        .collect();
    if lowerings.is_empty() {
        cx.error(
            key("case"),
            LoadErrorKind::Invalid(format!(
                "cross-vendor case `{}` does not run on profile {}: it lowers no {}",
                case.id, profile.id, case.operation
            )),
        );
    }
    check_not_unspecified(entry, case.basis, cx, key);
    if let Some(l) = &entry.instruction {
        if !lowerings.contains(l) {
            cx.error(
                key("instruction"),
                LoadErrorKind::Unknown {
                    what: "lowering of this cross-vendor case",
                    name: l.clone(),
                    expected: lowerings,
                },
            );
        }
    }
    variant_exists(entry, profile, cx, key);
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;
    use std::sync::Arc;

    use super::*;
    use crate::model::Case;

    fn case(id: &str, basis: Basis, variants: Option<&[&str]>) -> Arc<Case> {
        Arc::new(Case {
            instructions: Arc::from(vec!["HABIN".to_string(), "HABINP".to_string()]),
            variants: variants.map(|v| v.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>()),
            ..crate::test_support::habin_case(id, basis)
        })
    }

    fn profile() -> Profile {
        let mut errors = Vec::new();
        crate::load::parse_profile(
            Path::new("p.yaml"),
            "id: p\nname: P\nshort: p\nmanuals: {}\nerrors: {signal: code, flag: SM0, register: SD0}\n\
             devices: {D: {first: 0, last: 100}}\ninstructions: {}\n\
             variants: [{id: a, description: a}, {id: b, description: b}]\n",
            &mut errors,
        )
        .expect("profile")
    }

    fn load(text: &str, strict: bool) -> Result<KnownDifferences, LoadErrors> {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join("known.yaml");
        std::fs::write(&file, text).expect("write");
        let corpus = Corpus {
            cases: vec![
                case("c1", Basis::Manual, None),
                case("only-a", Basis::Manual, Some(&["a"])),
                case("open", Basis::Unspecified, None),
            ],
            cross_vendor: Vec::new(),
            protocol_fields: Vec::new(),
        };
        load_known(&file, Some(&profile()), &corpus, strict)
    }

    #[test]
    fn entries_are_checked_against_the_corpus_and_profile() {
        assert_load_errors(
            "differences:\n\
             - {case: c1, instruction: DHABIN, reason: r}\n\
             - {case: only-a, variant: b, reason: r}\n\
             - {case: open, reason: r}\n\
             - {case: c1, reason: \"  \"}\n\
             - {case: c1, reason: again}\n\
             - {case: typo, reason: r}\n",
            &[
                ":2: differences[0].instruction: unknown instruction of this case `DHABIN`; expected one of: HABIN, HABINP",
                ":3: differences[1].variant: unknown variant of this case `b`; expected one of: a",
                ":4: differences[2].case: case `open` is unspecified",
                ":5: differences[3].reason: a known difference needs its reason",
                ":6: differences[4].case: the same trials are already listed at",
                ":7: differences[5].case: unknown case id `typo`",
            ],
        );
    }

    #[test]
    fn an_entry_by_cause_covers_many_cases_and_is_checked() {
        let known = load(
            "differences:\n  - cause: takes lowercase\n    kind: bug\n    cases: [c*, only-*]\n",
            true,
        )
        .expect("loads");
        let e = &known.entries[0];
        assert_eq!(e.reason, "takes lowercase (bug)");
        assert_eq!(e.case(), None);
        let subject = |case| crate::model::known::Subject {
            case,
            text: None,
            instruction: "HABIN",
            variant: "a",
        };
        assert!(e.matches(&subject("c1")));
        assert!(e.matches(&subject("only-a")));
        assert!(!e.matches(&subject("open")));
        assert_load_errors(
            "differences:\n\
             - {cause: c, kind: bug, cases: [nothing-*]}\n\
             - {cases: [c1], kind: bug}\n\
             - {cause: c, cases: [c1]}\n\
             - {case: c1, cases: [c1], reason: r}\n\
             - {reason: r}\n\
             - {cause: c, kind: by-design, cases: [c1], variant: z}\n",
            &[
                ":2: differences[0].cases[0]: `nothing-*` matches no case this backend runs",
                ":3: differences[1].cause: an entry by cause needs its `cause`",
                ":4: differences[2].kind: an entry by cause needs its `kind`: `bug` or `by-design`",
                ":5: differences[3].case: an entry lists one `case`, or one cause's `cases`/`input`, not both",
                ":6: differences[4].case: an entry needs the `case` it lists",
                ":7: differences[5].variant: unknown variant `z`",
            ],
        );
    }

    /// The file's errors, each expected one among them.
    fn assert_load_errors(file: &str, expected: &[&str]) {
        let errors = load(file, true).expect_err("invalid").to_string();
        for expected in expected {
            assert!(errors.contains(expected), "{expected}\nin:\n{errors}");
        }
    }

    #[test]
    fn another_corpus_sets_unknown_cases_aside() {
        let known = load(
            "differences:\n  - {case: c1, reason: r}\n  - {case: elsewhere, reason: r}\n",
            false,
        )
        .expect("loads");
        assert_eq!(known.entries.len(), 1);
        assert_eq!(known.ignored.len(), 1);
        assert_eq!(known.ignored[0].case(), Some("elsewhere"));
    }
}
