//! Loading protocol profiles (`vendors/protocols/`) and protocol-field vector files
//! (`vectors/protocols/`).

use std::collections::BTreeMap;
use std::sync::Arc;

use super::checks::{check_cite, check_expect_optional, check_id, text_bytes, unknown};
use super::cross_vendor::number;
use super::{FileContext, LineIndex, LoadErrorKind};
use crate::model::cross_vendor::{Answer, CrossVendorCase, Operation};
use crate::model::profile::Profiles;
use crate::model::protocol::{Field, FieldRule, Protocol, Rule};
use crate::model::{Basis, Citation};
use crate::spec::protocol::{FieldOrder, ProtocolCaseSpec, ProtocolFileSpec, ProtocolSpec};

/// Whether a file of `vendors/` is a protocol profile: it names a `protocol` and its `rules`.
pub(super) fn is_protocol_profile(index: &LineIndex) -> bool {
    index.line("protocol").is_some() && index.line("rules").is_some()
}

/// Whether a vector file holds protocol-field cases: it names a `protocol`, no `instructions`.
pub(super) fn is_protocol_file(index: &LineIndex) -> bool {
    index.line("protocol").is_some() && index.line("instructions").is_none()
}

/// `<manual> p.<page>` as a citation; `None` when the cite is not of that form.
fn manual_cite(cite: &str) -> Option<(String, String)> {
    let (manual, page) = cite.trim().split_once(" p.")?;
    let page = page.trim();
    (!manual.contains(' ') && !page.is_empty()).then(|| (manual.to_string(), page.to_string()))
}

/// Parses and checks one protocol profile; problems go to `errors`.
pub(super) fn parse_protocol(text: &str, cx: &mut FileContext<'_>) -> Option<Protocol> {
    let before = cx.errors.len();
    let spec = super::parse_document::<ProtocolSpec>(text, cx)?;
    let manuals: Vec<String> = spec.manuals.keys().cloned().collect();
    let mut rules = BTreeMap::new();
    for (i, r) in spec.rules.iter().enumerate() {
        let key = format!("rules[{i}]");
        if r.id.is_empty() || !r.id.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
            cx.error(
                format!("{key}.id"),
                LoadErrorKind::Invalid(format!(
                    "rule id `{}` must be letters, digits and `-`, like the manual's own (`B3`)",
                    r.id
                )),
            );
        }
        let citation = match (r.basis, manual_cite(&r.cite)) {
            (Basis::Manual, Some((manual, page))) => {
                if !spec.manuals.contains_key(&manual) {
                    cx.error(
                        format!("{key}.cite"),
                        unknown("manual of this protocol", &manual, &manuals),
                    );
                }
                if r.quote.as_deref().is_none_or(|q| q.trim().is_empty()) {
                    cx.error(
                        &key,
                        LoadErrorKind::Missing("quote: a `manual` rule quotes its page"),
                    );
                }
                Citation {
                    manual,
                    page,
                    text: r.quote.clone(),
                }
            }
            (Basis::Manual, None) => {
                cx.error(
                    format!("{key}.cite"),
                    LoadErrorKind::Invalid(format!(
                        "a `manual` rule cites `<manual> p.<page>`, not `{}`",
                        r.cite
                    )),
                );
                continue;
            }
            (Basis::Inferred, _) if !r.cite.trim().is_empty() => Citation {
                manual: r.cite.clone(),
                page: String::new(),
                text: None,
            },
            (basis, _) => {
                cx.error(
                    format!("{key}.basis"),
                    LoadErrorKind::Invalid(format!(
                        "a rule is `manual` or `inferred` with what it rests on, not `{basis}`"
                    )),
                );
                continue;
            }
        };
        let rule = Rule {
            key: format!("{}/{}", spec.protocol, r.id),
            statement: r.statement.clone(),
            basis: r.basis,
            citation,
        };
        if rules.insert(r.id.clone(), Arc::new(rule)).is_some() {
            cx.error(
                format!("{key}.id"),
                LoadErrorKind::Invalid(format!("rule `{}` is given twice", r.id)),
            );
        }
    }
    let ids: Vec<String> = rules.keys().cloned().collect();
    let mut fields = BTreeMap::new();
    for (name, f) in &spec.fields {
        let key = format!("fields.{name}");
        if !(1..=16).contains(&f.digits) {
            cx.error(
                format!("{key}.digits"),
                LoadErrorKind::Invalid("a field has 1 to 16 digits".into()),
            );
        }
        for r in f.rules.iter().filter(|r| !rules.contains_key(*r)) {
            cx.error(format!("{key}.rules"), unknown("rule", r, &ids));
        }
        let width = match (f.check, f.width) {
            (Some(_), None) => 8,
            (None, Some(w @ (8 | 16 | 32))) => w,
            (Some(_), Some(_)) => {
                cx.error(
                    format!("{key}.width"),
                    LoadErrorKind::Invalid("a check character has no value width".into()),
                );
                8
            }
            (None, _) => {
                cx.error(
                    format!("{key}.width"),
                    LoadErrorKind::Invalid("a value field's width is 8, 16 or 32 bits".into()),
                );
                16
            }
        };
        if f.skip.is_some() && f.check.is_none() {
            cx.error(
                format!("{key}.skip"),
                LoadErrorKind::Invalid("only a check character has a `skip`".into()),
            );
        }
        fields.insert(
            name.clone(),
            Field {
                name: name.clone(),
                digits: f.digits,
                width,
                low_byte_first: f.order == FieldOrder::LowByteFirst,
                check: f.check,
                skip: f.skip.as_ref().map(|s| s.as_bytes().to_vec()),
            },
        );
    }
    (cx.errors.len() == before).then(|| Protocol {
        id: spec.protocol.clone(),
        name: spec.name.clone(),
        manuals: spec.manuals.clone(),
        fields,
        unconvertible: spec.unconvertible.clone(),
        rules,
    })
}

