//! Loading cross-vendor vector files and the `cross_vendor` sections of profiles.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use super::checks::{check_cite, check_expect_optional, check_id, text_bytes, unknown};
use super::{FileContext, LoadErrorKind};
use crate::device::{code_matches, Device};
use crate::model::cross_vendor::{
    Answer, CrossVendorCase, CrossVendorSection, ErrorClass, Lowering, Operation,
};
use crate::model::profile::{DeviceTable, Profiles, SignalKind};
use crate::model::{Citation, ErrorSignal, Operand};
use crate::spec::cross_vendor::{CrossVendorCaseSpec, CrossVendorFileSpec};
use crate::spec::profile::ProfileSpec;
use crate::spec::ScalarSpec;
use crate::value::{parse_number, parse_word, to_bits};

/// The most digits a cross-vendor case may ask for: results are lifted into 64 bits.
const MAX_DIGITS: u32 = 16;

/// Whether a vector file is a cross-vendor one (it names an `operation`, not `instructions`).
pub(super) fn is_cross_vendor(index: &super::LineIndex) -> bool {
    index.line("operation").is_some() && index.line("instructions").is_none()
}

pub(crate) fn read_cases(
    spec: &CrossVendorFileSpec,
    profiles: &Profiles,
    cx: &mut FileContext<'_>,
) -> Vec<(String, CrossVendorCase)> {
    let keys: BTreeSet<String> = profiles
        .iter()
        .flat_map(|p| p.cross_vendor.lowerings.iter())
        .filter(|l| l.operation == spec.operation)
        .map(|l| l.key.clone())
        .collect();
    let known: Vec<String> = keys.iter().cloned().collect();
    super::checks::read_cases(&spec.cases, cx, |key, case, cx| {
        read_case(key, case, spec, &known, cx)
    })
}

