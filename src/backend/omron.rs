//! Reference model of Omron HEX (ASCII to hex: HEX(162) on CS/CJ/CP, HEX(--) on the C200H
//! series, CQM1H and CPM1) and ASC (hex to ASCII: ASC(086), ASC(86)).
//!
//! Rules and their evidence are in `docs/semantics.md#omron-hex`, `docs/semantics.md#omron-asc`
//! and `docs/semantics.md#omron-errors`. Both instructions are driven by a digit designator Di,
//! four hex digits: digit 0 the first digit (of D for HEX, of S for ASC), digit 1 the count
//! minus one, digit 2 the first byte (of S for HEX, of D for ASC; 0 the rightmost), digit 3 the
//! parity (0 none, 1 even, 2 odd).
//!
//! - Bytes are taken (HEX) or placed (ASC) from the first byte on: the rightmost byte of a word,
//!   then its leftmost byte, then the rightmost byte of the next word.
//! - Digits are written (HEX) or read (ASC) from the first digit leftwards, towards digit 3,
//!   and wrap round to digit 0; digits and bytes the instruction does not reach keep their
//!   contents.
//! - The first character is therefore the *least* significant digit converted: "12" into digits
//!   0-1 of D gives xx21H, the reverse of the MELSEC and IDEC instructions.
//! - The leftmost bit of each byte is its parity bit: HEX checks it against Di digit 3 (with no
//!   parity it must be 0), ASC sets it.
//! - Every error turns on the ER flag and the instruction writes nothing: a Di digit out of
//!   range, a byte whose parity bit disagrees with Di, a character that is not a hex digit,
//!   words past the end of the data area.
//!
//! What varies between the CPU models is data in `vendors/omron-cs-cj.yaml`: the data area
//! ranges, and the variant feature `lowercase-hex` (the C200H series takes 61H-66H as digits).

use super::reference::{Model, Run, Stop};
use super::{Outcome, Request, Unsupported};
use crate::device::Device;
use crate::memory::Scratch;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "omron-cs-cj";

/// The variant feature that makes HEX take 61H-66H ('a'-'f') as digits.
pub(crate) const LOWERCASE_HEX: &str = "lowercase-hex";

/// What the model passes as the error code. Omron shows an instruction error as the ER flag
/// only and the profile signals with the flag, so this value never reaches a comparison.
const NO_CODE: u16 = 0;

/// The most characters (HEX) or digits (ASC) one execution converts: one word's digits.
const DIGITS: u32 = 4;

/// The Omron reference model.
pub(crate) struct Omron;

impl Model for Omron {
    const PROFILE: &'static str = PROFILE;

    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[("HEX", hex), ("ASC", asc)];
}

/// The parity Di digit 3 designates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Parity {
    None,
    Even,
    Odd,
}

impl Parity {
    /// Whether a byte as read (HEX) has the designated parity: with none, its leftmost bit is
    /// 0; with even or odd, the count of ON bits in the byte is even or odd.
    pub(crate) fn accepts(self, byte: u8) -> bool {
        match self {
            Parity::None => byte & 0x80 == 0,
            Parity::Even => byte.count_ones() % 2 == 0,
            Parity::Odd => byte.count_ones() % 2 == 1,
        }
    }

    /// A 7-bit character with its leftmost bit set so that the byte has the designated parity
    /// (ASC); 0 with none.
    pub(crate) fn apply(self, ch: u8) -> u8 {
        let ch = ch & 0x7F;
        let odd = ch.count_ones() % 2 == 1;
        match self {
            Parity::Even if odd => ch | 0x80,
            Parity::Odd if !odd => ch | 0x80,
            Parity::None | Parity::Even | Parity::Odd => ch,
        }
    }
}

/// A digit designator, decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Designator {
    /// Digit 0: the first digit of D (HEX) or of S (ASC), 0-3.
    pub first_digit: u32,
    /// Digit 1 plus one: how many characters (HEX) or digits (ASC), 1-4.
    pub count: u32,
    /// Digit 2: the first byte of S (HEX) or of D (ASC), 0 the rightmost, 1 the leftmost.
    pub first_byte: u32,
    /// Digit 3.
    pub parity: Parity,
}

impl Designator {
    /// Reads Di; `None` when a digit is outside its range ("Di must be within the values given
    /// below"), which is an instruction error.
    pub(crate) fn decode(di: u16) -> Option<Self> {
        let digit = |k: u32| u32::from((di >> (4 * k)) & 0xF);
        let parity = match digit(3) {
            0 => Parity::None,
            1 => Parity::Even,
            2 => Parity::Odd,
            _ => return None,
        };
        (digit(0) < DIGITS && digit(1) < DIGITS && digit(2) <= 1).then_some(Designator {
            first_digit: digit(0),
            count: digit(1) + 1,
            first_byte: digit(2),
            parity,
        })
    }

    /// The words the bytes occupy from the head (S for HEX, D for ASC): the first byte's
    /// position plus the count, two bytes per word. Four bytes from a leftmost first byte take
    /// three words.
    pub(crate) fn byte_words(&self) -> u32 {
        (self.first_byte + self.count).div_ceil(2)
    }

    /// Where the `k`-th byte lives: the word offset from the head, and whether it is the
    /// leftmost byte of that word.
    pub(crate) fn byte_at(&self, k: u32) -> (u32, bool) {
        let position = self.first_byte + k;
        (position / 2, position % 2 == 1)
    }

    /// The digit the `k`-th character goes to (HEX) or comes from (ASC): from the first digit
    /// leftwards, round to digit 0 after digit 3.
    pub(crate) fn digit_at(&self, k: u32) -> u32 {
        (self.first_digit + k) % DIGITS
    }
}

