//! Generators: each a numbered space of inputs, so that input `i` is the same on any machine,
//! in any shard and in any order, and a sweep is repeated exactly from its printed settings.
//!
//! - **values**: every 16-bit value; or, for 32 bits, the lattice of values whose eight hex
//!   digits are each 0, 1, 9, A or F (390,625 values) plus every boundary: 2^k-1, 2^k, 2^k+1
//!   and each single non-zero digit at each position, and the lattice's neighbours ±1.
//! - **text**: every string of length 1..n over an alphabet of bytes (by default the
//!   boundaries of the byte classes: 00H, 20H, 2FH, '0', '9', 3AH, 40H, 'A', 'F', 47H, 60H,
//!   'a', 'f', 67H, 7FH, 80H, FFH).
//! - **random**: `count` inputs from the seed: uniform bytes, or valid hex text with one or two
//!   bytes replaced (by any byte, a class boundary, 00H, a token number parsers know such as
//!   `0x`, a sign or `_`, or the UTF-8 form of a character outside ASCII); lengths, counts,
//!   flag settings, and operands at the end of a device range.
//! - **full**: all 2^32 texts of 4 bytes. By class (the default), one text per tuple of byte
//!   classes, each standing for all the texts of its tuple (`super::classes`); or each text
//!   asked, in a scrambled order (any contiguous part or shard is an even sample of the whole).
//!
//! Each text or value is crossed with the digit counts asked for and, for an instruction,
//! with every setting of the flags it reads (the random generator draws them instead).

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;

use super::classes::ByteClasses;
use super::input::{Data, Point};
use super::rng::Rng;
use crate::device::Device;

/// The default alphabet of the text generator: the boundaries of the byte classes.
pub(crate) const BOUNDARIES: [u8; 17] = [
    0x00, 0x20, 0x2F, b'0', b'9', 0x3A, 0x40, b'A', b'F', 0x47, 0x60, b'a', b'f', 0x67, 0x7F, 0x80,
    0xFF,
];

/// What number parsers commonly read as part of a number besides its digits: prefixes, signs,
/// separators, blanks, suffixes. The random generator writes them over valid text.
pub(crate) const TOKENS: [&[u8]; 14] = [
    b"0x", b"0X", b"+", b"-", b" ", b"\t", b"_", b".", b",", b"h", b"H", b"#", b"$", b"&H",
];

/// The largest digit count a generated input gives (the cross-vendor format's limit).
pub(crate) const MAX_DIGITS: u32 = 16;

/// Which generator.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Generator {
    /// Every value of `bits` (16: all; 32: the lattice and the boundaries).
    Values { bits: u32 },
    /// Every text of length 1..=`max_len` over `alphabet`.
    Text {
        #[serde(serialize_with = "hex_bytes")]
        alphabet: Vec<u8>,
        max_len: u32,
    },
    /// `count` random inputs, texts up to `max_len` bytes.
    Random { count: u64, max_len: u32 },
    /// All 2^32 texts of 4 bytes: by class (`super::classes`), or each text asked.
    Full { by_class: bool },
}

fn hex_bytes<S: serde::Serializer>(b: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(b.iter().map(|b| format!("{b:02X}H")))
}

impl Generator {
    /// Whether the seed decides the inputs: the random generator's, and the random texts that
    /// check the byte classes. The enumerations ignore it.
    pub fn uses_seed(&self) -> bool {
        matches!(
            self,
            Generator::Random { .. } | Generator::Full { by_class: true }
        )
    }

    /// `, seed N` where the seed decides the inputs, else nothing.
    pub fn seed_text(&self, seed: u64) -> String {
        if self.uses_seed() {
            format!(", seed {seed}")
        } else {
            String::new()
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Generator::Values { .. } => "values",
            Generator::Text { .. } => "text",
            Generator::Random { .. } => "random",
            Generator::Full { .. } => "full",
        }
    }

    /// Whether the generator makes texts (else values).
    pub fn makes_text(&self) -> bool {
        !matches!(self, Generator::Values { .. })
    }
}

/// How digit counts are chosen for each text or value.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Digits {
    /// The text's length, or the value's width (4 for 16 bits, 8 for 32).
    Natural,
    /// Each of these counts.
    Each(Vec<u32>),
}

/// A numbered space of inputs.
#[derive(Debug, Clone)]
pub struct Space {
    pub generator: Generator,
    pub seed: u64,
    pub digits: Digits,
    /// Whether the target takes a digit count (else every point has count 0).
    pub counted: bool,
    /// The flags the instruction reads (empty for an operation sweep).
    pub flags: Vec<String>,
    /// Bits of the values the random generator draws.
    pub value_bits: u32,
    /// Random generator: where a source or destination may be put instead of its usual device,
    /// the last words of each device range the profile's variants have.
    pub range_ends: Vec<Device>,
    /// Whether the target reads text (the random generator draws texts, else values).
    pub reads_text: bool,
    /// The 32-bit value list (built once).
    values32: Vec<u64>,
    /// The full generator by class: the byte classes, once found. Each point is then the
    /// representative of a tuple of classes, standing for [`Space::weight`] texts.
    pub classes: Option<Arc<ByteClasses>>,
}

