//! The list of libraries of the results table (`libraries.yaml`) as written on disk.

use schemars::JsonSchema;
use serde::Deserialize;

/// `libraries.yaml`: the third-party libraries whose runs make the results table, in its order.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct LibrariesFileSpec {
    pub libraries: Vec<LibrarySpec>,
}

/// One library: the backend whose runs it is, and what a reader needs to find its code.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct LibrarySpec {
    /// The backend name its runs carry (`aslmp`).
    pub backend: String,
    /// The package as its registry names it (`aslmp`, `@csllc/cs-modbus`).
    pub package: String,
    /// `Python`, `JavaScript` or `Rust`.
    pub language: Language,
    /// The licence the package declares (SPDX).
    pub licence: String,
    /// The protocol whose corpus judges it (`mc-ascii`); none for a library judged at the
    /// instruction level only.
    pub protocol: Option<String>,
    /// The library's functions the adapter calls, with the pinned version's file and line.
    pub wired: String,
    /// Other backends of the same library (its instruction level, say), whose trials count in
    /// the row's instruction view.
    #[serde(default)]
    pub also: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Deserialize, JsonSchema)]
pub(crate) enum Language {
    Python,
    JavaScript,
    Rust,
}

impl Language {
    /// The registry its packages come from.
    pub(crate) fn registry(self) -> &'static str {
        match self {
            Language::Python => "PyPI",
            Language::JavaScript => "npm",
            Language::Rust => "crates.io",
        }
    }
}

impl std::fmt::Display for Language {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Language::Python => "Python",
            Language::JavaScript => "JavaScript",
            Language::Rust => "Rust",
        })
    }
}
