//! The document's value, built from the same parse that indexes its lines ([`super::locate`]).
//!
//! Every file used to be parsed twice, once by the span-reporting parser for its lines and once
//! by the deserializer's for its value; in a process that runs one trial, or a dependent's
//! unoptimised build, the second parse was a third of the start-up. The value is built here from
//! the first parse's events, resolving plain scalars as the deserializer does (YAML 1.2's core
//! schema: null, booleans, integers in four bases, floats, else a string). What this does not
//! build the same way — a tag, a repeated key, an integer past 64 bits, a
//! syntax error — gives no value, and the loader parses the text the old way, so the result
//! (and every error message) is the deserializer's own.

use std::collections::HashMap;

use saphyr_parser::{Event, ScalarStyle};
use serde_yaml::{Mapping, Number, Value};

/// A collection still open, with its anchor (0 for none).
enum Open {
    Sequence(Vec<Value>, usize),
    Mapping(Mapping, Option<Value>, usize),
}

/// Builds a [`Value`] from parser events, or gives up.
#[derive(Default)]
pub(super) struct Builder {
    open: Vec<Open>,
    root: Option<Value>,
    /// Anchored nodes and how many nodes each holds, for the aliases that repeat them (the
    /// deserializer copies them too).
    anchors: HashMap<usize, (Value, usize)>,
    /// Events read, and nodes copied by aliases: a file of nested aliases (a "billion laughs")
    /// would grow without end: past a hundred copies an event the document is left to the
    /// deserializer, which has limits of its own.
    events: usize,
    copied: usize,
    given_up: bool,
}

impl Builder {
    /// Takes the next event of the document.
    pub(super) fn event(&mut self, event: &Event<'_>) {
        if self.given_up {
            return;
        }
        self.events += 1;
        match event {
            Event::Scalar(_, _, _, Some(_))
            | Event::SequenceStart(_, Some(_))
            | Event::MappingStart(_, Some(_)) => self.give_up(),
            Event::Scalar(text, style, anchor, None) => match scalar(text, *style) {
                Some(value) => self.add(value, *anchor),
                None => self.give_up(),
            },
            Event::SequenceStart(anchor, None) => {
                self.open.push(Open::Sequence(Vec::new(), *anchor))
            }
            Event::MappingStart(anchor, None) => {
                self.open.push(Open::Mapping(Mapping::new(), None, *anchor))
            }
            Event::SequenceEnd | Event::MappingEnd => match self.open.pop() {
                Some(Open::Sequence(items, anchor)) => self.add(Value::Sequence(items), anchor),
                Some(Open::Mapping(map, None, anchor)) => self.add(Value::Mapping(map), anchor),
                _ => self.give_up(),
            },
            Event::Alias(anchor) => match self.anchors.get(anchor) {
                Some((_, nodes)) if self.copied + nodes > 100 * self.events => self.give_up(),
                Some((value, nodes)) => {
                    self.copied += nodes;
                    self.add(value.clone(), 0)
                }
                None => self.give_up(),
            },
            _ => {}
        }
    }

    /// The parse stopped early (a syntax error, a text the index refuses).
    pub(super) fn give_up(&mut self) {
        self.given_up = true;
    }

    /// The whole document, when every event was one this builds the deserializer's way.
    pub(super) fn finish(self) -> Option<Value> {
        if self.given_up || !self.open.is_empty() {
            return None;
        }
        self.root
    }

    fn add(&mut self, value: Value, anchor: usize) {
        if anchor != 0 {
            self.anchors.insert(anchor, (value.clone(), nodes(&value)));
        }
        match self.open.last_mut() {
            None if self.root.is_none() => self.root = Some(value),
            None => self.give_up(),
            Some(Open::Sequence(items, _)) => items.push(value),
            Some(Open::Mapping(map, key, _)) => match key.take() {
                None => *key = Some(value),
                // The deserializer refuses a repeated key with its own message.
                Some(k) if map.contains_key(&k) => self.give_up(),
                Some(k) => {
                    map.insert(k, value);
                }
            },
        }
    }
}

