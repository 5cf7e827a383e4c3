//! Modbus TCP messages (ADUs): the MBAP header and the PDUs of four functions, both directions.
//!
//! The layout (Modbus Messaging on TCP/IP Implementation Guide V1.0b, Modbus Application Protocol
//! Specification V1.1b3): transaction id, protocol id 0, a length counting the unit id and the
//! PDU, the unit id, then the function code and its data; every number big-endian. The
//! simulated CPU decodes what the client encodes, so both directions live here and are tested
//! against the specification's own example bytes, not against each other only. Only FC01, FC03,
//! FC06 and FC16 are encodable: nothing here can build a diagnostic, file or coil write.

use std::fmt;

/// Read Coils.
pub(crate) const READ_COILS: u8 = 0x01;
/// Read Holding Registers.
pub(crate) const READ_HOLDING: u8 = 0x03;
/// Write Single Register.
pub(crate) const WRITE_SINGLE: u8 = 0x06;
/// Write Multiple Registers.
pub(crate) const WRITE_MULTIPLE: u8 = 0x10;

/// Most registers one FC03 may read (V1.1b3: 0x7D), so that the reply fits in 253 PDU bytes.
pub(crate) const MAX_READ_REGISTERS: usize = 125;
/// Most registers one FC16 may write (V1.1b3: 0x7B).
pub(crate) const MAX_WRITE_REGISTERS: usize = 123;
/// Most coils one FC01 may read (V1.1b3: 0x7D0).
pub(crate) const MAX_READ_COILS: usize = 2000;
/// The MBAP header: transaction id, protocol id, length, unit id.
pub(crate) const MBAP_LEN: usize = 7;
/// The longest ADU: the MBAP header and a PDU of at most 253 bytes.
pub(crate) const MAX_ADU: usize = 260;

/// A message that is not what it should be; the detail names the fields and numbers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FrameError {
    pub detail: String,
}

impl FrameError {
    fn new(detail: impl Into<String>) -> Self {
        FrameError {
            detail: detail.into(),
        }
    }
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.detail)
    }
}

impl std::error::Error for FrameError {}

/// What an exception code means, in the specification's words (V1.1b3, section 7).
pub(crate) fn exception_meaning(code: u8) -> Option<&'static str> {
    Some(match code {
        0x01 => "ILLEGAL FUNCTION",
        0x02 => "ILLEGAL DATA ADDRESS",
        0x03 => "ILLEGAL DATA VALUE",
        0x04 => "SERVER DEVICE FAILURE",
        0x05 => "ACKNOWLEDGE",
        0x06 => "SERVER DEVICE BUSY",
        0x0A => "GATEWAY PATH UNAVAILABLE",
        0x0B => "GATEWAY TARGET DEVICE FAILED TO RESPOND",
        _ => return None,
    })
}

/// A request, in wire addresses (0-based: holding register 400001 is address 0).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Request {
    ReadCoils { address: u16, count: u16 },
    ReadHolding { address: u16, count: u16 },
    WriteSingle { address: u16, value: u16 },
    WriteMultiple { address: u16, values: Vec<u16> },
}

impl Request {
    pub(crate) fn function(&self) -> u8 {
        match self {
            Request::ReadCoils { .. } => READ_COILS,
            Request::ReadHolding { .. } => READ_HOLDING,
            Request::WriteSingle { .. } => WRITE_SINGLE,
            Request::WriteMultiple { .. } => WRITE_MULTIPLE,
        }
    }
}

/// A response. `Exception` carries the function as requested, without the 0x80 bit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Response {
    /// Trimmed to the count asked: the last byte's padding bits are not coils.
    Coils(Vec<bool>),
    Registers(Vec<u16>),
    WroteSingle {
        address: u16,
        value: u16,
    },
    WroteMultiple {
        address: u16,
        count: u16,
    },
    Exception {
        function: u8,
        code: u8,
    },
}

/// What a server makes of a request: one it serves, a function it does not know (it answers
/// exception 01), or one it must refuse with `code` (03 for a quantity out of the limits, 02 for
/// a range past address 0xFFFF).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Decoded {
    Request(Request),
    Unsupported { function: u8 },
    Illegal { function: u8, code: u8 },
}

fn word(bytes: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([bytes[at], bytes[at + 1]])
}

fn adu(tid: u16, unit: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(MBAP_LEN + pdu.len());
    out.extend_from_slice(&tid.to_be_bytes());
    out.extend_from_slice(&[0, 0]);
    // A PDU is at most 253 bytes, so the length always fits.
    out.extend_from_slice(&((pdu.len() + 1) as u16).to_be_bytes());
    out.push(unit);
    out.extend_from_slice(pdu);
    out
}

