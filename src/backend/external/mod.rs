//! External backends: implementations in another process, spoken to over the JSON-lines
//! protocol of `docs/protocol.md`.
//!
//! An external backend is somebody's emulator, soft-PLC or library, in any language. Everything
//! it can do wrong becomes the outcome of the case it was running, never a pass and never a
//! harness crash: a hang is a timeout, an exit is a crash (and the process is started again for
//! the next case), a line that is not the expected answer is a protocol error that quotes it.
//! What it cannot do at all — start, or agree on the protocol — is an error before any case
//! runs.

mod process;
pub(crate) mod protocol;
pub(crate) mod serve;
pub(crate) mod window;

use std::collections::BTreeMap;
use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::Serialize;

mod convert;

pub(crate) use process::{adopt_orphans, closing, closing_flag, kill_all, MAX_LINE};
use process::{describe_exit, Next, Process};
use protocol::{
    first_version_for, BackendInfo, BackendMessage, Capabilities, CaseRequest, ErrorReport,
    FillName, HarnessMessage, MemoryRange, OperandValue, ProtocolViolation, RunCase, SignalReport,
    PROTOCOL_VERSION, SUPPORTED_VERSIONS,
};

use super::breaker::Breaker;
use super::{Backend, Fault, Outcome, Question, Request, Response, Setting};
use crate::device::Device;
use crate::memory::{Fill, Unit, Value};
use crate::model::cross_vendor::{
    Answer, CodecAbilities, FieldShape, Operation, OperationAbilities, ProtocolClaim,
};
use crate::model::profile::{Profile, Profiles};
use crate::model::project::ExternalSettings;
use crate::model::{ErrorSignal, Operand};

/// How much of an offending line a protocol error quotes.
const QUOTE: usize = 200;

/// Why an external backend cannot be used at all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExternalError {
    pub backend: String,
    pub command: String,
    pub kind: ExternalErrorKind,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExternalErrorKind {
    /// The process could not be started.
    Spawn(String),
    /// It started but did not complete the handshake (with what it wrote to stderr).
    Handshake(String),
    /// It speaks another protocol version.
    Version { theirs: u32 },
    /// Its capabilities do not fit the profiles or the configuration.
    Capabilities(String),
}

