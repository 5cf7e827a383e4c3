//! SLMP messages in binary code: 3E and 4E frames, requests and responses, both directions.
//!
//! The layout (MELSEC SLMP, as `docs/live-cpu.md` lays it out field by field): a subheader, the route (network, station, module I/O, multidrop), the data
//! length counted from the field after it, then for a request the monitoring timer, command and
//! subcommand, for a response the end code; every number little-endian. A 4E frame adds a serial
//! number after the subheader, the only way to match a reply to its request. The simulator
//! decodes what the client encodes, so both directions live here and are tested against bytes
//! written out by hand, not against each other only.

use std::fmt;

use crate::backend::bench::tcp::hex;

/// Which frame a message uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// 3E: no serial number.
    E3,
    /// 4E: a serial number the reply repeats.
    E4,
}

impl FrameKind {
    /// The bytes before the data length's end: subheader (+ serial area) and route and length.
    pub fn header_len(self) -> usize {
        match self {
            FrameKind::E3 => 9,
            FrameKind::E4 => 13,
        }
    }

    fn request_subheader(self) -> [u8; 2] {
        match self {
            FrameKind::E3 => [0x50, 0x00],
            FrameKind::E4 => [0x54, 0x00],
        }
    }

    fn response_subheader(self) -> [u8; 2] {
        match self {
            FrameKind::E3 => [0xD0, 0x00],
            FrameKind::E4 => [0xD4, 0x00],
        }
    }

    /// The frame a request's first byte announces.
    pub fn of_request(first: u8) -> Option<FrameKind> {
        match first {
            0x50 => Some(FrameKind::E3),
            0x54 => Some(FrameKind::E4),
            _ => None,
        }
    }
}

impl fmt::Display for FrameKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FrameKind::E3 => "3E",
            FrameKind::E4 => "4E",
        })
    }
}

/// How a device is named in a command: the Q-compatible form (subcommand 0000, number in 3
/// bytes, code in 1) or the iQ-R long form (subcommand 0002, number in 4 bytes, code in 2).
/// FX5 CPUs answer the long form with an error, so the form is chosen per family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceForm {
    Short,
    Long,
}

impl DeviceForm {
    /// The subcommand of word-unit device access in this form.
    pub fn word_subcommand(self) -> u16 {
        match self {
            DeviceForm::Short => 0x0000,
            DeviceForm::Long => 0x0002,
        }
    }

    fn of_subcommand(sub: u16) -> Option<DeviceForm> {
        match sub {
            0x0000 => Some(DeviceForm::Short),
            0x0002 => Some(DeviceForm::Long),
            _ => None,
        }
    }

    fn spec_len(self) -> usize {
        match self {
            DeviceForm::Short => 4,
            DeviceForm::Long => 6,
        }
    }
}

/// The route of a message: to the connected station itself unless configured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Route {
    pub network: u8,
    pub station: u8,
    pub module_io: u16,
    pub multidrop: u8,
}

impl Default for Route {
    /// Network 00, station FF, module I/O 03FF (the CPU), multidrop 00: the connected CPU.
    fn default() -> Self {
        Route {
            network: 0x00,
            station: 0xFF,
            module_io: 0x03FF,
            multidrop: 0x00,
        }
    }
}

/// The commands this client sends. Nothing else is encodable: remote RUN/STOP/RESET, latch
/// clear, file and password commands have no constructor here.
pub mod command {
    /// Read the CPU model name and code.
    pub const READ_TYPE_NAME: u16 = 0x0101;
    /// Batch read in word units.
    pub const READ: u16 = 0x0401;
    /// Random read in word units.
    pub const RANDOM_READ: u16 = 0x0403;
    /// Batch write in word units.
    pub const WRITE: u16 = 0x1401;
}

/// How a port codes its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Code {
    Binary,
    /// Every field as hexadecimal text (`super::ascii`).
    Ascii,
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Code::Binary => "binary",
            Code::Ascii => "ASCII",
        })
    }
}

/// Most words one batch read or write may carry (the SLMP limit for word units; one FX5U
/// measured the same: 960 accepted, 961 refused).
pub(crate) const MAX_BATCH_WORDS: usize = 960;
/// Most word points one random read may name.
pub(crate) const MAX_RANDOM_WORDS: usize = 192;
/// The longest message either side accepts: a batch of 960 words is under 2 KiB.
pub(crate) const MAX_MESSAGE: usize = 8192;

