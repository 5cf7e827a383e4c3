//! Differential sweeps: generated inputs run on several backends, the inputs on which they
//! disagree grouped by behaviour, each group shrunk to a minimal input and written back as a
//! vector.
//!
//! A sweep is built on the pipeline, not beside it. Every generated input becomes an
//! `unspecified` case — a cross-vendor case for an operation, a native case for an instruction —
//! and each column (a backend through a lowering, or on a variant) runs it as a
//! [`crate::plan::Trial`]: the plan's lowering makes its memory and operands, the executor runs
//! it under both fills, and the judge records what the backend did as a
//! [`crate::judge::Verdict`]. External backends get the trials through [`crate::session::run_trials`]
//! with a [`crate::report::Reporter`] that keeps the verdicts, batched as in any run and stopped
//! by the same flag. The built-in reference models run in process, spread over threads: each
//! input's request is made as the plan makes it and answered by the model directly
//! ([`direct`]), because millions of inputs would otherwise spend their time building trials
//! rather than in the models; `Settings::direct = false` runs them as trials with
//! [`crate::session::run_one`] instead, with the same replies.
//!
//! - [`generate`]: the generators, each a numbered space of inputs ([`generate::Space`]);
//! - [`classes`]: byte classes, by which the full generator covers all 2^32 texts;
//! - [`target`]: what is swept (an operation or an instruction) and the columns;
//! - [`group`]: answers reduced to behaviour signatures and counted;
//! - [`shrink`]: a group's inputs reduced to the simplest that behaves the same;
//! - [`emit`]: a shrunk input written as a vector in the corpus format;
//! - [`explain`]: a judged codec's differences read for the field shape that would describe them;
//! - [`merge`]: the JSON results of a sweep's shards put back together as the whole sweep's;
//! - [`render`]: the results as text, JSON and HTML.

pub(crate) mod classes;
pub(crate) mod direct;
pub mod emit;
pub(crate) mod exhaustive;
pub(crate) mod explain;
pub(crate) mod generate;
pub(crate) mod group;
pub(crate) mod input;
pub(crate) mod known;
pub(crate) mod merge;
pub mod render;
pub(crate) mod request;
pub(crate) mod rng;
pub(crate) mod shrink;
pub(crate) mod target;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::backend::Backend;
use crate::model::profile::Profiles;
use crate::report::{Event, Reporter};
use generate::{shard_indices, Digits, Generator, Space};
use group::{Found, Groups, Reply};
use input::Point;
pub(crate) use target::Oracle;
use target::{columns, Ask, Cases, Column, Shape, Target};

/// Random texts that check the byte classes of a full sweep by class.
pub(crate) const DEFAULT_CLASS_CHECK: u64 = 1 << 20;

/// What to sweep and how.
#[derive(Debug, Clone, Serialize)]
pub struct Settings {
    pub target: Target,
    pub generator: Generator,
    pub seed: u64,
    pub digits: Digits,
    /// `(k, n)`: run the k-th of n shards (1-based); `(1, 1)` is the whole sweep.
    pub shard: (u64, u64),
    /// Threads for the built-in models, backends side by side for the others.
    #[serde(skip)]
    pub jobs: usize,
    /// Classes counted separately per group.
    #[serde(skip)]
    pub max_classes: usize,
    /// Classes shrunk and written as vectors per group (the largest first); 0 shrinks none.
    #[serde(skip)]
    pub shrink: usize,
    /// Ask the built-in models directly (`direct`) rather than through a trial per input;
    /// the replies are the same.
    #[serde(skip)]
    pub direct: bool,
    /// The full generator by class: random texts asked as they are, to check the classes.
    pub class_check: u64,
    /// What codec columns are judged against (operation sweeps).
    pub oracle: Oracle,
    /// The full generator asking each text of hex-to-value over the built-in lowerings asks
    /// them through the lowerings' rules (`exhaustive`); the results are the same.
    #[serde(skip)]
    pub exhaustive: bool,
}

