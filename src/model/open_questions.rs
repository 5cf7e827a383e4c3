//! Open questions, validated: what a bench run with `plc-conformance run --probes` settles.

use super::Location;

#[derive(Debug, Clone)]
pub struct OpenQuestion {
    pub id: String,
    pub title: String,
    pub profile: String,
    /// The readings' ids, in file order.
    pub readings: Vec<String>,
    pub model_takes: String,
    /// Case ids whose outcome tells the readings apart; every one is in the corpus.
    pub probes: Vec<String>,
    pub location: Location,
}
