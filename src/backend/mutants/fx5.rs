//! Teeth for the FX5 corpus: plausible wrong implementations of ASCI(P) and HEXA(P), each the
//! reference model with one behaviour changed, and a check that some vector catches each one.
//! A survivor means the corpus has a gap: add the vector that tells it apart from the manual.

#[cfg(test)]
use std::collections::BTreeMap;
use std::sync::Arc;

use super::{assert_kills_counted, Mutant};
use super::{device, with_bytes, with_d_last, with_flag, with_operands, with_units, Answer};
use crate::backend::fx5::{self, Packing};
use crate::Device;
use crate::{Backend, Outcome, Request, Response};
use crate::{ErrorSignal, Operand};

fn is_asci(req: &Request<'_>) -> bool {
    req.instruction.starts_with("ASCI")
}

fn eight_bit(req: &Request<'_>) -> bool {
    req.flag("SM8161")
}

/// n as the instruction reads it, 16-bit unsigned.
fn n_of(req: &Request<'_>) -> Option<u32> {
    match req.operands.get("n")? {
        Operand::Constant(k) => Some((*k as u16).into()),
        Operand::Device(d) => Some(req.memory.read(d)),
    }
}

/// The base model run as a backend that takes unit k of an (s) or (d) head to be the word
/// `wrong(head, k)` (`None`: the head is one it reads right): the right model is given that
/// word where it reads unit k, and its writes are moved back to where the wrong one puts them.
fn units_elsewhere(
    req: &Request<'_>,
    base: &dyn Backend,
    wrong: impl Fn(&Device, u32) -> Option<Device>,
) -> Answer {
    let heads: Vec<Device> = ["s", "d"]
        .into_iter()
        .filter_map(|name| device(req, name))
        .filter(|d| wrong(d, 1).is_some())
        .collect();
    if heads.is_empty() {
        return base.execute(req);
    }
    let mut words = req.memory.explicit().clone();
    for head in &heads {
        for k in 1..64 {
            if let (Some(unit), Some(there)) = (head.offset(k), wrong(head, k)) {
                words.insert(unit, req.memory.read(&there));
            }
        }
    }
    let answer = with_units(req, base, words)?;
    let Response::Done(mut o) = answer else {
        return Ok(answer);
    };
    let mut moved = BTreeMap::new();
    for (dev, value) in std::mem::take(&mut o.writes) {
        let there = heads.iter().find_map(|h| {
            (0..64).find_map(|k| (h.offset(k).as_ref() == Some(&dev)).then(|| wrong(h, k))?)
        });
        moved.insert(there.unwrap_or(dev), value);
    }
    o.writes = moved;
    Ok(Response::Done(o))
}

