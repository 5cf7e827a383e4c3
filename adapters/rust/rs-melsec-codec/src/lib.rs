//! rs-melsec's MC protocol (3E frame, ASCII code) word coding as a plc-conformance codec.
//!
//! In MC protocol ASCII code a word is 4 hex digits sent from the upper digit, a double word 8,
//! the high word first (mc-ascii/M1, M2). rs-melsec 0.1.0 decodes a reply's fields in the
//! private `Client::decode_value` (src/client.rs:277: `hex::decode`, then a little-endian
//! read), reached from outside only through a request to a PLC: `Client::batch_read`
//! (l.340) on a connected client. So a field is read here as the library reads a reply: a
//! one-shot peer on 127.0.0.1 answers the batch read with a 3E ASCII response whose data part is
//! the field. `Client::encode_value` (l.225) is public and is what the client puts in a
//! request; it writes binary whatever the communication data code, and is wired as it is.
//!
//! Judged by the protocol's own corpus (`protocol: mc-ascii`): word (`DataType::UWORD`) and
//! dword (`DataType::UDWORD`). The end code is not claimed: it is only checked against zero.

use std::io::{Read, Write};
use std::net::TcpListener;

use plc_conformance::{
    Answer, CodecAbilities, ErrorClass, Operation, OperationAbilities, ProtocolClaim,
};
use plc_conformance::{Codec, Question, Unsupported};
use rs_melsec::client::Client;
use rs_melsec::db::DataType;

/// rs-melsec 0.1 as a codec: the library calls and nothing else.
pub struct RsMelsec;

/// A 3E ASCII response up to its end code: subheader D000, network 00, PC FF, module I/O 03FF,
/// station 00, data length (not read by rs-melsec), end code 0000. The data starts at
/// character 22, where rs-melsec reads it (src/device_info.rs:25).
const RESPONSE_HEAD: &[u8] = b"D00000FF03FF0000000000";

fn data_type(field: &str, digits: u32) -> DataType {
    match (field, digits) {
        ("dword", _) | ("", 8) => DataType::UDWORD,
        _ => DataType::UWORD,
    }
}

impl RsMelsec {
    /// `field` read by `batch_read` from a peer's response.
    fn read(&self, field: &[u8], ty: DataType) -> Result<Answer, Unsupported> {
        let peer = |e: std::io::Error| Unsupported(format!("loopback peer: {e}"));
        let listener = TcpListener::bind("127.0.0.1:0").map_err(peer)?;
        let port = listener.local_addr().map_err(peer)?.port();
        let mut response = RESPONSE_HEAD.to_vec();
        response.extend_from_slice(field);
        let answering = std::thread::spawn(move || -> std::io::Result<()> {
            let (mut stream, _) = listener.accept()?;
            let mut request = [0u8; 4096];
            let _ = stream.read(&mut request)?;
            stream.write_all(&response)
        });
        let mut client = Client::new("127.0.0.1".to_string(), port, "Q", false);
        client.set_comm_type("ascii");
        if let Err(e) = client.connect() {
            // The peer still waits in accept: left behind, as a failed connect is a fault here.
            return Err(Unsupported(format!("rs-melsec connect: {e}")));
        }
        let answer = match client.batch_read("D0", 1, ty, true) {
            Ok(tags) => match tags.first().and_then(|t| t.value.as_deref()) {
                Some(v) => v
                    .parse::<u64>()
                    .map_or(Answer::Error(ErrorClass::Error), Answer::Value),
                None => Answer::Error(ErrorClass::Error),
            },
            // hex::FromHexError (a character, an odd count) or a short read: which one is not
            // told apart here; a protocol case takes any error.
            Err(_) => Answer::Error(ErrorClass::InvalidDigit),
        };
        drop(client);
        let _ = answering.join();
        Ok(answer)
    }
}

impl Codec for RsMelsec {
    fn name(&self) -> &str {
        "rs-melsec"
    }

    fn abilities(&self) -> CodecAbilities {
        let field = OperationAbilities {
            width: 32,
            ..OperationAbilities::default()
        };
        CodecAbilities {
            hex_to_value: Some(field.clone()),
            value_to_hex: Some(field),
            protocol: Some(ProtocolClaim {
                id: "mc-ascii".into(),
                fields: Some(vec!["word".into(), "dword".into()]),
                cross_vendor: false,
            }),
            ..CodecAbilities::default()
        }
    }

    /// The version Cargo.toml pins (`=0.1.0`).
    fn version(&self) -> Option<String> {
        Some("rs-melsec 0.1.0".into())
    }

    fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
        let ty = data_type(q.field, q.digits);
        match q.operation {
            Operation::HexToValue => {
                // batch_read slices `DataType::size()` characters of the reply with no length
                // check (src/client.rs:430): a shorter reply panics there, so it is not sent.
                if q.text.len() < ty.size() as usize {
                    return Err(Unsupported(format!(
                        "rs-melsec 0.1.0 panics on a reply shorter than {} characters after \
                         the end code (src/client.rs:430, slice out of range)",
                        ty.size()
                    )));
                }
                self.read(q.text, ty)
            }
            Operation::ValueToHex => {
                let mut client = Client::new("127.0.0.1".to_string(), 0, "Q", false);
                client.set_comm_type("ascii");
                client
                    .encode_value(q.value as i64, ty, false)
                    .map(Answer::Text)
                    .map_err(|e| Unsupported(format!("rs-melsec encode_value: {e}")))
            }
            other => Err(Unsupported(format!("implements no {other}"))),
        }
    }
}
