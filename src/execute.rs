//! Executing planned trials: each under every fill, batched per backend.
//!
//! Every trial runs under [`Fill::ALL`], so a stray write is always a change and a read of memory
//! the case does not set shows as a fill-dependent result. Trials of one backend are sent in
//! chunks (an external backend answers a chunk in one exchange, which is what makes it fast),
//! backends run side by side on their own threads, and each trial's observations are handed
//! back as soon as its chunk is answered, so a report can show the first difference while a slow
//! backend is still running.

use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::backend::{Fault, Question, Request, Response};
use crate::memory::{Fill, Image};
use crate::plan::{Check, Trial};

/// Why a run ended before every trial ran: what its end event and its reports say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stopped {
    /// A signal (SIGINT, SIGTERM) interrupted it: its backends were killed, and a trial they
    /// were running is cancelled, not failed.
    Interrupted,
    /// `--fail-fast`: a trial failed, and no batch started after it. The backends were left
    /// alone, so whatever finished is a result like any other.
    FailFast,
}

/// What a run checks before each batch: whether it is to stop.
pub trait ShouldStop: Sync {
    fn should_stop(&self) -> bool;
}

/// The process-wide interruption flag alone (or a test's own).
impl ShouldStop for AtomicBool {
    fn should_stop(&self) -> bool {
        self.load(Ordering::Relaxed)
    }
}

/// A run's stop: the interruption flag it was given, and its own decision to stop at the first
/// failure, kept apart so that the run can say which one ended it.
pub(crate) struct Stop<'a> {
    interrupt: &'a AtomicBool,
    failed: AtomicBool,
}

impl<'a> Stop<'a> {
    pub(crate) fn new(interrupt: &'a AtomicBool) -> Self {
        Stop {
            interrupt,
            failed: AtomicBool::new(false),
        }
    }

    /// A trial failed under `--fail-fast`: no further batch starts.
    pub(crate) fn at_failure(&self) {
        self.failed.store(true, Ordering::Relaxed);
    }

    /// Whether the interruption flag is set: the backends are being killed.
    pub(crate) fn interrupted(&self) -> bool {
        self.interrupt.load(Ordering::Relaxed)
    }

    /// Why the run stopped, if it did: an interruption wins over a failure.
    pub(crate) fn reason(&self) -> Option<Stopped> {
        if self.interrupted() {
            Some(Stopped::Interrupted)
        } else if self.failed.load(Ordering::Relaxed) {
            Some(Stopped::FailFast)
        } else {
            None
        }
    }
}

impl ShouldStop for Stop<'_> {
    fn should_stop(&self) -> bool {
        self.reason().is_some()
    }
}

/// What one backend did under one fill (a codec-level backend answers once, reported under
/// fill A: it reads no memory).
#[derive(Debug, Clone, Serialize)]
pub struct Observation {
    pub fill: Fill,
    pub result: Result<Response, Fault>,
}

/// What the executor reports while it runs.
#[derive(Debug)]
pub enum Progress {
    /// The observations of the trial at this index of the planned list, and the time it took:
    /// its batch's time shared equally among the batch's trials.
    Observed(usize, Vec<Observation>, Duration),
    /// A backend's process was started again after a fault; `restarts` counts them so far.
    Restarted { backend: String, restarts: usize },
    /// A backend is still answering its current chunk: `answered` of its `of` requests so far.
    /// Sent at most every `ANSWERING_EVERY`, so that only a slow chunk sends any.
    Answering {
        backend: String,
        answered: usize,
        of: usize,
    },
}

/// Backends run side by side when nothing says how many: one per CPU.
pub(crate) fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
}

/// Whether a backend's next chunk waits until the trials of the one before are judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// Execution runs ahead of judging: the fastest.
    Ahead,
    /// A chunk starts only once every observation sent before it has been handed to
    /// `progress`, so a stop set there (`--fail-fast`) holds every later chunk back however
    /// slowly the verdicts are written.
    Judged,
}

/// What a backend's thread sends the calling thread.
enum Message {
    Progress(Progress),
    /// Answered once everything sent before it has been handed on.
    Judged(mpsc::Sender<()>),
}

/// How often a chunk still being answered is reported.
pub(crate) const ANSWERING_EVERY: Duration = Duration::from_millis(250);

/// A callback for a backend's batch that reports, at most every [`ANSWERING_EVERY`], how many
/// of its `of` requests are answered.
fn answering<'a>(
    backend: &'a str,
    of: usize,
    tx: &'a mpsc::Sender<Message>,
) -> impl FnMut(usize) + 'a {
    let mut last = Instant::now();
    move |answered| {
        if answered < of && last.elapsed() >= ANSWERING_EVERY {
            last = Instant::now();
            let _ = tx.send(Message::Progress(Progress::Answering {
                backend: backend.to_string(),
                answered,
                of,
            }));
        }
    }
}

/// The memory before a trial, once per fill (in [`Fill::ALL`] order).
pub fn images(trial: &Trial) -> Vec<Image> {
    Fill::ALL.iter().map(|&fill| trial.image(fill)).collect()
}

/// The requests that run a trial on its images. A variant the profile lacks cannot happen for a
/// planned trial (the plan takes variants from the profile), and gives no request.
pub fn requests<'a>(trial: &'a Trial, images: &'a [Image]) -> Vec<Request<'a>> {
    let Some(profile) = &trial.profile else {
        return Vec::new();
    };
    let Some(variant) = profile.variant(&trial.variant) else {
        return Vec::new();
    };
    images
        .iter()
        .map(|memory| Request {
            profile,
            variant,
            instruction: &trial.input.instruction,
            case_id: trial.case_id(),
            flags: &trial.input.flags,
            operands: &trial.input.operands,
            indirect: &trial.input.indirect,
            memory,
        })
        .collect()
}

