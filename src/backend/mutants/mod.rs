//! Teeth for the corpus: each reference model held to the corpus by mutation. Every file here
//! builds deliberately wrong backends around one family's reference model, each with one
//! behaviour changed, and checks that the corpus tells each of them apart from the manual; this
//! module holds what they share.

#[cfg(test)]
pub(super) use crate::test_support::{
    assert_corpus_kills, failing_trials, map_done, reference, session, with_constant, with_memory,
    Mutant,
};

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::spec::profile::DeviceRanges;
use crate::{Backend, Device, Fault, Image, Operand, Outcome, Request, Response, Value};

/// What a backend answers a request.
type Answer = Result<Response, Fault>;

mod fc4a;
mod fp;
mod fx3;
mod fx5;
mod iqr;
mod kv;
mod omron;
mod s7;
mod s7_200;

/// Asserts that the corpus passes the reference model of `profile` and kills every mutant
/// `mutants` makes of it.
fn assert_kills(profile: &str, mutants: impl FnOnce(&Arc<dyn Backend>) -> Vec<Arc<dyn Backend>>) {
    let project = session();
    let base = reference(&project, profile);
    assert_corpus_kills(&project, &base, &mutants(&base));
}

/// As [`assert_kills`], after printing how many trials catch each mutant: which vectors do the
/// work.
fn assert_kills_counted(
    profile: &str,
    mutants: impl FnOnce(&Arc<dyn Backend>) -> Vec<Arc<dyn Backend>>,
) {
    let project = session();
    let base = reference(&project, profile);
    let mutants = mutants(&base);
    for m in &mutants {
        eprintln!(
            "{:<45} caught by {} trials",
            m.name(),
            failing_trials(&project, m).len()
        );
    }
    assert_corpus_kills(&project, &base, &mutants);
}

/// The mutants the two Siemens families (S7-1200 and S7-200) share, where their ATH and HTA
/// agree: each is a mistake a byte-array codec makes.
fn siemens_mutants(base: &Arc<dyn Backend>) -> Vec<Arc<dyn Backend>> {
    vec![
        // The two digits of each ATH byte the other way round.
        Mutant::new("ath-nibbles-swapped", base, |req, base| {
            map_writes(base.execute(req), req.instruction == "ATH", |v| {
                (v >> 4 | v << 4) & 0xFF
            })
        }),
        // HTA writes lowercase letters.
        Mutant::new("hta-lowercase", base, |req, base| {
            map_writes(base.execute(req), req.instruction == "HTA", hex_lower)
        }),
    ]
}

/// An operand as the device it names (`None` for a constant, or an operand the case omits).
fn device(req: &Request<'_>, name: &str) -> Option<Device> {
    match req.operands.get(name)? {
        Operand::Device(d) => Some(d.clone()),
        Operand::Constant(_) => None,
    }
}

/// A count operand: a constant (0 when it is negative or does not fit), or the unit it names; 0
/// when the case omits it.
fn count(req: &Request<'_>, name: &str) -> u32 {
    match req.operands.get(name) {
        Some(Operand::Constant(k)) => u32::try_from(*k).unwrap_or(0),
        Some(Operand::Device(d)) => req.memory.read(d),
        None => 0,
    }
}

/// The value of a word operand as the CPU reads it: a constant that fits 16 bits, or the word it
/// names.
fn word_of(req: &Request<'_>, name: &str) -> Option<u16> {
    match req.operands.get(name)? {
        Operand::Constant(k) => u16::try_from(*k).ok(),
        Operand::Device(d) => Some(req.memory.word(d)),
    }
}

/// Runs the base on the same request with some operands replaced.
fn with_operands(req: &Request<'_>, base: &dyn Backend, replace: &[(&str, Operand)]) -> Answer {
    let mut operands = req.operands.clone();
    for (name, op) in replace {
        operands.insert((*name).to_string(), op.clone());
    }
    base.execute(&Request {
        operands: &operands,
        ..*req
    })
}