fn read_case(
    key: &str,
    spec: &CrossVendorCaseSpec,
    file: &CrossVendorFileSpec,
    lowerings: &[String],
    cx: &mut FileContext<'_>,
) -> Option<CrossVendorCase> {
    let before = cx.errors.len();
    check_id(key, &spec.id, cx);
    let cite = check_cite(key, spec.basis, spec.cite.as_deref(), cx);
    if spec.digits > MAX_DIGITS {
        cx.error(
            format!("{key}.digits"),
            LoadErrorKind::Invalid(format!("at most {MAX_DIGITS} digits")),
        );
    }
    let (text, value) = match file.operation {
        Operation::Check | Operation::Verify => {
            cx.error(
                "operation",
                LoadErrorKind::Invalid(format!(
                    "a cross-vendor file asks hex-to-value or value-to-hex; {} is a protocol's \
                     (vectors/protocols/)",
                    file.operation
                )),
            );
            return None;
        }
        Operation::HexToValue => {
            if spec.value.is_some() {
                cx.error(
                    format!("{key}.value"),
                    LoadErrorKind::Invalid("hex-to-value cases give `text`, not `value`".into()),
                );
            }
            let text = match &spec.text {
                Some(t) => text_bytes(&format!("{key}.text"), t, cx).unwrap_or_default(),
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
        Some(e) if e.accepted.is_some() => {
            cx.error(
                format!("{key}.expect.accepted"),
                LoadErrorKind::Invalid(
                    "`accepted` answers a protocol's verify, not a cross-vendor case".into(),
                ),
            );
            None
        }
        Some(e) => outcome(
            &format!("{key}.expect"),
            e.value.as_ref(),
            e.text.as_deref(),
            e.error.as_ref(),
            file.operation,
            cx,
        ),
        None => {
            check_expect_optional(key, spec.basis, cx);
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
        if e.unspecified {
            if e.value.is_some() || e.text.is_some() || e.error.is_some() {
                cx.error(
                    &ekey,
                    LoadErrorKind::Invalid(
                        "`unspecified` leaves the answer open: give no `value`, `text` or `error`"
                            .into(),
                    ),
                );
            } else {
                except.insert(name.clone(), (None, e.why.clone()));
            }
        } else if let Some(o) = outcome(
            &ekey,
            e.value.as_ref(),
            e.text.as_deref(),
            e.error.as_ref(),
            file.operation,
            cx,
        ) {
            except.insert(name.clone(), (Some(o), e.why.clone()));
        }
    }
    (cx.errors.len() == before).then(|| CrossVendorCase {
        id: spec.id.clone(),
        operation: file.operation,
        basis: spec.basis,
        citation: Citation {
            // The cases of a cross-vendor file rest on several manuals: the file's `source`
            // says which, in words.
            manual: file.source.clone(),
            page: String::new(),
            text: cite,
        },
        location: cx.location(key),
        text,
        value,
        digits: spec.digits,
        expect,
        except,
        note: spec.note.clone(),
        protocol: None,
    })
}

fn outcome(
    key: &str,
    value: Option<&ScalarSpec>,
    text: Option<&str>,
    error: Option<&ErrorClass>,
    op: Operation,
    cx: &mut FileContext<'_>,
) -> Option<Answer> {
    match (value, text, error) {
        (Some(v), None, None) if op == Operation::HexToValue => {
            number(&format!("{key}.value"), v, 64, cx).map(Answer::Value)
        }
        (None, Some(t), None) if op == Operation::ValueToHex => {
            text_bytes(&format!("{key}.text"), t, cx).map(Answer::Text)
        }
        (None, None, Some(e)) => Some(Answer::Error(e.clone())),
        (Some(v), None, Some(e)) if op == Operation::HexToValue => {
            number(&format!("{key}.value"), v, 64, cx).map(|v| Answer::ErrorAndValue(e.clone(), v))
        }
        _ => {
            cx.error(
                key,
                LoadErrorKind::Invalid(
                    if op == Operation::HexToValue {
                        "give `value`, `error`, or both (an error after which the destination \
                         still holds a value)"
                    } else {
                        "give exactly one of `text` or `error`"
                    }
                    .to_string(),
                ),
            );
            None
        }
    }
}

/// A value of a vector as a number of `bits` bits (64: unsigned, any width below it checked).
pub(super) fn number(
    key: &str,
    v: &ScalarSpec,
    bits: u32,
    cx: &mut FileContext<'_>,
) -> Option<u64> {
    if let (ScalarSpec::Text(t), true) = (v, bits >= 64) {
        return crate::value::parse_unsigned(t)
            .map_err(|e| cx.error(key, LoadErrorKind::Value(e)))
            .ok();
    }
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

/// Parses a lowering's operand: a device (numbered as the profile numbers its code: `W1A`
/// is W 26) or a constant.
pub(crate) fn parse_operand(
    text: &str,
    devices: &DeviceTable,
) -> Result<Operand, crate::device::DeviceSyntaxError> {
    if let Ok(k) = parse_number(text) {
        return Ok(Operand::Constant(k));
    }
    devices.parse(text).map(Operand::Device)
}

/// Checks a profile's `cross_vendor` section against the rest of the profile and parses it.
pub(crate) fn read_section(
    p: &ProfileSpec,
    devices: &DeviceTable,
    cx: &mut FileContext<'_>,
) -> CrossVendorSection {
    let mut out = CrossVendorSection::default();
    let Some(section) = &p.cross_vendor else {
        return out;
    };
    let signal_of = |key: &String| match p.errors.signal {
        SignalKind::Code => parse_word(key).ok().map(ErrorSignal::Code),
        SignalKind::Flag => (Some(key) == p.errors.flag.as_ref())
            .then(|| devices.parse(key).ok().map(ErrorSignal::Flag))
            .flatten(),
    };
    for (key, class) in &section.errors {
        match signal_of(key) {
            Some(s) => out.errors.push((s, class.clone())),
            None => cx.error(
                format!("cross_vendor.errors.{key}"),
                LoadErrorKind::Invalid(format!("`{key}` is not an error signal of this profile")),
            ),
        }
    }
    for (i, key) in section.written_on_error.iter().enumerate() {
        match signal_of(key) {
            Some(s) if out.errors.iter().any(|(e, _)| *e == s) => out.written_on_error.push(s),
            _ => cx.error(
                format!("cross_vendor.written_on_error[{i}]"),
                LoadErrorKind::Invalid(format!("`{key}` is not one of this section's `errors`")),
            ),
        }
    }
    let mut names = BTreeSet::new();
    for (i, l) in section.lowerings.iter().enumerate() {
        let key = format!("cross_vendor.lowerings[{i}]");
        let before = cx.errors.len();
        if !names.insert(&l.name) {
            cx.error(
                format!("{key}.name"),
                LoadErrorKind::Invalid(format!("lowering `{}` is defined twice", l.name)),
            );
        }
        if matches!(l.operation, Operation::Check | Operation::Verify) {
            cx.error(
                format!("{key}.operation"),
                LoadErrorKind::Invalid(format!(
                    "a lowering answers hex-to-value or value-to-hex, not {}",
                    l.operation
                )),
            );
            continue;
        }
        let Some(def) = p.instructions.get(&l.instruction) else {
            let known: Vec<String> = p.instructions.keys().cloned().collect();
            cx.error(
                format!("{key}.instruction"),
                unknown("instruction", &l.instruction, &known),
            );
            continue;
        };
        let variant = match &l.variant {
            Some(v) => {
                if !p.variants.iter().any(|pv| pv.id == *v) {
                    let known: Vec<String> = p.variants.iter().map(|v| v.id.clone()).collect();
                    cx.error(format!("{key}.variant"), unknown("variant", v, &known));
                }
                v.clone()
            }
            None => p.variants.first().map(|v| v.id.clone()).unwrap_or_default(),
        };
        let runs_on = p.variants.iter().find(|v| v.id == variant);
        for flag in l.flags.keys() {
            if !def.flags.contains(flag) {
                cx.error(
                    format!("{key}.flags.{flag}"),
                    unknown("flag", flag, &def.flags),
                );
            }
        }
        let names_of_operands: Vec<String> = def.operands.keys().cloned().collect();
        let mut operands = BTreeMap::new();
        for (name, text) in &l.operands {
            if !def.operands.contains_key(name) {
                cx.error(
                    format!("{key}.operands.{name}"),
                    unknown("operand", name, &names_of_operands),
                );
                continue;
            }
            match parse_operand(text, devices) {
                Ok(o) => {
                    if let Operand::Device(d) = &o {
                        let allowed = def.operands.get(name).map(|o| &o.devices);
                        if let Some(problem) = lowering_device(p, runs_on, allowed, d) {
                            cx.error(format!("{key}.operands.{name}"), problem);
                        }
                    }
                    operands.insert(name.clone(), o);
                }
                Err(e) => cx.error(format!("{key}.operands.{name}"), LoadErrorKind::Device(e)),
            }
        }
        if let Some(count) = &l.count {
            if !l.operands.contains_key(count) && !def.operands.contains_key(count) {
                cx.error(
                    format!("{key}.count"),
                    LoadErrorKind::Invalid(format!(
                        "`{count}` is not among the lowering's operands"
                    )),
                );
            }
        }
        let mut device = |field: &str, name: &str| match operands.get(name) {
            Some(Operand::Device(d)) => Some(d.clone()),
            Some(Operand::Constant(_)) => {
                cx.error(
                    format!("{key}.{field}"),
                    LoadErrorKind::Invalid(format!("operand `{name}` must be a device")),
                );
                None
            }
            None => {
                cx.error(
                    format!("{key}.{field}"),
                    LoadErrorKind::Invalid(format!(
                        "`{name}` is not among the lowering's operands"
                    )),
                );
                None
            }
        };
        let source = device("source", &l.source);
        let destination = device("destination", &l.destination);
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
                    names_of_operands.join(", ")
                )),
            );
        }
        if l.count.is_none() && l.width.is_none() {
            cx.error(
                &key,
                LoadErrorKind::Missing(
                    "width: an instruction that takes no count has a fixed digit width",
                ),
            );
        }
        let count_constants = l
            .count
            .as_ref()
            .and_then(|c| def.operands.get(c))
            .and_then(|d| d.constants);
        let count_register = match &l.count_register {
            Some(text) => match devices.parse(text) {
                Ok(d) => Some(d),
                Err(e) => {
                    cx.error(format!("{key}.count_register"), LoadErrorKind::Device(e));
                    None
                }
            },
            None => None,
        };
        if count_constants.is_some() && count_register.is_none() {
            cx.error(
                &key,
                LoadErrorKind::Missing(
                    "count_register: the count operand takes only some constants, so a count \
                     outside them needs a register",
                ),
            );
        }
        if !l.text.fits(p.memory_unit) {
            cx.error(
                format!("{key}.text"),
                LoadErrorKind::Invalid(
                    "`packed` puts two characters in a word; a byte-addressed profile holds one                      character per byte: use `words`"
                        .into(),
                ),
            );
        }
        let (Some(source), Some(destination)) = (source, destination) else {
            continue;
        };
        if cx.errors.len() != before {
            continue;
        }
        out.lowerings.push(Arc::new(Lowering {
            key: format!("{}/{}", p.short, l.name),
            name: l.name.clone(),
            description: l.description.clone(),
            operation: l.operation,
            instruction: l.instruction.clone(),
            variant,
            flags: l.flags.clone(),
            operands,
            source,
            destination,
            text: l.text,
            count: l.count.clone(),
            count_constants,
            count_register,
            width: l.width,
            unit: p.memory_unit,
            order: l.value_order,
        }));
    }
    out
}

