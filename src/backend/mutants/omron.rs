//! Teeth for the Omron corpus: deliberately wrong HEX/ASC implementations, each of which some
//! vector must tell apart from the manual. Each one is a mistake an emulator of the digit
//! designator makes: the first character in the highest digit (the MELSEC habit), the leftmost
//! byte first, no wrap-round, untouched digits or bytes cleared, lowercase taken or refused on
//! the wrong CPU models, parity ignored or inverted, the characters before a bad one written,
//! Di digits not checked, the data area not checked. Lowercase on CS/CJ/CP is no mutant: it is
//! the open question omron-hex-lowercase-cs-cj, whose probes record what a backend does rather
//! than judge it.

#[cfg(test)]
use std::collections::BTreeMap;
use std::sync::Arc;

use super::{assert_kills, map_done, Mutant};
use super::{device, map_writes, with_d_ranges, with_operands, with_units, without_error, word_of};
use crate::backend::omron::{Designator, Parity};
use crate::spec::profile::DeviceRanges;
use crate::Device;
use crate::Image;
use crate::Operand;
use crate::{Backend, Fault, Request, Response};

const PROFILE: &str = "omron-cs-cj";

/// The digit designator word as the case gives it.
fn di_word(req: &Request<'_>) -> Option<u16> {
    word_of(req, "Di")
}

/// The operand `name` as a device, with the designator Di decodes to, when it is one and Di
/// decodes.
fn designated(req: &Request<'_>, name: &str) -> Option<(Device, Designator)> {
    Some((
        device(req, name)?,
        di_word(req).and_then(Designator::decode)?,
    ))
}

/// Runs the base with Di replaced by a constant.
fn with_di(req: &Request<'_>, base: &dyn Backend, di: u16) -> Result<Response, Fault> {
    with_operands(req, base, &[("Di", Operand::Constant(i64::from(di)))])
}

/// Runs the base with memory rewritten by `f`.
fn with_memory(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl FnOnce(&mut BTreeMap<Device, u16>),
) -> Result<Response, Fault> {
    // Omron's channels are 16-bit words.
    let mut words: BTreeMap<Device, u16> = (req.memory.explicit().iter())
        .map(|(d, v)| (d.clone(), *v as u16))
        .collect();
    f(&mut words);
    let words = words.into_iter().map(|(d, v)| (d, u32::from(v))).collect();
    with_units(req, base, words)
}

/// The word and byte the `k`-th byte of a designator lives in, from `head`.
fn byte_place(di: &Designator, head: &Device, k: u32) -> Option<(Device, bool)> {
    let (offset, leftmost) = di.byte_at(k);
    head.offset(offset).map(|d| (d, leftmost))
}

fn get_byte(words: &BTreeMap<Device, u16>, memory: &Image, at: &(Device, bool)) -> u8 {
    let w = words
        .get(&at.0)
        .copied()
        .unwrap_or_else(|| memory.word(&at.0));
    if at.1 {
        (w >> 8) as u8
    } else {
        w as u8
    }
}

fn set_byte(words: &mut BTreeMap<Device, u16>, memory: &Image, at: &(Device, bool), b: u8) {
    let w = words
        .get(&at.0)
        .copied()
        .unwrap_or_else(|| memory.word(&at.0));
    let w = if at.1 {
        (w & 0x00FF) | (u16::from(b) << 8)
    } else {
        (w & 0xFF00) | u16::from(b)
    };
    words.insert(at.0.clone(), w);
}

/// Runs HEX with each source byte the designator reads rewritten by `f` (index, byte) -> byte.
fn hex_bytes(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl Fn(u32, u8) -> u8,
) -> Result<Response, Fault> {
    let Some((s, di)) = designated(req, "S") else {
        return base.execute(req);
    };
    with_memory(req, base, |words| {
        for k in 0..di.count {
            if let Some(at) = byte_place(&di, &s, k) {
                let b = get_byte(words, req.memory, &at);
                set_byte(words, req.memory, &at, f(k, b));
            }
        }
    })
}