/// Runs the base on the same request over other memory: `units` in place of the units the case
/// sets, over the same fill and with the same unit size.
fn with_units(req: &Request<'_>, base: &dyn Backend, units: BTreeMap<Device, Value>) -> Answer {
    let memory = Image::of_units(units, req.memory.fill(), req.memory.unit());
    base.execute(&Request {
        memory: &memory,
        ..*req
    })
}

/// Runs the base with IN's first `n` units (bytes, in the Siemens families) rewritten by `f`.
fn with_input(req: &Request<'_>, base: &dyn Backend, n: u32, f: impl Fn(u16) -> u16) -> Answer {
    let mut units = req.memory.explicit().clone();
    if let Some(input) = device(req, "IN") {
        for d in (0..n).filter_map(|k| input.offset(k)) {
            let b = req.memory.word(&d);
            units.insert(d, u32::from(f(b)));
        }
    }
    with_units(req, base, units)
}

/// A word with both its bytes rewritten by `f` (anything above them dropped).
fn map_bytes(word: Value, f: &impl Fn(u8) -> u8) -> Value {
    let [lo, hi, ..] = word.to_le_bytes();
    u32::from(u16::from_le_bytes([f(lo), f(hi)]))
}

/// Runs the base on the vector's words with every byte rewritten: how a backend that
/// misreads characters sees the source.
fn with_bytes(req: &Request<'_>, base: &dyn Backend, f: impl Fn(u8) -> u8) -> Answer {
    let words = req
        .memory
        .explicit()
        .iter()
        .map(|(d, w)| (d.clone(), map_bytes(*w, &f)))
        .collect();
    with_units(req, base, words)
}

/// Runs the base with a flag forced, as a backend that misreads the flag would.
fn with_flag(req: &Request<'_>, base: &dyn Backend, name: &str, value: bool) -> Answer {
    let mut flags = req.flags.clone();
    flags.insert(name.to_string(), value);
    base.execute(&Request {
        flags: &flags,
        ..*req
    })
}

/// Runs the base on a variant whose data registers (D) are `ranges`: a backend with a wrong
/// range check.
fn with_d_ranges(req: &Request<'_>, base: &dyn Backend, ranges: DeviceRanges) -> Answer {
    let mut variant = req.variant.clone();
    variant.devices.insert("D".into(), ranges);
    base.execute(&Request {
        variant: &variant,
        ..*req
    })
}

/// Runs the base with the last D register of the first range moved to `last(it)`.
fn with_d_last(req: &Request<'_>, base: &dyn Backend, last: impl Fn(u32) -> u32) -> Answer {
    let Some(mut ranges) = req.profile.ranges(req.variant, "D") else {
        return base.execute(req);
    };
    ranges.last = last(ranges.last);
    with_d_ranges(req, base, ranges)
}

/// The base's answer with its finished outcome changed by `f` when `on`.
fn map_done_if(answer: Answer, on: bool, f: impl FnOnce(Outcome) -> Outcome) -> Answer {
    if on {
        map_done(answer, f)
    } else {
        answer
    }
}

/// The base's answer with every unit it writes rewritten by `f` when `on`.
fn map_writes(answer: Answer, on: bool, f: impl Fn(Value) -> Value) -> Answer {
    map_done_if(answer, on, |mut o| {
        for v in o.writes.values_mut() {
            *v = f(*v);
        }
        o
    })
}

/// An operation error reported nowhere: the base's answer without its error signal.
fn without_error(req: &Request<'_>, base: &dyn Backend) -> Answer {
    map_done(base.execute(req), |mut o| {
        o.error = None;
        o
    })
}

/// A lowercase a-f read as its digit (the uppercase letter); any other byte as it is.
fn hex_upper(b: u16) -> u16 {
    if (0x61..=0x66).contains(&b) {
        b - 0x20
    } else {
        b
    }
}

/// Both bytes of a word through [`hex_upper`].
fn hex_upper_bytes(w: u16) -> u16 {
    hex_upper(w >> 8) << 8 | hex_upper(w & 0xFF)
}

/// An uppercase A-F written as its lowercase letter; any other unit as it is.
fn hex_lower(v: Value) -> Value {
    if (0x41..=0x46).contains(&v) {
        v + 0x20
    } else {
        v
    }
}
