//! Known-differences files as written on disk.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A known-differences file as written.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct KnownFileSpec {
    pub differences: Vec<EntrySpec>,
}

/// One entry: a single case (`case` and `reason`), or one cause that explains many cases
/// (`cause`, `kind`, and the cases it covers by id pattern and/or by the class of their input).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct EntrySpec {
    /// A case id of the corpus (a cross-vendor case id too).
    pub case: Option<String>,
    /// An entry by cause: case id patterns it covers, `*` standing for any characters
    /// (`xv-h2v-6*h`, `habin-fixed-*-is-invalid`).
    #[serde(default)]
    pub cases: Vec<String>,
    /// An entry by cause: the cross-vendor cases whose text has any of these classes.
    #[serde(default)]
    pub input: Vec<InputClass>,
    /// Only this instruction of the case's file (for a cross-vendor case: only this lowering of
    /// the profile, e.g. `habin-fixed`).
    pub instruction: Option<String>,
    /// Only this variant of the profile.
    pub variant: Option<String>,
    /// An entry by cause: the cause, in one line (what the implementation does).
    pub cause: Option<String>,
    /// Whether the difference is a bug or a deliberate choice of the implementation.
    pub kind: Option<Kind>,
    /// The protocol rule the difference breaks, `<protocol>/<rule>` (`modbus-ascii/B3`):
    /// required for an entry that covers protocol-field cases, and the rule of one of them.
    pub rule: Option<String>,
    /// Why the backend differs: shown with the trial. Required for a single case; for an entry
    /// by cause, more detail after the cause.
    pub reason: Option<String>,
}

/// Whether a listed difference is a bug or a deliberate choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum Kind {
    Bug,
    ByDesign,
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Kind::Bug => "bug",
            Kind::ByDesign => "by design",
        })
    }
}

/// A class of input text, as codecs tend to mistreat it: the characters no vendor takes as a
/// digit (30H-39H and 41H-46H are the digits).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum InputClass {
    /// A lowercase hex digit a-f (61H-66H): what "lowercase" means of a hex field.
    Lowercase,
    /// Another lowercase letter g-z (67H-7AH), the `x` of a `0x` prefix aside (that is
    /// `hex-prefix`).
    OtherLowercase,
    /// A space or a tab, line feed, vertical tab, form feed or carriage return (20H, 09H-0DH).
    Blank,
    /// `+` or `-`.
    Sign,
    /// A `0x` or `0X`.
    HexPrefix,
    /// `_`.
    Underscore,
    /// A byte above 7FH.
    #[serde(rename = "above-7fh")]
    Above7fh,
    /// A 00H.
    Nul,
    /// Another control character (01H-08H, 0EH-1FH, 7FH).
    Control,
    /// No character at all.
    Empty,
    /// An uppercase letter G-Z (47H-5AH): no digit, and no lowercase either.
    OtherUppercase,
    /// Other printable punctuation (21H-2FH, 3AH-40H, 5BH-60H, 7BH-7EH) but `+`, `-` and `_`,
    /// which are `sign` and `underscore`.
    Punctuation,
    /// A blank (as `blank`) before the first other character: `" 5A8"`.
    BlankLeading,
    /// A blank after the last other character: `"5A8 "`.
    BlankTrailing,
    /// A blank between two other characters: `"5A 8"`.
    BlankInside,
}

/// A space or a tab, line feed, vertical tab, form feed or carriage return.
fn is_blank(b: u8) -> bool {
    b == b' ' || (0x09..=0x0D).contains(&b)
}

impl InputClass {
    /// Whether a text has a character of the class.
    pub(crate) fn holds(self, text: &[u8]) -> bool {
        let any = |f: fn(u8) -> bool| text.iter().any(|&b| f(b));
        match self {
            InputClass::Lowercase => any(|b| (b'a'..=b'f').contains(&b)),
            InputClass::OtherLowercase => text.iter().enumerate().any(|(i, &b)| {
                let prefix_x = b == b'x' && i > 0 && text[i - 1] == b'0';
                (b'g'..=b'z').contains(&b) && !prefix_x
            }),
            InputClass::Blank => any(is_blank),
            InputClass::Sign => any(|b| b == b'+' || b == b'-'),
            InputClass::HexPrefix => text.windows(2).any(|w| w == b"0x" || w == b"0X"),
            InputClass::Underscore => any(|b| b == b'_'),
            InputClass::Above7fh => any(|b| b > 0x7F),
            InputClass::Nul => any(|b| b == 0),
            InputClass::Control => {
                any(|b| (0x01..=0x08).contains(&b) || (0x0E..=0x1F).contains(&b) || b == 0x7F)
            }
            InputClass::Empty => text.is_empty(),
            InputClass::OtherUppercase => any(|b| (b'G'..=b'Z').contains(&b)),
            InputClass::Punctuation => any(|b| {
                matches!(b, 0x21..=0x2F | 0x3A..=0x40 | 0x5B..=0x60 | 0x7B..=0x7E)
                    && !matches!(b, b'+' | b'-' | b'_')
            }),
            InputClass::BlankLeading => text.first().is_some_and(|&b| is_blank(b)),
            InputClass::BlankTrailing => text.last().is_some_and(|&b| is_blank(b)),
            InputClass::BlankInside => {
                let first = text.iter().position(|&b| !is_blank(b));
                let last = text.iter().rposition(|&b| !is_blank(b));
                match (first, last) {
                    (Some(f), Some(l)) => text[f..l].iter().any(|&b| is_blank(b)),
                    _ => false,
                }
            }
        }
    }
}
