//! The messages of the external-backend protocol, version [`PROTOCOL_VERSION`].
//!
//! One JSON object per line in each direction; `docs/protocol.md` is the specification for
//! implementers and `schema/protocol.schema.json` is generated from these types, so the document,
//! the schema and the harness cannot drift apart. Messages from a backend are read strictly
//! (unknown fields are errors): a misspelt `writes` must not read as "wrote nothing".

use std::collections::BTreeMap;
use std::fmt;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::device::{code_matches, Device, DeviceSyntaxError};
use crate::memory::{Unit, Value};
use crate::model::cross_vendor::{ErrorClass, Operation};

/// The newest protocol version this harness speaks: it says so in its `hello`.
pub(crate) const PROTOCOL_VERSION: u32 = 5;
/// The versions a backend may answer with: 1 (instruction level only), 2 (instruction or
/// codec level), 3 (also byte-addressed families, whose memory ranges carry `bytes`), 4
/// (also families whose unit is a 32-bit word, `dwords`) and 5 (also `convert`: many
/// conversions answered in one line). Any other is refused before a case runs.
pub(crate) const SUPPORTED_VERSIONS: [u32; 5] = [1, 2, 3, 4, 5];

/// The first version that carries `convert` messages.
pub(crate) const CONVERT_VERSION: u32 = 5;

/// The first version that can carry memory of `unit`s.
pub(crate) fn first_version_for(unit: Unit) -> u32 {
    match unit {
        Unit::Word => 1,
        Unit::Byte => 3,
        Unit::Dword => 4,
    }
}

/// A device name as the protocol carries it: a code and a decimal number (`D100`, `MB20`,
/// `DB1.DBB10`).
const DEVICE_PATTERN: &str = crate::device::PATTERN;
/// A device operand: a device name, or `@` and one for indirect specification (`@D10`).
const OPERAND_PATTERN: &str =
    r"^@?([A-Z]([A-Z0-9.\\]*[A-Z])?([0-9]+\.[0-7]|[0-9]+)|[A-Z]([A-Z0-9.\\]*[A-Z])?[0-9A-F]+)$";

/// A message from the harness to a backend.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(crate) enum HarnessMessage {
    /// The first message: the backend answers with its own `hello`.
    Hello {
        /// The protocol version the harness speaks.
        protocol: u32,
        /// The harness and its version, for logs.
        harness: String,
    },
    /// Cases to execute: the backend answers each with one `result` or `unsupported` line, in
    /// the order given.
    Run { cases: Vec<RunCase> },
    /// Version 5, codec level: conversions of one operation, answered by one `converted` line.
    /// A sweep asks millions of texts; a line per answer is what made a codec in another
    /// process slow, not the codec.
    Convert {
        /// Echoed by the answer.
        id: u64,
        operation: Operation,
        /// The digit count of each item.
        digits: Vec<u32>,
        /// Hex-to-value: the texts, one character per byte (U+0000-U+00FF).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        #[schemars(with = "Option<Vec<String>>")]
        texts: Option<Vec<Latin1>>,
        /// Value-to-hex: the values.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        values: Option<Vec<u64>>,
    },
    /// The last message: the backend exits. The harness then closes stdin and, after a grace
    /// period, kills a backend that is still running.
    Shutdown,
}

/// One case to execute, with everything needed to execute it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CaseRequest {
    /// Unique within the session; the answer repeats it.
    pub id: u64,
    /// The corpus case id (the same case runs under several fills, variants and instructions).
    pub case: String,
    /// The instruction as the manual names it, e.g. `HABIN` or `HABINP`.
    pub instruction: String,
    /// The vendor profile id, e.g. `mitsubishi-iqr`.
    pub profile: String,
    /// The profile variant (CPU model or firmware), e.g. `rcpu`.
    pub variant: String,
    /// Every mode flag the instruction reads: the case's setting, or the profile default.
    pub flags: BTreeMap<String, bool>,
    /// Flags this variant does not implement, with the value it behaves as: such a CPU acts as
    /// if the flag held this value whatever `flags` says.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub ignored_flags: BTreeMap<String, bool>,
    /// Operands by the manual's names: a device as a string (`"D100"`, or `"@D10"` for
    /// indirect specification) or a constant as an integer (`4`, `-1`).
    pub operands: BTreeMap<String, OperandValue>,
    /// For each pointer of an operand given by indirect specification, the device whose
    /// address it holds: `{"D10": "D100"}` makes `@D10` address D100. The backend stores the
    /// address in the pointer's two words its own way (as its ADRSET would) before executing;
    /// what it answers for those two words is not judged. Left out when no operand is indirect.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub addresses: BTreeMap<String, String>,
    /// The fill pattern of the words the case does not set (see `docs/protocol.md` for the
    /// formula): what a word outside `memory` holds.
    pub fill: FillName,
    /// The memory before execution: every word the case may touch, fill included. The backend
    /// reports memory after for these same ranges (or lists its writes).
    pub memory: Vec<MemoryRange>,
    /// The device codes of the profile whose numbers are hexadecimal (MELSEC `W`, `SW`): `W1A`
    /// is word 26, the one after `W19`. Left out when the profile has none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hexadecimal: Vec<String>,
}

