//! The JSON Schemas in `schema/` are what editors use to complete and check files; they must be
//! exactly what the types generate, or an editor would accept what the loader rejects.

use std::path::Path;

fn checked_in(name: &str) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("schema")
        .join(name);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{} is not JSON: {e}", path.display()))
}

#[test]
fn vector_schema_is_current() {
    assert!(
        checked_in("vectors.schema.json") == plc_conformance::spec::vector_file_schema(),
        "schema/vectors.schema.json is stale: run `cargo run -- schema > schema/vectors.schema.json`"
    );
}

#[test]
fn profile_schema_is_current() {
    assert!(
        checked_in("profile.schema.json") == plc_conformance::profile::profile_schema(),
        "schema/profile.schema.json is stale: run `cargo run -- schema --kind profile > schema/profile.schema.json`"
    );
}

#[test]
fn vector_schema_is_draft_07_and_closed() {
    let schema = plc_conformance::spec::vector_file_schema();
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

#[test]
fn cross_vendor_schema_is_current() {
    assert!(
        checked_in("cross-vendor.schema.json") == plc_conformance::neutral::spec::neutral_file_schema(),
        "schema/cross-vendor.schema.json is stale: run `cargo run -- schema --kind cross-vendor > schema/cross-vendor.schema.json`"
    );
}
