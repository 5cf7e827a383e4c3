//! The protocol-field corpora judge a codec by its protocol's own manual: a codec written here
//! from each protocol's rules passes every case, and a lenient one — Python's `int(text, 16)`,
//! `bytes.fromhex`, JavaScript's `parseInt` — fails exactly on the rules it breaks, each failure
//! naming the rule and its page. A codec served by a process through the binary is judged the
//! same way in tests/protocols.rs.

#[cfg(test)]
use std::collections::BTreeSet;
use std::sync::Arc;

use super::root;
use crate::model::protocol::{Field, Protocol};
use crate::{
    codec_backend, Answer, Backend, Codec, CodecAbilities, ErrorClass, Operation,
    OperationAbilities, Paths, Project, ProtocolClaim, Question, Status, Unsupported,
};
use rstest::rstest;

/// How a codec reads a field's characters.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reader {
    /// Every character a capital hex digit, exactly the field's count: the protocols' rule.
    Strict,
    /// Python's `int(text, 16)`: blanks around, a sign, a `0x` prefix, lowercase, `_` between
    /// digits; any length.
    PythonInt,
    /// Python's `bytes.fromhex`: pairs of either case, blanks between pairs.
    FromHex,
    /// JavaScript's `parseInt(text, 16)`: leading blanks, a sign, `0x`, lowercase, and the
    /// digits before the first character it cannot read.
    ParseInt,
}

fn digit(c: u8, lowercase: bool) -> Option<u64> {
    match c {
        b'0'..=b'9' => Some(u64::from(c - b'0')),
        b'A'..=b'F' => Some(u64::from(c - b'A' + 10)),
        b'a'..=b'f' if lowercase => Some(u64::from(c - b'a' + 10)),
        _ => None,
    }
}

fn digits_of(text: &[u8], lowercase: bool) -> Option<u64> {
    if text.is_empty() || text.len() > 16 {
        return None;
    }
    text.iter()
        .try_fold(0u64, |v, c| Some(v << 4 | digit(*c, lowercase)?))
}

impl Reader {
    fn read(self, text: &[u8], digits: usize) -> Result<u64, ErrorClass> {
        let bad = Err(ErrorClass::InvalidDigit);
        match self {
            Reader::Strict => {
                if text.len() != digits {
                    return Err(ErrorClass::InvalidCount);
                }
                digits_of(text, false).ok_or(ErrorClass::InvalidDigit)
            }
            Reader::PythonInt => {
                let t = std::str::from_utf8(text).map_err(|_| ErrorClass::InvalidDigit)?;
                let t = t.trim().trim_start_matches('+');
                let t = t
                    .strip_prefix("0x")
                    .or_else(|| t.strip_prefix("0X"))
                    .unwrap_or(t);
                let t: String = t.chars().filter(|c| *c != '_').collect();
                digits_of(t.as_bytes(), true).map_or(bad, Ok)
            }
            Reader::FromHex => {
                let t: Vec<u8> = text.iter().copied().filter(|c| *c != b' ').collect();
                if t.len() % 2 == 1 {
                    return bad;
                }
                digits_of(&t, true).map_or(bad, Ok)
            }
            Reader::ParseInt => {
                let t = std::str::from_utf8(text).unwrap_or("");
                let t = t.trim_start().trim_start_matches('+');
                let t = t
                    .strip_prefix("0x")
                    .or_else(|| t.strip_prefix("0X"))
                    .unwrap_or(t);
                let run: Vec<u8> = t
                    .bytes()
                    .take_while(|c| digit(*c, true).is_some())
                    .collect();
                digits_of(&run, true).map_or(bad, Ok)
            }
        }
    }
}

/// A codec of one protocol's fields, from the protocol profile's data: what a library would
/// write from the rules, with the reader given.
struct FieldCodec {
    protocol: Arc<Protocol>,
    reader: Reader,
    slip: Option<Slip>,
}

/// One mistake of a codec otherwise written from the rules.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slip {
    /// Every field read and written the most significant digit first (MEWTOCOL's words are not).
    HighFirst,
    /// Letters written in lowercase (`format(v, "04x")`).
    Lowercase,
    /// A check character computed and never compared.
    NeverCompares,
}

