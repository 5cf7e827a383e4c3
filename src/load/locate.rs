//! Finds the line of a key in a YAML document.
//!
//! The serde deserializer reports lines only for errors it raises itself. Errors found later,
//! when a vector is checked against its profile (an unknown flag, a duplicate id), still have to
//! name the line, so each document is walked once more with a span-reporting parser and every
//! key path (`cases[3].before.D100`) is mapped to the line it starts on.

use std::collections::hash_map::Entry;
use std::collections::HashMap;

use saphyr_parser::{Event, Parser};

use super::document::Builder;

/// The deepest nesting of mappings and sequences a file may have. The formats need five; a
/// pathological file of 100,000 levels would otherwise hold the deserializer for a minute.
pub(super) const MAX_DEPTH: usize = 64;

/// Refuses a character YAML forbids (C0 and C1 controls other than tab and line breaks, DEL,
/// U+FFFE, U+FFFF) before any parser sees the text, with its line.
fn forbidden_character(text: &str) -> Result<(), (usize, String)> {
    for (i, line) in text.split('\n').enumerate() {
        if let Some(c) = line.chars().find(|c| forbidden(*c)) {
            return Err((
                i + 1,
                format!(
                    "control character U+{:04X} in the text: YAML allows only printable \
                     characters, tabs and line breaks (write it as an escape in a \
                     double-quoted string)",
                    u32::from(c)
                ),
            ));
        }
    }
    Ok(())
}

fn too_deep() -> String {
    format!("nested more than {MAX_DEPTH} levels deep; no format of this tool nests that far")
}

fn forbidden(c: char) -> bool {
    matches!(c, '\u{0}'..='\u{8}' | '\u{b}' | '\u{c}' | '\u{e}'..='\u{1f}' | '\u{7f}')
        || ('\u{80}'..='\u{9f}').contains(&c) && c != '\u{85}'
        || c == '\u{fffe}'
        || c == '\u{ffff}'
}

/// Lines of key paths in one document.
#[derive(Debug, Default)]
pub(crate) struct LineIndex {
    lines: HashMap<String, usize>,
    duplicates: Vec<(String, usize)>,
}

enum Frame {
    /// `key`: the path of the value its last key starts, until that value is read.
    Map {
        path: String,
        key: Option<String>,
    },
    Seq {
        path: String,
        next: usize,
    },
}

impl LineIndex {
    /// Indexes a document whose text [`LineIndex::read`] would refuse as far as it goes.
    #[cfg(test)]
    pub(crate) fn new(text: &str) -> Self {
        Self::checked(text).unwrap_or_default()
    }

    /// [`LineIndex::read`] without the document.
    #[cfg(test)]
    pub(crate) fn checked(text: &str) -> Result<Self, (usize, String)> {
        Self::read(text).map(|(index, _)| index)
    }

    /// Checks what the deserializer must never see and indexes the document in the same pass,
    /// stopping at the first problem: a character YAML forbids, a second document, or nesting
    /// deeper than [`MAX_DEPTH`] (which the deserializer takes quadratic time over). Returns the
    /// line and the message of the problem. A syntax error ends the index where it is: the
    /// deserializer reports it, with its own line. The same parse builds the document's value
    /// when [`super::document`] can build it as the deserializer would.
    pub(crate) fn read(text: &str) -> Result<(Self, Option<serde_yaml::Value>), (usize, String)> {
        forbidden_character(text)?;
        let mut document = Builder::default();
        let mut lines = HashMap::new();
        let mut duplicates = Vec::new();
        let mut stack: Vec<Frame> = Vec::new();
        let mut documents = 0usize;
        for item in Parser::new_from_str(text) {
            let (event, span) = match item {
                Ok(item) => item,
                // The scanner counts flow levels in a byte: past 255 it gives up.
                Err(e) if e.info().contains("recursion limit") => {
                    return Err((e.marker().line(), too_deep()))
                }
                Err(_) => {
                    document.give_up();
                    break;
                }
            };
            document.event(&event);
            let line = span.start.line();
            // The path of the node this event starts, and whether it is a mapping key.
            let (path, is_key) = match stack.last_mut() {
                None => (String::new(), false),
                Some(Frame::Seq { path, next }) => {
                    let p = format!("{path}[{next}]");
                    if !matches!(event, Event::SequenceEnd) {
                        *next += 1;
                    }
                    (p, false)
                }
                // A key's own path is made below, once it is read.
                Some(Frame::Map { key, .. }) => match key.take() {
                    Some(full) => (full, false),
                    None => (String::new(), true),
                },
            };
            match event {
                Event::DocumentStart(_) => {
                    documents += 1;
                    if documents > 1 {
                        return Err((
                            line,
                            "a second YAML document: a file holds exactly one (remove the `---` \
                             line and merge the documents, or make a second file)"
                                .into(),
                        ));
                    }
                }
                Event::Scalar(value, ..) if is_key => {
                    let full = match stack.last() {
                        Some(Frame::Map { path, .. }) => join(path, &value),
                        _ => value.to_string(),
                    };
                    match lines.entry(full.clone()) {
                        Entry::Occupied(e) => duplicates.push((e.key().clone(), line)),
                        Entry::Vacant(e) => {
                            e.insert(line);
                        }
                    }
                    if let Some(Frame::Map { key, .. }) = stack.last_mut() {
                        *key = Some(full);
                    }
                }
                Event::Scalar(..) | Event::Alias(..) => {
                    lines.entry(path).or_insert(line);
                }
                Event::MappingStart(..) | Event::SequenceStart(..) => {
                    if stack.len() >= MAX_DEPTH {
                        return Err((line, too_deep()));
                    }
                    lines.entry(path.clone()).or_insert(line);
                    stack.push(match event {
                        Event::MappingStart(..) => Frame::Map { path, key: None },
                        _ => Frame::Seq { path, next: 0 },
                    });
                }
                Event::MappingEnd | Event::SequenceEnd => {
                    stack.pop();
                }
                _ => {}
            }
        }
        Ok((LineIndex { lines, duplicates }, document.finish()))
    }