impl Space {
    pub fn new(generator: Generator, seed: u64, digits: Digits, counted: bool) -> Space {
        let reads_text = generator.makes_text();
        let values32 = match &generator {
            Generator::Values { bits: 32 } => lattice32(),
            _ => Vec::new(),
        };
        Space {
            generator,
            seed,
            digits,
            counted,
            flags: Vec::new(),
            value_bits: 16,
            range_ends: Vec::new(),
            reads_text,
            values32,
            classes: None,
        }
    }

    /// How many points the space has: [`Space::total`], or for a sweep by class one per tuple
    /// of classes (crossed, like any text, with the counts and flag settings).
    pub fn points(&self) -> u64 {
        match &self.classes {
            Some(c) => c.tuples().saturating_mul(self.settings()),
            None => self.total(),
        }
    }

    /// How many inputs point `index` stands for: 1, or for a sweep by class the texts of its
    /// tuple.
    pub fn weight(&self, index: u64) -> u64 {
        match &self.classes {
            Some(c) => c.weight(index / self.settings()),
            None => 1,
        }
    }

    /// How many inputs shard `(k, n)` holds: every n-th point from the k-th, each standing for
    /// its weight (one input, or the texts of a tuple of classes).
    pub(crate) fn held_by(&self, shard: (u64, u64)) -> u64 {
        match &self.classes {
            Some(_) => shard_indices(self.points(), shard)
                .fold(0u64, |total, i| total.saturating_add(self.weight(i))),
            None => self.total().saturating_sub(shard.0 - 1).div_ceil(shard.1),
        }
    }

    fn data_count(&self) -> u64 {
        match &self.generator {
            Generator::Values { bits: 16 } => 1 << 16,
            Generator::Values { .. } => self.values32.len() as u64,
            Generator::Text { alphabet, max_len } => (1..=*max_len)
                .map(|l| (alphabet.len() as u64).saturating_pow(l))
                .fold(0u64, u64::saturating_add),
            Generator::Random { count, .. } => *count,
            Generator::Full { .. } => 1 << 32,
        }
    }

    fn digit_choices(&self) -> u64 {
        match (&self.digits, self.counted, &self.generator) {
            (_, false, _) | (_, _, Generator::Random { .. }) | (Digits::Natural, _, _) => 1,
            (Digits::Each(list), true, _) => list.len().max(1) as u64,
        }
    }

    fn flag_choices(&self) -> u64 {
        match self.generator {
            Generator::Random { .. } => 1,
            _ => 1 << self.flags.len().min(16),
        }
    }

    /// How many inputs the whole space has.
    pub fn total(&self) -> u64 {
        self.data_count()
            .saturating_mul(self.digit_choices())
            .saturating_mul(self.flag_choices())
    }

    /// Input `index` (below [`Space::points`]).
    pub fn point(&self, index: u64) -> Point {
        if let Generator::Random { max_len, .. } = self.generator {
            return self.random(index, max_len);
        }
        let settings = self.settings();
        let data_pick = index / settings;
        let data = match (&self.generator, &self.classes) {
            (Generator::Full { .. }, Some(c)) => Data::Text(c.representative(data_pick).to_vec()),
            (generator, _) => match generator {
                Generator::Values { bits: 16 } => Data::Value(data_pick),
                Generator::Values { .. } => Data::Value(self.values32[data_pick as usize]),
                Generator::Text { alphabet, .. } => Data::Text(nth_text(alphabet, data_pick)),
                Generator::Full { .. } => {
                    Data::Text(scramble(data_pick as u32).to_be_bytes().to_vec())
                }
                Generator::Random { .. } => unreachable!("handled above"),
            },
        };
        self.with_setting(data, index % settings)
    }

    /// How many settings (digit count and flags) each text or value is crossed with.
    pub fn settings(&self) -> u64 {
        self.digit_choices().saturating_mul(self.flag_choices())
    }

    /// `data` with setting number `pick` (below [`Space::settings`]): its digit count and
    /// flags.
    pub fn with_setting(&self, data: Data, pick: u64) -> Point {
        let flags_n = self.flag_choices();
        let flag_pick = pick % flags_n;
        let digit_pick = (pick / flags_n) % self.digit_choices();
        let digits = if !self.counted {
            0
        } else {
            match &self.digits {
                Digits::Natural => natural_digits(&data, &self.generator),
                Digits::Each(list) => list.get(digit_pick as usize).copied().unwrap_or(0),
            }
        };
        let flags = self
            .flags
            .iter()
            .enumerate()
            .map(|(i, f)| (f.clone(), flag_pick >> i & 1 == 1))
            .collect();
        Point {
            data,
            digits,
            flags,
            source: None,
            destination: None,
            counted: self.counted,
        }
    }

