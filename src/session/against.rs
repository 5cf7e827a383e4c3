//! `diff --against`: one backend's trials judged against what another did, with the same
//! diffs, faults and reports as a run against the corpus.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::run::observe;
use super::Session;
use crate::backend::{Backend, Response};
use crate::execute::Observation;
use crate::judge::lift::lift;
use crate::judge::{Effect, Verdict};
use crate::model::cross_vendor::CrossVendorCase;
use crate::model::{Basis, Case, Citation, Expectation};
use crate::plan::{Check, Trial};

/// Two backends' shared trials: the second's trials with the first's outcome as their
/// expectation, ready to run and judge; and the first's trials that give nothing to judge
/// against, with the verdict that says why.
pub(crate) struct Against {
    pub paired: Vec<Trial>,
    pub unpaired: Vec<(Trial, Verdict)>,
}

impl Session {
    /// Runs `a`'s trials that `b` also runs (those whose names contain `filter`), batched as any
    /// run is, and pairs each with `b`'s trial of the same question. Backends of one family
    /// share every trial; backends of different families meet on the cross-vendor cases,
    /// through their own lowerings. An interrupted run pairs what it observed.
    pub(crate) fn against(
        &self,
        a: &Arc<dyn Backend>,
        b: &Arc<dyn Backend>,
        filter: Option<&str>,
        jobs: usize,
        stop: &AtomicBool,
    ) -> Against {
        let trials_a: Vec<Trial> = (self.plan(std::slice::from_ref(a)).into_iter())
            .filter(|t| filter.is_none_or(|f| t.name().contains(f)))
            .collect();
        let trials_b = self.plan(std::slice::from_ref(b));
        let key = |t: &Trial| {
            (
                t.is_cross_vendor(),
                t.input.instruction.clone(),
                t.case_id().to_string(),
                t.check_name().to_string(),
                t.variant.clone(),
            )
        };
        let same_family = a.profile() == b.profile();
        let pairs: Vec<(&Trial, &Trial)> = (trials_a.iter().filter(|t| t.skip.is_none()))
            .filter_map(|ta| {
                let tb = if same_family {
                    (trials_b.iter()).find(|t| t.skip.is_none() && key(t) == key(ta))
                } else {
                    trials_b.iter().find(|t| {
                        t.skip.is_none()
                            && t.is_cross_vendor()
                            && ta.is_cross_vendor()
                            && t.case_id() == ta.case_id()
                    })
                };
                tb.map(|tb| (ta, tb))
            })
            .collect();
        let asked: Vec<Trial> = pairs.iter().map(|(ta, _)| (*ta).clone()).collect();
        let observed = observe(&asked, jobs, stop);
        let mut out = Against {
            paired: Vec::new(),
            unpaired: Vec::new(),
        };
        for ((ta, tb), observations) in pairs.into_iter().zip(observed) {
            let Some(observations) = observations else {
                continue;
            };
            match judged_against(ta, &observations, tb) {
                Ok(t) => out.paired.push(t),
                Err(verdict) => out.unpaired.push((ta.clone(), verdict)),
            }
        }
        out
    }
}

/// The second backend's trial with the first backend's answer as its expectation (`diff
/// --against`): judging it says where the second parts from the first, with the same diffs,
/// faults and reports as a run against the corpus. `Err` is the verdict on the first backend's
/// trial when it gives nothing to judge against: a fault, an unsupported answer, or an outcome
/// that depends on the fill.
fn judged_against(first: &Trial, did: &[Observation], second: &Trial) -> Result<Trial, Verdict> {
    let name = first.backend.name();
    let mut answers = Vec::new();
    let mut effects = Vec::new();
    for o in did {
        match &o.result {
            Err(fault) => {
                return Err(Verdict::Fault {
                    fill: o.fill,
                    fault: fault.clone(),
                })
            }
            Ok(Response::Unsupported(reason)) => {
                return Err(Verdict::Unsupported {
                    reason: reason.clone(),
                })
            }
            Ok(Response::Answer(a)) => answers.push(a.clone()),
            Ok(Response::Done(outcome)) => match (&first.check, &first.profile) {
                (Check::CrossVendor { lowering, case }, Some(profile)) => answers.push(lift(
                    profile,
                    lowering,
                    case.digits,
                    outcome,
                    &first.image(o.fill),
                )),
                _ => effects.push(Effect::of(&first.image(o.fill), outcome)),
            },
        }
    }
    let fill_dependent = |what: String| Verdict::Unsupported {
        reason: format!("{name}'s outcome depends on the fill ({what}): nothing to judge against"),
    };
    let citation = Citation {
        manual: format!("backend {name}"),
        page: String::new(),
        text: Some("its outcome on this trial".into()),
    };
    let check = match (&second.check, effects.as_slice(), answers.as_slice()) {
        (Check::Native { instruction, case }, [e, rest @ ..], []) => {
            if let Some(other) = rest.iter().find(|x| *x != e) {
                return Err(fill_dependent(format!("{e} / {other}")));
            }
            Check::Native {
                instruction: instruction.clone(),
                case: Arc::new(Case {
                    basis: Basis::Observed,
                    citation,
                    expect: Some(Expectation {
                        after: e.changed.clone(),
                        error: e.error.clone(),
                    }),
                    ..(**case).clone()
                }),
            }
        }
        (Check::CrossVendor { case, .. } | Check::Codec { case }, [], [a, rest @ ..]) => {
            if let Some(other) = rest.iter().find(|x| *x != a) {
                return Err(fill_dependent(format!("{a} / {other}")));
            }
            let case = Arc::new(CrossVendorCase {
                basis: Basis::Observed,
                citation,
                expect: Some(a.clone()),
                except: Default::default(),
                ..(**case).clone()
            });
            match &second.check {
                Check::CrossVendor { lowering, .. } => Check::CrossVendor {
                    lowering: lowering.clone(),
                    case,
                },
                _ => Check::Codec { case },
            }
        }
        _ => {
            return Err(Verdict::Unsupported {
                reason: format!(
                    "{name} answered another kind of question than {} asks",
                    second.backend.name()
                ),
            })
        }
    };
    Ok(Trial {
        check,
        known: None,
        ..second.clone()
    })
}