    /// Keys that appear twice in one mapping, with the line of the repeat. The deserializer
    /// keeps the last value of a repeated map key without a word, which would silently drop a
    /// memory word a vector author wrote.
    pub(crate) fn duplicates(&self) -> &[(String, usize)] {
        &self.duplicates
    }

    /// The line of a key path, or of its nearest indexed ancestor.
    pub(crate) fn line(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some(line) = self.lines.get(p) {
                return Some(*line);
            }
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
        }
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = "\
instructions: [HABIN]
cases:
  - id: a
    before:
      D100: 4135H
  - id: b
    operands:
      s: D100
";

    #[test]
    fn finds_nested_keys() {
        let index = LineIndex::new(DOC);
        assert_eq!(index.line("instructions"), Some(1));
        assert_eq!(index.line("cases[0].id"), Some(3));
        assert_eq!(index.line("cases[0].before.D100"), Some(5));
        assert_eq!(index.line("cases[1]"), Some(6));
        assert_eq!(index.line("cases[1].operands.s"), Some(8));
    }

    #[test]
    fn reports_repeated_keys() {
        let index = LineIndex::new("a:\n  D1: 1\n  D1: 2\nb: [1]\n");
        assert_eq!(index.duplicates(), &[("a.D1".to_string(), 3)]);
    }

    #[test]
    fn refuses_what_the_deserializer_must_not_see() {
        let check_text = |text: &str| LineIndex::checked(text).map(|_| ());
        assert_eq!(check_text(DOC), Ok(()));
        let (line, message) = check_text("a: 1\nb: \"x\u{1b}[31m\"\n").expect_err("ESC");
        assert_eq!(line, 2);
        assert!(message.contains("U+001B"), "{message}");
        let (line, message) = check_text("a: 1\n---\nb: 2\n").expect_err("two documents");
        assert_eq!(line, 2);
        assert!(message.contains("second YAML document"), "{message}");
        // Past the limit the pass stops at once: were it to walk on, a 100,000-level nesting
        // would hold this test for minutes.
        let deep = format!("a: {}1{}\n", "[".repeat(100_000), "]".repeat(100_000));
        let (line, message) = check_text(&deep).expect_err("deep");
        assert_eq!(line, 1);
        assert!(message.contains("more than 64 levels"), "{message}");
        let ok = format!("a: {}1{}\n", "[".repeat(60), "]".repeat(60));
        assert_eq!(check_text(&ok), Ok(()));
        let deep = format!("{}1\n", "- ".repeat(100_000));
        let (_, message) = check_text(&deep).expect_err("deep block nesting");
        assert!(message.contains("more than 64 levels"), "{message}");
    }

    #[test]
    fn falls_back_to_the_parent() {
        let index = LineIndex::new(DOC);
        assert_eq!(index.line("cases[1].operands.missing"), Some(7));
    }
}
