//! Backends: the implementations under test.
//!
//! A backend executes one instruction on one memory image and answers with the words it wrote
//! and the error it signalled, or says it does not implement what was asked. It knows nothing of
//! YAML, planning, judging or reporting; everything vendor-specific it needs comes in the
//! [`Request`] from the profile.

pub(crate) mod bench;
mod breaker;
mod emulator;
pub(crate) mod external;
pub(crate) mod fc4a;
pub(crate) mod fp;
pub(crate) mod fx3;
pub(crate) mod fx5;
pub(crate) mod iqr;
pub(crate) mod kv;
pub(crate) mod modbus;
pub(crate) mod omron;
pub(crate) mod reference;
pub(crate) mod s7;
pub(crate) mod s7_200;
pub(crate) mod simulate;
pub(crate) mod slmp;

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use serde::Serialize;

pub use emulator::{emulator_backend, Emulator};

use crate::device::Device;
use crate::memory::{Image, Value};
use crate::model::cross_vendor::{Answer, CodecAbilities, Operation};
use crate::model::profile::{Profile, Profiles, Variant};
use crate::model::{ErrorSignal, Indirect, Operand};

/// Everything a backend needs to execute one case.
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    /// The vendor family's profile: its devices, flags, error signalling and manuals.
    pub profile: &'a Profile,
    /// The CPU model the case runs on: [`Request::flag`] and [`Request::words_exist`] heed it.
    pub variant: &'a Variant,
    /// The instruction to execute, as the profile names it (`HABIN`).
    pub instruction: &'a str,
    /// The case id, for backends that log or correlate.
    pub case_id: &'a str,
    /// The flags the case sets; [`Request::flag`] applies defaults and the variant.
    pub flags: &'a BTreeMap<String, bool>,
    /// The case's operands by name (`s`, `d`, `n`); [`Request::operand`] reads one.
    pub operands: &'a BTreeMap<String, Operand>,
    /// The operands given by indirect specification, with their pointers: a reference model
    /// executes on the addressed device in `operands` and needs nothing more; an external
    /// backend is told the pointer and what it addresses.
    pub indirect: &'a Indirect,
    /// The memory before execution: the units the case sets, over fill A or B.
    pub memory: &'a Image,
}

impl Request<'_> {
    /// A flag as the CPU sees it: the case's setting, or the profile default, except that a
    /// variant which does not implement the flag always sees the default.
    ///
    /// # Panics
    ///
    /// When the profile has no flag `name`: a misspelt flag would otherwise read as off, and an
    /// emulator would pass every case that leaves it off. The message names the flag nearest
    /// it and the profile's flags; the trial fails with it.
    pub fn flag(&self, name: &str) -> bool {
        if !self.profile.flags.contains_key(name) {
            panic!("{}", self.profile.unknown_flag(name));
        }
        self.profile.flag_seen(self.variant, self.flags, name)
    }

    /// The flags the case sets, with the profile's defaults for the rest, as the vector wrote
    /// them (before the variant's view): what an external backend is told.
    pub fn all_flags(&self) -> BTreeMap<String, bool> {
        self.profile.flags_of(self.instruction, self.flags)
    }

    /// An operand by name, or [`Unsupported`] naming it when the case does not give it.
    pub fn operand(&self, name: &str) -> Result<&Operand, Unsupported> {
        self.operands
            .get(name)
            .ok_or_else(|| Unsupported(format!("{} needs operand `{name}`", self.instruction)))
    }

    /// An operand that must be a device.
    pub fn device(&self, name: &str) -> Result<&Device, Unsupported> {
        match self.operand(name)? {
            Operand::Device(d) => Ok(d),
            Operand::Constant(k) => Err(Unsupported(format!(
                "operand `{name}` as a constant (K{k}) is not modelled"
            ))),
        }
    }

    /// Whether `count` words from `head` exist on this variant.
    pub fn words_exist(&self, head: &Device, count: u32) -> bool {
        self.profile.words_exist(self.variant, head, count)
    }

    /// The signal for an operation error with the vendor's code. For a profile that signals
    /// with a flag only, the code is not visible and the flag is what the program sees.
    pub fn error(&self, code: u16) -> ErrorSignal {
        self.profile.error(code)
    }
}

