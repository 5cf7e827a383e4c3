//! What the integration tests share: the binary run on this project, a scratch folder, the
//! session and a reference model, a mutant of a model, the Python of the pinned adapters, and
//! the readers of XML reports. (The crate's white-box tests have their own, in
//! `src/test_support.rs`: an integration test cannot reach a `#[cfg(test)]` item.)
// Each test file compiles this module anew and uses only part of it.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};
use std::sync::{Arc, OnceLock};

use plc_conformance::testing::session::Session;
use plc_conformance::Value;
use plc_conformance::{Backend, Fault, Request, Response};
use plc_conformance::{Paths, Project};

/// The project root: its `vendors/`, `vectors/` and project file.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The binary, without colour and without a project file named by the environment.
pub fn bin() -> assert_cmd::Command {
    let mut command = assert_cmd::cargo::cargo_bin_cmd!("plc-conformance");
    command
        .env("NO_COLOR", "1")
        .env_remove(plc_conformance::testing::load::ENV_CONFIG);
    command
}

/// Runs the binary on this project, without colour.
pub fn cli(args: &[&str]) -> Output {
    bin()
        .args(["--root", root().to_str().unwrap_or(".")])
        .args(args)
        .output()
        .expect("the binary runs")
}

/// An empty scratch folder for one test, removed when dropped.
pub fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("plc-conformance-")
        .tempdir()
        .expect("temp dir")
}

pub fn session() -> Session {
    match Project::load(&Paths::under(root())) {
        Ok(s) => Session::with_references(s),
        Err(e) => panic!("the corpus does not load:\n{e}"),
    }
}

/// The reference backend of a profile.
pub fn reference(session: &Session, profile: &str) -> Arc<dyn Backend> {
    session
        .backends
        .iter()
        .find(|b| b.profile() == profile)
        .cloned()
        .unwrap_or_else(|| panic!("no reference backend for {profile}"))
}

type Behaviour = dyn Fn(&Request<'_>, &dyn Backend) -> Result<Response, Fault> + Send + Sync;

/// A wrong implementation: the reference model with one behaviour changed.
pub struct Mutant {
    pub name: &'static str,
    pub base: Arc<dyn Backend>,
    pub behave: Box<Behaviour>,
}

impl Mutant {
    /// Returns the mutant ready to run next to the other backends, hence not `Self`.
    #[allow(clippy::new_ret_no_self)]
    pub fn new(
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

/// Runs the base with every word (or byte) the case sets rewritten by `f` (the families the
/// mutants break are 16-bit or byte families).
pub fn with_memory(
    req: &Request<'_>,
    base: &dyn Backend,
    f: impl Fn(u16) -> u16,
) -> Result<Response, Fault> {
    let units: std::collections::BTreeMap<plc_conformance::Device, Value> = req
        .memory
        .explicit()
        .iter()
        .map(|(d, v)| (d.clone(), Value::from(f(*v as u16))))
        .collect();
    let memory = plc_conformance::Image::of_units(units, req.memory.fill(), req.memory.unit());
    base.execute(&Request {
        memory: &memory,
        ..*req
    })
}

/// The trials of the corpus that fail on a backend (recorded `unspecified` cases never do).
pub fn failing_trials(session: &Project, backend: &Arc<dyn Backend>) -> Vec<String> {
    session
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| t.skip.is_none())
        .filter(|t| plc_conformance::run_one(t).is_failure())
        .map(|t| t.name())
        .collect()
}

/// The Python interpreter itself (not a launcher script in front of it, which would add a
/// shell start to every restart), or `None` on a machine without python3.
pub fn interpreter() -> Option<&'static str> {
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
pub fn python() -> bool {
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
pub fn xml_elements(text: &str) -> Vec<(String, Vec<(String, String)>)> {
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
pub fn xml_attributes(e: &quick_xml::events::BytesStart<'_>) -> Vec<(String, String)> {
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

/// A vector file of one case: the HABIN example of iqr-instructions-ja p.478 ("5A8D" in D100),
/// with case id `id` and `expected` as the word D200 must hold (`5A8DH` is what the manual says).
pub fn habin_example(id: &str, expected: &str) -> String {
    format!(
        "\
instructions: [HABIN]
profiles: [mitsubishi-iqr]
source: {{manual: iqr-instructions-ja, page: 478}}
cases:
  - id: {id}
    basis: manual
    cite: example on p.478
    operands: {{s: D100, d: D200}}
    before:
      D100: {{ascii: \"5A8D\"}}
    expect:
      after: {{D200: {expected}}}
"
    )
}

/// A folder and everything in it, copied: a fixture to change in a scratch folder.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).expect("copy");
        }
    }
}

/// The Python of `.venv-adapters` when it imports `modules` (an import list, `a, b`), or `None`
/// with a note saying how to install `packages`; with PLC_CONFORMANCE_REQUIRE_BACKENDS set (as
/// in CI) a missing one fails the test instead of skipping it.
pub fn adapters_python(modules: &str, packages: &str) -> Option<std::path::PathBuf> {
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
