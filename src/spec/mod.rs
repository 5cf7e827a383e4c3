//! Everything the project reads from disk, as written: vector files, cross-vendor files, vendor
//! profiles, the project file and known-differences files.
//!
//! These types mirror the YAML one to one and check only its shape; what the values mean is
//! checked when [`crate::load`] turns them into [`crate::model`] types. The JSON Schemas shipped
//! for editors are generated from these types by one function, so schema and loader cannot
//! drift.

pub(crate) mod cross_vendor;
pub(crate) mod known;
pub(crate) mod libraries;
pub(crate) mod open_questions;
pub(crate) mod profile;
pub(crate) mod project;
pub(crate) mod protocol;
pub(crate) mod vectors;

pub use vectors::Basis;
pub(crate) use vectors::ScalarSpec;

/// The formats that have a JSON Schema: the on-disk files, the external-backend protocol's
/// messages and the JSON report (the command line's `schema --kind` takes these names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub(crate) enum SchemaKind {
    /// Vector files (`vectors/<family>/*.yaml`).
    Vectors,
    /// Vendor profiles (`vendors/*.yaml`).
    Profile,
    /// Cross-vendor vector files (`vectors/cross-vendor/*.yaml`).
    CrossVendor,
    /// The messages of the external-backend protocol.
    Protocol,
    /// The project file, `plc-conformance.yaml`.
    Project,
    /// A known-differences file.
    Known,
    /// The open-questions file, `docs/open-questions.yaml`.
    OpenQuestions,
    /// Protocol profiles (`vendors/protocols/*.yaml`): a communication protocol's fields and
    /// rules.
    ProtocolProfile,
    /// Protocol-field vector files (`vectors/protocols/*.yaml`).
    ProtocolFields,
    /// The libraries of the results table (`libraries.yaml`).
    Libraries,
    /// The JSON report (`--format json`, `--save`).
    Results,
}

/// The JSON report's schema, as shipped in `schema/`: written by hand, as the report's types
/// serialize by hand too (`report::json`).
const RESULTS_SCHEMA: &str = include_str!("../../schema/results.schema.json");

/// The JSON Schema (draft-07) of one format; `None` for the external-backend protocol's
/// messages, whose types live with that backend (`backend::external::protocol`), above this
/// layer.
pub(crate) fn schema(kind: SchemaKind) -> Option<serde_json::Value> {
    Some(match kind {
        SchemaKind::Vectors => schema_of::<vectors::VectorFileSpec>(),
        SchemaKind::Profile => schema_of::<profile::ProfileSpec>(),
        SchemaKind::CrossVendor => schema_of::<cross_vendor::CrossVendorFileSpec>(),
        SchemaKind::Project => schema_of::<project::ProjectFileSpec>(),
        SchemaKind::Known => schema_of::<known::KnownFileSpec>(),
        SchemaKind::OpenQuestions => schema_of::<open_questions::OpenQuestionsSpec>(),
        SchemaKind::ProtocolProfile => schema_of::<protocol::ProtocolSpec>(),
        SchemaKind::ProtocolFields => schema_of::<protocol::ProtocolFileSpec>(),
        SchemaKind::Libraries => schema_of::<libraries::LibrariesFileSpec>(),
        SchemaKind::Results => serde_json::from_str(RESULTS_SCHEMA).unwrap_or_default(),
        SchemaKind::Protocol => return None,
    })
}

/// The JSON Schema (draft-07) of any type: the one helper every schema comes from (the
/// external-backend protocol's too).
pub(crate) fn schema_of<T: schemars::JsonSchema>() -> serde_json::Value {
    let generator = schemars::generate::SchemaSettings::draft07().into_generator();
    serde_json::to_value(generator.into_root_schema_for::<T>()).unwrap_or_default()
}