/// Why `count` items from `address` cannot be one request of `function`, if they cannot.
fn span_fault(function: u8, address: u16, count: usize, max: usize) -> Option<(u8, String)> {
    if !(1..=max).contains(&count) {
        return Some((
            3,
            format!("FC{function:02} quantity {count} is outside 1..={max}"),
        ));
    }
    if usize::from(address) + count > 0x1_0000 {
        return Some((
            2,
            format!(
                "FC{function:02} of {count} from address 0x{address:04X} runs past address 0xFFFF"
            ),
        ));
    }
    None
}

/// The ADU of one request; refuses quantities outside the specification's limits and ranges
/// past the last address, so that no server ever has to.
pub(crate) fn encode_request(tid: u16, unit: u8, request: &Request) -> Result<Vec<u8>, FrameError> {
    let f = request.function();
    let refuse = |address, count, max| match span_fault(f, address, count, max) {
        Some((_, detail)) => Err(FrameError::new(detail)),
        None => Ok(()),
    };
    let mut pdu = vec![f];
    match request {
        Request::ReadCoils { address, count } | Request::ReadHolding { address, count } => {
            let max = if f == READ_COILS {
                MAX_READ_COILS
            } else {
                MAX_READ_REGISTERS
            };
            refuse(*address, usize::from(*count), max)?;
            pdu.extend_from_slice(&address.to_be_bytes());
            pdu.extend_from_slice(&count.to_be_bytes());
        }
        Request::WriteSingle { address, value } => {
            pdu.extend_from_slice(&address.to_be_bytes());
            pdu.extend_from_slice(&value.to_be_bytes());
        }
        Request::WriteMultiple { address, values } => {
            refuse(*address, values.len(), MAX_WRITE_REGISTERS)?;
            pdu.extend_from_slice(&address.to_be_bytes());
            pdu.extend_from_slice(&(values.len() as u16).to_be_bytes());
            pdu.push((values.len() * 2) as u8);
            values
                .iter()
                .for_each(|v| pdu.extend_from_slice(&v.to_be_bytes()));
        }
    }
    Ok(adu(tid, unit, &pdu))
}

/// The whole ADU's length from its first six bytes, so that a reader takes exactly one message.
/// A header whose protocol id is not 0 is refused before its length is believed.
pub(crate) fn message_len(header: &[u8; 6]) -> Result<usize, FrameError> {
    let protocol = word(header, 2);
    if protocol != 0 {
        return Err(FrameError::new(format!(
            "protocol id {protocol} where Modbus has 0"
        )));
    }
    let length = usize::from(word(header, 4));
    if !(2..=MAX_ADU - 6).contains(&length) {
        return Err(FrameError::new(format!(
            "a length field of {length} bytes, outside 2..={} (unit id and PDU)",
            MAX_ADU - 6
        )));
    }
    Ok(6 + length)
}

/// The MBAP header of a whole ADU, checked against the bytes: (tid, unit, PDU).
fn split(bytes: &[u8]) -> Result<(u16, u8, &[u8]), FrameError> {
    if bytes.len() < MBAP_LEN + 1 {
        return Err(FrameError::new(format!(
            "{} bytes, fewer than the {} of an MBAP header and a function code",
            bytes.len(),
            MBAP_LEN + 1
        )));
    }
    let protocol = word(bytes, 2);
    if protocol != 0 {
        return Err(FrameError::new(format!(
            "protocol id {protocol} where Modbus has 0"
        )));
    }
    let length = usize::from(word(bytes, 4));
    if length != bytes.len() - 6 {
        return Err(FrameError::new(format!(
            "the length field says {length} bytes follow it, {} do",
            bytes.len() - 6
        )));
    }
    Ok((word(bytes, 0), bytes[6], &bytes[MBAP_LEN..]))
}