/// How many nodes a value holds, itself included: what an alias to it copies.
fn nodes(value: &Value) -> usize {
    1 + match value {
        Value::Sequence(items) => items.iter().map(nodes).sum(),
        Value::Mapping(map) => map.iter().map(|(k, v)| nodes(k) + nodes(v)).sum(),
        _ => 0,
    }
}

/// An untagged scalar as the deserializer reads it into a [`Value`]; `None` for an integer it
/// would read as 128 bits.
fn scalar(text: &str, style: ScalarStyle) -> Option<Value> {
    if style != ScalarStyle::Plain {
        return Some(Value::String(text.to_string()));
    }
    Some(match text {
        "" | "~" | "null" | "Null" | "NULL" => Value::Null,
        "true" | "True" | "TRUE" => Value::Bool(true),
        "false" | "False" | "FALSE" => Value::Bool(false),
        // Most scalars are words: no number starts with a letter.
        _ if !text.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.')) => {
            Value::String(text.to_string())
        }
        _ => {
            if let Some(n) = unsigned(text) {
                Value::Number(Number::from(n))
            } else if let Some(n) = negative(text) {
                Value::Number(Number::from(n))
            } else if unsigned_wide(text) || negative_wide(text) {
                return None;
            } else if let Some(f) = (!leading_zero(text)).then(|| float(text)).flatten() {
                Value::Number(Number::from(f))
            } else {
                Value::String(text.to_string())
            }
        }
    })
}

const BASES: [(&str, u32); 3] = [("0x", 16), ("0o", 8), ("0b", 2)];

/// `007`, `-01`: digits after a leading zero are a string in YAML 1.2.
fn leading_zero(text: &str) -> bool {
    let digits = text.strip_prefix(['-', '+']).unwrap_or(text);
    digits.len() > 1 && digits.starts_with('0') && digits[1..].bytes().all(|b| b.is_ascii_digit())
}

/// A non-negative integer: decimal, or `0x`/`0o`/`0b` with an optional `+`.
fn unsigned_with<T>(
    text: &str,
    radix: fn(&str, u32) -> Result<T, std::num::ParseIntError>,
) -> Option<T> {
    let rest = text.strip_prefix('+').unwrap_or(text);
    for (prefix, base) in BASES {
        if let Some(digits) = rest.strip_prefix(prefix) {
            if digits.starts_with(['+', '-']) {
                return None;
            }
            if let Ok(n) = radix(digits, base) {
                return Some(n);
            }
        }
    }
    if rest.starts_with(['+', '-']) || leading_zero(text) {
        return None;
    }
    radix(rest, 10).ok()
}

/// A negative integer: decimal, or `-0x`/`-0o`/`-0b`.
fn negative_with<T>(
    text: &str,
    radix: fn(&str, u32) -> Result<T, std::num::ParseIntError>,
) -> Option<T> {
    for (prefix, base) in BASES {
        if let Some(digits) = text.strip_prefix('-').and_then(|t| t.strip_prefix(prefix)) {
            if let Ok(n) = radix(&format!("-{digits}"), base) {
                return Some(n);
            }
        }
    }
    if leading_zero(text) {
        return None;
    }
    radix(text, 10).ok()
}

fn unsigned(text: &str) -> Option<u64> {
    unsigned_with(text, u64::from_str_radix)
}

fn negative(text: &str) -> Option<i64> {
    negative_with(text, i64::from_str_radix)
}

fn unsigned_wide(text: &str) -> bool {
    unsigned_with(text, u128::from_str_radix).is_some()
}

fn negative_wide(text: &str) -> bool {
    negative_with(text, i128::from_str_radix).is_some()
}