impl CaseRequest {
    /// A device name of the case or of its answer, read with the case's numbering.
    pub(crate) fn device(&self, text: &str) -> Result<Device, DeviceSyntaxError> {
        // Most profiles number nothing in hexadecimal: read those names the short way, as
        // every request and answer names several.
        if self.hexadecimal.is_empty() {
            return text.parse();
        }
        Device::parse_numbered(text, |code| {
            self.hexadecimal.iter().any(|h| code_matches(h, code))
        })
    }

    /// A device operand as the instruction reaches it: `D100` itself, or for `@D10` the device
    /// `addresses` gives for D10, with the pointer.
    pub(crate) fn operand_device(
        &self,
        text: &str,
    ) -> Result<(Device, Option<Device>), OperandError> {
        let Some(pointer) = text.strip_prefix('@') else {
            return Ok((self.device(text)?, None));
        };
        let pointer = self.device(pointer)?;
        for (name, target) in &self.addresses {
            if self.device(name).as_ref() == Ok(&pointer) {
                let target = self
                    .device(target)
                    .map_err(|source| OperandError::Address {
                        name: name.clone(),
                        source,
                    })?;
                return Ok((target, Some(pointer)));
            }
        }
        Err(OperandError::NoAddress {
            text: text.to_string(),
            pointer,
        })
    }

    /// The words of the pointers in `addresses`: two from each, which hold an address in the
    /// backend's own encoding.
    pub(crate) fn pointer_words(&self) -> Vec<Device> {
        let pointers: Vec<Device> = (self.addresses.keys())
            .filter_map(|name| self.device(name).ok())
            .collect();
        crate::model::pointer_words(&pointers)
    }
}

/// One case of a `run` message: an instruction to execute (levels 1 and 2) or a conversion to
/// make (codec level, version 2).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum RunCase {
    Instruction(CaseRequest),
    Codec(CodecRequest),
}

impl RunCase {
    pub(crate) fn id(&self) -> u64 {
        match self {
            RunCase::Instruction(c) => c.id,
            RunCase::Codec(c) => c.id,
        }
    }
    /// The corpus case id.
    pub(crate) fn case(&self) -> &str {
        match self {
            RunCase::Instruction(c) => &c.case,
            RunCase::Codec(c) => &c.case,
        }
    }
}

/// One cross-vendor conversion asked of a codec-level backend.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CodecRequest {
    pub id: u64,
    /// The cross-vendor case id.
    pub case: String,
    pub operation: Operation,
    /// hex-to-value: the characters, as byte values, exactly as the case gives them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub text: Option<Vec<u8>>,
    /// value-to-hex: the value to convert.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<u64>,
    /// The digit count (FX5 n, IDEC S2).
    pub digits: u32,
    /// A protocol-field question: the field of the codec's protocol asked (`word`, `lrc`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field: Option<String>,
}

/// An operand: a device name or a constant.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum OperandValue {
    /// A word device as the manuals write it, e.g. `D100`; `@D10` is the device whose address
    /// D10 holds (see `addresses`).
    Device(#[schemars(regex(pattern = OPERAND_PATTERN))] String),
    /// A constant (`K4` is `4`, `H0ABC` is `2748`).
    Constant(i64),
}

/// The two fill patterns of [`crate::memory::Fill`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub(crate) enum FillName {
    A,
    B,
}

