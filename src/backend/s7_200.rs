//! Reference model of Siemens S7-200 and S7-200 SMART ATH (ASCII to hex) and HTA (hex to
//! ASCII), on byte-addressed memory.
//!
//! Rules and their evidence are in `docs/semantics.md#s7-200-ath` and
//! `docs/semantics.md#s7-200-hta`. The S7-200 parts from the S7-1200 ([`super::s7`]) where
//! byte-array codecs part too: an odd LEN leaves the low nibble of the last byte unchanged
//! rather than zeroing it; an illegal character turns SM1.7 on rather than returning a code; HTA
//! counts hex digits, not bytes. What an illegal character leaves in OUT is not stated: the
//! model writes nothing (open question `s7-200-ath-illegal-output`), and LEN = 0 converts
//! nothing (open question `s7-200-len-zero`).

use super::reference::{Model, Run, Stop};
use super::{Outcome, Request, Unsupported};
use crate::device::Device;
use crate::memory::Scratch;
use crate::model::Operand;
use crate::text::digit_char;

/// The profile this model implements.
pub(crate) const PROFILE: &str = "siemens-s7-200";

/// What the model passes as the error code: the S7-200 shows an illegal character as SM1.7 only,
/// so the profile turns any code into that flag and this value never reaches a comparison.
const ILLEGAL_ASCII: u16 = 0;

/// The S7-200 / S7-200 SMART reference model.
pub(crate) struct S7200;

impl Model for S7200 {
    const PROFILE: &'static str = PROFILE;

    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[("ATH", ath), ("HTA", hta)];
}

/// IN, LEN and OUT, once both arrays are inside the conformance program's areas: `n_in(LEN)`
/// bytes of input and `n_out(LEN)` of output. Past them the CPU answers a non-fatal 0091H that
/// the profile does not compare, so such a request is not modelled.
fn arrays<'r>(
    req: &'r Request<'_>,
    n_in: impl Fn(u32) -> u32,
    n_out: impl Fn(u32) -> u32,
) -> Result<(&'r Device, u32, &'r Device), Stop> {
    let input = req.device("IN")?;
    let output = req.device("OUT")?;
    let len = match req.operand("LEN")? {
        Operand::Constant(k) => {
            u32::try_from(*k).map_err(|_| Unsupported(format!("LEN = K{k} is not a BYTE")))?
        }
        Operand::Device(d) => u32::from(req.memory.word(d)),
    };
    for (array, units) in [(input, n_in(len)), (output, n_out(len))] {
        if !req.words_exist(array, units) {
            return Err(Unsupported(format!(
                "{units} bytes from {array} run past the conformance program's area (0091H is not modelled)"
            ))
            .into());
        }
    }
    Ok((input, len, output))
}

/// ATH: LEN characters, one per byte from IN -> ceil(LEN/2) bytes from OUT; an odd LEN keeps
/// the old low nibble of the last byte.
fn ath(req: &Request<'_>) -> Result<Outcome, Stop> {
    let (input, len, output) = arrays(req, |n| n, |n| n.div_ceil(2))?;
    let mut nibbles = Vec::with_capacity(len as usize);
    for k in 0..len {
        let ch = input.offset(k).map_or(0, |d| req.memory.word(&d));
        // 30H-39H and 41H-46H only: S7-200 ATH's legal characters, unlike the S7-1200's.
        match u8::try_from(ch).ok().and_then(crate::text::digit_value) {
            Some(v) => nibbles.push(v),
            None => return Err(Stop::Error(ILLEGAL_ASCII)),
        }
    }
    let mut scratch = Scratch::new(req.memory);
    for (j, pair) in nibbles.chunks(2).enumerate() {
        if let Some(d) = output.offset(j as u32) {
            let low = match pair {
                [_, low] => *low,
                _ => (req.memory.word(&d) & 0x0F) as u8,
            };
            scratch.write(d, u16::from(pair[0] << 4 | low));
        }
    }
    Ok(Outcome::written(scratch.into_writes()))
}

/// HTA: LEN hex digits from IN, the high nibble of each byte first -> LEN uppercase characters
/// from OUT.
fn hta(req: &Request<'_>) -> Result<Outcome, Stop> {
    let (input, len, output) = arrays(req, |n| n.div_ceil(2), |n| n)?;
    let mut scratch = Scratch::new(req.memory);
    for k in 0..len {
        let byte = input.offset(k / 2).map_or(0, |d| req.memory.word(&d));
        let nibble = if k % 2 == 0 { byte >> 4 } else { byte & 0xF };
        if let Some(d) = output.offset(k) {
            scratch.write(d, u16::from(digit_char(u64::from(nibble))));
        }
    }
    Ok(Outcome::written(scratch.into_writes()))
}
