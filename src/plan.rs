//! Planning and running trials: one per (backend, variant, instruction, case).

use std::sync::Arc;

use crate::backend::{Backend, Fault, Request, Response};
use crate::compare::{judge, Observation, Verdict};
use crate::memory::{Fill, Image};
use crate::model::{Case, Corpus};
use crate::profile::{Profile, Profiles};

/// One case as run by one backend on one variant of its profile.
#[derive(Clone)]
pub struct Trial {
    pub backend: Arc<dyn Backend>,
    pub profile: Arc<Profile>,
    pub variant: String,
    pub instruction: String,
    pub case: Arc<Case>,
    /// Why the trial is not run, when the backend does not claim it.
    pub skip: Option<String>,
}

impl Trial {
    /// `backend::instruction::case-id::variant`: filtering on a prefix selects a backend, an
    /// instruction or a case across variants.
    pub fn name(&self) -> String {
        format!(
            "{}::{}::{}::{}",
            self.backend.name(),
            self.instruction.to_lowercase(),
            self.case.id,
            self.variant
        )
    }

    /// Runs the case under every fill and judges it.
    pub fn run(&self) -> Verdict {
        let images = self.images();
        match self.requests(&images) {
            Ok(requests) => self.judge(self.backend.execute_batch(&requests)),
            Err(verdict) => verdict,
        }
    }

    /// Runs the case under every fill: what the backend did, before any judgement.
    pub fn observe(&self) -> Result<Vec<Observation>, Verdict> {
        let images = self.images();
        let requests = self.requests(&images)?;
        Ok(observations(self.backend.execute_batch(&requests)))
    }

    /// The memory before, once per fill (in [`Fill::ALL`] order).
    pub fn images(&self) -> Vec<Image> {
        Fill::ALL
            .iter()
            .map(|&fill| Image::new(self.case.before.clone(), fill))
            .collect()
    }

    /// The requests that run the case on the images; callers that batch many trials collect
    /// these. A trial whose variant the profile lacks is already judged.
    pub fn requests<'a>(&'a self, images: &'a [Image]) -> Result<Vec<Request<'a>>, Verdict> {
        let Some(variant) = self.profile.variant(&self.variant) else {
            return Err(Verdict::Unsupported {
                reason: format!(
                    "profile {} has no variant {}",
                    self.profile.id, self.variant
                ),
            });
        };
        Ok(images
            .iter()
            .map(|memory| Request {
                profile: &self.profile,
                variant,
                instruction: &self.instruction,
                case_id: &self.case.id,
                flags: &self.case.flags,
                operands: &self.case.operands,
                memory,
            })
            .collect())
    }

    /// Judges the answers to [`Trial::requests`], in the same order.
    pub fn judge(&self, results: Vec<Result<Response, Fault>>) -> Verdict {
        judge(&self.case, &observations(results))
    }
}

/// Answers to the requests of [`Trial::requests`], paired with their fills.
fn observations(results: Vec<Result<Response, Fault>>) -> Vec<Observation> {
    Fill::ALL
        .iter()
        .zip(results)
        .map(|(&fill, result)| Observation { fill, result })
        .collect()
}

/// Every trial of the corpus on the given backends, in corpus order. A case runs on a backend
/// when the backend implements one of the case's profiles; within that, on every variant the
/// case allows and for every instruction of its file.
pub fn plan(corpus: &Corpus, profiles: &Profiles, backends: &[Arc<dyn Backend>]) -> Vec<Trial> {
    let mut trials = Vec::new();
    for backend in backends {
        for case in &corpus.cases {
            if !case.profiles.iter().any(|p| p == backend.profile()) {
                continue;
            }
            let Some(profile) = profiles.get(backend.profile()) else {
                continue;
            };
            for instruction in case.instructions.iter() {
                for variant in profile.variants.iter().filter(|v| case.runs_on(&v.id)) {
                    let skip = if backend.claims(instruction, &variant.id) {
                        backend.declines(&case.flags, instruction, variant)
                    } else {
                        Some(format!(
                            "{} does not implement {instruction} on {}",
                            backend.name(),
                            variant.id
                        ))
                    };
                    trials.push(Trial {
                        backend: backend.clone(),
                        profile: profile.clone(),
                        variant: variant.id.clone(),
                        instruction: instruction.clone(),
                        case: case.clone(),
                        skip,
                    });
                }
            }
        }
    }
    trials
}
