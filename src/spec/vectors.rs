//! The vector files as written on disk: the corpus authors' format.
//!
//! These types mirror the YAML one to one and check only its shape (known keys, scalar vs list vs
//! map); what the values mean is checked when they are read into [`crate::model`] against the
//! vendor profile, so that a message can say which profile rule a value breaks. The JSON Schema
//! shipped for editors is generated from these types, so the schema and the loader cannot drift.

use std::collections::BTreeMap;
use std::fmt;

use schemars::JsonSchema;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

/// One vector file: the cases for one instruction (and its forms) of one or more profiles.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance vector file")]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct VectorFileSpec {
    /// The instructions every case runs as, e.g. `[HABIN, HABINP]`: the pulse form of an
    /// instruction converts the same way, so it shares the vectors.
    pub instructions: Vec<String>,
    /// The vendor profiles (files in `vendors/`) the cases apply to, by id.
    pub profiles: Vec<String>,
    /// Where the cases come from unless a case says otherwise.
    pub source: SourceSpec,
    /// Free text for readers of the file.
    pub description: Option<String>,
    pub cases: Vec<CaseSpec>,
}

/// A manual page (or page range) from the profile's list of manuals.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct SourceSpec {
    /// A manual id from the profile's `manuals`.
    pub manual: String,
    /// The page, e.g. `478` or `"654-658"`.
    pub page: PageSpec,
}

#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum PageSpec {
    Number(u32),
    Text(String),
}

impl fmt::Display for PageSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PageSpec::Number(n) => write!(f, "{n}"),
            PageSpec::Text(t) => f.write_str(t),
        }
    }
}

/// How much a case's expectation can be trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Basis {
    /// A manual states it; `cite` says where.
    Manual,
    /// Our reading of a manual or of vendor convention; `cite` says what it rests on.
    Inferred,
    /// No source fixes the outcome: the case runs and records what each backend does, and never
    /// fails a run.
    Unspecified,
    /// What a real CPU did; `cite` gives the provenance (model, firmware, date, who).
    Observed,
}

impl fmt::Display for Basis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Basis::Manual => "manual",
            Basis::Inferred => "inferred",
            Basis::Unspecified => "unspecified",
            Basis::Observed => "observed",
        })
    }
}

/// One test vector.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CaseSpec {
    /// Stable id, unique in the whole corpus: lowercase letters, digits and `-`.
    pub id: String,
    pub basis: Basis,
    /// Where the expectation comes from: page, table row, quote, or an erratum it relies on.
    /// Required unless the basis is `unspecified`.
    pub cite: Option<String>,
    /// Overrides the file's `source`.
    pub source: Option<SourceSpec>,
    /// Restricts the case to these profile variants; all variants when absent.
    pub variants: Option<Vec<String>>,
    /// Mode flags, e.g. `{SM705: on}`. Flags not given hold the profile's default.
    #[serde(default)]
    #[schemars(extend("propertyNames" = {"pattern": crate::device::PATTERN}))]
    pub flags: BTreeMap<String, FlagSpec>,
    /// Operands by the names the manual uses (`s`, `d`, `n`; `S1`, `S2`, `D1`): a device such as
    /// `D100` or a constant such as `K4` / `H0ABC`.
    #[serde(default)]
    pub operands: BTreeMap<String, ScalarSpec>,
    /// For an operand written with indirect specification (`s: '@D10'`): the device whose
    /// address each pointer holds, as ADRSET stores it (`{D10: D100}`: D10 and D11 hold D100's
    /// address, so `@D10` is D100). The manuals do not give that encoding, so `before` and
    /// `expect.after` cannot name a pointer's two words.
    #[serde(default)]
    #[schemars(extend("propertyNames" = {"pattern": crate::device::PATTERN}))]
    pub addresses: BTreeMap<String, String>,
    /// Memory before execution, by device (`D100`). Every word not listed holds a fill pattern.
    #[serde(default)]
    #[schemars(extend("propertyNames" = {"pattern": crate::device::PATTERN}))]
    pub before: BTreeMap<String, ValueSpec>,
    /// The expected outcome; optional only for `basis: unspecified`.
    pub expect: Option<ExpectSpec>,
    /// Free text for readers.
    pub note: Option<String>,
    /// Where an `observed` expectation was observed (written by `plc-conformance record`).
    pub provenance: Option<ProvenanceSpec>,
}

