//! Checking a document's shape against its JSON Schema before deserialising it, so that every
//! unknown key, missing key and misplaced list or mapping of a file is reported in one pass —
//! the deserializer stops at the first — and an unknown key comes with the nearest known one.
//!
//! The schema is the one generated from the on-disk types ([`crate::spec`]), so this check and
//! the deserializer agree on what a file may hold. Only the parts of draft-07 the generated
//! schemas use for structure are read (`$ref`, `type`, `properties`, `required`,
//! `additionalProperties`, `items`); alternatives (`anyOf`, `oneOf`) and scalar formats are left
//! to the deserializer, which reports them with their own line.

use serde_json::Value as Json;
use serde_yaml::Value as Yaml;

use super::{FileContext, LoadErrorKind};

/// Reports every shape problem of `doc` against `schema`; true when there is none.
pub(crate) fn check(doc: &Yaml, schema: &Json, cx: &mut FileContext<'_>) -> bool {
    let before = cx.errors.len();
    walk(doc, schema, schema, &Path::Root, cx);
    cx.errors.len() == before
}

fn resolve<'a>(node: &'a Json, root: &'a Json) -> &'a Json {
    let mut node = node;
    // `$ref`s point into `definitions`; a chain of them ends at a real schema.
    for _ in 0..16 {
        match node.get("$ref").and_then(Json::as_str) {
            Some(r) => match r
                .strip_prefix("#/definitions/")
                .and_then(|name| root.get("definitions")?.get(name))
            {
                Some(target) => node = target,
                None => return node,
            },
            None => return node,
        }
    }
    node
}

fn types(schema: &Json) -> Vec<&str> {
    match schema.get("type") {
        Some(Json::String(t)) => vec![t.as_str()],
        Some(Json::Array(ts)) => ts.iter().filter_map(Json::as_str).collect(),
        _ => Vec::new(),
    }
}

/// Where a node is (`cases[3].before`), written out only for an error: most documents have
/// none, and a path made for every node was most of the walk.
enum Path<'a> {
    Root,
    Key(&'a Path<'a>, &'a str),
    Index(&'a Path<'a>, usize),
}

impl Path<'_> {
    fn render(&self) -> String {
        match self {
            Path::Root => String::new(),
            Path::Key(Path::Root, key) => key.to_string(),
            Path::Key(parent, key) => format!("{}.{key}", parent.render()),
            Path::Index(parent, i) => format!("{}[{i}]", parent.render()),
        }
    }
}

fn walk(doc: &Yaml, schema: &Json, root: &Json, path: &Path<'_>, cx: &mut FileContext<'_>) {
    let schema = resolve(schema, root);
    if let Some(branches) = schema
        .get("anyOf")
        .or_else(|| schema.get("oneOf"))
        .and_then(Json::as_array)
    {
        // An optional field is "this or null": its one other branch is the shape to check.
        // Real alternatives are the deserializer's to decide.
        let others: Vec<&Json> = branches
            .iter()
            .filter(|b| resolve(b, root).get("type").and_then(Json::as_str) != Some("null"))
            .collect();
        if let ([only], false) = (others.as_slice(), doc.is_null()) {
            walk(doc, only, root, path, cx);
        }
        return;
    }
    let kinds = types(schema);
    match doc {
        Yaml::Mapping(map) if kinds.is_empty() || kinds.contains(&"object") => {
            let properties = schema.get("properties").and_then(Json::as_object);
            let closed = schema.get("additionalProperties") == Some(&Json::Bool(false));
            let extra = schema.get("additionalProperties").filter(|a| a.is_object());
            for (k, v) in map {
                let key = yaml_key(k);
                let here = Path::Key(path, &key);
                match properties.and_then(|p| p.get(key.as_ref())) {
                    Some(sub) => walk(v, sub, root, &here, cx),
                    None if closed => {
                        let known: Vec<&str> = properties
                            .map(|p| p.keys().map(String::as_str).collect())
                            .unwrap_or_default();
                        cx.error(here.render(), unknown_key(&key, &known));
                    }
                    None => {
                        if let Some(sub) = extra {
                            walk(v, sub, root, &here, cx);
                        }
                    }
                }
            }
            for required in schema
                .get("required")
                .and_then(Json::as_array)
                .into_iter()
                .flatten()
                .filter_map(Json::as_str)
            {
                let present = map.keys().any(|k| yaml_key(k) == required);
                if !present {
                    cx.error(
                        path.render(),
                        LoadErrorKind::Shape(format!("missing field `{required}`")),
                    );
                }
            }
        }
        Yaml::Sequence(items) if kinds.is_empty() || kinds.contains(&"array") => {
            if let Some(item) = schema.get("items") {
                for (i, v) in items.iter().enumerate() {
                    walk(v, item, root, &Path::Index(path, i), cx);
                }
            }
        }
        Yaml::Tagged(t) => walk(&t.value, schema, root, path, cx),
        _ => {
            let wanted = if kinds.contains(&"object") {
                Some("a mapping (`key: value` lines)")
            } else if kinds.contains(&"array") {
                Some("a list (`[a, b]` or `- a` lines)")
            } else {
                None
            };
            let got = match doc {
                Yaml::Mapping(_) => Some("a mapping"),
                Yaml::Sequence(_) => Some("a list"),
                Yaml::Null if kinds.contains(&"null") => None,
                _ => {
                    if wanted.is_some() {
                        Some("a single value")
                    } else {
                        None
                    }
                }
            };
            if let (Some(wanted), Some(got)) = (wanted, got) {
                cx.error(
                    path.render(),
                    LoadErrorKind::Shape(format!("expected {wanted}, found {got}")),
                );
            }
        }
    }
}

fn yaml_key(k: &Yaml) -> std::borrow::Cow<'_, str> {
    match k {
        Yaml::String(s) => s.as_str().into(),
        Yaml::Number(n) => n.to_string().into(),
        Yaml::Bool(b) => b.to_string().into(),
        other => serde_yaml::to_string(other)
            .unwrap_or_default()
            .trim()
            .to_string()
            .into(),
    }
}

/// An unknown key, with the nearest known one when it is a likely typo.
fn unknown_key(key: &str, known: &[&str]) -> LoadErrorKind {
    let nearest = crate::nearest::nearest(key, known.iter().copied());
    let listed = known
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ");
    LoadErrorKind::Shape(match nearest {
        Some(k) => {
            format!("unknown field `{key}`: did you mean `{k}`? (expected one of {listed})")
        }
        None => format!("unknown field `{key}`, expected one of {listed}"),
    })
}
