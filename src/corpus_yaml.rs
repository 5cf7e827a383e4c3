//! Writing the corpus's own YAML: what `sweep --emit` writes as vector files, what `record`
//! writes into them, and the starting known-differences files of `record --known`. One writer,
//! so that every file the tool writes reads back through the loaders as it was meant: strings
//! quoted where YAML would read them otherwise, values in the corpus's hexadecimal notation,
//! free text folded at any length.

use std::fmt::Write as _;

use crate::judge::Effect;
use crate::model::cross_vendor::Answer;
use crate::model::ErrorSignal;
use crate::value::hex_word;

/// An effect as a vector's `expect:` key at `indent`: every word written, and the error (or
/// `none`), so that nothing the backend did is left implicit. No newline at the end.
pub(crate) fn expect_lines(effect: &Effect, indent: &str) -> String {
    let after: Vec<String> = effect
        .changed
        .iter()
        .map(|(d, w)| format!("{d}: {}", effect.unit.hex(*w)))
        .collect();
    let error = match &effect.error {
        None => "none".to_string(),
        Some(ErrorSignal::Code(c)) => hex_word(*c),
        Some(ErrorSignal::Flag(d)) => d.to_string(),
    };
    format!(
        "{indent}expect:\n{indent}  after: {{{}}}\n{indent}  error: {error}",
        after.join(", ")
    )
}

/// A value as the vectors write it: hexadecimal, at least four digits, `H`.
pub(crate) fn hex_value(v: u64) -> String {
    format!("{v:04X}H")
}

/// A cross-vendor expectation's keys, as a flow map's body: `value: 1234H`, `error: ...`.
pub(crate) fn answer(a: &Answer) -> String {
    match a {
        Answer::Value(v) => format!("value: {}", hex_value(*v)),
        Answer::Text(t) => format!("text: {}", quote(t)),
        Answer::Error(c) => format!("error: {c}"),
        Answer::ErrorAndValue(c, v) => format!("error: {c}, value: {}", hex_value(*v)),
        Answer::OtherError(e) => format!("error: {e}"),
        Answer::Accepted => "accepted: true".to_string(),
    }
}

/// A YAML double-quoted string of bytes, one character per byte (`\xHH` above 7EH).
pub(crate) fn quote(bytes: &[u8]) -> String {
    let mut s = String::from("\"");
    for &b in bytes {
        match b {
            b'"' => s.push_str("\\\""),
            b'\\' => s.push_str("\\\\"),
            0 => s.push_str("\\0"),
            0x20..=0x7E => s.push(b as char),
            _ => {
                let _ = write!(s, "\\x{b:02X}");
            }
        }
    }
    s.push('"');
    s
}

/// A YAML double-quoted string of text: characters kept, quotes, backslashes and control
/// characters escaped.
pub(crate) fn quote_str(text: &str) -> String {
    let mut s = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            c if (c as u32) < 0x20 || c == '\u{7F}' => {
                let _ = write!(s, "\\x{:02X}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// Free text as a folded block scalar (`>-`) under a key at `indent`: every line of the text
/// indented two further, so that a line break, a `#` or a `:` in it stays text.
pub(crate) fn folded(indent: &str, text: &str) -> String {
    let mut out = String::from(">-");
    for line in text.lines() {
        let _ = write!(out, "\n{indent}  {line}");
    }
    out
}

/// The name an enumeration's value has in the files (its serde name: `lowercase`, `above-7fh`).
pub(crate) fn name_of<T: serde::Serialize>(value: &T) -> String {
    serde_yaml::to_string(value)
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_keeps_every_byte() {
        assert_eq!(quote(b"5A\"\\"), "\"5A\\\"\\\\\"");
        assert_eq!(quote(&[0, 0x09, 0xEF]), "\"\\0\\x09\\xEF\"");
        assert_eq!(quote_str("例 \"a\"\t"), "\"例 \\\"a\\\"\\x09\"");
    }

    #[test]
    fn folded_text_reads_back_as_it_was() {
        let text = "two lines: one\n# and a hash";
        let yaml = format!("reason: {}\n", folded("", text));
        let back: std::collections::BTreeMap<String, String> =
            serde_yaml::from_str(&yaml).expect("reads");
        assert_eq!(back["reason"], "two lines: one # and a hash");
        let quoted = format!("cause: {}\n", quote_str("a \"cause\": #1"));
        let back: std::collections::BTreeMap<String, String> =
            serde_yaml::from_str(&quoted).expect("reads");
        assert_eq!(back["cause"], "a \"cause\": #1");
    }
}
