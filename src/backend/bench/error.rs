//! The live path's one error type: settings, a manifest, a program or a case that does not
//! hold together (refused before any byte is sent), and what went wrong reaching the CPU.

use std::error::Error;
use std::fmt;

use super::fence::Refused;
use super::link::LinkError;
use super::tcp::ProtocolError;

/// An error underneath another: a device that does not parse, a file that cannot be read, the
/// link's error, or a nested [`LiveError`].
pub(crate) type Cause = Box<dyn Error + Send + Sync>;

/// Why the live path refuses or stops.
#[derive(Debug)]
pub enum LiveError {
    /// What does not hold together, in words, with what to do instead.
    Refused(String),
    /// The part concerned (`` `mailbox` ``, `rung 3 operand `s``, a file) and the error
    /// underneath, returned by `source()`.
    In { part: String, source: Cause },
    /// The CPU could not be reached or answered with an error.
    Link(LinkError),
    /// A write outside the write fence.
    Fence(Refused),
}

impl From<Refused> for LiveError {
    fn from(e: Refused) -> Self {
        LiveError::Fence(e)
    }
}

impl From<LinkError> for LiveError {
    fn from(e: LinkError) -> Self {
        LiveError::Link(e)
    }
}

/// A link client's error, as its link's error ([`LinkError`]'s `From`).
impl<E: ProtocolError> From<E> for LiveError {
    fn from(e: E) -> Self {
        LiveError::Link(e.into())
    }
}

impl LiveError {
    /// `source` as the error of `part`.
    pub(crate) fn within(part: impl Into<String>, source: impl Into<Cause>) -> Self {
        LiveError::In {
            part: part.into(),
            source: source.into(),
        }
    }
}

impl fmt::Display for LiveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LiveError::Refused(why) => f.write_str(why),
            LiveError::In { part, .. } => f.write_str(part),
            LiveError::Link(e) => write!(f, "{e}"),
            LiveError::Fence(e) => write!(f, "{e}"),
        }
    }
}

impl Error for LiveError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        match self {
            LiveError::Refused(_) => None,
            LiveError::In { source, .. } => Some(source.as_ref()),
            LiveError::Link(e) => e.source(),
            LiveError::Fence(e) => e.source(),
        }
    }
}

/// A [`LiveError::Refused`] written as `format!` is.
macro_rules! refused {
    ($($message:tt)*) => {
        $crate::backend::bench::error::LiveError::Refused(format!($($message)*))
    };
}
pub(crate) use refused;
