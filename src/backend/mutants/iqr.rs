//! Teeth for the MELSEC iQ-R corpus: each mutant below is the iQ-R reference model with one
//! plausible implementation mistake, and the corpus must tell every one of them apart from the
//! manual. A mutant that survives means a vector is missing, not that the mutant is unfair.

#[cfg(test)]
use std::collections::BTreeMap;
use std::sync::Arc;

use super::{assert_kills_counted, map_done, Mutant};
use super::{map_bytes, map_done_if, map_writes, with_bytes, with_d_last, with_flag, with_units};
use crate::Device;
use crate::{Backend, Outcome, Request};
use crate::{ErrorSignal, Operand};

/// HABIN(P) and DHABIN(P): text in, number out.
fn from_ascii(req: &Request<'_>) -> bool {
    matches!(req.instruction, "HABIN" | "HABINP" | "DHABIN" | "DHABINP")
}

/// BINHA(P) and DBINHA(P): number in, text out.
fn to_ascii(req: &Request<'_>) -> bool {
    matches!(req.instruction, "BINHA" | "BINHAP" | "DBINHA" | "DBINHAP")
}

fn double(req: &Request<'_>) -> bool {
    req.instruction.starts_with('D')
}

fn destination(req: &Request<'_>) -> Option<Device> {
    req.device("d").ok().cloned()
}

/// The written words from (d) on, as one number with (d) the least significant word.
fn result_words(req: &Request<'_>, o: &Outcome) -> Option<(Vec<Device>, u64)> {
    let d = destination(req)?;
    let count = if double(req) { 2 } else { 1 };
    let devices: Vec<Device> = (0..count).filter_map(|i| d.offset(i)).collect();
    let mut value = 0u64;
    for (i, dev) in devices.iter().enumerate() {
        value |= u64::from(*o.writes.get(dev)?) << (16 * i);
    }
    Some((devices, value))
}