impl fmt::Display for ExternalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "external backend `{}` (`{}`): ",
            self.backend, self.command
        )?;
        match &self.kind {
            ExternalErrorKind::Spawn(m) => write!(f, "cannot be started: {m}"),
            ExternalErrorKind::Handshake(m) => write!(f, "handshake failed: {m}"),
            ExternalErrorKind::Version { theirs } => write!(
                f,
                "speaks protocol version {theirs}; this harness speaks versions 1 to \
                 {PROTOCOL_VERSION}"
            ),
            ExternalErrorKind::Capabilities(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for ExternalError {}

impl ExternalError {
    fn of(spec: &ExternalSettings, kind: ExternalErrorKind) -> Self {
        ExternalError {
            backend: spec.name.clone(),
            command: spec.launch.to_string(),
            kind,
        }
    }
}

/// A backend in another process.
pub struct ExternalBackend {
    settings: ExternalSettings,
    info: BackendInfo,
    restarts: std::sync::atomic::AtomicUsize,
    capabilities: Capabilities,
    /// The profile of an instruction-level backend.
    profile: Option<Arc<Profile>>,
    /// What a codec-level backend implements.
    codec: Option<CodecAbilities>,
    /// The protocol version the handshake agreed.
    version: u32,
    /// The answer to `hello`, as the backend wrote it.
    hello: Vec<u8>,
    /// Codec questions still travel in `convert` messages (version 5); cleared when one hangs
    /// or crashes the process.
    converting: std::sync::atomic::AtomicBool,
    state: Mutex<State>,
}

struct State {
    process: Option<Process>,
    next_id: u64,
    /// Set when the process could not be started again after a fault, or after
    /// `max_consecutive_faults` faults in a row (the circuit breaker): every later case gets
    /// this as its fault without another attempt.
    down: Option<String>,
    /// Cases that ended in a fault since the last one answered.
    breaker: Breaker,
}

/// Why the remaining trials of an interrupted run are not run.
const INTERRUPTED: &str = "not run: the run was interrupted";

impl ExternalBackend {
    /// Starts the process and completes the handshake; checks the capabilities against the
    /// profiles and the configured profile family.
    pub fn start(
        spec: ExternalSettings,
        profiles: &Profiles,
    ) -> Result<ExternalBackend, ExternalError> {
        match handshake(&spec) {
            Ok((process, greeting)) => Self::greeted(spec, Some(process), greeting, profiles),
            Err(kind) => Err(ExternalError::of(&spec, kind)),
        }
    }

    /// A backend planned from the answer to `hello` it gave another time (`hello`, as
    /// [`ExternalBackend::hello`] returned it), checked as a live one is, without a process:
    /// what listing trials needs (the cases it declines), never started, every case
    /// unreachable.
    pub(crate) fn planned(
        spec: ExternalSettings,
        hello: &[u8],
        profiles: &Profiles,
    ) -> Result<ExternalBackend, ExternalError> {
        let greeting = read_hello(hello.to_vec()).map_err(|kind| ExternalError::of(&spec, kind))?;
        let backend = Self::greeted(spec, None, greeting, profiles)?;
        if let Ok(mut state) = backend.state.lock() {
            state.down = Some("planned from an earlier handshake, not started".into());
        }
        Ok(backend)
    }

    fn greeted(
        spec: ExternalSettings,
        process: Option<Process>,
        greeting: Greeting,
        profiles: &Profiles,
    ) -> Result<ExternalBackend, ExternalError> {
        // A process whose capabilities are refused is dropped, which kills it.
        let (profile, codec) = check_greeting(&spec, &greeting, profiles)
            .map_err(|kind| ExternalError::of(&spec, kind))?;
        let process = match process {
            Some(process) if !spec.persistent => {
                process.shutdown(shutdown_message());
                None
            }
            process => process,
        };
        let breaker = Breaker::new(spec.max_consecutive_faults);
        Ok(ExternalBackend {
            settings: spec,
            info: greeting.info,
            restarts: std::sync::atomic::AtomicUsize::new(0),
            capabilities: greeting.capabilities,
            profile,
            codec,
            version: greeting.protocol,
            hello: greeting.line,
            converting: std::sync::atomic::AtomicBool::new(true),
            state: Mutex::new(State {
                process,
                next_id: 1,
                down: None,
                breaker,
            }),
        })
    }

    /// The backend's answer to `hello`, as it wrote it: what [`ExternalBackend::planned`]
    /// plans from another time.
    pub(crate) fn hello(&self) -> &[u8] {
        &self.hello
    }

    pub fn settings(&self) -> &ExternalSettings {
        &self.settings
    }

    pub fn info(&self) -> &BackendInfo {
        &self.info
    }

    pub fn capabilities(&self) -> &Capabilities {
        &self.capabilities
    }

    /// Sends `shutdown` and waits for the process to exit.
    pub fn shutdown(&self) {
        if let Ok(mut state) = self.state.lock() {
            if let Some(p) = state.process.take() {
                p.shutdown(shutdown_message());
            }
        }
    }

    /// Runs one batch of case requests, restarting the process after each fault and resending
    /// the cases after the faulty one. `sent`: the batch is already queued to the running
    /// process. `ahead` queues the next batch once this one is sent, before its answers are
    /// read; the returned flag says whether that next batch is still queued to a live process
    /// (a fault here kills the process it went to).
    fn run_chunk(
        &self,
        state: &mut State,
        cases: &[RunCase],
        mut sent: bool,
        mut ahead: impl FnMut(&mut Process) -> bool,
        answered: &mut dyn FnMut(usize),
    ) -> (Vec<Result<Response, Fault>>, bool) {
        let mut results: Vec<Result<Response, Fault>> = Vec::with_capacity(cases.len());
        let mut ahead_sent = false;
        while results.len() < cases.len() {
            let rest = &cases[results.len()..];
            if let Some(why) = &state.down {
                results.extend(rest.iter().map(|_| Err(Fault::Unreachable(why.clone()))));
                break;
            }
            if state.process.is_none() {
                sent = false;
                self.start_again(state);
            }
            let Some(process) = state.process.as_mut() else {
                continue;
            };
            let mark = process.stderr_mark();
            if !std::mem::take(&mut sent) {
                process.send(run_message(rest));
            }
            if !ahead_sent {
                ahead_sent = ahead(process);
            }
            let mut deadline = Instant::now() + self.settings.timeout;
            for case in rest {
                match self.answer(process, case, deadline) {
                    Ok(response) => {
                        results.push(Ok(response));
                        answered(results.len());
                        state.breaker.answered();
                        deadline = Instant::now() + self.settings.timeout;
                    }
                    Err(fault) => {
                        let mut process = state.process.take();
                        let stderr = process.as_mut().map_or_else(String::new, |p| {
                            p.kill();
                            p.stderr_since(mark, Duration::from_millis(300))
                        });
                        ahead_sent = false;
                        let tripped = state.breaker.trips(&self.settings.name, &fault);
                        if closing() {
                            state.down = Some(INTERRUPTED.into());
                        } else if tripped.is_some() {
                            state.down = tripped;
                        }
                        results.push(Err(with_stderr(fault, &stderr)));
                        answered(results.len());
                        break;
                    }
                }
            }
        }
        if !self.settings.persistent {
            if let Some(p) = state.process.take() {
                p.shutdown(shutdown_message());
            }
        }
        (results, ahead_sent && state.process.is_some())
    }

    /// Starts the process again after a fault ended it. When it cannot be started (or the run
    /// is being interrupted) the backend is down: every later case gets the reason as its
    /// fault, without another attempt.
    fn start_again(&self, state: &mut State) {
        if state.process.is_some() || state.down.is_some() {
            return;
        }
        match handshake(&self.settings) {
            Ok((p, _)) => {
                if self.settings.persistent {
                    self.restarts
                        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
                state.process = Some(p);
            }
            Err(_) if closing() => state.down = Some(INTERRUPTED.into()),
            Err(kind) => {
                state.down = Some(format!(
                    "could not be started again: {}",
                    ExternalError::of(&self.settings, kind)
                ));
            }
        }
    }

    /// Reads the answer to one case.
    fn answer(
        &self,
        process: &mut Process,
        case: &RunCase,
        deadline: Instant,
    ) -> Result<Response, Fault> {
        let which = || format!("request {} (case {})", case.id(), case.case());
        let line = match next_message(process, deadline) {
            Next::Line(line) => line,
            Next::Oversized { head, length } => {
                return Err(Fault::Protocol(format!(
                    "while waiting for the answer to {}: a line of {length} bytes, over the \
                     {} KiB limit; it starts: {}",
                    which(),
                    MAX_LINE / 1024,
                    quote(&head)
                )))
            }
            Next::Timeout | Next::Closed(_) if closing() => {
                return Err(Fault::Unreachable(INTERRUPTED.into()))
            }
            Next::Timeout => {
                return Err(Fault::Timeout(format!(
                    "no answer to {} within {}",
                    which(),
                    seconds(self.settings.timeout)
                )))
            }
            Next::Closed(why) => {
                let status = process.exit_status(Duration::from_millis(500));
                return Err(Fault::Crashed(format!(
                    "the backend {} while running {}{}",
                    describe_exit(status),
                    which(),
                    why.map(|w| format!(" ({w})")).unwrap_or_default()
                )));
            }
        };
        let message = BackendMessage::from_line(&line).map_err(|e| {
            Fault::Protocol(format!(
                "the answer to {} is not a protocol message ({e}): {}",
                which(),
                quote(&line)
            ))
        })?;
        let unexpected = |what: String| {
            Fault::Protocol(format!(
                "while waiting for the answer to {}: {what}: {}",
                which(),
                quote(&line)
            ))
        };
        match message {
            BackendMessage::Result {
                id,
                memory,
                writes,
                error,
                value,
                text,
                accepted,
            } if id == case.id() => match case {
                RunCase::Instruction(case)
                    if value.is_none() && text.is_none() && accepted.is_none() =>
                {
                    let unit = self.profile.as_ref().map_or(Unit::Word, |p| p.unit);
                    let registers = self
                        .profile
                        .as_ref()
                        .map_or_else(Vec::new, |p| p.errors.code_registers());
                    outcome(case, unit, memory, writes, error)
                        .map(|o| Response::Done(o.registers_from_writes(&registers)))
                        .map_err(|e| unexpected(e.0))
                }
                RunCase::Instruction(_) => Err(unexpected(
                    "a codec answer (`value`, `text` or `accepted`) to an instruction request"
                        .into(),
                )),
                RunCase::Codec(_) => codec_answer(memory, writes, error, value, text, accepted)
                    .map(Response::Answer)
                    .map_err(|e| unexpected(e.0)),
            },
            BackendMessage::Unsupported { id, reason } if id == case.id() => {
                Ok(Response::Unsupported(reason))
            }
            BackendMessage::Result { id, .. } | BackendMessage::Unsupported { id, .. } => {
                Err(unexpected(format!("an answer for request {id}")))
            }
            BackendMessage::Hello { .. } => {
                Err(unexpected("a hello in the middle of a run".into()))
            }
            BackendMessage::Converted { id, .. } => Err(unexpected(format!(
                "a `converted` line (for message {id}) where a case's answer was due"
            ))),
        }
    }
}

impl Drop for ExternalBackend {
    fn drop(&mut self) {
        self.shutdown();
    }
}

impl Backend for ExternalBackend {
    fn name(&self) -> &str {
        &self.settings.name
    }

    fn profile(&self) -> &str {
        &self.capabilities.profile
    }

    /// Several `run` messages' worth (its `batch` cases each), so that the next message is
    /// queued while the current one is answered (`send_all`).
    fn chunk_trials(&self) -> usize {
        self.settings.batch.max(1) * 4
    }

    fn codec(&self) -> Option<&CodecAbilities> {
        self.codec.as_ref()
    }

    fn convert_batch(
        &self,
        questions: &[Question<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        // A `convert` message carries conversions only: a protocol field's question (its
        // field, a check) travels in `run` messages.
        if self.converts() && questions.iter().all(|q| q.field.is_empty()) {
            return self.convert_all(questions, answered);
        }
        self.send_all(questions.len(), answered, |i, id| {
            convert::codec_case(&questions[i], id)
        })
    }

    fn describe(&self) -> String {
        format!(
            "external: {} {} (`{}`)",
            self.info.name, self.info.version, self.settings.launch
        )
    }

    fn version(&self) -> Option<String> {
        Some(format!("{} {}", self.info.name, self.info.version))
    }

    fn claims(&self, instruction: &str, variant: &str) -> bool {
        let Some(profile) = &self.profile else {
            return false;
        };
        self.capabilities
            .instructions
            .iter()
            .any(|i| i == instruction)
            && self
                .capabilities
                .variants
                .as_ref()
                .is_none_or(|v| v.iter().any(|v| v == variant))
            && profile
                .variant(variant)
                .is_some_and(|v| profile.has_instruction(v, instruction))
    }

    fn declines(&self, setting: &Setting<'_>) -> Option<String> {
        let profile = self.profile.as_ref()?;
        let reads = &profile.instructions.get(setting.instruction)?.flags;
        let name = &self.settings.name;
        let flag = self
            .capabilities
            .flags
            .iter()
            .filter(|(flag, _)| reads.contains(flag))
            .find_map(|(flag, settings)| {
                let value = profile.flag_seen(setting.variant, setting.flags, flag);
                (!settings.contains(&value)).then(|| {
                    format!(
                        "{name} does not implement {flag} {}",
                        if value { "on" } else { "off" }
                    )
                })
            });
        flag.or_else(|| {
            setting.operands.iter().find_map(|(op, value)| {
                let caps = self.capabilities.operands.get(op)?;
                match value {
                    Operand::Constant(k) => caps
                        .constants
                        .as_ref()
                        .filter(|list| !list.contains(k))
                        .map(|_| format!("{name} does not implement operand {op} as K{k}")),
                    Operand::Device(d) => caps
                        .devices
                        .as_ref()
                        .filter(|list| !list.iter().any(|c| c == d.code()))
                        .map(|_| {
                            format!(
                                "{name} does not implement operand {op} as a {} device",
                                d.code()
                            )
                        }),
                }
            })
        })
    }

    fn checks_device_ranges(&self) -> bool {
        self.capabilities.device_ranges.unwrap_or(true)
    }

    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        self.execute_batch(std::slice::from_ref(request), &mut |_| {})
            .pop()
            .unwrap_or_else(|| Err(Fault::Protocol("no answer".into())))
    }

    fn restarts(&self) -> usize {
        self.restarts.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn execute_batch(
        &self,
        requests: &[Request<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        self.send_all(requests.len(), answered, |i, id| {
            RunCase::Instruction(case_request(&requests[i], id))
        })
    }
}

impl ExternalBackend {
    /// Sends `count` requests in batches and reads their answers; `make(i, id)` builds the
    /// `i`-th with its id. A persistent process gets the next batch as soon as the current one
    /// is sent, built while the process works on the current one: both sides stay busy, where
    /// sending a batch only once the last is answered would leave each waiting on the other.
    /// `answered` hears of every answer as it is read.
    fn send_all(
        &self,
        count: usize,
        answered: &mut dyn FnMut(usize),
        make: impl Fn(usize, u64) -> RunCase,
    ) -> Vec<Result<Response, Fault>> {
        let mut state = match self.state.lock() {
            Ok(s) => s,
            Err(poisoned) => poisoned.into_inner(),
        };
        let first_id = state.next_id;
        state.next_id += count as u64;
        let size = if self.settings.persistent {
            self.settings.batch.max(1)
        } else {
            1
        };
        let build = |k: usize| -> Vec<RunCase> {
            (k * size..((k + 1) * size).min(count))
                .map(|i| make(i, first_id + i as u64))
                .collect()
        };
        let batches = count.div_ceil(size);
        let mut results = Vec::with_capacity(count);
        let mut next: Option<Vec<RunCase>> = None;
        let mut sent = false;
        for k in 0..batches {
            let cases = next.take().unwrap_or_else(|| build(k));
            let mut ahead: Option<Vec<RunCase>> = None;
            let pipelined = self.settings.persistent && k + 1 < batches;
            let done = results.len();
            let (answers, ahead_sent) = self.run_chunk(
                &mut state,
                &cases,
                sent,
                |process: &mut Process| {
                    if !pipelined {
                        return false;
                    }
                    process.send(run_message(ahead.get_or_insert_with(|| build(k + 1))));
                    true
                },
                &mut |n| answered(done + n),
            );
            results.extend(answers);
            sent = ahead_sent;
            next = ahead;
        }
        results
    }
}

/// Starts the process and exchanges `hello`.
fn handshake(spec: &ExternalSettings) -> Result<(Process, Greeting), ExternalErrorKind> {
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
fn check_greeting(
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
struct Greeting {
    protocol: u32,
    info: BackendInfo,
    capabilities: Capabilities,
    /// The answer as the backend wrote it.
    line: Vec<u8>,
}

/// Reads an answer to `hello`.
fn read_hello(line: Vec<u8>) -> Result<Greeting, ExternalErrorKind> {
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
fn next_message(process: &mut Process, deadline: Instant) -> Next {
    loop {
        match process.next_line(deadline) {
            Next::Line(line) if line.iter().all(u8::is_ascii_whitespace) => continue,
            next => return next,
        }
    }
}

/// Checks a codec-level handshake: no instruction-level claims beside it, no profile configured,
/// every digit count and width one a field can have (each count once), and a declared reading
/// one of the built-in lowerings of its operation (`fx5/hexa-16bit`).
fn check_codec(
    spec: &ExternalSettings,
    caps: &Capabilities,
    codec: &protocol::CodecCapabilities,
    profiles: &Profiles,
) -> Result<CodecAbilities, ExternalErrorKind> {
    if let Some(configured) = &spec.profile {
        return Err(ExternalErrorKind::Capabilities(format!(
            "is configured as implementing profile `{configured}` but its handshake claims the \
             codec level; leave `profile` out for a codec-level backend"
        )));
    }
    if !caps.profile.is_empty()
        || !caps.instructions.is_empty()
        || caps.variants.is_some()
        || !caps.flags.is_empty()
        || !caps.operands.is_empty()
        || caps.device_ranges.is_some()
    {
        return Err(ExternalErrorKind::Capabilities(
            "claims the codec level and instruction-level capabilities at once; give either \
             `codec` or `profile` and `instructions`"
                .into(),
        ));
    }
    let refuse = |why: String| Err(ExternalErrorKind::Capabilities(why));
    let ability = |operation: Operation, c: &Option<protocol::OperationCapabilities>| match c {
        None => Ok(None),
        Some(c) => {
            let name = operation.to_string();
            let width = c.width.unwrap_or(16);
            if width != 16 && width != 32 {
                return refuse(format!("claims {name} of width {width}; give 16 or 32"));
            }
            if let Some(digits) = &c.digits {
                if digits.is_empty() {
                    return refuse(format!(
                        "claims {name} of no digit count (`digits: []`); list the counts it \
                         reads, or leave `digits` out for any"
                    ));
                }
                if let Some(d) = digits.iter().find(|d| !(1..=16).contains(*d)) {
                    return refuse(format!(
                        "claims {name} of {d} digits; give counts from 1 to 16"
                    ));
                }
                let mut sorted = digits.clone();
                sorted.sort_unstable();
                if let Some(d) = sorted.windows(2).find(|w| w[0] == w[1]) {
                    return refuse(format!("claims {name} of {} digits twice", d[0]));
                }
            }
            if c.widths.as_ref().is_some_and(|w| w.is_empty()) {
                return refuse(format!(
                    "claims {name} widths for no digit count (`widths: {{}}`); map counts to \
                     widths, or leave `widths` out"
                ));
            }
            let mut widths = std::collections::BTreeMap::new();
            for (d, w) in c.widths.iter().flatten() {
                let count = d.parse::<u32>().ok().filter(|n| (1..=16).contains(n));
                let Some(count) = count.filter(|n| n.to_string() == *d) else {
                    return refuse(format!(
                        "claims {name} widths for `{d}` digits; give a count from 1 to 16, \
                         written as a plain number"
                    ));
                };
                if ![8, 16, 32].contains(w) {
                    return refuse(format!(
                        "claims {name} of width {w} for {count} digits; give 8, 16 or 32"
                    ));
                }
                widths.insert(count, *w);
            }
            if c.blanks_between_pairs == Some(true) && operation == Operation::ValueToHex {
                return refuse(format!(
                    "claims {name} skips blanks between byte pairs; only a text is read, so \
                     give `blanks-between-pairs` for hex-to-value"
                ));
            }
            if let Some(reading) = &c.reading {
                let readings: Vec<String> = (profiles.iter())
                    .flat_map(|p| {
                        (p.cross_vendor.lowerings.iter())
                            .filter(|l| l.operation == operation)
                            .map(|l| l.key.clone())
                    })
                    .collect();
                if !readings.contains(reading) {
                    return refuse(format!(
                        "declares {name} reading `{reading}`, which is not a built-in reading; \
                         the readings are: {}",
                        readings.join(", ")
                    ));
                }
            }
            Ok(Some(OperationAbilities {
                digits: c.digits.clone(),
                width,
                reading: c.reading.clone(),
                shape: FieldShape {
                    widths,
                    variable: c.variable.unwrap_or(false),
                    leading_zeros: c.leading_zeros.unwrap_or(true),
                    low_byte_first: c.byte_order == Some(protocol::ByteOrder::LowFirst),
                    whole_frame: c.whole_frame.unwrap_or(false),
                    blanks_between_pairs: c.blanks_between_pairs.unwrap_or(false),
                },
            }))
        }
    };
    let abilities = CodecAbilities {
        hex_to_value: ability(Operation::HexToValue, &codec.hex_to_value)?,
        value_to_hex: ability(Operation::ValueToHex, &codec.value_to_hex)?,
        check: ability(Operation::Check, &codec.check)?,
        verify: ability(Operation::Verify, &codec.verify)?,
        protocol: protocol_claim(spec, codec, profiles)?,
    };
    if [
        Operation::HexToValue,
        Operation::ValueToHex,
        Operation::Check,
        Operation::Verify,
    ]
    .iter()
    .all(|o| abilities.of(*o).is_none())
    {
        return Err(ExternalErrorKind::Capabilities(
            "claims the codec level but no operation".into(),
        ));
    }
    Ok(abilities)
}

/// Checks a codec's protocol: one a protocol profile defines, the one its configuration names
/// (a backend planned before it starts is planned by that), with fields the profile has.
fn protocol_claim(
    spec: &ExternalSettings,
    codec: &protocol::CodecCapabilities,
    profiles: &Profiles,
) -> Result<Option<ProtocolClaim>, ExternalErrorKind> {
    let refuse = |why: String| Err(ExternalErrorKind::Capabilities(why));
    let Some(id) = &codec.protocol else {
        if codec.fields.is_some() || codec.cross_vendor.is_some() {
            return refuse(
                "gives `fields` or `cross-vendor` but no `protocol`; name the protocol whose \
                 fields it implements"
                    .into(),
            );
        }
        if let Some(configured) = &spec.protocol {
            return refuse(format!(
                "is configured as implementing protocol `{configured}` but its handshake names \
                 no protocol"
            ));
        }
        if codec.check.is_some() || codec.verify.is_some() {
            return refuse(
                "claims `check` or `verify` but no `protocol`: a check character is a \
                 protocol's"
                    .into(),
            );
        }
        return Ok(None);
    };
    let Some(found) = profiles.protocols.get(id) else {
        return refuse(format!(
            "names protocol `{id}`, which no protocol profile defines; the protocols are: {}",
            profiles.protocols.ids().join(", ")
        ));
    };
    match &spec.protocol {
        Some(configured) if configured != id => {
            return refuse(format!(
                "is configured as implementing protocol `{configured}` but its handshake names \
                 `{id}`"
            ))
        }
        None if spec.codec => {
            return refuse(format!(
                "names protocol `{id}` but its configuration does not: add `protocol: {id}` to \
                 its entry in the project file, so that its trials are planned by that protocol"
            ))
        }
        _ => {}
    }
    let cross_vendor = codec.cross_vendor.unwrap_or(false);
    if spec.protocol.is_some() && cross_vendor != spec.cross_vendor {
        return refuse(format!(
            "asks for the cross-vendor view {} but its configuration {}; make `cross_vendor` in \
             the project file and `cross-vendor` in the handshake agree",
            if cross_vendor { "too" } else { "not" },
            if spec.cross_vendor {
                "does"
            } else {
                "does not"
            }
        ));
    }
    if let Some(fields) = &codec.fields {
        if fields.is_empty() {
            return refuse(format!(
                "implements no field of {id} (`fields: []`); list them, or leave `fields` out for \
                 every one"
            ));
        }
        if let Some(unknown) = fields.iter().find(|f| !found.fields.contains_key(*f)) {
            let known: Vec<&str> = found.fields.keys().map(String::as_str).collect();
            return refuse(format!(
                "claims field `{unknown}` of {id}, which has: {}",
                known.join(", ")
            ));
        }
    }
    Ok(Some(ProtocolClaim {
        id: id.clone(),
        fields: codec.fields.clone(),
        cross_vendor,
    }))
}

/// Checks a handshake's capabilities against the profiles and the configured family.
fn check_capabilities(
    spec: &ExternalSettings,
    caps: &Capabilities,
    profiles: &Profiles,
    version: u32,
) -> Result<Arc<Profile>, ExternalErrorKind> {
    if let Some(configured) = &spec.profile {
        if configured != &caps.profile {
            return Err(ExternalErrorKind::Capabilities(format!(
                "is configured as implementing profile `{configured}` but its handshake claims `{}`",
                caps.profile
            )));
        }
    }
    let profile = profiles.get(&caps.profile).ok_or_else(|| {
        ExternalErrorKind::Capabilities(format!(
            "claims profile `{}`, which is not loaded; known profiles: {}",
            caps.profile,
            profiles.ids().join(", ")
        ))
    })?;
    let needs = first_version_for(profile.unit);
    if version < needs {
        return Err(ExternalErrorKind::Capabilities(format!(
            "answers hello with protocol version {version}, but profile `{}`'s memory unit is a \
             {}: its memory ranges carry `{}`, which needs version {needs}",
            profile.id,
            profile.unit.name(),
            MemoryRange::field(profile.unit)
        )));
    }
    let unknown = |what: &str, name: &str, known: Vec<String>| {
        format!(
            "claims {what} `{name}`, which profile `{}` does not define; it defines: {}",
            profile.id,
            known.join(", ")
        )
    };
    for i in &caps.instructions {
        if !profile.instructions.contains_key(i) {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "instruction",
                i,
                profile.instructions.keys().cloned().collect(),
            )));
        }
    }
    for v in caps.variants.iter().flatten() {
        if profile.variant(v).is_none() {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "variant",
                v,
                profile.variants.iter().map(|v| v.id.clone()).collect(),
            )));
        }
    }
    for (op, forms) in &caps.operands {
        let claimed = caps.instructions.iter().any(|i| {
            profile
                .instructions
                .get(i)
                .is_some_and(|d| d.operands.contains_key(op))
        });
        if !claimed {
            return Err(ExternalErrorKind::Capabilities(format!(
                "claims forms of operand `{op}`, which no instruction it claims has"
            )));
        }
        for code in forms.devices.iter().flatten() {
            if !profile.devices.contains_key(code) {
                return Err(ExternalErrorKind::Capabilities(unknown(
                    "device",
                    code,
                    profile.devices.keys().cloned().collect(),
                )));
            }
        }
    }
    for (f, settings) in &caps.flags {
        if !profile.flags.contains_key(f) {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "flag",
                f,
                profile.flags.keys().cloned().collect(),
            )));
        }
        if settings.is_empty() {
            return Err(ExternalErrorKind::Capabilities(format!(
                "lists no setting for flag `{f}`; leave a flag out to claim both settings"
            )));
        }
    }
    Ok(profile.clone())
}