/// Consecutive devices from a start device: words of a word-addressed family, (version 3)
/// bytes of a byte-addressed one, or (version 4) 32-bit words of a family whose unit is one;
/// exactly one of `words`, `bytes` and `dwords`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct MemoryRange {
    /// The first device, e.g. `D100` or `DB1.DBB10`.
    #[schemars(regex(pattern = DEVICE_PATTERN))]
    pub start: String,
    /// The words from `start` on, as unsigned 16-bit integers (word-addressed families). A
    /// digit-designated start's next word is 16 points on: `K4M0`, `K4M16`, ...
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub words: Vec<u16>,
    /// The bytes from `start` on, as unsigned 8-bit integers (byte-addressed families,
    /// version 3).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bytes: Vec<u8>,
    /// The 32-bit words from `start` on, as unsigned 32-bit integers (families whose unit is a
    /// 32-bit word, version 4).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dwords: Vec<u32>,
}

impl MemoryRange {
    /// A range of units of memory.
    pub(crate) fn new(start: String, unit: Unit, values: Vec<Value>) -> Self {
        let mut range = MemoryRange {
            start,
            words: Vec::new(),
            bytes: Vec::new(),
            dwords: Vec::new(),
        };
        match unit {
            Unit::Word => range.words = values.into_iter().map(|v| v as u16).collect(),
            Unit::Byte => range.bytes = values.into_iter().map(|v| v as u8).collect(),
            Unit::Dword => range.dwords = values,
        }
        range
    }

    /// The field a range of `unit`s is given in.
    pub(crate) fn field(unit: Unit) -> &'static str {
        match unit {
            Unit::Byte => "bytes",
            Unit::Word => "words",
            Unit::Dword => "dwords",
        }
    }

    /// The range's values in `unit`s; an error names what does not fit.
    pub(crate) fn values(&self, unit: Unit) -> Result<Vec<Value>, ProtocolViolation> {
        let refuse =
            |what: String| ProtocolViolation(format!("the range from {} {what}", self.start));
        let given: Vec<Unit> = [Unit::Byte, Unit::Word, Unit::Dword]
            .into_iter()
            .filter(|u| match u {
                Unit::Byte => !self.bytes.is_empty(),
                Unit::Word => !self.words.is_empty(),
                Unit::Dword => !self.dwords.is_empty(),
            })
            .collect();
        match given.as_slice() {
            [] => Ok(Vec::new()),
            [u] if *u == unit => Ok(match unit {
                Unit::Byte => self.bytes.iter().map(|b| Value::from(*b)).collect(),
                Unit::Word => self.words.iter().map(|w| Value::from(*w)).collect(),
                Unit::Dword => self.dwords.clone(),
            }),
            [u] => Err(refuse(format!(
                "gives `{}`, but the family's unit is a {}: give `{}`",
                Self::field(*u),
                unit.name(),
                Self::field(unit)
            ))),
            _ => Err(refuse(
                "gives more than one of `words`, `bytes` and `dwords`".to_string(),
            )),
        }
    }
}

/// What a message does wrong against the protocol: it becomes the case's protocol-error fault.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ProtocolViolation(pub String);

impl std::fmt::Display for ProtocolViolation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// A message from a backend to the harness.
// The hello carries the capabilities and is read once per backend; the results, read by the
// thousand, are not held long enough for their size to matter either.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(crate) enum BackendMessage {
    /// The answer to the harness's `hello`.
    Hello {
        /// The protocol version the backend speaks; must equal the harness's.
        protocol: u32,
        backend: BackendInfo,
        capabilities: Capabilities,
    },
    /// What one case did. Words in neither `memory` nor `writes` are unchanged.
    Result {
        /// The `id` of the case answered.
        id: u64,
        /// Memory after execution, e.g. the ranges the request gave. A word reported with its
        /// old value is not a change.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        memory: Vec<MemoryRange>,
        /// The words written, by device name: an alternative to `memory` for backends that
        /// track writes. Both may be given; `writes` wins for a word in both. A name given
        /// twice is an error.
        #[serde(
            default,
            skip_serializing_if = "BTreeMap::is_empty",
            deserialize_with = "unique_writes"
        )]
        writes: BTreeMap<String, Value>,
        /// The operation error signalled, or null for none.
        #[serde(default)]
        error: Option<ErrorReport>,
        /// Codec level, hex-to-value: the value decoded.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        value: Option<i64>,
        /// Codec level, value-to-hex: the characters written, as byte values.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        text: Option<Vec<u8>>,
        /// Codec level, verify: `true` when the check characters match their span (a mismatch
        /// is the error `bad-check`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        accepted: Option<bool>,
    },
    /// The backend does not implement this case. For a case it claims in its capabilities this
    /// counts as a difference, never as a skip.
    Unsupported { id: u64, reason: String },
    /// Version 5: the answers to one `convert` message, one per item, in order.
    Converted {
        /// The `id` of the `convert` message answered.
        id: u64,
        answers: Vec<Converted>,
    },
}

