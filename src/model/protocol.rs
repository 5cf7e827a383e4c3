//! Communication protocols whose hex fields a library's codec reads and writes, validated: the
//! book a protocol library is judged by, beside the instruction manuals of the cross-vendor
//! view.

use std::collections::BTreeMap;
use std::sync::Arc;

use super::{Basis, Citation};
pub(crate) use crate::spec::protocol::CheckAlgorithm;

/// One protocol profile (`vendors/protocols/<id>.yaml`).
#[derive(Debug, Clone)]
pub struct Protocol {
    pub id: String,
    pub name: String,
    /// Manual id -> its title and number.
    pub manuals: BTreeMap<String, String>,
    pub fields: BTreeMap<String, Field>,
    /// What a device answers to data it cannot convert.
    pub unconvertible: String,
    pub rules: BTreeMap<String, Arc<Rule>>,
}

/// A field kind of a protocol.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    pub digits: u32,
    /// The value width in bits; 8 for a check character.
    pub width: u32,
    /// The first character pair is the low byte (MEWTOCOL data words).
    pub low_byte_first: bool,
    /// A check character's algorithm; `None` for a value field.
    pub check: Option<CheckAlgorithm>,
    /// What stands for "no check" in place of the check characters.
    pub skip: Option<Vec<u8>>,
}

/// A rule of a protocol and its evidence.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rule {
    /// `<protocol>/<id>` (`modbus-ascii/B3`): how a difference and a known difference name it.
    pub key: String,
    pub statement: String,
    pub basis: Basis,
    pub citation: Citation,
}

impl std::fmt::Display for Rule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}): {}", self.key, self.citation, self.statement)
    }
}

/// Where a codec question comes from when a protocol asks it: the protocol, the field and the
/// rule it tests.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FieldRule {
    pub protocol: String,
    pub field: String,
    pub rule: Arc<Rule>,
}

/// The protocols loaded, by id.
#[derive(Debug, Clone, Default)]
pub struct Protocols {
    by_id: BTreeMap<String, Arc<Protocol>>,
}

impl Protocols {
    pub fn new(protocols: impl IntoIterator<Item = Protocol>) -> Self {
        Protocols {
            by_id: protocols
                .into_iter()
                .map(|p| (p.id.clone(), Arc::new(p)))
                .collect(),
        }
    }
    pub fn get(&self, id: &str) -> Option<&Arc<Protocol>> {
        self.by_id.get(id)
    }
    pub fn iter(&self) -> impl Iterator<Item = &Arc<Protocol>> {
        self.by_id.values()
    }
    pub fn ids(&self) -> Vec<String> {
        self.by_id.keys().cloned().collect()
    }
}

impl CheckAlgorithm {
    /// The check byte of a span; `None` for an LRC span that is not whole hex pairs.
    pub fn compute(self, span: &[u8]) -> Option<u8> {
        match self {
            CheckAlgorithm::Sum => Some(span.iter().fold(0u8, |a, b| a.wrapping_add(*b))),
            CheckAlgorithm::Xor => Some(span.iter().fold(0u8, |a, b| a ^ b)),
            CheckAlgorithm::Lrc => {
                if span.len() % 2 == 1 {
                    return None;
                }
                let mut sum = 0u8;
                for pair in span.chunks(2) {
                    let digit = |c: u8| match c {
                        b'0'..=b'9' => Some(c - b'0'),
                        b'A'..=b'F' => Some(c - b'A' + 10),
                        _ => None,
                    };
                    sum = sum.wrapping_add(digit(pair[0])? << 4 | digit(pair[1])?);
                }
                Some(sum.wrapping_neg())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::CheckAlgorithm;

    /// The manuals' worked examples: Delta's LRC of 01 03 04 01 00 01 is F6 (its sum 0AH), the
    /// FX computer link's sum of `00FFBR3ABCD` is 2BDH, so BD.
    #[test]
    fn the_check_algorithms_give_the_manuals_examples() {
        assert_eq!(CheckAlgorithm::Lrc.compute(b"010304010001"), Some(0xF6));
        assert_eq!(CheckAlgorithm::Sum.compute(b"00FFBR3ABCD"), Some(0xBD));
        assert_eq!(CheckAlgorithm::Xor.compute(b"AB"), Some(0x41 ^ 0x42));
        assert_eq!(CheckAlgorithm::Lrc.compute(b"0g"), None);
        assert_eq!(CheckAlgorithm::Lrc.compute(b"012"), None);
    }
}
