//! Checks shared by the loaders of vector files, cross-vendor files and profiles.

use super::{FileContext, LoadErrorKind};
use crate::model::Basis;

/// Case ids: lowercase letters, digits and `-`, so that trial names stay filterable.
pub(crate) fn check_id(key: &str, id: &str, cx: &mut FileContext<'_>) {
    let ok = !id.is_empty()
        && id
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
        && !id.starts_with('-');
    if !ok {
        cx.error(
            format!("{key}.id"),
            LoadErrorKind::Invalid(format!(
                "case id `{id}` must be lowercase letters, digits and `-`, like `fixed-4-digits-example`"
            )),
        );
    }
}

/// Only an `unspecified` case may leave its expectation out.
pub(crate) fn check_expect_optional(key: &str, basis: Basis, cx: &mut FileContext<'_>) {
    if basis != Basis::Unspecified {
        cx.error(
            key,
            LoadErrorKind::Missing("expect: only `basis: unspecified` may leave it out"),
        );
    }
}

/// The citation text; required unless the basis is `unspecified`.
pub(crate) fn check_cite(
    key: &str,
    basis: Basis,
    cite: Option<&str>,
    cx: &mut FileContext<'_>,
) -> Option<String> {
    let cite = cite.map(str::trim).filter(|c| !c.is_empty());
    if cite.is_none() && basis != Basis::Unspecified {
        cx.error(
            key,
            LoadErrorKind::Missing(match basis {
                Basis::Manual => "cite: `basis: manual` must say where the manual states it",
                Basis::Observed => "cite: `basis: observed` must give the provenance",
                _ => "cite: `basis: inferred` must say what the reading rests on",
            }),
        );
    }
    cite.map(str::to_string)
}

/// Text as the bytes a PLC stores: one per character, so no character may be above FFH.
pub(crate) fn text_bytes(key: &str, text: &str, cx: &mut FileContext<'_>) -> Option<Vec<u8>> {
    let out: Option<Vec<u8>> = text.chars().map(|c| u8::try_from(c).ok()).collect();
    if out.is_none() {
        cx.error(
            key,
            LoadErrorKind::Invalid(format!(
                "`{}` has a character above FFH; ASCII text stores one byte per character",
                text.escape_default()
            )),
        );
    }
    out
}

pub(crate) fn unknown(what: &'static str, name: &str, expected: &[String]) -> LoadErrorKind {
    LoadErrorKind::Unknown {
        what,
        name: name.to_string(),
        expected: expected.to_vec(),
    }
}

/// Each case of a vector file read by `read`, with its key (`cases[i]`); a file of no case is
/// an error. What every kind of vector file (an instruction's, cross-vendor, protocol-field)
/// does with its list.
pub(crate) fn read_cases<S, C>(
    cases: &[S],
    cx: &mut FileContext<'_>,
    mut read: impl FnMut(&str, &S, &mut FileContext<'_>) -> Option<C>,
) -> Vec<(String, C)> {
    if cases.is_empty() {
        cx.error(
            "cases",
            LoadErrorKind::Missing("case: a vector file holds at least one"),
        );
    }
    (cases.iter().enumerate())
        .filter_map(|(i, case)| {
            let key = format!("cases[{i}]");
            read(&key, case, cx).map(|c| (key, c))
        })
        .collect()
}
