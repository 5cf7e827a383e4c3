//! The JSON Schemas in `schema/` are what editors use to complete and check files; they must be
//! exactly what the types generate, or an editor would accept what the loader rejects.

use std::path::Path;

use plc_conformance::spec::{schema, SchemaKind};
use rstest::rstest;

fn checked_in(name: &str) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("schema")
        .join(name);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{} is not JSON: {e}", path.display()))
}

#[rstest]
#[case::vectors(SchemaKind::Vectors, "vectors.schema.json", "vectors")]
#[case::profile(SchemaKind::Profile, "profile.schema.json", "profile")]
#[case::cross_vendor(SchemaKind::CrossVendor, "cross-vendor.schema.json", "cross-vendor")]
#[case::project(SchemaKind::Project, "project.schema.json", "project")]
#[case::known(SchemaKind::Known, "known.schema.json", "known")]
fn checked_in_schema_is_current(#[case] kind: SchemaKind, #[case] file: &str, #[case] flag: &str) {
    assert!(
        checked_in(file) == schema(kind),
        "schema/{file} is stale: run `cargo run -- schema --kind {flag} > schema/{file}`"
    );
}

#[test]
fn vector_schema_is_draft_07_and_closed() {
    let schema = schema(SchemaKind::Vectors);
    assert_eq!(schema["$schema"], "http://json-schema.org/draft-07/schema#");
    assert_eq!(schema["additionalProperties"], false);
    let case = &schema["definitions"]["CaseSpec"];
    assert_eq!(case["additionalProperties"], false);
    for key in [
        "id", "basis", "cite", "flags", "operands", "before", "expect",
    ] {
        assert!(
            case["properties"].get(key).is_some(),
            "case schema lacks `{key}`"
        );
    }
}
