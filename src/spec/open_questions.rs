//! The open-questions file, `docs/open-questions.yaml`, as written on disk: the facts no cited
//! manual page settles, each with its competing readings and the probe vectors whose outcome on
//! a real CPU tells them apart.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Deserialize;

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance open questions")]
pub(crate) struct OpenQuestionsSpec {
    pub questions: Vec<QuestionSpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct QuestionSpec {
    /// Stable id: lowercase letters, digits and `-`.
    #[schemars(regex(pattern = r"^[a-z0-9]+(-[a-z0-9]+)*$"))]
    pub id: String,
    /// The question, in one line.
    pub title: String,
    /// The profile it is about (a question of an instruction).
    pub profile: Option<String>,
    /// The instructions it is about, as the profile spells them.
    #[serde(default)]
    pub instructions: Vec<String>,
    /// The protocol it is about (a question of a protocol's field, settled by a device's
    /// answer to a request), instead of `profile` and `instructions`.
    pub protocol: Option<String>,
    /// The profile variants it is about; all when absent.
    pub variants: Option<Vec<String>>,
    /// The competing answers, at least two.
    pub readings: Vec<ReadingSpec>,
    /// The reading the reference model implements, or `none`.
    pub model_takes: String,
    /// What the sources say: each a citation and its gist.
    pub evidence: Vec<String>,
    /// Case ids whose outcome on a real CPU tells the readings apart.
    pub probes: Vec<String>,
    /// The probe that tells every reading apart, and its outcome under each reading.
    pub decides: Option<DecidesSpec>,
    pub note: Option<String>,
    /// What CPUs on the bench answered.
    #[serde(default)]
    pub observed: Vec<ObservationSpec>,
}

#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct ReadingSpec {
    #[schemars(regex(pattern = r"^[a-z0-9]+(-[a-z0-9]+)*$"))]
    pub id: String,
    pub text: String,
}

/// A probe whose outcome differs under every reading: the outcome each reading predicts, written
/// as a report writes what a backend did (`error 3401H, no change`, `D200=0030H`, `no change`;
/// for a cross-vendor probe its answer, `0030H`), or in words for a reading that predicts no
/// single outcome (`an error other than 3401H`).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct DecidesSpec {
    /// One of the question's probes.
    pub probe: String,
    /// By reading id: every reading, each outcome different.
    pub outcomes: BTreeMap<String, String>,
}

/// One CPU's answer to a question.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct ObservationSpec {
    /// The reading the CPU's outcome matched.
    pub reading: String,
    pub variant: String,
    pub firmware: String,
    /// `YYYY-MM-DD`.
    #[schemars(regex(pattern = r"^[0-9]{4}-[0-9]{2}-[0-9]{2}$"))]
    pub date: String,
    pub by: String,
    pub note: Option<String>,
}
