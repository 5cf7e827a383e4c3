//! SLMP messages in ASCII code, for CPU ports configured that way.
//!
//! ASCII code carries the binary message's fields as hexadecimal text, most significant digit
//! first: a field of n bytes becomes 2n characters (`0401` for command 0401H, where binary code
//! sends `01 04`), and the data length counts characters. Two fields differ in kind: a device is
//! named by its letters padded with `*` (`D*` in the Q-compatible form, `D***` in the long form)
//! and its number in 6 (8) digits, decimal for decimal-numbered devices (D, SD, R, ...) and
//! hexadecimal for hexadecimal-numbered ones (X, Y, B, SB, W, SW); and the type name of 0101 travels as
//! its 16 characters. Every word of data is 4 characters.
//!
//! The binary [`Request`] and [`Response`] stay the one model of a message: a request is
//! rendered from it, and a response is read into it, with its data in binary layout, so the
//! client's readers of words and type names serve both codes.

use super::frame::{
    command, device_code, device_letters, hex_numbered, DeviceForm, FrameError, FrameKind, Request,
    Response, Route, MAX_MESSAGE,
};

/// Characters before the end of the length field: subheader, (serial and reserved area), route
/// and length.
pub(crate) fn header_len(frame: FrameKind) -> usize {
    match frame {
        FrameKind::E3 => 18,
        FrameKind::E4 => 26,
    }
}

fn hex_field(out: &mut Vec<u8>, value: u32, bytes: usize) {
    out.extend_from_slice(format!("{value:0width$X}", width = 2 * bytes).as_bytes());
}

fn number_at(text: &[u8], at: usize, chars: usize) -> Result<u32, FrameError> {
    let field = text.get(at..at + chars).ok_or(FrameError::Short {
        need: at + chars,
        got: text.len(),
    })?;
    std::str::from_utf8(field)
        .ok()
        .filter(|s| s.bytes().all(|b| b.is_ascii_hexdigit()))
        .and_then(|s| u32::from_str_radix(s, 16).ok())
        .ok_or_else(|| {
            FrameError::Body(format!(
                "`{}` at character {at} is not a hexadecimal field",
                String::from_utf8_lossy(field)
            ))
        })
}

fn u16_le(data: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*data.get(at)?, *data.get(at + 1)?]))
}

/// One device spec of a binary body, rendered in ASCII; returns the binary bytes it took.
fn device(out: &mut Vec<u8>, form: DeviceForm, data: &[u8]) -> Result<usize, FrameError> {
    let (number, code, taken, letters_width, digits) = match form {
        DeviceForm::Short => {
            let d = data
                .get(..4)
                .ok_or_else(|| FrameError::Body("a device spec is cut short".into()))?;
            (
                u32::from_le_bytes([d[0], d[1], d[2], 0]),
                u16::from(d[3]),
                4,
                2,
                6,
            )
        }
        DeviceForm::Long => {
            let d = data
                .get(..6)
                .ok_or_else(|| FrameError::Body("a device spec is cut short".into()))?;
            (
                u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
                u16::from_le_bytes([d[4], d[5]]),
                6,
                4,
                8,
            )
        }
    };
    let letters = device_letters(code)
        .ok_or_else(|| FrameError::Body(format!("device code {code:04X}H has no letters")))?;
    out.extend_from_slice(format!("{letters:*<letters_width$}").as_bytes());
    let number = if hex_numbered(letters) {
        format!("{number:0digits$X}")
    } else {
        format!("{number:0digits$}")
    };
    if number.len() != digits {
        return Err(FrameError::Body(format!(
            "{letters}{number} does not fit {digits} digits"
        )));
    }
    out.extend_from_slice(number.as_bytes());
    Ok(taken)
}

