//! Lines for people on stderr beside a command's output: notes, warnings, what was written, and
//! the error that ended a command. The command line's one place that writes to stderr.
//!
//! Text that may come from outside (a backend's stderr, a file name) is made safe for a
//! terminal here, once.

use std::io::Write;

use super::sanitize::terminal;

/// Writes one line to stderr. A failing stderr has nowhere left to report to, so it is ignored.
fn line(text: &str) {
    let mut err = anstream::stderr();
    let _ = writeln!(err, "{}", terminal(text));
}

/// `note: ...`: something the user may want to know; the command goes on.
pub(crate) fn note(text: &str) {
    line(&format!("note: {text}"));
}

/// `warning: ...`: something is not as it should be; the command goes on.
pub(crate) fn warning(text: &str) {
    line(&format!("warning: {text}"));
}

/// A status line as it is (`wrote 3 vector(s) to x.yaml`, a baseline comparison).
pub(crate) fn status(text: &str) {
    line(text);
}

/// The error that ended a command, already rendered (`error: ...` lines).
pub(crate) fn error(rendered: &str) {
    line(rendered);
}
