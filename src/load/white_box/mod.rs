//! The loader and the corpus's own evidence held to what they promise: every bad vector, profile
//! or question a load error with its file, line and key, the schemas what the types generate, and
//! every citation and quote pointing inside the repository. White-box tests of the crate's own
//! parts, with no binary to run, so they live beside the code they reach into.

#[cfg(test)]
pub(super) use crate::test_support::{root, scratch, session};

use crate::load::load_profiles;
use crate::model::profile::Profiles;

mod citations;
mod fc4a_devices;
mod fx5_operands;
mod load_errors;
mod open_questions;
mod schema;

/// The vendor profiles of `vendors/`.
pub(super) fn profiles() -> Profiles {
    let dir = root().join("vendors");
    load_profiles(&dir).unwrap_or_else(|e| panic!("vendor profiles do not load:\n{e}"))
}

/// Loads one vector file's text against the real profiles: `Ok` or the load errors as shown.
pub(super) fn load_probe(text: &str) -> Result<(), String> {
    let mut builder = crate::load::CorpusBuilder::default();
    builder.add_file(std::path::Path::new("probe.yaml"), text, &profiles());
    builder.finish().map(|_| ()).map_err(|e| e.to_string())
}
