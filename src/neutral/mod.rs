//! Cross-vendor operations: one vendor-neutral case, run on every vendor's version of it.
//!
//! Several vendors implement "hex ASCII text -> 16-bit value" and "value -> hex ASCII text", each
//! with its own operands, character layout, digit-count convention and error signalling. A
//! neutral case gives only the text (or value) and a digit count. Each profile says, as data
//! (its `neutral` section), how to lower that onto one of its instructions — which operands,
//! flags and layout — and how its error signals read as neutral error classes. The outcome is
//! lifted back to a neutral value, text or error class, so that the vendors' answers to the same
//! question can be compared side by side.

pub mod lower;
pub mod spec;

use std::collections::BTreeMap;
use std::fmt;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::model::{Basis, Citation, Location};

/// The operations several vendors implement.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Deserialize, Serialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Operation {
    /// Hex ASCII text -> binary value (HABIN, FX5 HEXA, ATOH).
    HexToValue,
    /// Binary value -> hex ASCII text (BINHA, FX5 ASCI, HTOA).
    ValueToHex,
}

impl fmt::Display for Operation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Operation::HexToValue => "hex-to-value",
            Operation::ValueToHex => "value-to-hex",
        })
    }
}

/// What kind of error a vendor signalled, in words every vendor shares.
#[derive(
    Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize, Serialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorClass {
    /// A character that is not a hex digit.
    InvalidDigit,
    /// A digit count out of range.
    InvalidCount,
    /// An operand past the end of its device range.
    DeviceRange,
    /// An error whose kind the vendor does not tell (IDEC M8004).
    Error,
}

impl fmt::Display for ErrorClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ErrorClass::InvalidDigit => "invalid-digit",
            ErrorClass::InvalidCount => "invalid-count",
            ErrorClass::DeviceRange => "device-range",
            ErrorClass::Error => "error",
        })
    }
}

/// A neutral outcome.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NeutralOutcome {
    Value(u64),
    /// Characters as bytes, up to the first 00H.
    Text(Vec<u8>),
    Error(ErrorClass),
    /// An error signal the profile does not classify (shown as the vendor wrote it).
    OtherError(String),
}

impl fmt::Display for NeutralOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NeutralOutcome::Value(v) => write!(f, "{v:04X}H"),
            NeutralOutcome::Text(t) => {
                write!(f, "\"")?;
                for b in t {
                    match b {
                        0x20..=0x7E if *b != b'"' && *b != b'\\' => write!(f, "{}", *b as char)?,
                        _ => write!(f, "\\x{b:02X}")?,
                    }
                }
                write!(f, "\"")
            }
            NeutralOutcome::Error(c) => write!(f, "{c}"),
            NeutralOutcome::OtherError(e) => write!(f, "error {e}"),
        }
    }
}

/// A profile's `neutral` section: how its instructions answer the neutral operations.
#[derive(Debug, Clone, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NeutralSection {
    /// How the profile's error signals read as neutral classes, e.g. `3401H: invalid-digit`
    /// for a code, `M8004: error` for a flag.
    #[serde(default)]
    pub errors: BTreeMap<String, ErrorClass>,
    #[serde(default)]
    pub lowerings: Vec<Lowering>,
}

/// One way of answering a neutral operation with one of the profile's instructions.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Lowering {
    /// The column name, unique within the profile, e.g. `habin-fixed`. Neutral cases refer to
    /// it as `<profile short>/<name>` (`iqr/habin-fixed`).
    pub name: String,
    pub description: String,
    pub operation: Operation,
    pub instruction: String,
    /// The variant to run on; the profile's first when absent.
    #[serde(default)]
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
    #[serde(default)]
    pub count: Option<String>,
    /// The digits the instruction handles when it takes no count (HABIN, BINHA: 4).
    #[serde(default)]
    pub width: Option<u32>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum TextLayout {
    /// Two characters per word, first character in the low byte.
    Packed,
    /// One character per word, in the low byte.
    Words,
}

/// A validated neutral case.
#[derive(Debug, Clone, Serialize)]
pub struct NeutralCase {
    pub id: String,
    pub operation: Operation,
    pub basis: Basis,
    pub citation: Citation,
    pub location: Location,
    /// The text (hex-to-value) as bytes.
    pub text: Vec<u8>,
    /// The value (value-to-hex).
    pub value: u64,
    /// The digit count given to instructions that take one.
    pub digits: u32,
    /// The answer every lowering is expected to give unless listed in `except`.
    pub expect: Option<NeutralOutcome>,
    /// Lowerings that answer differently, by `<profile short>/<lowering>`, with the reason.
    pub except: BTreeMap<String, (NeutralOutcome, String)>,
    pub note: Option<String>,
}

impl NeutralCase {
    /// What a lowering is expected to answer.
    pub fn expected_for(&self, lowering_key: &str) -> Option<&NeutralOutcome> {
        self.except
            .get(lowering_key)
            .map(|(o, _)| o)
            .or(self.expect.as_ref())
    }
}
