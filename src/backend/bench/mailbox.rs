//! The mailbox: 32 data registers through which the PC hands the CPU's test program one case at
//! a time and reads back what happened (layout 2).
//!
//! The PC writes the case's memory window, then the rung and the flags, then the trigger alone,
//! a sequence number. The program answers with `ack` equal to the trigger once the case is done,
//! having reset the error state first, executed the selected rung for exactly one scan, and
//! captured the error flag and registers in that scan and in the next. An acknowledgement alone
//! proves nothing about the rung (a program acknowledges a trigger whether or not the rung is
//! there), so the rung itself, in the scan it is enabled, writes its number, the trigger it ran
//! for and its ENO: the proof of execution the PC checks before it judges anything. Everything
//! else here is written by the program every scan: a signature (magic, layout, program hash,
//! rung count) that says which program runs, whether a simulator runs it, the scan counter that
//! says it runs, and the error flag now.

use super::addressing::Addressing;
use super::fence::WordRange;
use crate::device::{Device, DeviceSyntaxError};

/// The layout version the program and the PC agree on.
pub(crate) const LAYOUT: u16 = 2;
/// Words in the mailbox.
pub(crate) const WORDS: u32 = 32;
/// `'P','C'`, `'H','I'` as two characters per word, low byte first.
pub(crate) const MAGIC: [u16; 2] = [0x4350, 0x4948];
/// `'S','I'`: what the simulated CPU writes at [`off::ORIGIN`], where the generated program on a
/// CPU writes 0, so that nothing a simulator answered is ever taken for an observation.
pub(crate) const SIMULATOR: u16 = 0x4953;

/// Word offsets from the mailbox head.
pub(crate) mod off {
    /// Magic, two words (program).
    pub(crate) const MAGIC: u32 = 0;
    /// Layout version (program).
    pub(crate) const LAYOUT: u32 = 2;
    /// Low and high word of the program hash's low 32 bits (program).
    pub(crate) const HASH: u32 = 3;
    /// Rung count (program).
    pub(crate) const RUNGS: u32 = 5;
    /// 0 from the program on a CPU, [`super::SIMULATOR`] from the simulated CPU (program).
    pub(crate) const ORIGIN: u32 = 6;
    /// Sequence number of the case asked for, 1-65535 (PC; written last, alone).
    pub(crate) const TRIGGER: u32 = 8;
    /// Sequence number of the case done (program).
    pub(crate) const ACK: u32 = 9;
    /// Rung to execute (PC).
    pub(crate) const RUNG: u32 = 10;
    /// Flag bits, in the manifest's flag order (PC).
    pub(crate) const FLAGS: u32 = 11;
    /// The program's state, see [`super::state`] (program).
    pub(crate) const STATE: u32 = 12;
    /// Scan counter (program).
    pub(crate) const SCANS: u32 = 13;
    /// The error flag this scan, 0 or 1 (program).
    pub(crate) const FLAG_NOW: u32 = 14;
    /// The error flag after the reset, before the instruction (program).
    pub(crate) const FLAG_BEFORE: u32 = 16;
    /// The error flag right after the instruction, same scan (program).
    pub(crate) const FLAG_AFTER: u32 = 17;
    /// The error register right after the instruction (program).
    pub(crate) const CODE: u32 = 18;
    /// The profile's further error register, same scan (program).
    pub(crate) const CODE_EXTRA: u32 = 19;
    /// The error register one scan later (program).
    pub(crate) const CODE_NEXT: u32 = 20;
    /// The rung that ran, written by the rung itself in the scan it was enabled (program).
    pub(crate) const RAN: u32 = 21;
    /// The trigger that rung ran for (program).
    pub(crate) const RAN_FOR: u32 = 22;
    /// The rung's ENO in that scan, 0 or 1 (program).
    pub(crate) const ENO: u32 = 23;
}

/// The program's states.
pub(crate) mod state {
    pub(crate) const IDLE: u16 = 0;
    pub(crate) const RESETTING: u16 = 1;
    pub(crate) const EXECUTING: u16 = 2;
    pub(crate) const DONE: u16 = 3;
    /// The error flag stayed on after the error reset: the case was not executed.
    pub(crate) const RESET_FAILED: u16 = 8;

    /// A state's name, for messages.
    pub(crate) fn name(state: u16) -> &'static str {
        match state {
            IDLE => "idle",
            RESETTING => "resetting errors",
            EXECUTING => "executing",
            DONE => "done, acknowledging next scan",
            RESET_FAILED => "the error reset failed",
            _ => "no state of the generated program",
        }
    }
}

/// The words of the mailbox the PC writes: the trigger, the rung and the flags. Nothing else of
/// the mailbox is in the write fence.
pub(crate) fn pc_words(head: &Device) -> Vec<WordRange> {
    vec![
        WordRange::within(head, head.index + off::TRIGGER, head.index + off::TRIGGER),
        WordRange::within(head, head.index + off::RUNG, head.index + off::FLAGS),
    ]
}

