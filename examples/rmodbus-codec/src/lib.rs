//! rmodbus's Modbus ASCII hex coding as a plc-conformance codec.
//!
//! A Modbus ASCII frame carries every byte as two hex characters, high nibble first; a 16-bit
//! register is two bytes, high byte first, so its four characters read like a hex number
//! (MODBUS over Serial Line V1.02). rmodbus's `parse_ascii_frame` and `generate_ascii_frame`
//! are judged first by that protocol's corpus (`protocol: modbus-ascii`, its byte and register
//! fields), and also by the cross-vendor view: the same conversion as HABIN and BINHA (SM705
//! off), FX5 HEXA/ASCI and IDEC ATOH/HTOA, with 2 digits (a byte) or 4 (a register).

use plc_conformance::{
    Answer, CodecAbilities, ErrorClass, Operation, OperationAbilities, ProtocolClaim,
};
use plc_conformance::{Codec, Question, Unsupported};

/// rmodbus 0.13 as a codec: the library calls and nothing else.
pub struct Rmodbus;

impl Codec for Rmodbus {
    fn name(&self) -> &str {
        "rmodbus"
    }

    fn abilities(&self) -> CodecAbilities {
        let field = OperationAbilities {
            digits: Some(vec![2, 4]),
            width: 16,
            ..OperationAbilities::default()
        };
        CodecAbilities {
            hex_to_value: Some(field.clone()),
            value_to_hex: Some(field),
            protocol: Some(ProtocolClaim {
                id: "modbus-ascii".into(),
                fields: Some(vec!["byte".into(), "register".into()]),
                cross_vendor: true,
            }),
            ..CodecAbilities::default()
        }
    }

    /// The version Cargo.toml pins (`=0.13.0`).
    fn version(&self) -> Option<String> {
        Some("rmodbus 0.13.0".into())
    }

    fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
        match q.operation {
            Operation::HexToValue => {
                // A protocol field is the whole text, as a frame would carry it (rmodbus decodes
                // what it is given, of any length); the cross-vendor view gives the characters
                // as they arrive, the field's digits first. rmodbus indexes the first byte
                // without a length check, so an empty field is not handed to it.
                let field = if q.field.is_empty() {
                    &q.text[..q.text.len().min(q.digits as usize)]
                } else {
                    q.text
                };
                if field.is_empty() {
                    return Ok(Answer::Error(ErrorClass::InvalidDigit));
                }
                let mut bytes = [0u8; 256];
                Ok(
                    match rmodbus::parse_ascii_frame(field, field.len(), &mut bytes, 0) {
                        Ok(n) => Answer::Value(
                            bytes[..usize::from(n)]
                                .iter()
                                .fold(0, |v, b| v << 8 | u64::from(*b)),
                        ),
                        Err(_) => Answer::Error(ErrorClass::InvalidDigit),
                    },
                )
            }
            Operation::ValueToHex => {
                let bytes = match q.digits {
                    2 => vec![q.value as u8],
                    _ => (q.value as u16).to_be_bytes().to_vec(),
                };
                let mut frame: Vec<u8> = Vec::new();
                rmodbus::generate_ascii_frame(&bytes, &mut frame)
                    .map_err(|e| Unsupported(format!("rmodbus: {e:?}")))?;
                // The frame is ':', the characters, CR LF.
                let text = frame.get(1..frame.len().saturating_sub(2)).unwrap_or(&[]);
                Ok(Answer::Text(text.to_vec()))
            }
            other => Err(Unsupported(format!("implements no {other}"))),
        }
    }
}