/// Bytes carried as a JSON string of one character per byte (U+0000-U+00FF): what a codec's
/// text is in a `convert` message, read with one call in any language (`latin-1`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Latin1(pub Vec<u8>);

impl Serialize for Latin1 {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(&self.0.iter().map(|&b| char::from(b)).collect::<String>())
    }
}

impl<'de> Deserialize<'de> for Latin1 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = std::borrow::Cow::<str>::deserialize(d)?;
        s.chars()
            .map(|c| u8::try_from(u32::from(c)).ok())
            .collect::<Option<Vec<u8>>>()
            .map(Latin1)
            .ok_or_else(|| {
                serde::de::Error::custom(
                    "a character above U+00FF in a text (one character per byte)",
                )
            })
    }
}

/// One answer of a `converted` line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum Converted {
    /// Hex-to-value: the value (a negative one is a difference, not garbage).
    Value(i64),
    /// Value-to-hex: the characters written, one per byte.
    Text(#[schemars(with = "String")] Latin1),
    Error(ConvertedError),
    Unsupported(ConvertedUnsupported),
}

/// `{"error": "invalid-digit"}`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ConvertedError {
    pub error: ErrorClass,
}

/// `{"unsupported": "why"}`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ConvertedUnsupported {
    pub unsupported: String,
}

/// Who the backend is.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BackendInfo {
    pub name: String,
    pub version: String,
}

/// What a backend implements. Trials outside it are skipped with a reason; trials inside it
/// must be answered. An instruction-level backend gives `profile` and `instructions`; a
/// codec-level one (version 2) gives `codec` instead.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Capabilities {
    /// The vendor profile id it implements, e.g. `mitsubishi-iqr`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub profile: String,
    /// The instructions it implements, as the profile names them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub instructions: Vec<String>,
    /// Codec level: the cross-vendor operations it implements.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub codec: Option<CodecCapabilities>,
    /// Operands of which it implements only some forms, by the manual's operand name: a trial
    /// with another form is skipped, not failed (`{"n": {"constants": [4]}}`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub operands: BTreeMap<String, OperandCapabilities>,
    /// Whether it checks device ranges (default true). A library with no devices of its own says
    /// false, and the cases expecting a device-range error are skipped for it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device_ranges: Option<bool>,
    /// The variants it implements; every variant of the profile when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variants: Option<Vec<String>>,
    /// Flags of which it implements only some settings: flag -> the settings it implements, as
    /// the variant sees them. Flags not listed are implemented in both settings.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub flags: BTreeMap<String, Vec<bool>>,
}

/// The forms of one operand a backend implements; a form not listed is all of its kind.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OperandCapabilities {
    /// The device codes implemented; empty for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub devices: Option<Vec<String>>,
    /// The constants implemented; empty for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constants: Option<Vec<i64>>,
}

/// The operations of a codec-level backend.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CodecCapabilities {
    /// Text -> value; absent when not implemented.
    #[serde(
        rename = "hex-to-value",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub hex_to_value: Option<OperationCapabilities>,
    /// Value -> text; absent when not implemented.
    #[serde(
        rename = "value-to-hex",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub value_to_hex: Option<OperationCapabilities>,
    /// A protocol's check characters computed over a span; absent when not implemented.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<OperationCapabilities>,
    /// A protocol's check characters verified; absent when not implemented.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verify: Option<OperationCapabilities>,
    /// The protocol whose fields the codec implements (`mc-ascii`, `modbus-ascii`): it is
    /// judged by that protocol's corpus (`vectors/protocols/`) instead of the cross-vendor one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub protocol: Option<String>,
    /// The protocol's fields implemented, by the protocol profile's names; every field when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields: Option<Vec<String>>,
    /// With `protocol`: also run the cross-vendor (instruction) corpus, the second view.
    #[serde(
        rename = "cross-vendor",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub cross_vendor: Option<bool>,
}