/// Where an `observed` expectation comes from: the backend that did it (a CPU reached through
/// an adapter, an emulator), when, and on which model or firmware.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// Some fields are there for the file's readers and its schema (descriptions, evidence,
// provenance); the run reads none of them, and the loader still refuses a file without them.
#[allow(dead_code)]
pub(crate) struct ProvenanceSpec {
    /// The backend's name, as `plc-conformance list` shows it.
    pub backend: String,
    /// What the backend says of itself, with its version.
    pub version: Option<String>,
    /// The date of the recording, `YYYY-MM-DD`.
    pub date: String,
    /// The profile variants it ran on.
    #[serde(default)]
    pub variants: Vec<String>,
    /// The model or firmware of those variants, from the profile.
    pub model: Option<String>,
}

/// The expected outcome: the words that change and the error signalled.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ExpectSpec {
    /// The words that change, by device, with their new values. Any other change is a
    /// difference.
    #[serde(default)]
    #[schemars(extend("propertyNames" = {"pattern": crate::device::PATTERN}))]
    pub after: BTreeMap<String, ValueSpec>,
    /// `none`, the vendor's error code (`3401H`), or the error flag the profile signals with
    /// (`M8004`). An empty `error:` is refused: `none` is the one way to say "no error".
    #[serde(default, deserialize_with = "given_error")]
    #[schemars(with = "ScalarSpec")]
    pub error: Option<ScalarSpec>,
}

/// `error:` when the key is there: a value, never null or empty.
fn given_error<'de, D: Deserializer<'de>>(d: D) -> Result<Option<ScalarSpec>, D::Error> {
    match Option::<ScalarSpec>::deserialize(d)? {
        Some(v) => Ok(Some(v)),
        None => Err(de::Error::custom(
            "an empty `error:` says nothing: write `none` for no error, or the error the profile \
             signals (a code like `3401H`, or its error flag)",
        )),
    }
}

/// A flag setting: `on`/`off`, `true`/`false` or `1`/`0`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(untagged)]
pub(crate) enum FlagSpec {
    Bool(bool),
    Number(i64),
    Text(String),
}

/// A scalar: a number as the manuals write it, or a name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ScalarSpec {
    Number(i64),
    Text(String),
}

impl fmt::Display for ScalarSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ScalarSpec::Number(n) => write!(f, "{n}"),
            ScalarSpec::Text(t) => f.write_str(t),
        }
    }
}

/// Memory contents starting at a device: one word, consecutive words, or ASCII text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ValueSpec {
    Word(ScalarSpec),
    Words(Vec<ScalarSpec>),
    /// Two characters per word, first character in the low byte (MELSEC string storage). An odd
    /// length leaves 00H in the last high byte.
    Ascii(String),
    /// One character per word, in the low byte (IDEC ATOH/HTOA, FX5 8-bit mode).
    AsciiWords(String),
}

const SCALAR_EXPECTED: &str = "a number such as `4135H`, `K100`, `H0ABC` or 16693, or a name";
const VALUE_EXPECTED: &str = "a word (`4135H`, `K100`, 16693), a list of words, `{ascii: \"5A8D\"}` or `{ascii_words: \"12\"}`";

struct ScalarVisitor;

impl<'de> Visitor<'de> for ScalarVisitor {
    type Value = ScalarSpec;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(SCALAR_EXPECTED)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScalarSpec, E> {
        Ok(ScalarSpec::Number(v))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScalarSpec, E> {
        i64::try_from(v)
            .map(ScalarSpec::Number)
            .map_err(|_| E::custom(format!("{v} is too large")))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<ScalarSpec, E> {
        Ok(ScalarSpec::Text(v.to_string()))
    }
}

impl<'de> Deserialize<'de> for ScalarSpec {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ScalarVisitor)
    }
}

