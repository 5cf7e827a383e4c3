//! Device addresses as the manuals write them: a code and a decimal number (`D100`, `SD0`,
//! `M1260`, `DT100`, `MB20`, `DB1.DBB10`, MELSEC's module buffer memory `U1\G10`), or a bit of
//! a byte (`SM1.7`, the S7-200's error bit).
//!
//! A device names one unit of its family's memory ([`crate::memory::Unit`]): a 16-bit word, or
//! a byte in a byte-addressed family. The number is the unit's address, so `(s)+1` is the next
//! word or the next byte. For a bit device used as a word operand (IDEC's "16 points", e.g. `M0`
//! as a destination) the address names the word made of the 16 points starting at that head.
//! MELSEC writes such a word with a digit designation, `K4M0`: 4 digits of 4 bits from M0. Its
//! code is `K4M`, its number the head point, and `(s)+1` is the next 16 points, `K4M16`
//! ([`Device::points`]).
//!
//! The syntax is the same for every family, a code and the number after it; which codes exist is
//! data in the vendor profile (`devices:`), where a `#` in a code stands for a block number
//! (`DB#.DBB` is every data block's bytes). The number is decimal unless the profile numbers the
//! code in hexadecimal (MELSEC `W1A`), which only a reader that knows the profile can tell:
//! [`Device::parse_numbered`].

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// One unit-sized device address.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Device {
    code: Code,
    /// The device number: as written in decimal, or the value of its hexadecimal digits for a
    /// code numbered in hexadecimal (MELSEC `W1A` is 26).
    pub index: u32,
    /// Whether the number is written in hexadecimal. Only the profile knows which codes are
    /// (`numbering: hexadecimal`), so a device read without it is decimal: see
    /// [`Device::parse_numbered`].
    hexadecimal: bool,
}

/// The longest device code: MELSEC's are up to three letters (`ZR`, `SW`, `LCN`), a Siemens data
/// block's bytes carry the block number (`DB65535.DBB`).
pub(crate) const MAX_CODE_LEN: usize = 12;

/// The device syntax as a JSON Schema pattern (vector files, the protocol):
/// [`Device::parse_numbered`] is the rule, this is the same rule for editors and other
/// languages, with any code allowed a hexadecimal number (which codes have one is the
/// profile's).
pub(crate) const PATTERN: &str =
    r"^([A-Z]([A-Z0-9.\\]*[A-Z])?([0-9]+\.[0-7]|[0-9]+)|[A-Z]([A-Z0-9.\\]*[A-Z])?[0-9A-F]+)$";

/// A device code kept inline, zero-padded. Memory images and effects are maps keyed
/// by devices, and a sweep builds millions of them: a code that is a `String` makes every
/// address copy an allocation. A code's characters are never zero, so comparing the
/// padded arrays orders codes as their text does.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Code([u8; MAX_CODE_LEN]);

/// The padded bytes compared as two big-endian numbers: the order of the bytes, in two
/// comparisons instead of a call to compare twelve bytes (images are searched by device for
/// every read).
impl Ord for Code {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        let halves = |c: &Code| {
            let [a, b, c, d, e, f, g, h, i, j, k, l] = c.0;
            (
                u64::from_be_bytes([a, b, c, d, e, f, g, h]),
                u32::from_be_bytes([i, j, k, l]),
            )
        };
        halves(self).cmp(&halves(other))
    }
}

impl PartialOrd for Code {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

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

