//! TCP as every link's client uses it: one connection tried on each address a host resolves
//! to, within a time limit and without Nagle's delay (a request is one small write, which Nagle
//! would hold back waiting for an acknowledgement); and a reply read whole by a deadline, since
//! a reply may arrive in several segments and must never be read past.

use std::fmt::{self, Display};
use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// A connection to `address` (`host:port`), or the last address's error (`NotFound` when the
/// address resolves to nothing).
pub(crate) fn connect(address: &str, timeout: Duration) -> std::io::Result<TcpStream> {
    let mut last = std::io::Error::new(
        std::io::ErrorKind::NotFound,
        "the address resolves to nothing",
    );
    for a in address.to_socket_addrs()? {
        match TcpStream::connect_timeout(&a, timeout) {
            Ok(stream) => {
                let _ = stream.set_nodelay(true);
                return Ok(stream);
            }
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// A client's one connection to a CPU, as every link keeps it: made on the first request (and
/// on the first after a fault dropped it), counted with the requests sent, for a run's figures.
#[derive(Debug, Default)]
pub(crate) struct Connection {
    stream: Option<TcpStream>,
    pub(crate) requests: u64,
    pub(crate) connections: u64,
}

/// Why an exchange got no usable reply, in the ways every link shares: no connection, no
/// whole reply in time, a lost connection, a reply that does not decode, or a request the client
/// refuses to build. A protocol's own refusal (an SLMP end code, a Modbus exception) is a whole
/// reply and belongs to its link's error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum TransportError {
    /// No connection could be made.
    Connect { address: String, error: String },
    /// No (whole) reply within the reply timeout; `hint` is what the link's devices do when
    /// they stay silent.
    Timeout {
        what: String,
        waited: Duration,
        hint: &'static str,
    },
    /// The other side closed the connection, or the socket failed.
    Closed { what: String, error: String },
    /// A reply that does not decode, or answers another request, in `protocol`.
    Frame {
        what: String,
        detail: String,
        protocol: &'static str,
    },
    /// A request the client refuses to build (a limit of the protocol); nothing was sent.
    Request { what: String, detail: String },
}

impl fmt::Display for TransportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TransportError::Connect { address, error } => {
                write!(f, "no connection to {address}: {error}")
            }
            TransportError::Timeout { what, waited, hint } => write!(
                f,
                "no reply to {what} within {} s; {hint}",
                waited.as_secs_f64()
            ),
            TransportError::Closed { what, error } => {
                write!(f, "the connection was lost during {what}: {error}")
            }
            TransportError::Frame {
                what,
                detail,
                protocol,
            } => write!(
                f,
                "the reply to {what} is not a valid {protocol} response: {detail}"
            ),
            TransportError::Request { what, detail } => write!(f, "{what}: {detail}"),
        }
    }
}

impl std::error::Error for TransportError {}

impl TransportError {
    /// A request the client refuses to build: nothing was sent.
    pub(crate) fn refused(what: impl Into<String>, detail: impl Display) -> Self {
        TransportError::Request {
            what: what.into(),
            detail: detail.to_string(),
        }
    }

    /// A reply (or part of one) in `protocol` that does not decode, or answers another request.
    pub(crate) fn garbled(
        what: impl Into<String>,
        detail: impl Display,
        protocol: &'static str,
    ) -> Self {
        TransportError::Frame {
            what: what.into(),
            detail: detail.to_string(),
            protocol,
        }
    }

    /// How a bench backend reports it.
    pub(crate) fn failure(&self) -> super::Failure {
        match self {
            TransportError::Connect { .. } => super::Failure::Unreachable,
            TransportError::Timeout { .. } => super::Failure::Timeout,
            TransportError::Closed { .. } => super::Failure::Lost,
            TransportError::Frame { .. } | TransportError::Request { .. } => {
                super::Failure::Protocol
            }
        }
    }

    /// A read may be sent again on a new connection after this: nothing came back whole.
    pub(crate) fn worth_retrying(&self) -> bool {
        matches!(
            self,
            TransportError::Timeout { .. } | TransportError::Closed { .. }
        )
    }
}

/// One exchange as a link's client describes it, for its errors.
pub(crate) struct Exchange<'a> {
    /// What the request does, as a capture shows it (`FC03 read of 4 registers at 0x0064`).
    pub what: &'a str,
    /// How long the whole reply may take.
    pub timeout: Duration,
    /// The protocol's name, for a reply that does not decode.
    pub protocol: &'static str,
    /// What the link's devices do when they stay silent.
    pub silence: &'static str,
}

impl Exchange<'_> {
    /// A reply (or part of one) that does not decode.
    pub(crate) fn frame(&self, detail: String) -> TransportError {
        TransportError::garbled(self.what, detail, self.protocol)
    }

    /// A request the client refuses to build.
    pub(crate) fn refused(&self, detail: impl Display) -> TransportError {
        TransportError::refused(self.what, detail)
    }
}

impl Connection {
    pub(crate) fn is_connected(&self) -> bool {
        self.stream.is_some()
    }

    /// Drops the connection; the next request makes a new one.
    pub(crate) fn disconnect(&mut self) {
        self.stream = None;
    }

