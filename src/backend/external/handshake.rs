//! The `hello` exchange that opens every process, first or after a fault: kept apart from the
//! running of cases because what fails here is the backend itself (it cannot be started, or
//! speaks another protocol), never the case it was asked.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::capabilities::{check_capabilities, check_codec};
use super::process::{closing, describe_exit, Next, Process};
use super::protocol::{
    BackendInfo, BackendMessage, Capabilities, HarnessMessage, PROTOCOL_VERSION, SUPPORTED_VERSIONS,
};
use super::wire::quote;
use super::{append_stderr, seconds, ExternalErrorKind};
use crate::model::cross_vendor::CodecAbilities;
use crate::model::profile::{Profile, Profiles};
use crate::model::project::ExternalSettings;

/// Starts the process and exchanges `hello`.
pub(super) fn handshake(spec: &ExternalSettings) -> Result<(Process, Greeting), ExternalErrorKind> {
    let mut process = Process::spawn(&spec.launch, spec.cwd.as_ref(), &spec.env)
        .map_err(|e| ExternalErrorKind::Spawn(e.to_string()))?;
    let hello = HarnessMessage::Hello {
        protocol: PROTOCOL_VERSION,
        harness: format!("plc-conformance {}", env!("CARGO_PKG_VERSION")),
    };
    process.send(serde_json::to_vec(&hello).unwrap_or_default());
    let deadline = Instant::now() + spec.startup_timeout;
    let failed = |process: &mut Process, what: String| {
        process.kill();
        let stderr = process.stderr_since(0, Duration::from_millis(300));
        ExternalErrorKind::Handshake(append_stderr(what, &stderr))
    };
    let line = match next_message(&mut process, deadline) {
        // A byte-order mark before hello (some runtimes write one) is not part of the message.
        Next::Line(line) => match line.strip_prefix(b"\xEF\xBB\xBF") {
            Some(rest) => rest.to_vec(),
            None => line,
        },
        Next::Oversized { head, length } => {
            return Err(failed(
                &mut process,
                format!(
                "the answer to hello is a line of {length} bytes, over the limit; it starts: {}",
                quote(&head)
            ),
            ))
        }
        Next::Timeout | Next::Closed(_) if closing() => {
            return Err(failed(
                &mut process,
                "interrupted before it answered hello".into(),
            ))
        }
        Next::Timeout => {
            return Err(failed(
                &mut process,
                format!(
                    "no answer to hello within {}",
                    seconds(spec.startup_timeout)
                ),
            ))
        }
        Next::Closed(why) => {
            let status = process.exit_status(Duration::from_millis(500));
            return Err(failed(
                &mut process,
                format!(
                    "the backend {} before answering hello{}",
                    describe_exit(status),
                    why.map(|w| format!(" ({w})")).unwrap_or_default()
                ),
            ));
        }
    };
    match read_hello(line) {
        Ok(greeting) => Ok((process, greeting)),
        Err(ExternalErrorKind::Handshake(what)) => Err(failed(&mut process, what)),
        // The process is dropped, which kills it.
        Err(kind) => Err(kind),
    }
}

/// Checks a handshake's capabilities against the configuration and the profiles: the profile an
/// instruction-level backend implements, or what a codec-level one does.
pub(super) fn check_greeting(
    spec: &ExternalSettings,
    greeting: &Greeting,
    profiles: &Profiles,
) -> Result<(Option<Arc<Profile>>, Option<CodecAbilities>), ExternalErrorKind> {
    let capabilities = &greeting.capabilities;
    if spec.codec && capabilities.codec.is_none() {
        return Err(ExternalErrorKind::Capabilities(
            "is configured as codec-level but its handshake claims the instruction level".into(),
        ));
    }
    Ok(match &capabilities.codec {
        Some(codec) => (
            None,
            Some(check_codec(spec, capabilities, codec, profiles)?),
        ),
        None => (
            Some(check_capabilities(
                spec,
                capabilities,
                profiles,
                greeting.protocol,
            )?),
            None,
        ),
    })
}

/// What a backend's answer to `hello` says.
pub(super) struct Greeting {
    pub(super) protocol: u32,
    pub(super) info: BackendInfo,
    pub(super) capabilities: Capabilities,
    /// The answer as the backend wrote it.
    pub(super) line: Vec<u8>,
}

/// Reads an answer to `hello`.
pub(super) fn read_hello(line: Vec<u8>) -> Result<Greeting, ExternalErrorKind> {
    // The version is read on its own first, so that a backend of a later protocol version
    // whose hello has other fields is told apart from a broken one.
    let version = serde_json::from_slice::<serde_json::Value>(&line)
        .ok()
        .and_then(|v| v.get("protocol").and_then(serde_json::Value::as_u64));
    if let Some(theirs) =
        version.filter(|v| !SUPPORTED_VERSIONS.iter().any(|s| u64::from(*s) == *v))
    {
        return Err(ExternalErrorKind::Version {
            theirs: u32::try_from(theirs).unwrap_or(u32::MAX),
        });
    }
    match BackendMessage::from_line(&line) {
        Ok(BackendMessage::Hello {
            protocol: 1,
            capabilities: Capabilities { codec: Some(_), .. },
            ..
        }) => Err(ExternalErrorKind::Handshake(
            "answers hello with protocol version 1 but claims the codec level, which is version 2"
                .into(),
        )),
        Ok(BackendMessage::Hello {
            protocol,
            backend,
            capabilities,
        }) => Ok(Greeting {
            protocol,
            info: backend,
            capabilities,
            line,
        }),
        Ok(_) => Err(ExternalErrorKind::Handshake(format!(
            "expected a hello, got: {}",
            quote(&line)
        ))),
        Err(e) => Err(ExternalErrorKind::Handshake(format!(
            "the answer to hello is not a hello message ({e}): {}",
            quote(&line)
        ))),
    }
}

/// The next line that is not blank: blank lines between messages are tolerated, as `serve`
/// tolerates them from the harness.
pub(super) fn next_message(process: &mut Process, deadline: Instant) -> Next {
    loop {
        match process.next_line(deadline) {
            Next::Line(line) if line.iter().all(u8::is_ascii_whitespace) => continue,
            next => return next,
        }
    }
}