/// The ASCII rendering of a request built for binary code (0101, 0401, 0403 or 1401).
pub(crate) fn encode_request(request: &Request) -> Result<Vec<u8>, FrameError> {
    let data = &request.data;
    let form = match request.subcommand {
        0x0000 => DeviceForm::Short,
        0x0002 => DeviceForm::Long,
        other => {
            return Err(FrameError::Body(format!(
                "subcommand {other:04X}H has no ASCII rendering here"
            )))
        }
    };
    let cut = || FrameError::Body("the request data is cut short".into());
    let mut body = Vec::new();
    hex_field(&mut body, u32::from(request.timer), 2);
    hex_field(&mut body, u32::from(request.command), 2);
    hex_field(&mut body, u32::from(request.subcommand), 2);
    match request.command {
        command::READ_TYPE_NAME => {}
        command::READ | command::WRITE => {
            let at = device(&mut body, form, data)?;
            let points = u16_le(data, at).ok_or_else(cut)?;
            hex_field(&mut body, u32::from(points), 2);
            let words = &data[at + 2..];
            if request.command == command::WRITE {
                if words.len() != 2 * usize::from(points) {
                    return Err(FrameError::Body(
                        "the written words do not match the point count".into(),
                    ));
                }
                for w in words.chunks_exact(2) {
                    hex_field(&mut body, u32::from(u16::from_le_bytes([w[0], w[1]])), 2);
                }
            }
        }
        command::RANDOM_READ => {
            let (&words, &dwords) = (data.first().ok_or_else(cut)?, data.get(1).ok_or_else(cut)?);
            hex_field(&mut body, u32::from(words), 1);
            hex_field(&mut body, u32::from(dwords), 1);
            let mut at = 2;
            for _ in 0..usize::from(words) + usize::from(dwords) {
                at += device(&mut body, form, data.get(at..).ok_or_else(cut)?)?;
            }
        }
        other => {
            return Err(FrameError::Body(format!(
                "command {other:04X}H has no ASCII rendering here"
            )))
        }
    }
    Ok(message(
        request.frame,
        [b"5000", b"5400"],
        request.serial,
        request.route,
        &body,
    ))
}

/// A whole message: the subheader of its frame (`subheaders`: the 3E one, the 4E one, which the
/// serial follows), the route, the length of the body in characters, and the body.
fn message(
    frame: FrameKind,
    subheaders: [&[u8; 4]; 2],
    serial: u16,
    r: Route,
    body: &[u8],
) -> Vec<u8> {
    let mut out = Vec::with_capacity(header_len(frame) + body.len());
    match frame {
        FrameKind::E3 => out.extend_from_slice(subheaders[0]),
        FrameKind::E4 => {
            out.extend_from_slice(subheaders[1]);
            hex_field(&mut out, u32::from(serial), 2);
            out.extend_from_slice(b"0000");
        }
    }
    route(&mut out, r);
    hex_field(&mut out, body.len() as u32, 2);
    out.extend_from_slice(body);
    out
}

fn route(out: &mut Vec<u8>, r: Route) {
    hex_field(out, u32::from(r.network), 1);
    hex_field(out, u32::from(r.station), 1);
    hex_field(out, u32::from(r.module_io), 2);
    hex_field(out, u32::from(r.multidrop), 1);
}

/// The whole length of an ASCII response, once its header is in.
pub(crate) fn message_len(frame: FrameKind, header: &[u8]) -> Result<usize, FrameError> {
    let need = header_len(frame);
    if header.len() < need {
        return Err(FrameError::Short {
            need,
            got: header.len(),
        });
    }
    let length = number_at(header, need - 4, 4)? as usize;
    if length > 2 * MAX_MESSAGE {
        return Err(FrameError::Length(length));
    }
    Ok(need + length)
}