/// The request for one case: everything the backend needs, fill included.
pub(crate) fn case_request(req: &Request<'_>, id: u64) -> CaseRequest {
    let ignored_flags = req
        .variant
        .ignores_flags
        .iter()
        .map(|f| (f.clone(), req.profile.flag_default(f)))
        .collect();
    CaseRequest {
        id,
        case: req.case_id.to_string(),
        instruction: req.instruction.to_string(),
        profile: req.profile.id.clone(),
        variant: req.variant.id.clone(),
        flags: req.all_flags(),
        ignored_flags,
        operands: req
            .operands
            .iter()
            .map(|(k, v)| {
                let value = match (v, req.indirect.get(k)) {
                    (Operand::Device(_), Some(pointer)) => {
                        OperandValue::Device(format!("@{pointer}"))
                    }
                    (Operand::Device(d), None) => OperandValue::Device(d.to_string()),
                    (Operand::Constant(k), _) => OperandValue::Constant(*k),
                };
                (k.clone(), value)
            })
            .collect(),
        addresses: req
            .indirect
            .iter()
            .filter_map(|(name, pointer)| match req.operands.get(name) {
                Some(Operand::Device(d)) => Some((pointer.to_string(), d.to_string())),
                _ => None,
            })
            .collect(),
        fill: match req.memory.fill() {
            Fill::A => FillName::A,
            Fill::B => FillName::B,
        },
        memory: window::memory(req),
        hexadecimal: req.profile.devices.hexadecimal_codes(),
    }
}

