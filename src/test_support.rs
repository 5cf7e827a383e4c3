//! What the crate's white-box tests share, once: the project root and a scratch folder, the
//! session with the reference models, a mutant of a model, and the readers of what a trial or a
//! report holds. Compiled for tests only (declared `#[cfg(test)]` in `lib.rs`).

#[cfg(test)]
use std::path::Path;
use std::process::Command;
use std::sync::{Arc, OnceLock};

use crate::plan::Check;
use crate::session::Session;
use crate::{
    Backend, Basis, Difference, ErrorSignal, Fault, Request, Response, Trial, Value, Verdict,
};
use crate::{Paths, Project};

/// The project root: its `vendors/`, `vectors/` and project file.
pub(crate) fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// An empty scratch folder for one test, removed when dropped.
pub(crate) fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("plc-conformance-")
        .tempdir()
        .expect("temp dir")
}

pub(crate) fn session() -> Session {
    match Project::load(&Paths::under(root())) {
        Ok(s) => Session::with_references(s),
        Err(e) => panic!("the corpus does not load:\n{e}"),
    }
}

/// The reference backend of a profile.
pub(crate) fn reference(session: &Session, profile: &str) -> Arc<dyn Backend> {
    session
        .backends
        .iter()
        .find(|b| b.profile() == profile)
        .cloned()
        .unwrap_or_else(|| panic!("no reference backend for {profile}"))
}

