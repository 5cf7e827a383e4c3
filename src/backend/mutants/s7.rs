//! Teeth for the Siemens S7 corpus: deliberately wrong ATH/HTA implementations, each of which
//! some vector must tell apart from the manual. Each one is a mistake a byte-array codec makes:
//! the nibbles of a byte swapped, an invalid character that stops the conversion or is read as
//! F, an odd count that keeps the old low nibble, a missing RET_VAL, and so on. Lowercase
//! accepted is no mutant: it is the open question s7-ath-lowercase, whose probes record what a
//! backend does rather than judge it.

#[cfg(test)]
use std::sync::Arc;

use super::{assert_kills, map_done, siemens_mutants, with_constant, Mutant};
use super::{count, device, with_input};
use crate::ErrorSignal;
use crate::{Backend, Response};

const PROFILE: &str = "siemens-s7-1200";

fn is_digit(b: u16) -> bool {
    matches!(b, 0x30..=0x39 | 0x41..=0x46)
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        // An invalid character stops the conversion: nothing written, as MELSEC does.
        Mutant::new("ath-invalid-writes-nothing", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error == Some(ErrorSignal::Code(0x0007)) {
                    o.writes.clear();
                }
                o
            })
        }),
        // An invalid character converted and reported nowhere.
        Mutant::new("ath-invalid-silent", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error == Some(ErrorSignal::Code(0x0007)) {
                    o.error = None;
                }
                o
            })
        }),
        // An invalid character read as F instead of 0.
        Mutant::new("ath-invalid-as-f", base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            let out = with_input(req, base, count(req, "N"), |b| {
                if is_digit(b) {
                    b
                } else {
                    u16::from(b'F')
                }
            });
            map_done(out, |mut o| {
                o.error = base.execute(req).ok().and_then(|r| match r {
                    Response::Done(o) => o.error,
                    _ => None,
                });
                o
            })
        }),
        // An odd count keeps the old low nibble of the last byte (the S7-200 rule).
        Mutant::new("ath-odd-keeps-nibble", base, |req, base| {
            let (Some(out), n) = (device(req, "OUT"), count(req, "N")) else {
                return base.execute(req);
            };
            let odd = req.instruction == "ATH" && n % 2 == 1;
            let last = out.offset(n / 2);
            let old = last.as_ref().map(|d| req.memory.read(d));
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d), Some(old)) = (odd, last, old) {
                    if let Some(v) = o.writes.get_mut(&d) {
                        *v = (*v & 0xF0) | (old & 0x0F);
                    }
                }
                o
            })
        }),
        // HTA writes the low nibble first.
        Mutant::new("hta-low-nibble-first", base, |req, base| {
            if req.instruction != "HTA" {
                return base.execute(req);
            }
            with_input(req, base, count(req, "N"), |b| (b >> 4 | b << 4) & 0xFF)
        }),
        // HTA ends its text with 00H.
        Mutant::new("hta-terminated", base, |req, base| {
            let end = device(req, "OUT").and_then(|d| d.offset(2 * count(req, "N")));
            let hta = req.instruction == "HTA";
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d), None) = (hta, end, &o.error) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
        // The buffer checks missing: the output written as far as the array goes.
        Mutant::new("no-buffer-check", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if matches!(o.error, Some(ErrorSignal::Code(0x8182 | 0x8382))) {
                    o.error = None;
                }
                o
            })
        }),
        // N read as a number of bytes for ATH (twice the characters).
        Mutant::new("ath-n-as-bytes", base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            with_constant(req, base, "N", |k| k * 2)
        }),
    ]
}

#[test]
fn the_s7_corpus_kills_every_mutant() {
    assert_kills(PROFILE, |base| {
        [siemens_mutants(base), mutants(base)].concat()
    });
}
