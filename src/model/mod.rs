//! The validated model: what the loader produces and everything downstream consumes.
//!
//! Unlike [`crate::spec`], nothing here is stringly typed: devices are parsed, values are words,
//! flags are booleans, and every case knows where it was written so a report can point at it.

pub(crate) mod cross_vendor;
pub(crate) mod known;
pub(crate) mod library;
pub(crate) mod open_questions;
pub(crate) mod profile;
pub(crate) mod project;
pub(crate) mod protocol;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use serde::Serialize;

use crate::device::Device;
use crate::memory::Value;
use crate::value::hex_word;

pub use crate::spec::Basis;

/// A place in a vector file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Location {
    pub file: PathBuf,
    pub line: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.file.display(), self.line)
    }
}

/// An operand as written in a vector.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", content = "value", rename_all = "lowercase")]
pub enum Operand {
    Device(Device),
    /// A constant (`K4`, `H0ABC`, `4`), kept wide: 32-bit instructions take 32-bit constants.
    Constant(i64),
}

impl fmt::Display for Operand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Operand::Device(d) => write!(f, "{d}"),
            Operand::Constant(k) => write!(f, "K{k}"),
        }
    }
}

/// How an operation error became visible: the vendor's code, or a flag for vendors that signal
/// with a relay only. The two never compare equal, so an IDEC expectation of M8004 is never
/// satisfied by a Mitsubishi-style code, nor the other way round.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ErrorSignal {
    Code(u16),
    Flag(Device),
}

impl fmt::Display for ErrorSignal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorSignal::Code(c) => f.write_str(&hex_word(*c)),
            ErrorSignal::Flag(d) => write!(f, "{d} on"),
        }
    }
}

/// Displays an optional error as the vectors write it.
pub(crate) fn error_text(error: Option<&ErrorSignal>) -> String {
    error.map_or_else(|| "none".to_string(), ToString::to_string)
}

/// What a case expects: the words that change and the error signalled.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
pub struct Expectation {
    pub after: BTreeMap<Device, Value>,
    pub error: Option<ErrorSignal>,
}

/// Where an expectation comes from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Citation {
    pub manual: String,
    pub page: String,
    pub text: Option<String>,
}

impl fmt::Display for Citation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.page.is_empty() {
            write!(f, "{}", self.manual)?;
        } else {
            write!(f, "{} p.{}", self.manual, self.page)?;
        }
        if let Some(text) = &self.text {
            write!(f, ": {text}")?;
        }
        Ok(())
    }
}

/// Operands given by indirect specification, by name, with the device holding each one's
/// address.
pub type Indirect = BTreeMap<String, Device>;

/// No operand given by indirect specification: for requests that are not a vector's.
pub(crate) const DIRECT: &Indirect = &BTreeMap::new();

/// The words of these pointers: two from each, holding an address in the CPU's own encoding.
pub(crate) fn pointer_words<'a>(pointers: impl IntoIterator<Item = &'a Device>) -> Vec<Device> {
    pointers
        .into_iter()
        .flat_map(|p| [Some(p.clone()), p.offset(1)])
        .flatten()
        .collect()
}

/// One validated test vector.
#[derive(Debug, Clone, Serialize)]
pub struct Case {
    pub id: String,
    pub basis: Basis,
    pub citation: Citation,
    pub location: Location,
    /// The instructions the case runs as (from its file).
    pub instructions: Arc<[String]>,
    /// The profiles the case applies to (from its file).
    pub profiles: Arc<[String]>,
    /// Restriction to some variants; `None` is every variant.
    pub variants: Option<BTreeSet<String>>,
    /// Flags the case sets; the rest hold the profile default.
    pub flags: BTreeMap<String, bool>,
    /// Operands by name; one given by indirect specification holds the device it addresses.
    pub operands: BTreeMap<String, Operand>,
    /// The operands given by indirect specification (`s: '@D10'`), with the device holding
    /// their address (`s` -> D10): models execute on the addressed device in `operands`, an
    /// emulator over the protocol is given the pointer and the address to store in it.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub indirect: Indirect,
    pub before: BTreeMap<Device, Value>,
    /// `None` only for `unspecified` cases that record without a guess.
    pub expect: Option<Expectation>,
    pub note: Option<String>,
}

impl Case {
    pub fn runs_on(&self, variant: &str) -> bool {
        self.variants.as_ref().is_none_or(|v| v.contains(variant))
    }
}

/// Every case of every vector file, in file order.
#[derive(Debug, Clone, Default)]
pub struct Corpus {
    pub cases: Vec<Arc<Case>>,
    /// Cross-vendor cases (`vectors/cross-vendor/`).
    pub cross_vendor: Vec<Arc<cross_vendor::CrossVendorCase>>,
    /// Protocol-field cases (`vectors/protocols/`): codec questions a protocol's manual answers.
    pub protocol_fields: Vec<Arc<cross_vendor::CrossVendorCase>>,
}
