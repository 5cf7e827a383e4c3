//! Reference model of the FX3-style ASCI and HEX: Mitsubishi FX3 (FNC 82/83) and Delta DVP
//! (API 82/83), which copies them with other flag numbers.
//!
//! Rules and their evidence are in `docs/semantics.md#fx3-asci-hex` and
//! `docs/semantics.md#delta-asci-hex`. The conversions are the FX5's ([`super::fx5`], whose
//! HEXA rules were read from this very FX3 page): the lowest n digits, most significant first,
//! two characters per word low byte first or one per word by the mode flag; HEX right-justified.
//! Where the FX3 parts from the FX5: ASCI writes nothing after the last character (there is no
//! SM701), n is 1 to 256, and every error is an operation error that turns on one flag (M8067,
//! M1067 on the Delta) and writes nothing. What a family varies is the [`Dialect`]: its profile
//! and its flags.

use std::marker::PhantomData;

use super::fx5::{asci_digits, asci_source_words, asci_stores, hex_chars, hex_words, Packing};
use super::reference::{constant_word, Model, Stop};
use super::{Outcome, Request, Unsupported};
use crate::memory::Scratch;
use crate::model::Operand;

/// What an FX3-style family names its own way.
pub trait Dialect: Send + Sync + 'static {
    /// The profile.
    const PROFILE: &'static str;
    /// The flag that chooses 8-bit mode (M8161, M1161).
    const MODE_FLAG: &'static str;
}

/// Mitsubishi FX3 series.
pub struct Fx3;

impl Dialect for Fx3 {
    const PROFILE: &'static str = "mitsubishi-fx3";
    const MODE_FLAG: &'static str = "M8161";
}

/// Delta DVP, the FX3 clone.
pub struct Delta;

impl Dialect for Delta {
    const PROFILE: &'static str = "delta-dvp";
    const MODE_FLAG: &'static str = "M1161";
}

/// The most characters ASCI and HEX convert: n = 1 to 256.
pub const MAX_CHARS: u32 = 256;

/// What the model passes as the error code: these families show an operation error as one flag,
/// so the profile turns any code into it and this value never reaches a comparison. It is the
/// FX3's string-data operation error, K6706.
const OPERATION_ERROR: u16 = 6706;

/// The ASCI/HEX reference model of an FX3-style family.
pub struct AsciHex<D>(PhantomData<D>);

#[derive(Debug, Clone, Copy)]
enum Op {
    Asci,
    Hex,
}

fn op(instruction: &str) -> Option<Op> {
    match instruction {
        "ASCI" | "ASCIP" => Some(Op::Asci),
        "HEX" | "HEXP" => Some(Op::Hex),
        _ => None,
    }
}

impl<D: Dialect> Model for AsciHex<D> {
    const PROFILE: &'static str = D::PROFILE;

    fn models(instruction: &str) -> bool {
        op(instruction).is_some()
    }

    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        let packing = Packing::from_sm8161(req.flag(D::MODE_FLAG));
        match op(req.instruction) {
            Some(Op::Asci) => asci(req, packing),
            Some(Op::Hex) => hex(req, packing),
            None => Err(Unsupported(format!("{} is not modelled", req.instruction)).into()),
        }
    }
}

/// n, read as 16-bit unsigned and checked for 1..256.
fn count(req: &Request<'_>) -> Result<u32, Stop> {
    let n = match req.operand("n")? {
        Operand::Constant(k) => constant_word("n", *k)?,
        Operand::Device(dev) => {
            if !req.words_exist(dev, 1) {
                return Err(Stop::Error(OPERATION_ERROR));
            }
            req.memory.read(dev)
        }
    };
    let n = u32::from(n);
    if (1..=MAX_CHARS).contains(&n) {
        Ok(n)
    } else {
        Err(Stop::Error(OPERATION_ERROR))
    }
}

/// ASCI: hex code at (s) -> n ASCII characters at (d), nothing after them.
fn asci(req: &Request<'_>, packing: Packing) -> Result<Outcome, Stop> {
    let n = count(req)?;
    let source: Vec<u16> = match req.operand("s")? {
        Operand::Constant(k) => vec![constant_word("s", *k)?],
        Operand::Device(s) => {
            let words = asci_source_words(n);
            if !req.words_exist(s, words) {
                return Err(Stop::Error(OPERATION_ERROR));
            }
            (0..words)
                .filter_map(|i| s.offset(i))
                .map(|dev| req.memory.read(&dev))
                .collect()
        }
    };
    let d = req.device("d")?;
    if !req.words_exist(d, packing.words_for(n)) {
        return Err(Stop::Error(OPERATION_ERROR));
    }
    let mut out = Scratch::new(req.memory);
    for (i, store) in asci_stores(&asci_digits(&source, n), packing, false)
        .into_iter()
        .enumerate()
    {
        if let Some(dev) = d.offset(i as u32) {
            let old = out.read(&dev);
            out.write(dev, store.apply(old));
        }
    }
    Ok(Outcome {
        writes: out.into_writes(),
        error: None,
    })
}

/// HEX: n ASCII characters at (s) -> hex code at (d), right-justified.
fn hex(req: &Request<'_>, packing: Packing) -> Result<Outcome, Stop> {
    let n = count(req)?;
    let s = req.device("s")?;
    let d = req.device("d")?;
    if !req.words_exist(s, packing.words_for(n)) || !req.words_exist(d, n.div_ceil(4)) {
        return Err(Stop::Error(OPERATION_ERROR));
    }
    let words = hex_words(&hex_chars(req.memory, s, n, packing))
        .map_err(|_| Stop::Error(OPERATION_ERROR))?;
    let mut out = Scratch::new(req.memory);
    for (i, word) in words.into_iter().enumerate() {
        if let Some(dev) = d.offset(i as u32) {
            out.write(dev, word);
        }
    }
    Ok(Outcome {
        writes: out.into_writes(),
        error: None,
    })
}