/// What one codec operation takes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OperationCapabilities {
    /// The digit counts implemented; any from 1 to 8 when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub digits: Option<Vec<u32>>,
    /// The value width in bits, 16 or 32 (16 when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// The built-in reading the codec follows, as a sweep names it (`fx5/hexa-16bit`): what
    /// `sweep --operation` judges the codec against unless `--oracle` says otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reading: Option<String>,
    /// The value width in bits (8, 16 or 32) for each digit count the field takes, by count:
    /// `{"2": 8, "4": 16}`. The counts given are the counts taken when `digits` is absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub widths: Option<std::collections::BTreeMap<String, u32>>,
    /// A token of whatever length: text -> value reads the characters it is given (a case whose
    /// text is not exactly its digit count is skipped).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variable: Option<bool>,
    /// Whether value -> text writes the field's leading zeros (true when absent).
    #[serde(
        rename = "leading-zeros",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub leading_zeros: Option<bool>,
    /// `high-first` (when absent) or `low-first`: the first character pair is the low byte.
    #[serde(
        rename = "byte-order",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub byte_order: Option<ByteOrder>,
    /// The codec checks its field as part of a whole frame: a text with characters after the
    /// field is skipped.
    #[serde(
        rename = "whole-frame",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub whole_frame: Option<bool>,
    /// Text -> value skips blanks (20H) between byte pairs, as Python's `bytes.fromhex`: a text
    /// with a blank where a pair could start is skipped.
    #[serde(
        rename = "blanks-between-pairs",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub blanks_between_pairs: Option<bool>,
}

/// Which byte a field's first character pair is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum ByteOrder {
    HighFirst,
    LowFirst,
}

/// An operation error: the vendor's code or flag (instruction level), or an error class (codec
/// level, version 2).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum ErrorReport {
    Signal(SignalReport),
    /// Codec level: `"invalid-digit"`, `"invalid-count"`, `"device-range"` or `"error"`.
    Class(ErrorClass),
}

/// An instruction-level error signal.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub(crate) enum SignalReport {
    /// The error code, e.g. `13313` for 3401H.
    Code(u16),
    /// The error flag turned on, e.g. `"M8004"`.
    Flag(#[schemars(regex(pattern = DEVICE_PATTERN))] String),
}

/// `writes` with every name once: JSON lets a key repeat, and a map would keep the last value
/// without a word.
fn unique_writes<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<BTreeMap<String, Value>, D::Error> {
    struct Unique;
    impl<'de> serde::de::Visitor<'de> for Unique {
        type Value = BTreeMap<String, Value>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map of device names to values (words, bytes or 32-bit words)")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some((name, word)) = map.next_entry::<String, Value>()? {
                if out.contains_key(&name) {
                    return Err(serde::de::Error::custom(format!(
                        "`{name}` is given twice in `writes`"
                    )));
                }
                out.insert(name, word);
            }
            Ok(out)
        }
    }
    deserializer.deserialize_map(Unique)
}

fn some_unique_writes<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<Option<BTreeMap<String, Value>>, D::Error> {
    unique_writes(deserializer).map(Some)
}

/// Refuses a field a message of this type does not have: decoding every type's fields into one
/// struct would otherwise accept, say, `cases` on a `hello`.
fn only_fields(
    kind: &str,
    present: &[(&str, bool)],
    allowed: &[&str],
) -> Result<(), serde_json::Error> {
    use serde::de::Error;
    match present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        Some((k, _)) => Err(serde_json::Error::custom(format!(
            "unknown field `{k}` in a `{kind}` message"
        ))),
        None => Ok(()),
    }
}