/// Decodes the reply to `request`, sent with `tid` to `unit`: an exception is a valid answer,
/// anything that is not exactly the answer to that request is an error.
pub(crate) fn decode_response(
    tid: u16,
    unit: u8,
    request: &Request,
    bytes: &[u8],
) -> Result<Response, FrameError> {
    let (got_tid, got_unit, pdu) = split(bytes)?;
    if got_tid != tid {
        return Err(FrameError::new(format!(
            "transaction id 0x{got_tid:04X} where 0x{tid:04X} was sent"
        )));
    }
    if got_unit != unit {
        return Err(FrameError::new(format!(
            "unit {got_unit} where {unit} was addressed"
        )));
    }
    let f = request.function();
    let sized = |n: usize| {
        if pdu.len() == n {
            Ok(())
        } else {
            Err(FrameError::new(format!(
                "a PDU of {} bytes where FC{:02} answers with {n}",
                pdu.len(),
                pdu[0] & 0x7F
            )))
        }
    };
    if pdu[0] == f | 0x80 {
        sized(2)?;
        return Ok(Response::Exception {
            function: f,
            code: pdu[1],
        });
    }
    if pdu[0] != f {
        return Err(FrameError::new(format!(
            "function 0x{:02X} where 0x{f:02X} was asked",
            pdu[0]
        )));
    }
    let byte_count = |need: usize| {
        let got = pdu.get(1).map_or(0, |&b| usize::from(b));
        if got != need {
            return Err(FrameError::new(format!(
                "byte count {got} where {need} were needed"
            )));
        }
        sized(2 + need).map(|()| &pdu[2..])
    };
    match request {
        Request::ReadCoils { count, .. } => {
            let n = usize::from(*count);
            let data = byte_count(n.div_ceil(8))?;
            Ok(Response::Coils(
                (0..n).map(|i| (data[i / 8] >> (i % 8)) & 1 == 1).collect(),
            ))
        }
        Request::ReadHolding { count, .. } => {
            let data = byte_count(usize::from(*count) * 2)?;
            Ok(Response::Registers(
                data.chunks_exact(2).map(|c| word(c, 0)).collect(),
            ))
        }
        Request::WriteSingle { address, value } => {
            sized(5)?;
            let (a, v) = (word(pdu, 1), word(pdu, 3));
            if (a, v) != (*address, *value) {
                return Err(FrameError::new(format!(
                    "the echo says 0x{v:04X} at 0x{a:04X}, 0x{value:04X} at 0x{address:04X} was \
                     written"
                )));
            }
            Ok(Response::WroteSingle {
                address: a,
                value: v,
            })
        }
        Request::WriteMultiple { address, values } => {
            sized(5)?;
            let (a, n) = (word(pdu, 1), word(pdu, 3));
            if (a, usize::from(n)) != (*address, values.len()) {
                return Err(FrameError::new(format!(
                    "the echo says {n} registers at 0x{a:04X}, {} at 0x{address:04X} were written",
                    values.len()
                )));
            }
            Ok(Response::WroteMultiple {
                address: a,
                count: n,
            })
        }
    }
}

/// A server's reading of one whole request ADU: (tid, unit, what it asks). A malformed message
/// is an error (the server drops it); a request it must refuse is a `Decoded`, to answer.
pub(crate) fn decode_request(bytes: &[u8]) -> Result<(u16, u8, Decoded), FrameError> {
    let (tid, unit, pdu) = split(bytes)?;
    let f = pdu[0];
    let sized = |n: usize| {
        if pdu.len() == n {
            Ok(())
        } else {
            Err(FrameError::new(format!(
                "a PDU of {} bytes where an FC{f:02} request has {n}",
                pdu.len()
            )))
        }
    };
    let span = |address, count, max| {
        span_fault(f, address, count, max).map(|(code, _)| Decoded::Illegal { function: f, code })
    };
    let decoded = match f {
        READ_COILS | READ_HOLDING => {
            sized(5)?;
            let (address, count) = (word(pdu, 1), word(pdu, 3));
            let max = if f == READ_COILS {
                MAX_READ_COILS
            } else {
                MAX_READ_REGISTERS
            };
            span(address, usize::from(count), max).unwrap_or(Decoded::Request(if f == READ_COILS {
                Request::ReadCoils { address, count }
            } else {
                Request::ReadHolding { address, count }
            }))
        }
        WRITE_SINGLE => {
            sized(5)?;
            Decoded::Request(Request::WriteSingle {
                address: word(pdu, 1),
                value: word(pdu, 3),
            })
        }
        WRITE_MULTIPLE => {
            let declared = pdu.get(5).map_or(0, |&b| usize::from(b));
            sized(6 + declared)?;
            let (address, count) = (word(pdu, 1), usize::from(word(pdu, 3)));
            // V1.1b3 refuses a byte count that disagrees with the quantity with exception 03.
            if declared != count * 2 {
                Decoded::Illegal {
                    function: f,
                    code: 3,
                }
            } else {
                span(address, count, MAX_WRITE_REGISTERS).unwrap_or_else(|| {
                    Decoded::Request(Request::WriteMultiple {
                        address,
                        values: pdu[6..].chunks_exact(2).map(|c| word(c, 0)).collect(),
                    })
                })
            }
        }
        function => Decoded::Unsupported { function },
    };
    Ok((tid, unit, decoded))
}