fn swap_bytes(v: u64, digits: u32) -> u64 {
    (0..digits / 2).fold(0, |acc, i| acc << 8 | (v >> (8 * i)) & 0xFF)
}

impl FieldCodec {
    fn field(&self, q: &Question<'_>) -> &Field {
        &self.protocol.fields[q.field]
    }
}

impl Codec for FieldCodec {
    fn name(&self) -> &str {
        "field-codec"
    }
    fn abilities(&self) -> CodecAbilities {
        let any = OperationAbilities {
            width: 32,
            ..OperationAbilities::default()
        };
        CodecAbilities {
            hex_to_value: Some(any.clone()),
            value_to_hex: Some(any.clone()),
            check: Some(any.clone()),
            verify: Some(any),
            protocol: Some(ProtocolClaim {
                id: self.protocol.id.clone(),
                fields: None,
                cross_vendor: false,
            }),
        }
    }
    fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
        let field = self.field(q);
        let hex = |v: u64, n: u32| match self.slip {
            Some(Slip::Lowercase) => format!("{v:0width$x}", width = n as usize).into_bytes(),
            _ => format!("{v:0width$X}", width = n as usize).into_bytes(),
        };
        Ok(match q.operation {
            Operation::HexToValue => match self.reader.read(q.text, field.digits as usize) {
                Ok(v) if field.low_byte_first && self.slip != Some(Slip::HighFirst) => {
                    Answer::Value(swap_bytes(v, field.digits))
                }
                Ok(v) => Answer::Value(v),
                Err(class) => Answer::Error(class),
            },
            Operation::ValueToHex => {
                let v = if field.low_byte_first && self.slip != Some(Slip::HighFirst) {
                    swap_bytes(q.value, field.digits)
                } else {
                    q.value
                };
                Answer::Text(hex(v, field.digits))
            }
            Operation::Check => match field.check.and_then(|c| c.compute(q.text)) {
                Some(byte) => Answer::Text(hex(u64::from(byte), 2)),
                None => Answer::Error(ErrorClass::InvalidDigit),
            },
            Operation::Verify => {
                let (span, given) = q.text.split_at(q.text.len().saturating_sub(2));
                if field.skip.as_deref() == Some(given) || self.slip == Some(Slip::NeverCompares) {
                    return Ok(Answer::Accepted);
                }
                let computed = field.check.and_then(|c| c.compute(span));
                match (computed, self.reader.read(given, 2)) {
                    (Some(c), Ok(g)) if u64::from(c) == g => Answer::Accepted,
                    _ => Answer::Error(ErrorClass::BadCheck),
                }
            }
        })
    }
}

fn project() -> Project {
    Project::load(&Paths::under(root())).unwrap_or_else(|e| panic!("the corpus loads:\n{e}"))
}

/// The rules (`<protocol>/<id>`) of the failing trials of a codec, with the trials counted.
fn failing_rules(project: &Project, backend: Arc<dyn Backend>) -> (BTreeSet<String>, usize) {
    let trials = project.plan(&[backend]);
    assert!(!trials.is_empty(), "the protocol's corpus planned no trial");
    let verdicts = crate::verdicts(&trials);
    let mut rules = BTreeSet::new();
    let mut ran = 0;
    for (t, v) in trials.iter().zip(&verdicts) {
        assert_ne!(v.status(), Status::Skipped, "{}: {v:?}", t.name());
        ran += 1;
        if v.is_failure() {
            let case = t.cross_vendor_case().expect("a codec trial");
            let from = case.protocol.as_ref().expect("a protocol case");
            rules.insert(from.rule.key.clone());
        }
    }
    (rules, ran)
}

const PROTOCOLS: [&str; 6] = [
    "mc-ascii",
    "modbus-ascii",
    "fx-computer-link",
    "mewtocol-com",
    "omron-host-link",
    "keyence-kv-l2",
];

