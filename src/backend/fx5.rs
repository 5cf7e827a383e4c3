//! Reference model of MELSEC iQ-F FX5 ASCI(P) and HEXA(P).
//!
//! Rules and their evidence are in `docs/semantics.md#fx5-asci` and `docs/semantics.md#fx5-hexa`;
//! the corpus authors' summary is `vectors/mitsubishi-fx5/README.md`. ASCI writes the lowest n
//! hex digits of a multi-word source, most significant first; HEXA reads n characters and
//! stores the number they spell right-justified. SM8161 chooses two characters per word (16-bit
//! mode) or one (8-bit mode); SM701 decides whether ASCI stores a NULL after the last character.
//!
//! HEXA descends from the FX3 HEX (FNC 83), which is not the MELSEC Q/iQ-R instruction named
//! HEX: that one left-justifies, so nothing here is shared with `super::iqr`.
//!
//! Checks run in this order, and each stops the instruction before anything is written:
//! n (3405H), because the extent of (s) and (d) depends on it; then the words (s) and (d) occupy
//! (2820H); then, for HEXA, the characters (3401H). The manual does not fix the order between
//! the codes; vectors that break two rules at once are `unspecified`.

use super::reference::{constant_word, Model, Stop};
use super::{Outcome, Request, Unsupported};
use crate::device::Device;
use crate::memory::{Image, Scratch};
use crate::model::cross_vendor::TextLayout;
use crate::model::Operand;
use crate::text::{digit_char, digit_value};

/// The profile this model implements.
pub(crate) const PROFILE: &str = "mitsubishi-fx5";

/// A device past the end of its range (ASCI(P) error table).
pub(crate) const ERR_DEVICE_RANGE: u16 = 0x2820;
/// A character that is not a hex digit. The FX5 code for HEXA is not confirmed: 3401H is the
/// family's "invalid data" code (`docs/semantics.md#fx5-hexa-rules`, inferred).
pub(crate) const ERR_INVALID_DATA: u16 = 0x3401;
/// n outside 1 to 32767 (ASCI(P) error table, erratum 2: "(s)" there means (n)).
pub(crate) const ERR_COUNT: u16 = 0x3405;
/// The largest character count n.
pub(crate) const MAX_CHARS: u32 = 32767;

/// How characters are stored in words, chosen by SM8161.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Packing {
    /// 16-bit mode (SM8161 off): two characters per word, first in the low byte.
    TwoPerWord,
    /// 8-bit mode (SM8161 on): one character per word in the low byte, high byte 00H.
    OnePerWord,
}

impl Packing {
    pub(crate) fn from_sm8161(on: bool) -> Self {
        if on {
            Packing::OnePerWord
        } else {
            Packing::TwoPerWord
        }
    }

    /// The words that hold `chars` characters.
    pub(crate) fn words_for(self, chars: u32) -> u32 {
        match self {
            Packing::TwoPerWord => chars.div_ceil(2),
            Packing::OnePerWord => chars,
        }
    }
}

/// The words ASCI reads from (s): four hex digits per word.
pub(crate) fn asci_source_words(n: u32) -> u32 {
    n.div_ceil(4)
}

/// The words ASCI occupies at (d): the characters, and the NULL when SM701 is off. This is the
/// page's "number of devices occupied" table with erratum 3 applied (n / 2 rounds up; "n / 1"
/// with SM701 off in 8-bit mode is n + 1).
pub(crate) fn asci_destination_words(n: u32, packing: Packing, terminate: bool) -> u32 {
    packing.words_for(n + u32::from(terminate))
}

/// The characters ASCI writes: the lowest `n` hex digits of the number whose words are
/// `words` ((s) least significant), most significant digit first. Digits beyond the given
/// words are 0, which is how a constant source (one word) reads for n > 4.
pub(crate) fn asci_digits(words: &[u16], n: u32) -> Vec<u8> {
    (0..n)
        .rev()
        .map(|k| {
            let word = words.get((k / 4) as usize).copied().unwrap_or(0);
            digit_char(u64::from(word >> (4 * (k % 4))))
        })
        .collect()
}

