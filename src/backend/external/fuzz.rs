//! Property tests of what reads untrusted input: the vector loader and the protocol decoder. On
//! any input — random text, damaged corpus files, damaged protocol lines, random JSON — they
//! return a value or an error, never panic, and finish in bounded time.
//!
//! `cargo test --lib backend::external::fuzz` runs 256 cases per property (a few seconds); run
//! longer with `PROPTEST_CASES=100000 cargo test --release --lib backend::external::fuzz`. A
//! failing input is shrunk and saved under `proptest-regressions/backend/external/fuzz.txt`, and
//! replayed first on every later run.

#[cfg(test)]
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use crate::backend::external::protocol::{BackendMessage, HarnessMessage};
use crate::backend::external::serve::serve;
use crate::backend::reference_backends;
use crate::load::{load_profiles, yaml_files, CorpusBuilder};
use crate::model::profile::Profiles;
use proptest::prelude::*;

/// The longest any one input may take: far above the milliseconds each takes, far below a hang.
const BOUND: Duration = Duration::from_secs(5);

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn profiles() -> &'static Profiles {
    static PROFILES: OnceLock<Profiles> = OnceLock::new();
    PROFILES.get_or_init(|| {
        load_profiles(&root().join("vendors")).unwrap_or_else(|e| panic!("profiles: {e}"))
    })
}

/// The corpus files and the profiles, as text: the seeds that damage starts from.
fn seeds() -> &'static [(PathBuf, String)] {
    static SEEDS: OnceLock<Vec<(PathBuf, String)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let mut files = yaml_files(&root().join("vectors")).expect("the corpus");
        files.extend(yaml_files(&root().join("vendors")).expect("the profiles"));
        files
            .into_iter()
            .map(|f| {
                let text = std::fs::read_to_string(&f).expect("readable");
                (f, text)
            })
            .collect()
    })
}

fn load(text: &str) {
    let started = Instant::now();
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("fuzz.yaml"), text, profiles());
    let _ = builder.finish();
    assert!(started.elapsed() < BOUND, "took {:?}", started.elapsed());
}

/// Bits of YAML and of the formats' vocabulary, so that random text reaches past the parser.
#[rustfmt::skip]
const TOKENS: &[&str] = &[
    "\n", "  ", "- ", ": ", "[", "]", "{", "}", ", ", "&a ", "*a", "!!str ", "? ", "|", ">",
    "'", "\"", "#", "---\n", "...\n", "~", "\t", "\\", "\u{0}", "\u{1b}", "\u{feff}", "\u{fffe}",
    "cases:", "id: x", "basis: manual", "cite: c", "variants: []", "variants: [rcpu]",
    "operands: {s: D100, d: D200}", "before:", "expect:", "after:", "error:", "none", "3401H",
    "M8004", "K0", "K-1", "H0ABC", "0x10", "99999999999999999999H", "{ascii: \"5A8D\"}",
    "{ascii: 5}", "{ascii_words: \"12\"}", "D100", "D18431", "D99999", "SM705: on",
    "instructions: [HABIN]", "profiles: [mitsubishi-iqr]", "operation: hex-to-value",
    "digits: 4", "text: \"5A8D\"", "value: 0ABCH", "except:", "why: w",
    "source: {manual: iqr-instructions-ja, page: 478}",
];

#[derive(Debug, Clone)]
enum Edit {
    Delete { at: usize, len: usize },
    Insert { at: usize, token: usize },
    Byte { at: usize, byte: u8 },
    DuplicateLine { at: usize },
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 0usize..64).prop_map(|(at, len)| Edit::Delete { at, len }),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(at, token)| Edit::Insert { at, token }),
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Edit::Byte { at, byte }),
        any::<usize>().prop_map(|at| Edit::DuplicateLine { at }),
    ]
}

/// Applies edits to text, at char boundaries (a byte edit that breaks UTF-8 is read lossily,
/// as the loader would report invalid UTF-8 before any of this).
fn damage(text: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for e in edits {
        let at = |n: usize| {
            if chars.is_empty() {
                0
            } else {
                n % (chars.len() + 1)
            }
        };
        match e {
            Edit::Delete { at: a, len } => {
                let start = at(*a);
                let end = (start + len).min(chars.len());
                chars.drain(start..end);
            }
            Edit::Insert { at: a, token } => {
                let start = at(*a);
                chars.splice(start..start, TOKENS[*token].chars());
            }
            Edit::Byte { at: a, byte } => {
                let start = at(*a);
                chars.insert(start, char::from(*byte));
            }
            Edit::DuplicateLine { at: a } => {
                let text: String = chars.iter().collect();
                let lines: Vec<&str> = text.split_inclusive('\n').collect();
                if !lines.is_empty() {
                    let i = a % lines.len();
                    let mut out: Vec<&str> = lines.clone();
                    out.insert(i, lines[i]);
                    chars = out.concat().chars().collect();
                }
            }
        }
    }
    chars.into_iter().collect()
}

