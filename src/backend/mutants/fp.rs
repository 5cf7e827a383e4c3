//! Teeth for the Panasonic FP corpus: deliberately wrong F72/F71 implementations, each of which
//! some vector must tell apart from the help pages. Most are another vendor's packing (the
//! first pair in the high byte, as Mitsubishi and Siemens read), or what a MEWTOCOL codec gets
//! wrong (lowercase accepted, a zero count passed over, the digits of a byte swapped).

#[cfg(test)]
use std::sync::Arc;

use super::{assert_kills, map_done, with_memory, Mutant};
use super::{device, hex_upper_bytes, map_writes, without_error};
use crate::Operand;
use crate::{Backend, Request, Response};

const PROFILE: &str = "panasonic-fp";

fn count(req: &Request<'_>) -> i64 {
    match req.operands.get("s2") {
        Some(Operand::Constant(k)) => *k,
        Some(Operand::Device(d)) => i64::from(req.memory.read(d) as i16),
        None => 0,
    }
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        // F72 bytes in the other order: the first pair in the high byte.
        Mutant::new("f72-first-pair-high", base, |req, base| {
            map_writes(base.execute(req), req.instruction == "F72", u32::swap_bytes)
        }),
        // F71 characters the other way round in each word: the low digit's in the low byte.
        Mutant::new("f71-low-digit-first", base, |req, base| {
            map_writes(base.execute(req), req.instruction == "F71", u32::swap_bytes)
        }),
        // F71 reads the high byte of each source word first.
        Mutant::new("f71-high-byte-first", base, |req, base| {
            if req.instruction != "F71" {
                return base.execute(req);
            }
            with_memory(req, base, u16::swap_bytes)
        }),
        // An odd count keeps the last low nibble instead of writing 0 there.
        Mutant::new("f72-odd-keeps-nibble", base, |req, base| {
            let n = count(req);
            let odd = req.instruction == "F72" && n > 0 && n % 2 == 1;
            let Some(d) = device(req, "d") else {
                return base.execute(req);
            };
            let bytes = (n as u32).div_ceil(2);
            let last = d.offset((bytes - u32::from(bytes > 0)) / 2);
            let high = bytes % 2 == 0;
            let old = last.as_ref().map(|l| req.memory.read(l));
            map_done(base.execute(req), |mut o| {
                if let (true, Some(l), Some(old)) = (odd, last, old) {
                    if let Some(v) = o.writes.get_mut(&l) {
                        let keep = if high { old & 0x0F00 } else { old & 0x000F };
                        *v |= keep;
                    }
                }
                o
            })
        }),
        // Lowercase a-f read as digits.
        Mutant::new("f72-lowercase-accepted", base, |req, base| {
            if req.instruction != "F72" {
                return base.execute(req);
            }
            with_memory(req, base, hex_upper_bytes)
        }),
        // An operation error reported nowhere.
        Mutant::new("error-silent", base, without_error),
        // A count of 0 converts nothing, without an error.
        Mutant::new("count-zero-silent", base, |req, base| {
            if count(req) == 0 {
                return Ok(Response::Done(Default::default()));
            }
            base.execute(req)
        }),
        // On an error, the destination is cleared as well.
        Mutant::new("error-clears-destination", base, |req, base| {
            let d = device(req, "d");
            map_done(base.execute(req), |mut o| {
                if let (Some(_), Some(d)) = (&o.error, d) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
    ]
}

#[test]
fn the_panasonic_corpus_kills_every_mutant() {
    assert_kills(PROFILE, mutants);
}
