//! Device addresses as the manuals write them: a device letter code and a number (`D100`, `SD0`,
//! `M1260`).
//!
//! A device here always names one 16-bit word. For a bit device used as a word operand (IDEC's
//! "16 points", e.g. `M0` as a destination) the address names the word made of the 16 points
//! starting at that head; the vendor profile says which device codes exist and their ranges.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// One word-sized device address.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Device {
    code: Code,
    /// The device number as written, read in decimal.
    pub index: u32,
}

/// The longest device code: the manuals' longest is three letters (`ZR`, `SW`, `LCN`).
pub const MAX_CODE_LEN: usize = 8;

/// A device letter code kept inline, zero-padded. Memory images and effects are maps keyed
/// by devices, and a sweep builds millions of them: a code that is a `String` makes every
/// address copy an allocation. Uppercase letters are never zero, so comparing the padded
/// arrays orders codes as their text does.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
struct Code([u8; MAX_CODE_LEN]);

impl Code {
    /// `None` for a code longer than [`MAX_CODE_LEN`] or holding a zero byte.
    fn new(code: &str) -> Option<Code> {
        let bytes = code.as_bytes();
        if bytes.len() > MAX_CODE_LEN || bytes.contains(&0) {
            return None;
        }
        let mut padded = [0; MAX_CODE_LEN];
        padded[..bytes.len()].copy_from_slice(bytes);
        Some(Code(padded))
    }

    fn as_str(&self) -> &str {
        let len = self.0.iter().position(|b| *b == 0).unwrap_or(MAX_CODE_LEN);
        // Built from a `&str` cut at its end, so always whole UTF-8.
        std::str::from_utf8(&self.0[..len]).unwrap_or_default()
    }
}

impl fmt::Debug for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl Device {
    /// A device from a code the profiles define. Profile and vector loading reject longer
    /// codes ([`Device::from_str`], the profile checks), so the only codes that reach here fit;
    /// one that does not is kept cut to [`MAX_CODE_LEN`] letters rather than lost.
    pub fn new(code: &str, index: u32) -> Self {
        let code = Code::new(code).unwrap_or_else(|| {
            debug_assert!(false, "device code `{code}` longer than {MAX_CODE_LEN}");
            Code::new(code.get(..MAX_CODE_LEN).unwrap_or_default()).unwrap_or(Code([0; 8]))
        });
        Device { code, index }
    }

    /// The device letter code, uppercase (`D`, `SD`, `M`, `T`).
    pub fn code(&self) -> &str {
        self.code.as_str()
    }

    /// The device `offset` words after this one, e.g. `(s)+1`. `None` when the number would
    /// overflow, which callers treat like any other address past the end of the device range.
    pub fn offset(&self, offset: u32) -> Option<Device> {
        self.index.checked_add(offset).map(|index| Device {
            code: self.code,
            index,
        })
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.code(), self.index)
    }
}

/// Why a device name could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceSyntaxError(pub String);

impl fmt::Display for DeviceSyntaxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}` is not a device name; expected uppercase letters followed by a decimal number, like `D100`",
            self.0
        )
    }
}

impl std::error::Error for DeviceSyntaxError {}

impl FromStr for Device {
    type Err = DeviceSyntaxError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || DeviceSyntaxError(s.to_string());
        let split = s.find(|c: char| c.is_ascii_digit()).ok_or_else(err)?;
        let (code, number) = s.split_at(split);
        if code.is_empty()
            || code.len() > MAX_CODE_LEN
            || !code.chars().all(|c| c.is_ascii_uppercase())
            || !number.chars().all(|c| c.is_ascii_digit())
        {
            return Err(err());
        }
        let index = number.parse::<u32>().map_err(|_| err())?;
        Ok(Device::new(code, index))
    }
}

impl Serialize for Device {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Device {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = String::deserialize(deserializer)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("D100", "D", 100)]
    #[case("SD0", "SD", 0)]
    #[case("M1277", "M", 1277)]
    fn parses(#[case] text: &str, #[case] code: &str, #[case] index: u32) {
        assert_eq!(text.parse::<Device>(), Ok(Device::new(code, index)));
    }

    #[rstest]
    #[case("d100")]
    #[case("D")]
    #[case("100")]
    #[case("D10A")]
    #[case("D-1")]
    #[case("D99999999999")]
    #[case("ABCDEFGHI1")]
    #[case("")]
    fn rejects(#[case] text: &str) {
        assert!(text.parse::<Device>().is_err());
    }
}