/// Reads an ASCII response to a request with `command` into the binary model: the data of a
/// normal completion in binary layout (words little-endian, a type name as its 16 characters
/// and the model code); error information is dropped.
pub(crate) fn decode_response(
    frame: FrameKind,
    command_code: u16,
    bytes: &[u8],
) -> Result<Response, FrameError> {
    let expected: &[u8] = match frame {
        FrameKind::E3 => b"D000",
        FrameKind::E4 => b"D400",
    };
    if bytes.len() >= 4 && &bytes[..4] != expected {
        return Err(FrameError::Body(format!(
            "subheader `{}` where `{}` was expected",
            String::from_utf8_lossy(&bytes[..4]),
            String::from_utf8_lossy(expected)
        )));
    }
    let total = message_len(frame, bytes)?;
    if bytes.len() < total {
        return Err(FrameError::Short {
            need: total,
            got: bytes.len(),
        });
    }
    let (serial, at) = match frame {
        FrameKind::E3 => (0, 4),
        FrameKind::E4 => (number_at(bytes, 4, 4)? as u16, 12),
    };
    let route = Route {
        network: number_at(bytes, at, 2)? as u8,
        station: number_at(bytes, at + 2, 2)? as u8,
        module_io: number_at(bytes, at + 4, 4)? as u16,
        multidrop: number_at(bytes, at + 8, 2)? as u8,
    };
    let start = header_len(frame);
    if total < start + 4 {
        return Err(FrameError::Body(
            "a response shorter than its end code".into(),
        ));
    }
    let end_code = number_at(bytes, start, 4)? as u16;
    let text = &bytes[start + 4..total];
    let mut data = Vec::new();
    if end_code == 0 {
        if command_code == command::READ_TYPE_NAME {
            let name = text.get(..16).ok_or(FrameError::Short {
                need: 20,
                got: text.len(),
            })?;
            data.extend_from_slice(name);
            data.extend_from_slice(&(number_at(text, 16, 4)? as u16).to_le_bytes());
        } else {
            if text.len() % 4 != 0 {
                return Err(FrameError::Body(format!(
                    "{} characters of data, not whole words of 4",
                    text.len()
                )));
            }
            for i in (0..text.len()).step_by(4) {
                data.extend_from_slice(&(number_at(text, i, 4)? as u16).to_le_bytes());
            }
        }
    }
    Ok(Response {
        frame,
        serial,
        route,
        end_code,
        data,
    })
}

/// Why an ASCII request is not carried out, as the end code its answer carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// ASCII that cannot be converted to binary: end code C050H from a CPU's built-in Ethernet
    /// port (qnu-ethernet p.62, `mc-ascii/M4`).
    NotConvertible,
    /// A command or subcommand this port does not read in ASCII: C059H.
    Unsupported,
}

impl Refusal {
    pub(crate) fn end_code(self) -> u16 {
        match self {
            Refusal::NotConvertible => 0xC050,
            Refusal::Unsupported => 0xC059,
        }
    }
}

/// A field of hex digits read as the manual writes them: 0-9 and the capitals A-F only
/// (`mc-ascii/M1`, `M4`); anything else cannot be converted.
fn strict_at(text: &[u8], at: usize, chars: usize) -> Result<u32, Refusal> {
    let field = text.get(at..at + chars).ok_or(Refusal::NotConvertible)?;
    field.iter().try_fold(0u32, |v, c| {
        let digit = match c {
            b'0'..=b'9' => c - b'0',
            b'A'..=b'F' => c - b'A' + 10,
            _ => return Err(Refusal::NotConvertible),
        };
        Ok(v << 4 | u32::from(digit))
    })
}

/// A device number: its digits in the device's radix, a leading blank standing for 0
/// (`mc-ascii/M11`, mcp p.69: "The '0' in the upper digits can also be specified with a space").
fn device_number(text: &[u8], at: usize, chars: usize, hex: bool) -> Result<u32, Refusal> {
    let field = text.get(at..at + chars).ok_or(Refusal::NotConvertible)?;
    let leading = field.iter().take_while(|c| **c == b' ').count();
    let digits: Vec<u8> = (field.iter().enumerate())
        .map(|(i, c)| if i < leading { b'0' } else { *c })
        .collect();
    if hex {
        return strict_at(&digits, 0, chars);
    }
    digits.iter().try_fold(0u32, |v, c| match c {
        b'0'..=b'9' => Ok(v * 10 + u32::from(c - b'0')),
        _ => Err(Refusal::NotConvertible),
    })
}

