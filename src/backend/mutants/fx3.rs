//! Teeth for the FX3 and Delta DVP corpora: deliberately wrong ASCI/HEX implementations, each of
//! which some vector must tell apart from the manual. Most are the FX5's or the iQ-R's rules
//! where the FX3 parts from them (a NULL after the last character, n up to 32767), or what a
//! codec gets wrong (lowercase accepted, bytes swapped, the mode flag ignored). Both families
//! share one model, so both corpora face the same mutants.

#[cfg(test)]
use super::{assert_corpus_kills, map_done, reference, session, Mutant};
use super::{count, device, hex_upper_bytes, map_writes, with_flag, without_error};
use super::{with_constant, with_memory};
use crate::Operand;
use crate::{Backend, Request, Response};

fn is_hex(req: &Request<'_>) -> bool {
    req.instruction.starts_with("HEX")
}

fn mutants(
    base: &std::sync::Arc<dyn Backend>,
    mode_flag: &'static str,
) -> Vec<std::sync::Arc<dyn Backend>> {
    vec![
        // ASCI stores a NULL after the last character (the FX5 with SM701 off).
        Mutant::new("asci-terminated", base, move |req, base| {
            let (asci, n, eight) = (!is_hex(req), count(req, "n"), req.flag(mode_flag));
            let d = device(req, "d");
            map_done(base.execute(req), |mut o| {
                if let (true, Some(d), None) = (asci, d, &o.error) {
                    let at = if eight { n } else { n / 2 };
                    if let Some(dev) = d.offset(at) {
                        let old = o.writes.get(&dev).copied().unwrap_or(0);
                        let v = if !eight && n % 2 == 1 {
                            old & 0x00FF
                        } else {
                            0
                        };
                        o.writes.insert(dev, v);
                    }
                }
                o
            })
        }),
        // Two characters per word, the first in the high byte.
        Mutant::new("asci-high-byte-first", base, move |req, base| {
            let swap = !is_hex(req) && !req.flag(mode_flag);
            map_writes(base.execute(req), swap, u32::swap_bytes)
        }),
        // The mode flag ignored: always 16-bit mode.
        Mutant::new("mode-flag-ignored", base, move |req, base| {
            with_flag(req, base, mode_flag, false)
        }),
        // HEX reads lowercase a-f as digits.
        Mutant::new("hex-lowercase-accepted", base, |req, base| {
            if !is_hex(req) {
                return base.execute(req);
            }
            with_memory(req, base, hex_upper_bytes)
        }),
        // An invalid character converted and reported nowhere.
        Mutant::new("error-silent", base, without_error),
        // HEX keeps the old high digits of the last word instead of zeroing them.
        Mutant::new("hex-high-digits-kept", base, |req, base| {
            let (hex, n, d) = (is_hex(req), count(req, "n"), device(req, "d"));
            let last = d.and_then(|d| d.offset(n.div_ceil(4).saturating_sub(1)));
            let old = last.as_ref().map(|l| req.memory.read(l));
            map_done(base.execute(req), |mut o| {
                if let (true, Some(l), Some(old), 1..=3) = (hex, last, old, n % 4) {
                    let mask = (0xFFFFu32 << (4 * (n % 4))) & 0xFFFF;
                    if let Some(v) = o.writes.get_mut(&l) {
                        *v |= old & mask;
                    }
                }
                o
            })
        }),
        // n up to 32767, as the FX5: 257 converts 256 characters.
        Mutant::new("n-up-to-32767", base, |req, base| {
            with_constant(req, base, "n", |k| if k == 257 { 256 } else { k })
        }),
        // n = 0 converts nothing, without an error.
        Mutant::new("n-zero-silent", base, |req, base| {
            if matches!(req.operands.get("n"), Some(Operand::Constant(0))) {
                return Ok(Response::Done(Default::default()));
            }
            base.execute(req)
        }),
        // 8-bit mode reads the high byte as well (a high byte other than 0 is invalid).
        Mutant::new("hex-8bit-reads-high-byte", base, move |req, base| {
            let high = is_hex(req)
                && req.flag(mode_flag)
                && req
                    .memory
                    .explicit()
                    .values()
                    .any(|w| w >> 8 != 0 && w >> 8 != 0x5A);
            if high {
                return with_constant(req, base, "n", |_| 0);
            }
            base.execute(req)
        }),
    ]
}

#[test]
fn the_fx3_and_delta_corpora_kill_every_mutant() {
    let project = session();
    for (profile, flag) in [("mitsubishi-fx3", "M8161"), ("delta-dvp", "M1161")] {
        let base = reference(&project, profile);
        assert_corpus_kills(&project, &base, &mutants(&base, flag));
    }
}