/// Device codes in binary code, by the letters the manuals write (the codes the common SLMP
/// libraries and servers use; `docs/live-cpu.md` lists them).
pub(crate) fn device_code(letters: &str) -> Option<u16> {
    Some(match letters {
        "SM" => 0x91,
        "SD" => 0xA9,
        "X" => 0x9C,
        "Y" => 0x9D,
        "M" => 0x90,
        "L" => 0x92,
        "F" => 0x93,
        "V" => 0x94,
        "B" => 0xA0,
        "SB" => 0xA1,
        "D" => 0xA8,
        "W" => 0xB4,
        "SW" => 0xB5,
        "R" => 0xAF,
        "ZR" => 0xB0,
        _ => return None,
    })
}

/// Every device [`device_code`] knows, by its letters.
pub(crate) const DEVICE_LETTERS: [&str; 15] = [
    "SM", "SD", "X", "Y", "M", "L", "F", "V", "B", "SB", "D", "W", "SW", "R", "ZR",
];

/// Whether MELSEC numbers a device in hexadecimal (`W1A`, `SW0F`): how ASCII code carries its
/// number, and how a manifest, a sandbox and a rung write it.
pub(crate) fn hex_numbered(letters: &str) -> bool {
    matches!(letters, "X" | "Y" | "B" | "SB" | "W" | "SW")
}

/// The letters of a device code (the inverse of [`device_code`]).
pub(crate) fn device_letters(code: u16) -> Option<&'static str> {
    DEVICE_LETTERS
        .into_iter()
        .find(|l| device_code(l) == Some(code))
}

/// One device as a command names it: code and number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct DeviceRef {
    pub code: u16,
    pub number: u32,
}

impl fmt::Display for DeviceRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match device_letters(self.code) {
            Some(l) => write!(f, "{l}{}", self.number),
            None => write!(f, "device code {:04X}H no. {}", self.code, self.number),
        }
    }
}

/// A message that does not decode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum FrameError {
    /// Fewer bytes than the header or the declared length needs.
    Short { need: usize, got: usize },
    /// A subheader that is not the expected one.
    Subheader { found: [u8; 2], expected: [u8; 2] },
    /// A declared length outside what either side sends.
    Length(usize),
    /// A body that does not fit its command.
    Body(String),
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Short { need, got } => {
                write!(f, "a message of {got} bytes where {need} are needed")
            }
            FrameError::Subheader { found, expected } => write!(
                f,
                "subheader {} where {} was expected",
                hex(found),
                hex(expected)
            ),
            FrameError::Length(n) => write!(
                f,
                "a declared data length of {n} bytes, over the {MAX_MESSAGE}-byte limit"
            ),
            FrameError::Body(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for FrameError {}

/// A request message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Request {
    pub frame: FrameKind,
    /// The serial number (4E only; 0 on 3E).
    pub serial: u16,
    pub route: Route,
    /// Monitoring timer in units of 250 ms; 0 waits forever.
    pub timer: u16,
    pub command: u16,
    pub subcommand: u16,
    pub data: Vec<u8>,
}

/// A response message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Response {
    pub frame: FrameKind,
    pub serial: u16,
    pub route: Route,
    /// 0 for normal completion; otherwise the error, and `data` holds the error information.
    pub end_code: u16,
    pub data: Vec<u8>,
}

