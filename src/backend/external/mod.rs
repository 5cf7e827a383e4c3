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
pub mod protocol;
pub mod serve;
pub mod window;

use std::collections::BTreeMap;
use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::Serialize;

pub use process::MAX_LINE;
use process::{describe_exit, Next, Process};
use protocol::{
    BackendInfo, BackendMessage, Capabilities, CaseRequest, ErrorReport, FillName, HarnessMessage,
    MemoryRange, OperandValue, PROTOCOL_VERSION,
};

use super::{Backend, Fault, Outcome, Request, Response};
use crate::device::Device;
use crate::memory::Fill;
use crate::model::profile::{Profile, Profiles, Variant};
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
                "speaks protocol version {theirs}; this harness speaks version {PROTOCOL_VERSION}"
            ),
            ExternalErrorKind::Capabilities(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for ExternalError {}

/// A backend in another process.
pub struct ExternalBackend {
    settings: ExternalSettings,
    info: BackendInfo,
    restarts: std::sync::atomic::AtomicUsize,
    capabilities: Capabilities,
    profile: Arc<Profile>,
    state: Mutex<State>,
}

struct State {
    process: Option<Process>,
    next_id: u64,
    /// Set when the process could not be started again after a fault: every later case gets
    /// this as its fault without another attempt.
    down: Option<String>,
}

impl ExternalBackend {
    /// Starts the process and completes the handshake; checks the capabilities against the
    /// profiles and the configured profile family.
    pub fn start(
        spec: ExternalSettings,
        profiles: &Profiles,
    ) -> Result<ExternalBackend, ExternalError> {
        let error = |kind| ExternalError {
            backend: spec.name.clone(),
            command: spec.launch.to_string(),
            kind,
        };
        let (process, info, capabilities) = handshake(&spec).map_err(error)?;
        let profile = check_capabilities(&spec, &capabilities, profiles)
            .map_err(|m| error(ExternalErrorKind::Capabilities(m)))?;
        let process = if spec.persistent {
            Some(process)
        } else {
            process.shutdown(shutdown_message());
            None
        };
        Ok(ExternalBackend {
            settings: spec,
            info,
            restarts: std::sync::atomic::AtomicUsize::new(0),
            capabilities,
            profile,
            state: Mutex::new(State {
                process,
                next_id: 1,
                down: None,
            }),
        })
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
    /// the cases after the faulty one.
    fn run_chunk(&self, state: &mut State, cases: &[CaseRequest]) -> Vec<Result<Response, Fault>> {
        let mut results: Vec<Result<Response, Fault>> = Vec::with_capacity(cases.len());
        while results.len() < cases.len() {
            let rest = &cases[results.len()..];
            if let Some(why) = &state.down {
                results.extend(rest.iter().map(|_| Err(Fault::Unreachable(why.clone()))));
                break;
            }
            if state.process.is_none() {
                match handshake(&self.settings) {
                    Ok((p, _, _)) => {
                        if self.settings.persistent {
                            self.restarts
                                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                        state.process = Some(p)
                    }
                    Err(kind) => {
                        let why = format!(
                            "could not be started again: {}",
                            ExternalError {
                                backend: self.settings.name.clone(),
                                command: self.settings.launch.to_string(),
                                kind,
                            }
                        );
                        state.down = Some(why);
                        continue;
                    }
                }
            }
            let Some(process) = state.process.as_mut() else {
                continue;
            };
            let mark = process.stderr_mark();
            process.send(run_message(rest));
            let mut deadline = Instant::now() + self.settings.timeout;
            for case in rest {
                match self.answer(process, case, deadline) {
                    Ok(response) => {
                        results.push(Ok(response));
                        deadline = Instant::now() + self.settings.timeout;
                    }
                    Err(fault) => {
                        let mut process = state.process.take();
                        let stderr = process.as_mut().map_or_else(String::new, |p| {
                            p.kill();
                            p.stderr_since(mark, Duration::from_millis(300))
                        });
                        results.push(Err(with_stderr(fault, &stderr)));
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
        results
    }

    /// Reads the answer to one case.
    fn answer(
        &self,
        process: &mut Process,
        case: &CaseRequest,
        deadline: Instant,
    ) -> Result<Response, Fault> {
        let which = || format!("request {} (case {})", case.id, case.case);
        let line = match process.next_line(deadline) {
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
            } if id == case.id => outcome(case, memory, writes, error)
                .map(Response::Done)
                .map_err(unexpected),
            BackendMessage::Unsupported { id, reason } if id == case.id => {
                Ok(Response::Unsupported(reason))
            }
            BackendMessage::Result { id, .. } | BackendMessage::Unsupported { id, .. } => {
                Err(unexpected(format!("an answer for request {id}")))
            }
            BackendMessage::Hello { .. } => {
                Err(unexpected("a hello in the middle of a run".into()))
            }
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

    fn describe(&self) -> String {
        format!(
            "external: {} {} (`{}`)",
            self.info.name, self.info.version, self.settings.launch
        )
    }

    fn claims(&self, instruction: &str, variant: &str) -> bool {
        self.capabilities
            .instructions
            .iter()
            .any(|i| i == instruction)
            && self
                .capabilities
                .variants
                .as_ref()
                .is_none_or(|v| v.iter().any(|v| v == variant))
            && self
                .profile
                .variant(variant)
                .is_some_and(|v| self.profile.has_instruction(v, instruction))
    }

    fn declines(
        &self,
        flags: &BTreeMap<String, bool>,
        instruction: &str,
        variant: &Variant,
    ) -> Option<String> {
        let reads = &self.profile.instructions.get(instruction)?.flags;
        self.capabilities
            .flags
            .iter()
            .filter(|(flag, _)| reads.contains(flag))
            .find_map(|(flag, settings)| {
                let value = self.profile.flag_seen(variant, flags, flag);
                (!settings.contains(&value)).then(|| {
                    format!(
                        "{} does not implement {flag} {}",
                        self.settings.name,
                        if value { "on" } else { "off" }
                    )
                })
            })
    }

    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        self.execute_batch(std::slice::from_ref(request))
            .pop()
            .unwrap_or_else(|| Err(Fault::Protocol("no answer".into())))
    }

    fn restarts(&self) -> usize {
        self.restarts.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn execute_batch(&self, requests: &[Request<'_>]) -> Vec<Result<Response, Fault>> {
        let mut state = match self.state.lock() {
            Ok(s) => s,
            Err(poisoned) => poisoned.into_inner(),
        };
        let first = state.next_id;
        state.next_id += requests.len() as u64;
        let cases: Vec<CaseRequest> = requests
            .iter()
            .zip(first..)
            .map(|(r, id)| case_request(r, id))
            .collect();
        let size = if self.settings.persistent {
            self.settings.batch.max(1)
        } else {
            1
        };
        cases
            .chunks(size)
            .flat_map(|chunk| self.run_chunk(&mut state, chunk))
            .collect()
    }
}

/// Starts the process and exchanges `hello`.
fn handshake(
    spec: &ExternalSettings,
) -> Result<(Process, BackendInfo, Capabilities), ExternalErrorKind> {
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
    let line = match process.next_line(deadline) {
        Next::Line(line) => line,
        Next::Oversized { head, length } => {
            return Err(failed(
                &mut process,
                format!(
                "the answer to hello is a line of {length} bytes, over the limit; it starts: {}",
                quote(&head)
            ),
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
    // The version is read on its own first, so that a backend of a later protocol version
    // whose hello has other fields is told apart from a broken one.
    let version = serde_json::from_slice::<serde_json::Value>(&line)
        .ok()
        .and_then(|v| v.get("protocol").and_then(serde_json::Value::as_u64));
    if let Some(theirs) = version.filter(|v| *v != u64::from(PROTOCOL_VERSION)) {
        process.kill();
        return Err(ExternalErrorKind::Version {
            theirs: u32::try_from(theirs).unwrap_or(u32::MAX),
        });
    }
    match BackendMessage::from_line(&line) {
        Ok(BackendMessage::Hello {
            protocol: _,
            backend,
            capabilities,
        }) => Ok((process, backend, capabilities)),
        Ok(_) => Err(failed(
            &mut process,
            format!("expected a hello, got: {}", quote(&line)),
        )),
        Err(e) => Err(failed(
            &mut process,
            format!(
                "the answer to hello is not a hello message ({e}): {}",
                quote(&line)
            ),
        )),
    }
}

/// Checks a handshake's capabilities against the profiles and the configured family.
fn check_capabilities(
    spec: &ExternalSettings,
    caps: &Capabilities,
    profiles: &Profiles,
) -> Result<Arc<Profile>, String> {
    if let Some(configured) = &spec.profile {
        if configured != &caps.profile {
            return Err(format!(
                "is configured as implementing profile `{configured}` but its handshake claims `{}`",
                caps.profile
            ));
        }
    }
    let profile = profiles.get(&caps.profile).ok_or_else(|| {
        format!(
            "claims profile `{}`, which is not loaded; known profiles: {}",
            caps.profile,
            profiles.ids().join(", ")
        )
    })?;
    let unknown = |what: &str, name: &str, known: Vec<String>| {
        format!(
            "claims {what} `{name}`, which profile `{}` does not define; it defines: {}",
            profile.id,
            known.join(", ")
        )
    };
    for i in &caps.instructions {
        if !profile.instructions.contains_key(i) {
            return Err(unknown(
                "instruction",
                i,
                profile.instructions.keys().cloned().collect(),
            ));
        }
    }
    for v in caps.variants.iter().flatten() {
        if profile.variant(v).is_none() {
            return Err(unknown(
                "variant",
                v,
                profile.variants.iter().map(|v| v.id.clone()).collect(),
            ));
        }
    }
    for (f, settings) in &caps.flags {
        if !profile.flags.contains_key(f) {
            return Err(unknown("flag", f, profile.flags.keys().cloned().collect()));
        }
        if settings.is_empty() {
            return Err(format!(
                "lists no setting for flag `{f}`; leave a flag out to claim both settings"
            ));
        }
    }
    Ok(profile.clone())
}

/// The request for one case: everything the backend needs, fill included.
pub fn case_request(req: &Request<'_>, id: u64) -> CaseRequest {
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
                let value = match v {
                    Operand::Device(d) => OperandValue::Device(d.to_string()),
                    Operand::Constant(k) => OperandValue::Constant(*k),
                };
                (k.clone(), value)
            })
            .collect(),
        fill: match req.memory.fill() {
            Fill::A => FillName::A,
            Fill::B => FillName::B,
        },
        memory: window::memory(req),
    }
}

/// Turns a `result` into an outcome: every reported word is a write, except words of `memory`
/// that kept their value (an echoed window is not a list of writes).
fn outcome(
    case: &CaseRequest,
    memory: Vec<MemoryRange>,
    writes: BTreeMap<String, u16>,
    error: Option<ErrorReport>,
) -> Result<Outcome, String> {
    let device = |name: &str| {
        name.parse::<Device>()
            .map_err(|e| format!("bad device in the answer: {e}"))
    };
    // Only an echoed window needs the words before; a list of writes is taken as it is.
    let before: BTreeMap<Device, u16> = if memory.is_empty() {
        BTreeMap::new()
    } else {
        case.memory
            .iter()
            .filter_map(|r| r.start.parse::<Device>().ok().map(|d| (d, &r.words)))
            .flat_map(|(d, words)| {
                words
                    .iter()
                    .enumerate()
                    .filter_map(move |(i, w)| d.offset(i as u32).map(|d| (d, *w)))
            })
            .collect()
    };
    let mut out = Outcome::default();
    for range in memory {
        let start = device(&range.start)?;
        for (i, word) in range.words.into_iter().enumerate() {
            let d = start
                .offset(i as u32)
                .ok_or_else(|| format!("memory from {start} runs past the last device number"))?;
            if before.get(&d) != Some(&word) {
                out.writes.insert(d, word);
            }
        }
    }
    for (name, word) in writes {
        out.writes.insert(device(&name)?, word);
    }
    out.error = match error {
        None => None,
        Some(ErrorReport::Code(c)) => Some(ErrorSignal::Code(c)),
        Some(ErrorReport::Flag(f)) => Some(ErrorSignal::Flag(device(&f)?)),
    };
    Ok(out)
}

fn run_message(cases: &[CaseRequest]) -> Vec<u8> {
    #[derive(Serialize)]
    struct Run<'a> {
        #[serde(rename = "type")]
        kind: &'static str,
        cases: &'a [CaseRequest],
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