    fn random(&self, index: u64, max_len: u32) -> Point {
        let mut r = Rng::for_input(self.seed, index);
        let data = if self.reads_text {
            Data::Text(random_text(&mut r, max_len))
        } else {
            Data::Value(random_value(&mut r, self.value_bits))
        };
        let digits = if !self.counted {
            0
        } else {
            let natural = natural_digits(&data, &self.generator);
            match (&self.digits, r.below(3)) {
                (Digits::Each(list), _) if !list.is_empty() => *r.pick(list),
                (_, 0) => natural,
                (_, 1) => r.below(u64::from(natural) + 3) as u32,
                _ => r.below(u64::from(MAX_DIGITS) + 1) as u32,
            }
            .min(MAX_DIGITS)
        };
        let flags: BTreeMap<String, bool> = self
            .flags
            .iter()
            .map(|f| (f.clone(), r.chance(1, 2)))
            .collect();
        let near_end = |r: &mut Rng| -> Option<Device> {
            if self.range_ends.is_empty() || !r.chance(1, 4) {
                return None;
            }
            let end = r.pick(&self.range_ends).clone();
            let back = r.below(9) as u32;
            Some(Device::new(end.code(), end.index.saturating_sub(back)))
        };
        let source = near_end(&mut r);
        let destination = near_end(&mut r);
        Point {
            data,
            digits,
            flags,
            source,
            destination,
            counted: self.counted,
        }
    }
}

fn natural_digits(data: &Data, generator: &Generator) -> u32 {
    match data {
        Data::Text(t) => (t.len() as u32).min(MAX_DIGITS),
        Data::Value(v) => match generator {
            Generator::Values { bits } => bits / 4,
            _ => super::input::significant_digits(*v).max(4),
        },
    }
}

/// Text number `n` of the enumeration: all texts of length 1, then of length 2, ..., each
/// length in base-`k` order of the alphabet.
fn nth_text(alphabet: &[u8], mut n: u64) -> Vec<u8> {
    let k = alphabet.len().max(1) as u64;
    let mut len = 1u32;
    loop {
        let here = k.saturating_pow(len);
        if n < here {
            break;
        }
        n -= here;
        len += 1;
    }
    let mut out = vec![alphabet[0]; len as usize];
    for slot in out.iter_mut().rev() {
        *slot = alphabet[(n % k) as usize];
        n /= k;
    }
    out
}

/// A bijection of the 32-bit numbers that spreads any contiguous block over the whole space.
pub(crate) fn scramble(x: u32) -> u32 {
    let mut x = x.wrapping_mul(0x9E37_79B1);
    x ^= x >> 15;
    x = x.wrapping_mul(0x85EB_CA77);
    x ^= x >> 13;
    x
}

fn random_text(r: &mut Rng, max_len: u32) -> Vec<u8> {
    let len = r.below(u64::from(max_len) + 1) as usize;
    if r.chance(1, 4) {
        return (0..len).map(|_| r.byte()).collect();
    }
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    let mut t: Vec<u8> = (0..len).map(|_| *r.pick(HEX)).collect();
    if t.is_empty() {
        return t;
    }
    for _ in 0..=r.below(2) {
        let at = r.below(t.len() as u64) as usize;
        match r.below(5) {
            0 => t[at] = r.byte(),
            1 => t[at] = *r.pick(&BOUNDARIES),
            2 => t[at] = 0,
            3 => {
                for (i, b) in r.pick(&TOKENS).iter().enumerate() {
                    if let Some(slot) = t.get_mut(at + i) {
                        *slot = *b;
                    }
                }
            }
            _ => {
                // A character outside ASCII, in UTF-8: two bytes (U+0080-U+07FF) or three
                // (U+0800-U+FFFF, surrogates excluded).
                let c = if r.chance(1, 2) {
                    char::from_u32(0x80 + r.below(0x780) as u32)
                } else {
                    char::from_u32(0x800 + r.below(0xF800) as u32)
                };
                let mut buf = [0u8; 4];
                let bytes = c.unwrap_or('\u{A0}').encode_utf8(&mut buf).as_bytes();
                for (i, b) in bytes.iter().enumerate() {
                    if let Some(slot) = t.get_mut(at + i) {
                        *slot = *b;
                    }
                }
            }
        }
    }
    t
}

