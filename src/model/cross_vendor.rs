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

use super::protocol::FieldRule;
use super::{Basis, Citation, ErrorSignal, Location, Operand};
use crate::device::Device;
use crate::memory::{Image, Unit, Value};
pub(crate) use crate::spec::cross_vendor::TextLayout;
pub(crate) use crate::spec::cross_vendor::ValueOrder;
pub use crate::spec::cross_vendor::{ErrorClass, Operation};

/// How a family stores text (a lowering's `text`), in one place: packing a text into units,
/// reading a character back, the vector notation that writes it, and which units can hold it.
impl TextLayout {
    /// Characters to a unit: as many as it has bytes when packed, one otherwise.
    fn per_unit(self, unit: Unit) -> u32 {
        match self {
            TextLayout::Packed | TextLayout::PackedHighFirst => unit.bits() / 8,
            TextLayout::Words => 1,
        }
    }

    /// Text with its 00H terminator, in memory units.
    pub(crate) fn units(self, unit: Unit, text: &[u8]) -> Vec<Value> {
        let mut chars = text.to_vec();
        chars.push(0);
        match self {
            TextLayout::Packed => unit.pack(&chars),
            // The first character in the unit's highest byte.
            TextLayout::PackedHighFirst => (unit.pack(&chars).into_iter())
                .map(|v| v.swap_bytes() >> (Value::BITS - unit.bits()))
                .collect(),
            TextLayout::Words => chars.iter().map(|c| Value::from(*c)).collect(),
        }
    }

    /// The `k`th character of a text stored this way, `read(i)` giving its `i`th unit.
    pub(crate) fn char_at(
        self,
        unit: Unit,
        k: u32,
        read: impl Fn(u32) -> Option<Value>,
    ) -> Option<u8> {
        let per = self.per_unit(unit);
        let (value, i) = (read(k / per)?, k % per);
        let shift = match self {
            TextLayout::Packed | TextLayout::Words => 8 * i,
            TextLayout::PackedHighFirst => unit.bits() - 8 * (i + 1),
        };
        Some((value >> shift) as u8)
    }

    /// The `k`th character of a text stored this way from `head` on in `memory` (MELSEC
    /// string storage is [`TextLayout::Packed`]: two characters a word, the first low).
    pub fn char_in(self, memory: &Image, head: &Device, k: u32) -> Option<u8> {
        self.char_at(memory.unit(), k, |i| Some(memory.read(&head.offset(i)?)))
    }

    /// The vector notation that stores a text this way (`ascii`, `ascii_words`), if one does.
    pub(crate) fn notation(self) -> Option<&'static str> {
        match self {
            TextLayout::Packed => Some("ascii"),
            TextLayout::Words => Some("ascii_words"),
            TextLayout::PackedHighFirst => None,
        }
    }

    /// Whether units of `unit` can hold text this way: packing needs more than a byte a unit.
    pub(crate) fn fits(self, unit: Unit) -> bool {
        self == TextLayout::Words || unit != Unit::Byte
    }
}

/// What a vendor answered to a cross-vendor question.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Answer {
    /// A binary value: what a hex-to-value conversion gives.
    Value(u64),
    /// Characters as bytes, up to the first 00H.
    Text(Vec<u8>),
    /// An error, as the shared class the profile's table maps the vendor's signal to.
    Error(ErrorClass),
    /// An error after which the instruction has still written its destination, so that what it
    /// wrote is part of the answer (Siemens ATH: an invalid character converts as 0 and
    /// RET_VAL is 0007H). Only the signals a profile lists in `written_on_error` lift so.
    ErrorAndValue(ErrorClass, u64),
    /// An error signal the profile does not classify (shown as the vendor wrote it).
    OtherError(String),
    /// Check characters found to match their span (a protocol's `verify`).
    Accepted,
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
            Answer::Accepted => write!(f, "accepted"),
        }
    }
}

