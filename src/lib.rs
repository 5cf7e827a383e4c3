//! plc-conformance: a differential conformance harness for PLC instructions.
//!
//! The crate root is the interface an emulator or codec author depends on: implement
//! [`Emulator`] for an emulator (one instruction on one memory image) or [`Codec`] for a hex
//! codec (one cross-vendor or protocol-field question), and run the corpus against it from your
//! own `cargo test` with [`Harness`] (one libtest trial per case), or plan and judge it yourself
//! with [`Project`], [`verdicts`] and [`Verdict`]. [`Backend`] is what both become, and what a
//! backend in another process implements. Everything else is the command-line tool's and may
//! change between releases; `testing` lists what this repository's own tests reach.
//!
//! An emulator answers a [`Request`] — the profile and variant, the instruction, its operands
//! and flags, the memory before — with the words it wrote and the error it signalled:
//!
//! ```
//! use plc_conformance::{Emulator, Outcome, Paths, Project, Request, Setting, Unsupported,
//!     Value};
//!
//! /// Knows MELSEC iQ-R HABIN with SM705 off (a fixed 4 digits) and nothing else.
//! struct MyEmulator;
//!
//! impl Emulator for MyEmulator {
//!     fn name(&self) -> &str { "my-emulator" }
//!     // The profile's id (`plc-conformance list` shows them); an unknown one is refused.
//!     fn profile(&self) -> &str { "mitsubishi-iqr" }
//!     fn claims(&self, instruction: &str, _variant: &str) -> bool { instruction == "HABIN" }
//!     // What it does not implement of what it claims is declined: skipped with the reason.
//!     fn declines(&self, s: &Setting<'_>) -> Option<String> {
//!         (s.flags.get("SM705") == Some(&true)).then(|| "SM705 on is not implemented".into())
//!     }
//!     // It keeps no device ranges: the cases about them are skipped, not failed.
//!     fn checks_device_ranges(&self) -> bool { false }
//!     fn execute(&self, r: &Request<'_>) -> Result<Outcome, Unsupported> {
//!         let (s, d) = (r.device("s")?, r.device("d")?);
//!         // 4135H 4438H reads "5A8D", low byte first (`iqr-instructions-ja p.478`).
//!         let mut value: Value = 0;
//!         for i in 0..2 {
//!             let word = s.offset(i).map_or(0, |device| r.memory.read(&device));
//!             for byte in [word as u8, (word >> 8) as u8] {
//!                 let Some(digit) = (byte as char).to_digit(16).filter(|_| !byte.is_ascii_lowercase())
//!                 else {
//!                     return Ok(Outcome::error(r.error(0x3401)));
//!                 };
//!                 value = value << 4 | digit;
//!             }
//!         }
//!         Ok(Outcome::written([(d.clone(), value)].into()))
//!     }
//! }
//!
//! // The corpus built into the crate, planned and judged for it: every trial it runs conforms.
//! // (In a `harness = false` test, `Harness::embedded().emulator(MyEmulator, None).run()`
//! // makes each a libtest trial.)
//! let project = Project::load(&Paths::embedded()).expect("the shipped corpus loads");
//! let trials = project.plan(&[plc_conformance::emulator_backend(MyEmulator)]);
//! let verdicts = plc_conformance::verdicts(&trials);
//! let failing: Vec<String> = (trials.iter().zip(&verdicts))
//!     .filter(|(_, v)| v.is_failure())
//!     .map(|(t, v)| format!("{}: {v:?}", t.name()))
//!     .collect();
//! assert!(failing.is_empty(), "{failing:#?}");
//! assert!(verdicts.iter().filter(|v| **v == plc_conformance::Verdict::Conforms).count() > 20);
//! ```
//!
//! A codec answers with a value, a text or an error class. A protocol library's codec names the
//! protocol whose fields it implements, and is judged by that protocol's own manual
//! (`vectors/protocols/`), each difference naming the rule it breaks and its page; a codec of
//! no protocol (`protocol: None`) runs the cross-vendor (instruction) corpus instead:
//!
//! ```
//! use plc_conformance::{Answer, Codec, CodecAbilities, ErrorClass, Operation,
//!     OperationAbilities, ProtocolClaim, Question, Unsupported};
//!
//! /// A Modbus ASCII register read with `u16::from_str_radix`.
//! struct FromStrRadix;
//!
//! impl Codec for FromStrRadix {
//!     fn name(&self) -> &str { "from-str-radix" }
//!     fn abilities(&self) -> CodecAbilities {
//!         CodecAbilities {
//!             hex_to_value: Some(OperationAbilities::default()),
//!             protocol: Some(ProtocolClaim { id: "modbus-ascii".into(),
//!                 fields: Some(vec!["register".into()]), cross_vendor: false }),
//!             ..CodecAbilities::default()
//!         }
//!     }
//!     fn convert(&self, q: &Question<'_>) -> Result<Answer, Unsupported> {
//!         match q.operation {
//!             Operation::HexToValue => Ok(std::str::from_utf8(q.text).ok()
//!                 .and_then(|t| u16::from_str_radix(t, 16).ok())
//!                 .map_or(Answer::Error(ErrorClass::InvalidDigit), |v| Answer::Value(v.into()))),
//!             _ => Err(Unsupported("decode only".into())),
//!         }
//!     }
//! }
//!
//! // Judged by Modbus ASCII: `from_str_radix` takes a sign ("+234") and a field of 3 digits,
//! // each a difference naming the protocol's rule; everything else conforms.
//! let project = plc_conformance::Project::load(&plc_conformance::Paths::embedded()).unwrap();
//! let trials = project.plan(&[plc_conformance::codec_backend(FromStrRadix)]);
//! let verdicts = plc_conformance::verdicts(&trials);
//! let failing: Vec<&str> = (trials.iter().zip(&verdicts))
//!     .filter(|(_, v)| v.is_failure())
//!     .map(|(t, _)| t.case_id())
//!     .collect();
//! assert_eq!(failing, ["mb-register-decode-plus", "mb-register-decode-short"]);
//! ```
//!
//! Inside, data flows one way, one module per stage, none importing from a later one: `spec`
//! (the on-disk formats), `load` (the validated model, every problem with `file:line`), `plan`
//! (trials), `execute` (batched per backend), `judge` (verdicts, known differences), `report`
//! (reporters fed by events); `session` builds a run, `sweep` runs generated inputs, `libtest`
//! maps trials onto `cargo test`, and `cli` is the command line (docs/architecture.md).