/// One whole binary message, either way: the head, the data length, then the fixed words (a
/// request's timer, command and subcommand; a response's end code) and the data. Both ways
/// declare the same length, of the fixed words and the data together.
fn encode_message(
    subheader: [u8; 2],
    (frame, serial, route): (FrameKind, u16, Route),
    words: &[u16],
    data: &[u8],
) -> Vec<u8> {
    let length = 2 * words.len() + data.len();
    let mut out = Vec::with_capacity(frame.header_len() + length);
    out.extend_from_slice(&subheader);
    if frame == FrameKind::E4 {
        out.extend_from_slice(&serial.to_le_bytes());
        out.extend_from_slice(&[0, 0]);
    }
    out.push(route.network);
    out.push(route.station);
    out.extend_from_slice(&route.module_io.to_le_bytes());
    out.push(route.multidrop);
    out.extend_from_slice(&(length as u16).to_le_bytes());
    for word in words {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(data);
    out
}

fn u16_at(bytes: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([bytes[at], bytes[at + 1]])
}

/// Reads the head of a message: (serial, route, the declared length, where data starts).
fn take_head(
    bytes: &[u8],
    frame: FrameKind,
    subheader: [u8; 2],
) -> Result<(u16, Route, usize), FrameError> {
    let header = frame.header_len();
    // The subheader first: bytes that are not this frame at all say so, whatever their length.
    if let [a, b, ..] = *bytes {
        if [a, b] != subheader {
            return Err(FrameError::Subheader {
                found: [a, b],
                expected: subheader,
            });
        }
    }
    if bytes.len() < header {
        return Err(FrameError::Short {
            need: header,
            got: bytes.len(),
        });
    }
    let (serial, at) = match frame {
        FrameKind::E3 => (0, 2),
        FrameKind::E4 => (u16_at(bytes, 2), 6),
    };
    let route = Route {
        network: bytes[at],
        station: bytes[at + 1],
        module_io: u16_at(bytes, at + 2),
        multidrop: bytes[at + 4],
    };
    let length = usize::from(u16_at(bytes, at + 5));
    if length > MAX_MESSAGE {
        return Err(FrameError::Length(length));
    }
    if bytes.len() < header + length {
        return Err(FrameError::Short {
            need: header + length,
            got: bytes.len(),
        });
    }
    Ok((serial, route, length))
}

/// The whole length of a message, once its header is in: what a reader waits for, since a
/// reply may arrive in several TCP segments.
pub(crate) fn message_len(frame: FrameKind, header: &[u8]) -> Result<usize, FrameError> {
    let need = frame.header_len();
    if header.len() < need {
        return Err(FrameError::Short {
            need,
            got: header.len(),
        });
    }
    let length = usize::from(u16_at(header, need - 2));
    if length > MAX_MESSAGE {
        return Err(FrameError::Length(length));
    }
    Ok(need + length)
}

impl Request {
    pub(crate) fn encode(&self) -> Vec<u8> {
        encode_message(
            self.frame.request_subheader(),
            (self.frame, self.serial, self.route),
            &[self.timer, self.command, self.subcommand],
            &self.data,
        )
    }

    /// Decodes one whole request; the frame is read from its subheader.
    pub(crate) fn decode(bytes: &[u8]) -> Result<Request, FrameError> {
        let first = bytes
            .first()
            .copied()
            .ok_or(FrameError::Short { need: 1, got: 0 })?;
        let frame = FrameKind::of_request(first).ok_or(FrameError::Subheader {
            found: [first, bytes.get(1).copied().unwrap_or(0)],
            expected: [0x50, 0x00],
        })?;
        let (serial, route, length) = take_head(bytes, frame, frame.request_subheader())?;
        if length < 6 {
            return Err(FrameError::Body(format!(
                "a request data length of {length}, under the 6 bytes of timer, command and \
                 subcommand"
            )));
        }
        let at = frame.header_len();
        Ok(Request {
            frame,
            serial,
            route,
            timer: u16_at(bytes, at),
            command: u16_at(bytes, at + 2),
            subcommand: u16_at(bytes, at + 4),
            data: bytes[at + 6..at + length].to_vec(),
        })
    }
}

impl Response {
    pub(crate) fn encode(&self) -> Vec<u8> {
        encode_message(
            self.frame.response_subheader(),
            (self.frame, self.serial, self.route),
            &[self.end_code],
            &self.data,
        )
    }

    /// Decodes one whole response of the expected frame.
    pub(crate) fn decode(frame: FrameKind, bytes: &[u8]) -> Result<Response, FrameError> {
        let (serial, route, length) = take_head(bytes, frame, frame.response_subheader())?;
        if length < 2 {
            return Err(FrameError::Body(format!(
                "a response data length of {length}, under the 2 bytes of the end code"
            )));
        }
        let at = frame.header_len();
        Ok(Response {
            frame,
            serial,
            route,
            end_code: u16_at(bytes, at),
            data: bytes[at + 2..at + length].to_vec(),
        })
    }
}

/// The command, subcommand and data of a request, before framing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Body {
    pub command: u16,
    pub subcommand: u16,
    pub data: Vec<u8>,
}