impl Settings {
    /// The classes a group keeps: `max_classes`, except in a shard, which keeps them all so that
    /// a merge can keep the whole sweep's first `max_classes` (`merge`).
    pub(crate) fn class_cap(&self) -> usize {
        if self.shard.1 > 1 {
            usize::MAX
        } else {
            self.max_classes
        }
    }

    pub fn new(target: Target, generator: Generator, seed: u64) -> Settings {
        Settings {
            target,
            generator,
            seed,
            digits: Digits::Natural,
            shard: (1, 1),
            jobs: crate::execute::default_jobs(),
            max_classes: 64,
            shrink: 4,
            direct: true,
            class_check: DEFAULT_CLASS_CHECK,
            oracle: Oracle::Declared,
            exhaustive: true,
        }
    }
}

/// A sweep ready to run: its columns and its space of inputs.
pub struct Sweep {
    pub settings: Settings,
    pub columns: Vec<Column>,
    pub shape: Option<Shape>,
    pub space: Space,
}

/// A column as the results name it.
#[derive(Debug, Clone, Serialize)]
pub struct ColumnInfo {
    pub name: String,
    pub backend: String,
    pub description: String,
    /// The column it is judged against.
    pub oracle: Option<String>,
    /// What a known-differences entry names as the instruction: the instruction, the
    /// lowering, or `codec`, as for a trial of the corpus.
    #[serde(skip)]
    pub check: String,
    #[serde(skip)]
    pub variant: String,
}

/// A group's input reduced to the simplest one that behaves the same.
#[derive(Debug, Clone, Serialize)]
pub struct Shrunk {
    /// The group's place in [`Results::groups`] order.
    pub group: usize,
    pub class: String,
    pub from: Found,
    pub to: Found,
}

/// What a sweep found.
#[derive(Debug, Serialize)]
pub struct Results {
    pub settings: Settings,
    pub columns: Vec<ColumnInfo>,
    /// Inputs in the whole space (every shard).
    pub space: u64,
    /// Inputs in this shard.
    pub shard_inputs: u64,
    /// Inputs run (all of the shard unless interrupted).
    pub swept: u64,
    pub interrupted: bool,
    #[serde(skip)]
    pub elapsed: Duration,
    /// The groups, in [`Groups::sorted`] order.
    #[serde(skip)]
    pub groups: Groups,
    pub shrunk: Vec<Shrunk>,
    /// The full generator by class: the classes and their check.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub classes: Option<classes::Report>,
    /// Every text asked through the built-in lowerings' rules (`exhaustive`): how.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exhaustive: Option<exhaustive::Report>,
    /// Field shapes that would describe a judged codec's differences (`sweep::explain`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub hints: Vec<explain::Hint>,
}

impl Results {
    /// Why the counts are not exact, when they are not: the byte classes did not hold, or the
    /// built-in models answered unlike their rules as every text was asked. Such a sweep fails
    /// whatever else it found.
    pub(crate) fn inexact(&self) -> Option<String> {
        if let Some(m) = self.classes.as_ref().and_then(|c| c.mismatch.as_ref()) {
            return Some(format!(
                "the byte classes do not hold: {} answers differently from its class \
                 representative {}; the counts above are not exact (--each-text asks every text)",
                m.text.point, m.representative.point
            ));
        }
        let disagreement = (self.exhaustive.as_ref()).and_then(|e| e.disagreement.as_ref())?;
        Some(format!(
            "the built-in models answer {} unlike their rules as the sweep asked every text; the \
             counts above are not exact",
            disagreement.point
        ))
    }

    /// The groups in report order.
    pub fn ordered(&self) -> Vec<&group::Group> {
        self.groups.sorted()
    }

    /// The columns whose backend faulted (crashed, hung, answered garbage or not at all, or
    /// said `unsupported` of an input it claimed), with how and on how many inputs: a sweep with
    /// one is a failure, whatever else it found, since those inputs were never answered.
    pub fn faulted(&self) -> Vec<Faulted> {
        let mut out: Vec<Faulted> = Vec::new();
        for g in self.groups.by_key.values() {
            for (column, reply) in self.columns.iter().zip(&g.representative.replies) {
                let group::Reply::Failed { label, .. } = reply else {
                    continue;
                };
                match out
                    .iter_mut()
                    .find(|f| f.column == column.name && f.label == *label)
                {
                    Some(f) => f.inputs += g.inputs,
                    None => out.push(Faulted {
                        column: column.name.clone(),
                        label: label.clone(),
                        inputs: g.inputs,
                    }),
                }
            }
        }
        out
    }

