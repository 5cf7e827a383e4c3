//! Neutral vector files as written on disk.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Deserialize;

use super::{ErrorClass, Operation};
use crate::spec::{Basis, ScalarSpec};

/// A file of vendor-neutral cases for one operation.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance cross-vendor vector file")]
pub struct NeutralFileSpec {
    pub operation: Operation,
    /// Where the cases' expectations come from, in words (they span several manuals).
    pub source: String,
    #[serde(default)]
    pub description: Option<String>,
    /// Texts several cases share, to be named with YAML anchors (`- &idec "..."`) and used as
    /// aliases (`why: *idec`); not read otherwise.
    #[serde(default)]
    pub reasons: Vec<String>,
    pub cases: Vec<NeutralCaseSpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NeutralCaseSpec {
    /// Unique in the whole corpus.
    pub id: String,
    pub basis: Basis,
    #[serde(default)]
    pub cite: Option<String>,
    /// hex-to-value: the characters (`\0` for NUL).
    #[serde(default)]
    pub text: Option<String>,
    /// value-to-hex: the value (`0ABCH`, `K100`).
    #[serde(default)]
    pub value: Option<ScalarSpec>,
    /// The digit count, for instructions that take one (FX5 `n`, IDEC `S2`).
    pub digits: u32,
    /// What every lowering answers unless listed in `except`.
    #[serde(default)]
    pub expect: Option<NeutralExpectSpec>,
    /// Lowerings that answer differently, by `<profile short>/<lowering name>`.
    #[serde(default)]
    pub except: BTreeMap<String, NeutralExceptSpec>,
    #[serde(default)]
    pub note: Option<String>,
}

/// One of `value`, `text` or `error`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NeutralExpectSpec {
    #[serde(default)]
    pub value: Option<ScalarSpec>,
    #[serde(default)]
    pub text: Option<String>,
    #[serde(default)]
    pub error: Option<ErrorClass>,
}

/// A lowering's own answer, and why it differs.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NeutralExceptSpec {
    #[serde(default)]
    pub value: Option<ScalarSpec>,
    #[serde(default)]
    pub text: Option<String>,
    #[serde(default)]
    pub error: Option<ErrorClass>,
    /// The manual rule that makes this vendor answer differently.
    pub why: String,
}

/// The JSON Schema (draft-07) of a cross-vendor vector file.
pub fn neutral_file_schema() -> serde_json::Value {
    let generator = schemars::generate::SchemaSettings::draft07().into_generator();
    serde_json::to_value(generator.into_root_schema_for::<NeutralFileSpec>()).unwrap_or_default()
}
