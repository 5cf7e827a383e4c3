//! One generated input of a sweep, and what it looks like to the grouping and the shrinker.
//!
//! A [`Point`] is a text (hex-to-value, or an instruction that reads characters) or a value
//! (value-to-hex), with the digit count given to the instructions that take one, and — for an
//! instruction sweep — the flag settings and where the operands sit. How a point becomes memory
//! and operands is the column's business (`super::target`).

use std::collections::BTreeMap;
use std::fmt::{self, Write as _};

use serde::Serialize;

use crate::device::Device;
use crate::model::cross_vendor::Answer;

/// The data of an input.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Data {
    /// Characters, as the bytes a PLC stores.
    Text(#[serde(serialize_with = "text_as_string")] Vec<u8>),
    /// A binary value.
    Value(u64),
}

fn text_as_string<S: serde::Serializer>(t: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&Answer::Text(t.to_vec()).to_string())
}

/// One input of a sweep.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize)]
pub struct Point {
    pub data: Data,
    /// The digit count given to instructions that take one (FX5 n, IDEC S2).
    pub digits: u32,
    /// Instruction sweeps: the flags set (every flag the instruction reads).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub flags: BTreeMap<String, bool>,
    /// Instruction sweeps: the source operand, when not the default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<Device>,
    /// Instruction sweeps: the destination operand, when not the default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub destination: Option<Device>,
    /// Whether the target takes the digit count (shown only then).
    #[serde(skip)]
    pub counted: bool,
}

impl Point {
    pub fn text(text: &[u8], digits: u32) -> Self {
        Point {
            data: Data::Text(text.to_vec()),
            digits,
            flags: BTreeMap::new(),
            source: None,
            destination: None,
            counted: true,
        }
    }

    pub fn value(value: u64, digits: u32) -> Self {
        Point {
            data: Data::Value(value),
            digits,
            flags: BTreeMap::new(),
            source: None,
            destination: None,
            counted: true,
        }
    }

    /// The shrinker's order: a smaller key is a simpler input. Shortest text, then fewest
    /// characters other than '0', then the lowest bytes; for a value, the fewest set bits, then
    /// the lowest value; then the smallest count, the fewest flags on, operands where they
    /// usually are.
    pub fn simplicity(&self) -> (u64, u64, Vec<u8>, u32, usize, usize) {
        let (a, b, c) = match &self.data {
            Data::Text(t) => (
                t.len() as u64,
                t.iter().filter(|&&b| b != b'0').count() as u64,
                t.clone(),
            ),
            Data::Value(v) => (u64::from(v.count_ones()), *v, Vec::new()),
        };
        (
            a,
            b,
            c,
            self.digits,
            self.flags.values().filter(|on| **on).count(),
            usize::from(self.source.is_some()) + usize::from(self.destination.is_some()),
        )
    }

    /// The features the grouping keys on besides the answers: the kind of the first character
    /// that is not a hex digit, and how the count compares with the data. Flags and operand
    /// places are not features: where they matter, the answers differ.
    pub fn features(&self, counted: bool) -> Vec<String> {
        let mut out = Vec::new();
        match &self.data {
            Data::Text(t) => {
                let first = t.iter().find(|b| kind(**b) != Kind::Digit);
                out.push(match first {
                    Some(b) => format!("first non-digit: {}", kind(*b)),
                    None => "hex digits only".to_string(),
                });
                if counted {
                    out.push(count_relation(self.digits, t.len() as u32, "text"));
                }
            }
            Data::Value(v) => {
                if counted {
                    out.push(count_relation(self.digits, significant_digits(*v), "value"));
                }
                if *v == 0 {
                    out.push("value 0".into());
                }
            }
        }
        out
    }

