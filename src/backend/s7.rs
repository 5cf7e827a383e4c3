//! Reference model of Siemens S7-1200 (and S7-1500, TIA Portal) ATH (ASCII to hex) and HTA
//! (hex to ASCII), on byte-addressed memory.
//!
//! Rules and their evidence are in `docs/semantics.md#s7-ath` and `docs/semantics.md#s7-hta`:
//! IN and OUT are byte arrays; two characters make one byte, the first in the high nibble, in
//! reading order; an odd count leaves 0 in the last low nibble. Unlike every Mitsubishi and
//! IDEC instruction, a character that is not a hex digit is converted to 0 and the conversion
//! goes on: OUT is written, and RET_VAL 0007H (ENO FALSE) reports it. Which characters are
//! digits (lowercase a-f?) is the open question `s7-ath-lowercase`; the model takes lowercase
//! a-f as digits too, the reading most of the documentation supports. A buffer that cannot hold N (here: an array that runs past the end of its data block
//! or marker area) is RET_VAL 8182H (IN) or 8382H (OUT), and nothing is written. HTA writes 2N
//! uppercase characters and always ends with ENO TRUE.

use super::reference::{Model, Run, Stop};
use super::{Outcome, Request, Unsupported};
use crate::device::Device;
use crate::memory::Scratch;
use crate::model::{ErrorSignal, Operand};
use crate::text::digit_char;

/// The profile this model implements.
pub(crate) const PROFILE: &str = "siemens-s7-1200";

/// RET_VAL: a character that is not a hex digit was converted to 0.
pub(crate) const INVALID_CHARACTER: u16 = 0x0007;
/// RET_VAL: the input buffer is too small for N.
pub(crate) const INPUT_TOO_SMALL: u16 = 0x8182;
/// RET_VAL: the output buffer is too small for N.
pub(crate) const OUTPUT_TOO_SMALL: u16 = 0x8382;

/// The S7-1200 reference model.
pub(crate) struct S71200;

impl Model for S71200 {
    const PROFILE: &'static str = PROFILE;

    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[("ATH", ath), ("HTA", hta)];
}

/// The value of an ASCII hex digit as the S7-1200 reads it: 0-9, A-F and a-f (the 0007H
/// condition, the 'a23' and '0a23' rows and the 09/2016 body text;
/// `docs/semantics.md#s7-ath-lowercase`).
pub(super) fn digit(ch: u16) -> Option<u8> {
    match u8::try_from(ch).ok()? {
        c @ b'0'..=b'9' => Some(c - b'0'),
        c @ b'A'..=b'F' => Some(c - b'A' + 10),
        c @ b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    }
}

/// N: a constant or a byte read from memory (a UInt operand).
fn count(req: &Request<'_>) -> Result<u32, Stop> {
    match req.operand("N")? {
        Operand::Constant(k) => u32::try_from(*k)
            .map_err(|_| Stop::Unsupported(Unsupported(format!("N = K{k} is not a UInt")))),
        Operand::Device(d) => Ok(u32::from(req.memory.word(d))),
    }
}

/// IN, N and OUT, once both arrays are checked to hold what N asks: N bytes of input and
/// `n_out(N)` of output.
fn arrays<'r>(
    req: &'r Request<'_>,
    n_out: impl Fn(u32) -> u32,
) -> Result<(&'r Device, u32, &'r Device), Stop> {
    let input = req.device("IN")?;
    let output = req.device("OUT")?;
    let n = count(req)?;
    if !req.words_exist(input, n) {
        return Err(Stop::Error(INPUT_TOO_SMALL));
    }
    if !req.words_exist(output, n_out(n)) {
        return Err(Stop::Error(OUTPUT_TOO_SMALL));
    }
    Ok((input, n, output))
}

/// ATH: N characters, one per byte from IN -> ceil(N/2) bytes from OUT.
fn ath(req: &Request<'_>) -> Result<Outcome, Stop> {
    let (input, n, output) = arrays(req, |n| n.div_ceil(2))?;
    let mut invalid = false;
    let mut nibbles = Vec::with_capacity(n as usize + 1);
    for k in 0..n {
        let ch = input.offset(k).map_or(0, |d| req.memory.word(&d));
        nibbles.push(digit(ch).unwrap_or_else(|| {
            invalid = true;
            0
        }));
    }
    if n % 2 == 1 {
        nibbles.push(0);
    }
    let mut scratch = Scratch::new(req.memory);
    for (j, pair) in nibbles.chunks(2).enumerate() {
        if let Some(d) = output.offset(j as u32) {
            scratch.write(d, u16::from(pair[0] << 4 | pair[1]));
        }
    }
    Ok(Outcome {
        error: invalid.then_some(ErrorSignal::Code(INVALID_CHARACTER)),
        ..Outcome::written(scratch.into_writes())
    })
}

/// HTA: N bytes from IN -> 2N characters from OUT, uppercase, the high nibble first.
fn hta(req: &Request<'_>) -> Result<Outcome, Stop> {
    let (input, n, output) = arrays(req, |n| 2 * n)?;
    let mut scratch = Scratch::new(req.memory);
    for k in 0..n {
        let byte = input.offset(k).map_or(0, |d| req.memory.word(&d));
        for (i, nibble) in [byte >> 4, byte & 0xF].into_iter().enumerate() {
            if let Some(d) = output.offset(2 * k + i as u32) {
                scratch.write(d, u16::from(digit_char(u64::from(nibble))));
            }
        }
    }
    Ok(Outcome::written(scratch.into_writes()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case(b'0', Some(0))]
    #[case(b'9', Some(9))]
    #[case(b'A', Some(10))]
    #[case(b'F', Some(15))]
    #[case(b'a', Some(10))]
    #[case(b'f', Some(15))]
    #[case(b'g', None)]
    #[case(b'G', None)]
    #[case(b' ', None)]
    fn digits_are_0_to_9_and_a_to_f_in_either_case(#[case] ch: u8, #[case] value: Option<u8>) {
        assert_eq!(digit(u16::from(ch)), value);
    }
}