fn mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    let mut out = vec![
        // --- reading characters -----------------------------------------------------------
        Mutant::new("accepts-lowercase", base, |req, base| {
            if !from_ascii(req) {
                return base.execute(req);
            }
            with_bytes(req, base, |b| match b {
                b'a'..=b'f' => b - 0x20,
                _ => b,
            })
        }),
        Mutant::new("masks-bit-7", base, |req, base| {
            if !from_ascii(req) {
                return base.execute(req);
            }
            with_bytes(req, base, |b| b & 0x7F)
        }),
        Mutant::new("fixed-mode-reads-00h-as-0", base, |req, base| {
            if !from_ascii(req) || req.flag("SM705") {
                return base.execute(req);
            }
            with_bytes(req, base, |b| if b == 0 { b'0' } else { b })
        }),
        Mutant::new("reads-high-byte-first", base, |req, base| {
            if !from_ascii(req) {
                return base.execute(req);
            }
            let words = req
                .memory
                .explicit()
                .iter()
                .map(|(d, w)| (d.clone(), w.swap_bytes()))
                .collect();
            with_units(req, base, words)
        }),
        Mutant::new("reads-digits-from-the-wrong-end", base, |req, base| {
            map_done_if(base.execute(req), from_ascii(req), |mut o| {
                if let Some((devices, value)) = result_words(req, &o) {
                    let nibbles = 4 * devices.len() as u32;
                    let reversed = (0..nibbles).fold(0u64, |acc, i| {
                        acc | ((value >> (4 * i)) & 0xF) << (4 * (nibbles - 1 - i))
                    });
                    for (i, dev) in devices.into_iter().enumerate() {
                        o.writes
                            .insert(dev, u32::from((reversed >> (16 * i)) as u16));
                    }
                }
                o
            })
        }),
        Mutant::new("dhabin-words-swapped", base, |req, base| {
            let on = from_ascii(req) && double(req);
            map_done_if(base.execute(req), on, |mut o| {
                if let Some((devices, value)) = result_words(req, &o) {
                    o.writes
                        .insert(devices[0].clone(), u32::from((value >> 16) as u16));
                    o.writes.insert(devices[1].clone(), u32::from(value as u16));
                }
                o
            })
        }),
        Mutant::new("double-forms-convert-16-bits", base, |req, base| {
            let single = match req.instruction {
                "DHABIN" => "HABIN",
                "DHABINP" => "HABINP",
                "DBINHA" => "BINHA",
                "DBINHAP" => "BINHAP",
                _ => return base.execute(req),
            };
            base.execute(&Request {
                instruction: single,
                ..*req
            })
        }),
        // --- writing characters -----------------------------------------------------------
        Mutant::new("writes-high-byte-first", base, |req, base| {
            map_writes(base.execute(req), to_ascii(req), u32::swap_bytes)
        }),
        Mutant::new("writes-lowercase", base, |req, base| {
            let lower = |b: u8| {
                if (b'A'..=b'F').contains(&b) {
                    b + 0x20
                } else {
                    b
                }
            };
            map_writes(base.execute(req), to_ascii(req), |w| map_bytes(w, &lower))
        }),
        Mutant::new("dbinha-source-words-swapped", base, |req, base| {
            let Ok(Operand::Device(s)) = req.operand("s") else {
                return base.execute(req);
            };
            let (Some(high), true) = (s.offset(1), to_ascii(req) && double(req)) else {
                return base.execute(req);
            };
            let mut words: BTreeMap<Device, u32> = req.memory.explicit().clone();
            words.insert(s.clone(), req.memory.read(&high));
            words.insert(high.clone(), req.memory.read(s));
            with_units(req, base, words)
        }),
        Mutant::new("terminator-low-byte-keeps-high-byte", base, |req, base| {
            let on = to_ascii(req) && req.flag("SM705");
            map_done_if(base.execute(req), on, |mut o| {
                if let Some((dev, word)) = o.writes.iter_mut().next_back() {
                    if *word == 0 {
                        *word = req.memory.read(dev) & 0xFF00;
                    }
                }
                o
            })
        }),
        Mutant::new(
            "short-result-unterminated-with-sm701-on",
            base,
            |req, base| {
                let on = to_ascii(req) && req.flag("SM705") && req.flag("SM701");
                map_done_if(base.execute(req), on, |mut o| {
                    if let Some((dev, word)) = o.writes.pop_last() {
                        let before = req.memory.read(&dev);
                        match (word & 0xFF, word >> 8) {
                            (0, _) => {}
                            (low, 0) => {
                                o.writes.insert(dev, (before & 0xFF00) | low);
                            }
                            _ => {
                                o.writes.insert(dev, word);
                            }
                        }
                    }
                    o
                })
            },
        ),
        // --- flags and firmware -----------------------------------------------------------
        Mutant::new("ignores-sm705", base, |req, base| {
            with_flag(req, base, "SM705", false)
        }),
        Mutant::new("sm705-always-on", base, |req, base| {
            with_flag(req, base, "SM705", true)
        }),
        Mutant::new("habin-ignores-sm705", base, |req, base| {
            if !from_ascii(req) {
                return base.execute(req);
            }
            with_flag(req, base, "SM705", false)
        }),
        Mutant::new("binha-keeps-leading-zeros-with-sm705", base, |req, base| {
            if !to_ascii(req) {
                return base.execute(req);
            }
            with_flag(req, base, "SM705", false)
        }),
        Mutant::new(
            "honours-sm705-without-firmware-support",
            base,
            |req, base| {
                let mut variant = req.variant.clone();
                variant.ignores_flags.clear();
                base.execute(&Request {
                    variant: &variant,
                    ..*req
                })
            },
        ),
        Mutant::new("terminator-despite-sm701-on", base, |req, base| {
            with_flag(req, base, "SM701", false)
        }),
        Mutant::new("no-terminator-with-sm701-off", base, |req, base| {
            with_flag(req, base, "SM701", true)
        }),
        // --- device range and errors ------------------------------------------------------
        Mutant::new("no-range-check", base, |req, base| {
            with_d_last(req, base, |_| u32::from(u16::MAX))
        }),
        Mutant::new("range-one-word-too-long", base, |req, base| {
            with_d_last(req, base, |last| last + 1)
        }),
        Mutant::new("range-one-word-too-short", base, |req, base| {
            with_d_last(req, base, |last| last - 1)
        }),
        Mutant::new("writes-destination-on-error", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if o.error.is_some() {
                    if let Some(d) = destination(req) {
                        o.writes.insert(d, 0);
                    }
                }
                o
            })
        }),
        // The code signalled, but SD0 left holding the error before it.
        Mutant::new("sd0-not-written", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                if let Some(sd0) = o.registers.get_mut(&"SD0".parse().expect("SD0")) {
                    *sd0 = 0;
                }
                o
            })
        }),
        Mutant::new("swaps-error-codes", base, |req, base| {
            map_done(base.execute(req), |mut o| {
                o.error = o.error.map(|e| match e {
                    ErrorSignal::Code(0x3401) => ErrorSignal::Code(0x2820),
                    ErrorSignal::Code(0x2820) => ErrorSignal::Code(0x3401),
                    other => other,
                });
                o
            })
        }),
    ];
    // Each neighbour of the digit ranges accepted as if it were '0'.
    for (name, byte) in [
        ("accepts-2fh", 0x2F),
        ("accepts-3ah", 0x3A),
        ("accepts-40h", 0x40),
        ("accepts-47h", 0x47),
        ("accepts-60h", 0x60),
        ("accepts-66h", 0x66),
    ] {
        out.push(Mutant::new(name, base, move |req, base| {
            if !from_ascii(req) {
                return base.execute(req);
            }
            with_bytes(req, base, |b| if b == byte { b'0' } else { b })
        }));
    }
    out
}

#[test]
fn the_iqr_corpus_kills_every_mutant() {
    assert_kills_counted("mitsubishi-iqr", mutants);
}
