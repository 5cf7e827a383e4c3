//! A Modbus TCP client over one TCP connection, one request in flight.
//!
//! One request at a time, though MBAP's transaction id would allow more: many PLC Ethernet
//! modules serve one request per connection at a time and queue, drop or misanswer the rest,
//! and a conformance run must know which request each value answers. Every reply is read by the
//! length its MBAP header declares, since it may arrive in several segments, and never past it.
//! A timeout, a lost connection or a reply that does not decode (another transaction id
//! included) drops the connection: a late reply must never be read as the answer to the next
//! request. An exception is a whole, well-formed reply and keeps it. Reads are sent again (on a
//! new connection) up to `read_retries` times, since reading twice changes nothing; writes never
//! are, so that no write can land twice or late without the caller knowing.

use std::fmt;
use std::time::Duration;

use crate::backend::bench::tcp::{self, TransportError};

use super::frame::{
    self, decode_response, encode_request, exception_meaning, message_len, Request, Response,
};

/// How much one request may carry on this link; every batch is split at these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ModbusLimits {
    pub read_registers: usize,
    pub write_registers: usize,
    pub read_coils: usize,
}

impl Default for ModbusLimits {
    /// The specification's limits (125, 123, 2000); a CPU's manual may give less.
    fn default() -> Self {
        ModbusLimits {
            read_registers: frame::MAX_READ_REGISTERS,
            write_registers: frame::MAX_WRITE_REGISTERS,
            read_coils: frame::MAX_READ_COILS,
        }
    }
}

/// How to reach and talk to one Modbus TCP server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ModbusSettings {
    /// `host:port`.
    pub address: String,
    pub unit: u8,
    /// How long to wait for one whole reply.
    pub reply_timeout: Duration,
    /// How long to wait for a connection.
    pub connect_timeout: Duration,
    /// How many times a read is sent again after a timeout or a lost connection.
    pub read_retries: u32,
    pub limits: ModbusLimits,
}

impl ModbusSettings {
    /// Defaults: unit 1, a reply timeout of 1 s, a connect timeout of 3 s, 2 read retries.
    /// Unit 1 is a plain default, not the Messaging guide's 0xFF: a server that is the device
    /// itself ignores the field or answers only the station it is configured as, commonly 1,
    /// and a gateway needs the address of the device behind it; set it for either.
    pub(crate) fn new(address: impl Into<String>) -> Self {
        ModbusSettings {
            address: address.into(),
            unit: 1,
            reply_timeout: Duration::from_secs(1),
            connect_timeout: Duration::from_secs(3),
            read_retries: 2,
            limits: ModbusLimits::default(),
        }
    }

    /// The transport as provenance names it: `Modbus TCP 127.0.0.1:502 unit 1`.
    pub(crate) fn describe(&self) -> String {
        format!("Modbus TCP {} unit {}", self.address, self.unit)
    }
}

/// Why a request got no usable answer: the transport's ways, shared with every link, or the
/// server's exception.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ModbusError {
    Transport(TransportError),
    /// The server answered with an exception; `function` is the one requested.
    Exception {
        what: String,
        function: u8,
        code: u8,
    },
}

/// What a Modbus TCP server that stays silent is likely telling.
const SILENCE: &str = "a gateway may stay silent when no device answers at the unit id, and a \
                       server may ignore a unit id it does not serve";

impl From<TransportError> for ModbusError {
    fn from(e: TransportError) -> Self {
        ModbusError::Transport(e)
    }
}

