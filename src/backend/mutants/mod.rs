//! Teeth for the corpus: each reference model held to the corpus by mutation. Every file here
//! builds deliberately wrong backends around one family's reference model, each with one
//! behaviour changed, and checks that the corpus tells each of them apart from the manual; this
//! module holds what they share.

#[cfg(test)]
use std::path::Path;
use std::sync::Arc;

use crate::session::Session;
use crate::Value;
use crate::{Backend, Fault, Request, Response};
use crate::{Paths, Project};

mod fc4a;
mod fp;
mod fx3;
mod fx5;
mod iqr;
mod kv;
mod omron;
mod s7;
mod s7_200;

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

/// Changes a finished outcome (a mutant's one change to what the reference did).
pub(super) fn map_done(
    result: Result<Response, Fault>,
    f: impl FnOnce(crate::Outcome) -> crate::Outcome,
) -> Result<Response, Fault> {
    result.map(|r| match r {
        Response::Done(o) => Response::Done(f(o)),
        other => other,
    })
}

/// Runs the base with every word (or byte) the case sets rewritten by `f` (the families the
/// mutants break are 16-bit or byte families).
pub(super) fn with_memory(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl Fn(u16) -> u16,
) -> Result<Response, Fault> {
    let units: std::collections::BTreeMap<crate::Device, Value> = req
        .memory
        .explicit()
        .iter()
        .map(|(d, v)| (d.clone(), Value::from(f(*v as u16))))
        .collect();
    let memory = crate::Image::of_units(units, req.memory.fill(), req.memory.unit());
    base.execute(&Request {
        memory: &memory,
        ..*req
    })
}

/// Runs the base with the constant operand `name` replaced by `f(k)` (as is when it is a
/// device).
pub(super) fn with_constant(
    req: &Request<'_>,
    base: &dyn Backend,
    name: &str,
    f: impl Fn(i64) -> i64,
) -> Result<Response, Fault> {
    let Some(crate::Operand::Constant(k)) = req.operands.get(name) else {
        return base.execute(req);
    };
    let mut operands = req.operands.clone();
    operands.insert(name.into(), crate::Operand::Constant(f(*k)));
    base.execute(&Request {
        operands: &operands,
        ..*req
    })
}

/// The trials of the corpus that fail on a backend (recorded `unspecified` cases never do).
pub(super) fn failing_trials(session: &Project, backend: &Arc<dyn Backend>) -> Vec<String> {
    session
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| t.skip.is_none())
        .filter(|t| crate::run_one(t).is_failure())
        .map(|t| t.name())
        .collect()
}

/// Asserts that the reference passes and that every mutant fails at least one trial.
pub(super) fn assert_corpus_kills(
    session: &Project,
    reference: &Arc<dyn Backend>,
    mutants: &[Arc<dyn Backend>],
) {
    let failing = failing_trials(session, reference);
    assert!(
        failing.is_empty(),
        "the reference model itself fails: {failing:?}"
    );
    let survivors: Vec<&str> = mutants
        .iter()
        .filter(|m| failing_trials(session, m).is_empty())
        .map(|m| m.name())
        .collect();
    assert!(
        survivors.is_empty(),
        "the corpus lets these wrong backends through (a vector is missing): {survivors:?}"
    );
}
