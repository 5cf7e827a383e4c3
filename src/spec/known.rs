//! Known-differences files as written on disk.

use schemars::JsonSchema;
use serde::Deserialize;

/// A known-differences file as written.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KnownFileSpec {
    pub differences: Vec<EntrySpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EntrySpec {
    /// A case id of the corpus (a cross-vendor case id too).
    pub case: String,
    /// Only this instruction of the case's file (for a cross-vendor case: only this lowering of
    /// the profile, e.g. `habin-fixed`).
    #[serde(default)]
    pub instruction: Option<String>,
    /// Only this variant of the profile.
    #[serde(default)]
    pub variant: Option<String>,
    /// Why the backend differs: shown with the trial.
    pub reason: String,
}