impl fmt::Display for ModbusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModbusError::Transport(e) => write!(f, "{e}"),
            ModbusError::Exception { what, code, .. } => {
                write!(f, "the server answered {what} with exception {code:02X}")?;
                if let Some(meaning) = exception_meaning(*code) {
                    write!(f, " ({meaning})")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for ModbusError {}

impl tcp::ProtocolError for ModbusError {
    fn transport(&self) -> Option<&TransportError> {
        match self {
            ModbusError::Transport(e) => Some(e),
            ModbusError::Exception { .. } => None,
        }
    }
}

/// One connection to a server (made on first use, dropped after a fault); the transaction id
/// is the client's request number.
pub(crate) type ModbusClient = tcp::Client<ModbusSettings>;

impl ModbusClient {
    /// Sends one request and reads its reply; drops the connection on any fault but an
    /// exception.
    fn exchange(&mut self, what: &str, request: &Request) -> Result<Response, ModbusError> {
        let (tid, unit) = (self.next_sequence(), self.settings.unit);
        let exchange = tcp::Exchange {
            what,
            timeout: self.settings.reply_timeout,
            protocol: "Modbus TCP",
            silence: SILENCE,
        };
        let bytes = encode_request(tid, unit, request).map_err(|e| exchange.refused(e))?;
        let reply = self.connection.exchange(
            &self.settings.address,
            self.settings.connect_timeout,
            &bytes,
            &exchange,
            6,
            |header| {
                let fixed: &[u8; 6] = (header.try_into())
                    .map_err(|_| exchange.frame("a short header".to_string()))?;
                message_len(fixed).map_err(|e| exchange.frame(tcp::received(&e, header)))
            },
        )?;
        match decode_response(tid, unit, request, &reply) {
            Ok(Response::Exception { function, code }) => Err(ModbusError::Exception {
                what: what.into(),
                function,
                code,
            }),
            Ok(response) => Ok(response),
            Err(e) => {
                self.connection.disconnect();
                Err(exchange.frame(tcp::received(&e, &reply)).into())
            }
        }
    }

    /// A read, sent again on a new connection after a timeout or a lost connection.
    fn read_exchange(&mut self, what: &str, request: &Request) -> Result<Response, ModbusError> {
        let retries = self.settings.read_retries;
        tcp::retry_read(retries, || self.exchange(what, request))
    }

    /// FC03: `count` holding registers from wire address `address`, in batches of at most the
    /// link's limit. A range past 0xFFFF is refused before anything is sent.
    pub(crate) fn read_holding(
        &mut self,
        address: u16,
        count: usize,
    ) -> Result<Vec<u16>, ModbusError> {
        self.read_batched(
            (address, count),
            self.settings.limits.read_registers,
            ("FC03 read", "registers"),
            |address, count| Request::ReadHolding { address, count },
            |response| match response {
                Response::Registers(values) => Ok(values),
                other => Err(other),
            },
        )
    }

    /// FC01: `count` coils from wire address `address`, in batches of at most the link's limit.
    pub(crate) fn read_coils(
        &mut self,
        address: u16,
        count: usize,
    ) -> Result<Vec<bool>, ModbusError> {
        self.read_batched(
            (address, count),
            self.settings.limits.read_coils,
            ("FC01 read", "coils"),
            |address, count| Request::ReadCoils { address, count },
            |response| match response {
                Response::Coils(values) => Ok(values),
                other => Err(other),
            },
        )
    }

    /// `count` points from `address` (`span`), in requests of at most `batch` points (each
    /// `request(at, n)`, named `action` of n `unit` for errors), all checked before the first is
    /// sent; `values` takes each reply's points out, and a reply of another kind is a frame
    /// error. What FC03 and FC01 differ in is only which request and which reply.
    fn read_batched<T>(
        &mut self,
        (address, count): (u16, usize),
        batch: usize,
        (action, unit): (&str, &str),
        request: impl Fn(u16, u16) -> Request,
        values: impl Fn(Response) -> Result<Vec<T>, Response>,
    ) -> Result<Vec<T>, ModbusError> {
        let mut out = Vec::with_capacity(count);
        for (at, n) in batches(address, count, batch.max(1), action, unit)? {
            let what = describe(action, n, unit, at);
            let response = self.read_exchange(&what, &request(at, n as u16))?;
            out.extend(values(response).map_err(|other| unexpected(what, &other))?);
        }
        Ok(out)
    }

    /// One value: FC06; more: FC16 in batches of at most the link's limit. Never sent twice; if
    /// a later batch fails, the earlier ones have landed and the error names the one that did
    /// not.
    pub(crate) fn write_registers(
        &mut self,
        address: u16,
        values: &[u16],
    ) -> Result<(), ModbusError> {
        if let [value] = values {
            let what = describe("FC06 write", 1, "register", address);
            let request = Request::WriteSingle {
                address,
                value: *value,
            };
            return self.exchange(&what, &request).map(drop);
        }
        let batch = self.settings.limits.write_registers.max(1);
        let mut done = 0;
        for (at, n) in batches(address, values.len(), batch, "FC16 write", "registers")? {
            let what = describe("FC16 write", n, "registers", at);
            let request = Request::WriteMultiple {
                address: at,
                values: values[done..done + n].to_vec(),
            };
            self.exchange(&what, &request)?;
            done += n;
        }
        Ok(())
    }
}

/// `FC03 read of 100 registers at 0x0064`: the function and the wire address, as a capture shows.
fn describe(action: &str, n: usize, unit: &str, at: u16) -> String {
    format!("{action} of {n} {unit} at 0x{at:04X}")
}

/// The (address, count) of each request, all checked before the first is sent.
fn batches(
    address: u16,
    count: usize,
    batch: usize,
    action: &str,
    unit: &str,
) -> Result<Vec<(u16, usize)>, ModbusError> {
    if usize::from(address) + count > 0x1_0000 {
        return Err(ModbusError::Transport(TransportError::refused(
            describe(action, count, unit, address),
            "the range runs past address 0xFFFF",
        )));
    }
    Ok((0..count)
        .step_by(batch)
        .map(|done| {
            (
                (usize::from(address) + done) as u16,
                batch.min(count - done),
            )
        })
        .collect())
}

fn unexpected(what: String, response: &Response) -> ModbusError {
    ModbusError::Transport(TransportError::garbled(
        what,
        format!("decoded as {response:?}"),
        "Modbus TCP",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::tcp::hex;
    use frame::{bytes_of, encode_response};
    use std::io::{Read, Write};
    use std::net::TcpListener;
    use std::thread::JoinHandle;

    /// What the scripted server does after reading one request.
    enum Act {
        /// Sends these chunks, pausing between them.
        Reply(Vec<Vec<u8>>),
        /// Answers nothing.
        Silent,
        /// Closes the connection without answering.
        Close,
    }

    fn reply(tid: u16, response: Response) -> Act {
        Act::Reply(vec![encode_response(tid, 1, &response)])
    }

    /// A server that follows one script per connection it accepts, and returns every request
    /// it read, as hex. After a script that does not close, it holds the connection until the
    /// client lets it go, as a silent server would.
    fn scripted(connections: Vec<Vec<Act>>) -> (String, JoinHandle<Vec<String>>) {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
        let address = listener.local_addr().expect("addr").to_string();
        let handle = std::thread::spawn(move || {
            let mut received = Vec::new();
            for script in connections {
                let Ok((mut s, _)) = listener.accept() else {
                    break;
                };
                let mut closed = false;
                for act in script {
                    let mut header = [0u8; 6];
                    let Ok(()) = s.read_exact(&mut header) else {
                        break;
                    };
                    let total = message_len(&header).unwrap_or(6);
                    let mut adu = header.to_vec();
                    adu.resize(total, 0);
                    let _ = s.read_exact(&mut adu[6..]);
                    received.push(hex(&adu));
                    match act {
                        Act::Reply(chunks) => {
                            for c in chunks {
                                let _ = s.write_all(&c);
                                std::thread::sleep(Duration::from_millis(30));
                            }
                        }
                        Act::Silent => {}
                        Act::Close => {
                            closed = true;
                            break;
                        }
                    }
                }
                if !closed {
                    let _ = s.read_to_end(&mut Vec::new());
                }
            }
            received
        });
        (address, handle)
    }

    fn settings(address: &str) -> ModbusSettings {
        let mut s = ModbusSettings::new(address);
        s.reply_timeout = Duration::from_millis(200);
        s.read_retries = 0;
        s
    }

    #[test]
    fn a_reply_in_several_segments_is_read_whole() {
        let r = bytes_of("00 01 00 00 00 09 01 03 06 02 2B 00 00 00 64");
        let chunks = vec![r[..3].to_vec(), r[3..8].to_vec(), r[8..].to_vec()];
        let (address, server) = scripted(vec![vec![Act::Reply(chunks)]]);
        let mut c = ModbusClient::new(settings(&address));
        assert_eq!(c.read_holding(0x6B, 3), Ok(vec![0x022B, 0, 0x64]));
        drop(c);
        let sent = server.join().expect("server");
        assert_eq!(sent, ["00 01 00 00 00 06 01 03 00 6B 00 03"]);
    }

    #[test]
    fn garbage_is_a_frame_error_quoting_the_bytes() {
        let (address, _server) = scripted(vec![vec![Act::Reply(vec![
            b"HTTP/1.1 400 Bad Request\r\n".to_vec(),
        ])]]);
        let mut c = ModbusClient::new(settings(&address));
        let e = c.read_holding(0, 1).expect_err("garbage");
        assert!(
            matches!(e, ModbusError::Transport(TransportError::Frame { .. })),
            "{e}"
        );
        assert!(e.to_string().contains("received: 48 54 54 50"), "{e}");
        assert!(!c.is_connected(), "the connection is dropped after garbage");
    }

    #[test]
    fn silence_is_a_timeout_and_drops_the_connection() {
        let (address, _server) = scripted(vec![vec![Act::Silent]]);
        let mut c = ModbusClient::new(settings(&address));
        let e = c.read_coils(0x13, 19).expect_err("silent");
        assert_eq!(
            e,
            ModbusError::Transport(TransportError::Timeout {
                what: "FC01 read of 19 coils at 0x0013".into(),
                waited: Duration::from_millis(200),
                hint: SILENCE,
            })
        );
        assert!(!c.is_connected());
    }

    #[test]
    fn an_exception_keeps_the_connection() {
        let exception = Response::Exception {
            function: 3,
            code: 2,
        };
        let (address, _server) = scripted(vec![vec![
            reply(1, exception),
            reply(2, Response::Registers(vec![7])),
        ]]);
        let mut c = ModbusClient::new(settings(&address));
        let e = c.read_holding(100, 10).expect_err("exception");
        assert_eq!(
            e.to_string(),
            "the server answered FC03 read of 10 registers at 0x0064 with exception 02 \
             (ILLEGAL DATA ADDRESS)"
        );
        assert!(c.is_connected());
        assert_eq!(c.read_holding(0, 1), Ok(vec![7]));
        assert_eq!((c.connections(), c.requests()), (1, 2));
    }

    #[test]
    fn a_read_after_a_dropped_connection_is_sent_again() {
        let (address, server) = scripted(vec![
            vec![Act::Close],
            vec![reply(2, Response::Registers(vec![0x1234]))],
        ]);
        let mut s = settings(&address);
        s.read_retries = 1;
        let mut c = ModbusClient::new(s);
        assert_eq!(c.read_holding(5, 1), Ok(vec![0x1234]));
        assert_eq!((c.connections(), c.requests()), (2, 2));
        drop(c);
        let sent = server.join().expect("server");
        assert_eq!(
            sent,
            [
                "00 01 00 00 00 06 01 03 00 05 00 01",
                "00 02 00 00 00 06 01 03 00 05 00 01"
            ]
        );
    }

    #[test]
    fn a_write_after_a_dropped_connection_is_not_sent_again() {
        let (address, server) = scripted(vec![vec![Act::Close]]);
        let mut s = settings(&address);
        s.read_retries = 3;
        let mut c = ModbusClient::new(s);
        let e = c.write_registers(1, &[3]).expect_err("closed");
        assert!(
            matches!(e, ModbusError::Transport(TransportError::Closed { .. })),
            "{e}"
        );
        assert_eq!((c.connections(), c.requests()), (1, 1));
        let sent = server.join().expect("server");
        assert_eq!(sent, ["00 01 00 00 00 06 01 06 00 01 00 03"]);
    }

    #[test]
    fn a_300_register_read_is_split_at_the_limit() {
        let (address, server) = scripted(vec![vec![
            reply(1, Response::Registers((0..125).collect())),
            reply(2, Response::Registers((125..250).collect())),
            reply(3, Response::Registers((250..300).collect())),
        ]]);
        let mut c = ModbusClient::new(settings(&address));
        assert_eq!(c.read_holding(0, 300), Ok((0..300).collect()));
        drop(c);
        let sent = server.join().expect("server");
        assert_eq!(
            sent,
            [
                "00 01 00 00 00 06 01 03 00 00 00 7D",
                "00 02 00 00 00 06 01 03 00 7D 00 7D",
                "00 03 00 00 00 06 01 03 00 FA 00 32"
            ]
        );
    }

    #[test]
    fn one_word_is_fc06_and_two_are_fc16() {
        let (address, server) = scripted(vec![vec![
            reply(
                1,
                Response::WroteSingle {
                    address: 1,
                    value: 3,
                },
            ),
            reply(
                2,
                Response::WroteMultiple {
                    address: 1,
                    count: 2,
                },
            ),
        ]]);
        let mut c = ModbusClient::new(settings(&address));
        assert_eq!(c.write_registers(1, &[3]), Ok(()));
        assert_eq!(c.write_registers(1, &[0x000A, 0x0102]), Ok(()));
        drop(c);
        let sent = server.join().expect("server");
        assert_eq!(
            sent,
            [
                "00 01 00 00 00 06 01 06 00 01 00 03",
                "00 02 00 00 00 0B 01 10 00 01 00 02 04 00 0A 01 02"
            ]
        );
    }

    #[test]
    fn a_reply_with_another_transaction_id_drops_the_connection() {
        let (address, _server) = scripted(vec![vec![reply(9, Response::Registers(vec![1]))]]);
        let mut c = ModbusClient::new(settings(&address));
        let e = c.read_holding(0, 1).expect_err("another tid");
        assert!(
            matches!(e, ModbusError::Transport(TransportError::Frame { .. })),
            "{e}"
        );
        assert!(
            e.to_string()
                .contains("transaction id 0x0009 where 0x0001 was sent"),
            "{e}"
        );
        assert!(!c.is_connected());
    }

    #[test]
    fn a_range_past_the_last_address_sends_nothing() {
        let (address, server) = scripted(vec![]);
        let mut c = ModbusClient::new(settings(&address));
        let e = c
            .write_registers(0xFFF0, &[0; 200])
            .expect_err("past 0xFFFF");
        assert!(
            matches!(e, ModbusError::Transport(TransportError::Request { .. })),
            "{e}"
        );
        assert!(!c.is_connected(), "a client connects only when it sends");
        assert!(server.join().expect("server").is_empty());
    }

    #[test]
    fn settings_describe_the_transport() {
        let s = ModbusSettings::new("127.0.0.1:502");
        assert_eq!(s.describe(), "Modbus TCP 127.0.0.1:502 unit 1");
        assert_eq!(
            (
                s.limits.read_registers,
                s.limits.write_registers,
                s.limits.read_coils
            ),
            (125, 123, 2000)
        );
    }
}
