//! Teeth for the Siemens S7 corpus: deliberately wrong ATH/HTA implementations, each of which
//! some vector must tell apart from the manual. Each one is a mistake a byte-array codec makes:
//! the nibbles of a byte swapped, an invalid character that stops the conversion or is read as
//! F, an odd count that keeps the old low nibble, a missing RET_VAL, and so on. Lowercase
//! accepted is no mutant: it is the open question s7-ath-lowercase, whose probes record what a
//! backend does rather than judge it.

#[cfg(test)]
use std::collections::BTreeMap;

use super::{assert_corpus_kills, map_done, reference, session, Mutant};
use crate::Device;
use crate::Image;
use crate::{Backend, Fault, Request, Response};
use crate::{ErrorSignal, Operand};

const PROFILE: &str = "siemens-s7-1200";

fn device(req: &Request<'_>, name: &str) -> Option<Device> {
    match req.operands.get(name)? {
        Operand::Device(d) => Some(d.clone()),
        Operand::Constant(_) => None,
    }
}

fn count(req: &Request<'_>) -> u32 {
    match req.operands.get("N") {
        Some(Operand::Constant(k)) => u32::try_from(*k).unwrap_or(0),
        Some(Operand::Device(d)) => req.memory.read(d),
        None => 0,
    }
}

/// Runs the base with IN's characters rewritten by `f` (character index, byte) -> byte.
fn with_input(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl Fn(u32, u16) -> u16,
) -> Result<Response, Fault> {
    let mut bytes: BTreeMap<Device, u32> = req.memory.explicit().clone();
    if let Some(input) = device(req, "IN") {
        for k in 0..count(req) {
            if let Some(d) = input.offset(k) {
                let b = req.memory.word(&d);
                bytes.insert(d, u32::from(f(k, b)));
            }
        }
    }
    let memory = Image::of_units(bytes, req.memory.fill(), req.memory.unit());
    base.execute(&Request {
        memory: &memory,
        ..*req
    })
}

fn is_digit(b: u16) -> bool {
    matches!(b, 0x30..=0x39 | 0x41..=0x46)
}

#[test]
fn the_s7_corpus_kills_every_mutant() {
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
        // An invalid character stops the conversion: nothing written, as MELSEC does.
        Mutant::new("ath-invalid-writes-nothing", &base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error == Some(ErrorSignal::Code(0x0007)) {
                    o.writes.clear();
                }
                o
            })
        }),
        // An invalid character converted and reported nowhere.
        Mutant::new("ath-invalid-silent", &base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error == Some(ErrorSignal::Code(0x0007)) {
                    o.error = None;
                }
                o
            })
        }),
        // An invalid character read as F instead of 0.
        Mutant::new("ath-invalid-as-f", &base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            let out = with_input(
                req,
                base,
                |_, b| if is_digit(b) { b } else { u16::from(b'F') },
            );
            map_done(out, |mut o| {
                o.error = base.execute(req).ok().and_then(|r| match r {
                    Response::Done(o) => o.error,
                    _ => None,
                });
                o
            })
        }),
        // An odd count keeps the old low nibble of the last byte (the S7-200 rule).
        Mutant::new("ath-odd-keeps-nibble", &base, |req, base| {
            let (Some(out), n) = (device(req, "OUT"), count(req)) else {
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
            with_input(req, base, |_, b| (b >> 4 | b << 4) & 0xFF)
        }),
        // HTA ends its text with 00H.
        Mutant::new("hta-terminated", &base, |req, base| {
            let end = device(req, "OUT").and_then(|d| d.offset(2 * count(req)));
            let hta = req.instruction == "HTA";
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d), None) = (hta, end, &o.error) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
        // The buffer checks missing: the output written as far as the array goes.
        Mutant::new("no-buffer-check", &base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if matches!(o.error, Some(ErrorSignal::Code(0x8182 | 0x8382))) {
                    o.error = None;
                }
                o
            })
        }),
        // N read as a number of bytes for ATH (twice the characters).
        Mutant::new("ath-n-as-bytes", &base, |req, base| {
            if req.instruction != "ATH" {
                return base.execute(req);
            }
            let n = match req.operands.get("N") {
                Some(Operand::Constant(k)) => Operand::Constant(k * 2),
                _ => return base.execute(req),
            };
            let mut operands = req.operands.clone();
            operands.insert("N".into(), n);
            base.execute(&Request {
                operands: &operands,
                ..*req
            })
        }),
    ];
    assert_corpus_kills(&project, &base, &mutants);
}