/// How a profile answers the cross-vendor operations, validated.
#[derive(Debug, Clone, Default)]
pub(crate) struct CrossVendorSection {
    /// How the profile's error signals read as shared classes.
    pub errors: Vec<(ErrorSignal, ErrorClass)>,
    /// The signals after which the destination still holds the conversion.
    pub written_on_error: Vec<ErrorSignal>,
    pub lowerings: Vec<Arc<Lowering>>,
}

impl CrossVendorSection {
    /// A vendor's error signal as a shared class, by the profile's table.
    pub(crate) fn classify(&self, signal: &ErrorSignal) -> Answer {
        match self.errors.iter().find(|(s, _)| s == signal) {
            Some((_, class)) => Answer::Error(class.clone()),
            None => Answer::OtherError(signal.to_string()),
        }
    }

    /// Whether the destination still holds the conversion after this signal.
    pub(crate) fn writes_on(&self, signal: &ErrorSignal) -> bool {
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
    /// The case id: what trial names, filters and known-differences entries use.
    pub id: String,
    /// What is asked: hex-to-value, value-to-hex, or a protocol's check or verify.
    pub operation: Operation,
    /// How far the expectation can be trusted: manual, inferred, unspecified or observed.
    pub basis: Basis,
    /// The manual, page and quoted text the expectation rests on.
    pub citation: Citation,
    /// Where the case is written, for reports to point at.
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
    /// Free text for readers of the case.
    pub note: Option<String>,
    /// The protocol, field and rule of a protocol-field case; `None` for a cross-vendor one.
    #[serde(skip)]
    pub(crate) protocol: Option<FieldRule>,
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
    /// Hex ASCII text to a value (decoding a field); `None` when the codec does not decode.
    pub hex_to_value: Option<OperationAbilities>,
    /// A value to hex ASCII text (encoding a field); `None` when the codec does not encode.
    pub value_to_hex: Option<OperationAbilities>,
    /// A protocol's check characters computed over a span.
    pub check: Option<OperationAbilities>,
    /// A protocol's check characters verified.
    pub verify: Option<OperationAbilities>,
    /// The protocol whose fields the codec implements: it is judged by that protocol's corpus.
    pub protocol: Option<ProtocolClaim>,
}

/// Which protocol's fields a codec implements, and which views judge it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProtocolClaim {
    /// The protocol profile's id (`modbus-ascii`).
    pub id: String,
    /// The fields implemented, by the profile's names; `None` for every field.
    pub fields: Option<Vec<String>>,
    /// Also run the cross-vendor (instruction) corpus, the second view.
    pub cross_vendor: bool,
}

impl CodecAbilities {
    /// The abilities of one operation.
    pub fn of(&self, operation: Operation) -> Option<&OperationAbilities> {
        match operation {
            Operation::HexToValue => self.hex_to_value.as_ref(),
            Operation::ValueToHex => self.value_to_hex.as_ref(),
            Operation::Check => self.check.as_ref(),
            Operation::Verify => self.verify.as_ref(),
        }
    }

    /// Whether the cross-vendor corpus asks this codec: a codec of no protocol, or one that
    /// asks for that view too.
    pub fn takes_cross_vendor(&self) -> bool {
        self.protocol.as_ref().is_none_or(|p| p.cross_vendor)
    }
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
    /// The shape of its field, where it is not a fixed run of digits, most significant first.
    pub shape: FieldShape,
}