/// The base model's answer with its outcome changed (when it did run).
fn reshape(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl Fn(&Request<'_>, Outcome) -> Outcome,
) -> Answer {
    match base.execute(req)? {
        Response::Done(outcome) => Ok(Response::Done(f(req, outcome))),
        other => Ok(other),
    }
}

/// The base model run with one flag forced for ASCI (`asci`) or for HEXA (`!asci`); the other
/// instruction runs as it is.
fn with_flag_for(
    req: &Request<'_>,
    base: &dyn Backend,
    asci: bool,
    flag: &str,
    on: bool,
) -> Answer {
    if is_asci(req) == asci {
        with_flag(req, base, flag, on)
    } else {
        base.execute(req)
    }
}

/// The base model run on a variant whose data registers end `delta` words later.
fn with_d_range(req: &Request<'_>, base: &dyn Backend, delta: i64) -> Answer {
    with_d_last(req, base, |last| (i64::from(last) + delta).max(0) as u32)
}

fn code(outcome: &Outcome) -> Option<u16> {
    match outcome.error {
        Some(ErrorSignal::Code(c)) => Some(c),
        _ => None,
    }
}

/// ASCI's device range error answered instead by a run on data registers `delta` words longer,
/// where the destination words for n characters (and a terminator, with `terminator`) do exist:
/// a backend whose range check counts other words than the model's.
fn asci_range_error_passed(
    req: &Request<'_>,
    base: &dyn Backend,
    terminator: bool,
    delta: i64,
) -> Answer {
    let answer = base.execute(req)?;
    let (Some(n), Some(d)) = (n_of(req), device(req, "d")) else {
        return Ok(answer);
    };
    let packing = Packing::from_sm8161(eight_bit(req));
    let dest = fx5::asci_destination_words(n, packing, terminator);
    match &answer {
        Response::Done(o)
            if is_asci(req)
                && code(o) == Some(fx5::ERR_DEVICE_RANGE)
                && req.words_exist(&d, dest) =>
        {
            with_d_range(req, base, delta)
        }
        _ => Ok(answer),
    }
}

/// Where ASCI's i-th character goes: the word, and whether it is the high byte.
fn slot(d: &Device, i: u32, eight: bool) -> Option<(Device, bool)> {
    if eight {
        Some((d.offset(i)?, false))
    } else {
        Some((d.offset(i / 2)?, i % 2 == 1))
    }
}

/// ASCI's outcome with its n characters replaced by `f(characters)`.
fn map_chars(
    req: &Request<'_>,
    outcome: Outcome,
    f: impl Fn(&Request<'_>, Vec<u8>) -> Vec<u8>,
) -> Outcome {
    let (Some(d), Some(n)) = (device(req, "d"), n_of(req)) else {
        return outcome;
    };
    if outcome.error.is_some() || !is_asci(req) {
        return outcome;
    }
    let eight = eight_bit(req);
    let mut writes = outcome.writes.clone();
    let read = |writes: &BTreeMap<Device, u32>, dev: &Device| {
        writes
            .get(dev)
            .copied()
            .unwrap_or_else(|| req.memory.read(dev))
    };
    let chars: Vec<u8> = (0..n)
        .filter_map(|i| slot(&d, i, eight))
        .map(|(dev, high)| {
            let w = read(&writes, &dev);
            if high {
                (w >> 8) as u8
            } else {
                w as u8
            }
        })
        .collect();
    for (i, ch) in f(req, chars).into_iter().enumerate() {
        if let Some((dev, high)) = slot(&d, i as u32, eight) {
            let w = read(&writes, &dev);
            let new = if high {
                (w & 0x00FF) | u32::from(ch) << 8
            } else {
                (w & 0xFF00) | u32::from(ch)
            };
            writes.insert(dev, new);
        }
    }
    Outcome { writes, ..outcome }
}

/// The source words ASCI reads: a constant, or ceil(n/4) words from (s).
fn asci_source(req: &Request<'_>, n: u32) -> Vec<u16> {
    match req.operands.get("s") {
        Some(Operand::Constant(k)) => vec![*k as u16],
        Some(Operand::Device(s)) => (0..fx5::asci_source_words(n))
            .filter_map(|i| s.offset(i))
            .map(|dev| req.memory.word(&dev))
            .collect(),
        None => Vec::new(),
    }
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        Mutant::new("asci-digits-least-significant-first", base, |req, b| {
            reshape(req, b, |req, o| {
                map_chars(req, o, |_, mut c| {
                    c.reverse();
                    c
                })
            })
        }),
        Mutant::new("asci-digits-from-the-top-of-the-words", base, |req, b| {
            reshape(req, b, |req, o| {
                map_chars(req, o, |req, c| {
                    let n = c.len() as u32;
                    let words = asci_source(req, n);
                    let all = fx5::asci_digits(&words, 4 * n.div_ceil(4));
                    all[..n as usize].to_vec()
                })
            })
        }),
        Mutant::new("asci-writes-lowercase", base, |req, b| {
            reshape(req, b, |req, o| {
                map_chars(req, o, |_, c| c.to_ascii_lowercase())
            })
        }),
        Mutant::new("asci-first-character-in-high-byte", base, |req, b| {
            reshape(req, b, |req, mut o| {
                if is_asci(req) && !eight_bit(req) {
                    o.writes.values_mut().for_each(|w| *w = w.swap_bytes());
                }
                o
            })
        }),
        Mutant::new("asci-terminator-despite-sm701-on", base, |req, b| {
            with_flag_for(req, b, true, "SM701", false)
        }),
        Mutant::new("asci-no-terminator-with-sm701-off", base, |req, b| {
            with_flag_for(req, b, true, "SM701", true)
        }),
        Mutant::new("asci-odd-count-clears-kept-high-byte", base, |req, b| {
            reshape(req, b, |req, mut o| {
                let odd = n_of(req).is_some_and(|n| n % 2 == 1);
                if is_asci(req) && !eight_bit(req) && req.flag("SM701") && odd {
                    if let Some(last) = o.writes.keys().next_back().cloned() {
                        o.writes.entry(last).and_modify(|w| *w &= 0x00FF);
                    }
                }
                o
            })
        }),
        Mutant::new("asci-8bit-keeps-old-high-byte", base, |req, b| {
            reshape(req, b, |req, mut o| {
                if is_asci(req) && eight_bit(req) {
                    for (dev, w) in o.writes.iter_mut() {
                        *w = (req.memory.read(dev) & 0xFF00) | (*w & 0x00FF);
                    }
                }
                o
            })
        }),
        Mutant::new("asci-8bit-character-in-both-bytes", base, |req, b| {
            reshape(req, b, |req, mut o| {
                if is_asci(req) && eight_bit(req) {
                    o.writes.values_mut().for_each(|w| *w |= *w << 8);
                }
                o
            })
        }),
        Mutant::new("asci-ignores-sm8161", base, |req, b| {
            with_flag_for(req, b, true, "SM8161", false)
        }),
        Mutant::new("hexa-ignores-sm8161", base, |req, b| {
            with_flag_for(req, b, false, "SM8161", false)
        }),
        Mutant::new("n-zero-accepted", base, |req, b| {
            if n_of(req) == Some(0) {
                Ok(Response::Done(Outcome::default()))
            } else {
                b.execute(req)
            }
        }),
        Mutant::new("n-read-as-15-bits", base, |req, b| {
            let Some(n) = n_of(req) else {
                return b.execute(req);
            };
            with_operands(req, b, &[("n", Operand::Constant(i64::from(n & 0x7FFF)))])
        }),
        // Without the upper bound, n > 32767 can never fit D0-D7999: the range check answers.
        Mutant::new("n-upper-bound-missing", base, |req, b| {
            if n_of(req).is_some_and(|n| n > fx5::MAX_CHARS) {
                Ok(Response::Done(Outcome::error(
                    req.error(fx5::ERR_DEVICE_RANGE),
                )))
            } else {
                b.execute(req)
            }
        }),
        Mutant::new("range-check-allows-one-word-too-many", base, |req, b| {
            with_d_range(req, b, 1)
        }),
        Mutant::new("range-check-one-word-short", base, |req, b| {
            with_d_range(req, b, -1)
        }),
        Mutant::new("asci-source-range-unchecked", base, |req, b| {
            asci_range_error_passed(req, b, !req.flag("SM701"), 10_000)
        }),
        Mutant::new("asci-range-check-forgets-the-terminator", base, |req, b| {
            asci_range_error_passed(req, b, false, 1)
        }),
        // Each word's 4 characters as they come, the last word padded with 0 below its digits.
        Mutant::new("hexa-left-justified", base, |req, b| {
            hexa_words(req, b, |group| {
                let mut digits = group.to_vec();
                digits.resize(4, b'0');
                digits
            })
        }),
        // The MELSEC-Q/iQ-R HEX(P) order: the first character of each word in its lowest digit
        // ("4321" is 1234H), the last word padded with 0 above its digits.
        Mutant::new("hexa-reversed-like-iqr-hex", base, |req, b| {
            hexa_words(req, b, |group| {
                let mut digits = vec![b'0'; 4 - group.len()];
                digits.extend(group.iter().rev());
                digits
            })
        }),
        Mutant::new("hexa-accepts-lowercase", base, |req, b| {
            if is_asci(req) {
                return b.execute(req);
            }
            with_bytes(req, b, |c| c.to_ascii_uppercase())
        }),
        Mutant::new("hexa-keeps-old-high-digits", base, |req, b| {
            reshape(req, b, |req, mut o| {
                let Some(n) = n_of(req) else { return o };
                if is_asci(req) || o.error.is_some() || n % 4 == 0 {
                    return o;
                }
                let mask: u32 = (1 << (4 * (n % 4))) - 1;
                if let Some((dev, w)) = o.writes.iter_mut().next_back() {
                    *w = (req.memory.read(dev) & !mask) | (*w & mask);
                }
                o
            })
        }),
        Mutant::new("hexa-clears-the-next-word", base, |req, b| {
            reshape(req, b, |req, mut o| {
                let (Some(d), Some(n)) = (device(req, "d"), n_of(req)) else {
                    return o;
                };
                if !is_asci(req) && o.error.is_none() {
                    if let Some(dev) = d.offset(fx5::hex_destination_words(n)) {
                        o.writes.insert(dev, 0);
                    }
                }
                o
            })
        }),
        Mutant::new("hexa-8bit-checks-the-high-byte", base, |req, b| {
            reshape(req, b, |req, o| {
                let (Some(s), Some(n)) = (device(req, "s"), n_of(req)) else {
                    return o;
                };
                let dirty = (0..n)
                    .filter_map(|i| s.offset(i))
                    .any(|dev| req.memory.read(&dev) >> 8 != 0);
                if !is_asci(req) && eight_bit(req) && o.error.is_none() && dirty {
                    Outcome::error(req.error(fx5::ERR_INVALID_DATA))
                } else {
                    o
                }
            })
        }),
        Mutant::new("hexa-odd-count-reads-whole-last-word", base, |req, b| {
            let Some(n) = n_of(req) else {
                return b.execute(req);
            };
            if is_asci(req) || eight_bit(req) || n % 2 == 0 || n >= fx5::MAX_CHARS {
                return b.execute(req);
            }
            let wide = with_operands(req, b, &[("n", Operand::Constant(i64::from(n + 1)))])?;
            match wide {
                Response::Done(o) if code(&o) == Some(fx5::ERR_INVALID_DATA) => {
                    Ok(Response::Done(o))
                }
                _ => b.execute(req),
            }
        }),
        // A digit-designated operand's next word taken one point on (K4M1 after K4M0), as a
        // backend that steps device numbers by one for every code would.
        Mutant::new("digit-designation-one-point-apart", base, |req, b| {
            units_elsewhere(req, b, |head, k| {
                (head.points() > 1).then(|| head.with_index(head.index + k))
            })
        }),
        // A hexadecimal-numbered operand stepped in decimal (W10 after W9, for WA), as a
        // backend that reads every device number as decimal would.
        Mutant::new("hexadecimal-numbers-stepped-in-decimal", base, |req, b| {
            units_elsewhere(req, b, |head, k| {
                let decimal: u32 = format!("{:X}", head.index).parse().ok()?;
                let text = (decimal + k * head.points()).to_string();
                let index = u32::from_str_radix(&text, 16).ok()?;
                head.is_hexadecimal().then(|| head.with_index(index))
            })
        }),
        // An operand given by indirect specification taken to be its pointer (`@D10` read as
        // D10), as a backend that drops the `@` would.
        Mutant::new("pointer-taken-for-the-operand", base, |req, b| {
            let mut operands = req.operands.clone();
            for (name, pointer) in req.indirect {
                operands.insert(name.clone(), Operand::Device(pointer.clone()));
            }
            b.execute(&Request {
                operands: &operands,
                ..*req
            })
        }),
        Mutant::new("destination-written-on-error", base, |req, b| {
            reshape(req, b, |req, mut o| {
                if let (Some(_), Some(d)) = (&o.error, device(req, "d")) {
                    o.writes.insert(d, 0);
                }
                o
            })
        }),
        Mutant::new("count-and-range-codes-swapped", base, |req, b| {
            reshape(req, b, |req, o| match code(&o) {
                Some(fx5::ERR_COUNT) => Outcome::error(req.error(fx5::ERR_DEVICE_RANGE)),
                Some(fx5::ERR_DEVICE_RANGE) => Outcome::error(req.error(fx5::ERR_COUNT)),
                _ => o,
            })
        }),
        // SD0 right, but the FX-compatible SD8067 not written (or written only on ASCI).
        Mutant::new("sd8067-not-written", base, |req, b| {
            reshape(req, b, |_, mut o| {
                o.registers.remove(&"SD8067".parse().expect("SD8067"));
                o
            })
        }),
        Mutant::new("sd8067-only-for-asci", base, |req, b| {
            reshape(req, b, |req, mut o| {
                if !is_asci(req) {
                    o.registers.remove(&"SD8067".parse().expect("SD8067"));
                }
                o
            })
        }),
        Mutant::new("hexa-invalid-character-as-3405h", base, |req, b| {
            reshape(req, b, |req, o| match code(&o) {
                Some(fx5::ERR_INVALID_DATA) => Outcome::error(req.error(fx5::ERR_COUNT)),
                _ => o,
            })
        }),
    ]
}

#[test]
fn the_fx5_corpus_catches_every_wrong_model() {
    assert_kills_counted(fx5::PROFILE, |base| {
        let mutants = mutants(base);
        assert!(mutants.len() >= 10);
        mutants
    });
}

/// HEXA's result rebuilt by a mutant: the characters read as the model reads them, in groups of
/// 4 (one word each), each group turned into the 4 digits `word` makes of it.
fn hexa_words(req: &Request<'_>, b: &dyn Backend, word: impl Fn(&[u8]) -> Vec<u8>) -> Answer {
    reshape(req, b, |req, o| {
        let (Some(s), Some(d), Some(n)) = (device(req, "s"), device(req, "d"), n_of(req)) else {
            return o;
        };
        if is_asci(req) || o.error.is_some() {
            return o;
        }
        let packing = Packing::from_sm8161(eight_bit(req));
        let chars = fx5::hex_chars(req.memory, &s, n, packing);
        let mut writes = BTreeMap::new();
        for (i, group) in chars.chunks(4).enumerate() {
            if let (Ok(w), Some(dev)) = (fx5::hex_words(&word(group)), d.offset(i as u32)) {
                writes.insert(dev, u32::from(w[0]));
            }
        }
        Outcome { writes, ..o }
    })
}
