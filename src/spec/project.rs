//! The project file, `plc-conformance.yaml`, as written on disk.

use std::path::PathBuf;

use schemars::JsonSchema;
use serde::Deserialize;

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance project file")]
pub(crate) struct ProjectFileSpec {
    /// External backends, run as extra trials.
    #[serde(default)]
    pub backends: Vec<BackendSpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct BackendSpec {
    /// The name in trial names: lowercase letters, digits, `-` and `_`.
    pub name: String,
    /// A command line run by `sh -c`, or a list of program and arguments run directly.
    pub command: CommandSpec,
    /// The profile family the backend implements; its handshake must claim the same.
    pub profile: Option<String>,
    /// The backend is codec-level (it answers the cross-vendor operations directly); its
    /// handshake must claim the codec level. Declared here, as `profile` is for an
    /// instruction-level backend, it lets `cargo test` plan its trials without starting it.
    #[serde(default)]
    pub codec: bool,
    /// A codec-level backend that implements a protocol's fields (`mc-ascii`, `modbus-ascii`):
    /// it is judged by that protocol's corpus, and its handshake must name the same protocol.
    pub protocol: Option<String>,
    /// With `protocol`: also run the cross-vendor (instruction) corpus.
    #[serde(default)]
    pub cross_vendor: bool,
    /// Seconds to wait for one case's answer.
    pub timeout: Option<f64>,
    /// Seconds to wait for the backend to start and answer `hello`.
    pub startup_timeout: Option<f64>,
    /// The backend's known-differences file.
    pub known_differences: Option<PathBuf>,
    /// Files the backend needs (an interpreter in a virtual environment, a built binary). When
    /// one is missing the backend is skipped with a message, or is an error when
    /// `PLC_CONFORMANCE_REQUIRE_BACKENDS` is set.
    #[serde(default)]
    pub requires: Vec<PathBuf>,
    /// Cases per `run` message.
    pub batch: Option<usize>,
    /// Faults (crash, timeout, protocol error) in a row after which the backend's remaining
    /// trials are reported as not run, as failures with the reason (default 5).
    pub max_consecutive_faults: Option<usize>,
    /// Run only when named with `--backend`: for a check of the harness itself (the built-in
    /// models served through the protocol) rather than an implementation under test. Such a
    /// backend is in no `run`, `diff` or `cargo test` trial unless asked for.
    #[serde(default)]
    pub on_request: bool,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum CommandSpec {
    Shell(String),
    Exec(Vec<String>),
}