fn put_device(out: &mut Vec<u8>, form: DeviceForm, device: DeviceRef) -> Result<(), FrameError> {
    match form {
        DeviceForm::Short => {
            if device.number > 0xFF_FFFF {
                return Err(FrameError::Body(format!(
                    "{device}: the number does not fit the 3 bytes of the Q-compatible form"
                )));
            }
            let code = u8::try_from(device.code).map_err(|_| {
                FrameError::Body(format!(
                    "{device}: the code does not fit the 1 byte of the Q-compatible form"
                ))
            })?;
            out.extend_from_slice(&device.number.to_le_bytes()[..3]);
            out.push(code);
        }
        DeviceForm::Long => {
            out.extend_from_slice(&device.number.to_le_bytes());
            out.extend_from_slice(&device.code.to_le_bytes());
        }
    }
    Ok(())
}

fn take_device(data: &[u8], form: DeviceForm) -> Option<DeviceRef> {
    match form {
        DeviceForm::Short => (data.len() >= 4).then(|| DeviceRef {
            number: u32::from_le_bytes([data[0], data[1], data[2], 0]),
            code: u16::from(data[3]),
        }),
        DeviceForm::Long => (data.len() >= 6).then(|| DeviceRef {
            number: u32::from_le_bytes([data[0], data[1], data[2], data[3]]),
            code: u16_at(data, 4),
        }),
    }
}

fn points(count: usize, limit: usize, what: &str) -> Result<u16, FrameError> {
    if count == 0 || count > limit {
        return Err(FrameError::Body(format!(
            "{count} points in one {what}; give 1 to {limit}"
        )));
    }
    Ok(count as u16)
}

/// 0401: read `count` words from `head`.
pub(crate) fn read_words(
    form: DeviceForm,
    head: DeviceRef,
    count: usize,
) -> Result<Body, FrameError> {
    let mut data = Vec::with_capacity(8);
    put_device(&mut data, form, head)?;
    data.extend_from_slice(&points(count, MAX_BATCH_WORDS, "batch read")?.to_le_bytes());
    Ok(Body {
        command: command::READ,
        subcommand: form.word_subcommand(),
        data,
    })
}

/// 1401: write `words` from `head`. Only the client's write of a fenced write calls this.
pub(super) fn write_words(
    form: DeviceForm,
    head: DeviceRef,
    words: &[u16],
) -> Result<Body, FrameError> {
    let mut data = Vec::with_capacity(8 + 2 * words.len());
    put_device(&mut data, form, head)?;
    data.extend_from_slice(&points(words.len(), MAX_BATCH_WORDS, "batch write")?.to_le_bytes());
    for w in words {
        data.extend_from_slice(&w.to_le_bytes());
    }
    Ok(Body {
        command: command::WRITE,
        subcommand: form.word_subcommand(),
        data,
    })
}

/// 0403: read single words from several places in one request.
pub(crate) fn random_read(form: DeviceForm, devices: &[DeviceRef]) -> Result<Body, FrameError> {
    let n = points(devices.len(), MAX_RANDOM_WORDS, "random read")?;
    let mut data = Vec::with_capacity(2 + form.spec_len() * devices.len());
    data.push(n as u8);
    data.push(0);
    for d in devices {
        put_device(&mut data, form, *d)?;
    }
    Ok(Body {
        command: command::RANDOM_READ,
        subcommand: form.word_subcommand(),
        data,
    })
}

/// 0101: read the CPU's type name.
pub(crate) fn read_type_name() -> Body {
    Body {
        command: command::READ_TYPE_NAME,
        subcommand: 0x0000,
        data: Vec::new(),
    }
}

/// Words from the data of a read's response.
pub(crate) fn words_of(data: &[u8], count: usize) -> Result<Vec<u16>, FrameError> {
    if data.len() != 2 * count {
        return Err(FrameError::Body(format!(
            "{} bytes of data where {count} words ({} bytes) were asked for",
            data.len(),
            2 * count
        )));
    }
    Ok(data.chunks_exact(2).map(|c| u16_at(c, 0)).collect())
}

/// The answer to 0101.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TypeName {
    /// The model name, trailing spaces removed (`FX5U-32MT/DS`).
    pub name: String,
    /// The model code.
    pub code: u16,
}

impl fmt::Display for TypeName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({:04X}H)", self.name, self.code)
    }
}