impl HarnessMessage {
    /// Reads one line. Equivalent to deserializing the enum, but field by field: serde reads an
    /// internally tagged enum by buffering the whole message first, which for a batch of cases
    /// costs more than executing them.
    pub(crate) fn from_line(line: &[u8]) -> Result<HarnessMessage, serde_json::Error> {
        use serde::de::Error;
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Line {
            #[serde(rename = "type")]
            kind: String,
            protocol: Option<u32>,
            harness: Option<String>,
            cases: Option<Vec<RunCase>>,
            id: Option<u64>,
            operation: Option<Operation>,
            digits: Option<Vec<u32>>,
            texts: Option<Vec<Latin1>>,
            values: Option<Vec<u64>>,
        }
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct InstructionRun {
            #[serde(rename = "type")]
            kind: String,
            cases: Vec<CaseRequest>,
        }
        // Instruction requests are read without the untagged detour when they are all there is:
        // a batch of them is what the native adapter's throughput depends on.
        if let Ok(run) = serde_json::from_slice::<InstructionRun>(line) {
            if run.kind == "run" {
                return Ok(HarnessMessage::Run {
                    cases: run.cases.into_iter().map(RunCase::Instruction).collect(),
                });
            }
        }
        let l: Line = serde_json::from_slice(line)?;
        let present = [
            ("protocol", l.protocol.is_some()),
            ("harness", l.harness.is_some()),
            ("cases", l.cases.is_some()),
            ("id", l.id.is_some()),
            ("operation", l.operation.is_some()),
            ("digits", l.digits.is_some()),
            ("texts", l.texts.is_some()),
            ("values", l.values.is_some()),
        ];
        let only = |allowed: &[&str]| only_fields(&l.kind, &present, allowed);
        let missing = |k: &'static str| serde_json::Error::missing_field(k);
        match l.kind.as_str() {
            "hello" => {
                only(&["protocol", "harness"])?;
                Ok(HarnessMessage::Hello {
                    protocol: l.protocol.ok_or_else(|| missing("protocol"))?,
                    harness: l.harness.clone().ok_or_else(|| missing("harness"))?,
                })
            }
            "run" => {
                only(&["cases"])?;
                Ok(HarnessMessage::Run {
                    cases: l.cases.ok_or_else(|| missing("cases"))?,
                })
            }
            "convert" => {
                only(&["id", "operation", "digits", "texts", "values"])?;
                Ok(HarnessMessage::Convert {
                    id: l.id.ok_or_else(|| missing("id"))?,
                    operation: l.operation.ok_or_else(|| missing("operation"))?,
                    digits: l.digits.ok_or_else(|| missing("digits"))?,
                    texts: l.texts,
                    values: l.values,
                })
            }
            "shutdown" => {
                only(&[])?;
                Ok(HarnessMessage::Shutdown)
            }
            other => Err(serde_json::Error::unknown_variant(
                other,
                &["hello", "run", "convert", "shutdown"],
            )),
        }
    }
}

impl BackendMessage {
    /// Reads one line, field by field (see [`HarnessMessage::from_line`]).
    pub(crate) fn from_line(line: &[u8]) -> Result<BackendMessage, serde_json::Error> {
        use serde::de::Error;
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Line {
            #[serde(rename = "type")]
            kind: String,
            id: Option<u64>,
            memory: Option<Vec<MemoryRange>>,
            #[serde(default, deserialize_with = "some_unique_writes")]
            writes: Option<BTreeMap<String, Value>>,
            // Present-and-null and absent both mean "no error".
            #[serde(default)]
            error: Option<ErrorReport>,
            reason: Option<String>,
            protocol: Option<u32>,
            backend: Option<BackendInfo>,
            capabilities: Option<Capabilities>,
            value: Option<i64>,
            text: Option<Vec<u8>>,
            accepted: Option<bool>,
            answers: Option<Vec<Converted>>,
        }
        let l: Line = serde_json::from_slice(line)?;
        let present = [
            ("id", l.id.is_some()),
            ("memory", l.memory.is_some()),
            ("writes", l.writes.is_some()),
            ("error", l.error.is_some()),
            ("reason", l.reason.is_some()),
            ("protocol", l.protocol.is_some()),
            ("backend", l.backend.is_some()),
            ("capabilities", l.capabilities.is_some()),
            ("value", l.value.is_some()),
            ("text", l.text.is_some()),
            ("accepted", l.accepted.is_some()),
            ("answers", l.answers.is_some()),
        ];
        let only = |allowed: &[&str]| only_fields(&l.kind, &present, allowed);
        let missing = |k: &'static str| serde_json::Error::missing_field(k);
        match l.kind.as_str() {
            "result" => {
                only(&[
                    "id", "memory", "writes", "error", "value", "text", "accepted",
                ])?;
                Ok(BackendMessage::Result {
                    id: l.id.ok_or_else(|| missing("id"))?,
                    memory: l.memory.unwrap_or_default(),
                    writes: l.writes.unwrap_or_default(),
                    error: l.error,
                    value: l.value,
                    text: l.text,
                    accepted: l.accepted,
                })
            }
            "unsupported" => {
                only(&["id", "reason"])?;
                Ok(BackendMessage::Unsupported {
                    id: l.id.ok_or_else(|| missing("id"))?,
                    reason: l.reason.ok_or_else(|| missing("reason"))?,
                })
            }
            "hello" => {
                only(&["protocol", "backend", "capabilities"])?;
                Ok(BackendMessage::Hello {
                    protocol: l.protocol.ok_or_else(|| missing("protocol"))?,
                    backend: l.backend.ok_or_else(|| missing("backend"))?,
                    capabilities: l.capabilities.ok_or_else(|| missing("capabilities"))?,
                })
            }
            "converted" => {
                only(&["id", "answers"])?;
                Ok(BackendMessage::Converted {
                    id: l.id.ok_or_else(|| missing("id"))?,
                    answers: l.answers.ok_or_else(|| missing("answers"))?,
                })
            }
            other => Err(serde_json::Error::unknown_variant(
                other,
                &["hello", "result", "unsupported", "converted"],
            )),
        }
    }
}

