//! Interruption: SIGINT and SIGTERM end a run with what it has, and no backend outlives it.
//!
//! Backends run in process groups of their own, so the terminal's Ctrl-C never reaches them. On
//! a signal the harness sets the one stop flag ([`stop_flag`]: no further chunk of trials
//! starts, no backend process starts, a live bench answers nothing more), kills every backend
//! process group — also one still in its handshake — and starts no
//! backend any more. The run then finishes with the trials that finished, its reports marked
//! incomplete, and the command exits with the status of an interruption, 128 + the signal
//! ([`exit_status`]: 130 for SIGINT, 143 for SIGTERM). A second signal exits at once.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

use crate::backend::external;

static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// What a signal does once the backends are killed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OnSignal {
    /// Set the stop flag and let the run finish with what it has (`run`, `diff`).
    Finish,
    /// Exit at once with the interruption's status (a test harness, which cannot be stopped
    /// half-way).
    Exit,
}

/// The stop flag a run is given: set by an interruption (the flag that also keeps any backend
/// from starting once the backends are being killed).
pub(crate) fn stop_flag() -> &'static AtomicBool {
    external::closing_flag()
}

/// The signal that interrupted the run, if one did.
pub(crate) fn signal() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The exit status of an interrupted command: 128 + the signal.
pub(crate) fn exit_status() -> Option<u8> {
    signal().and_then(|s| u8::try_from(128 + s).ok())
}

/// Interrupts the run as a signal would: records the signal, sets the stop flag and kills every
/// backend process group.
pub(crate) fn interrupt(signal: i32) {
    SIGNAL.store(signal, Ordering::SeqCst);
    external::kill_all();
}

/// Wraps the panic hook: a codec's panic, caught as its case's crash
/// (`backend::convert_or_panic`), is kept with where it happened and not printed; any other
/// panic, with `kill`, first kills every backend process group.
pub(crate) fn install_panic_hook(kill: bool) {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if crate::backend::asking_codec() {
            if let Some(at) = info.location() {
                crate::backend::codec_panicked_at(at.to_string());
            }
            return;
        }
        if kill {
            external::kill_all();
        }
        previous(info);
    }));
}

/// Handles SIGINT and SIGTERM on a thread of their own from now on. With
/// [`OnSignal::Finish`] (a command, which a panic ends) a panic also kills every backend
/// process group; a test harness, which turns a panic into one failed test, keeps them.
pub(crate) fn install(on_signal: OnSignal) -> std::io::Result<()> {
    install_panic_hook(on_signal == OnSignal::Finish);
    handle_signals(on_signal)
}

#[cfg(all(unix, feature = "signals"))]
fn handle_signals(on_signal: OnSignal) -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                let again = external::closing();
                interrupt(signal);
                if again || on_signal == OnSignal::Exit {
                    std::process::exit(128 + signal);
                }
            }
        })?;
    Ok(())
}

#[cfg(all(unix, not(feature = "signals")))]
fn handle_signals(_: OnSignal) -> std::io::Result<()> {
    Err(std::io::Error::other(
        "the crate is built without its `signals` feature",
    ))
}

/// No process group to kill where there are no Unix signals.
#[cfg(not(unix))]
fn handle_signals(_: OnSignal) -> std::io::Result<()> {
    Ok(())
}