/// Why a device a lowering names cannot be used on the variant it runs on: a device the profile
/// does not have or the operand does not take, or a word past the variant's range. Found when
/// the profile loads rather than as a failure of every trial through the lowering.
fn lowering_device(
    p: &ProfileSpec,
    variant: Option<&crate::model::profile::Variant>,
    allowed: Option<&Vec<String>>,
    d: &Device,
) -> Option<LoadErrorKind> {
    let devices = crate::model::profile::DeviceTable::new(p.devices.clone());
    if !devices.contains_key(d.code()) {
        let known: Vec<String> = p.devices.keys().cloned().collect();
        return Some(unknown("device", d.code(), &known));
    }
    if let Some(allowed) = allowed.filter(|a| !a.iter().any(|c| code_matches(c, d.code()))) {
        return Some(unknown("device for this operand", d.code(), allowed));
    }
    let variant = variant?;
    (!crate::model::profile::words_exist(&devices, variant, d, 1)).then(|| {
        LoadErrorKind::Invalid(format!(
            "{d} does not exist on variant `{}`, which the lowering runs on",
            variant.id
        ))
    })
}

/// Reads a cross-vendor file into cases.
pub(crate) fn read_file(
    text: &str,
    profiles: &Profiles,
    cx: &mut FileContext<'_>,
) -> Vec<(String, CrossVendorCase)> {
    match super::parse_document::<CrossVendorFileSpec>(text, cx) {
        Some(spec) => read_cases(&spec, profiles, cx),
        None => Vec::new(),
    }
}
