//! What one request may carry and the monitoring timer to send, per CPU family, code and device
//! form, as the manuals give them (docs/live-cpu.md#limits-from-the-manuals). A request over a
//! limit is answered with an error end code (an FX5 answers a 481-word ASCII read with C052H),
//! so the client splits every batch at the limit of the port it talks to.

use super::frame::{Code, DeviceForm};

/// The CPU families the live backend reaches, as their limits differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Family {
    /// MELSEC iQ-R (and the Q/L CPUs the same reference manual covers).
    Iqr,
    /// MELSEC iQ-F FX5 CPU modules, built-in Ethernet port.
    Fx5,
}

impl Family {
    /// The family of a profile id: FX5 for `mitsubishi-fx5`, iQ-R otherwise.
    pub(crate) fn of_profile(profile: &str) -> Family {
        match profile {
            "mitsubishi-fx5" => Family::Fx5,
            _ => Family::Iqr,
        }
    }
}

/// Points one request may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Words of one batch read (0401) or write (1401) in word units.
    pub batch_words: usize,
    /// Word and double-word points of one random read (0403).
    pub random_points: usize,
}

/// The limits of a port.
///
/// - iQ-R: 960 words a batch in either code; a random read 192 points in the Q-compatible form
///   (subcommand 0000) and 96 in the long form (0002). MELSEC Communication Protocol Reference
///   Manual, Appendix 5 "Number of Processing per One Communication" (page 465): "Batch read in
///   word units 0401 ... Word device points 960 points", "Random read in word units 0403 0000
///   ... 192 points ... 0002 ... 96 points".
/// - FX5: "1 to 480 points" a batch in ASCII code and "1 to 960 points" in binary code (FX5
///   User's Manual (SLMP), 4.2 Device Read (Batch), number of devices in word units); a random
///   read 192 points in binary code, and half as many in ASCII code, where the manual counts
///   (word points + double-word points) x 2 against 192 (inferred from that rule as the aslmp
///   project reads it; the other FX5 figures measured on an FX5U-32MT/DS by the same project).
pub(crate) fn limits(family: Family, code: Code, form: DeviceForm) -> Limits {
    match (family, code) {
        (Family::Fx5, Code::Binary) => Limits {
            batch_words: 960,
            random_points: 192,
        },
        (Family::Fx5, Code::Ascii) => Limits {
            batch_words: 480,
            random_points: 96,
        },
        (Family::Iqr, _) => Limits {
            batch_words: 960,
            random_points: match form {
                DeviceForm::Short => 192,
                DeviceForm::Long => 96,
            },
        },
    }
}

/// The monitoring timer to send, in units of 250 ms.
///
/// - iQ-R: 8 (2 s). The reference manual's "Monitoring timer": "0000H (0): Wait infinitely",
///   "0001H to FFFFH (1 to 65535): Waiting time (unit: 250 ms)", recommended "0001H to 0028H"
///   for the connected station.
/// - FX5: 0. The FX5 SLMP manual's message format: "Set 0000H (0)" for the field (the
///   CPU module does not time its own processing).
pub(crate) fn monitoring_timer(family: Family) -> u16 {
    match family {
        Family::Iqr => 8,
        Family::Fx5 => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_fx5_in_ascii_code_takes_half_the_words_of_binary() {
        let fx5 = |code| limits(Family::Fx5, code, DeviceForm::Short);
        assert_eq!(fx5(Code::Binary).batch_words, 960);
        assert_eq!(fx5(Code::Ascii).batch_words, 480);
        assert_eq!(fx5(Code::Ascii).random_points, 96);
        let iqr = |code, form| limits(Family::Iqr, code, form);
        assert_eq!(iqr(Code::Ascii, DeviceForm::Long).batch_words, 960);
        assert_eq!(iqr(Code::Binary, DeviceForm::Long).random_points, 96);
        assert_eq!(iqr(Code::Binary, DeviceForm::Short).random_points, 192);
        assert_eq!(monitoring_timer(Family::Fx5), 0);
        assert_eq!(Family::of_profile("mitsubishi-fx5"), Family::Fx5);
    }
}