/// Turns a `result` into an outcome: every reported word is a write, except words of `memory`
/// that kept their value (an echoed window is not a list of writes).
fn outcome(
    case: &CaseRequest,
    unit: Unit,
    memory: Vec<MemoryRange>,
    writes: BTreeMap<String, Value>,
    error: Option<ErrorReport>,
) -> Result<Outcome, ProtocolViolation> {
    let device = |name: &str| {
        case.device(name)
            .map_err(|e| ProtocolViolation(format!("bad device in the answer: {e}")))
    };
    // Only an echoed window needs the words before; a list of writes is taken as it is.
    let before: BTreeMap<Device, Value> = if memory.is_empty() {
        BTreeMap::new()
    } else {
        case.memory
            .iter()
            .filter_map(|r| {
                let start = case.device(&r.start).ok()?;
                Some((start, r.values(unit).ok()?))
            })
            .flat_map(|(d, values)| {
                values
                    .into_iter()
                    .enumerate()
                    .filter_map(move |(i, w)| d.offset(i as u32).map(|d| (d, w)))
            })
            .collect()
    };
    let mut out = Outcome::default();
    // A pointer's words hold the address in the backend's own encoding: not judged.
    let pointers = case.pointer_words();
    // One word given two values in one answer is no answer: which one would count?
    let mut in_memory: BTreeMap<Device, String> = BTreeMap::new();
    for range in memory {
        let start = device(&range.start)?;
        for (i, word) in range.values(unit)?.into_iter().enumerate() {
            let d = start.offset(i as u32).ok_or_else(|| {
                ProtocolViolation(format!(
                    "memory from {start} runs past the last device number"
                ))
            })?;
            if let Some(first) = in_memory.insert(d.clone(), range.start.clone()) {
                return Err(ProtocolViolation(format!(
                    "{d} is given twice in `memory` (in the ranges from {first} and from {})",
                    range.start
                )));
            }
            if before.get(&d) != Some(&word) && !pointers.contains(&d) {
                out.writes.insert(d, word);
            }
        }
    }
    let mut in_writes: BTreeMap<Device, String> = BTreeMap::new();
    for (name, word) in writes {
        let d = device(&name)?;
        if word > unit.max() {
            return Err(ProtocolViolation(format!(
                "`{name}` in `writes` is {word}, past a {} ({} at most)",
                unit.name(),
                unit.max()
            )));
        }
        if let Some(first) = in_writes.insert(d.clone(), name.clone()) {
            return Err(ProtocolViolation(format!(
                "`{first}` and `{name}` in `writes` are the same word, {d}"
            )));
        }
        if !pointers.contains(&d) {
            out.writes.insert(d, word);
        }
    }
    out.error = match error {
        None => None,
        Some(ErrorReport::Signal(SignalReport::Code(c))) => Some(ErrorSignal::Code(c)),
        Some(ErrorReport::Signal(SignalReport::Flag(f))) => Some(ErrorSignal::Flag(device(&f)?)),
        Some(ErrorReport::Class(c)) => {
            return Err(ProtocolViolation(format!(
                "an error class (`{c}`) answers a codec question, not an instruction request"
            )))
        }
    };
    Ok(out)
}