/// Reads a request in ASCII code, strictly, into the binary model: its route (for the answer,
/// read as far as it converts), and the request or why it is refused. Reads 0101 and 0401, in
/// 3E and 4E frames.
pub(crate) fn decode_request(bytes: &[u8]) -> (FrameKind, u16, Route, Result<Request, Refusal>) {
    let (frame, serial, at) = match bytes.get(..4) {
        Some(b"5400") => (
            FrameKind::E4,
            strict_at(bytes, 4, 4).unwrap_or(0) as u16,
            12,
        ),
        _ => (FrameKind::E3, 0, 4),
    };
    let route = (|| {
        Ok::<_, Refusal>(Route {
            network: strict_at(bytes, at, 2)? as u8,
            station: strict_at(bytes, at + 2, 2)? as u8,
            module_io: strict_at(bytes, at + 4, 4)? as u16,
            multidrop: strict_at(bytes, at + 8, 2)? as u8,
        })
    })();
    let request = route.and_then(|route| {
        let body = header_len(frame);
        let timer = strict_at(bytes, body, 4)? as u16;
        let command_code = strict_at(bytes, body + 4, 4)? as u16;
        let subcommand = strict_at(bytes, body + 8, 4)? as u16;
        let mut data = Vec::new();
        match (command_code, subcommand) {
            (command::READ_TYPE_NAME, 0) => {}
            (command::READ, 0x0000 | 0x0002) => {
                let long = subcommand == 0x0002;
                let (letters_width, digits) = if long { (4, 8) } else { (2, 6) };
                let at = body + 12;
                let letters = bytes
                    .get(at..at + letters_width)
                    .ok_or(Refusal::NotConvertible)?;
                let letters = std::str::from_utf8(letters)
                    .map_err(|_| Refusal::NotConvertible)?
                    .trim_end_matches(['*', ' ']);
                let code = device_code(letters).ok_or(Refusal::NotConvertible)?;
                let number =
                    device_number(bytes, at + letters_width, digits, hex_numbered(letters))?;
                let points = strict_at(bytes, at + letters_width + digits, 4)? as u16;
                if long {
                    data.extend_from_slice(&number.to_le_bytes());
                    data.extend_from_slice(&code.to_le_bytes());
                } else {
                    data.extend_from_slice(&number.to_le_bytes()[..3]);
                    data.push(code as u8);
                }
                data.extend_from_slice(&points.to_le_bytes());
            }
            _ => return Err(Refusal::Unsupported),
        }
        Ok(Request {
            frame,
            serial,
            route,
            timer,
            command: command_code,
            subcommand,
            data,
        })
    });
    (frame, serial, route.unwrap_or_default(), request)
}

