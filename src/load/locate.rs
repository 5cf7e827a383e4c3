//! Finds the line of a key in a YAML document.
//!
//! The serde deserializer reports lines only for errors it raises itself. Errors found later,
//! when a vector is checked against its profile (an unknown flag, a duplicate id), still have to
//! name the line, so each document is walked once more with a span-reporting parser and every
//! key path (`cases[3].before.D100`) is mapped to the line it starts on.

use std::collections::hash_map::Entry;
use std::collections::HashMap;

use saphyr_parser::{Event, Parser};

/// Lines of key paths in one document.
#[derive(Debug, Default)]
pub struct LineIndex {
    lines: HashMap<String, usize>,
    duplicates: Vec<(String, usize)>,
}

enum Frame {
    Map { path: String, key: Option<String> },
    Seq { path: String, next: usize },
}

impl LineIndex {
    /// Indexes a document. A document the parser rejects yields an empty index: its syntax error
    /// is reported by the deserializer, with its own line.
    pub fn new(text: &str) -> Self {
        let mut lines = HashMap::new();
        let mut duplicates = Vec::new();
        let mut stack: Vec<Frame> = Vec::new();
        for item in Parser::new_from_str(text) {
            let Ok((event, span)) = item else { break };
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
                Some(Frame::Map { path, key }) => match key.take() {
                    Some(k) => (join(path, &k), false),
                    None => (path.clone(), true),
                },
            };
            match event {
                Event::Scalar(value, ..) if is_key => {
                    let full = match stack.last() {
                        Some(Frame::Map { path, .. }) => join(path, &value),
                        _ => value.to_string(),
                    };
                    match lines.entry(full) {
                        Entry::Occupied(e) => duplicates.push((e.key().clone(), line)),
                        Entry::Vacant(e) => {
                            e.insert(line);
                        }
                    }
                    if let Some(Frame::Map { key, .. }) = stack.last_mut() {
                        *key = Some(value.to_string());
                    }
                }
                Event::Scalar(..) | Event::Alias(..) => {
                    lines.entry(path).or_insert(line);
                }
                Event::MappingStart(..) => {
                    lines.entry(path.clone()).or_insert(line);
                    stack.push(Frame::Map { path, key: None });
                }
                Event::SequenceStart(..) => {
                    lines.entry(path.clone()).or_insert(line);
                    stack.push(Frame::Seq { path, next: 0 });
                }
                Event::MappingEnd | Event::SequenceEnd => {
                    stack.pop();
                }
                _ => {}
            }
        }
        LineIndex { lines, duplicates }
    }

    /// Keys that appear twice in one mapping, with the line of the repeat. The deserializer
    /// keeps the last value of a repeated map key without a word, which would silently drop a
    /// memory word a vector author wrote.
    pub fn duplicates(&self) -> &[(String, usize)] {
        &self.duplicates
    }

    /// The line of a key path, or of its nearest indexed ancestor.
    pub fn line(&self, path: &str) -> Option<usize> {
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
    fn falls_back_to_the_parent() {
        let index = LineIndex::new(DOC);
        assert_eq!(index.line("cases[1].operands.missing"), Some(7));
    }
}
