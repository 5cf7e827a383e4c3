//! A read-only look at a bench: what `plc-conformance hil doctor` prints. It only reads (the
//! CPU's name, its state, the mailbox), so it can be pointed at a CPU before anything is
//! trusted.

use std::time::{Duration, Instant};

use super::link::LinkSettings;
use super::mailbox::{self, off, Signature};
use super::settings::BenchSettings;
use crate::backend::bench::error::{refused, LiveError};

/// One finding: what was looked at, and what was found (`Err` when it stops a run).
#[derive(Debug)]
pub(crate) struct Finding {
    pub what: &'static str,
    pub result: Result<String, LiveError>,
}

/// Looks at the bench in the order the backend's interlocks do, and stops at the first thing
/// that makes the rest meaningless (no connection). Returns the findings and the requests sent.
pub(crate) fn doctor<L: LinkSettings>(settings: &BenchSettings<L>) -> (Vec<Finding>, u64) {
    let mut link = settings.link.open();
    let mut out = Vec::new();
    let mut push = |what, result| out.push(Finding { what, result });
    match link.identify() {
        Ok(t) if t.name == settings.confirm => {
            push("type name", Ok(format!("{}, as confirmed", t.shown)))
        }
        Ok(t) => push(
            "type name",
            Err(refused!(
                "{}, but `confirm` says `{}`",
                t.shown,
                settings.confirm
            )),
        ),
        Err(e) => {
            push("connection", Err(e.into()));
            return (out, link.requests());
        }
    }
    match link.run_state() {
        Ok(state) if state.running => push("operating status", Ok(state.text)),
        Ok(state) => push("operating status", Err(LiveError::Refused(state.text))),
        Err(e) => push("operating status", Err(e.into())),
    }
    let Ok(head) = settings.manifest.mailbox_head(settings.link.addressing()) else {
        push(
            "mailbox",
            Err(refused!("the manifest's mailbox is not a device")),
        );
        return (out, link.requests());
    };
    match link.read(&head, mailbox::WORDS) {
        Ok(words) => {
            let read = Signature::of(&words);
            let expected = settings.manifest.signature();
            push(
                "program signature",
                match read.mismatch(&expected) {
                    None => Ok(format!(
                        "program {} (layout {}, {} rungs) at {}",
                        settings.manifest.hash, expected.layout, expected.rungs, head
                    )),
                    Some(why) => Err(LiveError::Refused(why)),
                },
            );
            let get = |o: u32| words.get(o as usize).copied().unwrap_or(0);
            push(
                "answered by",
                Ok(match get(off::ORIGIN) {
                    mailbox::SIMULATOR => "the simulated CPU (plc-conformance hil sim): nothing \
                                           it answers is recorded as observed"
                        .to_string(),
                    _ => "a CPU running the generated program".to_string(),
                }),
            );
            let (trigger, ack, st) = (get(off::TRIGGER), get(off::ACK), get(off::STATE));
            push(
                "program state",
                if trigger == ack {
                    Ok(format!("idle (trigger {trigger}, ack {ack})"))
                } else {
                    Err(refused!(
                        "busy with case {trigger} (ack {ack}, state {st}); it finishes or the \
                         backend waits for it"
                    ))
                },
            );
            push(
                "error flag",
                Ok(if get(off::FLAG_NOW) != 0 {
                    format!(
                        "{} on now; the program resets it ({}) before each case",
                        settings.manifest.error.flag, settings.manifest.error.reset
                    )
                } else {
                    format!("{} off", settings.manifest.error.flag)
                }),
            );
            let counter = mailbox::at(&head, off::SCANS);
            let first = get(off::SCANS);
            let since = Instant::now();
            let moved = loop {
                match link.read(&counter, 1) {
                    Ok(w) if w.first().copied() != Some(first) => break Ok(()),
                    Ok(_) if since.elapsed() > Duration::from_secs(1) => {
                        break Err(refused!("{counter} did not move in 1 s"))
                    }
                    Ok(_) => std::thread::sleep(Duration::from_millis(5)),
                    Err(e) => break Err(e.into()),
                }
            };
            push(
                "scan counter",
                moved.map(|()| format!("{counter} moves: the program runs")),
            );
        }
        Err(e) => push("mailbox", Err(e.into())),
    }
    (out, link.requests())
}
