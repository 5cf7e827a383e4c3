//! Teeth for the KEYENCE KV corpus: deliberately wrong ASC/RASC implementations, each of which
//! some vector must tell apart from the manual: the characters the other way round in the word
//! (the low byte first, as MELSEC packs them), lowercase accepted, an invalid character passed
//! over in silence, the register cleared instead of kept.

#[cfg(test)]
use std::sync::Arc;

use super::{assert_kills, map_done, Mutant};
use super::{hex_upper_bytes, map_writes, with_operands, with_units, without_error};
use crate::Operand;
use crate::{Backend, Request, Response};

const PROFILE: &str = "keyence-kv";

/// The word LDA loads.
fn loaded(req: &Request<'_>) -> Option<u16> {
    match req.operands.get("s")? {
        Operand::Device(d) => Some(req.memory.word(d)),
        Operand::Constant(k) => Some(*k as u16),
    }
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        // ASC stores the first character in the low byte.
        Mutant::new("asc-low-byte-first", base, |req, base| {
            map_writes(base.execute(req), req.instruction == "ASC", u32::swap_bytes)
        }),
        // RASC reads the low byte as the first character.
        Mutant::new("rasc-low-byte-first", base, |req, base| {
            let (true, Some(Operand::Device(s))) =
                (req.instruction == "RASC", req.operands.get("s"))
            else {
                return base.execute(req);
            };
            let mut words = req.memory.explicit().clone();
            let w = req.memory.read(s);
            words.insert(s.clone(), w.swap_bytes());
            let answer = with_units(req, base, words);
            // Only the conversion swaps: what STA stores on an error is the word as loaded.
            map_done(answer, |mut o| {
                if o.error.is_some() {
                    for v in o.writes.values_mut() {
                        *v = w;
                    }
                }
                o
            })
        }),
        // RASC reads lowercase a-f as digits.
        Mutant::new("rasc-lowercase-accepted", base, |req, base| {
            let Some(w) = loaded(req).filter(|_| req.instruction == "RASC") else {
                return base.execute(req);
            };
            let fixed = hex_upper_bytes(w);
            if fixed == w {
                return base.execute(req);
            }
            with_operands(req, base, &[("s", Operand::Constant(i64::from(fixed)))])
        }),
        // An invalid character passed over in silence.
        Mutant::new("rasc-error-silent", base, without_error),
        // On an error the register is cleared, and STA stores 0.
        Mutant::new("rasc-error-clears", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error.is_some() {
                    for v in o.writes.values_mut() {
                        *v = 0;
                    }
                }
                o
            })
        }),
        // ASC converts the high-order byte too (four characters' worth, the low word kept).
        Mutant::new("asc-reads-high-byte", base, |req, base| {
            let high = loaded(req).is_some_and(|w| w >> 8 != 0) && req.instruction == "ASC";
            if high {
                return Ok(Response::Done(Default::default()));
            }
            base.execute(req)
        }),
    ]
}

#[test]
fn the_keyence_corpus_kills_every_mutant() {
    assert_kills(PROFILE, mutants);
}
