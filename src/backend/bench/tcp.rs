//! TCP as every link's client uses it: one connection tried on each address a host resolves
//! to, within a time limit and without Nagle's delay (a request is one small write, which Nagle
//! would hold back waiting for an acknowledgement); and a reply read whole by a deadline, since
//! a reply may arrive in several segments and must never be read past.

use std::fmt::Display;
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

/// Why a request was not sent: no connection could be made, or the write failed.
#[derive(Debug)]
pub(crate) enum Unsent {
    Connect(std::io::Error),
    Write(std::io::Error),
}

impl Connection {
    pub(crate) fn is_connected(&self) -> bool {
        self.stream.is_some()
    }

    /// Drops the connection; the next request makes a new one.
    pub(crate) fn disconnect(&mut self) {
        self.stream = None;
    }

    /// Sends `request` to `address`, connecting first when there is no connection; the stream
    /// to read its reply from.
    pub(crate) fn send(
        &mut self,
        address: &str,
        connect_timeout: Duration,
        request: &[u8],
    ) -> Result<&mut TcpStream, Unsent> {
        let stream = match &mut self.stream {
            Some(stream) => stream,
            slot => {
                let made = connect(address, connect_timeout).map_err(Unsent::Connect)?;
                self.connections += 1;
                slot.insert(made)
            }
        };
        self.requests += 1;
        stream.write_all(request).map_err(Unsent::Write)?;
        Ok(stream)
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
