//! Every four-byte text through every built-in hex-to-value lowering, at the speed of the rules
//! themselves: `sweep --operation hex-to-value --generator full --each-text` over the reference
//! models.
//!
//! Asking each of the 2^32 texts through the models' `Backend::execute` (a request, two memory
//! images, lifting) runs at a few hundred thousand texts a second: hours. But with a count of 4,
//! each built-in lowering's answer to a 4-byte text is a small function of its four bytes — the
//! rules of `docs/semantics.md` written out as [`Rule`]s, with no memory, request or response —
//! and the whole space is then minutes of arithmetic, spread over the cores.
//!
//! The results are exactly those of asking every text through the models, and are checked to be:
//!
//! 1. The texts are tallied by tuple of byte classes (`super::classes`, found as for the sweep
//!    by class). Each text's answers under the rules are compared with those of its tuple's
//!    representative; a text that answers alike is counted with its tuple (with the lowest
//!    number of such a text in the space, its first), and one that does not is kept apart and
//!    asked through the models on its own. So the classes need not hold for the counts to be
//!    exact: they only make the tally small.
//! 2. The first text of every tuple, and every text kept apart, is then asked through the models
//!    (the direct path, `super::direct`) and grouped as any sweep groups, with its tuple's
//!    count as its weight. Each of those texts' replies must be what the rules said; one that is
//!    not stops the sweep with the text ([`Report::disagreement`]), the counts not trusted.
//! 3. The sweep's white-box tests (`white_box.rs`) prove the rules equal to the models on many
//!    random texts, on every text made of class-boundary bytes, and — with the groups, counts,
//!    first inputs and classes of the general path — on every text of a shard.
//!
//! A codec written in Rust ([`crate::backend::Codec`], in process) joins them: its `convert` is
//! called on each text as a rule is, its answer made a code, and its texts tallied and checked
//! the same way — a codec's own speed, where a question through the general path costs a request
//! and a reply (seconds a million texts against hours for the space).
//!
//! Only the built-in lowerings whose rule is known here and codecs in process run this way, at a
//! count of 4 (the natural count of a 4-byte text) and with no flags; any other sweep, and any
//! with an external backend, takes the general path.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use serde::Serialize;

use super::classes::{self, ByteClasses};
use super::generate::{scramble, Generator};
use super::group::{Found, Groups, Reply};
use super::input::{Data, Point};
use super::target::{Ask, Target};
use super::{Results, Sweep};
use crate::model::cross_vendor::{Answer, Operation};

/// How a built-in lowering answers a 4-character text with a count of 4, as a function of the
/// text's bytes. A digit is 30H-39H or 41H-46H (`crate::text::digit_value`), and for S7-1200 ATH
/// 61H-66H too; each lowering has one error on such a text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Rule {
    /// All four characters must be digits: their value, else the error. HABIN with SM705 off,
    /// FX5 HEXA, IDEC ATOH, S7-200 ATH, FX3 and Delta HEX, in either packing.
    Whole,
    /// Each character that is not a digit (lowercase a-f are digits here) read as 0: the value,
    /// with the error when there was one (S7-1200 ATH writes the destination and returns the
    /// error, `written_on_error`).
    Zeroed,
    /// The characters before the first 00H (at most four), at least one, each a digit: their
    /// value, else the error. HABIN with SM705 on.
    Terminated,
    /// All four digits, two to a byte, the bytes from the low byte of the word: the value
    /// byte-swapped (Panasonic F72, `"ABCD"` is CDABH), else the error.
    ByteSwapped,
    /// The first two characters only, as one byte (KEYENCE RASC), else the error.
    FirstByte,
    /// All four characters must be digits, the first the lowest digit (Omron HEX with Di
    /// 0030H: `"1234"` is 4321H), else the error.
    Reversed,
}

/// The answer [`answer`] gives for the lowering's error (values are below 2^16).
pub(crate) const ERROR: u32 = 1 << 16;

/// Added to a value by [`answer`] when the lowering gives the error with the value.
pub(crate) const WITH_ERROR: u32 = 1 << 17;

/// Each byte's digit value, or 0xFF; with `lowercase`, a-f are digits too.
const fn digits(lowercase: bool) -> [u8; 256] {
    let mut t = [0xFFu8; 256];
    let mut b = 0;
    while b < 256 {
        t[b] = match b as u8 {
            c @ b'0'..=b'9' => c - b'0',
            c @ b'A'..=b'F' => c - b'A' + 10,
            c @ b'a'..=b'f' if lowercase => c - b'a' + 10,
            _ => 0xFF,
        };
        b += 1;
    }
    t
}

