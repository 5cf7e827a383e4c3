//! External backends: implementations in another process, spoken to over the JSON-lines
//! protocol of `docs/protocol.md`.
//!
//! An external backend is somebody's emulator, soft-PLC or library, in any language. Everything
//! it can do wrong becomes the outcome of the case it was running, never a pass and never a
//! harness crash: a hang is a timeout, an exit is a crash (and the process is started again for
//! the next case), a line that is not the expected answer is a protocol error that quotes it.
//! What it cannot do at all — start, or agree on the protocol — is an error before any case
//! runs.

mod capabilities;
mod handshake;
mod process;
pub(crate) mod protocol;
pub(crate) mod serve;
pub(crate) mod window;
mod wire;

use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod convert;

use handshake::{check_greeting, handshake, next_message, read_hello, Greeting};
pub(crate) use process::{adopt_orphans, closing, closing_flag, kill_all, MAX_LINE};
use process::{describe_exit, Next, Process};
use protocol::{BackendInfo, BackendMessage, Capabilities, RunCase, PROTOCOL_VERSION};
pub(crate) use wire::case_request;
use wire::{codec_answer, outcome, quote, run_message, shutdown_message};

use super::breaker::Breaker;
use super::{Backend, Fault, Question, Request, Response, Setting};
use crate::memory::Unit;
use crate::model::cross_vendor::CodecAbilities;
use crate::model::profile::{Profile, Profiles};
use crate::model::project::ExternalSettings;
use crate::model::Operand;

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
mod fuzz;

#[cfg(test)]
mod white_box;
