//! Open questions, validated: what a bench run with `plc-conformance run --probes` settles.

use super::Location;

// The run reads a question's id and probes; the other fields are the question as the loader
// checked it, which the corpus's own tests hold to its probes and readings.
#[derive(Debug, Clone)]
#[allow(dead_code)]
pub(crate) struct OpenQuestion {
    pub id: String,
    pub title: String,
    /// The profile of an instruction's question; empty for a protocol's.
    pub profile: String,
    /// The protocol of a protocol field's question.
    pub protocol: Option<String>,
    /// The profile variants it is about; all when `None`.
    pub variants: Option<Vec<String>>,
    /// The readings' ids, in file order.
    pub readings: Vec<String>,
    pub model_takes: String,
    /// Case ids whose outcome tells the readings apart; every one is in the corpus.
    pub probes: Vec<String>,
    /// The probe whose outcome differs under every reading, and each reading's outcome (as a
    /// report writes it); the reference model's must be `model_takes`'s.
    pub decides: Option<Decides>,
    pub location: Location,
}

#[derive(Debug, Clone)]
#[allow(dead_code)]
pub(crate) struct Decides {
    pub probe: String,
    /// By reading id, in the readings' order.
    pub outcomes: Vec<(String, String)>,
}
