//! A small emulator of MELSEC iQ-R HABIN(P), written as an emulator author would: against the
//! crate root of `plc-conformance` alone, with no access to its reference models.
//!
//! HABIN reads hexadecimal ASCII packed two characters a word, low byte first, from (s) and
//! writes the 16-bit value to (d) (`docs/semantics.md#iqr-habin`): with SM705 off exactly four
//! characters, with SM705 on up to four ended by 00H. A character outside 0-9/A-F is error
//! 3401H; an operand past its device range is 2820H.

use plc_conformance::{Device, Emulator, Outcome, Request, Unsupported, Value};

/// Data that does not convert.
const INVALID_DATA: u16 = 0x3401;
/// An operand past the end of its device range.
const DEVICE_RANGE: u16 = 0x2820;

/// The emulator, of the iQ-R profile.
pub struct HabinEmulator;

impl Emulator for HabinEmulator {
    fn name(&self) -> &str {
        "habin-emulator"
    }

    fn profile(&self) -> &str {
        "mitsubishi-iqr"
    }

    fn claims(&self, instruction: &str, _variant: &str) -> bool {
        matches!(instruction, "HABIN" | "HABINP")
    }

    fn execute(&self, r: &Request<'_>) -> Result<Outcome, Unsupported> {
        habin(r)
    }
}

fn habin(r: &Request<'_>) -> Result<Outcome, Unsupported> {
    let s = r.device("s")?;
    let d = r.device("d")?;
    let terminated = r.flag("SM705");
    if !r.words_exist(d, 1) || (!terminated && !r.words_exist(s, 2)) {
        return Ok(Outcome::error(r.error(DEVICE_RANGE)));
    }
    let mut value: Value = 0;
    let mut digits = 0;
    for k in 0..4 {
        // With SM705 on only the words the text reaches must exist.
        if !r.words_exist(s, k / 2 + 1) {
            return Ok(Outcome::error(r.error(DEVICE_RANGE)));
        }
        let ch = char_at(r, s, k);
        if terminated && ch == 0 {
            break;
        }
        let digit = match ch {
            b'0'..=b'9' => ch - b'0',
            b'A'..=b'F' => ch - b'A' + 10,
            _ => return Ok(Outcome::error(r.error(INVALID_DATA))),
        };
        value = value << 4 | Value::from(digit);
        digits += 1;
    }
    if digits == 0 {
        // 00H first with SM705 on: the manual does not say; this emulator calls it bad data.
        return Ok(Outcome::error(r.error(INVALID_DATA)));
    }
    Ok(Outcome::written([(d.clone(), value)].into()))
}

/// The k-th character of the text at `head`: word k/2, low byte first.
fn char_at(r: &Request<'_>, head: &Device, k: u32) -> u8 {
    let word = head
        .offset(k / 2)
        .map_or(0, |device| r.memory.read(&device));
    word.to_le_bytes()[(k % 2) as usize]
}