/// Reads a 0101 response: 16 characters of model name, space-padded, then the model code.
pub(crate) fn type_name_of(data: &[u8]) -> Result<TypeName, FrameError> {
    if data.len() != 18 {
        return Err(FrameError::Body(format!(
            "a type name answer of {} bytes where 18 (16 characters and a code) were expected",
            data.len()
        )));
    }
    let name: String = data[..16]
        .iter()
        .map(|b| {
            if b.is_ascii_graphic() || *b == b' ' {
                *b as char
            } else {
                '?'
            }
        })
        .collect();
    Ok(TypeName {
        name: name.trim_end().to_string(),
        code: u16_at(data, 16),
    })
}

/// The data of a 0101 response (the simulator's side).
pub(crate) fn type_name_data(name: &str, code: u16) -> Vec<u8> {
    let mut out: Vec<u8> = name.bytes().take(16).collect();
    out.resize(16, b' ');
    out.extend_from_slice(&code.to_le_bytes());
    out
}

/// A request's body as the server reads it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Decoded {
    TypeName,
    Read {
        head: DeviceRef,
        count: usize,
    },
    Write {
        head: DeviceRef,
        words: Vec<u16>,
    },
    RandomRead {
        devices: Vec<DeviceRef>,
    },
    /// A command this client never sends: the server answers it with an error.
    Other {
        command: u16,
        subcommand: u16,
    },
}

