//! The trait an emulator implements: the few things the harness asks of one, apart from the
//! codec's and from what only a backend in another process needs (batches, restarts, chunks).

use std::sync::Arc;

use super::{Backend, Fault, Outcome, Request, Response, Setting, Unsupported};

/// An emulator or soft-PLC written in Rust: it executes one instruction of one vendor profile
/// on the memory image a [`Request`] carries. Run it with [`crate::Harness::emulator`], or as a
/// [`Backend`] through [`emulator_backend`].
///
/// ```
/// use plc_conformance::{Emulator, Outcome, Request, Setting, Unsupported};
///
/// /// MELSEC iQ-R HABIN with SM705 off: four characters, two a word, low byte first.
/// struct Habin;
///
/// impl Emulator for Habin {
///     fn name(&self) -> &str { "habin" }
///     // The profile's id (`plc-conformance list` shows them); an unknown one fails the run.
///     fn profile(&self) -> &str { "mitsubishi-iqr" }
///     // Instructions it does not claim are listed as skipped, with the reason.
///     fn claims(&self, instruction: &str, _variant: &str) -> bool { instruction == "HABIN" }
///     // What it claims but does not implement is declined up front: skipped, with the reason.
///     fn declines(&self, setting: &Setting<'_>) -> Option<String> {
///         setting.flags.get("SM705").copied().unwrap_or(false)
///             .then(|| "SM705 on (a text ended by 00H) is not implemented".into())
///     }
///     // It keeps no device ranges: the cases about them are skipped, not failed.
///     fn checks_device_ranges(&self) -> bool { false }
///     fn execute(&self, r: &Request<'_>) -> Result<Outcome, Unsupported> {
///         let (s, d) = (r.device("s")?, r.device("d")?);
///         // The emulator's own RAM: the two words of the text, as the request holds them.
///         let mut text = [0; 2];
///         r.memory.copy_into(s, &mut text);
///         let mut value = 0;
///         for byte in text.iter().flat_map(|w| [*w as u8, (*w >> 8) as u8]) {
///             match (byte as char).to_digit(16).filter(|_| !byte.is_ascii_lowercase()) {
///                 Some(digit) => value = value << 4 | digit,
///                 None => return Ok(Outcome::error(r.error(0x3401))),
///             }
///         }
///         Ok(Outcome::written([(d.clone(), value)].into()))
///     }
/// }
///
/// // The shipped corpus, planned and judged for it: what `Harness::embedded().emulator(Habin)`
/// // runs as one libtest trial each.
/// let project = plc_conformance::Project::load(&plc_conformance::Paths::embedded()).unwrap();
/// let trials = project.plan(&[plc_conformance::emulator_backend(Habin)]);
/// let verdicts = plc_conformance::verdicts(&trials);
/// assert!(verdicts.iter().all(|v| !v.is_failure()), "{verdicts:?}");
/// assert!(verdicts.iter().any(|v| *v == plc_conformance::Verdict::Conforms));
/// ```
pub trait Emulator: Send + Sync {
    /// The name in trial names and reports.
    fn name(&self) -> &str;
    /// The id of the vendor profile whose cases it runs (`mitsubishi-iqr`): a profile the
    /// corpus does not have fails the run, with the nearest id.
    fn profile(&self) -> &str;
    /// Whether it implements an instruction (`HABIN`, `HABINP`) on a variant of the profile
    /// (`rcpu`). A trial it does not claim is listed as skipped with the reason.
    fn claims(&self, instruction: &str, variant: &str) -> bool;
    /// Why it declines a trial it claims, with the flags as the case sets them (a setting it
    /// does not implement): the trial is skipped with this reason rather than failed.
    fn declines(&self, _setting: &Setting<'_>) -> Option<String> {
        None
    }
    /// Whether it checks device ranges (an operand past the last device is an error); one that
    /// keeps no ranges says no, and the cases that expect such an error are skipped for it.
    fn checks_device_ranges(&self) -> bool {
        true
    }
    /// Executes the request's instruction on its memory image: the words written (and the
    /// registers set) and the error signalled, or [`Unsupported`] for a trial it claimed but
    /// cannot run after all, a difference (decline such a trial with [`Emulator::declines`]).
    /// A panic fails the trial with its message.
    fn execute(&self, request: &Request<'_>) -> Result<Outcome, Unsupported>;
    /// The emulator and its version (`my-plc 0.4.1`), for the reports.
    fn version(&self) -> Option<String> {
        None
    }
}

/// An [`Emulator`] as a [`Backend`], run in process.
pub fn emulator_backend(emulator: impl Emulator + 'static) -> Arc<dyn Backend> {
    Arc::new(EmulatorBackend(emulator))
}

struct EmulatorBackend<E>(E);

impl<E: Emulator> Backend for EmulatorBackend<E> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn profile(&self) -> &str {
        self.0.profile()
    }
    fn describe(&self) -> String {
        "emulator (in process)".into()
    }
    fn version(&self) -> Option<String> {
        self.0.version()
    }
    fn claims(&self, instruction: &str, variant: &str) -> bool {
        self.0.claims(instruction, variant)
    }
    fn declines(&self, setting: &Setting<'_>) -> Option<String> {
        self.0.declines(setting)
    }
    fn checks_device_ranges(&self) -> bool {
        self.0.checks_device_ranges()
    }
    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        Ok(match self.0.execute(request) {
            Ok(outcome) => Response::Done(outcome),
            Err(unsupported) => unsupported.into(),
        })
    }
}