/// A codec answer: exactly one of a value, a text or an error class, and nothing of the
/// instruction level.
fn codec_answer(
    memory: Vec<MemoryRange>,
    writes: BTreeMap<String, Value>,
    error: Option<ErrorReport>,
    value: Option<i64>,
    text: Option<Vec<u8>>,
    accepted: Option<bool>,
) -> Result<Answer, ProtocolViolation> {
    if !memory.is_empty() || !writes.is_empty() {
        return Err(ProtocolViolation(
            "`memory` or `writes` in the answer to a codec question".into(),
        ));
    }
    match accepted {
        Some(true) if value.is_none() && text.is_none() && error.is_none() => {
            return Ok(Answer::Accepted)
        }
        Some(true) => {
            return Err(ProtocolViolation(
                "`accepted` and a `value`, `text` or `error` in one codec answer".into(),
            ))
        }
        Some(false) => {
            return Err(ProtocolViolation(
                "`accepted: false` in a codec answer; a mismatch is `\"error\": \"bad-check\"`"
                    .into(),
            ))
        }
        None => {}
    }
    match (value, text, error) {
        // A negative value (some libraries return one) is an answer that differs, not garbage.
        (Some(v), None, None) => Ok(Answer::Value(v as u64)),
        (None, Some(t), None) => Ok(Answer::Text(
            t.into_iter().take_while(|b| *b != 0).collect(),
        )),
        (None, None, Some(ErrorReport::Class(c))) => Ok(Answer::Error(c)),
        (None, None, Some(ErrorReport::Signal(_))) => Err(ProtocolViolation(
            "a vendor's error signal answers a codec question; give an error class".into(),
        )),
        (None, None, None) => Err(ProtocolViolation(
            "no `value`, `text` or `error` in a codec answer".into(),
        )),
        _ => Err(ProtocolViolation(
            "more than one of `value`, `text` and `error` in a codec answer".into(),
        )),
    }
}