/// A float as YAML 1.2 writes one (`.inf`, `-.inf`, `.nan` included); an overflow to infinity
/// from digits is a string.
fn float(text: &str) -> Option<f64> {
    let rest = match text.strip_prefix('+') {
        Some(rest) if rest.starts_with(['+', '-']) => return None,
        Some(rest) => rest,
        None => text,
    };
    match (rest, text) {
        (".inf" | ".Inf" | ".INF", _) => Some(f64::INFINITY),
        (_, "-.inf" | "-.Inf" | "-.INF") => Some(f64::NEG_INFINITY),
        (_, ".nan" | ".NaN" | ".NAN") => Some(f64::NAN),
        _ => rest.parse::<f64>().ok().filter(|f| f.is_finite()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value built from the index's parse, or `None` when it gives up.
    fn built(text: &str) -> Option<Value> {
        let mut builder = Builder::default();
        for item in saphyr_parser::Parser::new_from_str(text) {
            match item {
                Ok((event, _)) => builder.event(&event),
                Err(_) => {
                    builder.give_up();
                    break;
                }
            }
        }
        builder.finish()
    }

    #[rstest::rstest]
    #[case::numbers(
        "[0, 1, -1, +1, 0x1F, 0o17, 0b101, -0x10, 007, -08, 1.5, -2e3, .inf, -.INF, +.5, 1_000]"
    )]
    #[case::words(
        "[~, null, Null, NULL, true, True, TRUE, false, FALSE, yes, no, on, 'true', \"1\"]"
    )]
    #[case::odd_numbers(
        "[0x, 0x+1, +-1, -0x-1, 0o8, 0b2, 1e400, -1e400, 0.0, -0, +0, 00, .5., 1.]"
    )]
    #[case::keys("{1: a, true: b, ~: c, 0x10: d, D100: 4135H, K$10: x}")]
    #[case::blocks("a: |\n  line one\n  line two\nb: >\n  folded\n  text\nc: 'it''s'\nd: \"tab\\there\\u00e9\"\ne:\n")]
    #[case::nesting("cases:\n  - id: a\n    before: {D100: 0x4135, D101: [1, 2]}\n  - id: b\n    after:\n      D1: -1\n")]
    #[case::plain_multiline("a: one\n  two\n  three\nb: x")]
    #[case::empty_collections("a: []\nb: {}\nc: [[], [{}]]")]
    #[case::anchors("a: &x 1\nb: *x\nc: &l [1, {d: 2}]\ne: [*l, *x]\nf: &x 3\ng: *x")]
    #[case::max_ints("[18446744073709551615, -9223372036854775808, 9223372036854775807]")]
    fn builds_what_the_deserializer_reads(#[case] text: &str) {
        let expected: Value = serde_yaml::from_str(text).expect("the deserializer reads it");
        assert_eq!(built(text), Some(expected), "{text}");
    }

    #[rstest::rstest]
    #[case::tag("a: !!str 1")]
    #[case::unknown_alias("a: *x")]
    #[case::custom_tag("a: !Thing {b: 1}")]
    #[case::repeated_key("a: 1\na: 2")]
    #[case::wide_integer("a: 18446744073709551616")]
    #[case::wide_negative("a: -9223372036854775809")]
    #[case::syntax_error("a: [1, 2")]
    #[case::billion_laughs("a: &a [x, x, x, x, x, x, x, x, x, x]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\nc: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]\nd: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]\ne: [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]")]
    #[case::nothing("")]
    fn gives_up_where_it_would_differ(#[case] text: &str) {
        assert_eq!(built(text), None, "{text}");
    }

    /// Every YAML file shipped (profiles, corpus) builds to the deserializer's value.
    #[test]
    fn every_shipped_file_builds_as_the_deserializer_reads_it() {
        let files = super::super::embedded_files(std::path::Path::new(super::super::EMBEDDED))
            .expect("the embedded folder");
        let mut checked = 0;
        for path in files {
            let text = super::super::embedded_text(&path).expect("an embedded file");
            let expected: Value = serde_yaml::from_str(text).expect("the deserializer reads it");
            // Not assert_eq: a file's whole value is too long to read in a failure.
            assert!(built(text) == Some(expected), "{}", path.display());
            checked += 1;
        }
        assert!(checked > 40, "only {checked} files embedded");
    }
}
