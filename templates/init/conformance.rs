//! {{name}} checked against plc-conformance's corpus: one libtest trial per cross-vendor case,
//! with the harness's diffs and known differences, in this crate's own `cargo test`.
//!
//! Written by `plc-conformance init codec --rust`. In Cargo.toml:
//!
//!     [dev-dependencies]
//!     # or { git = "...", rev = "..." }; the harness without the command line
//!     plc-conformance = { path = "../plc-conformance", default-features = false }
//!
//!     [[test]]
//!     name = "conformance"
//!     harness = false
//!
//! Guide: docs/check-your-library.md in plc-conformance; a complete example is its
//! examples/rmodbus-codec.

use plc_conformance::{
    Answer, Codec, CodecAbilities, ErrorClass, Harness, Operation,
    OperationAbilities, Question, Unsupported,
};

/// {{name}}'s conversions as the corpus asks them.
struct {{type}};

impl Codec for {{type}} {
    fn name(&self) -> &str {
        "{{name}}"
    }

    fn abilities(&self) -> CodecAbilities {
        // 1. The digit counts it converts, and the width of its values (16 or 32 bits).
        let ability = OperationAbilities {
            digits: Some(vec![4]),
            width: 16,
            reading: None,
            shape: Default::default(),
        };
        CodecAbilities {
            hex_to_value: Some(ability.clone()),
            value_to_hex: Some(ability),
            // 1b. The protocol it speaks, whose own manual then judges it, each difference
            //     naming the rule and its page: mc-ascii, modbus-ascii, fx-computer-link,
            //     mewtocol-com, omron-host-link or keyence-kv-l2 (None: a codec of no
            //     protocol, which the instruction manuals judge).
            {{protocol_rs}}
            ..CodecAbilities::default()
        }
    }

    fn convert(&self, question: &Question<'_>) -> Result<Answer, Unsupported> {
        Ok(match question.operation {
            // 2. Replace these stand-ins with your library's calls; map its errors to the
            //    shared classes (InvalidDigit, InvalidCount, DeviceRange, Error).
            Operation::HexToValue => {
                let field = &question.text[..question.text.len().min(question.digits as usize)];
                match std::str::from_utf8(field).ok().and_then(|t| u64::from_str_radix(t, 16).ok()) {
                    Some(value) => Answer::Value(value),
                    None => Answer::Error(ErrorClass::InvalidDigit),
                }
            }
            Operation::ValueToHex => Answer::Text(
                format!("{:0width$X}", question.value, width = question.digits as usize)
                    .into_bytes(),
            ),
            // A protocol's check character (check, verify), when it implements one.
            other => return Err(Unsupported(format!("implements no {other}"))),
        })
    }
}

fn main() -> std::process::ExitCode {
    // 3. The corpus and profiles built into the plc-conformance crate (`Harness::new(DIR)` for
    //    a folder with vendors/ and vectors/ of your own).
    Harness::embedded()
        .codec({{type}}, Some("{{name}}.known.yaml".into()))
        .run()
}