/// Any message of the protocol: the root of the JSON Schema.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
#[schemars(
    title = "plc-conformance external-backend protocol, versions 1 to 5",
    description = "One JSON object per line. The harness sends HarnessMessage lines on the \
                   backend's stdin; the backend answers with BackendMessage lines on stdout."
)]
// The root of the schema only: no message is kept in this type, so its size does not matter.
#[allow(clippy::large_enum_variant)]
pub(crate) enum ProtocolMessage {
    Harness(HarnessMessage),
    Backend(BackendMessage),
}

/// The JSON Schema (draft-07) of the protocol's messages, as `plc-conformance schema --kind
/// protocol` prints it.
pub(crate) fn protocol_schema() -> serde_json::Value {
    crate::spec::schema_of::<ProtocolMessage>()
}

/// Why an operand of a case does not name a device the backend can reach.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum OperandError {
    /// Not a device.
    Device(DeviceSyntaxError),
    /// The device `addresses` gives for a pointer is not a device.
    Address {
        name: String,
        source: DeviceSyntaxError,
    },
    /// An indirect operand whose pointer `addresses` does not name.
    NoAddress { text: String, pointer: Device },
}

impl From<DeviceSyntaxError> for OperandError {
    fn from(e: DeviceSyntaxError) -> Self {
        OperandError::Device(e)
    }
}

impl fmt::Display for OperandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OperandError::Device(e) => write!(f, "{e}"),
            OperandError::Address { name, .. } => write!(f, "`addresses.{name}`"),
            OperandError::NoAddress { text, pointer } => write!(
                f,
                "`{text}` is indirect, and `addresses` says nothing of {pointer}"
            ),
        }
    }
}