    /// Sends `request` to `address`, connecting first when there is no connection, and reads
    /// its whole reply: `header` bytes, then up to the length `total` reads from them (or its
    /// refusal of a header that does not start like a reply, [`Exchange::frame`]). Drops the connection on any error:
    /// a late reply must never be read as the answer to the next request.
    pub(crate) fn exchange(
        &mut self,
        address: &str,
        connect_timeout: Duration,
        request: &[u8],
        exchange: &Exchange<'_>,
        header: usize,
        total: impl Fn(&[u8]) -> Result<usize, TransportError>,
    ) -> Result<Vec<u8>, TransportError> {
        let result = (|| {
            let deadline = Instant::now() + exchange.timeout;
            let what = exchange.what;
            let stream = match &mut self.stream {
                Some(stream) => stream,
                slot => {
                    let made =
                        connect(address, connect_timeout).map_err(|e| TransportError::Connect {
                            address: address.into(),
                            error: e.to_string(),
                        })?;
                    self.connections += 1;
                    slot.insert(made)
                }
            };
            self.requests += 1;
            stream
                .write_all(request)
                .map_err(|e| TransportError::Closed {
                    what: what.into(),
                    error: e.to_string(),
                })?;
            let short = |short| match short {
                Short::Timeout => TransportError::Timeout {
                    what: what.into(),
                    waited: exchange.timeout,
                    hint: exchange.silence,
                },
                Short::Closed(error) => TransportError::Closed {
                    what: what.into(),
                    error,
                },
            };
            let mut buf = vec![0u8; header];
            read_full(stream, &mut buf, deadline).map_err(short)?;
            let total = total(&buf)?;
            buf.resize(total.max(header), 0);
            read_full(stream, &mut buf[header..], deadline).map_err(short)?;
            Ok(buf)
        })();
        if result.is_err() {
            self.disconnect();
        }
        result
    }
}

/// A link's client, as every link keeps one: its settings, its one connection, and the number
/// of its last request (Modbus's transaction id, SLMP's serial), so that a reply answering
/// another request is caught. Each link adds its requests in an `impl` of its own settings'
/// client; what all links keep the same way is here once.
pub(crate) struct Client<S> {
    pub(in crate::backend) settings: S,
    pub(in crate::backend) connection: Connection,
    sequence: u16,
}

impl<S> Client<S> {
    /// A client that has not connected yet: nothing is opened until the first request.
    pub(crate) fn new(settings: S) -> Self {
        Client {
            settings,
            connection: Connection::default(),
            sequence: 0,
        }
    }

    pub(crate) fn settings(&self) -> &S {
        &self.settings
    }

    pub(crate) fn is_connected(&self) -> bool {
        self.connection.is_connected()
    }

    /// Drops the connection; the next request makes a new one.
    pub(crate) fn disconnect(&mut self) {
        self.connection.disconnect();
    }

    /// Requests sent, for a run's figures.
    pub(crate) fn requests(&self) -> u64 {
        self.connection.requests
    }

    /// Connections made, for a run's figures.
    pub(crate) fn connections(&self) -> u64 {
        self.connection.connections
    }

    /// The next request's number: one past the last, wrapping, the first being 1.
    pub(in crate::backend) fn next_sequence(&mut self) -> u16 {
        self.sequence = self.sequence.wrapping_add(1);
        self.sequence
    }
}

/// A link's own error: the transport's failure, in the ways every link shares, or the
/// protocol's refusal in a whole reply (an SLMP end code, a Modbus exception), which is an
/// answer: it keeps the connection and is never sent again.
pub(crate) trait ProtocolError: std::error::Error + Send + Sync + 'static {
    /// The transport's failure, where the transport failed.
    fn transport(&self) -> Option<&TransportError>;
}

/// Sends a read (`send`) again, on a new connection, after a timeout or a lost connection, up to
/// `retries` times with a growing pause, since reading twice changes nothing. Writes must not
/// come here: a write sent twice could land twice, or late.
pub(crate) fn retry_read<T, E: ProtocolError>(
    retries: u32,
    mut send: impl FnMut() -> Result<T, E>,
) -> Result<T, E> {
    let mut attempt = 0;
    loop {
        match send() {
            Err(e)
                if e.transport().is_some_and(TransportError::worth_retrying)
                    && attempt < retries =>
            {
                attempt += 1;
                std::thread::sleep(Duration::from_millis(20 * u64::from(attempt)));
            }
            other => return other,
        }
    }
}

/// Why a buffer was not filled.
#[derive(Debug)]
pub(crate) enum Short {
    /// The deadline passed first.
    Timeout,
    /// The connection ended or failed, as said.
    Closed(String),
}

/// Fills `buf` from the stream before `deadline`.
pub(crate) fn read_full(
    stream: &mut TcpStream,
    buf: &mut [u8],
    deadline: Instant,
) -> Result<(), Short> {
    let mut at = 0;
    while at < buf.len() {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(Short::Timeout);
        }
        let _ = stream.set_read_timeout(Some(left));
        match stream.read(&mut buf[at..]) {
            Ok(0) => {
                return Err(Short::Closed(format!(
                    "closed by the other side after {at} of {} bytes",
                    buf.len()
                )))
            }
            Ok(n) => at += n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Err(Short::Timeout)
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Short::Closed(e.to_string())),
        }
    }
    Ok(())
}

/// Bytes as the protocols' manuals print them: `50 00 00 FF`.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A reply's decoding error with the bytes received (the first 32), for the message.
pub(crate) fn received(error: &dyn Display, bytes: &[u8]) -> String {
    let shown = &bytes[..bytes.len().min(32)];
    let more = if bytes.len() > shown.len() {
        " ..."
    } else {
        ""
    };
    format!("{error}; received: {}{more}", hex(shown))
}
