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
    /// The device letter code, uppercase (`D`, `SD`, `M`, `T`).
    pub code: String,
    /// The device number as written, read in decimal.
    pub index: u32,
}

impl Device {
    pub fn new(code: impl Into<String>, index: u32) -> Self {
        Device {
            code: code.into(),
            index,
        }
    }

    /// The device `offset` words after this one, e.g. `(s)+1`. `None` when the number would
    /// overflow, which callers treat like any other address past the end of the device range.
    pub fn offset(&self, offset: u32) -> Option<Device> {
        self.index.checked_add(offset).map(|index| Device {
            code: self.code.clone(),
            index,
        })
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.code, self.index)
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
    #[case("")]
    fn rejects(#[case] text: &str) {
        assert!(text.parse::<Device>().is_err());
    }
}