/// One store into a destination word: the bits in `mask` take `value`, the rest keep the word's
/// old contents. A character count that ends in a low byte with SM701 on leaves the high byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Store {
    pub value: u16,
    pub mask: u16,
}

impl Store {
    fn word(value: u16) -> Self {
        Store {
            value,
            mask: 0xFFFF,
        }
    }

    pub(crate) fn apply(self, old: u16) -> u16 {
        (old & !self.mask) | (self.value & self.mask)
    }
}

/// The stores ASCI makes from (d) on, one per word: the characters, then the NULL unless
/// SM701 is on. In 16-bit mode a NULL that would land in a low byte takes the whole word
/// (0000H); in 8-bit mode it is the next word, 0000H.
pub(crate) fn asci_stores(chars: &[u8], packing: Packing, terminate: bool) -> Vec<Store> {
    let mut bytes = chars.to_vec();
    if terminate {
        bytes.push(0);
    }
    match packing {
        Packing::OnePerWord => bytes.into_iter().map(|c| Store::word(c.into())).collect(),
        Packing::TwoPerWord => {
            if terminate && bytes.len() % 2 == 1 {
                bytes.push(0);
            }
            bytes
                .chunks(2)
                .map(|pair| match pair {
                    [low, high] => Store::word(u16::from(*low) | u16::from(*high) << 8),
                    [low] => Store {
                        value: u16::from(*low),
                        mask: 0x00FF,
                    },
                    _ => Store::word(0),
                })
                .collect()
        }
    }
}

/// The `n` characters HEXA reads from (s) on: low then high byte of each word in 16-bit mode,
/// the low byte of each word in 8-bit mode (the high byte is not read).
pub(crate) fn hex_chars(memory: &Image, s: &Device, n: u32, packing: Packing) -> Vec<u8> {
    (0..n)
        .map(|k| match packing {
            Packing::TwoPerWord => TextLayout::Packed.char_in(memory, s, k).unwrap_or(0),
            Packing::OnePerWord => s.offset(k).map_or(0, |dev| memory.word(&dev) as u8),
        })
        .collect()
}

/// The words HEXA writes at (d): four digits per word.
pub(crate) fn hex_destination_words(n: u32) -> u32 {
    n.div_ceil(4)
}

/// The character at `position` (0 = first read) is not a hex digit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct InvalidChar {
    pub position: usize,
    pub byte: u8,
}

/// The number the characters spell, right-justified: the last character is the least
/// significant digit of (d), and the high digits of the last word written are 0.
pub(crate) fn hex_words(chars: &[u8]) -> Result<Vec<u16>, InvalidChar> {
    let mut words = vec![0u16; chars.len().div_ceil(4)];
    for (position, &byte) in chars.iter().enumerate() {
        let digit = digit_value(byte).ok_or(InvalidChar { position, byte })?;
        let k = chars.len() - 1 - position;
        words[k / 4] |= u16::from(digit) << (4 * (k % 4));
    }
    Ok(words)
}

/// The FX5 reference backend.
pub(crate) struct Fx5;

/// The two conversions an FX-style family models.
#[derive(Debug, Clone, Copy)]
pub(super) enum Op {
    Asci,
    Hex,
}

impl Op {
    /// The conversion `instruction` names, in a family whose HEX(A) and its pulse form are
    /// `hex`: every FX-style family says ASCI, but the FX5 says HEXA where the FX3 and the Delta
    /// DVP say HEX.
    pub(super) fn of(instruction: &str, hex: [&str; 2]) -> Option<Op> {
        match instruction {
            "ASCI" | "ASCIP" => Some(Op::Asci),
            _ if hex.contains(&instruction) => Some(Op::Hex),
            _ => None,
        }
    }
}

/// The FX5's HEX, and its pulse form.
const HEXA: [&str; 2] = ["HEXA", "HEXAP"];

impl Model for Fx5 {
    const PROFILE: &'static str = PROFILE;

    fn models(instruction: &str) -> bool {
        Op::of(instruction, HEXA).is_some()
    }

    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        match Op::of(req.instruction, HEXA) {
            Some(Op::Asci) => asci(req),
            Some(Op::Hex) => hex(req),
            None => Err(Unsupported(format!("{} is not modelled", req.instruction)).into()),
        }
    }
}