/// What a trial asks of a backend, before any memory: for [`Backend::declines`].
#[derive(Debug, Clone, Copy)]
pub struct Setting<'a> {
    /// The instruction the trial runs (for a cross-vendor trial, its lowering's).
    pub instruction: &'a str,
    /// The CPU model the trial runs on.
    pub variant: &'a Variant,
    /// The flags set (the rest hold the profile default).
    pub flags: &'a BTreeMap<String, bool>,
    /// The operands by name, as the case or the lowering gives them.
    pub operands: &'a BTreeMap<String, Operand>,
    /// The operands given by indirect specification, with their pointers.
    pub indirect: &'a Indirect,
}

/// What an instruction did.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
pub struct Outcome {
    /// Every word written, with the value written (a word rewritten with its old value is
    /// still listed; the comparer decides what changed).
    pub writes: BTreeMap<Device, Value>,
    /// The error the instruction signalled; `None` when it completed without one.
    pub error: Option<ErrorSignal>,
    /// The registers where the profile says an error code lands (MELSEC SD0, FX5 SD8067 too),
    /// as the backend holds them after an error: kept apart from `writes` because they are
    /// judged against the code, not against the case's memory. Empty for a backend that models
    /// no such register, which is then judged on the code alone.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub registers: BTreeMap<Device, Value>,
}

impl Outcome {
    /// An outcome of an error alone: nothing written, no error registers reported.
    pub fn error(error: ErrorSignal) -> Self {
        Outcome {
            error: Some(error),
            ..Outcome::default()
        }
    }

    /// The words an instruction wrote, without an error.
    pub fn written(writes: BTreeMap<Device, Value>) -> Self {
        Outcome {
            writes,
            ..Outcome::default()
        }
    }

    /// The units of an emulator's own memory from `head` on that differ between `before` (as
    /// [`Image::copy_into`] filled it) and `after` (once the instruction ran), as writes,
    /// without an error. A unit of `after` past the end of `before` counts as written.
    ///
    /// ```
    /// use plc_conformance::{Device, Outcome};
    ///
    /// let d0: Device = "D0".parse().unwrap();
    /// let outcome = Outcome::changes(&d0, &[1, 2, 3], &[1, 7, 3]);
    /// assert_eq!(outcome, Outcome::written([("D1".parse().unwrap(), 7)].into()));
    /// ```
    pub fn changes(head: &Device, before: &[Value], after: &[Value]) -> Self {
        let writes = after
            .iter()
            .enumerate()
            .filter(|(i, unit)| before.get(*i) != Some(unit))
            .filter_map(|(i, unit)| Some((head.offset(u32::try_from(i).ok()?)?, *unit)))
            .collect();
        Outcome::written(writes)
    }

    /// Moves what was reported as writes to the error registers into `registers`: a backend
    /// that models its CPU's memory writes SD0 like any word.
    pub fn registers_from_writes(mut self, registers: &[Device]) -> Self {
        for register in registers {
            if let Some(value) = self.writes.remove(register) {
                self.registers.insert(register.clone(), value);
            }
        }
        self
    }
}

/// A cross-vendor question asked of a codec-level backend: no memory, no devices, no fill.
#[derive(Debug, Clone, Copy)]
pub struct Question<'a> {
    /// The cross-vendor case id, for backends that log or correlate.
    pub case_id: &'a str,
    /// What is asked: hex-to-value, value-to-hex, or a protocol's check or verify.
    pub operation: Operation,
    /// hex-to-value: the characters, exactly as the case gives them.
    pub text: &'a [u8],
    /// value-to-hex: the value.
    pub value: u64,
    /// The digit count (FX5 n, IDEC S2).
    pub digits: u32,
    /// The protocol field asked (`word`, `lrc`); empty for a cross-vendor question.
    pub field: &'a str,
}

/// A backend's answer to a request it understood.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase", tag = "kind", content = "value")]
#[non_exhaustive]
pub enum Response {
    /// The instruction ran: what it wrote and the error it signalled, if any.
    Done(Outcome),
    /// A codec-level backend's answer to a [`Question`].
    Answer(Answer),
    /// The backend does not implement this (instruction, variant, operand kind, ...).
    Unsupported(String),
}

