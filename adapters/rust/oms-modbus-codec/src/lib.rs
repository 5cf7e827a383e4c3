//! oms-modbus's Modbus ASCII hex coding as a plc-conformance codec.
//!
//! A Modbus ASCII frame carries every byte as two hex characters, high nibble first; a 16-bit
//! register is two bytes, high byte first (MODBUS over Serial Line V1.02). oms-modbus 0.2.0
//! writes frames with the public `codec::encode_ascii_frame` (src/codec.rs:98) and LRC
//! (`calculate_lrc`, codec.rs:69), but reads them only inside its transport: the private
//! `try_parse_ascii` (src/transport/ascii.rs:257) behind `AsciiClient`. So a register is read
//! here as a client reads one: `read_holding_registers` over an in-memory duplex stream whose
//! other end answers with a read response carrying the field. A line that oms-modbus cannot
//! read is skipped without a word (ascii.rs:291); the other end then closes, so the client's
//! "connection closed" is the answer, at once rather than after its timeout.
//!
//! Judged by the protocol's own corpus (`protocol: modbus-ascii`): register and lrc. The byte
//! field is not claimed (no public path reads one byte), nor is verify (a frame whose LRC
//! holds but whose PDU does not parse is an error too, so the LRC's own verdict is not seen).

use std::time::Duration;

use oms_modbus::{ModbusClient, ModbusError};
use plc_conformance::{
    Answer, CodecAbilities, ErrorClass, Operation, OperationAbilities, ProtocolClaim,
};
use plc_conformance::{Codec, Question, Unsupported};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// oms-modbus 0.2 as a codec: the library calls and nothing else.
pub struct OmsModbus {
    runtime: tokio::runtime::Runtime,
}

impl OmsModbus {
    pub fn new() -> Self {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("a tokio runtime");
        OmsModbus { runtime }
    }

    /// One register read by `AsciiClient` from the response `frame`.
    fn read_register(&self, frame: Vec<u8>) -> Result<Vec<u16>, ModbusError> {
        self.runtime.block_on(async move {
            let (client_end, mut peer) = tokio::io::duplex(4096);
            let client =
                oms_modbus::ascii::AsciiClient::with_timeout(client_end, Duration::from_secs(2));
            let answer = async move {
                // The request, up to its CR LF; then the response, then the end of the stream.
                let mut seen = Vec::new();
                let mut buf = [0u8; 512];
                while !seen.ends_with(b"\r\n") {
                    match peer.read(&mut buf).await {
                        Ok(0) | Err(_) => return,
                        Ok(n) => seen.extend_from_slice(&buf[..n]),
                    }
                }
                let _ = peer.write_all(&frame).await;
            };
            let (regs, ()) = tokio::join!(client.read_holding_registers(1, 0, 1), answer);
            regs
        })
    }
}

impl Default for OmsModbus {
    fn default() -> Self {
        Self::new()
    }
}

/// The bytes of a text of hex pairs, read by this adapter only to give a test frame a matching
/// LRC (or, for `check`, the span's bytes); `None` where the text is not pairs of 0-9, A-F, a-f.
/// Such a frame gets "00": oms-modbus drops it for its odd length or bad pair before the LRC
/// matters (ascii.rs:270-281), so the placeholder never decides an answer.
fn pairs(text: &[u8]) -> Option<Vec<u8>> {
    fn nibble(c: u8) -> Option<u8> {
        (c as char).to_digit(16).map(|d| d as u8)
    }
    if text.len() % 2 != 0 {
        return None;
    }
    text.chunks(2)
        .map(|p| Some(nibble(p[0])? << 4 | nibble(p[1])?))
        .collect()
}

impl Codec for OmsModbus {
    fn name(&self) -> &str {
        "oms-modbus"
    }

    fn abilities(&self) -> CodecAbilities {
        CodecAbilities {
            hex_to_value: Some(OperationAbilities::default()),
            value_to_hex: Some(OperationAbilities::default()),
            check: Some(OperationAbilities::default()),
            protocol: Some(ProtocolClaim {
                id: "modbus-ascii".into(),
                fields: Some(vec!["register".into(), "lrc".into()]),
                cross_vendor: false,
            }),
            ..CodecAbilities::default()
        }
    }

    /// The version Cargo.toml pins (`=0.2.0`).
    fn version(&self) -> Option<String> {
        Some("oms-modbus 0.2.0".into())
    }

    fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
        match q.operation {
            Operation::HexToValue => {
                // A read-holding-registers response: unit 01H, function 03H, byte count 02H,
                // the field, the LRC, CR LF.
                let mut frame = b":010302".to_vec();
                frame.extend_from_slice(q.text);
                let lrc = pairs(&frame[1..]).map_or(0, |b| oms_modbus::calculate_lrc(&b));
                frame.extend_from_slice(format!("{lrc:02X}\r\n").as_bytes());
                Ok(match self.read_register(frame) {
                    Ok(regs) => match regs.first() {
                        Some(r) => Answer::Value(u64::from(*r)),
                        None => Answer::Error(ErrorClass::Error),
                    },
                    // Which error says nothing of the field: a skipped line ends the stream.
                    Err(_) => Answer::Error(ErrorClass::Error),
                })
            }
            Operation::ValueToHex => {
                let data = match q.digits {
                    2 => vec![q.value as u8],
                    _ => (q.value as u16).to_be_bytes().to_vec(),
                };
                // ':' the field, the LRC, CR LF.
                let frame = oms_modbus::codec::encode_ascii_frame(&data);
                let text = frame.get(1..frame.len().saturating_sub(4)).unwrap_or(&[]);
                Ok(Answer::Text(text.to_vec()))
            }
            Operation::Check => {
                let bytes =
                    pairs(q.text).ok_or_else(|| Unsupported("a span of hex pairs".into()))?;
                let frame = oms_modbus::codec::encode_ascii_frame(&bytes);
                let n = frame.len();
                Ok(Answer::Text(frame[n - 4..n - 2].to_vec()))
            }
            other => Err(Unsupported(format!("implements no {other}"))),
        }
    }
}