/// Each byte's digit value, or 0xFF.
const DIGIT: [u8; 256] = digits(false);
/// The same with lowercase a-f as digits (S7-1200 ATH, `docs/semantics.md#s7-ath-lowercase`).
const DIGIT_ANY_CASE: [u8; 256] = digits(true);

/// The rule of a lowering, by its key; `None` for a lowering this module does not know.
pub(crate) fn rule(key: &str) -> Option<Rule> {
    Some(match key {
        "iqr/habin-fixed" | "fx5/hexa-16bit" | "fx5/hexa-8bit" | "fc4a/atoh" | "s7-200/ath"
        | "fx3/hex-16bit" | "fx3/hex-8bit" | "dvp/hex-16bit" | "dvp/hex-8bit" => Rule::Whole,
        "s7/ath" => Rule::Zeroed,
        "iqr/habin-terminated" => Rule::Terminated,
        "fp/f72" => Rule::ByteSwapped,
        "kv/rasc" => Rule::FirstByte,
        "omron/hex" => Rule::Reversed,
        _ => return None,
    })
}

/// The answer of `rule` to `text` with a count of 4: the value, [`ERROR`], or the value plus
/// [`WITH_ERROR`].
#[inline]
pub(crate) fn answer(rule: Rule, text: [u8; 4]) -> u32 {
    let d = text.map(|b| DIGIT[b as usize]);
    let whole = || {
        ((d[0] | d[1] | d[2] | d[3]) < 16).then(|| {
            u32::from(d[0]) << 12 | u32::from(d[1]) << 8 | u32::from(d[2]) << 4 | u32::from(d[3])
        })
    };
    match rule {
        Rule::Whole => whole().unwrap_or(ERROR),
        Rule::Zeroed => {
            let d = text.map(|b| DIGIT_ANY_CASE[b as usize]);
            let z = d.map(|x| if x < 16 { u32::from(x) } else { 0 });
            let value = z[0] << 12 | z[1] << 8 | z[2] << 4 | z[3];
            if (d[0] | d[1] | d[2] | d[3]) < 16 {
                value
            } else {
                value | WITH_ERROR
            }
        }
        Rule::Reversed => whole().map_or(ERROR, |v| {
            (v & 0xF) << 12 | (v & 0xF0) << 4 | (v & 0xF00) >> 4 | v >> 12
        }),
        Rule::ByteSwapped => whole().map_or(ERROR, |v| (v & 0xFF) << 8 | v >> 8),
        Rule::FirstByte => {
            if (d[0] | d[1]) < 16 {
                u32::from(d[0]) << 4 | u32::from(d[1])
            } else {
                ERROR
            }
        }
        Rule::Terminated => {
            let mut value = 0u32;
            let mut digits = 0;
            for (b, x) in text.iter().zip(d) {
                if *b == 0 {
                    break;
                }
                if x >= 16 {
                    return ERROR;
                }
                value = value << 4 | u32::from(x);
                digits += 1;
            }
            if digits == 0 {
                ERROR
            } else {
                value
            }
        }
    }
}

/// Whether a reply is the answer [`answer`] gave: the same value, for [`ERROR`] an error, for a
/// value plus [`WITH_ERROR`] an error with that value (which error is checked across texts by
/// the caller: a lowering has one).
pub(crate) fn agrees(code: u32, reply: &Reply) -> bool {
    match reply {
        Reply::Answer {
            answer,
            fill_dependent: false,
        } => match answer {
            Answer::Value(v) => code < ERROR && u64::from(code) == *v,
            Answer::Error(_) | Answer::OtherError(_) => code == ERROR,
            Answer::ErrorAndValue(_, v) => {
                code & WITH_ERROR != 0 && u64::from(code & !WITH_ERROR) == *v
            }
            Answer::Text(_) | Answer::Accepted => false,
        },
        _ => false,
    }
}

/// Whether an error reply's error is the one the column gave before (each lowering has one);
/// the first is kept.
fn same_error(seen: &mut Option<Reply>, reply: &Reply) -> bool {
    let class = |r: &Reply| match r {
        Reply::Answer {
            answer: Answer::Error(c) | Answer::ErrorAndValue(c, _),
            ..
        } => Some(Answer::Error(c.clone())),
        Reply::Answer {
            answer: a @ Answer::OtherError(_),
            ..
        } => Some(a.clone()),
        _ => None,
    };
    let first = seen.get_or_insert_with(|| reply.clone());
    class(first) == class(reply)
}

