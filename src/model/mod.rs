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
    /// The vector file the case is written in.
    pub file: PathBuf,
    /// The line the case starts on (its `- id:`), counted from 1 as editors do.
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
    /// A device (`D100`, `MB20`): memory the instruction reads or writes.
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
    /// An error code as the vendor documents it (MELSEC 3401H), in a register or returned.
    Code(u16),
    /// An error flag turned on (IDEC M8004), for vendors that signal with a relay only.
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
    /// The units expected to change, with their new values; any other change is a difference.
    pub after: BTreeMap<Device, Value>,
    /// The error signal expected; `None` expects the instruction to succeed.
    pub error: Option<ErrorSignal>,
}

/// Where an expectation comes from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Citation {
    /// The manual's id, as the profile lists its manuals (`iqr-instructions-ja`).
    pub manual: String,
    /// The page cited; empty when the citation names no page.
    pub page: String,
    /// The manual's words quoted, or what an inferred expectation rests on.
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
    /// The case id: what trial names, filters and known-differences entries use.
    pub id: String,
    /// How far the expectation can be trusted: manual, inferred, unspecified or observed.
    pub basis: Basis,
    /// The manual, page and quoted text the expectation rests on.
    pub citation: Citation,
    /// Where the case is written, for reports to point at.
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
    /// The memory the case sets before execution; every other unit holds fill A or B.
    pub before: BTreeMap<Device, Value>,
    /// `None` only for `unspecified` cases that record without a guess.
    pub expect: Option<Expectation>,
    /// Free text for readers of the case.
    pub note: Option<String>,
}

impl Case {
    /// Whether the case applies to a variant: to every one unless it lists some.
    pub fn runs_on(&self, variant: &str) -> bool {
        self.variants.as_ref().is_none_or(|v| v.contains(variant))
    }
}

/// Every case of every vector file, in file order.
#[derive(Debug, Clone, Default)]
pub struct Corpus {
    /// Native cases, each run on the instructions and profiles its file names.
    pub cases: Vec<Arc<Case>>,
    /// Cross-vendor cases (`vectors/cross-vendor/`).
    pub cross_vendor: Vec<Arc<cross_vendor::CrossVendorCase>>,
    /// Protocol-field cases (`vectors/protocols/`): codec questions a protocol's manual answers.
    pub protocol_fields: Vec<Arc<cross_vendor::CrossVendorCase>>,
}