struct ValueVisitor;

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = ValueSpec;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(VALUE_EXPECTED)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ValueSpec, E> {
        ScalarVisitor.visit_i64(v).map(ValueSpec::Word)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ValueSpec, E> {
        ScalarVisitor.visit_u64(v).map(ValueSpec::Word)
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<ValueSpec, E> {
        ScalarVisitor.visit_str(v).map(ValueSpec::Word)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ValueSpec, A::Error> {
        let mut words = Vec::new();
        while let Some(word) = seq.next_element::<ScalarSpec>()? {
            words.push(word);
        }
        if words.is_empty() {
            return Err(de::Error::custom("an empty list sets no word"));
        }
        Ok(ValueSpec::Words(words))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ValueSpec, A::Error> {
        let key: String = map
            .next_key()?
            .ok_or_else(|| de::Error::custom(format!("empty map; expected {VALUE_EXPECTED}")))?;
        let text = map.next_value::<Text>()?.0;
        let value = match key.as_str() {
            "ascii" => ValueSpec::Ascii(text),
            "ascii_words" => ValueSpec::AsciiWords(text),
            other => return Err(de::Error::unknown_field(other, &["ascii", "ascii_words"])),
        };
        if let Some(extra) = map.next_key::<String>()? {
            return Err(de::Error::custom(format!(
                "`{extra}` after `{key}`: a text value has exactly one key"
            )));
        }
        Ok(value)
    }
}

/// The text of `{ascii: ...}`: a YAML string only. `{ascii: 5}` is the number 5, not the
/// character `5`; reading it as text would hide the author's slip.
struct Text(String);

impl<'de> Deserialize<'de> for Text {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct TextVisitor;
        impl Visitor<'_> for TextVisitor {
            type Value = Text;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a YAML string, e.g. `{ascii: \"5A8D\"}` (quote text that reads as a number)",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Text, E> {
                Ok(Text(v.to_string()))
            }
        }
        deserializer.deserialize_any(TextVisitor)
    }
}

impl<'de> Deserialize<'de> for ValueSpec {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ValueVisitor)
    }
}

/// The schema side of [`ScalarSpec`] and [`ValueSpec`], whose deserializers are hand-written
/// for their error messages.
mod schema_shapes {
    use schemars::JsonSchema;

    /// A number as the manuals write it (`4135H`, `0ABCH`, `K100`, `K-1`, `H0ABC`, `0x4135`,
    /// 16693) or a device / name (`D100`, `@D10`, `none`, `M8004`).
    #[derive(JsonSchema)]
    #[serde(untagged)]
    #[allow(dead_code)]
    pub(super) enum Scalar {
        Number(i64),
        Text(
            #[schemars(regex(
                pattern = r"^\s*(K-?[0-9]+|0[xX][0-9A-Fa-f]+|[0-9A-Fa-f]+[Hh]|H[0-9A-Fa-f]+|-?[0-9]+|@?[A-Z]([A-Z0-9.\\]*[A-Z])?([0-9]+\.[0-7]|[0-9]+)|@?[A-Z]([A-Z0-9.\\]*[A-Z])?[0-9A-F]+|none)\s*$"
            ))]
            String,
        ),
    }

    /// Two ASCII characters per word, first character in the low byte. `\0` writes a NUL.
    #[derive(JsonSchema)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    pub(super) struct Ascii {
        ascii: String,
    }

    /// One ASCII character per word, in the low byte.
    #[derive(JsonSchema)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    pub(super) struct AsciiWords {
        ascii_words: String,
    }

    /// Memory contents from a device on: a word, consecutive words, or ASCII text.
    #[derive(JsonSchema)]
    #[serde(untagged)]
    #[allow(dead_code)]
    pub(super) enum Value {
        Word(super::ScalarSpec),
        Words(Vec<super::ScalarSpec>),
        Ascii(Ascii),
        AsciiWords(AsciiWords),
    }
}

impl JsonSchema for ScalarSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Scalar".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schema_shapes::Scalar::json_schema(generator)
    }
}

impl JsonSchema for ValueSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Value".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schema_shapes::Value::json_schema(generator)
    }
}