/// The inverse of `super::generate::scramble`: a text's number in the full generator's space.
pub(crate) fn unscramble(x: u32) -> u32 {
    /// The inverse of an odd number modulo 2^32 (Newton's iteration).
    const fn inverse(a: u32) -> u32 {
        let mut x = a;
        let mut i = 0;
        while i < 5 {
            x = x.wrapping_mul(2u32.wrapping_sub(a.wrapping_mul(x)));
            i += 1;
        }
        x
    }
    const A: u32 = inverse(0x9E37_79B1);
    const B: u32 = inverse(0x85EB_CA77);
    let mut x = x ^ x >> 13 ^ x >> 26;
    x = x.wrapping_mul(B);
    x ^= x >> 15 ^ x >> 30;
    x.wrapping_mul(A)
}

/// A sweep this module can run: each column's rule, or its codec asked in process.
pub(crate) struct Plan<'s> {
    /// The distinct rules of the columns.
    rules: Vec<Rule>,
    /// The codecs written in Rust among the columns, asked each text directly.
    codecs: Vec<InProcess<'s>>,
    /// Each column's place among its answers' codes: a place in `rules`, or `rules.len()` plus
    /// a place in `codecs`.
    of: Vec<usize>,
}

/// A codec written in Rust ([`crate::backend::Codec`]) as a column of this path: each text is
/// its own `convert` call, its answer a code as a rule's is, so that the texts are tallied and
/// checked exactly as the rules' are (a code no tuple can share, [`OTHER`], keeps a text apart).
struct InProcess<'s> {
    codec: &'s dyn crate::backend::Codec,
    /// What it takes (of hex-to-value): a text outside it is skipped, as the general path
    /// skips it.
    abilities: crate::model::cross_vendor::CodecAbilities,
    /// Every 4-digit text is outside it; else only some texts can be (a field that skips
    /// blanks between byte pairs is the one shape that looks at the text's bytes), and only
    /// then is each text checked.
    declined: Declined,
}

#[derive(PartialEq, Eq)]
enum Declined {
    Every,
    Some,
    None,
}

/// A codec's codes: a value below 2^32 is itself; these are above.
const SKIPPED: u64 = 1 << 40;
const UNSUPPORTED: u64 = 1 << 41;
const CLASS: u64 = 1 << 42;
/// Any other answer (a wider value, a text, an error with a value): never counted with a
/// tuple, asked through the general path on its own.
const OTHER: u64 = 1 << 43;

fn class_code(c: &crate::model::cross_vendor::ErrorClass) -> u64 {
    use crate::model::cross_vendor::ErrorClass;
    CLASS
        + match c {
            ErrorClass::InvalidDigit => 0,
            ErrorClass::InvalidCount => 1,
            ErrorClass::DeviceRange => 2,
            ErrorClass::Error => 3,
            ErrorClass::BadCheck => 4,
        }
}

impl InProcess<'_> {
    /// Whether the codec's abilities decline a 4-digit text, as `plan::codec_declined` does.
    fn declines(&self, text: &[u8]) -> bool {
        (self.abilities)
            .declines_asking(Operation::HexToValue, text, 0, 4, None)
            .is_some()
    }

    #[inline]
    fn code(&self, text: [u8; 4]) -> u64 {
        let declined = match self.declined {
            Declined::Every => true,
            Declined::Some => self.declines(&text),
            Declined::None => false,
        };
        if declined {
            return SKIPPED;
        }
        let question = crate::backend::Question {
            case_id: "",
            operation: Operation::HexToValue,
            text: &text,
            value: 0,
            digits: 4,
            field: "",
        };
        // A panic is kept apart too: the general path asks the text and records the crash.
        match crate::backend::convert_or_panic(self.codec, &question) {
            Ok(Ok(Answer::Value(v))) if v >> 32 == 0 => v,
            Ok(Ok(Answer::Error(c))) => class_code(&c),
            Ok(Err(_)) => UNSUPPORTED,
            _ => OTHER,
        }
    }
}

/// Whether a codec's reply through the general path is the code its `convert` call gave.
fn codec_agrees(code: u64, reply: &Reply) -> bool {
    match reply {
        Reply::Answer {
            answer: Answer::Value(v),
            fill_dependent: false,
        } => code == *v,
        Reply::Answer {
            answer: Answer::Error(c),
            fill_dependent: false,
        } => code == class_code(c),
        Reply::Skipped { .. } => code == SKIPPED,
        Reply::Failed { label, .. } => label == "unsupported" && code == UNSUPPORTED,
        _ => false,
    }
}

