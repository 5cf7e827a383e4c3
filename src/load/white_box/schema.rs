//! The JSON Schemas in `schema/` are what editors use to complete and check files; they must be
//! exactly what the types generate, or an editor would accept what the loader rejects.

#[cfg(test)]
use std::path::Path;

use crate::spec::{schema, SchemaKind};
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
#[case::open_questions(
    SchemaKind::OpenQuestions,
    "open-questions.schema.json",
    "open-questions"
)]
#[case::protocol_profile(
    SchemaKind::ProtocolProfile,
    "protocol-profile.schema.json",
    "protocol-profile"
)]
#[case::protocol_fields(
    SchemaKind::ProtocolFields,
    "protocol-fields.schema.json",
    "protocol-fields"
)]
#[case::libraries(SchemaKind::Libraries, "libraries.schema.json", "libraries")]
fn checked_in_schema_is_current(#[case] kind: SchemaKind, #[case] file: &str, #[case] flag: &str) {
    assert!(
        checked_in(file) == schema(kind).expect("a file format"),
        "schema/{file} is stale: run `cargo run -- schema --kind {flag} > schema/{file}`"
    );
}

#[test]
fn vector_schema_is_draft_07_and_closed() {
    let schema = schema(SchemaKind::Vectors).expect("a file format");
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

/// Every YAML file of the project names its schema on its first line, and the schema exists, so
/// an editor checks it as it is typed.
#[test]
fn every_yaml_file_names_its_schema() {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let p = e.path();
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if p.is_dir() {
                // `templates/` holds what `init` writes into another repository, where no
                // schema of this one is at hand.
                if !matches!(name, "node_modules" | "target" | "templates" | ".git")
                    && !name.starts_with('.')
                {
                    walk(&p, out);
                }
            } else if name.ends_with(".yaml") {
                out.push(p);
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    walk(root, &mut files);
    assert!(files.len() > 15, "{files:?}");
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let first = text.lines().next().unwrap_or("");
        let Some(schema) = first.strip_prefix("# yaml-language-server: $schema=") else {
            panic!("{} does not name its schema on line 1", file.display());
        };
        let target = file.parent().unwrap_or(root).join(schema);
        assert!(
            target.is_file(),
            "{}: the schema {schema} does not exist",
            file.display()
        );
    }
}

/// Validates YAML text against a checked-in schema with an independent JSON Schema validator;
/// the error text, or `None` when valid.
fn validate(schema_file: &str, yaml: &str) -> Option<String> {
    let schema = checked_in(schema_file);
    let validator = jsonschema::validator_for(&schema)
        .unwrap_or_else(|e| panic!("{schema_file} does not compile: {e}"));
    let instance: serde_json::Value =
        serde_yaml::from_str(yaml).unwrap_or_else(|e| panic!("not YAML: {e}"));
    let errors: Vec<String> = validator
        .iter_errors(&instance)
        .map(|e| e.to_string())
        .collect();
    (!errors.is_empty()).then(|| errors.join("\n"))
}

/// The shipped corpus is valid under its schemas, and the schemas' patterns catch what an
/// editor should flag while typing: a device with letter O for zero, a value that is not hex.
#[test]
fn an_independent_validator_accepts_the_corpus_and_flags_bad_devices_and_values() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("vectors");
    let mut checked = 0;
    for dir in std::fs::read_dir(&root).expect("vectors").flatten() {
        for file in std::fs::read_dir(dir.path())
            .into_iter()
            .flatten()
            .flatten()
        {
            let p = file.path();
            if p.extension().and_then(|e| e.to_str()) != Some("yaml") {
                continue;
            }
            let text = std::fs::read_to_string(&p).expect("read");
            let schema = if p.parent().is_some_and(|d| d.ends_with("cross-vendor")) {
                "cross-vendor.schema.json"
            } else if p.parent().is_some_and(|d| d.ends_with("protocols")) {
                "protocol-fields.schema.json"
            } else {
                "vectors.schema.json"
            };
            assert_eq!(validate(schema, &text), None, "{}", p.display());
            checked += 1;
        }
    }
    assert!(checked >= 9, "{checked} files");
    let good = concat!(
        "instructions: [HABIN]\n",
        "profiles: [mitsubishi-iqr]\n",
        "source: {manual: iqr-instructions-ja, page: 478}\n",
        "cases:\n",
        "- id: c\n",
        "  basis: manual\n",
        "  cite: x\n",
        "  operands: {s: D100, d: D200}\n",
        "  before: {D100: 4135H}\n",
        "  expect: {after: {D200: 5A8DH}}\n",
    );
    assert_eq!(validate("vectors.schema.json", good), None);
    for (find, replace) in [
        ("s: D100", "s: D1OO"),
        ("before: {D100:", "before: {D2OO:"),
        ("D100: 4135H", "D100: 5A8G"),
        ("after: {D200: 5A8DH}", "after: {D200: 5A8GH}"),
    ] {
        let bad = good.replacen(find, replace, 1);
        assert!(
            validate("vectors.schema.json", &bad).is_some(),
            "the schema accepts `{replace}`"
        );
    }
}