/// What a protocol's field is, beyond its digit count: what the harness must know to ask a codec
/// only what its field can hold, and to read its answer as the field means it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldShape {
    /// The value width in bits for each digit count the field takes (2 digits an 8-bit byte, 4 a
    /// word, 8 a double word); the counts given are the counts taken.
    pub widths: BTreeMap<u32, u32>,
    /// A token of whatever length (KEYENCE Host Link `.H`): it reads the characters it is given,
    /// so a case whose text is not exactly its digit count is not asked.
    pub variable: bool,
    /// Whether value -> text writes the leading zeros of the field; without them 007FH is "7F".
    pub leading_zeros: bool,
    /// The first character pair is the low byte (the MEWTOCOL order): "ABCD" is CDABH.
    pub low_byte_first: bool,
    /// The codec checks its field as part of a whole frame (trailing text, a checksum): a text
    /// with characters after its field is not asked.
    pub whole_frame: bool,
    /// Text -> value skips blanks (20H) between byte pairs (Python's `bytes.fromhex`): a text
    /// with a blank where a pair could start is not asked, since the vendors refuse it.
    pub blanks_between_pairs: bool,
}

impl Default for FieldShape {
    fn default() -> Self {
        FieldShape {
            widths: BTreeMap::new(),
            variable: false,
            leading_zeros: true,
            low_byte_first: false,
            whole_frame: false,
            blanks_between_pairs: false,
        }
    }
}

impl Default for OperationAbilities {
    fn default() -> Self {
        OperationAbilities {
            digits: None,
            width: 16,
            reading: None,
            shape: FieldShape::default(),
        }
    }
}

impl OperationAbilities {
    /// The value width for a digit count: the field's own for that count, else the operation's.
    pub fn width_for(&self, digits: u32) -> u32 {
        self.shape
            .widths
            .get(&digits)
            .copied()
            .unwrap_or(self.width)
    }

    /// The answer the field gives where the case expects `expected` of `digits` digits: the
    /// same, written as the field writes it (bytes low first, no leading zeros).
    pub fn shaped(&self, operation: Operation, digits: u32, expected: &Answer) -> Answer {
        match (operation, expected) {
            (Operation::HexToValue, Answer::Value(v)) if self.shape.low_byte_first => {
                let n = (digits / 2).min(8) as usize;
                let swapped = (0..n).fold(0u64, |acc, i| acc << 8 | (v >> (8 * i)) & 0xFF);
                Answer::Value(swapped)
            }
            (Operation::ValueToHex, Answer::Text(t)) => {
                let mut t = t.clone();
                if self.shape.low_byte_first {
                    t = t.chunks(2).rev().flatten().copied().collect();
                }
                if !self.shape.leading_zeros {
                    let zeros = t.iter().take_while(|b| **b == b'0').count();
                    t.drain(..zeros.min(t.len().saturating_sub(1)));
                }
                Answer::Text(t)
            }
            (_, other) => other.clone(),
        }
    }
}

/// Whether a blank (20H) stands where a byte pair could start: after an even number of the
/// characters that are not blanks.
pub(crate) fn blank_between_pairs(text: &[u8]) -> bool {
    let mut seen = 0usize;
    for &b in text {
        if b == b' ' {
            if seen % 2 == 0 {
                return true;
            }
        } else {
            seen += 1;
        }
    }
    false
}

impl CodecAbilities {
    /// Why a case is outside what the codec implements, if it is: it is then skipped with this
    /// reason, never failed.
    pub fn declines(&self, case: &CrossVendorCase) -> Option<String> {
        if let Some(from) = &case.protocol {
            let fields = match &self.protocol {
                Some(claim) if claim.id == from.protocol => claim.fields.as_ref(),
                _ => return Some(format!("implements no {} field", from.protocol)),
            };
            if fields.is_some_and(|f| !f.contains(&from.field)) {
                return Some(format!(
                    "implements no {} field of {}",
                    from.field, from.protocol
                ));
            }
        }
        self.declines_asking(
            case.operation,
            &case.text,
            case.value,
            case.digits,
            case.expect.as_ref(),
        )
    }

