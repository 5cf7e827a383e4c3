//! What the built-in reference models share: they are pure functions of the request, named after
//! their profile, and claim exactly the instructions they model on the variants that have them.

use std::marker::PhantomData;
use std::sync::Arc;

use super::{Backend, Fault, Outcome, Request, Response, Unsupported};
use crate::memory::Value;
use crate::model::profile::{Profile, Profiles};
use crate::model::ErrorSignal;
use crate::value::{narrow, to_bits};

/// One vendor family's reference model.
pub(crate) trait Model: Send + Sync + 'static {
    /// The profile id the model implements.
    const PROFILE: &'static str;
    /// The instructions the model runs, each by its function, for a model whose instruction's
    /// name is all it needs to choose (one that reads a width or a pulse form from the name
    /// gives `models` and `run` instead).
    const INSTRUCTIONS: &'static [(&'static str, Run)] = &[];
    /// Whether the model covers an instruction.
    fn models(instruction: &str) -> bool {
        Self::INSTRUCTIONS
            .iter()
            .any(|(name, _)| *name == instruction)
    }
    /// Executes one request.
    fn run(req: &Request<'_>) -> Result<Outcome, Stop> {
        match Self::INSTRUCTIONS
            .iter()
            .find(|(name, _)| *name == req.instruction)
        {
            Some((_, run)) => run(req),
            None => Err(Unsupported(format!("{} is not modelled", req.instruction)).into()),
        }
    }
}

/// One instruction of a model, run on a request.
pub(crate) type Run = fn(&Request<'_>) -> Result<Outcome, Stop>;

/// A 16-bit constant operand as the CPU holds it (`K-1` is FFFFH); one past 16 bits is not
/// programmable, so a model declines it.
pub(crate) fn constant_word(name: &str, k: i64) -> Result<u16, Unsupported> {
    // Asked once per execution: the constant's text is written only for the refusal.
    match narrow(k, 16) {
        Some(w) => Ok(w as u16),
        None => to_bits(&format!("K{k}"), k, 16)
            .map(|w| w as u16)
            .map_err(|e| Unsupported(format!("operand `{name}`: {e}"))),
    }
}

/// Why an instruction stopped short.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Stop {
    /// An operation error with the vendor's code: the instruction writes nothing. Profiles that
    /// signal with a flag only see the flag (see [`Request::error`]).
    Error(u16),
    /// The request asks for something the model does not implement.
    Unsupported(Unsupported),
}

impl From<Unsupported> for Stop {
    fn from(u: Unsupported) -> Self {
        Stop::Unsupported(u)
    }
}

/// The model's backend, when its profile is loaded: what [`super::reference_backends`] lists.
pub(crate) fn backend<M: Model>(profiles: &Profiles) -> Option<Arc<dyn Backend>> {
    profiles
        .get(M::PROFILE)
        .map(|p| Arc::new(Reference::<M>::new(p)) as Arc<dyn Backend>)
}

/// A reference model as a backend.
pub(crate) struct Reference<M> {
    name: String,
    profile: Profile,
    model: PhantomData<fn() -> M>,
}

impl<M: Model> Reference<M> {
    pub(crate) fn new(profile: &Profile) -> Self {
        Reference {
            name: profile.short.clone(),
            profile: profile.clone(),
            model: PhantomData,
        }
    }
}

impl<M: Model> Backend for Reference<M> {
    fn name(&self) -> &str {
        &self.name
    }
    fn profile(&self) -> &str {
        M::PROFILE
    }
    fn describe(&self) -> String {
        format!("reference model of {} (built in)", self.profile.name)
    }
    fn version(&self) -> Option<String> {
        Some(format!("plc-conformance {}", env!("CARGO_PKG_VERSION")))
    }
    fn simulated_by(&self) -> Option<String> {
        Some(format!(
            "the built-in reference model of {}",
            self.profile.name
        ))
    }
    fn claims(&self, instruction: &str, variant: &str) -> bool {
        M::models(instruction)
            && self
                .profile
                .variant(variant)
                .is_some_and(|v| self.profile.has_instruction(v, instruction))
    }
    fn execute(&self, req: &Request<'_>) -> Result<Response, Fault> {
        if !M::models(req.instruction) {
            return Ok(Unsupported(format!("{} is not modelled", req.instruction)).into());
        }
        let mut outcome = match M::run(req) {
            Ok(outcome) => outcome,
            Err(Stop::Error(code)) => Outcome::error(req.error(code)),
            Err(Stop::Unsupported(u)) => return Ok(u.into()),
        };
        // The code lands where the profile says (SD0, and SD8067 on FX5): the model holds
        // those registers as the CPU does, so a backend that reports them is judged on them.
        if let Some(ErrorSignal::Code(code)) = outcome.error {
            outcome.registers = (self.profile.errors.code_registers().into_iter())
                .map(|r| (r, Value::from(code)))
                .collect();
        }
        Ok(Response::Done(outcome))
    }
}