/// The digit designator: a constant or a word.
fn designator(req: &Request<'_>) -> Result<Designator, Stop> {
    let di = match req.operand("Di")? {
        Operand::Constant(k) => u16::try_from(*k).map_err(|_| {
            Stop::Unsupported(Unsupported(format!(
                "operand `Di` {k} is not a 16-bit constant"
            )))
        })?,
        Operand::Device(d) if req.words_exist(d, 1) => req.memory.word(d),
        Operand::Device(_) => return Err(Stop::Error(NO_CODE)),
    };
    Designator::decode(di).ok_or(Stop::Error(NO_CODE))
}

/// A byte of a word: the leftmost (high) or the rightmost (low).
fn byte_of(word: u16, leftmost: bool) -> u8 {
    if leftmost {
        (word >> 8) as u8
    } else {
        word as u8
    }
}

/// The value of a byte as HEX reads it, after the parity check; `None` is an error.
fn hex_digit(byte: u8, parity: Parity, lowercase: bool) -> Option<u8> {
    if !parity.accepts(byte) {
        return None;
    }
    let ch = byte & 0x7F;
    match ch {
        b'a'..=b'f' if lowercase => Some(ch - b'a' + 10),
        _ => digit_value(ch),
    }
}

/// The word `offset` words after `head`.
fn word_after(head: &Device, offset: u32) -> Result<Device, Stop> {
    head.offset(offset).ok_or(Stop::Error(NO_CODE))
}

/// HEX: `count` characters from the first byte of S on, each into one digit of D from the
/// first digit on; the other digits of D keep their contents.
fn hex(req: &Request<'_>) -> Result<Outcome, Stop> {
    let s = req.device("S")?;
    let d = req.device("D")?;
    let di = designator(req)?;
    if !req.words_exist(s, di.byte_words()) || !req.words_exist(d, 1) {
        return Err(Stop::Error(NO_CODE));
    }
    let lowercase = req.variant.has_feature(LOWERCASE_HEX);
    let mut value = req.memory.word(d);
    for k in 0..di.count {
        let (offset, leftmost) = di.byte_at(k);
        let byte = byte_of(req.memory.word(&word_after(s, offset)?), leftmost);
        let digit = hex_digit(byte, di.parity, lowercase).ok_or(Stop::Error(NO_CODE))?;
        let shift = 4 * di.digit_at(k);
        value = (value & !(0xF << shift)) | (u16::from(digit) << shift);
    }
    let mut out = Scratch::new(req.memory);
    out.write(d.clone(), value);
    Ok(Outcome::written(out.into_writes()))
}

/// ASC: `count` digits of S from the first digit on, each as one ASCII byte (uppercase, the
/// leftmost bit set for the parity) into D from the first byte on; the other byte of a word
/// written in part keeps its contents.
fn asc(req: &Request<'_>) -> Result<Outcome, Stop> {
    let s = req.device("S")?;
    let d = req.device("D")?;
    let di = designator(req)?;
    if !req.words_exist(s, 1) || !req.words_exist(d, di.byte_words()) {
        return Err(Stop::Error(NO_CODE));
    }
    let source = req.memory.word(s);
    let mut out = Scratch::new(req.memory);
    for k in 0..di.count {
        let digit = source >> (4 * di.digit_at(k));
        let byte = u16::from(di.parity.apply(digit_char(u64::from(digit))));
        let (offset, leftmost) = di.byte_at(k);
        let word = word_after(d, offset)?;
        let old = out.word(&word);
        let new = if leftmost {
            (old & 0x00FF) | (byte << 8)
        } else {
            (old & 0xFF00) | byte
        };
        out.write(word, new);
    }
    Ok(Outcome::written(out.into_writes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn designator_digits() {
        let di = Designator::decode(0x0121).expect("valid");
        assert_eq!(
            di,
            Designator {
                first_digit: 1,
                count: 3,
                first_byte: 1,
                parity: Parity::None
            }
        );
        assert_eq!(di.byte_words(), 2);
        assert_eq!(di.byte_at(0), (0, true));
        assert_eq!(di.byte_at(1), (1, false));
        assert_eq!(di.byte_at(2), (1, true));
        assert_eq!(Designator::decode(0x0131).map(|d| d.byte_words()), Some(3));
        assert_eq!(Designator::decode(0x0004), None);
        assert_eq!(Designator::decode(0x0040), None);
        assert_eq!(Designator::decode(0x0200), None);
        assert_eq!(Designator::decode(0x3000), None);
        assert_eq!(Designator::decode(0x2133).map(|d| d.digit_at(1)), Some(0));
    }

    #[test]
    fn parity_as_the_manual_examples() {
        // Even: "31" becomes "B1", "36" stays; odd: "36" becomes "B6", "31" stays.
        assert_eq!(Parity::Even.apply(0x31), 0xB1);
        assert_eq!(Parity::Even.apply(0x36), 0x36);
        assert_eq!(Parity::Odd.apply(0x36), 0xB6);
        assert_eq!(Parity::Odd.apply(0x31), 0x31);
        assert_eq!(Parity::None.apply(0x41), 0x41);
        assert!(Parity::Even.accepts(0xB1) && !Parity::Even.accepts(0x31));
        assert!(Parity::Odd.accepts(0x31) && !Parity::Odd.accepts(0xB1));
        assert!(Parity::None.accepts(0x31) && !Parity::None.accepts(0xB1));
    }

    #[test]
    fn hex_digits_strip_the_parity_bit() {
        assert_eq!(hex_digit(0xB1, Parity::Even, false), Some(1));
        assert_eq!(hex_digit(0x61, Parity::None, false), None);
        assert_eq!(hex_digit(0x61, Parity::None, true), Some(10));
        assert_eq!(hex_digit(0x47, Parity::None, true), None);
    }
}
