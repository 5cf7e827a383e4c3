//! Lowering cross-vendor vector files and checking profiles' `neutral` sections.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::profiles::unknown;
use super::{FileContext, LoadErrorKind};
use crate::model::Citation;
use crate::neutral::lower::{lowering_key, parse_operand};
use crate::neutral::spec::{NeutralCaseSpec, NeutralFileSpec};
use crate::neutral::{NeutralCase, NeutralOutcome, Operation};
use crate::profile::{Profile, Profiles};
use crate::spec::ScalarSpec;
use crate::value::{parse_number, to_bits};

/// The most digits a neutral case may ask for: results are lifted into 64 bits.
const MAX_DIGITS: u32 = 16;

/// Whether a vector file is a cross-vendor one (it names an `operation`, not `instructions`).
pub fn is_neutral(index: &super::LineIndex) -> bool {
    index.line("operation").is_some() && index.line("instructions").is_none()
}

pub(crate) fn lower_file(
    spec: &NeutralFileSpec,
    profiles: &Profiles,
    cx: &mut FileContext<'_>,
) -> Vec<(String, NeutralCase)> {
    let keys: BTreeSet<String> = profiles
        .iter()
        .flat_map(|p| {
            p.neutral
                .iter()
                .flat_map(|n| n.lowerings.iter())
                .filter(|l| l.operation == spec.operation)
                .map(|l| lowering_key(p, l))
        })
        .collect();
    let known: Vec<String> = keys.iter().cloned().collect();
    spec.cases
        .iter()
        .enumerate()
        .filter_map(|(i, case)| {
            let key = format!("cases[{i}]");
            lower_case(&key, case, spec, &known, cx).map(|c| (key, c))
        })
        .collect()
}

fn lower_case(
    key: &str,
    spec: &NeutralCaseSpec,
    file: &NeutralFileSpec,
    lowerings: &[String],
    cx: &mut FileContext<'_>,
) -> Option<NeutralCase> {
    let before = cx.errors.len();
    super::vectors::check_id(key, &spec.id, cx);
    let cite = super::vectors::check_cite(key, spec.basis, spec.cite.as_deref(), cx);
    if spec.digits > MAX_DIGITS {
        cx.error(
            format!("{key}.digits"),
            LoadErrorKind::Invalid(format!("at most {MAX_DIGITS} digits")),
        );
    }
    let (text, value) = match file.operation {
        Operation::HexToValue => {
            if spec.value.is_some() {
                cx.error(
                    format!("{key}.value"),
                    LoadErrorKind::Invalid("hex-to-value cases give `text`, not `value`".into()),
                );
            }
            let text = match &spec.text {
                Some(t) => {
                    super::vectors::text_bytes(&format!("{key}.text"), t, cx).unwrap_or_default()
                }
                None => {
                    cx.error(
                        key,
                        LoadErrorKind::Missing("text: the characters to convert"),
                    );
                    Vec::new()
                }
            };
            (text, 0)
        }
        Operation::ValueToHex => {
            if spec.text.is_some() {
                cx.error(
                    format!("{key}.text"),
                    LoadErrorKind::Invalid("value-to-hex cases give `value`, not `text`".into()),
                );
            }
            let value = match &spec.value {
                Some(v) => number(&format!("{key}.value"), v, 32, cx).unwrap_or(0),
                None => {
                    cx.error(key, LoadErrorKind::Missing("value: the number to convert"));
                    0
                }
            };
            (Vec::new(), value)
        }
    };
    let expect = match &spec.expect {
        Some(e) => outcome(
            &format!("{key}.expect"),
            e.value.as_ref(),
            e.text.as_deref(),
            e.error.as_ref(),
            file.operation,
            cx,
        ),
        None => {
            super::vectors::check_expect_optional(key, spec.basis, cx);
            None
        }
    };
    let mut except = BTreeMap::new();
    for (name, e) in &spec.except {
        let ekey = format!("{key}.except.{name}");
        if !lowerings.contains(name) {
            cx.error(
                &ekey,
                unknown("lowering for this operation", name, lowerings),
            );
            continue;
        }
        if e.why.trim().is_empty() {
            cx.error(
                &ekey,
                LoadErrorKind::Missing("why: the rule that makes this vendor differ"),
            );
        }
        if let Some(o) = outcome(
            &ekey,
            e.value.as_ref(),
            e.text.as_deref(),
            e.error.as_ref(),
            file.operation,
            cx,
        ) {
            except.insert(name.clone(), (o, e.why.clone()));
        }
    }
    (cx.errors.len() == before).then(|| NeutralCase {
        id: spec.id.clone(),
        operation: file.operation,
        basis: spec.basis,
        citation: Citation {
            manual: "cross-vendor".into(),
            page: file.source.clone(),
            text: cite,
        },
        location: cx.location(key),
        text,
        value,
        digits: spec.digits,
        expect,
        except,
        note: spec.note.clone(),
    })
}

