//! The built-in reference models asked directly: the same request the plan and the executor
//! would make for a trial (the plan's lowering, both fills), answered by the model's
//! `Backend::execute`, and recorded as the judge records an `unspecified` case — without
//! building a trial per input. An instruction's memory images are built once per input and
//! shared by every variant; a lowering's operands once per digit count, its two images share
//! one set of words. The sweep's white-box tests (`white_box.rs`) check that this gives exactly
//! the replies of the trial path (`runner::run_one`).

use std::collections::BTreeMap;
use std::sync::Arc;

use super::group::Reply;
use super::input::{Data, Point};
use super::target::{case_id, Ask, Cases, Column};
use crate::backend::{Fault, Request, Response};
use crate::device::Device;
use crate::judge::lift::lift;
use crate::judge::Effect;
use crate::memory::{Fill, Image, Unit, Value};
use crate::model::cross_vendor::{Lowering, Operation};
use crate::model::{Operand, DIRECT};
use crate::plan::{declined, lowering, Input};

/// The memory of one input under both fills, sharing its words.
pub(crate) struct Images([Image; 2]);

impl Images {
    pub(crate) fn of(input: &Input, unit: Unit) -> Images {
        Images::from_words(input.before.clone(), unit)
    }

    fn from_words(words: BTreeMap<Device, Value>, unit: Unit) -> Images {
        let words = Arc::new(words);
        Images([
            Image::sharing(words.clone(), Fill::A, unit),
            Image::sharing(words, Fill::B, unit),
        ])
    }
}

/// A lowering column's operands by digit count: the same for every text of a count, so a
/// worker makes them once per count rather than per input.
#[derive(Default)]
pub(crate) struct Lowered(Vec<(u32, BTreeMap<String, Operand>)>);

impl Lowered {
    fn operands(&mut self, lowering: &Lowering, digits: u32) -> &BTreeMap<String, Operand> {
        let at = match self.0.iter().position(|(d, _)| *d == digits) {
            Some(at) => at,
            None => {
                self.0.push((digits, lowering::operands(lowering, digits)));
                self.0.len() - 1
            }
        };
        &self.0[at].1
    }
}

/// One column's reply to one input. `native` is the instruction input and its images for an
/// instruction sweep; a lowering makes its own, with its operands from `lowered`.
pub(crate) fn reply(
    column: &Column,
    cases: &Cases,
    native: Option<&(Input, Images)>,
    lowered: &mut Lowered,
) -> Option<Reply> {
    let profile = column.profile.as_ref()?;
    let variant = profile.variant(&column.variant)?;
    let own_images;
    let (instruction, flags, operands, indirect, images, lowering, digits) =
        match (&column.ask, native) {
            (Ask::Lowering(l), _) => {
                let case = cases.cross_vendor.as_ref()?;
                if let Some(why) = &column.lowering_skip {
                    return Some(Reply::Skipped {
                        reason: why.clone(),
                    });
                }
                // The request reads memory from the images only.
                own_images = Images::from_words(lowering::memory(l, case), profile.unit);
                (
                    &l.instruction,
                    &l.flags,
                    lowered.operands(l, case.digits),
                    DIRECT,
                    &own_images,
                    Some(l),
                    case.digits,
                )
            }
            (Ask::Instruction, Some((input, images))) => {
                if let Some(reason) =
                    declined(column.backend.as_ref(), profile, &column.variant, input)
                {
                    return Some(Reply::Skipped { reason });
                }
                (
                    &input.instruction,
                    &input.flags,
                    &input.operands,
                    &input.indirect,
                    images,
                    None,
                    0,
                )
            }
            _ => return None,
        };
    let mut outcomes = Vec::with_capacity(2);
    for image in &images.0 {
        let request = Request {
            profile,
            variant,
            instruction,
            case_id: "sweep",
            flags,
            operands,
            indirect,
            memory: image,
        };
        match column.backend.execute(&request) {
            Ok(Response::Done(o)) => outcomes.push(o),
            Ok(Response::Unsupported(reason)) => {
                return Some(Reply::Failed {
                    label: "unsupported".into(),
                    detail: reason,
                })
            }
            Ok(Response::Answer(_)) => {
                return Some(Reply::Failed {
                    label: "protocol-error".into(),
                    detail: "a codec answer answered an instruction request".into(),
                })
            }
            Err(fault) => {
                return Some(Reply::Failed {
                    label: fault.kind().to_string(),
                    detail: fault.to_string(),
                })
            }
        }
    }
    let [a, b] = &images.0;
    Some(match lowering {
        Some(l) => {
            let first = lift(profile, l, digits, &outcomes[0], a);
            let second = lift(profile, l, digits, &outcomes[1], b);
            Reply::Answer {
                fill_dependent: first != second,
                answer: first,
            }
        }
        None => {
            let first = Effect::of(a, &outcomes[0]);
            let second = Effect::of(b, &outcomes[1]);
            Reply::Memory {
                fill_dependent: first != second,
                effect: first,
            }
        }
    })
}

/// A codec column's replies to the points, asked in one batch (`Backend::convert_batch`, which
/// a codec in another process answers in a few messages): `(point, reply)` per point, one outside
/// its abilities skipped with the plan's reason. A reply is what the judge records of an
/// `unspecified` codec trial (`white_box.rs` checks it against the trial path); `None` for a
/// question the stop left unanswered.
pub(crate) fn codec_replies(
    column: &Column,
    operation: Operation,
    points: &[(u64, Point)],
    stop: &std::sync::atomic::AtomicBool,
) -> Vec<(usize, Option<Reply>)> {
    let backend = column.backend.as_ref();
    let Some(abilities) = backend.codec() else {
        return Vec::new();
    };
    let ids: Vec<String> = points.iter().map(|(i, _)| case_id(*i)).collect();
    let mut out = Vec::with_capacity(points.len());
    let mut asked = Vec::new();
    let mut questions = Vec::new();
    for (p, ((_, point), id)) in points.iter().zip(&ids).enumerate() {
        let (text, value): (&[u8], u64) = match &point.data {
            Data::Text(t) => (t, 0),
            Data::Value(v) => (&[], *v),
        };
        match abilities.declines_asking(operation, text, value, point.digits, None) {
            Some(why) => out.push((
                p,
                Some(Reply::Skipped {
                    reason: format!("{} {why}", backend.name()),
                }),
            )),
            None => {
                asked.push(p);
                questions.push(crate::backend::Question {
                    case_id: id,
                    operation,
                    text,
                    value,
                    digits: point.digits,
                    field: "",
                });
            }
        }
    }
    let answers = backend.convert_batch(&questions, &mut |_| {});
    let stopped = stop.load(std::sync::atomic::Ordering::Relaxed);
    for (p, answer) in asked.into_iter().zip(answers) {
        let reply = match answer {
            Ok(Response::Answer(answer)) => Some(Reply::Answer {
                answer,
                fill_dependent: false,
            }),
            Ok(Response::Unsupported(reason)) => Some(Reply::Failed {
                label: "unsupported".into(),
                detail: reason,
            }),
            // A question the stop cut off was not answered: it is not counted as swept.
            Err(_) if stopped => None,
            Ok(Response::Done(_)) => Some(Reply::failed(&Fault::Protocol(
                "an instruction's outcome answered a codec question".into(),
            ))),
            Err(fault) => Some(Reply::failed(&fault)),
        };
        out.push((p, reply));
    }
    out
}