fn lowercase(b: u8) -> bool {
    (0x61..=0x66).contains(&(b & 0x7F))
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    let hex = |req: &Request<'_>| req.instruction == "HEX";
    let asc = |req: &Request<'_>| req.instruction == "ASC";
    vec![
        // HEX puts the first character in the highest digit converted, as MELSEC does.
        Mutant::new("hex-first-character-highest", base, move |req, base| {
            if !hex(req) {
                return base.execute(req);
            }
            let Some((s, di)) = designated(req, "S") else {
                return base.execute(req);
            };
            with_memory(req, base, |words| {
                let places: Vec<_> = (0..di.count)
                    .filter_map(|k| byte_place(&di, &s, k))
                    .collect();
                let bytes: Vec<u8> = places
                    .iter()
                    .map(|at| get_byte(words, req.memory, at))
                    .collect();
                for (at, b) in places.iter().zip(bytes.iter().rev()) {
                    set_byte(words, req.memory, at, *b);
                }
            })
        }),
        // HEX reads the leftmost byte of a word first (text stored high byte first).
        Mutant::new("hex-leftmost-byte-first", base, move |req, base| {
            if !hex(req) {
                return base.execute(req);
            }
            let Some(s) = device(req, "S") else {
                return base.execute(req);
            };
            with_memory(req, base, |words| {
                for i in 0..3 {
                    if let Some(d) = s.offset(i) {
                        let w = words
                            .get(&d)
                            .copied()
                            .unwrap_or_else(|| req.memory.word(&d));
                        words.insert(d, w.rotate_left(8));
                    }
                }
            })
        }),
        // No wrap-round: digits past digit 3 are not converted (HEX) or not read (ASC).
        Mutant::new("no-wrap-round", base, |req, base| {
            match di_word(req).and_then(Designator::decode) {
                Some(di) if di.first_digit + di.count > 4 => {
                    let count = 4 - di.first_digit;
                    let word = di_word(req).unwrap_or(0);
                    with_di(req, base, (word & 0xFF0F) | (((count - 1) as u16) << 4))
                }
                _ => base.execute(req),
            }
        }),
        // HEX clears the digits it does not write.
        Mutant::new("hex-clears-other-digits", base, move |req, base| {
            let di = di_word(req).and_then(Designator::decode);
            let is_hex = hex(req);
            map_done(base.execute(req), |mut o| {
                if let (true, Some(di)) = (is_hex, di) {
                    let mask: u16 = (0..di.count).fold(0, |m, k| m | 0xF << (4 * di.digit_at(k)));
                    for v in o.writes.values_mut() {
                        *v &= u32::from(mask);
                    }
                }
                o
            })
        }),
        // HEX takes lowercase a-f on every CPU model.
        Mutant::new("hex-lowercase-everywhere", base, move |req, base| {
            if !hex(req) {
                return base.execute(req);
            }
            hex_bytes(req, base, |_, b| if lowercase(b) { b - 0x20 } else { b })
        }),
        // HEX refuses lowercase a-f on the C200H series too.
        Mutant::new("hex-lowercase-nowhere", base, move |req, base| {
            if !hex(req) || req.variant.id != "c200h" {
                return base.execute(req);
            }
            hex_bytes(req, base, |_, b| if lowercase(b) { b'G' } else { b })
        }),
        // HEX ignores the parity bit and the designated parity.
        Mutant::new("hex-parity-ignored", base, move |req, base| {
            if !hex(req) {
                return base.execute(req);
            }
            let word = di_word(req).unwrap_or(0);
            let mut operands = req.operands.clone();
            operands.insert("Di".into(), Operand::Constant(i64::from(word & 0x0FFF)));
            let req = Request {
                operands: &operands,
                ..*req
            };
            hex_bytes(&req, base, |_, b| b & 0x7F)
        }),
        // HEX with parity keeps the parity bit as part of the character (B1H is no digit).
        Mutant::new("hex-parity-bit-not-stripped", base, move |req, base| {
            let parity = di_word(req).and_then(Designator::decode).map(|d| d.parity);
            if !hex(req) || parity == Some(Parity::None) {
                return base.execute(req);
            }
            hex_bytes(req, base, |_, b| if b & 0x80 != 0 { b'G' } else { b })
        }),
        // HEX writes the characters before the first bad byte, then signals ER.
        Mutant::new("hex-partial-write-on-error", base, move |req, base| {
            let result = base.execute(req);
            let failed = matches!(&result, Ok(Response::Done(o)) if o.error.is_some());
            let (true, true, Some(word), Some(di)) = (
                hex(req),
                failed,
                di_word(req),
                di_word(req).and_then(Designator::decode),
            ) else {
                return result;
            };
            // The longest prefix that converts.
            let good = (1..di.count).rev().find(|n| {
                let shorter = (word & 0xFF0F) | (((n - 1) as u16) << 4);
                matches!(with_di(req, base, shorter), Ok(Response::Done(o)) if o.error.is_none())
            });
            match good {
                Some(n) => {
                    let shorter = (word & 0xFF0F) | (((n - 1) as u16) << 4);
                    let partial = with_di(req, base, shorter);
                    let flag = match &result {
                        Ok(Response::Done(o)) => o.error.clone(),
                        _ => None,
                    };
                    map_done(partial, |mut o| {
                        o.error = flag;
                        o
                    })
                }
                None => result,
            }
        }),
        // The digits of Di are masked into range instead of checked.
        Mutant::new("di-unchecked", base, |req, base| match di_word(req) {
            Some(word) if Designator::decode(word).is_none() => {
                let parity = if (word >> 12) > 2 { 0 } else { word >> 12 };
                let masked = (parity << 12) | (word & 0x0100) | (word & 0x0030) | (word & 0x0003);
                with_di(req, base, masked)
            }
            _ => base.execute(req),
        }),
        // The data area is not checked: words past D32767 read as the fill and are written.
        Mutant::new("no-data-area-check", base, |req, base| {
            with_d_ranges(
                req,
                base,
                DeviceRanges {
                    first: 0,
                    last: 65535,
                    also: Vec::new(),
                },
            )
        }),
        // The last word of the data area taken for past its end.
        Mutant::new("data-area-one-short", base, |req, base| {
            let Some(r) = req.profile.ranges(req.variant, "D") else {
                return base.execute(req);
            };
            with_d_ranges(
                req,
                base,
                DeviceRanges {
                    first: r.first,
                    last: r.last - 1,
                    also: Vec::new(),
                },
            )
        }),
        // ER is never signalled: an error writes nothing and says nothing.
        Mutant::new("er-silent", base, without_error),
        // ASC writes the highest digit first, as MELSEC BINHA does.
        Mutant::new("asc-first-digit-highest", base, move |req, base| {
            let (true, Some((s, di))) = (asc(req), designated(req, "S")) else {
                return base.execute(req);
            };
            with_memory(req, base, |words| {
                let v = words
                    .get(&s)
                    .copied()
                    .unwrap_or_else(|| req.memory.word(&s));
                let mut out = v;
                for k in 0..di.count {
                    let from = di.digit_at(di.count - 1 - k);
                    let to = di.digit_at(k);
                    let nibble = (v >> (4 * from)) & 0xF;
                    out = (out & !(0xF << (4 * to))) | (nibble << (4 * to));
                }
                words.insert(s, out);
            })
        }),
        // ASC starts at the other byte of D.
        Mutant::new("asc-first-byte-flipped", base, move |req, base| {
            match (asc(req), di_word(req)) {
                (true, Some(word)) if Designator::decode(word).is_some() => {
                    with_di(req, base, word ^ 0x0100)
                }
                _ => base.execute(req),
            }
        }),
        // ASC writes lowercase letters.
        Mutant::new("asc-lowercase", base, move |req, base| {
            map_writes(base.execute(req), asc(req), |v| {
                let [lo, hi] = (v as u16).to_le_bytes();
                let low = |b: u8| {
                    if (0x41..=0x46).contains(&(b & 0x7F)) {
                        b + 0x20
                    } else {
                        b
                    }
                };
                u32::from(u16::from_le_bytes([low(lo), low(hi)]))
            })
        }),
        // ASC clears the other byte of a word it writes in part.
        Mutant::new("asc-clears-other-byte", base, move |req, base| {
            let (true, Some((d, di))) = (asc(req), designated(req, "D")) else {
                return base.execute(req);
            };
            let places: Vec<(Device, bool)> = (0..di.count)
                .filter_map(|k| byte_place(&di, &d, k))
                .collect();
            map_done(base.execute(req), |mut o| {
                for (word, v) in o.writes.iter_mut() {
                    let high = places.iter().any(|(w, l)| w == word && *l);
                    let low = places.iter().any(|(w, l)| w == word && !*l);
                    if !high {
                        *v &= 0x00FF;
                    }
                    if !low {
                        *v &= 0xFF00;
                    }
                }
                o
            })
        }),
        // ASC never sets the parity bit.
        Mutant::new("asc-parity-ignored", base, move |req, base| {
            map_writes(base.execute(req), asc(req), |v| v & 0x7F7F)
        }),
        // ASC with even and odd parity the other way round.
        Mutant::new("asc-parity-inverted", base, move |req, base| {
            match (asc(req), di_word(req)) {
                (true, Some(word)) if matches!(word >> 12, 1 | 2) => {
                    with_di(req, base, word ^ 0x3000)
                }
                _ => base.execute(req),
            }
        }),
    ]
}

#[test]
fn the_omron_corpus_kills_every_mutant() {
    assert_kills(PROFILE, mutants);
}