/// The whole mailbox.
pub(crate) fn range(head: &Device) -> WordRange {
    WordRange::within(head, head.index, head.index + WORDS - 1)
}

/// The mailbox head as `--mailbox` and a manifest write it, numbered as the CPU numbers the code
/// (`W100` is W 256 where W is numbered in hexadecimal), as the program and the frames will.
pub(crate) fn head(text: &str, addressing: &dyn Addressing) -> Result<Device, DeviceSyntaxError> {
    Device::parse_numbered(text, |code| addressing.hex_numbered(code))
}

/// The device at an offset, numbered as the head is (`W100` + 8 is `W108`).
pub(crate) fn at(head: &Device, offset: u32) -> Device {
    head.with_index(head.index + offset)
}

/// What the program writes every scan, read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Signature {
    pub magic: [u16; 2],
    pub layout: u16,
    pub hash: u32,
    pub rungs: u16,
}

impl Signature {
    /// From the mailbox's first six words; a cleared mailbox when there are fewer.
    pub fn of(words: &[u16]) -> Signature {
        let word = |i: usize| words.get(i).copied().unwrap_or(0);
        Signature {
            magic: [word(0), word(1)],
            layout: word(2),
            hash: u32::from(word(3)) | u32::from(word(4)) << 16,
            rungs: word(5),
        }
    }

    /// What a program with this hash and rung count writes.
    pub fn expected(hash: u32, rungs: u16) -> Signature {
        Signature {
            magic: MAGIC,
            layout: LAYOUT,
            hash,
            rungs,
        }
    }

    /// Why `self` (read) is not `expected`, if it is not.
    pub fn mismatch(&self, expected: &Signature) -> Option<String> {
        if self.magic != MAGIC {
            return Some(format!(
                "no test program signature in the mailbox (magic {:04X}H {:04X}H, expected \
                 {:04X}H {:04X}H): is the generated program written to the CPU and the mailbox \
                 where the manifest says?",
                self.magic[0], self.magic[1], MAGIC[0], MAGIC[1]
            ));
        }
        if self.layout != expected.layout {
            return Some(format!(
                "the program uses mailbox layout {}, this harness layout {}",
                self.layout, expected.layout
            ));
        }
        if self.hash != expected.hash || self.rungs != expected.rungs {
            return Some(format!(
                "the program on the CPU is another one than the manifest's (hash {:08X}H with {} \
                 rungs on the CPU, {:08X}H with {} in the manifest): write the program generated \
                 with this manifest",
                self.hash, self.rungs, expected.hash, expected.rungs
            ));
        }
        None
    }
}

/// The next trigger after `last`: 1-65535, never 0 (0 is what a cleared mailbox holds).
pub(crate) fn next_trigger(last: u16) -> u16 {
    match last.wrapping_add(1) {
        0 => 1,
        n => n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::addressing::Plain;

    #[test]
    fn magic_reads_as_pchi() {
        let bytes: Vec<u8> = MAGIC.iter().flat_map(|w| w.to_le_bytes()).collect();
        assert_eq!(bytes, b"PCHI");
    }

    /// A mailbox in link registers is numbered in hexadecimal throughout: its words, its range
    /// and the words the PC writes read as the CPU writes them.
    #[test]
    fn a_mailbox_keeps_the_numbering_of_its_head() {
        let w = head("W100", &Plain).expect("W100");
        assert_eq!(w.index, 0x100);
        assert_eq!(at(&w, off::TRIGGER).to_string(), "W108");
        assert_eq!(range(&w).to_string(), "W100-W11F");
        let d = head("D11000", &Plain).expect("D11000");
        assert_eq!(at(&d, off::FLAGS).to_string(), "D11011");
        assert_eq!(range(&d).to_string(), "D11000-D11031");
    }

    #[test]
    fn triggers_skip_zero() {
        assert_eq!(next_trigger(0), 1);
        assert_eq!(next_trigger(65535), 1);
        assert_eq!(next_trigger(7), 8);
    }

    #[test]
    fn the_pc_writes_three_words() {
        let words: u32 = pc_words(&Device::new("D", 12000))
            .iter()
            .map(WordRange::len)
            .sum();
        assert_eq!(words, 3);
    }

    #[test]
    fn signature_mismatches_are_explained() {
        let good = Signature::expected(0xDEADBEEF, 12);
        assert_eq!(good.mismatch(&good), None);
        let cleared = Signature::of(&[0; 6]);
        assert!(cleared
            .mismatch(&good)
            .is_some_and(|m| m.contains("no test program")));
        let other = Signature::expected(0x1234, 12);
        assert!(other
            .mismatch(&good)
            .is_some_and(|m| m.contains("another one")));
    }
}