/// What a mutant does with a request, given the model it wraps.
type Behaviour = dyn Fn(&Request<'_>, &dyn Backend) -> Result<Response, Fault> + Send + Sync;

/// A wrong implementation: the reference model with one behaviour changed.
pub(crate) struct Mutant {
    name: &'static str,
    base: Arc<dyn Backend>,
    behave: Box<Behaviour>,
}

impl Mutant {
    /// Returns the mutant ready to run next to the other backends, hence not `Self`.
    #[allow(clippy::new_ret_no_self)]
    pub(crate) fn new(
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
pub(crate) fn map_done(
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
pub(crate) fn with_memory(
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
pub(crate) fn with_constant(
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
pub(crate) fn failing_trials(session: &Project, backend: &Arc<dyn Backend>) -> Vec<String> {
    session
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| t.skip.is_none())
        .filter(|t| crate::run_one(t).is_failure())
        .map(|t| t.name())
        .collect()
}

/// Asserts that the reference passes and that every mutant fails at least one trial.
pub(crate) fn assert_corpus_kills(
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

/// The Python interpreter itself (not a launcher script in front of it, which would add a
/// shell start to every restart), or `None` on a machine without python3.
pub(crate) fn interpreter() -> Option<&'static str> {
    static PATH: OnceLock<Option<String>> = OnceLock::new();
    PATH.get_or_init(|| {
        let out = Command::new("python3")
            .args(["-c", "import sys; print(sys.executable)"])
            .output()
            .ok()?;
        let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
        (out.status.success() && !path.is_empty()).then_some(path)
    })
    .as_deref()
}

/// Python runs the fixture adapters; a machine without it cannot run these tests.
pub(crate) fn python() -> bool {
    let ok = interpreter().is_some();
    // CI sets PLC_CONFORMANCE_REQUIRE_BACKENDS: there a missing interpreter is a failure.
    assert!(
        ok || std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
        "python3 is required for the fixture adapters"
    );
    if !ok {
        eprintln!("skipped: python3 is not installed; the fixture adapters need it");
    }
    ok
}

/// Every element with its attributes, in document order, from a document that must be
/// well-formed XML (a panic says where it is not).
pub(crate) fn xml_elements(text: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = Vec::new();
    loop {
        match reader.read_event() {
            Ok(quick_xml::events::Event::Start(e)) | Ok(quick_xml::events::Event::Empty(e)) => {
                out.push((
                    String::from_utf8_lossy(e.name().as_ref()).into_owned(),
                    xml_attributes(&e),
                ));
            }
            Ok(quick_xml::events::Event::Eof) => break,
            Ok(_) => {}
            Err(e) => panic!("not well-formed XML at {}: {e}", reader.buffer_position()),
        }
    }
    out
}

/// An element's attributes, raw: the attributes the tests read (names, classes, paths) hold no
/// escapes.
pub(crate) fn xml_attributes(e: &quick_xml::events::BytesStart<'_>) -> Vec<(String, String)> {
    e.attributes()
        .filter_map(Result::ok)
        .map(|a| {
            (
                String::from_utf8_lossy(a.key.as_ref()).into_owned(),
                String::from_utf8_lossy(&a.value).into_owned(),
            )
        })
        .collect()
}

/// Whether a trial's case expects an operation error with a code, and is judged on it (not
/// `unspecified`).
pub(crate) fn expects_a_code(t: &Trial) -> bool {
    match &t.check {
        Check::Native { case, .. } => {
            case.basis != Basis::Unspecified
                && case
                    .expect
                    .as_ref()
                    .is_some_and(|e| matches!(e.error, Some(ErrorSignal::Code(_))))
        }
        _ => false,
    }
}

/// The error registers that do not hold the code, with what they held, when a verdict differs
/// on them alone (the words and the error signal as expected); `None` for any other verdict.
pub(crate) fn registers_alone(v: &Verdict) -> Option<Vec<(String, Option<Value>)>> {
    let Verdict::Differs {
        difference: Difference::Words { mismatches },
    } = v
    else {
        return None;
    };
    let m = mismatches.first()?;
    (!m.words_differ() && !m.error_differs()).then(|| {
        m.wrong_registers()
            .map(|r| (r.device.to_string(), r.actual))
            .collect()
    })
}

/// The Python of `.venv-adapters` when it imports `modules` (an import list, `a, b`), or `None`
/// with a note saying how to install `packages`; with PLC_CONFORMANCE_REQUIRE_BACKENDS set (as
/// in CI) a missing one fails the test instead of skipping it.
pub(crate) fn adapters_python(modules: &str, packages: &str) -> Option<std::path::PathBuf> {
    let python = root().join(".venv-adapters/bin/python");
    let ok = python.exists()
        && Command::new(&python)
            .args(["-c", &format!("import {modules}")])
            .output()
            .is_ok_and(|o| o.status.success());
    assert!(
        ok || std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
        "required from .venv-adapters: {packages}"
    );
    if !ok {
        eprintln!(
            "skipped: not installed: {packages}; install them with `python3 -m venv \
             .venv-adapters && .venv-adapters/bin/pip install -r adapters/python/requirements.txt`"
        );
    }
    ok.then_some(python)
}

/// A HABIN case of profile `p` with nothing set: the fields a test does not care about filled
/// once (a citation and a location that name nothing).
pub(crate) fn habin_case(id: &str, basis: crate::Basis) -> crate::model::Case {
    crate::model::Case {
        id: id.into(),
        basis,
        citation: crate::model::Citation {
            manual: "m".into(),
            page: "1".into(),
            text: None,
        },
        location: crate::model::Location {
            file: std::path::PathBuf::from("v.yaml"),
            line: 1,
        },
        instructions: Arc::from(vec!["HABIN".to_string()]),
        profiles: Arc::from(vec!["p".to_string()]),
        variants: None,
        flags: Default::default(),
        operands: Default::default(),
        indirect: Default::default(),
        before: Default::default(),
        expect: None,
        note: None,
    }
}

/// A bench program's rung calling `instruction` with `operands` (name, operand text).
pub(crate) fn rung(
    id: u16,
    instruction: &str,
    operands: &[(&str, &str)],
) -> crate::backend::bench::manifest::Rung {
    crate::backend::bench::manifest::Rung {
        id,
        instruction: instruction.into(),
        operands: operands
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        addresses: Default::default(),
    }
}

/// A bench program's manifest for one variant, its hash computed; the rest a test sets.
pub(crate) fn manifest(
    profile: &str,
    variant: &str,
    mailbox: &str,
    error: crate::backend::bench::manifest::ErrorDevices,
    rungs: Vec<crate::backend::bench::manifest::Rung>,
    writes: &[&str],
    flags: &[&str],
) -> crate::backend::bench::manifest::Manifest {
    let mut m = crate::backend::bench::manifest::Manifest {
        format: crate::backend::bench::manifest::FORMAT,
        generator: "test".into(),
        profile: profile.into(),
        variants: vec![variant.into()],
        mailbox: mailbox.into(),
        layout: crate::backend::bench::mailbox::LAYOUT,
        flags: flags.iter().map(|f| f.to_string()).collect(),
        error,
        rungs,
        unrealisable: vec![],
        writes: writes.iter().map(|w| w.to_string()).collect(),
        hash: String::new(),
    };
    m.hash = m.compute_hash();
    m
}