/// The plan for `sweep`, when every text of it can be asked through the rules: the full
/// generator asking each text, hex-to-value, a count of 4 and no flags, and every column a
/// built-in lowering with a known rule, asked directly, or a codec written in Rust.
pub(crate) fn plan(sweep: &Sweep) -> Option<Plan<'_>> {
    let s = &sweep.settings;
    if !s.exhaustive
        || !s.direct
        || !matches!(s.generator, Generator::Full { by_class: false })
        || s.target
            != (Target::Operation {
                operation: Operation::HexToValue,
            })
        || sweep.space.settings() != 1
        || sweep.space.classes.is_some()
        || sweep.space.with_setting(Data::Text(vec![0; 4]), 0).digits != 4
    {
        return None;
    }
    let mut rules = Vec::new();
    let mut of = Vec::new();
    let mut codecs = Vec::new();
    let mut codec_columns = Vec::new();
    for (i, c) in sweep.columns.iter().enumerate() {
        if let (Ask::Codec, Some(codec), Some(field)) =
            (&c.ask, c.backend.as_codec(), c.field.as_ref())
        {
            let mut codec = InProcess {
                codec,
                abilities: crate::model::cross_vendor::CodecAbilities {
                    hex_to_value: Some(field.1.clone()),
                    ..Default::default()
                },
                declined: Declined::Some,
            };
            codec.declined = if codec.declines(b"0000") {
                Declined::Every
            } else if field.1.shape.blanks_between_pairs {
                Declined::Some
            } else {
                Declined::None
            };
            codecs.push(codec);
            codec_columns.push(i);
            of.push(usize::MAX);
            continue;
        }
        let Ask::Lowering(l) = &c.ask else {
            return None;
        };
        if !c.in_process || c.lowering_skip.is_some() {
            return None;
        }
        let r = rule(&l.key)?;
        of.push(match rules.iter().position(|x| *x == r) {
            Some(i) => i,
            None => {
                rules.push(r);
                rules.len() - 1
            }
        });
    }
    for (k, &i) in codec_columns.iter().enumerate() {
        of[i] = rules.len() + k;
    }
    Some(Plan { rules, codecs, of })
}

impl Plan<'_> {
    /// The codes of a text, rule by rule, then codec by codec; whether one is [`OTHER`].
    #[inline]
    fn codes(&self, text: [u8; 4], codes: &mut [u64]) -> bool {
        let (by_rule, by_codec) = codes.split_at_mut(self.rules.len());
        for (code, rule) in by_rule.iter_mut().zip(&self.rules) {
            *code = u64::from(answer(*rule, text));
        }
        let mut other = false;
        for (code, codec) in by_codec.iter_mut().zip(&self.codecs) {
            *code = codec.code(text);
            other |= *code == OTHER;
        }
        other
    }

    fn width(&self) -> usize {
        self.rules.len() + self.codecs.len()
    }
}

/// How the texts were asked, as the results tell it.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Texts of this shard asked through the rules.
    pub texts: u64,
    /// The byte classes the tally was made by, described.
    pub classes: Vec<String>,
    /// Tuples of classes with a text in this shard: their first texts were asked through the
    /// models too.
    pub tuples: u64,
    /// Texts that answered unlike their tuple's representative: each asked through the models
    /// and counted on its own.
    pub apart: u64,
    /// Seconds spent asking every text through the rules.
    pub seconds: f64,
    /// A text whose replies through the models are not what the rules said: the counts are not
    /// to be trusted.
    pub disagreement: Option<Found>,
}

/// Texts kept apart beyond which the tally is abandoned for the general path (the classes then
/// describe the texts too badly for a tally by tuple to be worth it).
const MAX_APART: usize = 1 << 20;

/// Pieces the texts are shared out in among the threads.
const BLOCKS: u64 = 4096;

/// Texts asked of the models per round when the first texts are asked.
const CHUNK: usize = 1 << 16;

/// What one thread tallied.
struct Tally {
    count: Vec<u64>,
    first: Vec<u32>,
    apart: Vec<u32>,
}

