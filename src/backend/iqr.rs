//! Reference model of MELSEC iQ-R HABIN(P)/DHABIN(P) and BINHA(P)/DBINHA(P).
//!
//! Rules and their evidence are in `docs/semantics.md#iqr-habin` and
//! `docs/semantics.md#iqr-binha`: hex ASCII stored two characters per word, low byte first; SM705 switches between fixed digits and 00H-terminated text; SM701
//! decides whether BINHA writes a terminator word after a full-length result. Device ranges,
//! flag support per firmware and the error signalling come from the profile.

use super::reference::{Model, Stop};
use super::{Outcome, Request, Unsupported};
use crate::memory::{Scratch, Unit};
use crate::model::cross_vendor::TextLayout;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "mitsubishi-iqr";

/// Data does not convert: a character outside 30H-39H, 41H-46H.
pub(crate) const ERR_INVALID_DATA: u16 = 0x3401;
/// A device past the end of its range.
pub(crate) const ERR_DEVICE_RANGE: u16 = 0x2820;

/// The iQ-R reference model.
pub(crate) struct Iqr;

/// Result width in words: 1 for the 16-bit forms, 2 for the D-prefixed 32-bit forms.
fn width(instruction: &str) -> Option<(Op, u32)> {
    Some(match instruction {
        "HABIN" | "HABINP" => (Op::FromAscii, 1),
        "DHABIN" | "DHABINP" => (Op::FromAscii, 2),
        "BINHA" | "BINHAP" => (Op::ToAscii, 1),
        "DBINHA" | "DBINHAP" => (Op::ToAscii, 2),
        _ => return None,
    })
}

enum Op {
    FromAscii,
    ToAscii,
}

impl Model for Iqr {
    const PROFILE: &'static str = PROFILE;

    fn models(instruction: &str) -> bool {
        width(instruction).is_some()
    }

    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        Ok(match width(req.instruction) {
            Some((Op::FromAscii, words)) => habin(req, words)?,
            Some((Op::ToAscii, words)) => binha(req, words)?,
            None => return Err(Unsupported(format!("{} is not modelled", req.instruction)).into()),
        })
    }
}

/// HABIN / DHABIN: hex ASCII at (s) -> binary at (d).
fn habin(req: &Request<'_>, words: u32) -> Result<Outcome, Unsupported> {
    let s = req.device("s")?;
    let d = req.device("d")?;
    let max_digits = 4 * words;
    let terminated = req.flag("SM705");
    if !req.words_exist(d, words) {
        return Ok(Outcome::error(req.error(ERR_DEVICE_RANGE)));
    }
    // Fixed digits read whole words up front; terminated text reads word by word and stops at
    // the 00H, so only the words it reaches must exist.
    if !terminated && !req.words_exist(s, max_digits / 2) {
        return Ok(Outcome::error(req.error(ERR_DEVICE_RANGE)));
    }
    let mut value: u64 = 0;
    let mut digits = 0;
    for k in 0..max_digits {
        if k % 2 == 0 && !req.words_exist(s, k / 2 + 1) {
            return Ok(Outcome::error(req.error(ERR_DEVICE_RANGE)));
        }
        let ch = TextLayout::Packed.char_in(req.memory, s, k).unwrap_or(0);
        if terminated && ch == 0 {
            break;
        }
        match digit_value(ch) {
            Some(v) => value = value << 4 | u64::from(v),
            None => return Ok(Outcome::error(req.error(ERR_INVALID_DATA))),
        }
        digits += 1;
    }
    // Zero digits (00H first) is not fixed by the manual; the model reports invalid data.
    if digits == 0 {
        return Ok(Outcome::error(req.error(ERR_INVALID_DATA)));
    }
    let mut out = Scratch::new(req.memory);
    for w in 0..words {
        if let Some(dev) = d.offset(w) {
            out.write(dev, (value >> (16 * w)) as u16);
        }
    }
    Ok(Outcome::written(out.into_writes()))
}

/// BINHA / DBINHA: binary at (s) -> hex ASCII at (d).
fn binha(req: &Request<'_>, words: u32) -> Result<Outcome, Unsupported> {
    let bits = 16 * words;
    let value: u64 = match req.operand("s")? {
        Operand::Constant(k) => crate::value::to_bits(&format!("K{k}"), *k, bits)
            .map_err(|e| Unsupported(e.to_string()))?,
        Operand::Device(s) => {
            if !req.words_exist(s, words) {
                return Ok(Outcome::error(req.error(ERR_DEVICE_RANGE)));
            }
            (0..words)
                .filter_map(|w| s.offset(w))
                .enumerate()
                .fold(0, |acc, (i, dev)| {
                    acc | u64::from(req.memory.word(&dev)) << (16 * i)
                })
        }
    };
    let d = req.device("d")?;
    let max_digits = 4 * words as usize;
    let mut chars: Vec<u8> = if req.flag("SM705") {
        // Leading zeros dropped; the value 0 still has one digit.
        let n = (1..=max_digits)
            .rev()
            .find(|n| value >> (4 * (n - 1)) != 0)
            .unwrap_or(1);
        (0..n).rev().map(|i| digit_char(value >> (4 * i))).collect()
    } else {
        (0..max_digits)
            .rev()
            .map(|i| digit_char(value >> (4 * i)))
            .collect()
    };
    // A short result is always terminated; a full-length one gets a 0000H word unless SM701.
    if chars.len() < max_digits || !req.flag("SM701") {
        chars.push(0);
    }
    let packed = Unit::Word.pack(&chars);
    if !req.words_exist(d, packed.len() as u32) {
        return Ok(Outcome::error(req.error(ERR_DEVICE_RANGE)));
    }
    let mut out = Scratch::new(req.memory);
    for (i, word) in packed.into_iter().enumerate() {
        if let Some(dev) = d.offset(i as u32) {
            out.write(dev, word);
        }
    }
    Ok(Outcome::written(out.into_writes()))
}
