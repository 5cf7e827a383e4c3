//! Memory images: what a backend reads, and what it wrote.
//!
//! A family's memory is made of units, 16-bit words (MELSEC `D100`, IDEC `D0`) or bytes
//! (Siemens `MB20`, `DB1.DBB10`), as its profile says; a device names one unit, and a value in
//! an image is that unit's contents (a byte's value fits in the low 8 bits).
//!
//! Every unit a vector does not set holds a fill pattern, and each case runs under two fills
//! that share no byte value: a stray write is always a change, and a read of a unit the vector
//! did not set shows up as an outcome that depends on the fill.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::device::Device;

/// What one device of a family holds.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Default,
    Serialize,
    Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// One byte: byte-addressed memory, where consecutive numbers are consecutive bytes.
    Byte,
    /// One 16-bit word: word-addressed memory, where a character pair shares one device.
    #[default]
    Word,
    /// One 32-bit word: memory whose every device holds 32 bits, four characters of packed text.
    Dword,
}

/// What one unit of memory holds: a byte, a 16-bit or a 32-bit word, by the family's
/// `memory_unit`. Wide enough for the widest unit, so that nothing past the leaves assumes a
/// 16-bit word.
pub type Value = u32;

impl Unit {
    /// Bits in one unit: 8, 16 or 32.
    pub fn bits(self) -> u32 {
        match self {
            Unit::Byte => 8,
            Unit::Word => 16,
            Unit::Dword => 32,
        }
    }

    /// The largest value a unit holds.
    pub fn max(self) -> Value {
        match self {
            Unit::Byte => 0xFF,
            Unit::Word => 0xFFFF,
            Unit::Dword => 0xFFFF_FFFF,
        }
    }

    /// Characters packed into units as the family stores a string: as many to a unit as it has
    /// bytes, the first in the lowest byte; a short last unit is filled with 00H.
    pub fn pack(self, chars: &[u8]) -> Vec<Value> {
        let width = (self.bits() / 8) as usize;
        chars
            .chunks(width)
            .map(|unit| {
                (unit.iter().enumerate()).fold(0, |v, (i, c)| v | Value::from(*c) << (8 * i))
            })
            .collect()
    }

    /// Hex digits in one unit.
    pub fn digits(self) -> u32 {
        self.bits() / 4
    }

    /// A unit's value the way the manuals write it: `5A8DH` for a word, `5AH` for a byte,
    /// `89ABCDEFH` for a 32-bit word.
    pub fn hex(self, value: Value) -> String {
        format!("{value:0width$X}H", width = self.digits() as usize)
    }

    /// The name profiles and reports use (`byte`, `word`, `dword`).
    pub fn name(self) -> &'static str {
        match self {
            Unit::Byte => "byte",
            Unit::Word => "word",
            Unit::Dword => "dword",
        }
    }
}

/// A pattern for the words a vector leaves unset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Fill {
    /// Bytes A0H-A7H: never ASCII, so reading them as characters is invalid data.
    A,
    /// Valid hex digit characters that vary with the address: reading them converts without
    /// error, so a read past the vector's data changes the result instead.
    B,
}

impl Fill {
    /// Both fills, in the order each case runs under them: A, then B.
    pub const ALL: [Fill; 2] = [Fill::A, Fill::B];

    /// The fill's value of a unit: each byte of a word fill is the byte fill of the same kind,
    /// so a byte-addressed family sees the same kinds of bytes as a word-addressed one. It
    /// varies with the unit's position ([`Device::unit_number`]), so neighbouring units differ
    /// for a digit designation too (`K4M0`, `K4M16`).
    ///
    /// A 32-bit unit holds the word fill of its position low and that of the position eight on
    /// high, so its four bytes are of the fill's kind and its halves differ.
    pub fn value(self, device: &Device, unit: Unit) -> Value {
        let i = (device.unit_number() % 16) as usize;
        let word = |i: usize| -> Value {
            match self {
                Fill::A => 0xA5A5 ^ ((i % 6) as Value * 0x0101),
                Fill::B => {
                    const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
                    Value::from(DIGITS[i]) | (Value::from(DIGITS[15 - i]) << 8)
                }
            }
        };
        match unit {
            Unit::Byte | Unit::Word => word(i) & unit.max(),
            Unit::Dword => word(i) | word((i + 8) % 16) << 16,
        }
    }

