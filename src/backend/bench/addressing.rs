//! How a link reaches a CPU's devices, known without a connection: which devices it reaches,
//! how the CPU numbers them, and which a sandbox may hold.

use crate::device::Device;

/// What a word is to a sandbox: the harness writes word devices only, and a special one only
/// when the user names it. The link's `Addressing::kind` says which a device is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Data registers and their like: memory a test program may own.
    Data,
    /// The CPU's and the network's own words (special registers).
    Special,
    /// Bit devices (inputs, outputs, relays), 16 points to a word.
    Bit,
}

/// How a protocol reaches a CPU's devices; a fact of the protocol and the CPU family, known
/// without a connection (a dry run, `hil generate` and the settings use it).
pub trait Addressing: Send + Sync {
    /// Whether the CPU numbers a device code in hexadecimal (`W1A` is W 26); the program, the
    /// manifest and the sandbox write numbers as the CPU does.
    fn hex_numbered(&self, code: &str) -> bool;
    /// What a word is to a sandbox.
    fn kind(&self, device: &Device) -> Kind;
    /// Why the link can neither set nor read a device's words, if it cannot.
    fn unaddressable(&self, device: &Device) -> Option<String>;
    /// The devices a sandbox may hold, for messages: `D, R, ZR, W, and SD or SW when named`.
    fn sandbox_devices(&self) -> &'static str;
    /// Where a mailbox may be, for messages: `data or link register (D, R, ZR, W)`.
    fn data_devices(&self) -> &'static str;
}

/// A CPU for the bench layer's own tests: data registers D, R and W (W numbered in hexadecimal),
/// special registers SD, and bits.
#[cfg(test)]
pub(crate) struct Plain;

#[cfg(test)]
impl Addressing for Plain {
    fn hex_numbered(&self, code: &str) -> bool {
        code == "W"
    }
    fn kind(&self, device: &Device) -> Kind {
        match device.code() {
            "D" | "R" | "W" => Kind::Data,
            "SD" => Kind::Special,
            _ => Kind::Bit,
        }
    }
    fn unaddressable(&self, _: &Device) -> Option<String> {
        None
    }
    fn sandbox_devices(&self) -> &'static str {
        "D, R, W, and SD when named"
    }
    fn data_devices(&self) -> &'static str {
        "data or link register (D, R, W)"
    }
}