    /// [`CodecAbilities::declines`] of a question given by its parts (a sweep asks millions
    /// without making a case of each).
    pub fn declines_asking(
        &self,
        operation: Operation,
        text: &[u8],
        value: u64,
        digits: u32,
        expect: Option<&Answer>,
    ) -> Option<String> {
        let Some(ability) = self.of(operation) else {
            return Some(format!("implements no {}", operation));
        };
        let digits_ok = match (&ability.digits, ability.shape.widths.is_empty()) {
            (Some(list), _) => list.contains(&digits),
            (None, false) => ability.shape.widths.contains_key(&digits),
            (None, true) => (1..=8).contains(&digits),
        };
        if !digits_ok {
            let listed = ability.digits.clone().or_else(|| {
                (!ability.shape.widths.is_empty())
                    .then(|| ability.shape.widths.keys().copied().collect())
            });
            let taken = listed.as_ref().map_or_else(
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
                digits, operation
            ));
        }
        let shape = &ability.shape;
        let (length, count) = (text.len(), digits as usize);
        if operation == Operation::HexToValue {
            if shape.variable && length != count {
                return Some(format!(
                    "reads a token of whatever length, and the case gives {length} character(s) \
                     for a {count}-digit field"
                ));
            }
            if shape.blanks_between_pairs && blank_between_pairs(text) {
                return Some(
                    "skips blanks between byte pairs, and the text has a blank where a pair \
                     could start"
                        .into(),
                );
            }
            if shape.whole_frame && length > count {
                return Some(format!(
                    "checks its field as part of a whole frame, and the text has {} character(s) \
                     after its {count}-digit field",
                    length - count
                ));
            }
        }
        if shape.variable
            && operation == Operation::ValueToHex
            && u64::BITS - value.leading_zeros() > 4 * digits
        {
            return Some(format!(
                "writes every significant digit of the value, and {} has more than {count}",
                Answer::Value(value)
            ));
        }
        if shape.low_byte_first && count % 2 == 1 {
            return Some(format!(
                "puts the first character pair in the low byte, and {count} digit(s) are no \
                 whole bytes"
            ));
        }
        let width = ability.width_for(digits);
        let fits = |v: u64| width >= 64 || v >> width == 0;
        match (operation, expect) {
            (Operation::HexToValue, Some(Answer::Value(v))) if !fits(*v) => Some(format!(
                "the expected value {} is wider than its {width} bits",
                Answer::Value(*v),
            )),
            (Operation::ValueToHex, _) if !fits(value) => Some(format!(
                "the value {} is wider than its {width} bits",
                Answer::Value(value),
            )),
            _ => None,
        }
    }
}

#[cfg(test)]
mod shape_tests {

    /// Every layout a unit can hold reads back the text it stored, and the words of a 16-bit
    /// family are the manuals' (`5A` packed is 4135H; KEYENCE's `A5`, high byte first, too).
    #[test]
    fn a_text_reads_back_as_stored_in_every_layout_and_unit() {
        use crate::memory::Unit;
        for unit in [Unit::Byte, Unit::Word, Unit::Dword] {
            for layout in [
                TextLayout::Packed,
                TextLayout::PackedHighFirst,
                TextLayout::Words,
            ] {
                if !layout.fits(unit) {
                    continue;
                }
                let units = layout.units(unit, b"5A8DC");
                let back: Vec<u8> = (0..)
                    .map_while(|k| layout.char_at(unit, k, |i| units.get(i as usize).copied()))
                    .take_while(|c| *c != 0)
                    .collect();
                assert_eq!(back, b"5A8DC", "{layout:?} in {unit:?}");
            }
        }
        assert_eq!(TextLayout::Packed.units(Unit::Word, b"5A"), vec![0x4135, 0]);
        assert_eq!(
            TextLayout::PackedHighFirst.units(Unit::Word, b"A5"),
            vec![0x4135, 0]
        );
        assert_eq!(
            TextLayout::Packed.units(Unit::Dword, b"5A8D"),
            vec![0x4438_4135, 0]
        );
        assert!(!TextLayout::Packed.fits(Unit::Byte));
    }
    use std::path::PathBuf;