/// The reason a request is not implemented.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported(pub String);

impl From<Unsupported> for Response {
    fn from(u: Unsupported) -> Self {
        Response::Unsupported(u.0)
    }
}

/// Why a backend gave no answer: an external process that crashed, hung or answered garbage,
/// a live CPU not reached, a codec in process that panicked. Each is an outcome of the case,
/// never a pass.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "detail")]
#[non_exhaustive]
pub enum Fault {
    /// The process exited or was killed.
    Crashed(String),
    /// No answer within the time limit.
    Timeout(String),
    /// An answer that does not follow the protocol.
    Protocol(String),
    /// The backend could not be started or reached.
    Unreachable(String),
}

impl Fault {
    /// The fault's kind as reports label it.
    pub fn kind(&self) -> &'static str {
        match self {
            Fault::Crashed(_) => "crashed",
            Fault::Timeout(_) => "timeout",
            Fault::Protocol(_) => "protocol-error",
            Fault::Unreachable(_) => "unreachable",
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::Crashed(s) => write!(f, "crashed: {s}"),
            Fault::Timeout(s) => write!(f, "timeout: {s}"),
            Fault::Protocol(s) => write!(f, "protocol error: {s}"),
            Fault::Unreachable(s) => write!(f, "unreachable: {s}"),
        }
    }
}