/// The ADU of a server's answer. The server answers only what `decode_request` let through, so
/// the counts are within the limits and fit the byte-count field.
pub(crate) fn encode_response(tid: u16, unit: u8, response: &Response) -> Vec<u8> {
    let mut pdu = Vec::new();
    match response {
        Response::Coils(coils) => {
            pdu.extend_from_slice(&[READ_COILS, coils.len().div_ceil(8) as u8]);
            for chunk in coils.chunks(8) {
                pdu.push(
                    chunk
                        .iter()
                        .enumerate()
                        .fold(0, |b, (i, &on)| b | (u8::from(on) << i)),
                );
            }
        }
        Response::Registers(values) => {
            pdu.extend_from_slice(&[READ_HOLDING, (values.len() * 2) as u8]);
            values
                .iter()
                .for_each(|v| pdu.extend_from_slice(&v.to_be_bytes()));
        }
        Response::WroteSingle { address, value } => {
            pdu.push(WRITE_SINGLE);
            pdu.extend_from_slice(&address.to_be_bytes());
            pdu.extend_from_slice(&value.to_be_bytes());
        }
        Response::WroteMultiple { address, count } => {
            pdu.push(WRITE_MULTIPLE);
            pdu.extend_from_slice(&address.to_be_bytes());
            pdu.extend_from_slice(&count.to_be_bytes());
        }
        Response::Exception { function, code } => pdu.extend_from_slice(&[function | 0x80, *code]),
    }
    adu(tid, unit, &pdu)
}