fn run_message(cases: &[RunCase]) -> Vec<u8> {
    #[derive(Serialize)]
    struct Run<'a> {
        #[serde(rename = "type")]
        kind: &'static str,
        cases: &'a [RunCase],
    }
    // Sized for the usual request, so that neither the encoding nor the newline reallocates.
    let mut out = Vec::with_capacity(cases.len() * 1536 + 64);
    match serde_json::to_writer(&mut out, &Run { kind: "run", cases }) {
        Ok(()) => out,
        Err(_) => Vec::new(),
    }
}

fn shutdown_message() -> Vec<u8> {
    serde_json::to_vec(&HarnessMessage::Shutdown).unwrap_or_default()
}

/// A line as a protocol error shows it: lossy UTF-8, cut at [`QUOTE`] characters.
fn quote(line: &[u8]) -> String {
    let text = String::from_utf8_lossy(line);
    let mut chars = text.chars();
    let shown: String = chars.by_ref().take(QUOTE).collect();
    if chars.next().is_some() {
        format!("`{shown}`… ({} bytes)", line.len())
    } else {
        format!("`{shown}`")
    }
}

fn seconds(d: Duration) -> String {
    format!("{} s", d.as_secs_f64())
}

fn append_stderr(mut text: String, stderr: &str) -> String {
    let stderr = stderr.trim_end();
    if !stderr.is_empty() {
        text.push_str("\n    backend stderr:");
        for line in stderr.lines() {
            text.push_str("\n    | ");
            text.push_str(line);
        }
    }
    text
}