#[test]
fn a_codec_written_from_each_protocols_rules_passes_its_corpus() {
    let project = project();
    for id in PROTOCOLS {
        let protocol = project.profiles.protocols.get(id).expect(id).clone();
        let codec = FieldCodec {
            protocol,
            reader: Reader::Strict,
            slip: None,
        };
        let (failing, ran) = failing_rules(&project, codec_backend(codec));
        assert!(failing.is_empty(), "{id}: {failing:?}");
        assert!(ran >= 4, "{id}: only {ran} trials");
    }
}

/// Each lenient reader breaks the rule that a field holds only its hex digits, and the rule
/// that it is exactly its length where the reader takes any length: those rules fail, and no
/// other (lowercase on receipt is unspecified everywhere, recorded, never failed).
#[rstest]
#[case::python_int(Reader::PythonInt, &["HEX", "LEN"])]
#[case::from_hex(Reader::FromHex, &["HEX", "LEN"])]
#[case::parse_int(Reader::ParseInt, &["HEX", "LEN"])]
fn a_lenient_reader_fails_exactly_on_the_rules_it_breaks(
    #[case] reader: Reader,
    #[case] broken: &[&str],
) {
    let project = project();
    for id in PROTOCOLS {
        let protocol = project.profiles.protocols.get(id).expect(id).clone();
        // The rule a field's characters break, and the rule of its length, in this protocol.
        let hex = match id {
            "mc-ascii" => "M4",
            "modbus-ascii" => "B3",
            "fx-computer-link" => "F5",
            "mewtocol-com" => "HEX",
            "omron-host-link" => "O3",
            _ => "K3",
        };
        let expected: BTreeSet<String> = broken
            .iter()
            .filter_map(|r| match *r {
                "HEX" => Some(format!("{id}/{hex}")),
                "LEN" => Some(format!("{id}/LEN")),
                _ => None,
            })
            .collect();
        let codec = FieldCodec {
            protocol,
            reader,
            slip: None,
        };
        let (failing, _) = failing_rules(&project, codec_backend(codec));
        assert_eq!(failing, expected, "{id} read as {reader:?}");
    }
}

/// A lenient reader's difference names the protocol's rule and its page.
#[test]
fn a_difference_names_the_rule_and_its_page() {
    let project = project();
    let protocol = project
        .profiles
        .protocols
        .get("mc-ascii")
        .expect("mc")
        .clone();
    let codec = codec_backend(FieldCodec {
        protocol,
        reader: Reader::PythonInt,
        slip: None,
    });
    let trials = project.plan(&[codec]);
    let verdicts = crate::verdicts(&trials);
    let (t, _) = trials
        .iter()
        .zip(&verdicts)
        .find(|(t, v)| t.case_id() == "mc-word-decode-plus" && v.is_failure())
        .expect("int(text, 16) reads a sign");
    let text = crate::report::text::describe_setting(t);
    assert!(text.contains("field:       word of mc-ascii"), "{text}");
    assert!(
        text.contains("rule:        mc-ascii/M4 (qnu-ethernet p.62: "),
        "{text}"
    );
}

/// A codec that answers with another class of error than the case writes still conforms: a
/// protocol names one answer to data it refuses.
#[test]
fn any_refusal_is_the_protocols_refusal() {
    struct Refuses(Arc<Protocol>);
    impl Codec for Refuses {
        fn name(&self) -> &str {
            "refuses"
        }
        fn abilities(&self) -> CodecAbilities {
            FieldCodec {
                protocol: self.0.clone(),
                reader: Reader::Strict,
                slip: None,
            }
            .abilities()
        }
        fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
            let strict = FieldCodec {
                protocol: self.0.clone(),
                reader: Reader::Strict,
                slip: None,
            };
            Ok(match strict.convert(q)? {
                Answer::Error(_) => Answer::Error(ErrorClass::Error),
                other => other,
            })
        }
    }
    let project = project();
    let protocol = project.profiles.protocols.get("modbus-ascii").expect("mb");
    let (failing, _) = failing_rules(&project, codec_backend(Refuses(protocol.clone())));
    assert!(failing.is_empty(), "{failing:?}");
}