    /// The digit count of a digit-designated code (`K4M` -> 4): `K`, one digit 1-8, then
    /// letters. Read from the bytes, as every fill and `(s)+n` asks it.
    fn digit_designation(&self) -> Option<u32> {
        let [b'K', digit @ b'1'..=b'8', first, rest @ ..] = self.0 else {
            return None;
        };
        let letters = first.is_ascii_uppercase()
            && rest
                .iter()
                .take_while(|b| **b != 0)
                .all(u8::is_ascii_uppercase);
        letters.then_some(u32::from(digit - b'0'))
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
    /// one that does not is kept cut to `MAX_CODE_LEN` letters rather than lost.
    pub fn new(code: &str, index: u32) -> Self {
        let code = Code::new(code).unwrap_or_else(|| {
            debug_assert!(false, "device code `{code}` longer than {MAX_CODE_LEN}");
            Code::new(code.get(..MAX_CODE_LEN).unwrap_or_default())
                .unwrap_or(Code([0; MAX_CODE_LEN]))
        });
        Device {
            code,
            index,
            hexadecimal: false,
        }
    }

    /// A device whose code is numbered in hexadecimal (MELSEC W, SW): it prints its number in
    /// hexadecimal, `W1A` for 26.
    pub fn hexadecimal(code: &str, index: u32) -> Self {
        Device {
            hexadecimal: true,
            ..Device::new(code, index)
        }
    }

    /// Whether the number is written in hexadecimal.
    pub fn is_hexadecimal(&self) -> bool {
        self.hexadecimal
    }

    /// Whether this is the word `code` `index`, however either is written: a frame names a
    /// device by its letters and number, without the numbering it prints in.
    pub fn is(&self, code: &str, index: u32) -> bool {
        self.code() == code && self.index == index
    }

    /// The device of the same code, numbered the same way, with another number.
    pub fn with_index(&self, index: u32) -> Device {
        Device {
            index,
            ..self.clone()
        }
    }

    /// Reads a device name whose code may be numbered in hexadecimal, as `hexadecimal` says of
    /// a code: `W1A` is W 26 when W is, and `W10` W 16. The longest such code wins (`SW10` is
    /// SW 16, not S `W10`); a name with no such code reads as [`Device::from_str`] does.
    pub fn parse_numbered(
        text: &str,
        hexadecimal: impl Fn(&str) -> bool,
    ) -> Result<Device, DeviceSyntaxError> {
        for split in (1..text.len()).rev() {
            let Some((code, digits)) = text.split_at_checked(split) else {
                continue;
            };
            let is_hex_number = digits
                .bytes()
                .all(|b| b.is_ascii_digit() || (b'A'..=b'F').contains(&b));
            // A bit address's byte (`SM1.`) is never numbered in hexadecimal.
            if is_hex_number && !code.ends_with('.') && valid_code(code) && hexadecimal(code) {
                return u32::from_str_radix(digits, 16)
                    .map(|index| Device::hexadecimal(code, index))
                    .map_err(|_| DeviceSyntaxError(text.to_string()));
            }
        }
        text.parse()
    }

    /// The device code, uppercase (`D`, `SD`, `M`, `DB1.DBB`).
    pub fn code(&self) -> &str {
        self.code.as_str()
    }

    /// The device `offset` units after this one, e.g. `(s)+1`. `None` when the number would
    /// overflow, which callers treat like any other address past the end of the device range.
    pub fn offset(&self, offset: u32) -> Option<Device> {
        offset
            .checked_mul(self.points())
            .and_then(|points| self.index.checked_add(points))
            .map(|index| self.with_index(index))
    }

    /// How many device numbers one unit spans: 1, except for a MELSEC digit designation
    /// (`K` and a digit count, then a bit device: `K4M`), whose unit is 4 points per digit, so
    /// that `(s)+1` of `K4M0` is `K4M16` as on the CPU. Which designations exist is the
    /// profile's (`devices:`); the syntax alone says how far apart their units are.
    pub fn points(&self) -> u32 {
        self.code.digit_designation().map_or(1, |digits| 4 * digits)
    }

    /// The position of this unit in its code's sequence of units: the number for plain
    /// devices, the number divided by [`Device::points`] for a digit designation. The fill
    /// pattern varies with it, so that consecutive units differ.
    pub fn unit_number(&self) -> u32 {
        self.index / self.points()
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.hexadecimal {
            true => write!(f, "{}{:X}", self.code(), self.index),
            false => write!(f, "{}{}", self.code(), self.index),
        }
    }
}

/// Why a device name could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceSyntaxError(pub String);

impl fmt::Display for DeviceSyntaxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}` is not a device name; expected a code of uppercase letters followed by a decimal number, like `D100`, `MB20` or `DB1.DBB10` (a hexadecimal one, like `W1A`, only for a code the profile numbers in hexadecimal)",
            self.0
        )
    }
}

impl std::error::Error for DeviceSyntaxError {}

impl FromStr for Device {
    type Err = DeviceSyntaxError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || DeviceSyntaxError(s.to_string());
        let (code, number) = s.split_at(s.trim_end_matches(|c: char| c.is_ascii_digit()).len());
        if number.is_empty() || !valid_code(code) {
            return Err(err());
        }
        let index = number.parse::<u32>().map_err(|_| err())?;
        // A bit address (`SM1.7`) is the code `SM1.` and the bit number, which is 0-7.
        if code.ends_with('.') && index > 7 {
            return Err(err());
        }
        Ok(Device::new(code, index))
    }
}

/// A code: uppercase letters, optionally with block numbers between dots (`DB1.DBB`) or a
/// module number before a backslash (`U1\G`), starting and ending with a letter; or such a
/// code with a byte number and a dot, the head of a bit address (`SM1.` of `SM1.7`).
fn valid_code(code: &str) -> bool {
    if let Some(byte) = code.strip_suffix('.') {
        let letters = byte.trim_end_matches(|c: char| c.is_ascii_digit());
        return letters.len() < byte.len() && valid_code(letters);
    }
    let bytes = code.as_bytes();
    !code.is_empty()
        && code.len() <= MAX_CODE_LEN
        && bytes[0].is_ascii_uppercase()
        && bytes[bytes.len() - 1].is_ascii_uppercase()
        && bytes
            .iter()
            .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || matches!(b, b'.' | b'\\'))
        && !code.contains("..")
        && !code.contains("\\\\")
}

/// Whether a profile's device code names `code`: equal, or a pattern in which each `#` stands
/// for a decimal block number (`DB#.DBB` names `DB1.DBB` and `DB100.DBB`).
pub(crate) fn code_matches(pattern: &str, code: &str) -> bool {
    let Some((head, rest)) = pattern.split_once('#') else {
        return pattern == code;
    };
    let Some(after) = code.strip_prefix(head) else {
        return false;
    };
    let digits = after.len() - after.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    digits > 0 && code_matches(rest, &after[digits..])
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
    #[case("DT100", "DT", 100)]
    #[case("MB20", "MB", 20)]
    #[case("DB1.DBB10", "DB1.DBB", 10)]
    #[case("SM1.7", "SM1.", 7)]
    #[case("V10.0", "V10.", 0)]
    #[case("U1\\G10", "U1\\G", 10)]
    #[case("K4M16", "K4M", 16)]
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
    #[case("ABCDEFGHIJKLM1")]
    #[case("")]
    #[case("DB1.10")]
    #[case("DB1..DBB10")]
    #[case(".DBB10")]
    #[case("1D10")]
    #[case("Db1.DBB10")]
    #[case("D1ê00")]
    #[case("SM1.8")]
    #[case("SM.7")]
    #[case("SM1..7")]
    #[case("U1\\\\G10")]
    #[case("U1\\10")]
    #[case("\\G10")]
    fn rejects(#[case] text: &str) {
        assert!(text.parse::<Device>().is_err());
    }

    /// The schema pattern and the parser accept the same names.
    #[rstest]
    #[case("D100")]
    #[case("DB1.DBB10")]
    #[case("SM1.7")]
    #[case("SM1.8")]
    #[case("DB1.10")]
    #[case("d100")]
    #[case("D")]
    #[case("U1\\G10")]
    #[case("U1\\10")]
    #[case("W1A")]
    #[case("SW0F")]
    #[case("W1G")]
    #[case("W")]
    fn the_pattern_is_the_parser(#[case] text: &str) {
        let schema = serde_json::json!({"type": "string", "pattern": PATTERN});
        let pattern = jsonschema::validator_for(&schema).expect("the pattern compiles");
        assert_eq!(
            pattern.is_valid(&serde_json::json!(text)),
            Device::parse_numbered(text, |_| true).is_ok(),
            "{text}"
        );
    }

    #[rstest]
    #[case("W1A", "W1A", 26)]
    #[case("W10", "W10", 16)]
    #[case("WA", "WA", 10)]
    #[case("SW10", "SW10", 16)]
    #[case("W0", "W0", 0)]
    #[case("D10", "D10", 10)]
    #[case("DB1.DBB10", "DB1.DBB10", 10)]
    fn hexadecimal_numbers_read_and_print_as_written(
        #[case] text: &str,
        #[case] printed: &str,
        #[case] index: u32,
    ) {
        let hex = |code: &str| code == "W" || code == "SW";
        let device = Device::parse_numbered(text, hex).expect("a device");
        assert_eq!(device.index, index);
        assert_eq!(device.to_string(), printed);
        assert_eq!(device.is_hexadecimal(), hex(device.code()));
        assert!(Device::parse_numbered("W1G", hex).is_err());
        assert!(Device::parse_numbered("D1A", hex).is_err());
        let nine = Device::parse_numbered("W9", hex).expect("W9");
        assert_eq!(nine.offset(1).map(|d| d.to_string()).as_deref(), Some("WA"));
        assert_eq!(
            nine.offset(7).map(|d| d.to_string()).as_deref(),
            Some("W10")
        );
    }

    #[rstest]
    #[case("D", "D", true)]
    #[case("D", "DT", false)]
    #[case("DB#.DBB", "DB1.DBB", true)]
    #[case("DB#.DBB", "DB100.DBB", true)]
    #[case("DB#.DBB", "DB.DBB", false)]
    #[case("DB#.DBB", "DB1.DBW", false)]
    #[case("DB#.DBB", "DB1X.DBB", false)]
    #[case("U#\\G", "U1\\G", true)]
    #[case("U#\\G", "U\\G", false)]
    fn patterns(#[case] pattern: &str, #[case] code: &str, #[case] matches: bool) {
        assert_eq!(code_matches(pattern, code), matches);
    }

    #[rstest]
    #[case("D100", 1, "D101", 100)]
    #[case("K4M0", 16, "K4M16", 0)]
    #[case("K4M100", 16, "K4M116", 6)]
    #[case("K2M0", 8, "K2M8", 0)]
    #[case("K8M0", 32, "K8M32", 0)]
    #[case("KM0", 1, "KM1", 0)]
    #[case("K9M0", 1, "K9M1", 0)]
    #[case("K4DB1.DBB0", 1, "K4DB1.DBB1", 0)]
    fn a_digit_designation_steps_by_its_points(
        #[case] head: &str,
        #[case] points: u32,
        #[case] next: &str,
        #[case] unit: u32,
    ) {
        let head: Device = head.parse().expect("a device");
        assert_eq!(head.points(), points);
        assert_eq!(head.offset(1).map(|d| d.to_string()).as_deref(), Some(next));
        assert_eq!(head.unit_number(), unit);
        assert_eq!(Device::new("K4M", u32::MAX - 3).offset(1), None);
    }
}