    use super::*;

    fn case(operation: Operation, text: &[u8], value: u64, digits: u32) -> CrossVendorCase {
        CrossVendorCase {
            id: "c".into(),
            operation,
            basis: Basis::Inferred,
            citation: Citation {
                manual: "m".into(),
                page: "1".into(),
                text: None,
            },
            location: Location {
                file: PathBuf::from("x.yaml"),
                line: 1,
            },
            text: text.to_vec(),
            value,
            digits,
            expect: Some(Answer::Value(value)),
            except: BTreeMap::new(),
            note: None,
            protocol: None,
        }
    }

    fn codec(shape: FieldShape) -> CodecAbilities {
        let ability = OperationAbilities {
            shape,
            ..OperationAbilities::default()
        };
        CodecAbilities {
            hex_to_value: Some(ability.clone()),
            value_to_hex: Some(ability),
            ..CodecAbilities::default()
        }
    }

    #[test]
    fn a_field_shape_reads_the_expected_answer_as_the_field_writes_it() {
        let low = OperationAbilities {
            shape: FieldShape {
                low_byte_first: true,
                ..FieldShape::default()
            },
            ..OperationAbilities::default()
        };
        let h2v = Operation::HexToValue;
        let v2h = Operation::ValueToHex;
        assert_eq!(
            low.shaped(h2v, 4, &Answer::Value(0xABCD)),
            Answer::Value(0xCDAB)
        );
        assert_eq!(
            low.shaped(h2v, 2, &Answer::Value(0x7F)),
            Answer::Value(0x7F)
        );
        assert_eq!(
            low.shaped(v2h, 4, &Answer::Text(b"ABCD".to_vec())),
            Answer::Text(b"CDAB".to_vec())
        );
        let bare = OperationAbilities {
            shape: FieldShape {
                leading_zeros: false,
                ..FieldShape::default()
            },
            ..OperationAbilities::default()
        };
        assert_eq!(
            bare.shaped(v2h, 4, &Answer::Text(b"007F".to_vec())),
            Answer::Text(b"7F".to_vec())
        );
        assert_eq!(
            bare.shaped(v2h, 4, &Answer::Text(b"0000".to_vec())),
            Answer::Text(b"0".to_vec())
        );
        let errors = Answer::Error(ErrorClass::InvalidDigit);
        assert_eq!(low.shaped(h2v, 4, &errors), errors);
    }

    #[test]
    fn a_field_shape_declines_what_it_cannot_be_asked() {
        let h2v = Operation::HexToValue;
        let frame = codec(FieldShape {
            whole_frame: true,
            widths: BTreeMap::from([(2, 8)]),
            ..FieldShape::default()
        });
        assert!(frame.declines(&case(h2v, b"7F", 0x7F, 2)).is_none());
        let trailing = frame
            .declines(&case(h2v, b"7F00", 0x7F, 2))
            .expect("declined");
        assert!(trailing.contains("whole frame"), "{trailing}");
        let count = frame
            .declines(&case(h2v, b"5A8D", 0x5A8D, 4))
            .expect("declined");
        assert!(count.contains("takes 2 digit(s), not 4"), "{count}");
        let wide = frame
            .declines(&case(Operation::ValueToHex, b"", 0x0ABC, 2))
            .expect("declined");
        assert!(wide.contains("wider than its 8 bits"), "{wide}");
        let token = codec(FieldShape {
            variable: true,
            ..FieldShape::default()
        });
        assert!(token.declines(&case(h2v, b"12", 0x12, 4)).is_some());
        assert!(token.declines(&case(h2v, b"1234", 0x1234, 4)).is_none());
        let low = codec(FieldShape {
            low_byte_first: true,
            ..FieldShape::default()
        });
        assert!(low.declines(&case(h2v, b"ABC", 0xABC, 3)).is_some());
    }
}
