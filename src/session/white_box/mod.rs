//! The corpus through the backends: the cross-vendor cases against the reference models and
//! wrong ones, and the protocol-field corpora against codecs written here from each protocol's
//! rules. White-box tests of the crate's own parts, with no binary to run, so they live beside
//! the code they reach into.

#[cfg(test)]
use std::path::Path;
use std::sync::Arc;

use crate::session::Session;
use crate::{Backend, Fault, Request, Response};
use crate::{Paths, Project};

mod cross_vendor;
mod protocols;

/// The project root: its `vendors/`, `vectors/` and project file.
pub(super) fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

pub(super) fn session() -> Session {
    match Project::load(&Paths::under(root())) {
        Ok(s) => Session::with_references(s),
        Err(e) => panic!("the corpus does not load:\n{e}"),
    }
}

/// The reference backend of a profile.
pub(super) fn reference(session: &Session, profile: &str) -> Arc<dyn Backend> {
    session
        .backends
        .iter()
        .find(|b| b.profile() == profile)
        .cloned()
        .unwrap_or_else(|| panic!("no reference backend for {profile}"))
}

type Behaviour = dyn Fn(&Request<'_>, &dyn Backend) -> Result<Response, Fault> + Send + Sync;

/// A wrong implementation: the reference model with one behaviour changed.
pub(super) struct Mutant {
    name: &'static str,
    base: Arc<dyn Backend>,
    behave: Box<Behaviour>,
}

impl Mutant {
    /// Returns the mutant ready to run next to the other backends, hence not `Self`.
    #[allow(clippy::new_ret_no_self)]
    pub(super) fn new(
        name: &'static str,
        base: &Arc<dyn Backend>,
        behave: impl Fn(&Request<'_>, &dyn Backend) -> Result<Response, Fault> + Send + Sync + 'static,
    ) -> Arc<dyn Backend> {
        Arc::new(Mutant {
            name,
            base: base.clone(),
            behave: Box::new(behave),
        })
    }
}

impl Backend for Mutant {
    fn name(&self) -> &str {
        self.name
    }
    fn profile(&self) -> &str {
        self.base.profile()
    }
    fn describe(&self) -> String {
        format!("mutant {}", self.name)
    }
    fn claims(&self, instruction: &str, variant: &str) -> bool {
        self.base.claims(instruction, variant)
    }
    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        (self.behave)(request, self.base.as_ref())
    }
}