/// An implementation under test: of one profile family (instruction level), or of the
/// cross-vendor operations directly (codec level, see [`Backend::codec`]).
pub trait Backend: Send + Sync {
    /// The name used on the command line and in trial names.
    fn name(&self) -> &str;
    /// The profile id whose vectors this backend runs (empty for a codec-level backend).
    fn profile(&self) -> &str;
    /// One line for `plc-conformance list`.
    fn describe(&self) -> String;
    /// What the backend is and its version, for a report's run metadata (`pymcprotocol 0.3.0`);
    /// `None` when it does not say.
    fn version(&self) -> Option<String> {
        None
    }
    /// What answers in the backend's place when that is the harness's own model (a built-in
    /// reference model, or the simulated CPU running one), not a device or an implementation
    /// under test: `record` writes no `observed` expectation from it. A live backend knows once
    /// it has connected.
    fn simulated_by(&self) -> Option<String> {
        None
    }
    /// Whether the backend claims to implement an instruction on a variant. Trials it does not
    /// claim are listed as skipped with a reason; a claimed trial answered "unsupported" is a
    /// difference.
    fn claims(&self, instruction: &str, variant: &str) -> bool;
    /// Why the backend declines to run an instruction it claims with these flags (as a case or
    /// a cross-vendor lowering sets them), e.g. a flag setting it does not implement; the trial
    /// is then skipped with this reason, like an unclaimed one.
    fn declines(&self, _setting: &Setting<'_>) -> Option<String> {
        None
    }
    /// Whether the backend checks device ranges (an operand past the last device is an error):
    /// a codec-like library that has no devices says no, and the cases that expect such an
    /// error are skipped for it rather than failed.
    fn checks_device_ranges(&self) -> bool {
        true
    }
    /// How many trials the executor hands over at once. In process, a small chunk keeps
    /// progress and `--fail-fast` close to the trials; a backend in another process wants
    /// several messages' worth, so that it can keep the next one queued.
    fn chunk_trials(&self) -> usize {
        128
    }
    /// Executes one trial's instruction on the memory image the request carries, under one
    /// fill: `Ok(Response::Done(outcome))` with the words written and the error signalled,
    /// `Ok(Response::Unsupported(why))` for a trial it claimed but cannot execute after all (a
    /// failure: decline such a trial up front with [`Backend::declines`] instead), or a
    /// [`Fault`] when no answer could be had (a process that crashed or hung; an emulator in
    /// process rarely returns one).
    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault>;
    /// Executes several requests, answers in order, calling `answered` with how many are
    /// answered so far as they come in. A backend in another process answers a batch in one
    /// exchange, which is what makes it fast; `answered` is what shows a slow one working.
    fn execute_batch(
        &self,
        requests: &[Request<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        let mut out = Vec::with_capacity(requests.len());
        for r in requests {
            out.push(self.execute(r));
            answered(out.len());
        }
        out
    }
    /// How many times the backend's process has been started again after a fault: the
    /// executor reports each restart as an event.
    fn restarts(&self) -> usize {
        0
    }
    /// For a codec-level backend, the cross-vendor operations it implements: it then runs the
    /// cross-vendor corpus through [`Backend::convert_batch`] and no native case.
    fn codec(&self) -> Option<&CodecAbilities> {
        None
    }
    /// A codec written in Rust that this backend calls in process ([`codec_backend`]): a sweep
    /// of every 4-byte text calls it directly, text by text, at its own speed.
    fn as_codec(&self) -> Option<&dyn Codec> {
        None
    }
    /// Answers cross-vendor questions, in order (codec-level backends), calling `answered` as
    /// [`Backend::execute_batch`] does.
    fn convert_batch(
        &self,
        questions: &[Question<'_>],
        _answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        questions
            .iter()
            .map(|_| {
                Ok(Response::Unsupported(format!(
                    "{} is not a codec-level backend",
                    self.name()
                )))
            })
            .collect()
    }
}

/// A codec written in Rust: what a library implements, in the fewest words. Wrap it with
/// [`codec_backend`] to run it as a backend (in process, no protocol).
pub trait Codec: Send + Sync {
    /// The name in trial names.
    fn name(&self) -> &str;
    /// What it implements.
    fn abilities(&self) -> CodecAbilities;
    /// Answers one question: a value, a text or an error class; `Err` for a question it does
    /// not implement after all (a difference when inside its abilities).
    fn convert(&self, question: &Question<'_>) -> Result<Answer, Unsupported>;
    /// The library and its version (`rmodbus 0.13.0`), for the reports: what a saved run and
    /// the results table say was checked.
    fn version(&self) -> Option<String> {
        None
    }
}

/// A [`Codec`] as a [`Backend`].
pub fn codec_backend(codec: impl Codec + 'static) -> Arc<dyn Backend> {
    let abilities = codec.abilities();
    Arc::new(CodecBackend { codec, abilities })
}

struct CodecBackend<C> {
    codec: C,
    abilities: CodecAbilities,
}

impl<C: Codec> Backend for CodecBackend<C> {
    fn name(&self) -> &str {
        self.codec.name()
    }
    fn profile(&self) -> &str {
        ""
    }
    fn describe(&self) -> String {
        "codec-level backend (in process)".into()
    }
    fn version(&self) -> Option<String> {
        self.codec.version()
    }
    fn claims(&self, _instruction: &str, _variant: &str) -> bool {
        false
    }
    fn execute(&self, _request: &Request<'_>) -> Result<Response, Fault> {
        Ok(Response::Unsupported(
            "a codec executes no instruction".into(),
        ))
    }
    fn codec(&self) -> Option<&CodecAbilities> {
        Some(&self.abilities)
    }
    fn as_codec(&self) -> Option<&dyn Codec> {
        Some(&self.codec)
    }
    fn convert_batch(
        &self,
        questions: &[Question<'_>],
        _answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        questions
            .iter()
            .map(|q| match convert_or_panic(&self.codec, q) {
                Ok(Ok(answer)) => Ok(Response::Answer(answer)),
                Ok(Err(u)) => Ok(u.into()),
                Err(crashed) => Err(crashed),
            })
            .collect()
    }
}

thread_local! {
    /// Set while this thread asks a codec in process a question.
    static ASKING_CODEC: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Where the codec asked on this thread panicked, as the panic hook saw it.
    static CODEC_PANICKED_AT: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Whether a panic on this thread is a codec's, caught by [`convert_or_panic`] and reported as
/// its case's crash: the panic hook then neither prints it (a codec that panics on many texts
/// would flood the terminal) nor ends the run's backends.
pub(crate) fn asking_codec() -> bool {
    ASKING_CODEC.with(std::cell::Cell::get)
}

/// Keeps where the codec asked on this thread panicked, for its case's crash to say.
pub(crate) fn codec_panicked_at(location: String) {
    CODEC_PANICKED_AT.with(|at| *at.borrow_mut() = Some(location));
}

/// What a panic said, when it said it with `panic!`'s text (a `&str` or a `String`).
pub(crate) fn panic_message(panic: &(dyn std::any::Any + Send)) -> Option<String> {
    (panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .or_else(|| panic.downcast_ref::<String>().cloned())
}

/// A codec's answer, or what it panicked with: a codec in process that panics on a question has
/// crashed on that case, as a process that exits would have, and the run goes on.
pub(crate) fn convert_or_panic(
    codec: &dyn Codec,
    question: &Question<'_>,
) -> Result<Result<Answer, Unsupported>, Fault> {
    ASKING_CODEC.with(|a| a.set(true));
    let answer = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| codec.convert(question)));
    ASKING_CODEC.with(|a| a.set(false));
    answer.map_err(|panic| {
        let message = panic_message(panic.as_ref()).unwrap_or_else(|| "a panic".into());
        let at = CODEC_PANICKED_AT
            .with(|at| at.borrow_mut().take())
            .map(|at| format!(" (at {at})"))
            .unwrap_or_default();
        Fault::Crashed(format!(
            "the codec panicked on case {}: {message}{at}",
            question.case_id
        ))
    })
}

/// Makes a reference model's backend when its profile is loaded.
type MakeBackend = fn(&Profiles) -> Option<Arc<dyn Backend>>;

/// The built-in reference models: one line per family. A family whose profile is not loaded
/// has no backend.
const MODELS: &[MakeBackend] = &[
    reference::backend::<iqr::Iqr>,
    reference::backend::<fx5::Fx5>,
    reference::backend::<fc4a::Fc4a>,
    reference::backend::<s7::S71200>,
    reference::backend::<s7_200::S7200>,
    reference::backend::<fx3::AsciHex<fx3::Fx3>>,
    reference::backend::<fx3::AsciHex<fx3::Delta>>,
    reference::backend::<fp::Fp>,
    reference::backend::<kv::Kv>,
    reference::backend::<omron::Omron>,
];

/// The reference models, one per profile that has one.
pub(crate) fn reference_backends(profiles: &Profiles) -> Vec<Arc<dyn Backend>> {
    MODELS.iter().filter_map(|make| make(profiles)).collect()
}

/// The reference model of one profile: what a program generated for a CPU, or a simulated CPU,
/// computes its answers with.
/// A bench backend's command line, `slmp:...` or `modbus:...`; `None` when `text` is neither.
pub(crate) fn bench_settings(
    text: &str,
    base: &std::path::Path,
    profiles: &Profiles,
) -> Result<Option<bench::BenchSettings>, bench::error::LiveError> {
    if let Some(s) = slmp::SlmpBench::parse(text, base)? {
        return Ok(Some(s.erased()));
    }
    Ok(modbus::ModbusBench::parse(text, base, profiles)?.map(bench::BenchSettings::erased))
}

/// The forms of a bench backend's command line, for messages.
pub(crate) const BENCH_FORMS: &str =
    "slmp:NAME=HOST:PORT?manifest=FILE&confirm=TYPE&sandbox=RANGES \
     or modbus:NAME=HOST:PORT?manifest=FILE&confirm=CODE&sandbox=RANGES";

/// How the link of a profile's bench reaches its CPUs' devices: the one place a link kind
/// meets its module.
pub(crate) fn addressing(
    profile: &crate::model::profile::Profile,
) -> Result<Box<dyn bench::Addressing>, bench::error::LiveError> {
    use crate::model::profile::LinkKind;
    let bench = profile.bench.as_ref().ok_or_else(|| {
        bench::error::LiveError::Refused(format!(
            "{} has no `bench` section in its profile: no bench runs its corpus on a CPU",
            profile.id
        ))
    })?;
    Ok(match bench.link {
        LinkKind::Slmp => Box::new(slmp::Slmp),
        LinkKind::ModbusTcp => Box::new(modbus::Map::of(profile)?),
    })
}

pub(crate) fn reference_model(profiles: &Profiles, profile: &str) -> Option<Arc<dyn Backend>> {
    reference_backends(profiles)
        .into_iter()
        .find(|b| b.profile() == profile && b.codec().is_none())
}

#[cfg(test)]
mod mutants;
