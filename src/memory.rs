//! Memory images: what a backend reads, and what it wrote.
//!
//! Every word a vector does not set holds a fill pattern, and each case runs under two fills
//! that share no byte value: a stray write is always a change, and a read of a word the vector
//! did not set shows up as an outcome that depends on the fill.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::device::Device;

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
    pub const ALL: [Fill; 2] = [Fill::A, Fill::B];

    pub fn word(self, device: &Device) -> u16 {
        let i = (device.index % 16) as usize;
        match self {
            Fill::A => 0xA5A5 ^ ((i % 6) as u16 * 0x0101),
            Fill::B => {
                const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
                u16::from(DIGITS[i]) | (u16::from(DIGITS[15 - i]) << 8)
            }
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Fill::A => "A",
            Fill::B => "B",
        }
    }
}

/// Memory before execution: the vector's words over a fill.
#[derive(Debug, Clone)]
pub struct Image {
    words: BTreeMap<Device, u16>,
    fill: Fill,
}

impl Image {
    pub fn new(words: BTreeMap<Device, u16>, fill: Fill) -> Self {
        Image { words, fill }
    }

    pub fn read(&self, device: &Device) -> u16 {
        self.words
            .get(device)
            .copied()
            .unwrap_or_else(|| self.fill.word(device))
    }

    pub fn fill(&self) -> Fill {
        self.fill
    }

    /// The words the vector set explicitly.
    pub fn explicit(&self) -> &BTreeMap<Device, u16> {
        &self.words
    }
}

/// A backend's working view: reads see earlier writes; the writes are the result.
#[derive(Debug)]
pub struct Scratch<'a> {
    image: &'a Image,
    writes: BTreeMap<Device, u16>,
}

impl<'a> Scratch<'a> {
    pub fn new(image: &'a Image) -> Self {
        Scratch {
            image,
            writes: BTreeMap::new(),
        }
    }

    pub fn read(&self, device: &Device) -> u16 {
        self.writes
            .get(device)
            .copied()
            .unwrap_or_else(|| self.image.read(device))
    }

    pub fn write(&mut self, device: Device, value: u16) {
        self.writes.insert(device, value);
    }

    pub fn into_writes(self) -> BTreeMap<Device, u16> {
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
    fn scratch_reads_its_own_writes() {
        let d = Device::new("D", 1);
        let image = Image::new(BTreeMap::from([(d.clone(), 7)]), Fill::A);
        let mut s = Scratch::new(&image);
        assert_eq!(s.read(&d), 7);
        s.write(d.clone(), 9);
        assert_eq!(s.read(&d), 9);
        assert_eq!(s.into_writes(), BTreeMap::from([(d, 9)]));
    }
}