/// A response in ASCII code, from the binary model of it: a batch read's words 4 digits each,
/// a type name as its 16 characters and the model code; the error information of an error
/// response (route, command, subcommand) as its fields.
pub(crate) fn encode_response(response: &Response, command_code: u16) -> Vec<u8> {
    let data = &response.data;
    let mut body = Vec::new();
    hex_field(&mut body, u32::from(response.end_code), 2);
    if response.end_code != 0 {
        if let [network, station, io_lo, io_hi, multidrop, c_lo, c_hi, s_lo, s_hi] = data[..] {
            hex_field(&mut body, u32::from(network), 1);
            hex_field(&mut body, u32::from(station), 1);
            hex_field(&mut body, u32::from(u16::from_le_bytes([io_lo, io_hi])), 2);
            hex_field(&mut body, u32::from(multidrop), 1);
            hex_field(&mut body, u32::from(u16::from_le_bytes([c_lo, c_hi])), 2);
            hex_field(&mut body, u32::from(u16::from_le_bytes([s_lo, s_hi])), 2);
        }
    } else if command_code == command::READ_TYPE_NAME && data.len() == 18 {
        body.extend_from_slice(&data[..16]);
        hex_field(
            &mut body,
            u32::from(u16::from_le_bytes([data[16], data[17]])),
            2,
        );
    } else {
        for w in data.chunks_exact(2) {
            hex_field(&mut body, u32::from(u16::from_le_bytes([w[0], w[1]])), 2);
        }
    }
    message(
        response.frame,
        [b"D000", b"D400"],
        response.serial,
        response.route,
        &body,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::slmp::frame::{random_read, read_type_name, read_words, DeviceRef};
    use rstest::rstest;

    fn request(frame: FrameKind, serial: u16, body: crate::backend::slmp::frame::Body) -> Request {
        Request {
            frame,
            serial,
            route: Route::default(),
            timer: 0x10,
            command: body.command,
            subcommand: body.subcommand,
            data: body.data,
        }
    }

    const D: u16 = 0xA8;

    /// Requests as text. The first row is the 3E ASCII head the layout gives
    /// (`500000FF03FF00` + length + timer + command + subcommand) on a read of D100-D102.
    #[rstest]
    #[case::read_3e_short(FrameKind::E3, 0, read_words(DeviceForm::Short, DeviceRef { code: D, number: 100 }, 3), "500000FF03FF00001800100401000 0D*0001000003")]
    #[case::read_3e_long(FrameKind::E3, 0, read_words(DeviceForm::Long, DeviceRef { code: D, number: 100 }, 3), "500000FF03FF00001C00100401000 2D***000001000003")]
    #[case::read_4e(FrameKind::E4, 0x1234, read_words(DeviceForm::Short, DeviceRef { code: D, number: 100 }, 3), "5400123400 0000FF03FF00001800100401000 0D*0001000003")]
    #[case::random_sd203(FrameKind::E3, 0, random_read(DeviceForm::Short, &[DeviceRef { code: 0xA9, number: 203 }, DeviceRef { code: 0x9C, number: 0x1F }]), "500000FF03FF000020001004030000 0200SD000203X*00001F")]
    #[case::type_name(
        FrameKind::E3,
        0,
        Ok(read_type_name()),
        "500000FF03FF00000C001001010000"
    )]
    fn requests(
        #[case] frame: FrameKind,
        #[case] serial: u16,
        #[case] body: Result<crate::backend::slmp::frame::Body, FrameError>,
        #[case] expected: &str,
    ) {
        let r = request(frame, serial, body.expect("body"));
        let text = encode_request(&r).expect("encodes");
        assert_eq!(
            String::from_utf8_lossy(&text),
            expected.replace(' ', ""),
            "{r:?}"
        );
    }

    #[test]
    fn a_batch_write_carries_each_word_as_four_digits() {
        let body = crate::backend::slmp::frame::write_words(
            DeviceForm::Short,
            DeviceRef {
                code: D,
                number: 10,
            },
            &[0x5A8D, 0x0001],
        )
        .expect("encodes");
        let text = encode_request(&request(FrameKind::E3, 0, body)).expect("encodes");
        assert_eq!(
            String::from_utf8_lossy(&text),
            "500000FF03FF00002000101401000 0D*00001000025A8D0001".replace(' ', "")
        );
    }

    #[rstest]
    #[case::words(FrameKind::E3, command::READ, "D00000FF03FF00000C00005A8D0001", 0, &[0x8D, 0x5A, 0x01, 0x00])]
    #[case::words_4e(FrameKind::E4, command::READ, concat!("D40012340000", "00FF03FF0000080000", "5A8D"), 0, &[0x8D, 0x5A])]
    #[case::type_name(
        FrameKind::E3,
        command::READ_TYPE_NAME,
        "D00000FF03FF0000180000FX5U-32MT/DS    4A49",
        0,
        b"FX5U-32MT/DS    \x49\x4A"
    )]
    #[case::error(FrameKind::E3, command::READ, "D00000FF03FF000016C05600FF03FF0004010000", 0xC056, &[])]
    fn responses(
        #[case] frame: FrameKind,
        #[case] command_code: u16,
        #[case] text: &str,
        #[case] end_code: u16,
        #[case] data: &[u8],
    ) {
        let r = decode_response(frame, command_code, text.as_bytes()).expect("decodes");
        assert_eq!(r.end_code, end_code);
        assert_eq!(r.data, data);
        assert_eq!(message_len(frame, text.as_bytes()), Ok(text.len()));
        if frame == FrameKind::E4 {
            assert_eq!(r.serial, 0x1234);
        }
    }

    #[rstest]
    #[case("D0", "are needed")]
    #[case("D00000FF03FF00000C00005A8D00", "are needed")]
    #[case("D00000FF03FF00000600GG00", "not a hexadecimal field")]
    #[case("HTTP/1.1 400 Bad Request", "where `D000`")]
    fn bad_responses(#[case] text: &str, #[case] message: &str) {
        let e = decode_response(FrameKind::E3, command::READ, text.as_bytes())
            .expect_err("does not decode");
        assert!(e.to_string().contains(message), "{e}");
    }

    /// The simulated CPU's ASCII port reads a request as the manual writes it: capitals, the
    /// device number in its radix with leading blanks as 0; anything else is C050H.
    #[rstest]
    #[case::as_written("500000FF03FF000018001004010000D*0001000001", Ok((100, 1)))]
    #[case::leading_blanks("500000FF03FF000018001004010000D*  01000001", Ok((100, 1)))]
    #[case::points_capitals("500000FF03FF000018001004010000D*000100000A", Ok((100, 10)))]
    #[case::points_lowercase("500000FF03FF000018001004010000D*000100000a", Err(0xC050))]
    #[case::points_g("500000FF03FF000018001004010000D*000100000G", Err(0xC050))]
    #[case::hex_number_lowercase("500000FF03FF000018001004010000W*00001a0001", Err(0xC050))]
    #[case::hex_number("500000FF03FF000018001004010000W*00001A0001", Ok((0x1A, 1)))]
    #[case::decimal_number_with_a_letter("500000FF03FF000018001004010000D*0001A00001", Err(0xC050))]
    #[case::write_unsupported("500000FF03FF000018001014010000D*0001000001", Err(0xC059))]
    fn an_ascii_request_is_read_strictly(
        #[case] text: &str,
        #[case] expected: Result<(u32, u16), u16>,
    ) {
        let (_, _, route, request) = decode_request(text.as_bytes());
        assert_eq!(route, Route::default());
        let read = request.map_err(Refusal::end_code).map(|r| {
            let number = u32::from_le_bytes([r.data[0], r.data[1], r.data[2], 0]);
            (number, u16::from_le_bytes([r.data[4], r.data[5]]))
        });
        assert_eq!(read, expected);
    }

    /// A response the client's reader reads back: words, and an error with its information.
    #[test]
    fn an_ascii_response_reads_back() {
        let words = Response {
            frame: FrameKind::E3,
            serial: 0,
            route: Route::default(),
            end_code: 0,
            data: vec![0x8D, 0x5A, 0x01, 0x00],
        };
        let text = encode_response(&words, command::READ);
        assert_eq!(text, b"D00000FF03FF00000C00005A8D0001".to_vec());
        assert_eq!(
            decode_response(FrameKind::E3, command::READ, &text),
            Ok(words)
        );
        let error = Response {
            end_code: 0xC050,
            data: vec![0x00, 0xFF, 0xFF, 0x03, 0x00, 0x01, 0x04, 0x00, 0x00],
            ..decode_response(FrameKind::E3, command::READ, &text).expect("decodes")
        };
        assert_eq!(
            String::from_utf8_lossy(&encode_response(&error, command::READ)),
            "D00000FF03FF000016C05000FF03FF0004010000"
        );
    }
}
