//! An SLMP client over one TCP connection, binary code, one request in flight.
//!
//! One request at a time is a rule, not a simplification: an FX5U answered two pipelined
//! requests with one reply (for the last) and end code 0, which on 3E nothing can detect. Every
//! reply is read by its declared length, since a CPU's reply may arrive in several segments. A
//! timeout, a closed connection or a reply that does not decode drops the connection: a late
//! reply must never be read as the answer to the next request, and 3E has no serial number to
//! tell them apart. Reads are sent again (on a new connection) a bounded number of times, since
//! reading twice changes nothing; writes never are, so that no write can land twice or late
//! without the caller knowing.

use std::fmt;
use std::time::Duration;

use crate::backend::bench::tcp::{self, hex, TransportError};

use super::ascii;
pub(crate) use super::frame::Code;
use super::frame::{
    self, message_len, DeviceForm, DeviceRef, FrameError, FrameKind, Request, Response, Route,
    TypeName,
};
use super::limits::{limits, Family, Limits};
use crate::backend::bench::fence::FencedWrite;
use crate::device::Device;

/// How to reach and talk to one CPU port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClientSettings {
    /// `host:port`.
    pub address: String,
    pub frame: FrameKind,
    /// Binary code unless the port is configured for ASCII.
    pub code: Code,
    pub form: DeviceForm,
    pub route: Route,
    /// The monitoring timer sent with each request, in units of 250 ms.
    pub timer: u16,
    /// How long to wait for one reply.
    pub reply_timeout: Duration,
    /// How long to wait for a connection.
    pub connect_timeout: Duration,
    /// How many times a read is sent again after a timeout or a lost connection.
    pub read_retries: u32,
    /// What one request may carry on this port.
    pub limits: Limits,
}

impl ClientSettings {
    /// Defaults for a port: 4E frames and the long device form (iQ-R) unless told otherwise; a
    /// monitoring timer of 2 s, and a reply timeout half a second past it, so that the CPU's own
    /// timeout answer arrives before the client gives up.
    pub fn new(address: impl Into<String>) -> Self {
        ClientSettings {
            address: address.into(),
            frame: FrameKind::E4,
            code: Code::Binary,
            form: DeviceForm::Long,
            route: Route::default(),
            timer: 8,
            reply_timeout: Duration::from_millis(2500),
            connect_timeout: Duration::from_secs(3),
            read_retries: 2,
            limits: limits(Family::Iqr, Code::Binary, DeviceForm::Long),
        }
    }

    /// The transport as provenance names it: `SLMP 4E binary TCP 192.0.2.10:5007`.
    pub fn describe(&self) -> String {
        format!("SLMP {} {} TCP {}", self.frame, self.code, self.address)
    }
}

/// Why a request got no usable answer: the transport's ways, shared with every link, or the
/// CPU's error end code.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ClientError {
    Transport(TransportError),
    /// The CPU answered with an error end code; `form` is the device form the request used.
    EndCode {
        what: String,
        code: u16,
        form: DeviceForm,
    },
}

/// What a CPU that stays silent on SLMP is likely telling.
const SILENCE: &str = "a CPU stays silent when the frame (3E/4E), the code (binary/ASCII) or the \
                       device form does not match its port, or when the port is not open to \
                       this host";

impl From<TransportError> for ClientError {
    fn from(e: TransportError) -> Self {
        ClientError::Transport(e)
    }
}

