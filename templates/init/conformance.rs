//! {{name}} checked against plc-conformance's corpus: one libtest trial per cross-vendor case,
//! with the harness's diffs and known differences, in this crate's own `cargo test`.
//!
//! Written by `plc-conformance init codec --rust`. In Cargo.toml:
//!
//!     [dev-dependencies]
//!     # pinned: a new version is a new corpus; the harness without the command line
//!     plc-conformance = { version = "={{version}}", default-features = false }
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
            //    The stand-in reads as the manuals do (exactly the digits asked, each 0-9 or
            //    A-F), which is why the scaffold runs green as written.
            Operation::HexToValue => {
                {{field_rs}}
                let digits: Option<Vec<u32>> = (field.iter())
                    .map(|&b| match b {
                        b'0'..=b'9' | b'A'..=b'F' => (b as char).to_digit(16),
                        _ => None,
                    })
                    .collect();
                match digits {
                    Some(d) => Answer::Value(d.iter().fold(0, |v, d| v << 4 | u64::from(*d))),
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
