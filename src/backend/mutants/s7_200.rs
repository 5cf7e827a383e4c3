//! Teeth for the Siemens S7-200 corpus: deliberately wrong ATH/HTA implementations, each of
//! which some vector must tell apart from the manual. Most are the S7-1200's rules where the
//! S7-200 parts from them (an odd LEN zeroing the last nibble, HTA counting bytes), or what a
//! byte-array codec gets wrong (lowercase accepted, an illegal character passed over in
//! silence, a 00H taken for the end of the text).

#[cfg(test)]
use std::sync::Arc;

use super::{assert_kills, map_done, siemens_mutants, with_constant, Mutant};
use super::{count, device, hex_upper, with_input, without_error};
use crate::Backend;

const PROFILE: &str = "siemens-s7-200";

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        // An odd LEN zeroes the last low nibble (the S7-1200 rule).
        Mutant::new("ath-odd-zeroes-nibble", base, |req, base| {
            let n = count(req, "LEN");
            let last = device(req, "OUT").and_then(|d| d.offset(n / 2));
            let odd = req.instruction == "ATH" && n % 2 == 1;
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d)) = (odd, last) {
                    if let Some(v) = o.writes.get_mut(&d) {
                        *v &= 0xF0;
                    }
                }
                o
            })
        }),
        // An illegal character passed over in silence: SM1.7 never set.
        Mutant::new("ath-illegal-silent", base, without_error),
        // An illegal character zeroes every output byte as well as setting SM1.7.
        Mutant::new("ath-illegal-zeroes-output", base, |req, base| {
            let (out, n) = (device(req, "OUT"), count(req, "LEN"));
            map_done(base.execute(req), |mut o| {
                if let (Some(_), Some(out)) = (&o.error, out) {
                    for d in (0..n.div_ceil(2)).filter_map(|k| out.offset(k)) {
                        o.writes.insert(d, 0);
                    }
                }
                o
            })
        }),
        // Lowercase a-f read as digits.
        Mutant::new("ath-lowercase-accepted", base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            with_input(req, base, count(req, "LEN"), hex_upper)
        }),
        // A 00H ends the text early, as a C string: the characters before it are converted.
        Mutant::new("ath-nul-terminated", base, |req, base| {
            let Some(input) = device(req, "IN") else {
                return base.execute(req);
            };
            let n = count(req, "LEN");
            let nul = (0..n).find(|k| input.offset(*k).is_some_and(|d| req.memory.read(&d) == 0));
            match (req.instruction, nul) {
                ("ATH", Some(k)) => with_constant(req, base, "LEN", |_| i64::from(k)),
                _ => base.execute(req),
            }
        }),
        // LEN read as a number of bytes for ATH (twice the characters).
        Mutant::new("ath-len-as-bytes", base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            with_constant(req, base, "LEN", |k| (2 * k).min(255))
        }),
        // HTA writes the low nibble first.
        Mutant::new("hta-low-nibble-first", base, |req, base| {
            if req.instruction != "HTA" {
                return base.execute(req);
            }
            with_input(req, base, count(req, "LEN").div_ceil(2), |b| {
                (b >> 4 | b << 4) & 0xFF
            })
        }),
        // HTA's LEN counts bytes (the S7-1200's N): 2 LEN characters.
        Mutant::new("hta-len-as-bytes", base, |req, base| {
            if req.instruction != "HTA" {
                return base.execute(req);
            }
            with_constant(req, base, "LEN", |k| (2 * k).min(255))
        }),
        // HTA ends its text with 00H.
        Mutant::new("hta-terminated", base, |req, base| {
            let end = device(req, "OUT").and_then(|d| d.offset(count(req, "LEN")));
            let hta = req.instruction == "HTA";
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d)) = (hta, end) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
    ]
}

#[test]
fn the_s7_200_corpus_kills_every_mutant() {
    assert_kills(PROFILE, |base| {
        [siemens_mutants(base), mutants(base)].concat()
    });
}