fn outcome(
    key: &str,
    value: Option<&ScalarSpec>,
    text: Option<&str>,
    error: Option<&crate::neutral::ErrorClass>,
    op: Operation,
    cx: &mut FileContext<'_>,
) -> Option<NeutralOutcome> {
    match (value, text, error) {
        (Some(v), None, None) if op == Operation::HexToValue => {
            number(&format!("{key}.value"), v, 64, cx).map(NeutralOutcome::Value)
        }
        (None, Some(t), None) if op == Operation::ValueToHex => {
            super::vectors::text_bytes(&format!("{key}.text"), t, cx).map(NeutralOutcome::Text)
        }
        (None, None, Some(e)) => Some(NeutralOutcome::Error(e.clone())),
        _ => {
            cx.error(
                key,
                LoadErrorKind::Invalid(format!(
                    "give exactly one of `{}` or `error`",
                    if op == Operation::HexToValue {
                        "value"
                    } else {
                        "text"
                    }
                )),
            );
            None
        }
    }
}

fn number(key: &str, v: &ScalarSpec, bits: u32, cx: &mut FileContext<'_>) -> Option<u64> {
    let parsed = match v {
        ScalarSpec::Number(n) => Ok(*n),
        ScalarSpec::Text(t) => parse_number(t),
    };
    let checked = parsed.and_then(|n| {
        if bits >= 64 {
            u64::try_from(n).map_err(|_| crate::value::ValueError::TooWide {
                text: v.to_string(),
                bits: 63,
            })
        } else {
            to_bits(&v.to_string(), n, bits)
        }
    });
    checked
        .map_err(|e| cx.error(key, LoadErrorKind::Value(e)))
        .ok()
}

/// Checks a profile's `neutral` section against the rest of the profile.
pub(crate) fn check_section(p: &Profile, cx: &mut FileContext<'_>) {
    let Some(section) = &p.neutral else { return };
    for key in section.errors.keys() {
        let ok = match p.errors.signal {
            crate::profile::SignalKind::Code => crate::value::parse_word(key).is_ok(),
            crate::profile::SignalKind::Flag => *key == p.errors.flag,
        };
        if !ok {
            cx.error(
                format!("neutral.errors.{key}"),
                LoadErrorKind::Invalid(format!("`{key}` is not an error signal of this profile")),
            );
        }
    }
    let mut names = BTreeSet::new();
    for (i, l) in section.lowerings.iter().enumerate() {
        let key = format!("neutral.lowerings[{i}]");
        if !names.insert(&l.name) {
            cx.error(
                format!("{key}.name"),
                LoadErrorKind::Invalid(format!("lowering `{}` is defined twice", l.name)),
            );
        }
        let Some(def) = p.instructions.get(&l.instruction) else {
            let known: Vec<String> = p.instructions.keys().cloned().collect();
            cx.error(
                format!("{key}.instruction"),
                unknown("instruction", &l.instruction, &known),
            );
            continue;
        };
        if let Some(v) = &l.variant {
            if p.variant(v).is_none() {
                let known: Vec<String> = p.variants.iter().map(|v| v.id.clone()).collect();
                cx.error(format!("{key}.variant"), unknown("variant", v, &known));
            }
        }
        for flag in l.flags.keys() {
            if !def.flags.contains(flag) {
                cx.error(
                    format!("{key}.flags.{flag}"),
                    unknown("flag", flag, &def.flags),
                );
            }
        }
        let operands: Vec<String> = def.operands.keys().cloned().collect();
        for (name, text) in &l.operands {
            if !def.operands.contains_key(name) {
                cx.error(
                    format!("{key}.operands.{name}"),
                    unknown("operand", name, &operands),
                );
            } else if let Err(e) = parse_operand(text) {
                cx.error(format!("{key}.operands.{name}"), LoadErrorKind::Invalid(e));
            }
        }
        for (field, name) in [
            ("source", Some(&l.source)),
            ("destination", Some(&l.destination)),
            ("count", l.count.as_ref()),
        ] {
            let Some(name) = name else { continue };
            let given = l.operands.contains_key(name)
                || (field == "count" && def.operands.contains_key(name));
            if !given {
                cx.error(
                    format!("{key}.{field}"),
                    LoadErrorKind::Invalid(format!(
                        "`{name}` is not among the lowering's operands"
                    )),
                );
            }
        }
        let covered = l.operands.len()
            + usize::from(
                l.count
                    .as_ref()
                    .is_some_and(|c| !l.operands.contains_key(c)),
            );
        if covered != def.operands.len() {
            cx.error(
                format!("{key}.operands"),
                LoadErrorKind::Invalid(format!(
                    "{} needs operands {}",
                    l.instruction,
                    operands.join(", ")
                )),
            );
        }
        if l.count.is_none() && l.width.is_none() {
            cx.error(
                key,
                LoadErrorKind::Missing(
                    "width: an instruction that takes no count has a fixed digit width",
                ),
            );
        }
    }
}

/// Reads a neutral file into cases.
pub(crate) fn add_file(
    file: &Path,
    text: &str,
    profiles: &Profiles,
    errors: &mut Vec<super::LoadError>,
) -> Vec<(String, NeutralCase)> {
    let spec: NeutralFileSpec = match super::parse_yaml(file, text) {
        Ok(s) => s,
        Err(e) => {
            errors.push(e);
            return Vec::new();
        }
    };
    let mut cx = FileContext::new(file, text, errors);
    lower_file(&spec, profiles, &mut cx)
}
