//! Numbers as the manuals write them.
//!
//! Corpus authors copy values straight from manual pages, so every notation the pages use must
//! read back to the same number: suffix hex (`4135H`, `0ABCH`), MELSEC constants (`K100`,
//! `K-1`, `H0ABC`), C-style hex (`0x4135`) and plain integers.

use std::fmt;

/// Why a value could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ValueError {
    Syntax(String),
    TooWide { text: String, bits: u32 },
}

impl fmt::Display for ValueError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ValueError::Syntax(text) => write!(
                f,
                "`{text}` is not a value; expected hex like `4135H` or `H0ABC`, decimal like `K100` or `100`"
            ),
            ValueError::TooWide { text, bits } => {
                let bits = (*bits).clamp(1, 64);
                write!(
                    f,
                    "`{text}` is too wide for {bits} bits (expected {} to {})",
                    -(1i128 << (bits - 1)),
                    (1i128 << bits) - 1
                )
            }
        }
    }
}

impl std::error::Error for ValueError {}

/// Reads a number in any of the accepted notations, without a width check (a number past 64
/// bits is too wide for any).
pub(crate) fn parse_number(text: &str) -> Result<i64, ValueError> {
    parse_wide(text).and_then(|n| {
        i64::try_from(n).map_err(|_| ValueError::TooWide {
            text: text.to_string(),
            bits: 64,
        })
    })
}

/// Reads a non-negative number of up to 64 bits (a 64-bit value such as `0EFCDAB8967452301H`,
/// past the signed range [`parse_number`] keeps to).
pub(crate) fn parse_unsigned(text: &str) -> Result<u64, ValueError> {
    parse_wide(text).and_then(|n| {
        u64::try_from(n).map_err(|_| ValueError::TooWide {
            text: text.to_string(),
            bits: 64,
        })
    })
}

/// Any accepted notation, read into a number wide enough for every 64-bit value, signed or not.
fn parse_wide(text: &str) -> Result<i128, ValueError> {
    let syntax = || ValueError::Syntax(text.to_string());
    let too_wide = || ValueError::TooWide {
        text: text.to_string(),
        bits: 64,
    };
    let t = text.trim();
    let hex = |digits: &str| {
        if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
            return Err(syntax());
        }
        u64::from_str_radix(digits, 16)
            .map(i128::from)
            .map_err(|_| too_wide())
    };
    let dec = |digits: &str| {
        let unsigned = digits.strip_prefix('-').unwrap_or(digits);
        if unsigned.is_empty() || !unsigned.chars().all(|c| c.is_ascii_digit()) {
            return Err(syntax());
        }
        digits
            .parse::<i64>()
            .map(i128::from)
            .or_else(|_| digits.parse::<u64>().map(i128::from))
            .map_err(|_| too_wide())
    };
    if let Some(rest) = t.strip_prefix('K') {
        dec(rest)
    } else if let Some(rest) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        hex(rest)
    } else if let Some(rest) = t.strip_suffix('H').or_else(|| t.strip_suffix('h')) {
        // Suffix form first: `0ABCH` is the manuals' usual spelling. A leading `H` with a
        // trailing `H` (`H10H`) is not a notation anyone writes.
        if rest.starts_with('H') {
            return Err(syntax());
        }
        hex(rest)
    } else if let Some(rest) = t.strip_prefix('H') {
        hex(rest)
    } else {
        dec(t)
    }
}

/// Narrows a number to a word. Negative numbers down to the signed minimum are stored as two's
/// complement, as a PLC stores `K-1`.
pub(crate) fn to_bits(text: &str, value: i64, bits: u32) -> Result<u64, ValueError> {
    narrow(value, bits).ok_or_else(|| ValueError::TooWide {
        text: text.to_string(),
        bits,
    })
}

/// [`to_bits`] without the text for its error, for a caller that asks it on every execution.
pub(crate) fn narrow(value: i64, bits: u32) -> Option<u64> {
    let min = -(1i64 << (bits - 1));
    let max = (1i64 << bits) - 1;
    let mask = (1u64 << bits) - 1;
    (min..=max)
        .contains(&value)
        .then_some((value as u64) & mask)
}

/// Reads a 16-bit word.
pub(crate) fn parse_word(text: &str) -> Result<u16, ValueError> {
    parse_bits(text, 16).map(|w| w as u16)
}

/// Reads a number that must fit `bits` bits (at most 32: a memory unit).
pub(crate) fn parse_bits(text: &str, bits: u32) -> Result<u32, ValueError> {
    let value = parse_number(text).map_err(|e| match e {
        ValueError::TooWide { text, .. } => ValueError::TooWide { text, bits },
        e => e,
    })?;
    Ok(to_bits(text, value, bits)? as u32)
}

/// Formats a word the way the manuals do: four hex digits and an `H` suffix.
pub(crate) fn hex_word(word: impl Into<u32>) -> String {
    let word = word.into();
    format!("{word:04X}H")
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[test]
    fn sixty_four_bit_values_read_past_the_signed_range() {
        assert_eq!(
            parse_unsigned("0EFCDAB8967452301H"),
            Ok(0xEFCD_AB89_6745_2301)
        );
        assert_eq!(parse_unsigned("18446744073709551615"), Ok(u64::MAX));
        assert!(parse_unsigned("-1").is_err());
        assert!(parse_unsigned("10000000000000000H").is_err());
        assert!(parse_number("0EFCDAB8967452301H").is_err());
    }

    #[rstest]
    #[case("4135H", 0x4135)]
    #[case("0ABCH", 0x0ABC)]
    #[case("H0ABC", 0x0ABC)]
    #[case("K100", 100)]
    #[case("K-1", 0xFFFF)]
    #[case("K-32768", 0x8000)]
    #[case("0x10", 0x10)]
    #[case("65535", 0xFFFF)]
    #[case("0", 0)]
    fn reads_words(#[case] text: &str, #[case] word: u16) {
        assert_eq!(parse_word(text), Ok(word));
    }

    #[rstest]
    #[case("10000H")]
    #[case("K65536")]
    #[case("K-32769")]
    #[case("70000")]
    #[case("99999999999999999999H")]
    #[case("K-99999999999999999999")]
    fn rejects_wide(#[case] text: &str) {
        let e = parse_word(text).expect_err("too wide");
        assert!(matches!(e, ValueError::TooWide { bits: 16, .. }), "{e:?}");
        assert!(e.to_string().contains("is too wide for 16 bits"), "{e}");
    }

    #[test]
    fn every_width_has_a_message() {
        for bits in [1, 16, 32, 63, 64] {
            let e = ValueError::TooWide {
                text: "x".into(),
                bits,
            };
            assert!(e.to_string().contains(&format!("{bits} bits")));
        }
    }

    #[rstest]
    #[case("")]
    #[case("H")]
    #[case("GH")]
    #[case("K1A")]
    #[case("D100")]
    #[case("H10H")]
    #[case("4135 H")]
    fn rejects_syntax(#[case] text: &str) {
        assert!(matches!(parse_word(text), Err(ValueError::Syntax(_))));
    }
}