/// The question a codec-level trial asks.
pub(crate) fn question(trial: &Trial) -> Option<Question<'_>> {
    let Check::Codec { case } = &trial.check else {
        return None;
    };
    Some(Question {
        case_id: &case.id,
        operation: case.operation,
        text: &case.text,
        value: case.value,
        digits: case.digits,
        field: case.protocol.as_ref().map_or("", |p| p.field.as_str()),
    })
}

/// Runs one trial under every fill (a codec-level trial once).
pub(crate) fn execute(trial: &Trial) -> Vec<Observation> {
    if let Some(q) = question(trial) {
        return pair(trial.backend.convert_batch(&[q], &mut |_| {}));
    }
    let images = images(trial);
    let results = trial
        .backend
        .execute_batch(&requests(trial, &images), &mut |_| {});
    pair(results)
}

fn pair(results: Vec<Result<Response, Fault>>) -> Vec<Observation> {
    Fill::ALL
        .iter()
        .zip(results)
        .map(|(&fill, result)| Observation { fill, result })
        .collect()
}

/// Runs the trials at `indices` (skipped trials are not sent), each backend's in chunks on a
/// thread of its own with at most `jobs` backends at once, and calls `progress` on the calling
/// thread as results come in. Once `stop` is set, or `progress` breaks, no further chunk
/// starts; `pace` says whether a chunk may start before the previous one is handed on.
pub fn execute_all(
    trials: &[Trial],
    indices: &[usize],
    jobs: usize,
    stop: &dyn ShouldStop,
    pace: Pace,
    mut progress: impl FnMut(Progress) -> ControlFlow<()>,
) {
    let mut by_backend: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for &i in indices {
        if trials[i].skip.is_none() {
            by_backend
                .entry(trials[i].backend.name())
                .or_default()
                .push(i);
        }
    }
    let groups: Vec<Vec<usize>> = by_backend.into_values().collect();
    // `jobs` workers take backends in turn: a backend starts as soon as a worker is free, so a
    // slow backend holds up only its own worker.
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<Message>();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, groups.len().max(1)) {
            let (tx, groups, next) = (tx.clone(), &groups, &next);
            scope.spawn(move || {
                while let Some(group) = groups.get(next.fetch_add(1, Ordering::Relaxed)) {
                    run_backend(trials, group, stop, pace, &tx);
                }
            });
        }
        drop(tx);
        // Breaking drops the receiver: every backend's next send fails and it stops.
        for message in rx {
            match message {
                Message::Progress(p) => {
                    if progress(p).is_break() {
                        break;
                    }
                }
                Message::Judged(handed_on) => {
                    let _ = handed_on.send(());
                }
            }
        }
    });
}

/// One backend's trials, chunk by chunk.
fn run_backend(
    trials: &[Trial],
    group: &[usize],
    stop: &dyn ShouldStop,
    pace: Pace,
    tx: &mpsc::Sender<Message>,
) {
    let Some(&first) = group.first() else {
        return;
    };
    let backend = &trials[first].backend;
    let mut restarts = backend.restarts();
    for chunk in group.chunks(backend.chunk_trials().max(1)) {
        if stop.should_stop() {
            return;
        }
        let started = Instant::now();
        let each = |started: Instant| started.elapsed() / chunk.len().max(1) as u32;
        if backend.codec().is_some() {
            let questions: Vec<Question<'_>> =
                chunk.iter().filter_map(|&i| question(&trials[i])).collect();
            let mut answers = backend
                .convert_batch(
                    &questions,
                    &mut answering(backend.name(), questions.len(), tx),
                )
                .into_iter();
            let time = each(started);
            for &i in chunk {
                let answer = answers.next().unwrap_or_else(|| {
                    Err(Fault::Protocol("no answer to a codec question".into()))
                });
                if tx
                    .send(Message::Progress(Progress::Observed(
                        i,
                        pair(vec![answer]),
                        time,
                    )))
                    .is_err()
                {
                    return;
                }
            }
        } else {
            let images: Vec<Vec<Image>> = chunk.iter().map(|&i| images(&trials[i])).collect();
            let mut all = Vec::new();
            let mut spans = Vec::new();
            for (&i, images) in chunk.iter().zip(&images) {
                let r = requests(&trials[i], images);
                spans.push((i, r.len()));
                all.extend(r);
            }
            let mut results = backend
                .execute_batch(&all, &mut answering(backend.name(), all.len(), tx))
                .into_iter();
            let time = each(started);
            for (i, len) in spans {
                let answers: Vec<_> = results.by_ref().take(len).collect();
                let observed = Progress::Observed(i, pair(answers), time);
                if tx.send(Message::Progress(observed)).is_err() {
                    return;
                }
            }
        }
        let now = backend.restarts();
        if now != restarts {
            restarts = now;
            let _ = tx.send(Message::Progress(Progress::Restarted {
                backend: backend.name().to_string(),
                restarts,
            }));
        }
        if pace == Pace::Judged {
            let (handed_on, wait) = mpsc::channel();
            if tx.send(Message::Judged(handed_on)).is_err() || wait.recv().is_err() {
                return;
            }
        }
    }
}