/// What an FX-style family varies in ASCI and HEX(A): the most characters and the error of each
/// kind (the FX3 and the Delta DVP give one operation error for all, [`super::fx3`]).
pub(super) struct Rules {
    pub max_chars: u32,
    pub range: u16,
    pub count: u16,
    pub invalid: u16,
}

/// The FX5's: n up to 32767, 2820H past a device range, 3405H for n, 3401H for a character.
const FX5: Rules = Rules {
    max_chars: MAX_CHARS,
    range: ERR_DEVICE_RANGE,
    count: ERR_COUNT,
    invalid: ERR_INVALID_DATA,
};

/// n, read as 16-bit unsigned (a D register holding 8000H is 32768) and checked for
/// 1..`max_chars`.
fn count(req: &Request<'_>, rules: &Rules) -> Result<u32, Stop> {
    let n = match req.operand("n")? {
        Operand::Constant(k) => constant_word("n", *k)?,
        Operand::Device(dev) => {
            if !req.words_exist(dev, 1) {
                return Err(Stop::Error(rules.range));
            }
            req.memory.word(dev)
        }
    };
    let n = u32::from(n);
    if (1..=rules.max_chars).contains(&n) {
        Ok(n)
    } else {
        Err(Stop::Error(rules.count))
    }
}

fn packing(req: &Request<'_>) -> Packing {
    Packing::from_sm8161(req.flag("SM8161"))
}

/// ASCI: hex code at (s) -> n ASCII characters at (d), and a NULL after them when SM701 is off.
fn asci(req: &Request<'_>) -> Result<Outcome, Stop> {
    asci_with(req, packing(req), !req.flag("SM701"), &FX5)
}

/// ASCI of an FX-style family: `terminate` stores a NULL after the last character.
pub(super) fn asci_with(
    req: &Request<'_>,
    packing: Packing,
    terminate: bool,
    rules: &Rules,
) -> Result<Outcome, Stop> {
    let n = count(req, rules)?;
    let source: Vec<u16> = match req.operand("s")? {
        Operand::Constant(k) => vec![constant_word("s", *k)?],
        Operand::Device(s) => {
            let words = asci_source_words(n);
            if !req.words_exist(s, words) {
                return Err(Stop::Error(rules.range));
            }
            (0..words)
                .filter_map(|i| s.offset(i))
                .map(|dev| req.memory.word(&dev))
                .collect()
        }
    };
    let d = req.device("d")?;
    if !req.words_exist(d, asci_destination_words(n, packing, terminate)) {
        return Err(Stop::Error(rules.range));
    }
    let stores = asci_stores(&asci_digits(&source, n), packing, terminate);
    let mut out = Scratch::new(req.memory);
    for (i, store) in stores.into_iter().enumerate() {
        if let Some(dev) = d.offset(i as u32) {
            let old = out.word(&dev);
            out.write(dev, store.apply(old));
        }
    }
    Ok(Outcome::written(out.into_writes()))
}

/// HEXA: n ASCII characters at (s) -> hex code at (d), right-justified.
fn hex(req: &Request<'_>) -> Result<Outcome, Stop> {
    hex_with(req, packing(req), &FX5)
}

/// HEX(A) of an FX-style family.
pub(super) fn hex_with(
    req: &Request<'_>,
    packing: Packing,
    rules: &Rules,
) -> Result<Outcome, Stop> {
    let n = count(req, rules)?;
    let s = req.device("s")?;
    if !req.words_exist(s, packing.words_for(n)) {
        return Err(Stop::Error(rules.range));
    }
    let d = req.device("d")?;
    if !req.words_exist(d, hex_destination_words(n)) {
        return Err(Stop::Error(rules.range));
    }
    let words =
        hex_words(&hex_chars(req.memory, s, n, packing)).map_err(|_| Stop::Error(rules.invalid))?;
    let mut out = Scratch::new(req.memory);
    for (i, word) in words.into_iter().enumerate() {
        if let Some(dev) = d.offset(i as u32) {
            out.write(dev, word);
        }
    }
    Ok(Outcome::written(out.into_writes()))
}

#[cfg(test)]
mod tests {
    //! Properties over every 16-bit value, through the backend as the runner calls it.