fn with_stderr(fault: Fault, stderr: &str) -> Fault {
    match fault {
        Fault::Crashed(s) => Fault::Crashed(append_stderr(s, stderr)),
        Fault::Timeout(s) => Fault::Timeout(append_stderr(s, stderr)),
        Fault::Protocol(s) => Fault::Protocol(append_stderr(s, stderr)),
        Fault::Unreachable(s) => Fault::Unreachable(append_stderr(s, stderr)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> CaseRequest {
        CaseRequest {
            id: 1,
            case: "c".into(),
            instruction: "HABIN".into(),
            profile: "mitsubishi-iqr".into(),
            variant: "rcpu".into(),
            flags: BTreeMap::new(),
            ignored_flags: BTreeMap::new(),
            operands: BTreeMap::new(),
            addresses: BTreeMap::new(),
            fill: FillName::A,
            memory: vec![MemoryRange::new("D200".into(), Unit::Word, vec![0, 0])],
            hexadecimal: Vec::new(),
        }
    }

    /// The words of a pointer hold an address the backend encodes its own way: an answer
    /// that echoes them changed, or lists them as writes, says nothing the case can judge.
    #[test]
    fn an_answer_for_the_pointer_words_is_not_judged() {
        let mut case = request();
        case.operands
            .insert("s".into(), OperandValue::Device("@D10".into()));
        case.addresses.insert("D10".into(), "D100".into());
        assert_eq!(
            case.operand_device("@D10"),
            Ok((Device::new("D", 100), Some(Device::new("D", 10))))
        );
        assert!(case.operand_device("@D12").is_err(), "no address for D12");
        let writes = BTreeMap::from([
            ("D10".to_string(), 0x0064),
            ("D11".to_string(), 0),
            ("D12".to_string(), 7),
        ]);
        let out = outcome(&case, Unit::Word, Vec::new(), writes, None).expect("outcome");
        assert_eq!(out.writes, BTreeMap::from([(Device::new("D", 12), 7)]));
        let echoed = vec![
            MemoryRange::new("D10".into(), Unit::Word, vec![0x0064, 0]),
            MemoryRange::new("D200".into(), Unit::Word, vec![0, 5]),
        ];
        let out = outcome(&case, Unit::Word, echoed, BTreeMap::new(), None).expect("outcome");
        assert_eq!(out.writes, BTreeMap::from([(Device::new("D", 201), 5)]));
    }

    /// A code the request lists as hexadecimal is read so in the answer: `W1A` is the word
    /// after `W19`, and `W10` is W 16.
    #[test]
    fn an_answer_names_hexadecimal_devices_as_the_request_does() {
        let mut case = request();
        case.hexadecimal = vec!["W".into()];
        case.memory = vec![MemoryRange::new("W19".into(), Unit::Word, vec![0, 0])];
        let writes = BTreeMap::from([("W1A".to_string(), 7), ("D10".to_string(), 8)]);
        let o = outcome(&case, Unit::Word, Vec::new(), writes, None).expect("an outcome");
        assert_eq!(
            o.writes,
            BTreeMap::from([(Device::hexadecimal("W", 26), 7), (Device::new("D", 10), 8)])
        );
        let echoed = vec![MemoryRange::new("W19".into(), Unit::Word, vec![0, 5])];
        let o = outcome(&case, Unit::Word, echoed, BTreeMap::new(), None).expect("an outcome");
        assert_eq!(
            o.writes,
            BTreeMap::from([(Device::hexadecimal("W", 26), 5)])
        );
        let bad = BTreeMap::from([("W1G".to_string(), 7)]);
        assert!(outcome(&case, Unit::Word, Vec::new(), bad, None).is_err());
    }

    #[test]
    fn one_word_given_two_values_is_no_answer() {
        let range =
            |start: &str, words: Vec<Value>| MemoryRange::new(start.into(), Unit::Word, words);
        let e = outcome(
            &request(),
            Unit::Word,
            vec![range("D200", vec![1, 2]), range("D201", vec![3])],
            BTreeMap::new(),
            None,
        )
        .expect_err("two ranges over D201");
        assert!(e.0.contains("D201 is given twice in `memory`"), "{e}");
        let writes = BTreeMap::from([("D200".to_string(), 1), ("D0200".to_string(), 2)]);
        let e =
            outcome(&request(), Unit::Word, Vec::new(), writes, None).expect_err("D200 and D0200");
        assert!(
            e.0.contains("`D0200` and `D200` in `writes` are the same word, D200"),
            "{e}"
        );
        // `writes` wins over `memory` for a word in both, as documented.
        let writes = BTreeMap::from([("D200".to_string(), 7)]);
        let o = outcome(
            &request(),
            Unit::Word,
            vec![range("D200", vec![1])],
            writes,
            None,
        )
        .expect("ok");
        assert_eq!(o.writes.values().copied().collect::<Vec<_>>(), vec![7]);
    }

    /// A value past what the family's unit holds is no answer, and a range in another unit's
    /// field is refused with the field to use.
    #[test]
    fn a_value_wider_than_the_unit_is_no_answer() {
        let writes = BTreeMap::from([("D200".to_string(), 0x1_0000)]);
        let e = outcome(&request(), Unit::Word, Vec::new(), writes, None).expect_err("17 bits");
        assert!(
            e.0.contains("`D200` in `writes` is 65536, past a word"),
            "{e}"
        );
        let writes = BTreeMap::from([("D200".to_string(), 0x1_0000)]);
        outcome(&request(), Unit::Dword, Vec::new(), writes, None).expect("a 32-bit unit");
        let dwords = MemoryRange::new("D200".into(), Unit::Dword, vec![0x8000_0000]);
        let e = dwords
            .values(Unit::Word)
            .expect_err("dwords in word memory");
        assert!(e
            .0
            .contains("gives `dwords`, but the family's unit is a word: give `words`"));
        assert_eq!(
            dwords.values(Unit::Dword).expect("dwords"),
            vec![0x8000_0000]
        );
    }
}