fn random_value(r: &mut Rng, bits: u32) -> u64 {
    let bits = bits.clamp(1, 64);
    let mask = if bits == 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    };
    match r.below(4) {
        0 => r.next_u64() & mask,
        1 => (0..=r.below(3)).fold(0, |v, _| v | 1 << r.below(u64::from(bits))),
        2 => {
            let k = r.below(u64::from(bits) + 1);
            let p = if k >= 64 { u64::MAX } else { (1u64 << k) - 1 };
            (p.wrapping_add(r.below(3))).wrapping_sub(1) & mask
        }
        _ => {
            (0..bits.div_ceil(4)).fold(0u64, |v, i| {
                v | (*r.pick(&[0u64, 1, 9, 0xA, 0xF]) << (4 * i))
            }) & mask
        }
    }
}

/// The 32-bit values of the values generator: every value whose hex digits are each 0, 1, 9,
/// A or F, their neighbours ±1, every 2^k-1, 2^k, 2^k+1, and each single digit at each position;
/// sorted.
pub(crate) fn lattice32() -> Vec<u64> {
    let digits = [0u64, 1, 9, 0xA, 0xF];
    let mut out = Vec::with_capacity(400_000 * 3);
    for n in 0..5u64.pow(8) {
        let mut v = 0u64;
        let mut m = n;
        for i in 0..8 {
            v |= digits[(m % 5) as usize] << (4 * i);
            m /= 5;
        }
        out.push(v);
        out.push(v.wrapping_add(1) & 0xFFFF_FFFF);
        out.push(v.wrapping_sub(1) & 0xFFFF_FFFF);
    }
    for k in 0..=32u32 {
        let p = 1u64 << k;
        for v in [p.wrapping_sub(1), p, p + 1] {
            out.push(v & 0xFFFF_FFFF);
        }
    }
    for pos in 0..8 {
        for d in 1..16u64 {
            out.push(d << (4 * pos));
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Which indices shard `k` of `n` (1-based) runs: every `n`-th, from `k - 1`. The shards of a
/// sweep are disjoint and together are the whole sweep.
pub(crate) fn shard_indices(total: u64, shard: (u64, u64)) -> impl Iterator<Item = u64> {
    let (k, n) = shard;
    (k.saturating_sub(1)..total).step_by(n.max(1) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_enumeration_covers_every_string_once() {
        let s = Space::new(
            Generator::Text {
                alphabet: b"ab".to_vec(),
                max_len: 3,
            },
            0,
            Digits::Natural,
            true,
        );
        assert_eq!(s.total(), 2 + 4 + 8);
        let all: Vec<Vec<u8>> = (0..s.total())
            .map(|i| match s.point(i).data {
                Data::Text(t) => t,
                Data::Value(_) => unreachable!(),
            })
            .collect();
        let mut sorted = all.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), all.len());
        assert_eq!(all[0], b"a");
        assert_eq!(all[2], b"aa");
        assert_eq!(s.point(13).digits, 3);
    }

    #[test]
    fn flags_and_digits_multiply_the_space() {
        let mut s = Space::new(
            Generator::Values { bits: 16 },
            0,
            Digits::Each(vec![1, 4]),
            true,
        );
        s.flags = vec!["SM701".into(), "SM705".into()];
        assert_eq!(s.total(), 65536 * 2 * 4);
        let p = s.point(7);
        assert_eq!(p.data, Data::Value(0));
        assert_eq!(p.digits, 4);
        assert_eq!(p.flags.values().filter(|v| **v).count(), 2);
    }

    #[test]
    fn the_32_bit_scheme_has_the_lattice_and_the_boundaries() {
        let v = lattice32();
        for x in [
            0,
            1,
            0xFFFF_FFFF,
            0x1000_0000,
            0x8000_0000,
            0x0001_0000,
            0xA9F1_0019,
        ] {
            assert!(v.binary_search(&x).is_ok(), "{x:X}");
        }
        assert!(v.len() > 390_625 && v.len() < 1_300_000, "{}", v.len());
    }

    #[test]
    fn scramble_is_a_bijection_on_a_sample() {
        let mut seen: Vec<u32> = (0..1 << 16).map(|i| scramble(i * 65537)).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 1 << 16);
    }

    #[test]
    fn random_inputs_depend_on_seed_and_index_only() {
        let s = Space::new(
            Generator::Random {
                count: 100,
                max_len: 8,
            },
            42,
            Digits::Natural,
            true,
        );
        let a: Vec<Point> = (0..100).map(|i| s.point(i)).collect();
        let b: Vec<Point> = (0..100).rev().map(|i| s.point(i)).collect();
        assert_eq!(a, b.into_iter().rev().collect::<Vec<_>>());
        assert!(a.iter().all(|p| p.digits <= MAX_DIGITS));
    }
}