    use std::collections::BTreeMap;
    use std::path::Path;

    use super::*;
    use crate::backend::reference::Reference;
    use crate::backend::{Backend, Response};
    use crate::load::load_profiles;
    use crate::memory::{Fill, Value};
    use crate::model::profile::Profile;
    use crate::model::ErrorSignal;

    fn profile() -> Profile {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("vendors");
        let profiles = load_profiles(&dir).unwrap_or_else(|e| panic!("profiles do not load:\n{e}"));
        let p = profiles
            .get(PROFILE)
            .unwrap_or_else(|| panic!("no {PROFILE} profile"));
        p.as_ref().clone()
    }

    fn d(i: u32) -> Device {
        Device::new("D", i)
    }

    /// Runs one instruction on fx5u with D100 (and on) as the source and D200 as (d).
    struct Rig {
        profile: Profile,
        backend: Reference<Fx5>,
    }

    impl Rig {
        fn new() -> Self {
            let profile = profile();
            let backend = Reference::<Fx5>::new(&profile);
            Rig { profile, backend }
        }

        fn run(
            &self,
            instruction: &str,
            flags: &[(&str, bool)],
            n: i64,
            memory: &Image,
        ) -> Outcome {
            let variant = self
                .profile
                .variant("fx5u")
                .unwrap_or_else(|| panic!("no fx5u variant"));
            let flags: BTreeMap<String, bool> =
                flags.iter().map(|(f, on)| (f.to_string(), *on)).collect();
            let operands = BTreeMap::from([
                ("s".to_string(), Operand::Device(d(100))),
                ("d".to_string(), Operand::Device(d(200))),
                ("n".to_string(), Operand::Constant(n)),
            ]);
            let req = Request {
                profile: &self.profile,
                variant,
                instruction,
                case_id: "property",
                flags: &flags,
                operands: &operands,
                indirect: crate::model::DIRECT,
                memory,
            };
            match self.backend.execute(&req) {
                Ok(Response::Done(outcome)) => outcome,
                other => panic!("{instruction} did not run: {other:?}"),
            }
        }
    }

    fn image(words: impl IntoIterator<Item = (u32, u16)>, fill: Fill) -> Image {
        Image::new(
            (words.into_iter())
                .map(|(i, w)| (d(i), Value::from(w)))
                .collect(),
            fill,
        )
    }

    #[test]
    fn hex_inverts_asci_for_every_word_in_both_modes() {
        let rig = Rig::new();
        for sm8161 in [false, true] {
            let flags = [("SM8161", sm8161), ("SM701", false)];
            for x in 0..=u16::MAX {
                let asci = rig.run("ASCI", &flags, 4, &image([(100, x)], Fill::A));
                assert_eq!(asci.error, None, "ASCI {x:04X}H");
                // The characters, moved to the source of HEXA.
                let text = asci
                    .writes
                    .iter()
                    .map(|(dev, w)| (dev.index - 100, *w as u16))
                    .collect::<Vec<_>>();
                let back = rig.run("HEXA", &flags, 4, &image(text, Fill::A));
                assert_eq!(back.error, None, "HEXA of ASCI {x:04X}H");
                assert_eq!(
                    back.writes,
                    BTreeMap::from([(d(200), Value::from(x))]),
                    "HEXA(ASCI({x:04X}H)) with SM8161 {sm8161}"
                );
            }
        }
    }