    /// The finer class within a group: the shape of the text (kinds in order, runs of digits
    /// and of one kind collapsed), or the size of the value with the count.
    pub fn class(&self, counted: bool) -> String {
        let mut s = match &self.data {
            Data::Text(t) => {
                let mut s = String::new();
                let mut last = None;
                for k in t.iter().map(|b| kind(*b)) {
                    if last == Some(k) {
                        continue;
                    }
                    if last.is_some() {
                        s.push(' ');
                    }
                    last = Some(k);
                    if k == Kind::Digit {
                        s.push('D');
                    } else {
                        let _ = write!(s, "{k}");
                    }
                }
                if s.is_empty() {
                    "empty".to_string()
                } else {
                    s
                }
            }
            Data::Value(v) => format!("{} digit(s)", significant_digits(*v)),
        };
        if counted && matches!(self.data, Data::Value(_)) {
            s.push_str(&format!(", count {}", self.digits));
        }
        if let Some(d) = &self.source {
            s.push_str(&format!(", source {d}"));
        }
        if let Some(d) = &self.destination {
            s.push_str(&format!(", destination {d}"));
        }
        s
    }
}

impl fmt::Display for Point {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.data {
            Data::Text(t) => write!(f, "{}", Answer::Text(t.clone()))?,
            Data::Value(v) => write!(f, "{}", Answer::Value(*v))?,
        }
        if self.counted {
            write!(f, " digits {}", self.digits)?;
        }
        for (flag, on) in &self.flags {
            write!(f, " {flag}={}", if *on { "on" } else { "off" })?;
        }
        if let Some(d) = &self.source {
            write!(f, " source {d}")?;
        }
        if let Some(d) = &self.destination {
            write!(f, " destination {d}")?;
        }
        Ok(())
    }
}

pub(crate) use crate::text::significant_digits;

fn count_relation(count: u32, size: u32, what: &str) -> String {
    match count.cmp(&size) {
        _ if count == 0 => "count 0".to_string(),
        std::cmp::Ordering::Less => format!("count below the {what}"),
        std::cmp::Ordering::Equal => format!("count = the {what}"),
        std::cmp::Ordering::Greater => format!("count above the {what}"),
    }
}

/// How number parsers commonly see a byte: the taxonomy the grouping uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Kind {
    /// 30H-39H, 41H-46H.
    Digit,
    Nul,
    Control,
    /// 09H-0DH, 20H.
    Space,
    Plus,
    Minus,
    Punct,
    /// 61H-66H.
    LowerHex,
    UpperLetter,
    LowerLetter,
    /// 80H-FFH.
    High,
}

pub(crate) fn kind(b: u8) -> Kind {
    match b {
        b'0'..=b'9' | b'A'..=b'F' => Kind::Digit,
        0 => Kind::Nul,
        0x09..=0x0D | b' ' => Kind::Space,
        0x01..=0x1F | 0x7F => Kind::Control,
        b'+' => Kind::Plus,
        b'-' => Kind::Minus,
        b'a'..=b'f' => Kind::LowerHex,
        b'G'..=b'Z' => Kind::UpperLetter,
        b'g'..=b'z' => Kind::LowerLetter,
        0x80..=0xFF => Kind::High,
        _ => Kind::Punct,
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Kind::Digit => "digit",
            Kind::Nul => "00H",
            Kind::Control => "control",
            Kind::Space => "blank",
            Kind::Plus => "'+'",
            Kind::Minus => "'-'",
            Kind::Punct => "punctuation",
            Kind::LowerHex => "lowercase a-f",
            Kind::UpperLetter => "letter G-Z",
            Kind::LowerLetter => "letter g-z",
            Kind::High => "80H-FFH",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_and_features() {
        let p = Point::text(b" 5A8", 4);
        assert_eq!(p.class(true), "blank D");
        assert_eq!(
            p.features(true),
            vec!["first non-digit: blank", "count = the text"]
        );
        assert_eq!(Point::text(b"5a8D", 4).class(false), "D lowercase a-f D");
        assert_eq!(
            Point::text(b"12", 0).features(true),
            vec!["hex digits only", "count 0"]
        );
        assert_eq!(significant_digits(0), 1);
        assert_eq!(significant_digits(0xABC), 3);
        assert_eq!(significant_digits(0x1_0000), 5);
    }

    #[test]
    fn simpler_inputs_order_first() {
        assert!(Point::text(b"000a", 4).simplicity() < Point::text(b"5a8D", 4).simplicity());
        assert!(Point::text(b"7", 1).simplicity() < Point::text(b"00", 1).simplicity());
        assert!(Point::value(0x100, 4).simplicity() < Point::value(0x3, 4).simplicity());
    }
}
