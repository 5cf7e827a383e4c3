//! What a bench needs of a protocol, and nothing more: words read and written, the CPU named
//! and its operating state read. A link is the one place a protocol's frames are built; the
//! bench layer above it holds the mailbox, the fence, the interlocks and the breaker for every
//! link alike.

use std::error::Error;
use std::fmt;

use super::fence::{FencedWrite, Kind};
use crate::backend::Fault;
use crate::device::Device;

/// How a link failed, as the fault kinds every backend reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// No connection could be made.
    Unreachable,
    /// No (whole) answer in time.
    Timeout,
    /// The connection was lost.
    Lost,
    /// An answer that does not decode, answers another request, or says the CPU refused it.
    Protocol,
}

/// A link's error: its kind, and the protocol's own error, whose text is the message.
#[derive(Debug)]
pub struct LinkError {
    pub failure: Failure,
    error: Box<dyn Error + Send + Sync>,
}

impl LinkError {
    pub fn new(failure: Failure, error: impl Into<Box<dyn Error + Send + Sync>>) -> Self {
        LinkError {
            failure,
            error: error.into(),
        }
    }

    /// The protocol's own error, for a caller (a test) that knows the link.
    pub fn protocol_error(&self) -> &(dyn Error + Send + Sync + 'static) {
        self.error.as_ref()
    }

    /// The fault a case reports for this error.
    pub fn fault(&self) -> Fault {
        let text = self.to_string();
        match self.failure {
            Failure::Unreachable => Fault::Unreachable(text),
            Failure::Timeout => Fault::Timeout(text),
            Failure::Lost => Fault::Crashed(text),
            Failure::Protocol => Fault::Protocol(text),
        }
    }
}

/// The protocol's message: the link adds nothing to it.
impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.error.fmt(f)
    }
}

impl Error for LinkError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        self.error.source()
    }
}

/// Whether the CPU runs its program, and its state in words for messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunState {
    pub running: bool,
    /// `RUN (SD203=0000H)`, `STOP (M8000 off)`.
    pub text: String,
}

/// How a protocol reaches a CPU's devices; a fact of the protocol and the CPU family, known
/// without a connection (a dry run, `hil generate` and the settings use it).
pub trait Addressing: Send + Sync {
    /// Whether the CPU numbers a device code in hexadecimal (MELSEC `W1A`); the program, the
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

/// One connection to a CPU, opened on its first request and opened again after a fault.
pub trait Link: Send {
    /// The CPU as it names itself: compared with `confirm`.
    fn identify(&mut self) -> Result<Identity, LinkError>;
    /// Whether the CPU is in RUN.
    fn run_state(&mut self) -> Result<RunState, LinkError>;
    /// `count` words from `head`, split at the link's limits.
    fn read(&mut self, head: &Device, count: u32) -> Result<Vec<u16>, LinkError>;
    /// The words of scattered devices, in order, with the CPU's state: what a status poll
    /// reads. The default reads each run of consecutive words, then the state.
    fn poll(&mut self, devices: &[Device]) -> Result<(Vec<u16>, RunState), LinkError> {
        let mut out = Vec::with_capacity(devices.len());
        let mut i = 0;
        while i < devices.len() {
            let head = &devices[i];
            let mut n = 1;
            while devices
                .get(i + n)
                .is_some_and(|d| d.code() == head.code() && d.index == head.index + n as u32)
            {
                n += 1;
            }
            out.extend(self.read(head, n as u32)?);
            i += n;
        }
        Ok((out, self.run_state()?))
    }
    /// One fenced write; never sent again by the link.
    fn write(&mut self, write: &FencedWrite) -> Result<(), LinkError>;
    /// Words one write may carry.
    fn batch_words(&self) -> usize;
    /// Connections opened so far: a new one means the interlocks run again.
    fn connections(&self) -> u64;
    /// Requests sent so far.
    fn requests(&self) -> u64;
    fn is_connected(&self) -> bool;
    fn disconnect(&mut self);
}

/// The CPU as it named itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// What `confirm` is compared with.
    pub name: String,
    /// How provenance shows it (with a model code, say).
    pub shown: String,
}

/// How to reach a CPU over one protocol: what a bench's settings hold for its link.
pub trait LinkSettings: fmt::Debug + Send + Sync {
    /// A link, not yet connected.
    fn open(&self) -> Box<dyn Link>;
    /// The transport as provenance names it: `SLMP 4E binary TCP 192.0.2.10:5007`.
    fn describe(&self) -> String;
    /// `host:port`.
    fn address(&self) -> &str;
    fn addressing(&self) -> &'static dyn Addressing;
    fn clone_box(&self) -> Box<dyn LinkSettings>;
}

impl Clone for Box<dyn LinkSettings> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

impl LinkSettings for Box<dyn LinkSettings> {
    fn open(&self) -> Box<dyn Link> {
        self.as_ref().open()
    }
    fn describe(&self) -> String {
        self.as_ref().describe()
    }
    fn address(&self) -> &str {
        self.as_ref().address()
    }
    fn addressing(&self) -> &'static dyn Addressing {
        self.as_ref().addressing()
    }
    fn clone_box(&self) -> Box<dyn LinkSettings> {
        self.as_ref().clone_box()
    }
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
