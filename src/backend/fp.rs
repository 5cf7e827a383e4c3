//! Reference model of Panasonic FP F72 AHEX (ASCII to hex) and F71 HEXA (hex to ASCII).
//!
//! Rules and their evidence are in `docs/semantics.md#fp-ahex-hexa`. A third packing: two
//! characters make one byte, the first in the high nibble, and the bytes go in reading order
//! from the low byte of each word ("the characters of the upper and lower bytes are
//! interchanged"), so "ABCD" becomes CDABH — the MEWTOCOL word order. An odd count leaves 0 in
//! bits 0-3 of the last byte. Whether a last byte that ends in a low byte leaves the high byte
//! as it was is the open question `fp-ahex-odd-byte` (the model leaves it). F71 is the inverse:
//! each byte, the low byte of each word first, becomes a word of two characters, the high
//! digit's in the low byte. Every error (a count of 0, a character that is not 0-9 or A-F, an
//! area too small) is an operation error: the flag, and nothing written.

use super::reference::{constant_word, Model, Run, Stop};
use super::{Outcome, Request};
use crate::memory::Scratch;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "panasonic-fp";

/// What the model passes as the error code: the profile signals with the operation error flag
/// only, so this value never reaches a comparison.
const OPERATION_ERROR: u16 = 0;

/// The Panasonic FP reference model.
pub(crate) struct Fp;

impl Model for Fp {
    const PROFILE: &'static str = PROFILE;

    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[("F72", ahex), ("F71", hexa)];
}

/// A 16-bit operand: a constant as the CPU holds it, or a word of memory.
fn word(req: &Request<'_>, name: &str) -> Result<u16, Stop> {
    match req.operand(name)? {
        Operand::Constant(k) => Ok(constant_word(name, *k)?),
        Operand::Device(d) => {
            if !req.words_exist(d, 1) {
                return Err(Stop::Error(OPERATION_ERROR));
            }
            Ok(req.memory.word(d))
        }
    }
}

/// The count s2, read as a signed 16-bit number: 0 or less is an operation error.
fn count(req: &Request<'_>) -> Result<u32, Stop> {
    match word(req, "s2")? as i16 {
        n if n > 0 => Ok(n as u32),
        _ => Err(Stop::Error(OPERATION_ERROR)),
    }
}

/// The byte `k` of words stored from `head`, the low byte of each word first.
fn byte_of(words: impl Fn(u32) -> u16, k: u32) -> u8 {
    let w = words(k / 2);
    if k % 2 == 0 {
        w as u8
    } else {
        (w >> 8) as u8
    }
}

/// F72 AHEX: s2 characters from s1 -> ceil(s2/2) bytes from d, the first in the low byte.
fn ahex(req: &Request<'_>) -> Result<Outcome, Stop> {
    let n = count(req)?;
    let s = req.device("s1")?;
    let d = req.device("d")?;
    let bytes = n.div_ceil(2);
    if !req.words_exist(s, n.div_ceil(2)) || !req.words_exist(d, bytes.div_ceil(2)) {
        return Err(Stop::Error(OPERATION_ERROR));
    }
    let read = |i: u32| s.offset(i).map_or(0, |dev| req.memory.word(&dev));
    let mut digits = Vec::with_capacity(n as usize + 1);
    for k in 0..n {
        digits.push(digit_value(byte_of(read, k)).ok_or(Stop::Error(OPERATION_ERROR))?);
    }
    if n % 2 == 1 {
        digits.push(0);
    }
    let mut out = Scratch::new(req.memory);
    for (k, pair) in digits.chunks(2).enumerate() {
        let byte = u16::from(pair[0] << 4 | pair[1]);
        if let Some(dev) = d.offset(k as u32 / 2) {
            let old = out.word(&dev);
            let new = if k % 2 == 0 {
                (old & 0xFF00) | byte
            } else {
                (old & 0x00FF) | byte << 8
            };
            out.write(dev, new);
        }
    }
    Ok(Outcome::written(out.into_writes()))
}

/// F71 HEXA: s2 bytes from s1 -> s2 words of two characters from d.
fn hexa(req: &Request<'_>) -> Result<Outcome, Stop> {
    let n = count(req)?;
    let d = req.device("d")?;
    let source: Vec<u16> = match req.operand("s1")? {
        Operand::Constant(_) => vec![word(req, "s1")?],
        Operand::Device(s) => {
            if !req.words_exist(s, n.div_ceil(2)) {
                return Err(Stop::Error(OPERATION_ERROR));
            }
            (0..n.div_ceil(2))
                .map(|i| s.offset(i).map_or(0, |dev| req.memory.word(&dev)))
                .collect()
        }
    };
    if !req.words_exist(d, n) {
        return Err(Stop::Error(OPERATION_ERROR));
    }
    let mut out = Scratch::new(req.memory);
    for k in 0..n {
        let byte = byte_of(|i| source.get(i as usize).copied().unwrap_or(0), k);
        let high = u16::from(digit_char(u64::from(byte >> 4)));
        let low = u16::from(digit_char(u64::from(byte & 0xF)));
        if let Some(dev) = d.offset(k) {
            out.write(dev, high | low << 8);
        }
    }
    Ok(Outcome::written(out.into_writes()))
}
