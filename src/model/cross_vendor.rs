//! Cross-vendor operations: one vendor-neutral question, asked of every vendor.
//!
//! Several vendors implement "hex ASCII text -> value" and "value -> hex ASCII text", each with
//! its own operands, character layout, digit-count convention and error signalling. A
//! cross-vendor case gives only the text (or value) and a digit count. Each profile says, as data,
//! how to lower that onto one of its instructions — which operands, flags and layout — and how
//! its error signals read as shared error classes. The outcome is lifted back to an [`Answer`],
//! so that the vendors' answers to the same question can be compared side by side.

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{Basis, Citation, ErrorSignal, Location, Operand};
use crate::device::Device;
pub use crate::spec::cross_vendor::{ErrorClass, Operation, TextLayout, ValueOrder};

/// What a vendor answered to a cross-vendor question.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Answer {
    Value(u64),
    /// Characters as bytes, up to the first 00H.
    Text(Vec<u8>),
    Error(ErrorClass),
    /// An error after which the instruction has still written its destination, so that what it
    /// wrote is part of the answer (Siemens ATH: an invalid character converts as 0 and
    /// RET_VAL is 0007H). Only the signals a profile lists in `written_on_error` lift so.
    ErrorAndValue(ErrorClass, u64),
    /// An error signal the profile does not classify (shown as the vendor wrote it).
    OtherError(String),
}

impl fmt::Display for Answer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Answer::Value(v) => write!(f, "{v:04X}H"),
            Answer::Text(t) => {
                write!(f, "\"")?;
                for b in t {
                    match b {
                        0x20..=0x7E if *b != b'"' && *b != b'\\' => write!(f, "{}", *b as char)?,
                        _ => write!(f, "\\x{b:02X}")?,
                    }
                }
                write!(f, "\"")
            }
            Answer::Error(c) => write!(f, "{c}"),
            Answer::ErrorAndValue(c, v) => write!(f, "{c} and {v:04X}H"),
            Answer::OtherError(e) => write!(f, "error {e}"),
        }
    }
}

/// How a profile answers the cross-vendor operations, validated.
#[derive(Debug, Clone, Default)]
pub struct CrossVendorSection {
    /// How the profile's error signals read as shared classes.
    pub errors: Vec<(ErrorSignal, ErrorClass)>,
    /// The signals after which the destination still holds the conversion.
    pub written_on_error: Vec<ErrorSignal>,
    pub lowerings: Vec<Arc<Lowering>>,
}

impl CrossVendorSection {
    /// A vendor's error signal as a shared class, by the profile's table.
    pub fn classify(&self, signal: &ErrorSignal) -> Answer {
        match self.errors.iter().find(|(s, _)| s == signal) {
            Some((_, class)) => Answer::Error(class.clone()),
            None => Answer::OtherError(signal.to_string()),
        }
    }

    /// Whether the destination still holds the conversion after this signal.
    pub fn writes_on(&self, signal: &ErrorSignal) -> bool {
        self.written_on_error.contains(signal)
    }
}

/// One way of answering a cross-vendor operation with one of a profile's instructions, with its
/// operands parsed and its variant resolved when the profile was loaded.
#[derive(Debug, Clone)]
pub struct Lowering {
    /// `<profile short>/<name>`: how cross-vendor cases and matrix columns name it.
    pub key: String,
    pub name: String,
    pub description: String,
    pub operation: Operation,
    pub instruction: String,
    pub variant: String,
    pub flags: BTreeMap<String, bool>,
    /// The fixed operands.
    pub operands: BTreeMap<String, Operand>,
    /// The head of the input: the text for hex-to-value, the value for value-to-hex.
    pub source: Device,
    /// The head of the result.
    pub destination: Device,
    pub text: TextLayout,
    /// The operand that receives the digit count, for instructions that take one.
    pub count: Option<String>,
    /// The constants the count operand can be programmed with, when limited.
    pub count_constants: Option<crate::spec::profile::ConstantRange>,
    /// Where a count outside those constants is put instead.
    pub count_register: Option<Device>,
    /// The digits the instruction handles when it takes no count (HABIN, BINHA: 4).
    pub width: Option<u32>,
    /// What one device of the profile holds.
    pub unit: crate::memory::Unit,
    /// The order of a value's units in memory.
    pub order: ValueOrder,
}

/// A validated cross-vendor case.
#[derive(Debug, Clone, Serialize)]
pub struct CrossVendorCase {
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
    pub expect: Option<Answer>,
    /// Lowerings that answer differently, by `<profile short>/<lowering>`, with the reason;
    /// `None` where no rule fixes the lowering's answer (recorded, never judged).
    pub except: BTreeMap<String, (Option<Answer>, String)>,
    pub note: Option<String>,
}

impl CrossVendorCase {
    /// What a lowering is expected to answer; `None` when nothing is.
    pub fn expected_for(&self, lowering_key: &str) -> Option<&Answer> {
        match self.except.get(lowering_key) {
            Some((answer, _)) => answer.as_ref(),
            None => self.expect.as_ref(),
        }
    }

    /// The case's basis for a lowering: `unspecified` where its `except` entry says so.
    pub fn basis_for(&self, lowering_key: &str) -> Basis {
        match self.except.get(lowering_key) {
            Some((None, _)) => Basis::Unspecified,
            _ => self.basis,
        }
    }
}

/// What a codec-level backend implements of the cross-vendor operations: a library's codec,
/// asked the cross-vendor questions directly, with no memory, devices or fills.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CodecAbilities {
    pub hex_to_value: Option<OperationAbilities>,
    pub value_to_hex: Option<OperationAbilities>,
}

/// What one operation of a codec takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OperationAbilities {
    /// The digit counts implemented; `None` is any count from 1 to 8.
    pub digits: Option<Vec<u32>>,
    /// The value width in bits.
    pub width: u32,
    /// The built-in reading it claims to follow (`fx5/hexa-16bit`), the oracle of its sweeps.
    pub reading: Option<String>,
}

impl Default for OperationAbilities {
    fn default() -> Self {
        OperationAbilities {
            digits: None,
            width: 16,
            reading: None,
        }
    }
}

impl CodecAbilities {
    /// Why a case is outside what the codec implements, if it is: it is then skipped with this
    /// reason, never failed.
    pub fn declines(&self, case: &CrossVendorCase) -> Option<String> {
        let ability = match case.operation {
            Operation::HexToValue => &self.hex_to_value,
            Operation::ValueToHex => &self.value_to_hex,
        };
        let Some(ability) = ability else {
            return Some(format!("implements no {}", case.operation));
        };
        let digits_ok = match &ability.digits {
            Some(list) => list.contains(&case.digits),
            None => (1..=8).contains(&case.digits),
        };
        if !digits_ok {
            let taken = ability.digits.as_ref().map_or_else(
                || "1 to 8".to_string(),
                |l| {
                    l.iter()
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                },
            );
            return Some(format!(
                "takes {taken} digit(s), not {} ({})",
                case.digits, case.operation
            ));
        }
        let fits = |v: u64| ability.width >= 64 || v >> ability.width == 0;
        match (case.operation, &case.expect) {
            (Operation::HexToValue, Some(Answer::Value(v))) if !fits(*v) => Some(format!(
                "the expected value {} is wider than its {} bits",
                Answer::Value(*v),
                ability.width
            )),
            (Operation::ValueToHex, _) if !fits(case.value) => Some(format!(
                "the value {} is wider than its {} bits",
                Answer::Value(case.value),
                ability.width
            )),
            _ => None,
        }
    }
}
