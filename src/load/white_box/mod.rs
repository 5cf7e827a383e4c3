//! The loader and the corpus's own evidence held to what they promise: every bad vector, profile
//! or question a load error with its file, line and key, the schemas what the types generate, and
//! every citation and quote pointing inside the repository. White-box tests of the crate's own
//! parts, with no binary to run, so they live beside the code they reach into.

#[cfg(test)]
use std::path::Path;

use crate::load::load_profiles;
use crate::model::profile::Profiles;
use crate::session::Session;
use crate::{Paths, Project};

mod citations;
mod fc4a_devices;
mod load_errors;
mod open_questions;
mod schema;

/// The project root: its `vendors/`, `vectors/` and project file.
pub(super) fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// An empty scratch folder for one test, removed when dropped.
pub(super) fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("plc-conformance-")
        .tempdir()
        .expect("temp dir")
}

/// The vendor profiles of `vendors/`.
pub(super) fn profiles() -> Profiles {
    let dir = root().join("vendors");
    load_profiles(&dir).unwrap_or_else(|e| panic!("vendor profiles do not load:\n{e}"))
}

pub(super) fn session() -> Session {
    match Project::load(&Paths::under(root())) {
        Ok(s) => Session::with_references(s),
        Err(e) => panic!("the corpus does not load:\n{e}"),
    }
}
