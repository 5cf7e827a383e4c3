//! Teeth for the Siemens S7-200 corpus: deliberately wrong ATH/HTA implementations, each of
//! which some vector must tell apart from the manual. Most are the S7-1200's rules where the
//! S7-200 parts from them (an odd LEN zeroing the last nibble, HTA counting bytes), or what a
//! byte-array codec gets wrong (lowercase accepted, an illegal character passed over in
//! silence, a 00H taken for the end of the text).

#[cfg(test)]
use std::collections::BTreeMap;

use super::{assert_corpus_kills, map_done, reference, session, with_constant, Mutant};
use crate::Device;
use crate::Image;
use crate::Operand;
use crate::{Backend, Fault, Request, Response};

const PROFILE: &str = "siemens-s7-200";

fn device(req: &Request<'_>, name: &str) -> Option<Device> {
    match req.operands.get(name)? {
        Operand::Device(d) => Some(d.clone()),
        Operand::Constant(_) => None,
    }
}

fn len(req: &Request<'_>) -> u32 {
    match req.operands.get("LEN") {
        Some(Operand::Constant(k)) => u32::try_from(*k).unwrap_or(0),
        Some(Operand::Device(d)) => req.memory.read(d),
        None => 0,
    }
}

/// Runs the base with IN's first `n` bytes rewritten by `f`.
fn with_input(
    req: &Request<'_>,
    base: &dyn Backend,
    n: u32,
    f: impl Fn(u16) -> u16,
) -> Result<Response, Fault> {
    let mut bytes: BTreeMap<Device, u32> = req.memory.explicit().clone();
    if let Some(input) = device(req, "IN") {
        for d in (0..n).filter_map(|k| input.offset(k)) {
            let b = req.memory.word(&d);
            bytes.insert(d, u32::from(f(b)));
        }
    }
    let memory = Image::of_units(bytes, req.memory.fill(), req.memory.unit());
    base.execute(&Request {
        memory: &memory,
        ..*req
    })
}

#[test]
fn the_s7_200_corpus_kills_every_mutant() {
    let project = session();
    let base = reference(&project, PROFILE);
    let mutants = vec![
        // The two digits of each ATH byte the other way round.
        Mutant::new("ath-nibbles-swapped", &base, |req, base| {
            let ath = req.instruction == "ATH";
            map_done(base.execute(req), |mut o| {
                if ath {
                    for v in o.writes.values_mut() {
                        *v = (*v >> 4 | *v << 4) & 0xFF;
                    }
                }
                o
            })
        }),
        // An odd LEN zeroes the last low nibble (the S7-1200 rule).
        Mutant::new("ath-odd-zeroes-nibble", &base, |req, base| {
            let n = len(req);
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
        Mutant::new("ath-illegal-silent", &base, |req, base| {
            map_done(base.execute(req), |mut o| {
                o.error = None;
                o
            })
        }),
        // An illegal character zeroes every output byte as well as setting SM1.7.
        Mutant::new("ath-illegal-zeroes-output", &base, |req, base| {
            let (out, n) = (device(req, "OUT"), len(req));
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
        Mutant::new("ath-lowercase-accepted", &base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            with_input(req, base, len(req), |b| {
                if (0x61..=0x66).contains(&b) {
                    b - 0x20
                } else {
                    b
                }
            })
        }),
        // A 00H ends the text early, as a C string: the characters before it are converted.
        Mutant::new("ath-nul-terminated", &base, |req, base| {
            let Some(input) = device(req, "IN") else {
                return base.execute(req);
            };
            let n = len(req);
            let nul = (0..n).find(|k| input.offset(*k).is_some_and(|d| req.memory.read(&d) == 0));
            match (req.instruction, nul) {
                ("ATH", Some(k)) => with_constant(req, base, "LEN", |_| i64::from(k)),
                _ => base.execute(req),
            }
        }),
        // LEN read as a number of bytes for ATH (twice the characters).
        Mutant::new("ath-len-as-bytes", &base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            with_constant(req, base, "LEN", |k| (2 * k).min(255))
        }),
        // HTA writes lowercase letters.
        Mutant::new("hta-lowercase", &base, |req, base| {
            let hta = req.instruction == "HTA";
            map_done(base.execute(req), |mut o| {
                if hta {
                    for v in o.writes.values_mut() {
                        if (0x41..=0x46).contains(v) {
                            *v += 0x20;
                        }
                    }
                }
                o
            })
        }),
        // HTA writes the low nibble first.
        Mutant::new("hta-low-nibble-first", &base, |req, base| {
            if req.instruction != "HTA" {
                return base.execute(req);
            }
            with_input(req, base, len(req).div_ceil(2), |b| {
                (b >> 4 | b << 4) & 0xFF
            })
        }),
        // HTA's LEN counts bytes (the S7-1200's N): 2 LEN characters.
        Mutant::new("hta-len-as-bytes", &base, |req, base| {
            if req.instruction != "HTA" {
                return base.execute(req);
            }
            with_constant(req, base, "LEN", |k| (2 * k).min(255))
        }),
        // HTA ends its text with 00H.
        Mutant::new("hta-terminated", &base, |req, base| {
            let end = device(req, "OUT").and_then(|d| d.offset(len(req)));
            let hta = req.instruction == "HTA";
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d)) = (hta, end) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
    ];
    assert_corpus_kills(&project, &base, &mutants);
}