impl fmt::Display for ClientError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ClientError::Transport(e) => write!(f, "{e}"),
            ClientError::EndCode { what, code, form } => {
                write!(f, "the CPU answered {what} with end code {code:04X}H")?;
                if let Some(meaning) = end_code_meaning(*code, *form) {
                    write!(f, " ({meaning})")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for ClientError {}

/// What the common end codes mean, in a few words, for messages. The SLMP manuals list them;
/// these few are the ones a misconfigured bench meets. C059H blames the long device form only
/// when the request used it.
pub(crate) fn end_code_meaning(code: u16, form: DeviceForm) -> Option<&'static str> {
    Some(match code {
        0xC051..=0xC054 => "too many points for one request",
        0xC056 => "a device past the end of its range",
        0xC059 if form == DeviceForm::Long => {
            "command or subcommand not supported (an FX5 refuses the long device form: give \
             form=short)"
        }
        0xC059 => "command or subcommand not supported",
        0xC05B | 0xC05C => "device not supported or request malformed",
        0xC061 => "request data length does not match",
        _ => return None,
    })
}

/// A device as a command names it, for the request `what`.
pub(crate) fn device_ref(device: &Device, what: &str) -> Result<DeviceRef, ClientError> {
    let code = frame::device_code(device.code())
        .ok_or_else(|| refused(what, format!("{} has no SLMP device code", device.code())))?;
    Ok(DeviceRef {
        code,
        number: device.index,
    })
}

impl tcp::ProtocolError for ClientError {
    fn transport(&self) -> Option<&TransportError> {
        match self {
            ClientError::Transport(e) => Some(e),
            ClientError::EndCode { .. } => None,
        }
    }
}

/// One connection to a CPU (made on first use, dropped after a fault); a 4E frame carries the
/// client's request number as its serial.
pub(crate) type Client = tcp::Client<ClientSettings>;

impl Client {
    /// Sends one request and reads its reply; drops the connection on any fault.
    fn exchange(&mut self, what: &str, body: &frame::Body) -> Result<Vec<u8>, ClientError> {
        let frame_kind = self.settings.frame;
        let sequence = self.next_sequence();
        let serial = if frame_kind == FrameKind::E4 {
            sequence
        } else {
            0
        };
        let request = Request {
            frame: frame_kind,
            serial,
            route: self.settings.route,
            timer: self.settings.timer,
            command: body.command,
            subcommand: body.subcommand,
            data: body.data.clone(),
        };
        let code = self.settings.code;
        let request = match code {
            Code::Binary => request.encode(),
            Code::Ascii => ascii::encode_request(&request).map_err(|e| refused(what, e))?,
        };
        let exchange = tcp::Exchange {
            what,
            timeout: self.settings.reply_timeout,
            protocol: "SLMP",
            silence: SILENCE,
        };
        let bytes = self.connection.exchange(
            &self.settings.address,
            self.settings.connect_timeout,
            &request,
            &exchange,
            header_len(frame_kind, code),
            |header| reply_len(frame_kind, code, header, &exchange),
        )?;
        let result = (|| {
            let response = match code {
                Code::Binary => Response::decode(frame_kind, &bytes),
                Code::Ascii => ascii::decode_response(frame_kind, body.command, &bytes),
            }
            .map_err(|e| garbled(what, tcp::received(&e, &bytes)))?;
            if response.serial != serial {
                return Err(garbled(
                    what,
                    format!(
                        "it carries serial {:04X}H, the request {serial:04X}H",
                        response.serial
                    ),
                ));
            }
            if response.end_code != 0 {
                return Err(ClientError::EndCode {
                    what: what.into(),
                    code: response.end_code,
                    form: self.settings.form,
                });
            }
            Ok(response.data)
        })();
        if let Err(ClientError::Transport(_)) = &result {
            // An error answer is a whole, well-formed reply: the connection is still in step.
            self.connection.disconnect();
        }
        result
    }

    /// A read, sent again on a new connection after a timeout or a lost connection.
    fn read_exchange(&mut self, what: &str, body: &frame::Body) -> Result<Vec<u8>, ClientError> {
        let retries = self.settings.read_retries;
        tcp::retry_read(retries, || self.exchange(what, body))
    }

    /// 0101: the CPU's type name.
    pub(crate) fn type_name(&mut self) -> Result<TypeName, ClientError> {
        let what = "0101 (read type name)";
        let data = self.read_exchange(what, &frame::read_type_name())?;
        frame::type_name_of(&data).map_err(|e| garbled(what, e))
    }

    /// 0401: `count` words from `head`, in batches of at most the port's limit.
    pub(crate) fn read_words(
        &mut self,
        head: &Device,
        count: u32,
    ) -> Result<Vec<u16>, ClientError> {
        let mut out = Vec::with_capacity(count as usize);
        let first = device_ref(head, &format!("reading {head}"))?;
        while out.len() < count as usize {
            let n = (count as usize - out.len()).min(self.settings.limits.batch_words.max(1));
            let at = DeviceRef {
                number: first.number + out.len() as u32,
                ..first
            };
            let what = format!("0401 (read {at} x{n})");
            let body = frame::read_words(self.settings.form, at, n)
                .map_err(|e| refused(what.clone(), e))?;
            let data = self.read_exchange(&what, &body)?;
            out.extend(frame::words_of(&data, n).map_err(|e| garbled(what, e))?);
        }
        Ok(out)
    }

    /// 0403: one word from each device, in one request (at most the port's limit).
    pub(crate) fn random_read(&mut self, devices: &[Device]) -> Result<Vec<u16>, ClientError> {
        let names: Vec<String> = devices.iter().map(ToString::to_string).collect();
        let what = format!("0403 (read {})", names.join(" "));
        let refs = devices
            .iter()
            .map(|d| device_ref(d, &what))
            .collect::<Result<Vec<_>, _>>()?;
        let most = self.settings.limits.random_points;
        if refs.len() > most {
            return Err(refused(
                what,
                format!("more than {most} points, the limit of this port"),
            ));
        }
        let body =
            frame::random_read(self.settings.form, &refs).map_err(|e| refused(what.clone(), e))?;
        let data = self.read_exchange(&what, &body)?;
        frame::words_of(&data, refs.len()).map_err(|e| garbled(what, e))
    }

    /// 1401: one write the fence let through, encoded here and nowhere else; never sent twice.
    pub(crate) fn write(&mut self, write: &FencedWrite) -> Result<(), ClientError> {
        let what = format!("1401 (write {})", write.range());
        let body = device_ref(write.head(), &what).and_then(|head| {
            frame::write_words(self.settings.form, head, write.words())
                .map_err(|e| refused(what.clone(), e))
        })?;
        let data = self.exchange(&what, &body)?;
        if data.is_empty() {
            Ok(())
        } else {
            self.connection.disconnect();
            Err(garbled(
                what,
                format!("{} bytes of data after a write", data.len()),
            ))
        }
    }
}

/// A request refused before anything is sent.
fn refused(what: impl Into<String>, detail: impl fmt::Display) -> ClientError {
    ClientError::Transport(TransportError::refused(what, detail))
}

/// A reply that does not decode, or answers another request.
fn garbled(what: impl Into<String>, detail: impl fmt::Display) -> ClientError {
    ClientError::Transport(TransportError::garbled(what, detail, "SLMP"))
}

/// How many bytes of a reply say how long it is.
fn header_len(frame_kind: FrameKind, code: Code) -> usize {
    match code {
        Code::Ascii => ascii::header_len(frame_kind),
        Code::Binary => frame_kind.header_len(),
    }
}

/// A reply's whole length, from its header; a header that does not start like a reply is
/// refused before its length is believed.
fn reply_len(
    frame_kind: FrameKind,
    code: Code,
    header: &[u8],
    exchange: &tcp::Exchange<'_>,
) -> Result<usize, TransportError> {
    if code == Code::Ascii {
        return ascii::message_len(frame_kind, header)
            .and_then(|total| {
                ascii::decode_response(frame_kind, 0, header)
                    .err()
                    .filter(|e| !matches!(e, FrameError::Short { .. }))
                    .map_or(Ok(total), Err)
            })
            .map_err(|e| exchange.frame(tcp::received(&e, header)));
    }
    let expected = match frame_kind {
        FrameKind::E3 => 0xD0,
        FrameKind::E4 => 0xD4,
    };
    if header[0] != expected || header[1] != 0 {
        return Err(exchange.frame(format!(
            "subheader {} where {:02X} 00 was expected; received: {}",
            hex(&header[..2]),
            expected,
            hex(header)
        )));
    }
    message_len(frame_kind, header).map_err(|e| exchange.frame(tcp::received(&e, header)))
}

#[cfg(test)]
impl Client {
    /// The settings, to change before the first request (a connection made keeps its frame).
    pub(crate) fn settings_mut(&mut self) -> &mut ClientSettings {
        &mut self.settings
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::fence::{WordRange, WriteFence};
    use std::io::{Read, Write};
    use std::net::{TcpListener, TcpStream};

    /// A server that answers each request with the given byte chunks (with a pause between
    /// chunks), then closes; it returns every byte it received.
    fn scripted(replies: Vec<Vec<Vec<u8>>>) -> (String, std::thread::JoinHandle<Vec<u8>>) {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
        let address = listener.local_addr().expect("addr").to_string();
        let handle = std::thread::spawn(move || {
            let mut received = Vec::new();
            let Ok((mut s, _)) = listener.accept() else {
                return received;
            };
            for chunks in replies {
                let mut head = [0u8; 13];
                let Ok(()) = s.read_exact(&mut head[..9]) else {
                    break;
                };
                let frame = FrameKind::of_request(head[0]).unwrap_or(FrameKind::E3);
                if frame == FrameKind::E4 {
                    let _ = s.read_exact(&mut head[9..13]);
                }
                let total = message_len(frame, &head[..frame.header_len()]).unwrap_or(0);
                let mut rest = vec![0u8; total - frame.header_len()];
                let _ = s.read_exact(&mut rest);
                received.extend_from_slice(&head[..frame.header_len()]);
                received.extend_from_slice(&rest);
                for c in chunks {
                    let _ = s.write_all(&c);
                    std::thread::sleep(Duration::from_millis(30));
                }
            }
            // Hold the connection until the client lets it go, as a silent CPU would.
            let _ = s.read_to_end(&mut Vec::new());
            received
        });
        (address, handle)
    }

    fn settings(address: &str) -> ClientSettings {
        let mut s = ClientSettings::new(address);
        s.frame = FrameKind::E3;
        s.form = DeviceForm::Short;
        s.reply_timeout = Duration::from_millis(400);
        s.read_retries = 0;
        s
    }

    fn reply(data: &[u8]) -> Vec<u8> {
        Response {
            frame: FrameKind::E3,
            serial: 0,
            route: Route::default(),
            end_code: 0,
            data: data.to_vec(),
        }
        .encode()
    }

    #[test]
    fn a_reply_in_several_segments_is_read_whole() {
        let r = reply(&[0x8D, 0x5A, 0x34, 0x12]);
        let (address, server) = scripted(vec![vec![
            r[..5].to_vec(),
            r[5..12].to_vec(),
            r[12..].to_vec(),
        ]]);
        let mut c = Client::new(settings(&address));
        let words = c.read_words(&Device::new("D", 200), 2).expect("read");
        assert_eq!(words, [0x5A8D, 0x1234]);
        drop(c);
        let sent = server.join().expect("server");
        assert_eq!(
            hex(&sent),
            "50 00 00 FF FF 03 00 0C 00 08 00 01 04 00 00 C8 00 00 A8 02 00"
        );
    }

    #[test]
    fn garbage_is_a_frame_error_quoting_the_bytes() {
        let (address, _server) = scripted(vec![vec![b"HTTP/1.1 400 Bad".to_vec()]]);
        let mut c = Client::new(settings(&address));
        let e = c.read_words(&Device::new("D", 0), 1).expect_err("garbage");
        assert!(
            matches!(e, ClientError::Transport(TransportError::Frame { .. })),
            "{e}"
        );
        assert!(e.to_string().contains("received: 48 54 54 50"), "{e}");
        assert!(!c.is_connected(), "the connection is dropped after garbage");
    }

    #[test]
    fn silence_is_a_timeout_with_its_likely_causes() {
        let (address, _server) = scripted(vec![vec![]]);
        let mut c = Client::new(settings(&address));
        let e = c.type_name().expect_err("silent");
        assert!(
            matches!(e, ClientError::Transport(TransportError::Timeout { .. })),
            "{e}"
        );
        assert!(
            e.to_string()
                .contains("the frame (3E/4E), the code (binary/ASCII)"),
            "{e}"
        );
    }

    #[test]
    fn an_error_end_code_keeps_the_connection() {
        let r = Response {
            frame: FrameKind::E3,
            serial: 0,
            route: Route::default(),
            end_code: 0xC056,
            data: vec![0, 0xFF, 0xFF, 3, 0, 1, 4, 0, 0],
        }
        .encode();
        let (address, _server) = scripted(vec![vec![r]]);
        let mut c = Client::new(settings(&address));
        let e = c
            .read_words(&Device::new("D", 18432), 1)
            .expect_err("end code");
        assert_eq!(
            e.to_string(),
            "the CPU answered 0401 (read D18432 x1) with end code C056H (a device past the end \
             of its range)"
        );
        assert!(c.is_connected());
    }

    /// C059H blames the long device form only when the request used it.
    #[test]
    fn c059_names_the_long_form_only_when_it_was_sent() {
        let long = end_code_meaning(0xC059, DeviceForm::Long).expect("known");
        assert!(long.contains("long device form"), "{long}");
        let short = end_code_meaning(0xC059, DeviceForm::Short).expect("known");
        assert!(!short.contains("long"), "{short}");
    }

    #[test]
    fn a_refused_write_sends_nothing() {
        let (address, server) = scripted(vec![]);
        let fence = WriteFence::new(vec![WordRange::new("D", 0, 99)]);
        let refused = fence.writes(960, &Device::new("D", 99), &[1, 2]);
        assert!(refused.is_err());
        let c = Client::new(settings(&address));
        assert!(!c.is_connected(), "a client connects only when it sends");
        drop(c);
        // Wake the scripted server so that it returns what it got: nothing.
        let _ = TcpStream::connect(&address);
        assert!(server.join().expect("server").is_empty());
    }
}