#[cfg(test)]
pub(crate) fn bytes_of(hex: &str) -> Vec<u8> {
    hex.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).expect("test hex"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::bench::tcp::hex;
    use rstest::rstest;

    const TID: u16 = 0x1234;
    const UNIT: u8 = 0x11;

    fn coils(bits: &str) -> Vec<bool> {
        bits.chars().map(|c| c == '1').collect()
    }

    /// The requests of V1.1b3's examples, in an MBAP header written out by hand.
    #[rstest]
    #[case::fc03(Request::ReadHolding { address: 0x6B, count: 3 }, "12 34 00 00 00 06 11 03 00 6B 00 03")]
    #[case::fc06(Request::WriteSingle { address: 1, value: 3 }, "12 34 00 00 00 06 11 06 00 01 00 03")]
    #[case::fc16(
        Request::WriteMultiple { address: 1, values: vec![0x000A, 0x0102] },
        "12 34 00 00 00 0B 11 10 00 01 00 02 04 00 0A 01 02"
    )]
    #[case::fc01(Request::ReadCoils { address: 0x13, count: 0x13 }, "12 34 00 00 00 06 11 01 00 13 00 13")]
    fn spec_requests_both_ways(#[case] request: Request, #[case] wire: &str) {
        let bytes = encode_request(TID, UNIT, &request).expect("encodes");
        assert_eq!(hex(&bytes), wire);
        let decoded = decode_request(&bytes_of(wire)).expect("decodes");
        assert_eq!(decoded, (TID, UNIT, Decoded::Request(request)));
    }

    /// The responses of V1.1b3's examples (FC01: coils 20..38 read as CD 6B 05, first coil in
    /// the lowest bit).
    #[rstest]
    #[case::fc03(
        Request::ReadHolding { address: 0x6B, count: 3 },
        Response::Registers(vec![0x022B, 0, 0x64]),
        "12 34 00 00 00 09 11 03 06 02 2B 00 00 00 64"
    )]
    #[case::fc06(
        Request::WriteSingle { address: 1, value: 3 },
        Response::WroteSingle { address: 1, value: 3 },
        "12 34 00 00 00 06 11 06 00 01 00 03"
    )]
    #[case::fc16(
        Request::WriteMultiple { address: 1, values: vec![0x000A, 0x0102] },
        Response::WroteMultiple { address: 1, count: 2 },
        "12 34 00 00 00 06 11 10 00 01 00 02"
    )]
    #[case::fc01(
        Request::ReadCoils { address: 0x13, count: 0x13 },
        Response::Coils(coils("1011001111010110101")),
        "12 34 00 00 00 06 11 01 03 CD 6B 05"
    )]
    #[case::exception(
        Request::ReadHolding { address: 0x6B, count: 3 },
        Response::Exception { function: 3, code: 2 },
        "12 34 00 00 00 03 11 83 02"
    )]
    fn spec_responses_both_ways(
        #[case] request: Request,
        #[case] response: Response,
        #[case] wire: &str,
    ) {
        assert_eq!(hex(&encode_response(TID, UNIT, &response)), wire);
        let decoded = decode_response(TID, UNIT, &request, &bytes_of(wire)).expect("decodes");
        assert_eq!(decoded, response);
    }

    /// Every check of `decode_response`, each against a reply that fails only it.
    #[rstest]
    #[case::tid(
        read3(),
        "12 35 00 00 00 09 11 03 06 02 2B 00 00 00 64",
        "transaction id 0x1235 where 0x1234"
    )]
    #[case::protocol(
        read3(),
        "12 34 00 01 00 09 11 03 06 02 2B 00 00 00 64",
        "protocol id 1"
    )]
    #[case::short(read3(), "12 34 00 00 00 01 11", "7 bytes, fewer than the 8")]
    #[case::length(
        read3(),
        "12 34 00 00 00 0A 11 03 06 02 2B 00 00 00 64",
        "says 10 bytes follow it, 9 do"
    )]
    #[case::unit(
        read3(),
        "12 34 00 00 00 09 12 03 06 02 2B 00 00 00 64",
        "unit 18 where 17"
    )]
    #[case::function(
        read3(),
        "12 34 00 00 00 09 11 04 06 02 2B 00 00 00 64",
        "function 0x04 where 0x03"
    )]
    #[case::exception_of_another(read3(), "12 34 00 00 00 03 11 84 02", "function 0x84 where 0x03")]
    #[case::long_exception(read3(), "12 34 00 00 00 04 11 83 02 00", "PDU of 3 bytes")]
    #[case::byte_count(
        read3(),
        "12 34 00 00 00 07 11 03 04 02 2B 00 00",
        "byte count 4 where 6"
    )]
    #[case::extra_data(
        read3(),
        "12 34 00 00 00 0B 11 03 06 02 2B 00 00 00 64 00 00",
        "PDU of 10 bytes"
    )]
    #[case::coil_byte_count(coils19(), "12 34 00 00 00 05 11 01 02 CD 6B", "byte count 2 where 3")]
    #[case::single_echo(
        write1(),
        "12 34 00 00 00 06 11 06 00 01 00 04",
        "0x0004 at 0x0001, 0x0003"
    )]
    #[case::multiple_echo(
        write2(),
        "12 34 00 00 00 06 11 10 00 01 00 01",
        "1 registers at 0x0001, 2"
    )]
    #[case::multiple_echo_address(
        write2(),
        "12 34 00 00 00 06 11 10 00 02 00 02",
        "at 0x0002, 2 at 0x0001"
    )]
    fn every_decode_check_refuses(
        #[case] request: Request,
        #[case] wire: &str,
        #[case] says: &str,
    ) {
        let e = decode_response(TID, UNIT, &request, &bytes_of(wire)).expect_err(wire);
        assert!(e.to_string().contains(says), "{e}");
    }

    fn read3() -> Request {
        Request::ReadHolding {
            address: 0x6B,
            count: 3,
        }
    }
    fn coils19() -> Request {
        Request::ReadCoils {
            address: 0x13,
            count: 19,
        }
    }
    fn write1() -> Request {
        Request::WriteSingle {
            address: 1,
            value: 3,
        }
    }
    fn write2() -> Request {
        Request::WriteMultiple {
            address: 1,
            values: vec![0x0A, 0x0102],
        }
    }

    #[rstest]
    #[case::fc03_most(Request::ReadHolding { address: 0, count: 125 }, None)]
    #[case::fc03_over(Request::ReadHolding { address: 0, count: 126 }, Some("quantity 126 is outside 1..=125"))]
    #[case::fc03_none(Request::ReadHolding { address: 0, count: 0 }, Some("quantity 0"))]
    #[case::fc16_most(Request::WriteMultiple { address: 0, values: vec![0; 123] }, None)]
    #[case::fc16_over(Request::WriteMultiple { address: 0, values: vec![0; 124] }, Some("quantity 124 is outside 1..=123"))]
    #[case::fc16_none(Request::WriteMultiple { address: 0, values: vec![] }, Some("quantity 0"))]
    #[case::fc01_most(Request::ReadCoils { address: 0, count: 2000 }, None)]
    #[case::fc01_over(Request::ReadCoils { address: 0, count: 2001 }, Some("quantity 2001 is outside 1..=2000"))]
    #[case::last_address(Request::ReadHolding { address: 0xFFFF, count: 1 }, None)]
    #[case::ends_at_last(Request::ReadHolding { address: 0xFF83, count: 125 }, None)]
    #[case::past_last(Request::ReadHolding { address: 0xFF84, count: 125 }, Some("0xFF84 runs past address 0xFFFF"))]
    #[case::write_past_last(Request::WriteMultiple { address: 0xFFFF, values: vec![1, 2] }, Some("runs past"))]
    fn limits_of_the_specification(#[case] request: Request, #[case] refused: Option<&str>) {
        match (encode_request(TID, UNIT, &request), refused) {
            (Ok(bytes), None) => {
                assert!(bytes.len() <= MAX_ADU);
                let decoded = decode_request(&bytes).expect("decodes");
                assert_eq!(decoded.2, Decoded::Request(request));
            }
            (Err(e), Some(says)) => assert!(e.to_string().contains(says), "{e}"),
            (other, _) => panic!("{request:?}: {other:?}"),
        }
    }

    /// What a server must answer with an exception instead of serving.
    #[rstest]
    #[case::fc03_over("00 01 00 00 00 06 01 03 00 00 00 7E", Decoded::Illegal { function: 3, code: 3 })]
    #[case::fc01_over("00 01 00 00 00 06 01 01 00 00 07 D1", Decoded::Illegal { function: 1, code: 3 })]
    #[case::fc03_past("00 01 00 00 00 06 01 03 FF FF 00 02", Decoded::Illegal { function: 3, code: 2 })]
    #[case::fc16_count("00 01 00 00 00 09 01 10 00 00 00 02 02 00 01", Decoded::Illegal { function: 0x10, code: 3 })]
    #[case::fc16_over("00 01 00 00 00 07 01 10 00 00 00 7C 00", Decoded::Illegal { function: 0x10, code: 3 })]
    #[case::unknown("00 01 00 00 00 02 01 2B", Decoded::Unsupported { function: 0x2B })]
    fn requests_a_server_refuses(#[case] wire: &str, #[case] decoded: Decoded) {
        assert_eq!(decode_request(&bytes_of(wire)), Ok((1, 1, decoded)));
    }

    #[rstest]
    #[case::truncated("00 01 00 00 00 06 01 03 00 00 00", "says 6 bytes follow it, 5 do")]
    #[case::fc06_long(
        "00 01 00 00 00 07 01 06 00 00 00 01 00",
        "PDU of 6 bytes where an FC06"
    )]
    #[case::fc16_short("00 01 00 00 00 0A 01 10 00 00 00 02 04 00 01 00", "PDU of 9 bytes")]
    fn malformed_requests_are_errors(#[case] wire: &str, #[case] says: &str) {
        let e = decode_request(&bytes_of(wire)).expect_err(wire);
        assert!(e.to_string().contains(says), "{e}");
    }

    #[rstest]
    #[case::fc03_reply("00 01 00 00 00 09", Ok(15))]
    #[case::largest("00 01 00 00 00 FE", Ok(260))]
    #[case::too_long("00 01 00 00 00 FF", Err("length field of 255"))]
    #[case::no_pdu("00 01 00 00 00 01", Err("length field of 1"))]
    #[case::not_modbus("48 54 54 50 2F 31", Err("protocol id 21584"))]
    fn message_len_believes_only_a_modbus_header(
        #[case] header: &str,
        #[case] expected: Result<usize, &str>,
    ) {
        let header: [u8; 6] = bytes_of(header).try_into().expect("six bytes");
        match (message_len(&header), expected) {
            (Ok(n), Ok(m)) => assert_eq!(n, m),
            (Err(e), Err(says)) => assert!(e.to_string().contains(says), "{e}"),
            (got, want) => panic!("{got:?} where {want:?}"),
        }
    }

    #[rstest]
    #[case(0x01, Some("ILLEGAL FUNCTION"))]
    #[case(0x02, Some("ILLEGAL DATA ADDRESS"))]
    #[case(0x06, Some("SERVER DEVICE BUSY"))]
    #[case(0x0B, Some("GATEWAY TARGET DEVICE FAILED TO RESPOND"))]
    #[case(0x07, None)]
    fn exception_names(#[case] code: u8, #[case] meaning: Option<&str>) {
        assert_eq!(exception_meaning(code), meaning);
    }
}