/// Runs the sweep through the rules (see the module's text). `None` when it cannot finish this
/// way (too many texts apart from their tuple): the caller runs the general path.
pub(crate) fn run(
    sweep: &Sweep,
    plan: &Plan,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(u64, u64),
) -> Option<Results> {
    let started = Instant::now();
    let (k, n) = sweep.settings.shard;
    let shard_inputs = (1u64 << 32).saturating_sub(k - 1).div_ceil(n);
    progress(0, shard_inputs);
    let Some((classes, _)) = classes::derive(sweep, stop) else {
        let groups = Groups::new(sweep.settings.class_cap());
        return Some(sweep.results(shard_inputs, 0, true, groups, started));
    };
    let tuples = classes.tuples() as usize;
    let r = plan.width();
    // Each tuple's representative's answers, rule by rule (then codec by codec).
    let mut table = vec![0u64; tuples * r];
    for (t, row) in table.chunks_mut(r).enumerate() {
        plan.codes(classes.representative(t as u64), row);
    }
    let of: Vec<u32> = (0..=255u8)
        .map(|b| classes.tuple_of([0, 0, 0, b]) as u32)
        .collect();
    let pass = Instant::now();
    let tallies = tally(sweep, plan, &classes, &table, &of, stop, progress)?;
    let seconds = pass.elapsed().as_secs_f64();
    let mut count = vec![0u64; tuples];
    let mut first = vec![u32::MAX; tuples];
    let mut apart = Vec::new();
    for t in tallies {
        for (i, (c, f)) in t.count.into_iter().zip(t.first).enumerate() {
            count[i] += c;
            first[i] = first[i].min(f);
        }
        apart.extend(t.apart);
    }
    let interrupted = stop.load(Ordering::Relaxed);
    // Every text counted once, in the order the general path meets them: by number.
    let mut adds: Vec<(u32, Option<usize>)> = (0..tuples)
        .filter(|&t| count[t] > 0)
        .map(|t| (first[t], Some(t)))
        .chain(apart.iter().map(|&i| (i, None)))
        .collect();
    adds.sort_unstable();
    let mut groups = Groups::new(sweep.settings.class_cap());
    let mut swept = 0;
    let mut disagreement = None;
    let mut errors: Vec<Option<Reply>> = vec![None; sweep.columns.len()];
    for block in adds.chunks(CHUNK) {
        let points: Vec<(u64, Point)> = block
            .iter()
            .map(|&(i, _)| (u64::from(i), sweep.space.point(u64::from(i))))
            .collect();
        let answers = sweep.answers(&points, &AtomicBool::new(false));
        for ((&(index, tuple), (_, point)), replies) in block.iter().zip(&points).zip(answers) {
            let Some(replies) = replies else { continue };
            if let (Some(t), None) = (tuple, &disagreement) {
                let row = &table[t * r..t * r + r];
                let alike = replies.iter().enumerate().all(|(c, reply)| {
                    let place = plan.of[c];
                    if place >= plan.rules.len() {
                        return codec_agrees(row[place], reply);
                    }
                    let code = row[place] as u32;
                    agrees(code, reply) && (code < ERROR || same_error(&mut errors[c], reply))
                });
                if !alike {
                    disagreement = Some(Found {
                        index: u64::from(index),
                        point: point.clone(),
                        replies: replies.clone(),
                    });
                }
            }
            let weight = tuple.map_or(1, |t| count[t]);
            groups.add(
                &sweep.columns,
                sweep.counted(),
                u64::from(index),
                point,
                replies,
                weight,
            );
            swept += weight;
        }
    }
    let mut results = sweep.results(shard_inputs, swept, interrupted, groups, started);
    results.exhaustive = Some(Report {
        texts: swept,
        classes: classes.describe(),
        tuples: adds.iter().filter(|(_, t)| t.is_some()).count() as u64,
        apart: apart.len() as u64,
        seconds,
        disagreement,
    });
    progress(swept, shard_inputs);
    if !interrupted {
        results.shrunk = super::shrink::shrink_groups(sweep, &results, stop);
    }
    results.elapsed = started.elapsed();
    Some(results)
}