    /// The fill's value of a 16-bit word.
    pub fn word(self, device: &Device) -> u16 {
        self.value(device, Unit::Word) as u16
    }

    /// `A` or `B`, as reports name the fill.
    pub fn name(self) -> &'static str {
        match self {
            Fill::A => "A",
            Fill::B => "B",
        }
    }
}

/// Memory before execution: the vector's units over a fill.
#[derive(Debug, Clone)]
pub struct Image {
    /// Shared, so that a simulated CPU can give its whole memory to each execution without
    /// copying it.
    words: std::sync::Arc<BTreeMap<Device, Value>>,
    fill: Fill,
    unit: Unit,
}

impl Image {
    /// Word-addressed memory.
    pub fn new(words: BTreeMap<Device, Value>, fill: Fill) -> Self {
        Image::of_units(words, fill, Unit::Word)
    }

    /// Memory of `unit`-sized devices (bytes for a byte-addressed family): `words` over `fill`.
    pub fn of_units(words: BTreeMap<Device, Value>, fill: Fill, unit: Unit) -> Self {
        Image::sharing(std::sync::Arc::new(words), fill, unit)
    }

    /// Memory whose words are held elsewhere too: a simulated CPU's whole memory, or one
    /// input's words under both fills.
    pub(crate) fn sharing(
        words: std::sync::Arc<BTreeMap<Device, Value>>,
        fill: Fill,
        unit: Unit,
    ) -> Self {
        Image { words, fill, unit }
    }

    /// A unit's value: the one the case set, or the fill's.
    pub fn read(&self, device: &Device) -> Value {
        self.words
            .get(device)
            .copied()
            .unwrap_or_else(|| self.fill.value(device, self.unit))
    }

    /// A unit of a 16-bit family as the word it is (the low 16 bits of any unit): what the
    /// reference models of word- and byte-addressed families compute with.
    pub fn word(&self, device: &Device) -> u16 {
        self.read(device) as u16
    }

    /// The fill that the units the case does not set hold.
    pub fn fill(&self) -> Fill {
        self.fill
    }

    /// What one device of this memory holds: a byte, a word or a 32-bit word.
    pub fn unit(&self) -> Unit {
        self.unit
    }

    /// The words the vector set explicitly.
    pub fn explicit(&self) -> &BTreeMap<Device, Value> {
        &self.words
    }

    /// Copies the units from `head` on into an emulator's own memory, `ram[i]` from `head + i`,
    /// so that it can run the instruction on its RAM and report with [`crate::Outcome::changes`].
    /// Returns how many were copied: fewer than `ram` holds when the device numbers end first.
    ///
    /// ```
    /// use plc_conformance::{Device, Fill, Image};
    ///
    /// let d100: Device = "D100".parse().unwrap();
    /// let image = Image::new([(d100.clone(), 0x4135)].into(), Fill::B);
    /// let mut ram = [0; 3];
    /// assert_eq!(image.copy_into(&d100, &mut ram), 3);
    /// assert_eq!(ram[0], 0x4135);
    /// // A unit the case does not set reads as the fill.
    /// assert_eq!(ram[2], image.read(&"D102".parse().unwrap()));
    /// ```
    pub fn copy_into(&self, head: &Device, ram: &mut [Value]) -> usize {
        let mut copied = 0;
        for (i, unit) in ram.iter_mut().enumerate() {
            let Some(device) = u32::try_from(i).ok().and_then(|i| head.offset(i)) else {
                break;
            };
            *unit = self.read(&device);
            copied += 1;
        }
        copied
    }
}

/// A backend's working view: reads see earlier writes; the writes are the result.
#[derive(Debug)]
pub(crate) struct Scratch<'a> {
    image: &'a Image,
    writes: BTreeMap<Device, Value>,
}

impl<'a> Scratch<'a> {
    pub(crate) fn new(image: &'a Image) -> Self {
        Scratch {
            image,
            writes: BTreeMap::new(),
        }
    }

