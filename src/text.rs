//! Hex digits shared by the reference models (how characters sit in memory is
//! `TextLayout`'s, in `model::cross_vendor`).

/// The value of a hex digit character. Only 30H-39H and 41H-46H are digits: lowercase is
/// invalid in the manuals this project covers, except where a family's model says otherwise
/// (Omron C200H-series HEX reads 61H-66H).
pub(crate) fn digit_value(ch: u8) -> Option<u8> {
    match ch {
        b'0'..=b'9' => Some(ch - b'0'),
        b'A'..=b'F' => Some(ch - b'A' + 10),
        _ => None,
    }
}

/// The uppercase hex digit character for the low nibble of `value`.
pub(crate) fn digit_char(value: u64) -> u8 {
    b"0123456789ABCDEF"[(value & 0xF) as usize]
}

/// The hex digits a value has (at least 1).
pub(crate) fn significant_digits(v: u64) -> u32 {
    (64 - v.leading_zeros()).div_ceil(4).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_are_uppercase_hex_only() {
        let valid: Vec<u8> = (0..=255u8).filter(|b| digit_value(*b).is_some()).collect();
        assert_eq!(valid, b"0123456789ABCDEF");
        for n in 0..16 {
            assert_eq!(digit_value(digit_char(n)), Some(n as u8));
        }
    }
}