/// Protocol lines that decode, to damage.
const MESSAGES: &[&str] = &[
    r#"{"type":"hello","protocol":2,"backend":{"name":"x","version":"1"},"capabilities":{"profile":"mitsubishi-iqr","instructions":["HABIN"],"variants":["rcpu"],"flags":{"SM705":[false]}}}"#,
    r#"{"type":"hello","protocol":2,"backend":{"name":"x","version":"1"},"capabilities":{"codec":{"hex-to-value":{"digits":[4],"width":16}}}}"#,
    r#"{"type":"result","id":3,"writes":{"D200":23181},"error":{"code":13313}}"#,
    r#"{"type":"result","id":3,"memory":[{"start":"D200","words":[1,2]}],"error":null}"#,
    r#"{"type":"result","id":4,"error":{"flag":"M8004"}}"#,
    r#"{"type":"result","id":7,"value":23181}"#,
    r#"{"type":"result","id":7,"text":[48,65]}"#,
    r#"{"type":"result","id":7,"error":"invalid-digit"}"#,
    r#"{"type":"unsupported","id":5,"reason":"no"}"#,
    r#"{"type":"hello","protocol":2,"harness":"h"}"#,
    r#"{"type":"run","cases":[{"id":7,"case":"c","instruction":"HABIN","profile":"mitsubishi-iqr","variant":"rcpu","flags":{"SM705":false},"operands":{"s":"D100","d":"D200"},"fill":"A","memory":[{"start":"D100","words":[16693,17464]}]}]}"#,
    r#"{"type":"run","cases":[{"id":7,"case":"c","operation":"hex-to-value","text":[53,65],"digits":2}]}"#,
    r#"{"type":"shutdown"}"#,
];

/// Random JSON with the protocol's keys, nested a few levels.
fn json() -> impl Strategy<Value = serde_json::Value> {
    let keys = prop::sample::select(vec![
        "type",
        "id",
        "protocol",
        "backend",
        "capabilities",
        "writes",
        "memory",
        "error",
        "value",
        "text",
        "reason",
        "cases",
        "harness",
        "start",
        "words",
        "code",
        "flag",
        "codec",
        "instructions",
        "profile",
        "variant",
        "operands",
        "fill",
        "D200",
        "D0200",
    ]);
    let leaf = prop_oneof![
        Just(serde_json::Value::Null),
        any::<bool>().prop_map(serde_json::Value::from),
        any::<i64>().prop_map(serde_json::Value::from),
        any::<u64>().prop_map(serde_json::Value::from),
        prop::sample::select(vec![
            "hello",
            "result",
            "unsupported",
            "run",
            "shutdown",
            "D200",
            "A",
            "invalid-digit",
            "mitsubishi-iqr",
            "HABIN",
            "",
        ])
        .prop_map(serde_json::Value::from),
    ];
    leaf.prop_recursive(4, 64, 8, move |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..6).prop_map(serde_json::Value::Array),
            prop::collection::vec((keys.clone(), inner), 0..8).prop_map(|pairs| {
                serde_json::Value::Object(
                    pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
                )
            }),
        ]
    })
}

fn decode(line: &[u8]) {
    let started = Instant::now();
    let _ = BackendMessage::from_line(line);
    let _ = HarnessMessage::from_line(line);
    assert!(started.elapsed() < BOUND, "took {:?}", started.elapsed());
}

/// Lines into `plc-conformance serve`'s loop: it answers or stops with an error, never panics.
fn serve_lines(lines: &[Vec<u8>]) {
    static BACKENDS: OnceLock<Vec<std::sync::Arc<dyn crate::Backend>>> = OnceLock::new();
    let backends = BACKENDS.get_or_init(|| reference_backends(profiles()));
    let Some(backend) = backends.iter().find(|b| b.profile() == "mitsubishi-iqr") else {
        panic!("no iQ-R model");
    };
    let Some(profile) = profiles().get("mitsubishi-iqr") else {
        panic!("no iQ-R profile");
    };
    let mut input = Vec::new();
    for l in lines {
        input.extend_from_slice(l);
        input.push(b'\n');
    }
    let mut output = Vec::new();
    let started = Instant::now();
    let _ = serve(backend.as_ref(), profile, &input[..], &mut output);
    assert!(started.elapsed() < BOUND, "took {:?}", started.elapsed());
}

proptest! {
    #[test]
    fn the_loader_takes_any_text(text in prop::collection::vec(any::<char>(), 0..2000)) {
        load(&text.into_iter().collect::<String>());
    }

    #[test]
    fn the_loader_takes_any_damaged_corpus_file(
        seed in any::<prop::sample::Index>(),
        edits in prop::collection::vec(edit(), 1..12),
    ) {
        let (_, text) = seed.get(seeds());
        load(&damage(text, &edits));
    }

    #[test]
    fn the_loader_takes_any_sequence_of_tokens(
        tokens in prop::collection::vec(0..TOKENS.len(), 0..200),
    ) {
        let text: String = tokens.iter().map(|t| TOKENS[*t]).collect();
        load(&text);
    }

    #[test]
    fn the_decoder_takes_any_bytes(line in prop::collection::vec(any::<u8>(), 0..512)) {
        decode(&line);
    }

    #[test]
    fn the_decoder_takes_any_damaged_message(
        seed in 0..MESSAGES.len(),
        edits in prop::collection::vec(edit(), 1..8),
    ) {
        decode(damage(MESSAGES[seed], &edits).as_bytes());
    }

    #[test]
    fn the_decoder_takes_any_json(value in json()) {
        decode(value.to_string().as_bytes());
    }

    #[test]
    fn serve_takes_any_lines(
        lines in prop::collection::vec(
            prop_oneof![
                (0..MESSAGES.len()).prop_map(|i| MESSAGES[i].as_bytes().to_vec()),
                (0..MESSAGES.len(), prop::collection::vec(edit(), 1..4))
                    .prop_map(|(i, e)| damage(MESSAGES[i], &e).into_bytes()),
                json().prop_map(|v| v.to_string().into_bytes()),
            ],
            0..6,
        ),
    ) {
        serve_lines(&lines);
    }
}