/// Reads a request's command (the simulator's side). A body that does not fit its command is an
/// error; a command outside this client's set is [`Decoded::Other`].
pub(crate) fn decode_body(request: &Request) -> Result<Decoded, FrameError> {
    let bad = |what: &str| {
        FrameError::Body(format!(
            "command {:04X}H subcommand {:04X}H: {what}",
            request.command, request.subcommand
        ))
    };
    let data = &request.data;
    match request.command {
        command::READ_TYPE_NAME if request.subcommand == 0 && data.is_empty() => {
            Ok(Decoded::TypeName)
        }
        command::READ | command::WRITE | command::RANDOM_READ => {
            let Some(form) = DeviceForm::of_subcommand(request.subcommand) else {
                return Ok(Decoded::Other {
                    command: request.command,
                    subcommand: request.subcommand,
                });
            };
            let spec = form.spec_len();
            if request.command == command::RANDOM_READ {
                let (n, dwords) = match data.as_slice() {
                    [n, d, ..] => (usize::from(*n), *d),
                    _ => return Err(bad("no point counts")),
                };
                if dwords != 0 {
                    return Err(bad("double-word points are not served"));
                }
                if data.len() != 2 + n * spec {
                    return Err(bad("the data length does not match the point count"));
                }
                let devices = (0..n)
                    .filter_map(|i| take_device(&data[2 + i * spec..], form))
                    .collect();
                return Ok(Decoded::RandomRead { devices });
            }
            let head = take_device(data, form).ok_or_else(|| bad("no device"))?;
            let count = data
                .get(spec..spec + 2)
                .map(|c| usize::from(u16_at(c, 0)))
                .ok_or_else(|| bad("no point count"))?;
            if request.command == command::READ {
                if data.len() != spec + 2 {
                    return Err(bad("data after the point count"));
                }
                return Ok(Decoded::Read { head, count });
            }
            let words = &data[spec + 2..];
            if words.len() != 2 * count {
                return Err(bad("the written words do not match the point count"));
            }
            Ok(Decoded::Write {
                head,
                words: words.chunks_exact(2).map(|c| u16_at(c, 0)).collect(),
            })
        }
        _ => Ok(Decoded::Other {
            command: request.command,
            subcommand: request.subcommand,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn bytes(text: &str) -> Vec<u8> {
        text.split_whitespace()
            .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
            .collect()
    }

    const D: u16 = 0xA8;

    fn d(number: u32) -> DeviceRef {
        DeviceRef { code: D, number }
    }

    /// Request data of the commands, byte for byte, written out by hand from the field layout
    /// (command and subcommand little-endian, device number in 3 bytes then the code A8H for D in
    /// the Q-compatible form, 4 bytes then 2 in the long form, then the point count).
    #[rstest]
    #[case::read_d100_x3(
        read_words(DeviceForm::Short, d(100), 3),
        "01 04 00 00 64 00 00 A8 03 00"
    )]
    #[case::long_form(
        read_words(DeviceForm::Long, d(100), 3),
        "01 04 02 00 64 00 00 00 A8 00 03 00"
    )]
    #[case::sd203(read_words(DeviceForm::Short, DeviceRef { code: 0xA9, number: 203 }, 1), "01 04 00 00 CB 00 00 A9 01 00")]
    #[case::write_two(write_words(DeviceForm::Short, d(12010), &[0x0003, 0x0102]), "01 14 00 00 EA 2E 00 A8 02 00 03 00 02 01")]
    #[case::random(random_read(DeviceForm::Short, &[d(12009), DeviceRef { code: 0xA9, number: 203 }]), "03 04 00 00 02 00 E9 2E 00 A8 CB 00 00 A9")]
    #[case::type_name(Ok(read_type_name()), "01 01 00 00")]
    fn bodies(#[case] body: Result<Body, FrameError>, #[case] expected: &str) {
        let body = body.expect("encodes");
        let mut got = body.command.to_le_bytes().to_vec();
        got.extend_from_slice(&body.subcommand.to_le_bytes());
        got.extend_from_slice(&body.data);
        assert_eq!(hex(&got), hex(&bytes(expected)));
    }

    /// Whole messages: the 3E request header of the design notes (`50 00`, network 00, station
    /// FF, module 03FF, multidrop 00, length from the timer on), a 4E request with serial 1234H,
    /// and the responses (`D0 00` / `D4 00` + serial, end code).
    #[rstest]
    #[case::request_3e(
        FrameKind::E3,
        0,
        "50 00 00 FF FF 03 00 0C 00 08 00 01 04 00 00 64 00 00 A8 03 00"
    )]
    #[case::request_4e(
        FrameKind::E4,
        0x1234,
        "54 00 34 12 00 00 00 FF FF 03 00 0C 00 08 00 01 04 00 00 64 00 00 A8 03 00"
    )]
    fn requests(#[case] frame: FrameKind, #[case] serial: u16, #[case] expected: &str) {
        let body = read_words(DeviceForm::Short, d(100), 3).expect("body");
        let request = Request {
            frame,
            serial,
            route: Route::default(),
            timer: 8,
            command: body.command,
            subcommand: body.subcommand,
            data: body.data,
        };
        let encoded = request.encode();
        assert_eq!(hex(&encoded), hex(&bytes(expected)));
        assert_eq!(Request::decode(&encoded), Ok(request));
        assert_eq!(
            message_len(frame, &encoded[..frame.header_len()]),
            Ok(encoded.len())
        );
    }

    #[rstest]
    #[case::ok_3e(FrameKind::E3, 0, 0, "41 35", "D0 00 00 FF FF 03 00 04 00 00 00 41 35")]
    #[case::ok_4e(
        FrameKind::E4,
        0x1234,
        0,
        "41 35",
        "D4 00 34 12 00 00 00 FF FF 03 00 04 00 00 00 41 35"
    )]
    #[case::error_3e(
        FrameKind::E3,
        0,
        0xC056,
        "00 FF FF 03 00 01 04 00 00",
        "D0 00 00 FF FF 03 00 0B 00 56 C0 00 FF FF 03 00 01 04 00 00"
    )]
    fn responses(
        #[case] frame: FrameKind,
        #[case] serial: u16,
        #[case] end_code: u16,
        #[case] data: &str,
        #[case] expected: &str,
    ) {
        let response = Response {
            frame,
            serial,
            route: Route::default(),
            end_code,
            data: bytes(data),
        };
        let encoded = response.encode();
        assert_eq!(hex(&encoded), hex(&bytes(expected)));
        assert_eq!(Response::decode(frame, &encoded), Ok(response));
    }

    /// The FX5U answer recorded in the design notes: `FX5U-32MT/DS` padded to 16 characters,
    /// model code 4A49H.
    #[test]
    fn type_name_round_trip() {
        let data = type_name_data("FX5U-32MT/DS", 0x4A49);
        assert_eq!(
            hex(&data),
            "46 58 35 55 2D 33 32 4D 54 2F 44 53 20 20 20 20 49 4A"
        );
        let t = type_name_of(&data).expect("decodes");
        assert_eq!(t.name, "FX5U-32MT/DS");
        assert_eq!(t.to_string(), "FX5U-32MT/DS (4A49H)");
        assert!(type_name_of(&data[..17]).is_err());
    }

    #[rstest]
    #[case::short_header("50 00 00", "a message of 3 bytes where 9 are needed")]
    #[case::garbage(
        "47 45 54 20 2F 20 48 54 54 50",
        "subheader 47 45 where 50 00 was expected"
    )]
    #[case::length_past_end(
        "50 00 00 FF FF 03 00 0C 00 08 00",
        "a message of 11 bytes where 21 are needed"
    )]
    #[case::length_too_small("50 00 00 FF FF 03 00 02 00 08 00", "under the 6 bytes")]
    fn bad_requests(#[case] input: &str, #[case] message: &str) {
        let e = Request::decode(&bytes(input)).expect_err("does not decode");
        assert!(e.to_string().contains(message), "{e}");
    }

    #[test]
    fn a_response_of_the_other_frame_is_refused() {
        let r = Response {
            frame: FrameKind::E3,
            serial: 0,
            route: Route::default(),
            end_code: 0,
            data: vec![],
        };
        let e = Response::decode(FrameKind::E4, &r.encode()).expect_err("3E is not 4E");
        assert!(e.to_string().contains("subheader D0 00 where D4 00"), "{e}");
    }

    #[test]
    fn limits_are_refused_before_encoding() {
        assert!(read_words(DeviceForm::Short, d(0), 961).is_err());
        assert!(read_words(DeviceForm::Short, d(0), 0).is_err());
        assert!(read_words(DeviceForm::Short, d(0x0100_0000), 1).is_err());
        assert!(read_words(DeviceForm::Long, d(0x0100_0000), 1).is_ok());
        assert!(random_read(DeviceForm::Short, &[d(0); 193]).is_err());
    }

    #[test]
    fn bodies_decode_as_encoded() {
        let wrap = |b: Body| Request {
            frame: FrameKind::E3,
            serial: 0,
            route: Route::default(),
            timer: 0,
            command: b.command,
            subcommand: b.subcommand,
            data: b.data,
        };
        for form in [DeviceForm::Short, DeviceForm::Long] {
            let r = wrap(read_words(form, d(18431), 1).expect("read"));
            assert_eq!(
                decode_body(&r),
                Ok(Decoded::Read {
                    head: d(18431),
                    count: 1
                })
            );
            let r = wrap(write_words(form, d(7), &[1, 2, 3]).expect("write"));
            assert_eq!(
                decode_body(&r),
                Ok(Decoded::Write {
                    head: d(7),
                    words: vec![1, 2, 3]
                })
            );
            let r = wrap(random_read(form, &[d(1), d(2)]).expect("random"));
            assert_eq!(
                decode_body(&r),
                Ok(Decoded::RandomRead {
                    devices: vec![d(1), d(2)]
                })
            );
        }
        let run = Request {
            command: 0x1001,
            ..wrap(read_type_name())
        };
        assert_eq!(
            decode_body(&run),
            Ok(Decoded::Other {
                command: 0x1001,
                subcommand: 0
            })
        );
    }

    proptest::proptest! {
        #[test]
        fn any_request_round_trips(
            e4 in proptest::bool::ANY,
            serial in 0u16..,
            timer in 0u16..,
            command in 0u16..,
            subcommand in 0u16..,
            data in proptest::collection::vec(0u8.., 0..64),
        ) {
            let frame = if e4 { FrameKind::E4 } else { FrameKind::E3 };
            let r = Request { frame, serial: if e4 { serial } else { 0 }, route: Route::default(), timer, command, subcommand, data };
            proptest::prop_assert_eq!(Request::decode(&r.encode()), Ok(r));
        }

        #[test]
        fn any_response_round_trips(
            e4 in proptest::bool::ANY,
            serial in 0u16..,
            end_code in 0u16..,
            data in proptest::collection::vec(0u8.., 0..64),
        ) {
            let frame = if e4 { FrameKind::E4 } else { FrameKind::E3 };
            let r = Response { frame, serial: if e4 { serial } else { 0 }, route: Route::default(), end_code, data };
            proptest::prop_assert_eq!(Response::decode(frame, &r.encode()), Ok(r));
        }

        #[test]
        fn garbage_never_panics(data in proptest::collection::vec(0u8.., 0..40)) {
            let _ = Request::decode(&data);
            let _ = Response::decode(FrameKind::E3, &data);
            let _ = Response::decode(FrameKind::E4, &data);
        }
    }
}