    /// Whether any column differs from its oracle.
    pub fn differs(&self) -> bool {
        self.groups.by_key.values().any(|g| !g.differing.is_empty())
    }
}

/// A column that faulted: how, and on how many inputs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Faulted {
    pub column: String,
    pub label: String,
    pub inputs: u64,
}

/// Inputs per round for a sweep with an external backend (one `session::run_trials` each).
const CHUNK_EXTERNAL: usize = 4096;
/// Inputs per round for the built-in models and codecs asked directly.
const CHUNK_IN_PROCESS: usize = 1 << 16;
/// Bytes of text per round, whatever the count: million-byte random texts (`--length
/// 1000000`) are made, held and asked a few to a round, so a stop, read between rounds, is
/// honoured within a fraction of a second whatever the texts' length.
const ROUND_BYTES: usize = 1 << 22;

/// Why a sweep cannot be set up as asked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepError(pub String);

impl std::fmt::Display for SweepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SweepError {}

/// A whole sweep's results, known differences applied.
#[derive(Debug)]
pub(crate) struct Completed {
    pub results: Results,
    /// The known-differences entries could cover nothing here: a value-to-hex sweep's inputs
    /// have no input class, so only an entry for every case (`cases: ['*']`) covers them.
    pub known_cover_nothing: bool,
}

