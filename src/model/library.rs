//! The libraries of the results table, checked: each a backend whose saved runs make a row.

pub(crate) use crate::spec::libraries::Language;

/// One library of the results table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Library {
    pub backend: String,
    pub package: String,
    pub language: Language,
    pub licence: String,
    /// The protocol whose corpus judges it; `None` for the instruction level only.
    pub protocol: Option<String>,
    pub wired: String,
    /// Other backends of the same library, counted in its instruction view.
    pub also: Vec<String>,
}
