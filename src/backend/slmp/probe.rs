//! Read-only probes of a CPU's MC protocol (SLMP) port in ASCII code: batch reads (0401) of one
//! or ten words whose point count or device number is written as the manual writes it, or with
//! what the manual does not cover — a lowercase letter, a leading blank — or refuses — a
//! character that is not a hex digit. Each records the end code the CPU answers: a real CPU's
//! answers settle the open questions of `docs/open-questions.yaml` (`mc-ascii-lowercase`), a
//! simulator's settle nothing. Nothing is written.

use std::io::Write;
use std::time::{Duration, Instant};

use crate::backend::bench::tcp;

/// What the manual makes of a probe's request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Manual {
    /// The end code the manual states, and the protocol rule that states it.
    EndCode(u16, &'static str),
    /// No page settles it: the open question the answer informs.
    Open(&'static str),
}

/// One read request, as sent.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Probe {
    pub(crate) id: &'static str,
    /// The field that differs from the request as the manual writes it.
    pub(crate) field: &'static str,
    /// The device, as its letters padded with `*` and its 6-digit number.
    pub(crate) device: &'static str,
    /// The point count's 4 characters.
    pub(crate) points: &'static str,
    pub(crate) manual: Manual,
}

/// The probes, in the order they are sent: each lowercase one beside its capital twin, so that
/// a refusal is told apart from a device the CPU does not have.
pub(crate) const PROBES: [Probe; 7] = [
    Probe {
        id: "as-written",
        field: "none",
        device: "D*000000",
        points: "0001",
        manual: Manual::EndCode(0, "mc-ascii/M1"),
    },
    Probe {
        id: "points-capital",
        field: "point count",
        device: "D*000000",
        points: "000A",
        manual: Manual::EndCode(0, "mc-ascii/M1"),
    },
    Probe {
        id: "points-lowercase",
        field: "point count",
        device: "D*000000",
        points: "000a",
        manual: Manual::Open("mc-ascii-lowercase"),
    },
    Probe {
        id: "number-capital",
        field: "device number (hexadecimal W)",
        device: "W*00001A",
        points: "0001",
        manual: Manual::EndCode(0, "mc-ascii/M10"),
    },
    Probe {
        id: "number-lowercase",
        field: "device number (hexadecimal W)",
        device: "W*00001a",
        points: "0001",
        manual: Manual::Open("mc-ascii-lowercase"),
    },
    Probe {
        id: "number-leading-blanks",
        field: "device number",
        device: "D*  0000",
        points: "0001",
        manual: Manual::EndCode(0, "mc-ascii/M11"),
    },
    Probe {
        id: "points-not-hex",
        field: "point count",
        device: "D*000000",
        points: "000G",
        manual: Manual::EndCode(0xC050, "mc-ascii/M4"),
    },
];

impl Probe {
    /// The request in a 3E frame, ASCII code: a batch read in words (0401, subcommand 0000),
    /// monitoring timer 0010, to the own station.
    pub(crate) fn request(&self) -> Vec<u8> {
        let body = format!("001004010000{}{}", self.device, self.points);
        format!("500000FF03FF00{:04X}{body}", body.len()).into_bytes()
    }
}

/// What came back to a probe.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Heard {
    /// An answer with this end code.
    EndCode(u16),
    /// Nothing within the time limit, or the connection closed: the CPU did not answer.
    Nothing(String),
    /// Something that is no ASCII 3E answer, in hex.
    Garbage(String),
}

impl std::fmt::Display for Heard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Heard::EndCode(c) => write!(f, "{c:04X}H"),
            Heard::Nothing(why) => write!(f, "no answer ({why})"),
            Heard::Garbage(bytes) => write!(f, "not an answer: {bytes}"),
        }
    }
}

/// Every probe asked in turn, each with its answer; `Err` when no connection can be made.
pub(crate) fn ask_all(
    address: &str,
    timeout: Duration,
) -> std::io::Result<Vec<(&'static Probe, Heard)>> {
    PROBES
        .iter()
        .map(|p| ask(address, p, timeout).map(|heard| (p, heard)))
        .collect()
}

impl Manual {
    /// Whether `heard` is what the manual states; `None` where it states nothing.
    pub(crate) fn agrees(self, heard: &Heard) -> Option<bool> {
        match self {
            Manual::EndCode(code, _) => Some(*heard == Heard::EndCode(code)),
            Manual::Open(_) => None,
        }
    }
}

/// Sends a probe on a connection of its own (a refused request may leave a CPU's connection
/// in any state) and reads the answer's end code; `Err` when no connection can be made.
fn ask(address: &str, probe: &Probe, timeout: Duration) -> std::io::Result<Heard> {
    let mut stream = tcp::connect(address, timeout)?;
    stream.write_all(&probe.request())?;
    let deadline = Instant::now() + timeout;
    // Subheader, route and length: `D00000FF03FF00` and 4 characters.
    let mut head = [0u8; 18];
    if let Err(e) = tcp::read_full(&mut stream, &mut head, deadline) {
        return Ok(Heard::Nothing(match e {
            tcp::Short::Timeout => format!("none within {} s", timeout.as_secs_f64()),
            tcp::Short::Closed(why) => why,
        }));
    }
    let garbage = |bytes: &[u8]| Heard::Garbage(tcp::hex(bytes));
    if &head[..4] != b"D000" {
        return Ok(garbage(&head));
    }
    let Some(length) = std::str::from_utf8(&head[14..18])
        .ok()
        .and_then(|t| u16::from_str_radix(t, 16).ok())
        .filter(|n| *n >= 4)
    else {
        return Ok(garbage(&head));
    };
    let mut rest = vec![0u8; usize::from(length)];
    if let Err(e) = tcp::read_full(&mut stream, &mut rest, deadline) {
        return Ok(Heard::Nothing(match e {
            tcp::Short::Timeout => "the answer stopped short".into(),
            tcp::Short::Closed(why) => why,
        }));
    }
    Ok(std::str::from_utf8(&rest[..4])
        .ok()
        .and_then(|t| u16::from_str_radix(t, 16).ok())
        .map_or_else(|| garbage(&rest), Heard::EndCode))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each request is the 3E ASCII read the manual lays out, with its length right, and
    /// differs from the one as written in its own field only.
    #[test]
    fn each_probe_is_a_read_request_with_one_field_changed() {
        let written = String::from_utf8(PROBES[0].request()).expect("ASCII");
        assert_eq!(written, "500000FF03FF000018001004010000D*0000000001");
        for p in &PROBES {
            let text = String::from_utf8(p.request()).expect("ASCII");
            assert_eq!(text.len(), 18 + 24, "{}", p.id);
            assert_eq!(&text[..30], &written[..30], "{}", p.id);
            let differs = (text.bytes().zip(written.bytes()))
                .filter(|(a, b)| a != b)
                .count();
            assert!(p.id == "as-written" || differs > 0, "{}", p.id);
        }
    }
}
