//! Text from outside — a vector's cite or note, a backend's answer or stderr, a file name — on
//! its way out of a report. A terminal never receives a control character from it (an escape
//! sequence could recolour, retitle or rewrite the screen), and XML (JUnit, HTML) never a
//! character XML 1.0 forbids, which would make the whole document unreadable. Each such
//! character is shown as a visible escape: `\x1B`, `\u{FFFE}`.

use std::borrow::Cow;
use std::fmt::Write;

/// For a terminal or a log: every control character but newline and tab — ESC and the other
/// C0 controls, DEL, the C1 controls (CSI among them) — as a visible escape.
pub(crate) fn terminal(text: &str) -> Cow<'_, str> {
    replace(text, unsafe_on_a_terminal)
}

/// For XML 1.0 text and attribute values: the characters XML forbids (C0 controls but tab,
/// newline and carriage return; U+FFFE and U+FFFF) and those a terminal must not see either, as
/// visible escapes. Markup characters are left to the XML writer.
pub(crate) fn xml(text: &str) -> Cow<'_, str> {
    replace(text, |c| unsafe_on_a_terminal(c) || forbidden_in_xml(c))
}

/// Whether a character cannot appear in an XML 1.0 document, even as a reference.
pub(crate) fn forbidden_in_xml(c: char) -> bool {
    matches!(c, '\u{0}'..='\u{8}' | '\u{b}' | '\u{c}' | '\u{e}'..='\u{1f}' | '\u{fffe}' | '\u{ffff}')
}

fn unsafe_on_a_terminal(c: char) -> bool {
    c.is_control() && c != '\n' && c != '\t'
}

/// The visible escape of a character: `\xNN` up to FFH, `\u{NNNN}` above.
pub(crate) fn escaped(c: char) -> String {
    let code = u32::from(c);
    if code <= 0xFF {
        format!("\\x{code:02X}")
    } else {
        format!("\\u{{{code:04X}}}")
    }
}

fn replace(text: &str, bad: impl Fn(char) -> bool) -> Cow<'_, str> {
    if !text.chars().any(&bad) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if bad(c) {
            let _ = write!(out, "{}", escaped(c));
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_sequences_never_reach_a_terminal() {
        assert_eq!(terminal("plain\ttext\n"), "plain\ttext\n");
        assert_eq!(
            terminal("\u{1b}[31mred\u{1b}]0;title\u{7}\u{9b}2J\r"),
            "\\x1B[31mred\\x1B]0;title\\x07\\x9B2J\\x0D"
        );
    }

    #[test]
    fn xml_gets_no_forbidden_character() {
        assert_eq!(
            xml("a\u{fffe}b\u{ffff}c\u{1}"),
            "a\\u{FFFE}b\\u{FFFF}c\\x01"
        );
        assert_eq!(xml("ok: <&> ü 𝄞"), "ok: <&> ü 𝄞");
        assert!(matches!(xml("clean"), Cow::Borrowed(_)));
    }
}
