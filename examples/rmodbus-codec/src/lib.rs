//! rmodbus's Modbus ASCII hex coding as a plc-conformance codec.
//!
//! A Modbus ASCII frame carries every byte as two hex characters, high nibble first; a 16-bit
//! register is two bytes, high byte first, so its four characters read like a hex number. That
//! is the conversion HABIN and BINHA (SM705 off), FX5 HEXA/ASCI and IDEC ATOH/HTOA make, so
//! rmodbus's `parse_ascii_frame` and `generate_ascii_frame` answer the cross-vendor questions
//! with 2 digits (a byte) or 4 (a register).

use plc_conformance::{Answer, CodecAbilities, ErrorClass, Operation, OperationAbilities};
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
        }
    }

    fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
        match q.operation {
            Operation::HexToValue => {
                // The field's characters as they arrive; rmodbus indexes the first byte without
                // a length check, so an empty field is not handed to it.
                let field = &q.text[..q.text.len().min(q.digits as usize)];
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
        }
    }
}