/// The cases of one protocol-field file, checked against its protocol profile.
pub(super) fn read_file(
    text: &str,
    profiles: &Profiles,
    cx: &mut FileContext<'_>,
) -> Vec<(String, CrossVendorCase)> {
    let Some(spec) = super::parse_document::<ProtocolFileSpec>(text, cx) else {
        return Vec::new();
    };
    let Some(protocol) = profiles.protocols.get(&spec.protocol) else {
        cx.error(
            "protocol",
            unknown("protocol", &spec.protocol, &profiles.protocols.ids()),
        );
        return Vec::new();
    };
    super::checks::read_cases(&spec.cases, cx, |key, case, cx| {
        read_case(key, case, protocol, cx)
    })
}

fn read_case(
    key: &str,
    spec: &ProtocolCaseSpec,
    protocol: &Protocol,
    cx: &mut FileContext<'_>,
) -> Option<CrossVendorCase> {
    let before = cx.errors.len();
    check_id(key, &spec.id, cx);
    let names: Vec<String> = protocol.fields.keys().cloned().collect();
    let Some(field) = protocol.fields.get(&spec.field) else {
        cx.error(
            format!("{key}.field"),
            unknown("field of this protocol", &spec.field, &names),
        );
        return None;
    };
    let ids: Vec<String> = protocol.rules.keys().cloned().collect();
    let Some(rule) = protocol.rules.get(&spec.rule) else {
        cx.error(format!("{key}.rule"), unknown("rule", &spec.rule, &ids));
        return None;
    };
    let checks = matches!(spec.operation, Operation::Check | Operation::Verify);
    if checks != field.check.is_some() {
        cx.error(
            format!("{key}.operation"),
            LoadErrorKind::Invalid(format!(
                "`{}` is a {}: ask it {}",
                spec.field,
                if checks {
                    "value field"
                } else {
                    "check character"
                },
                if checks {
                    "hex-to-value or value-to-hex"
                } else {
                    "check or verify"
                }
            )),
        );
        return None;
    }
    // A manual case rests on a rule its page states; an inferred or unspecified one says why.
    let citation = match spec.basis {
        Basis::Manual if rule.basis == Basis::Manual => rule.citation.clone(),
        Basis::Manual => {
            cx.error(
                format!("{key}.basis"),
                LoadErrorKind::Invalid(format!(
                    "rule `{}` is inferred, so a case resting on it is not `manual`",
                    spec.rule
                )),
            );
            return None;
        }
        basis => Citation {
            manual: check_cite(key, basis, spec.cite.as_deref(), cx).unwrap_or_default(),
            page: String::new(),
            text: None,
        },
    };
    let (text, value) = match (spec.operation, &spec.text, &spec.value) {
        (Operation::ValueToHex, None, Some(v)) => (Vec::new(), number(key, v, field.width, cx)?),
        (Operation::ValueToHex, _, _) => {
            cx.error(
                key,
                LoadErrorKind::Invalid("value-to-hex gives `value` and no `text`".into()),
            );
            return None;
        }
        (_, Some(t), None) => (text_bytes(&format!("{key}.text"), t, cx)?, 0),
        (operation, _, _) => {
            cx.error(
                key,
                LoadErrorKind::Invalid(format!("{operation} gives `text` and no `value`")),
            );
            return None;
        }
    };
    let expect = match &spec.expect {
        None => {
            check_expect_optional(key, spec.basis, cx);
            None
        }
        Some(e) => {
            let ekey = format!("{key}.expect");
            let given = [
                e.value.is_some(),
                e.text.is_some(),
                e.error.is_some(),
                e.accepted.is_some(),
            ];
            if given.iter().filter(|g| **g).count() != 1 {
                cx.error(
                    &ekey,
                    LoadErrorKind::Invalid(
                        "give exactly one of `value`, `text`, `error` or `accepted`".into(),
                    ),
                );
                return None;
            }
            let answer = match (spec.operation, e) {
                (_, e) if e.error.is_some() => e.error.clone().map(Answer::Error),
                (Operation::HexToValue, e) if e.value.is_some() => {
                    let v = e.value.as_ref()?;
                    Some(Answer::Value(number(&ekey, v, field.width, cx)?))
                }
                (Operation::ValueToHex | Operation::Check, e) if e.text.is_some() => {
                    Some(Answer::Text(text_bytes(&ekey, e.text.as_deref()?, cx)?))
                }
                (Operation::Verify, e) if e.accepted == Some(true) => Some(Answer::Accepted),
                (operation, _) => {
                    cx.error(
                        &ekey,
                        LoadErrorKind::Invalid(format!(
                            "{operation} expects {}",
                            match operation {
                                Operation::HexToValue => "a `value` or an `error`",
                                Operation::ValueToHex | Operation::Check =>
                                    "a `text` or an `error`",
                                Operation::Verify => "`accepted: true` or an `error`",
                            }
                        )),
                    );
                    None
                }
            };
            Some(answer?)
        }
    };
    (cx.errors.len() == before).then(|| CrossVendorCase {
        id: spec.id.clone(),
        operation: spec.operation,
        basis: spec.basis,
        citation,
        location: cx.location(key),
        text,
        value,
        digits: field.digits,
        expect,
        except: BTreeMap::new(),
        note: spec.note.clone(),
        protocol: Some(FieldRule {
            protocol: protocol.id.clone(),
            field: field.name.clone(),
            rule: rule.clone(),
        }),
    })
}