#![warn(unreachable_pub)]
// Every type a public signature of the interface uses can be named from the root (so `cargo doc`
// links it), and every public item is documented. Checked without the command line, whose
// `testing` module reaches far more.
#![cfg_attr(not(feature = "cli"), warn(unnameable_types, missing_docs))]
// Without the command line, the operations only its commands call (sweeps, bench programs,
// records, the results table) are compiled but unused, and what only `testing` re-exports is
// reached by nothing public.
#![cfg_attr(
    not(feature = "cli"),
    allow(dead_code, unused_imports, unreachable_pub)
)]

mod backend;
#[cfg(feature = "cli")]
mod cli;
mod clock;
mod corpus_yaml;
mod device;
mod error_chain;
mod execute;
mod hil;
mod interrupt;
mod judge;
mod known_draft;
mod libtest;
mod load;
mod memory;
mod model;
mod nearest;
mod plan;
mod project;
mod record;
mod report;
mod session;
mod spec;
mod sweep;
#[cfg(test)]
mod test_support;
mod text;
mod value;

pub use backend::{
    codec_backend, emulator_backend, Backend, Codec, Emulator, Fault, Outcome, Question, Request,
    Response, Setting, Unsupported,
};
pub use device::{Device, DeviceSyntaxError};
pub use judge::{
    Difference, Effect, KnownEntry, Mismatch, Observed, RegisterRow, Status, Verdict, WordRow,
};
pub use libtest::Harness;
pub use load::LoadErrors;
pub use memory::{Fill, Image, Unit, Value};
pub use model::cross_vendor::CrossVendorCase;
pub use model::cross_vendor::{
    Answer, CodecAbilities, ErrorClass, FieldShape, Operation, OperationAbilities, ProtocolClaim,
};
pub use model::known::{KnownDifferences, Subject};
pub use model::profile::{Profile, Variant};
pub use model::{
    Basis, Case, Citation, Corpus, ErrorSignal, Expectation, Indirect, Location, Operand,
};
pub use plan::Trial;
pub use project::{Paths, Project};
pub use session::{run_one, verdicts};

/// What this repository's own tests reach inside the crate, with no stability promise: hidden
/// from the documentation, which shows the interface above.
#[doc(hidden)]
#[cfg(feature = "cli")]
pub mod testing;

/// The command line, for the `plc-conformance` binary: not part of the library's interface.
#[doc(hidden)]
#[cfg(feature = "cli")]
pub fn main() -> std::process::ExitCode {
    cli::main()
}

/// The `plc-conformance` command line with backends written in Rust beside the built-in ones,
/// each chosen by its name with `--backend` (and `--known-differences NAME=FILE`). A codec's
/// crate builds its own command from it, and every command works on the codec in process: a
/// sweep of every 4-byte text calls it directly, text by text, at its own speed.
///
/// ```no_run
/// # struct Mine;
/// # impl plc_conformance::Codec for Mine {
/// #     fn name(&self) -> &str { "mine" }
/// #     fn abilities(&self) -> plc_conformance::CodecAbilities { unimplemented!() }
/// #     fn convert(&self, _: &plc_conformance::Question<'_>)
/// #         -> Result<plc_conformance::Answer, plc_conformance::Unsupported> { unimplemented!() }
/// # }
/// // src/bin/plc-conformance-mine.rs:
/// // cargo run --release --bin plc-conformance-mine -- sweep --operation hex-to-value \
/// //     --generator full --each-text --backend mine
/// fn main() -> std::process::ExitCode {
///     plc_conformance::command_line(vec![plc_conformance::codec_backend(Mine)])
/// }
/// ```
///
/// Needs the `cli` feature (on by default).
#[cfg(feature = "cli")]
pub fn command_line(backends: Vec<std::sync::Arc<dyn Backend>>) -> std::process::ExitCode {
    cli::main_with(backends)
}
