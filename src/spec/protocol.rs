//! Protocol profiles (`vendors/protocols/*.yaml`) and protocol-field vector files
//! (`vectors/protocols/*.yaml`), as written on disk.
//!
//! A protocol library's codec reads and writes the hex fields of a communication protocol (MC
//! protocol ASCII code, Modbus ASCII, ...), whose own manual states the rules it must follow. A
//! protocol profile holds those rules as data — the field kinds, the check character, what a
//! device answers to data it cannot convert — each with its manual, page and quote; a
//! protocol-field file holds the cases that judge a codec by them.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Deserialize;

use super::cross_vendor::{CrossVendorExpectSpec, Operation};
use super::vectors::{Basis, ScalarSpec};

/// One communication protocol's hex fields, check character and error answers.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance protocol profile")]
// `description` is for the file's readers and its schema; the run reads only the rules.
#[allow(dead_code)]
pub(crate) struct ProtocolSpec {
    /// The protocol's id, which a codec names in its hello (`mc-ascii`, `modbus-ascii`).
    pub protocol: String,
    /// Its name as its manuals give it.
    pub name: String,
    pub description: Option<String>,
    /// The manuals its rules cite, by the id a cite uses (`mbsl p.16`): the document's title
    /// and number.
    pub manuals: BTreeMap<String, String>,
    /// The hex fields and check characters a codec of this protocol reads and writes, by name.
    pub fields: BTreeMap<String, FieldSpec>,
    /// What a device answers to data it cannot convert, in words, with the rules that say so.
    pub unconvertible: String,
    /// The protocol's rules, each stated once with its evidence; cases name them by `id`.
    pub rules: Vec<RuleSpec>,
}

/// One kind of field: a run of hex digits holding a value, or a check character.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(crate) struct FieldSpec {
    /// Its digits on the wire.
    pub digits: u32,
    /// The value width in bits (8, 16 or 32); absent for a check character.
    pub width: Option<u32>,
    /// `high-first` (the most significant digit first, the default) or `low-byte-first` (the
    /// first character pair is the low byte: MEWTOCOL's data words).
    #[serde(default)]
    pub order: FieldOrder,
    /// A check character: how it is computed over the checked span.
    pub check: Option<CheckAlgorithm>,
    /// The characters that stand for "no check" in place of a check character (MEWTOCOL `**`).
    pub skip: Option<String>,
    /// The rules that define the field, by id.
    pub rules: Vec<String>,
    pub description: String,
}

/// The order of a field's digits.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum FieldOrder {
    #[default]
    HighFirst,
    LowByteFirst,
}

/// How a check character is computed over its span.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum CheckAlgorithm {
    /// The span is hex digit pairs: the two's complement of the 8-bit sum of the bytes they
    /// stand for (Modbus ASCII LRC).
    Lrc,
    /// The low byte of the sum of the span's characters (MC protocol and FX computer link sum
    /// check).
    Sum,
    /// The exclusive OR of the span's characters (MEWTOCOL BCC, Omron Host Link FCS).
    Xor,
}

/// One rule of a protocol, with its evidence.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RuleSpec {
    /// Short and unique in the protocol (`B3`, `M1`).
    pub id: String,
    /// The rule in the project's words.
    pub statement: String,
    /// `manual` where a page states it, `inferred` otherwise (then `cite` says what it rests
    /// on).
    pub basis: Basis,
    /// `<manual> p.<page>` (a key of `manuals`), or the reasoning of an inferred rule.
    pub cite: String,
    /// The manual's words, short and verbatim: docs/semantics.md#protocols carries every one.
    pub quote: Option<String>,
}

/// A file of cases judging a codec by one protocol's rules.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance protocol-field vector file")]
#[allow(dead_code)]
pub(crate) struct ProtocolFileSpec {
    /// The protocol profile's id.
    pub protocol: String,
    pub description: Option<String>,
    /// Texts several cases share, named with YAML anchors; not read otherwise.
    #[serde(default)]
    pub reasons: Vec<String>,
    pub cases: Vec<ProtocolCaseSpec>,
}

/// One question of a protocol field and the protocol's answer.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ProtocolCaseSpec {
    /// Unique in the whole corpus.
    pub id: String,
    /// The field of the protocol profile asked.
    pub field: String,
    /// `hex-to-value` and `value-to-hex` for a value field; `check` (the span -> its check
    /// characters) and `verify` (the span and its check characters -> accepted or `bad-check`)
    /// for a check character.
    pub operation: Operation,
    /// The rule of the profile the case tests, by id: a difference names it.
    pub rule: String,
    pub basis: Basis,
    /// For `inferred` and `unspecified` cases, what the expectation rests on (a `manual` case
    /// takes its rule's cite and quote).
    pub cite: Option<String>,
    /// hex-to-value, check, verify: the characters (`\0` for NUL).
    pub text: Option<String>,
    /// value-to-hex: the value (`0ABCH`, `K100`).
    pub value: Option<ScalarSpec>,
    /// The protocol's answer: `value`, `text`, `error` or `accepted: true`; absent for an
    /// `unspecified` case.
    pub expect: Option<CrossVendorExpectSpec>,
    pub note: Option<String>,
}