    pub(crate) fn read(&self, device: &Device) -> Value {
        self.writes
            .get(device)
            .copied()
            .unwrap_or_else(|| self.image.read(device))
    }

    /// A unit as [`Image::word`] reads it.
    pub(crate) fn word(&self, device: &Device) -> u16 {
        self.read(device) as u16
    }

    pub(crate) fn write(&mut self, device: Device, value: impl Into<Value>) {
        self.writes.insert(device, value.into());
    }

    pub(crate) fn into_writes(self) -> BTreeMap<Device, Value> {
        self.writes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fills_share_no_byte_and_are_never_zero() {
        for index in 0..64 {
            let d = Device::new("D", index);
            let (a, b) = (Fill::A.word(&d), Fill::B.word(&d));
            for byte_a in a.to_le_bytes() {
                assert!(byte_a >= 0x80, "fill A byte {byte_a:02X} at {d}");
                assert!(!b.to_le_bytes().contains(&byte_a));
            }
            for byte_b in b.to_le_bytes() {
                assert!(byte_b.is_ascii_hexdigit() && !byte_b.is_ascii_lowercase());
            }
        }
    }

    #[test]
    fn byte_fills_are_the_word_fills_bytes() {
        for index in 0..64 {
            let d = Device::new("MB", index);
            for fill in Fill::ALL {
                assert_eq!(
                    fill.value(&d, Unit::Byte),
                    Value::from(fill.word(&d) & 0xFF)
                );
            }
            assert_ne!(Fill::A.value(&d, Unit::Byte), Fill::B.value(&d, Unit::Byte));
        }
        let image = Image::of_units(BTreeMap::new(), Fill::A, Unit::Byte);
        assert!(image.read(&Device::new("MB", 3)) <= 0xFF);
    }

    #[test]
    fn neighbouring_digit_designated_words_have_different_fills() {
        for fill in Fill::ALL {
            for k in 0..16 {
                let word = Device::new("K4M", 100 + 16 * k);
                assert_eq!(fill.word(&word), fill.word(&Device::new("D", 6 + k)));
                assert_ne!(
                    fill.word(&word),
                    fill.word(&Device::new("K4M", 116 + 16 * k)),
                    "{word}"
                );
            }
        }
    }

    #[test]
    fn a_32_bit_unit_holds_two_word_fills_and_four_characters() {
        for index in 0..16 {
            let d = Device::new("DW", index);
            let eight_on = Device::new("DW", (index + 8) % 16);
            for fill in Fill::ALL {
                let (low, high) = (fill.word(&d), fill.word(&eight_on));
                assert_eq!(
                    fill.value(&d, Unit::Dword),
                    Value::from(low) | Value::from(high) << 16
                );
            }
        }
        assert_eq!(Unit::Dword.pack(b"12345"), vec![0x3433_3231, 0x35]);
        assert_eq!(Unit::Word.pack(b"123"), vec![0x3231, 0x33]);
        // Two characters a word, first in the low byte; an odd count leaves 00H high.
        assert_eq!(Unit::Word.pack(b"5A8D"), vec![0x4135, 0x4438]);
        assert_eq!(Unit::Word.pack(b"5A8"), vec![0x4135, 0x0038]);
        assert_eq!(Unit::Byte.pack(b"12"), vec![0x31, 0x32]);
        assert_eq!(Unit::Dword.hex(0x89AB_CDEF), "89ABCDEFH");
        assert_eq!(Unit::Word.hex(0x5A8D), "5A8DH");
        assert_eq!(Unit::Byte.hex(0x5A), "5AH");
    }

    #[test]
    fn scratch_reads_its_own_writes() {
        let d = Device::new("D", 1);
        let image = Image::new(BTreeMap::from([(d.clone(), 7)]), Fill::A);
        let mut s = Scratch::new(&image);
        assert_eq!(s.read(&d), 7);
        s.write(d.clone(), 9u32);
        assert_eq!(s.read(&d), 9);
        assert_eq!(s.into_writes(), BTreeMap::from([(d, 9)]));
    }
}
