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

use super::fx5::{asci_with, hex_with, Op, Packing, Rules};
use super::reference::{Model, Stop};
use super::{Outcome, Request, Unsupported};

/// What an FX3-style family names its own way.
pub(crate) trait Dialect: Send + Sync + 'static {
    /// The profile.
    const PROFILE: &'static str;
    /// The flag that chooses 8-bit mode (M8161, M1161).
    const MODE_FLAG: &'static str;
}

/// Mitsubishi FX3 series.
pub(crate) struct Fx3;

impl Dialect for Fx3 {
    const PROFILE: &'static str = "mitsubishi-fx3";
    const MODE_FLAG: &'static str = "M8161";
}

/// Delta DVP, the FX3 clone.
pub(crate) struct Delta;

impl Dialect for Delta {
    const PROFILE: &'static str = "delta-dvp";
    const MODE_FLAG: &'static str = "M1161";
}

/// The most characters ASCI and HEX convert: n = 1 to 256.
pub(crate) const MAX_CHARS: u32 = 256;

/// What the model passes as the error code: these families show an operation error as one flag,
/// so the profile turns any code into it and this value never reaches a comparison. It is the
/// FX3's string-data operation error, K6706.
const OPERATION_ERROR: u16 = 6706;

/// The ASCI/HEX reference model of an FX3-style family.
pub(crate) struct AsciHex<D>(PhantomData<D>);

/// The FX3's HEX (FNC 83), and its pulse form; the Delta DVP names it alike.
const HEX: [&str; 2] = ["HEX", "HEXP"];

impl<D: Dialect> Model for AsciHex<D> {
    const PROFILE: &'static str = D::PROFILE;

    fn models(instruction: &str) -> bool {
        Op::of(instruction, HEX).is_some()
    }

    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        let packing = Packing::from_sm8161(req.flag(D::MODE_FLAG));
        match Op::of(req.instruction, HEX) {
            Some(Op::Asci) => asci(req, packing),
            Some(Op::Hex) => hex(req, packing),
            None => Err(Unsupported(format!("{} is not modelled", req.instruction)).into()),
        }
    }
}

/// One operation error for every kind: the flag is what the program sees.
const RULES: Rules = Rules {
    max_chars: MAX_CHARS,
    range: OPERATION_ERROR,
    count: OPERATION_ERROR,
    invalid: OPERATION_ERROR,
};

/// ASCI: hex code at (s) -> n ASCII characters at (d), nothing after them.
fn asci(req: &Request<'_>, packing: Packing) -> Result<Outcome, Stop> {
    asci_with(req, packing, false, &RULES)
}

/// HEX: n ASCII characters at (s) -> hex code at (d), right-justified.
fn hex(req: &Request<'_>, packing: Packing) -> Result<Outcome, Stop> {
    hex_with(req, packing, &RULES)
}
