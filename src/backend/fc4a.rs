//! Reference model of IDEC MicroSmart FC4A ATOH (ASCII to hex) and HTOA (hex to ASCII).
//!
//! Rules and their evidence are in `docs/semantics.md#layout`, `docs/semantics.md#fc4a-atoh` and
//! `docs/semantics.md#fc4a-htoa`: one character per word,
//! and the whole word is the character (30H-39H, 41H-46H), so a word with a non-zero upper byte
//! is not a digit; the digit count S2 is 1-4, given as a constant or read from a word operand;
//! every error is a user program execution error, which a program sees only as M8004 turning
//! on, and the destination is left unchanged. Device ranges and the error flag come from the
//! profile, so a model with other data register ranges is an edit to `vendors/idec-fc4a.yaml`.

use super::reference::{Model, Run, Stop};
use super::{Outcome, Request, Unsupported};
use crate::memory::Scratch;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "idec-fc4a";

/// What the model passes as the error code. The FC4A shows a user program execution error as
/// M8004; what the error-code register holds for ATOH/HTOA is not confirmed, and the profile
/// signals with the flag only, so this value never reaches a comparison.
const NO_CONFIRMED_CODE: u16 = 0;

/// The most digits one 16-bit word holds.
const MAX_DIGITS: u32 = 4;

/// The FC4A reference model.
pub(crate) struct Fc4a;

impl Model for Fc4a {
    const PROFILE: &'static str = PROFILE;

    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[("ATOH", atoh), ("HTOA", htoa)];
}

/// A 16-bit source operand: a constant, or one word (a bit device's 16 points, a timer's or
/// counter's current value) that must exist on the model.
fn read_word(req: &Request<'_>, name: &str) -> Result<u16, Stop> {
    match req.operand(name)? {
        Operand::Constant(k) => u16::try_from(*k).map_err(|_| {
            Stop::Unsupported(Unsupported(format!(
                "operand `{name}` K{k} is not a 16-bit constant"
            )))
        }),
        Operand::Device(d) if req.words_exist(d, 1) => Ok(req.memory.word(d)),
        Operand::Device(_) => Err(Stop::Error(NO_CONFIRMED_CODE)),
    }
}

/// The digit count S2: 1-4, or an execution error.
fn digit_count(req: &Request<'_>) -> Result<u32, Stop> {
    let n = u32::from(read_word(req, "S2")?);
    if (1..=MAX_DIGITS).contains(&n) {
        Ok(n)
    } else {
        Err(Stop::Error(NO_CONFIRMED_CODE))
    }
}

/// ATOH: S2 characters, one per word from S1, most significant first -> the value in D1.
fn atoh(req: &Request<'_>) -> Result<Outcome, Stop> {
    let s1 = req.device("S1")?;
    let d1 = req.device("D1")?;
    let n = digit_count(req)?;
    if !req.words_exist(s1, n) || !req.words_exist(d1, 1) {
        return Err(Stop::Error(NO_CONFIRMED_CODE));
    }
    let mut value: u16 = 0;
    for k in 0..n {
        let word = s1
            .offset(k)
            .map(|dev| req.memory.word(&dev))
            .ok_or(Stop::Error(NO_CONFIRMED_CODE))?;
        // The whole word is the character: 0131H is not '1'.
        let digit = u8::try_from(word)
            .ok()
            .and_then(digit_value)
            .ok_or(Stop::Error(NO_CONFIRMED_CODE))?;
        value = value << 4 | u16::from(digit);
    }
    let mut out = Scratch::new(req.memory);
    out.write(d1.clone(), value);
    Ok(Outcome::written(out.into_writes()))
}

/// HTOA: the lowest S2 digits of S1, most significant first, one character (00xxH) per word
/// from D1.
fn htoa(req: &Request<'_>) -> Result<Outcome, Stop> {
    let value = read_word(req, "S1")?;
    let n = digit_count(req)?;
    let d1 = req.device("D1")?;
    if !req.words_exist(d1, n) {
        return Err(Stop::Error(NO_CONFIRMED_CODE));
    }
    let mut out = Scratch::new(req.memory);
    for k in 0..n {
        let dev = d1.offset(k).ok_or(Stop::Error(NO_CONFIRMED_CODE))?;
        let shift = 4 * (n - 1 - k);
        out.write(dev, u16::from(digit_char(u64::from(value >> shift))));
    }
    Ok(Outcome::written(out.into_writes()))
}