/// A codec that reads every word the most significant digit first breaks MEWTOCOL's word rules
/// and no other protocol's; one that writes lowercase breaks each protocol's rule of the
/// characters written, on encode only; one that never compares a check character breaks each
/// protocol's verify rule, on verify only.
#[rstest]
#[case::high_first(Slip::HighFirst)]
#[case::lowercase(Slip::Lowercase)]
#[case::never_compares(Slip::NeverCompares)]
fn a_slip_fails_on_its_rules_only(#[case] slip: Slip) {
    let project = project();
    for id in PROTOCOLS {
        let protocol = project.profiles.protocols.get(id).expect(id).clone();
        let backend = codec_backend(FieldCodec {
            protocol,
            reader: Reader::Strict,
            slip: Some(slip),
        });
        let trials = project.plan(&[backend]);
        let verdicts = crate::verdicts(&trials);
        let failing: Vec<_> = (trials.iter().zip(&verdicts))
            .filter(|(_, v)| v.is_failure())
            .map(|(t, _)| t.cross_vendor_case().expect("codec trial"))
            .collect();
        let rules: BTreeSet<&str> = (failing.iter())
            .map(|c| {
                c.protocol
                    .as_ref()
                    .expect("protocol case")
                    .rule
                    .key
                    .as_str()
            })
            .collect();
        match slip {
            Slip::HighFirst if id == "mewtocol-com" => assert_eq!(
                rules,
                BTreeSet::from(["mewtocol-com/P1", "mewtocol-com/P5"]),
                "{id}"
            ),
            Slip::HighFirst => assert!(rules.is_empty(), "{id}: {rules:?}"),
            Slip::Lowercase | Slip::NeverCompares => {
                let operation = if slip == Slip::Lowercase {
                    [Operation::ValueToHex, Operation::Check]
                } else {
                    [Operation::Verify, Operation::Verify]
                };
                assert!(!failing.is_empty(), "{id}: {slip:?} got through");
                for c in &failing {
                    assert!(operation.contains(&c.operation), "{id}: {}", c.id);
                }
            }
        }
    }
}

/// The rules of the protocols whose `manual` quote or page docs/semantics.md does not carry, as
/// `rule: what is missing`.
fn uncarried(semantics: &str, project: &Project) -> Vec<String> {
    let mut out = Vec::new();
    for protocol in project.profiles.protocols.iter() {
        let section = format!("<a id=\"protocol-{}\"></a>", protocol.id);
        if !semantics.contains(&section) {
            out.push(format!("{}: no section {section}", protocol.id));
        }
        for rule in protocol.rules.values() {
            let c = &rule.citation;
            if let (crate::Basis::Manual, Some(quote)) = (rule.basis, &c.text) {
                let cite = format!("`{} p.{}`", c.manual, c.page);
                if !semantics.contains(&format!("{cite}: \"{quote}\"")) {
                    out.push(format!("{}: {cite} and its quote", rule.key));
                }
            }
        }
    }
    out
}

/// Every `manual` rule of a protocol — and so every `manual` protocol-field case, which takes
/// its rule's cite and quote — is carried in docs/semantics.md with its page and quote.
#[test]
fn every_manual_rule_and_its_quote_is_carried_in_the_semantics() {
    let project = project();
    let semantics =
        std::fs::read_to_string(root().join("docs/semantics.md")).expect("semantics.md");
    assert_eq!(uncarried(&semantics, &project), Vec::<String>::new());
    for case in &project.corpus.protocol_fields {
        let rule = &case.protocol.as_ref().expect("protocol case").rule;
        if case.basis == crate::Basis::Manual {
            assert_eq!(case.citation, rule.citation, "{}", case.id);
        }
    }
    // The check fails on a quote taken out.
    let quote = "Use capitalized code for alphabetical letter.\"";
    let planted = semantics.replacen(quote, "\"", 1);
    assert!(uncarried(&planted, &project)
        .iter()
        .any(|m| m.starts_with("mc-ascii/M1")));
}