impl Sweep {
    /// The sweep as one operation, for a command or a test alike: its inputs asked of the
    /// backends (`progress` hears how many of how many), or, given the JSON results of its
    /// shards, put back together from them; then made whole against `known` ([`Sweep::conclude`]).
    pub(crate) fn complete(
        &self,
        shards: Option<&[(std::path::PathBuf, merge::ShardFile)]>,
        known: &std::collections::BTreeMap<String, crate::model::known::KnownDifferences>,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Completed, SweepError> {
        let mut results = match shards {
            Some(files) => merge::merge(self, files, stop)?,
            None => self.run(stop, progress),
        };
        let known_cover_nothing = self.conclude(&mut results, known);
        Ok(Completed {
            results,
            known_cover_nothing,
        })
    }

    /// Makes the results whole: the groups of a judged column that a known-differences entry
    /// covers set apart, and the hints that explain the rest. `true` when the entries could
    /// cover nothing (a value-to-hex sweep's inputs have no input class).
    fn conclude(
        &self,
        results: &mut Results,
        known: &std::collections::BTreeMap<String, crate::model::known::KnownDifferences>,
    ) -> bool {
        let stale = known::apply(results, known);
        results.hints = explain::hints(self, results);
        stale
    }

    /// Sets up a sweep of `settings.target` on `backends`. The reference model of each profile
    /// involved should be among them: it is the oracle.
    pub fn new(
        settings: Settings,
        profiles: &Profiles,
        backends: &[Arc<dyn Backend>],
    ) -> Result<Sweep, SweepError> {
        let shape = match &settings.target {
            Target::Instruction {
                profile,
                instruction,
            } => {
                let p = profiles
                    .get(profile)
                    .ok_or_else(|| SweepError(format!("no profile `{profile}`")))?;
                Some(Shape::of(p, instruction)?)
            }
            Target::Operation { .. } => None,
        };
        let columns = columns(&settings.target, profiles, backends, &settings.oracle)?;
        let reads = settings.target.reads(shape.as_ref());
        let text = reads == crate::model::cross_vendor::Operation::HexToValue;
        if text != settings.generator.makes_text() && settings.generator.name() != "random" {
            return Err(SweepError(format!(
                "the {} generator makes {}, but {} reads {}",
                settings.generator.name(),
                if settings.generator.makes_text() {
                    "texts"
                } else {
                    "values"
                },
                settings.target,
                if text { "text" } else { "a value" }
            )));
        }
        let counted = match &shape {
            Some(s) => s.count.is_some(),
            None => true,
        };
        let mut space = Space::new(
            settings.generator.clone(),
            settings.seed,
            settings.digits.clone(),
            counted,
        );
        space.reads_text = text;
        if let Some(s) = &shape {
            space.flags = s.flags.clone();
            space.value_bits = 16 * s.words;
            space.range_ends = range_ends(s);
        } else {
            space.value_bits = 32;
        }
        let (k, n) = settings.shard;
        if n == 0 || k == 0 || k > n {
            return Err(SweepError(format!(
                "shard {k}/{n}: give K/N with 1 <= K <= N"
            )));
        }
        Ok(Sweep {
            settings,
            columns,
            shape,
            space,
        })
    }

    /// Whether the target takes a digit count.
    pub fn counted(&self) -> bool {
        self.space.counted
    }

    /// The answers of every column to each point, in column order; `None` for a point the run
    /// was stopped before answering.
    pub fn answers(&self, points: &[(u64, Point)], stop: &AtomicBool) -> Vec<Option<Vec<Reply>>> {
        let n = self.columns.len();
        let mut out: Vec<Vec<Option<Reply>>> = vec![vec![None; n]; points.len()];
        let in_process: Vec<usize> = (0..n).filter(|&c| self.columns[c].in_process).collect();
        let target = &self.settings.target;
        // Codecs are asked their questions directly, in one batch each, while the models work:
        // a trial per question would cost more than the conversion, and a codec in another
        // process would leave this one waiting (`Settings::direct` off asks them through
        // trials, with the same replies).
        let codecs: Vec<usize> = (0..n)
            .filter(|&c| self.settings.direct && matches!(self.columns[c].ask, Ask::Codec))
            .collect();
        let operation = target.reads(self.shape.as_ref());
        let asked: Vec<Vec<(usize, Option<Reply>)>> = std::thread::scope(|scope| {
            let handles: Vec<_> = codecs
                .iter()
                .filter(|_| !stop.load(Ordering::Relaxed))
                .map(|&c| {
                    let column = &self.columns[c];
                    scope.spawn(move || direct::codec_replies(column, operation, points, stop))
                })
                .collect();
            if !in_process.is_empty() {
                let jobs = self.settings.jobs.max(1);
                let per = points.len().div_ceil(jobs).max(1);
                for (rows, points) in out.chunks_mut(per).zip(points.chunks(per)) {
                    let columns = &self.columns;
                    let in_process = &in_process;
                    scope.spawn(move || {
                        let mut lowered: Vec<direct::Lowered> =
                            (0..n).map(|_| direct::Lowered::default()).collect();
                        for (row, (i, point)) in rows.iter_mut().zip(points) {
                            // An instruction asked directly needs only its input, made once for
                            // every variant; the other ways need the point's cases.
                            let native = match (self.settings.direct, &self.shape) {
                                (true, Some(shape)) => {
                                    let input = shape.input(point);
                                    let images = direct::Images::of(&input, shape.profile.unit);
                                    Some((input, images))
                                }
                                _ => None,
                            };
                            let cases = match native {
                                Some(_) => Cases::none(),
                                None => Cases::new(target, self.shape.as_ref(), *i, point),
                            };
                            for &c in in_process {
                                row[c] = if self.settings.direct {
                                    direct::reply(
                                        &columns[c],
                                        &cases,
                                        native.as_ref(),
                                        &mut lowered[c],
                                    )
                                } else {
                                    cases
                                        .trial(&columns[c])
                                        .map(|t| Reply::of(&crate::session::run_one(&t)))
                                };
                            }
                        }
                    });
                }
            }
            // A codec's panic is caught as its crash (`backend::convert_or_panic`); one of this
            // harness's own is not a result.
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect()
        });
        for (&c, replies) in codecs.iter().zip(asked) {
            for (p, reply) in replies {
                out[p][c] = reply;
            }
        }
        let others: Vec<usize> = (0..n)
            .filter(|&c| !self.columns[c].in_process && !codecs.contains(&c))
            .collect();
        if !others.is_empty() && !stop.load(Ordering::Relaxed) {
            let cases: Vec<Cases> = points
                .iter()
                .map(|(i, p)| Cases::new(target, self.shape.as_ref(), *i, p))
                .collect();
            let mut trials = Vec::new();
            let mut place = Vec::new();
            for (p, case) in cases.iter().enumerate() {
                for &c in &others {
                    if let Some(t) = case.trial(&self.columns[c]) {
                        trials.push(t);
                        place.push((p, c));
                    }
                }
            }
            let mut keep = Keep {
                place: &place,
                out: &mut out,
            };
            // Keep writes nothing, so the run cannot fail on a report.
            let _ = crate::session::run_trials(
                &trials,
                self.settings.jobs.max(1),
                &crate::execute::Stop::new(stop),
                crate::execute::Pace::Ahead,
                &mut keep,
            );
        }
        out.into_iter()
            .map(|row| row.into_iter().collect::<Option<Vec<Reply>>>())
            .collect()
    }

    /// Runs the sweep (this shard of it), calling `progress(done, of)` after each round, then
    /// shrinks the groups. Every text of hex-to-value through the built-in lowerings is asked
    /// through their rules ([`exhaustive`]), with the same results. A set `stop` ends it after the round under way, with what was found.
    /// The full generator by class first finds its byte classes and afterwards checks them
    /// ([`classes`]).
    pub fn run(&self, stop: &AtomicBool, progress: &mut dyn FnMut(u64, u64)) -> Results {
        if let Some(plan) = exhaustive::plan(self) {
            if let Some(results) = exhaustive::run(self, &plan, stop, progress) {
                return results;
            }
        }
        let started = Instant::now();
        let by_class = matches!(self.settings.generator, Generator::Full { by_class: true });
        let (space, split_texts) = self.space_to_run(stop);
        let weighted = space.classes.is_some();
        let shard = self.settings.shard;
        let shard_inputs = space.held_by(shard);
        // Codecs asked directly take a round's questions in bulk, as the models do; trials go
        // in smaller rounds, so that progress and a stop stay close to them.
        let chunk = if (self.columns.iter())
            .all(|c| c.in_process || (self.settings.direct && matches!(c.ask, Ask::Codec)))
        {
            CHUNK_IN_PROCESS
        } else {
            CHUNK_EXTERNAL
        };
        let mut groups = Groups::new(self.settings.class_cap());
        let mut digests = std::collections::HashMap::new();
        let mut swept = 0u64;
        let mut asked = 0u64;
        let mut indices = shard_indices(space.points(), shard);
        let mut interrupted = false;
        progress(0, shard_inputs);
        loop {
            if stop.load(Ordering::Relaxed) {
                interrupted = true;
                break;
            }
            let mut points: Vec<(u64, Point)> = Vec::new();
            let mut bytes = 0;
            while points.len() < chunk && bytes < ROUND_BYTES && !stop.load(Ordering::Relaxed) {
                let Some(i) = indices.next() else { break };
                let point = space.point(i);
                bytes += match &point.data {
                    input::Data::Text(t) => t.len(),
                    input::Data::Value(_) => 8,
                };
                points.push((i, point));
            }
            if points.is_empty() {
                break;
            }
            let answers = self.answers(&points, stop);
            for ((index, point), replies) in points.iter().zip(answers) {
                if let Some(replies) = replies {
                    let weight = space.weight(*index);
                    if weighted {
                        digests.insert(*index, classes::digest(&replies));
                    }
                    groups.add(
                        &self.columns,
                        self.counted(),
                        *index,
                        point,
                        replies,
                        weight,
                    );
                    swept += weight;
                    asked += 1;
                }
            }
            progress(swept, shard_inputs);
        }
        let class_report = space.classes.as_ref().filter(|_| by_class).map(|c| {
            let (checked, mismatch) = if interrupted {
                (0, None)
            } else {
                classes::check(self, c, &digests, self.settings.class_check, stop)
            };
            classes::Report {
                classes: c.describe(),
                split_texts,
                tuples: asked,
                checked,
                mismatch,
            }
        });
        let mut results = self.results(shard_inputs, swept, interrupted, groups, started);
        results.classes = class_report;
        if !stop.load(Ordering::Relaxed) {
            results.shrunk = shrink::shrink_groups(self, &results, stop);
        }
        results.elapsed = started.elapsed();
        results
    }

    /// The space the sweep numbers its inputs in: for the full generator by class, with the
    /// byte classes found first (and the texts asked to find them).
    pub(crate) fn space_to_run(&self, stop: &AtomicBool) -> (std::borrow::Cow<'_, Space>, u64) {
        let by_class = matches!(self.settings.generator, Generator::Full { by_class: true });
        match (&self.space.classes, by_class) {
            (None, true) => {
                let (found, asked) = classes::derive(self, stop)
                    .unwrap_or_else(|| (classes::ByteClasses::by_kind(), 0));
                let mut space = self.space.clone();
                space.classes = Some(Arc::new(found));
                (std::borrow::Cow::Owned(space), asked)
            }
            _ => (std::borrow::Cow::Borrowed(&self.space), 0),
        }
    }

    /// The results of this sweep with what was swept, before shrinking, with neither classes nor
    /// an exhaustive report.
    pub(crate) fn results(
        &self,
        shard_inputs: u64,
        swept: u64,
        interrupted: bool,
        groups: Groups,
        started: Instant,
    ) -> Results {
        Results {
            settings: self.settings.clone(),
            columns: self.column_info(),
            space: self.space.total(),
            shard_inputs,
            swept,
            interrupted,
            elapsed: started.elapsed(),
            groups,
            shrunk: Vec::new(),
            classes: None,
            exhaustive: None,
            hints: Vec::new(),
        }
    }

    pub fn column_info(&self) -> Vec<ColumnInfo> {
        self.columns
            .iter()
            .map(|c| ColumnInfo {
                name: c.name.clone(),
                backend: c.backend.name().to_string(),
                description: c.backend.describe(),
                oracle: c.oracle.map(|o| self.columns[o].name.clone()),
                check: match (&c.ask, &self.settings.target) {
                    (Ask::Lowering(l), _) => l.name.clone(),
                    (Ask::Codec, _) => "codec".into(),
                    (Ask::Instruction, Target::Instruction { instruction, .. }) => {
                        instruction.clone()
                    }
                    (Ask::Instruction, Target::Operation { .. }) => String::new(),
                },
                variant: c.variant.clone(),
            })
            .collect()
    }
}

/// Keeps each verdict of a batched run as a reply in its place.
struct Keep<'a> {
    place: &'a [(usize, usize)],
    out: &'a mut Vec<Vec<Option<Reply>>>,
}

impl Reporter for Keep<'_> {
    fn event(&mut self, event: &Event<'_>) -> std::io::Result<()> {
        if let Event::TrialFinished { index, verdict, .. } = event {
            // A cancelled trial leaves its input unanswered: it is not counted as swept.
            if let (Some(&(p, c)), false) = (
                self.place.get(*index),
                matches!(verdict, crate::judge::Verdict::Cancelled),
            ) {
                self.out[p][c] = Some(Reply::of(verdict));
            }
        }
        Ok(())
    }
}

/// The last words of each range of the source's device code on every variant: where the
/// random generator puts an operand to reach the end of a device range.
fn range_ends(shape: &Shape) -> Vec<crate::device::Device> {
    let Some(head) = shape.device(&shape.source) else {
        return Vec::new();
    };
    let mut ends: Vec<u32> = shape
        .profile
        .variants
        .iter()
        .filter_map(|v| shape.profile.ranges(v, head.code()))
        .flat_map(|r| r.iter().map(|r| r.last).collect::<Vec<_>>())
        .collect();
    ends.sort_unstable();
    ends.dedup();
    ends.into_iter()
        .map(|i| crate::device::Device::new(head.code(), i))
        .collect()
}

#[cfg(test)]
mod white_box;
