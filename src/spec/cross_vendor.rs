//! Cross-vendor vector files, and the `cross_vendor` section of a profile, as written on disk.

use std::collections::BTreeMap;
use std::fmt;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::vectors::{Basis, ScalarSpec};

/// The operations several vendors implement.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize, Serialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Operation {
    /// Hex ASCII text -> binary value (HABIN, FX5 HEXA, ATOH).
    HexToValue,
    /// Binary value -> hex ASCII text (BINHA, FX5 ASCI, HTOA).
    ValueToHex,
    /// A protocol's check character: the checked span -> its check characters (the Modbus
    /// ASCII LRC, the MC sum check, the MEWTOCOL BCC). Protocol-field cases only.
    Check,
    /// A protocol's check character verified: the span followed by its check characters ->
    /// accepted, or `bad-check`. Protocol-field cases only.
    Verify,
}

impl fmt::Display for Operation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Operation::HexToValue => "hex-to-value",
            Operation::ValueToHex => "value-to-hex",
            Operation::Check => "check",
            Operation::Verify => "verify",
        })
    }
}

/// What kind of error a vendor signalled, in words every vendor shares.
#[derive(
    Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize, Serialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum ErrorClass {
    /// A character that is not a hex digit.
    InvalidDigit,
    /// A digit count out of range.
    InvalidCount,
    /// An operand past the end of its device range.
    DeviceRange,
    /// An error whose kind the vendor does not tell (IDEC M8004).
    Error,
    /// Check characters that do not match the span they check (a protocol's LRC, sum check,
    /// BCC or FCS).
    BadCheck,
}

impl fmt::Display for ErrorClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ErrorClass::InvalidDigit => "invalid-digit",
            ErrorClass::InvalidCount => "invalid-count",
            ErrorClass::DeviceRange => "device-range",
            ErrorClass::Error => "error",
            ErrorClass::BadCheck => "bad-check",
        })
    }
}

/// How characters are stored in memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum TextLayout {
    /// Two characters per word, first character in the low byte (word-addressed memory only).
    Packed,
    /// Two characters per word, first character in the high byte (KEYENCE's ASC/RASC word:
    /// `A5` is 4135H).
    PackedHighFirst,
    /// One character per device: in the low byte of a word, or the whole byte of
    /// byte-addressed memory.
    Words,
}

/// The order of a multi-unit value's units in memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum ValueOrder {
    /// The least significant unit at the head (MELSEC D100/D101 for a BIN32).
    #[default]
    LowFirst,
    /// The most significant unit at the head: a byte array in reading order (Siemens).
    HighFirst,
}

/// A profile's `cross_vendor` section: how its instructions answer the cross-vendor operations.
#[derive(Debug, Clone, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CrossVendorSectionSpec {
    /// How the profile's error signals read as cross-vendor classes, e.g. `3401H: invalid-digit`
    /// for a code, `M8004: error` for a flag.
    #[serde(default)]
    pub errors: BTreeMap<String, ErrorClass>,
    /// Error signals of `errors` after which the instruction has still written its destination
    /// (Siemens ATH's 0007H: an invalid character converted as 0): a hex-to-value answer is then
    /// the error and the value (`{error: invalid-digit, value: 1034H}`), so the matrix shows it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub written_on_error: Vec<String>,
    #[serde(default)]
    pub lowerings: Vec<LoweringSpec>,
}

/// One way of answering a cross-vendor operation with one of the profile's instructions.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct LoweringSpec {
    /// The column name, unique within the profile, e.g. `habin-fixed`. Cross-vendor cases refer
    /// to it as `<profile short>/<name>` (`iqr/habin-fixed`).
    pub name: String,
    pub description: String,
    pub operation: Operation,
    pub instruction: String,
    /// The variant to run on; the profile's first when absent.
    pub variant: Option<String>,
    /// Mode flags, e.g. `{SM705: true}`.
    #[serde(default)]
    pub flags: BTreeMap<String, bool>,
    /// The fixed operands (`s: D100`, `d: D200`).
    pub operands: BTreeMap<String, String>,
    /// The operand holding the input: the text for hex-to-value, the value for value-to-hex.
    pub source: String,
    /// The operand receiving the result.
    pub destination: String,
    /// How the characters are stored: two per word low byte first, or one per word.
    pub text: TextLayout,
    /// The operand that receives the digit count (`n`, `S2`), for instructions that take one.
    pub count: Option<String>,
    /// Where the count goes when the instruction cannot take it as a constant (IDEC S2: only
    /// constants 1-4 can be programmed, so a count of 0 or 5 is read from this register).
    pub count_register: Option<String>,
    /// The digits the instruction handles when it takes no count (HABIN, BINHA: 4).
    pub width: Option<u32>,
    /// The order of the value's units at the source (value-to-hex) or destination
    /// (hex-to-value): `low-first` (the default) or `high-first`.
    #[serde(default)]
    pub value_order: ValueOrder,
}

/// A file of vendor-neutral cases for one operation.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance cross-vendor vector file")]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct CrossVendorFileSpec {
    pub operation: Operation,
    /// Where the cases' expectations come from, in words (they span several manuals).
    pub source: String,
    pub description: Option<String>,
    /// Texts several cases share, to be named with YAML anchors (`- &idec "..."`) and used as
    /// aliases (`why: *idec`); not read otherwise.
    #[serde(default)]
    pub reasons: Vec<String>,
    pub cases: Vec<CrossVendorCaseSpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CrossVendorCaseSpec {
    /// Unique in the whole corpus.
    pub id: String,
    pub basis: Basis,
    pub cite: Option<String>,
    /// hex-to-value: the characters (`\0` for NUL).
    pub text: Option<String>,
    /// value-to-hex: the value (`0ABCH`, `K100`).
    pub value: Option<ScalarSpec>,
    /// The digit count, for instructions that take one (FX5 `n`, IDEC `S2`).
    pub digits: u32,
    /// What every lowering answers unless listed in `except`.
    pub expect: Option<CrossVendorExpectSpec>,
    /// Lowerings that answer differently, by `<profile short>/<lowering name>`.
    #[serde(default)]
    pub except: BTreeMap<String, CrossVendorExceptSpec>,
    pub note: Option<String>,
}

/// One of `value`, `text` or `error` (`accepted` for a protocol's `verify`).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CrossVendorExpectSpec {
    pub value: Option<ScalarSpec>,
    pub text: Option<String>,
    pub error: Option<ErrorClass>,
    /// A protocol's `verify` only: the check characters match.
    pub accepted: Option<bool>,
}

/// A lowering's own answer, and why it differs.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CrossVendorExceptSpec {
    pub value: Option<ScalarSpec>,
    pub text: Option<String>,
    pub error: Option<ErrorClass>,
    /// No rule fixes this vendor's answer: it is recorded, never judged (instead of `value`,
    /// `text` or `error`).
    #[serde(default)]
    pub unspecified: bool,
    /// The manual rule that makes this vendor answer differently (or leaves it open).
    pub why: String,
}
