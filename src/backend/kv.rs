//! Reference model of KEYENCE KV ASC and RASC, which convert one byte through the internal
//! register.
//!
//! Rules and their evidence are in `docs/semantics.md#kv-asc-rasc`. The conformance program
//! runs each as `LDA s` / `ASC` (or `RASC`) / `STA d`. ASC turns the register's low-order 8 bits
//! into two characters, the high digit's in the high byte (`A5` -> 4135H), and ignores its
//! high-order 8 bits. RASC reads the register's two bytes, the high one first, as two hex
//! digits; a byte outside 30H-39H and 41H-46H disables the conversion and turns on the
//! special utility relay 2012 (CR2012), and then `STA` stores the register as it was loaded.
//! Which byte holds the first character is read from the manual's figure, whose labels
//! disagree (open question `kv-asc-byte-order`).

use super::reference::{constant_word, Model, Stop};
use super::{Outcome, Request, Unsupported};
use crate::memory::Scratch;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "keyence-kv";

/// The KEYENCE KV reference model.
pub(crate) struct Kv;

impl Model for Kv {
    const PROFILE: &'static str = PROFILE;

    fn models(instruction: &str) -> bool {
        matches!(instruction, "ASC" | "RASC")
    }

    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        let register = loaded(req)?;
        let (stored, error) = match req.instruction {
            "ASC" => (asc(register), None),
            "RASC" => match rasc(register) {
                Some(byte) => (byte, None),
                // The conversion is disabled: the register keeps what was loaded.
                // The profile signals with CR2012 only: no code reaches a comparison.
                None => (register, Some(req.error(0))),
            },
            other => return Err(Unsupported(format!("{other} is not modelled")).into()),
        };
        let d = req.device("d")?;
        let mut out = Scratch::new(req.memory);
        out.write(d.clone(), stored);
        Ok(Outcome {
            error,
            ..Outcome::written(out.into_writes())
        })
    }
}

/// What `LDA s` puts in the internal register.
fn loaded(req: &Request<'_>) -> Result<u16, Stop> {
    Ok(match req.operand("s")? {
        Operand::Constant(k) => constant_word("s", *k)?,
        Operand::Device(d) => req.memory.word(d),
    })
}

/// ASC: the low-order byte as two characters, the high digit's in the high byte.
fn asc(register: u16) -> u16 {
    let high = u16::from(digit_char(u64::from(register >> 4 & 0xF)));
    let low = u16::from(digit_char(u64::from(register & 0xF)));
    high << 8 | low
}

/// RASC: the two characters, the high byte's first, as one byte; `None` when either is not a
/// hex digit.
fn rasc(register: u16) -> Option<u16> {
    let first = digit_value((register >> 8) as u8)?;
    let second = digit_value(register as u8)?;
    Some(u16::from(first << 4 | second))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The manual's figure: A5 -> 0100000100110101 (4135H); 3643H -> 6CH.
    #[test]
    fn the_figure_s_bit_patterns() {
        assert_eq!(asc(0x00A5), 0x4135);
        assert_eq!(asc(0xFFA5), 0x4135);
        assert_eq!(rasc(0x3643), Some(0x6C));
        assert_eq!(rasc(0x3663), None);
    }
}
