//! What a bench needs of a protocol, and nothing more: words read and written, the CPU named
//! and its operating state read. A link is the one place a protocol's frames are built; the
//! bench layer above it holds the mailbox, the fence, the interlocks and the breaker for every
//! link alike.

use std::error::Error;
use std::fmt;

use super::addressing::Addressing;
use super::fence::FencedWrite;
use super::tcp::{ProtocolError, TransportError};
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

/// Every link's client error becomes a link error the same way: the transport's failure, or a
/// protocol fault where the CPU refused the request in a whole reply.
impl<E: ProtocolError> From<E> for LinkError {
    fn from(e: E) -> Self {
        let failure = e
            .transport()
            .map_or(Failure::Protocol, TransportError::failure);
        LinkError::new(failure, e)
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
    /// The state with where it was read: `STOP (M8000 off)`.
    pub text: String,
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
    /// reads. The default reads the span that holds them all in one request (the status words
    /// of the mailbox lie within its 32 words; reading a word twice changes nothing), then the
    /// state.
    fn poll(&mut self, devices: &[Device]) -> Result<(Vec<u16>, RunState), LinkError> {
        let mut out = Vec::with_capacity(devices.len());
        if let Some(head) = devices.iter().min_by_key(|d| d.index) {
            let last = devices.iter().map(|d| d.index).max().unwrap_or(head.index);
            let same_code = devices.iter().all(|d| d.code() == head.code());
            if same_code && (last - head.index) as usize <= self.batch_words() {
                let span = self.read(head, last - head.index + 1)?;
                for d in devices {
                    out.push(
                        span.get((d.index - head.index) as usize)
                            .copied()
                            .unwrap_or(0),
                    );
                }
            } else {
                for d in devices {
                    out.extend(self.read(d, 1)?);
                }
            }
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
    /// Which link this is: what a profile's `bench.link` must name for its manifests.
    fn kind(&self) -> crate::model::profile::LinkKind;
    /// A link, not yet connected.
    fn open(&self) -> Box<dyn Link>;
    /// The transport as provenance names it: the protocol, its options and the address.
    fn describe(&self) -> String;
    /// `host:port`.
    fn address(&self) -> &str;
    fn addressing(&self) -> &dyn Addressing;
    fn clone_box(&self) -> Box<dyn LinkSettings>;
}

impl Clone for Box<dyn LinkSettings> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

impl LinkSettings for Box<dyn LinkSettings> {
    fn kind(&self) -> crate::model::profile::LinkKind {
        self.as_ref().kind()
    }
    fn open(&self) -> Box<dyn Link> {
        self.as_ref().open()
    }
    fn describe(&self) -> String {
        self.as_ref().describe()
    }
    fn address(&self) -> &str {
        self.as_ref().address()
    }
    fn addressing(&self) -> &dyn Addressing {
        self.as_ref().addressing()
    }
    fn clone_box(&self) -> Box<dyn LinkSettings> {
        self.as_ref().clone_box()
    }
}