/// Every text of the shard through the rules, the first bytes shared out among the threads;
/// `None` when too many texts answer unlike their tuple.
fn tally(
    sweep: &Sweep,
    plan: &Plan,
    classes: &ByteClasses,
    table: &[u64],
    of: &[u32],
    stop: &AtomicBool,
    progress: &mut dyn FnMut(u64, u64),
) -> Option<Vec<Tally>> {
    let (k, n) = sweep.settings.shard;
    let (k, n) = (k as u32 - 1, n.min(u64::from(u32::MAX)) as u32);
    let shard_inputs = (1u64 << 32)
        .saturating_sub(u64::from(k))
        .div_ceil(u64::from(n));
    let tuples = classes.tuples() as usize;
    let width = classes.len() as u32;
    let r = plan.width();
    let next = AtomicUsize::new(0);
    let done = AtomicU64::new(0);
    let apart_total = AtomicUsize::new(0);
    let overflow = AtomicBool::new(false);
    let jobs = sweep.settings.jobs.max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..jobs)
            .map(|_| {
                scope.spawn(|| {
                    let mut t = Tally {
                        count: vec![0; tuples],
                        first: vec![u32::MAX; tuples],
                        apart: Vec::new(),
                    };
                    let mut codes = vec![0u64; r];
                    let mut ask = |text: [u8; 4], index: u32, t: &mut Tally| {
                        let tuple = ((((of[text[0] as usize] * width) + of[text[1] as usize])
                            * width
                            + of[text[2] as usize])
                            * width
                            + of[text[3] as usize]) as usize;
                        let other = plan.codes(text, &mut codes);
                        if !other && codes[..] == table[tuple * r..tuple * r + r] {
                            t.count[tuple] += 1;
                            t.first[tuple] = t.first[tuple].min(index);
                        } else {
                            t.apart.push(index);
                            if apart_total.fetch_add(1, Ordering::Relaxed) >= MAX_APART {
                                overflow.store(true, Ordering::Relaxed);
                            }
                        }
                    };
                    loop {
                        let block = next.fetch_add(1, Ordering::Relaxed) as u64;
                        if block >= BLOCKS || overflow.load(Ordering::Relaxed) {
                            break;
                        }
                        let mut counted = 0u64;
                        if n == 1 {
                            // The whole space: texts in order, so that a tuple's row of the
                            // table stays in cache while its last byte runs.
                            let from = (block << 32) / BLOCKS;
                            let to = ((block + 1) << 32) / BLOCKS;
                            for x in from..to {
                                let x = x as u32;
                                ask(x.to_be_bytes(), unscramble(x), &mut t);
                            }
                            counted = to - from;
                        } else {
                            // A shard: its own numbers only, each made into its text.
                            let all = shard_inputs;
                            let from = all * block / BLOCKS;
                            let to = all * (block + 1) / BLOCKS;
                            for j in from..to {
                                let index = (u64::from(k) + j * u64::from(n)) as u32;
                                ask(scramble(index).to_be_bytes(), index, &mut t);
                            }
                            counted += to - from;
                        }
                        done.fetch_add(counted, Ordering::Relaxed);
                        // Checked after a block, so that a sweep stopped at once still reports
                        // the texts of one block per thread.
                        if stop.load(Ordering::Relaxed) {
                            break;
                        }
                    }
                    t
                })
            })
            .collect();
        while !handles.iter().all(|h| h.is_finished()) {
            std::thread::sleep(Duration::from_millis(100));
            progress(done.load(Ordering::Relaxed), shard_inputs);
        }
        let tallies: Vec<Tally> = handles.into_iter().filter_map(|h| h.join().ok()).collect();
        (tallies.len() == jobs && !overflow.load(Ordering::Relaxed)).then_some(tallies)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unscramble_undoes_scramble() {
        for x in (0..1u64 << 32).step_by(65_521).map(|x| x as u32) {
            assert_eq!(unscramble(scramble(x)), x);
            assert_eq!(scramble(unscramble(x)), x);
        }
    }

    #[test]
    fn the_rules_read_the_manuals_examples() {
        assert_eq!(answer(Rule::Whole, *b"5A8D"), 0x5A8D);
        assert_eq!(answer(Rule::Whole, *b"5a8D"), ERROR);
        assert_eq!(answer(Rule::Terminated, *b"7F\0\0"), 0x7F);
        assert_eq!(answer(Rule::Terminated, *b"\x00000"), ERROR);
        assert_eq!(answer(Rule::ByteSwapped, *b"ABCD"), 0xCDAB);
        assert_eq!(answer(Rule::FirstByte, *b"7FGG"), 0x7F);
        assert_eq!(answer(Rule::FirstByte, *b"G7FF"), ERROR);
        assert_eq!(answer(Rule::Zeroed, *b"1G34"), 0x1034 | WITH_ERROR);
        assert_eq!(answer(Rule::Zeroed, *b"1A34"), 0x1A34);
        assert_eq!(answer(Rule::Reversed, *b"1234"), 0x4321);
        assert_eq!(answer(Rule::Reversed, *b"123a"), ERROR);
    }
}