    #[test]
    fn asci_writes_only_uppercase_digits_and_nulls() {
        let rig = Rig::new();
        for sm8161 in [false, true] {
            for sm701 in [false, true] {
                let flags = [("SM8161", sm8161), ("SM701", sm701)];
                for x in 0..=u16::MAX {
                    let out = rig.run("ASCI", &flags, 4, &image([(100, x)], Fill::A));
                    assert!(!out.writes.is_empty(), "ASCI {x:04X}H wrote nothing");
                    for (dev, word) in &out.writes {
                        for byte in word.to_le_bytes() {
                            assert!(
                                byte == 0 || b"0123456789ABCDEF".contains(&byte),
                                "ASCI {x:04X}H wrote {byte:02X}H in {dev} ({flags:?})"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn with_sm701_on_nothing_beyond_the_characters_is_written() {
        let rig = Rig::new();
        for sm8161 in [false, true] {
            let flags = [("SM8161", sm8161), ("SM701", true)];
            for x in 0..=u16::MAX {
                for n in 1..=4u32 {
                    let memory = image([(100, x)], Fill::A);
                    let out = rig.run("ASCI", &flags, i64::from(n), &memory);
                    let words = Packing::from_sm8161(sm8161).words_for(n);
                    for (dev, word) in &out.writes {
                        let old = memory.read(dev);
                        assert!(
                            (200..200 + words).contains(&dev.index),
                            "ASCI {x:04X}H K{n} wrote {dev} ({flags:?})"
                        );
                        // An odd count in 16-bit mode ends in a low byte.
                        let last_half = !sm8161 && n % 2 == 1 && dev.index == 200 + words - 1;
                        if last_half {
                            assert_eq!(word >> 8, old >> 8, "ASCI {x:04X}H K{n} in {dev}");
                        }
                    }
                    assert_eq!(out.writes.len(), words as usize, "ASCI {x:04X}H K{n}");
                }
            }
        }
    }

    #[test]
    fn the_seed_tables() {
        // D100=0ABCH, D101=1234H, D102=5678H; K9 -> "812340ABC" (ASCI(P) tables).
        let words = [0x0ABC, 0x1234, 0x5678];
        assert_eq!(asci_digits(&words, 4), b"0ABC");
        assert_eq!(asci_digits(&words, 9), b"812340ABC");
        assert_eq!(asci_digits(&words, 1), b"C");
        let stores = asci_stores(b"0ABC", Packing::TwoPerWord, false);
        let words: Vec<u16> = stores.iter().map(|s| s.apply(0xFFFF)).collect();
        assert_eq!(words, [0x4130, 0x4342]);
        let stores = asci_stores(b"BC", Packing::OnePerWord, false);
        let words: Vec<u16> = stores.iter().map(|s| s.apply(0xFFFF)).collect();
        assert_eq!(words, [0x0042, 0x0043]);
    }

    #[test]
    fn terminator_placement() {
        let at = |chars: &[u8], packing| -> Vec<u16> {
            asci_stores(chars, packing, true)
                .iter()
                .map(|s| s.apply(0xFFFF))
                .collect()
        };
        assert_eq!(at(b"C", Packing::TwoPerWord), [0x0043]);
        assert_eq!(at(b"BC", Packing::TwoPerWord), [0x4342, 0x0000]);
        assert_eq!(at(b"C", Packing::OnePerWord), [0x0043, 0x0000]);
        for n in 1..=9 {
            for packing in [Packing::TwoPerWord, Packing::OnePerWord] {
                for terminate in [false, true] {
                    let chars = vec![b'0'; n as usize];
                    assert_eq!(
                        asci_stores(&chars, packing, terminate).len() as u32,
                        asci_destination_words(n, packing, terminate),
                        "n={n} {packing:?} terminate={terminate}"
                    );
                }
            }
        }
    }

    #[test]
    fn hex_is_right_justified() {
        assert_eq!(hex_words(b"C"), Ok(vec![0x000C]));
        assert_eq!(hex_words(b"0AB"), Ok(vec![0x00AB]));
        assert_eq!(hex_words(b"0ABC1"), Ok(vec![0xABC1, 0x0000]));
        assert_eq!(hex_words(b"12345"), Ok(vec![0x2345, 0x0001]));
        assert_eq!(
            hex_words(b"1a"),
            Err(InvalidChar {
                position: 1,
                byte: b'a'
            })
        );
    }

    #[test]
    fn n_is_unsigned_and_limited() {
        let rig = Rig::new();
        let memory = image([(100, 0x0ABC)], Fill::A);
        for n in [0, 32768, 65535, -1] {
            let out = rig.run("ASCI", &[], n, &memory);
            assert_eq!(out.error, Some(ErrorSignal::Code(ERR_COUNT)), "n={n}");
            assert!(out.writes.is_empty(), "n={n}");
            let out = rig.run("HEXA", &[], n, &memory);
            assert_eq!(out.error, Some(ErrorSignal::Code(ERR_COUNT)), "n={n}");
        }
    }
}