impl std::error::Error for OperandError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            OperandError::Device(e) => e.source(),
            OperandError::Address { source, .. } => Some(source),
            OperandError::NoAddress { .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An operand is a device name as [`DEVICE_PATTERN`] has it, with an optional `@`.
    #[test]
    fn the_operand_pattern_is_the_device_pattern_with_indirection() {
        assert_eq!(OPERAND_PATTERN, DEVICE_PATTERN.replacen('^', "^@?", 1));
    }

    #[test]
    fn messages_read_as_documented() {
        let hello: BackendMessage = serde_json::from_str(
            r#"{"type":"hello","protocol":1,"backend":{"name":"x","version":"1"},
                "capabilities":{"profile":"mitsubishi-iqr","instructions":["HABIN"],
                "flags":{"SM705":[false]}}}"#,
        )
        .expect("hello");
        assert!(matches!(hello, BackendMessage::Hello { protocol: 1, .. }));
        let result: BackendMessage = serde_json::from_str(
            r#"{"type":"result","id":3,"writes":{"D200":23181},"error":{"code":13313}}"#,
        )
        .expect("result");
        assert_eq!(
            result,
            BackendMessage::Result {
                id: 3,
                memory: vec![],
                writes: BTreeMap::from([("D200".into(), 0x5A8D)]),
                error: Some(ErrorReport::Signal(SignalReport::Code(0x3401))),
                value: None,
                text: None,
                accepted: None,
            }
        );
        let codec: BackendMessage =
            serde_json::from_str(r#"{"type":"result","id":7,"error":"invalid-digit"}"#)
                .expect("codec error");
        assert!(matches!(
            codec,
            BackendMessage::Result {
                error: Some(ErrorReport::Class(ErrorClass::InvalidDigit)),
                ..
            }
        ));
        let run: HarnessMessage = serde_json::from_str(
            r#"{"type":"run","cases":[{"id":1,"case":"c","instruction":"HABIN",
                "profile":"p","variant":"v","flags":{"SM705":true},"operands":{"s":"D100","n":4},
                "fill":"A","memory":[{"start":"D100","words":[16693,17464]}]}]}"#,
        )
        .expect("run");
        let HarnessMessage::Run { cases } = run else {
            panic!("not a run message")
        };
        let RunCase::Instruction(case) = &cases[0] else {
            panic!("not an instruction request")
        };
        assert_eq!(case.operands["n"], OperandValue::Constant(4));
        assert_eq!(case.operands["s"], OperandValue::Device("D100".into()));
        let run = HarnessMessage::from_line(
            br#"{"type":"run","cases":[{"id":7,"case":"c","operation":"hex-to-value","text":[53,65],"digits":2}]}"#,
        )
        .expect("codec run");
        let HarnessMessage::Run { cases } = run else {
            panic!("not a run message")
        };
        assert!(matches!(&cases[0], RunCase::Codec(c) if c.text == Some(vec![53, 65])));
        assert_eq!(
            serde_json::to_string(&HarnessMessage::Shutdown).expect("json"),
            r#"{"type":"shutdown"}"#
        );
    }

    #[test]
    fn reading_field_by_field_agrees_with_the_enums() {
        let backend = [
            r#"{"type":"hello","protocol":1,"backend":{"name":"x","version":"1"},"capabilities":{"profile":"p","instructions":["HABIN"],"variants":["v"],"flags":{"SM705":[false]}}}"#,
            r#"{"type":"result","id":3,"writes":{"D200":23181},"error":{"code":13313}}"#,
            r#"{"id":3,"type":"result","memory":[{"start":"D200","words":[1,2]}],"error":null}"#,
            r#"{"type":"result","id":4,"error":{"flag":"M8004"}}"#,
            r#"{"type":"unsupported","id":5,"reason":"no"}"#,
            r#"{"type":"result","id":3,"reason":"no"}"#,
            r#"{"type":"unsupported","id":5}"#,
            r#"{"type":"result"}"#,
            r#"{"type":"bye","id":5}"#,
            r#"{"type":"result","id":3,"writes":{"D200":65536}}"#,
            r#"{"type":"result","id":3,"write":{}}"#,
            r#"{"type":"result","id":7,"value":23181}"#,
            r#"{"type":"result","id":7,"text":[48,65]}"#,
            r#"{"type":"result","id":7,"error":"invalid-digit"}"#,
            r#"{"type":"result","id":7,"error":"overflow"}"#,
            r#"{"type":"hello","protocol":2,"backend":{"name":"x","version":"1"},"capabilities":{"codec":{"hex-to-value":{"digits":[4],"width":16}}}}"#,
            r#"[1,2]"#,
        ];
        for line in backend {
            let enum_way = serde_json::from_str::<BackendMessage>(line).ok();
            assert_eq!(
                BackendMessage::from_line(line.as_bytes()).ok(),
                enum_way,
                "{line}"
            );
        }
        let harness = [
            r#"{"type":"hello","protocol":1,"harness":"h"}"#,
            r#"{"type":"run","cases":[]}"#,
            r#"{"type":"shutdown"}"#,
            r#"{"type":"run"}"#,
            r#"{"type":"stop"}"#,
        ];
        for line in harness {
            let enum_way = serde_json::from_str::<HarnessMessage>(line).ok();
            assert_eq!(
                HarnessMessage::from_line(line.as_bytes()).ok(),
                enum_way,
                "{line}"
            );
        }
        // Stricter than serde, which lets a unit variant of a tagged enum carry extra fields.
        assert!(HarnessMessage::from_line(br#"{"type":"shutdown","cases":[]}"#).is_err());
    }

    #[test]
    fn a_name_given_twice_in_writes_is_refused() {
        let line = br#"{"type":"result","id":3,"writes":{"D200":1,"D200":2}}"#;
        let e = BackendMessage::from_line(line).expect_err("a repeated name");
        assert!(e.to_string().contains("`D200` is given twice"), "{e}");
        assert!(serde_json::from_slice::<BackendMessage>(line).is_err());
    }

    #[test]
    fn a_misspelt_field_is_refused() {
        let e = serde_json::from_str::<BackendMessage>(r#"{"type":"result","id":3,"write":{}}"#);
        assert!(e.is_err());
        let e = serde_json::from_str::<BackendMessage>(
            r#"{"type":"result","id":3,"writes":{"D200":4294967296}}"#,
        );
        assert!(e.is_err(), "a value wider than any unit");
    }
}
