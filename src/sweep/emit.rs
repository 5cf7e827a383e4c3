//! Writing shrunk inputs as vectors in the corpus format: a cross-vendor file for an operation
//! sweep, a vector file for an instruction sweep. The expectation is what the reference models
//! answered; the basis is `inferred` (the models' rules are readings of the manuals, cited in
//! `docs/semantics.md`), never `manual`: a person who finds the page adds the citation. The
//! cite records the generator, the seed, the input found and every column's answer.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::group::{Found, Reply};
use super::input::{Data, Point};
use super::target::{Ask, Column, Target};
use super::{Results, Sweep};
use crate::corpus_yaml::{answer, expect_lines, hex_value, quote, quote_str};
use crate::load::CorpusBuilder;
use crate::model::cross_vendor::{Answer, Operation};
use crate::model::profile::Profiles;
use crate::model::{Corpus, Operand};

/// A vector file's header and one case per shrunk input that can be written (the input, and
/// the case's lines), and the inputs that could not be (with why).
pub struct Emitted {
    pub header: String,
    pub cases: Vec<(String, String)>,
    pub skipped: Vec<String>,
}

impl Emitted {
    /// The file with the given cases.
    pub fn yaml<'a>(&self, cases: impl IntoIterator<Item = &'a str>) -> String {
        let mut text = self.header.clone();
        cases.into_iter().for_each(|c| text.push_str(c));
        text
    }

    /// Keeps the cases that load as the corpus would load them from `path`, each checked in a
    /// file of its own; the others join `skipped` with the loader's reason.
    pub(crate) fn keep_loadable(&mut self, path: &std::path::Path, profiles: &Profiles) {
        let cases = std::mem::take(&mut self.cases);
        for (input, case) in cases {
            let mut builder = CorpusBuilder::default();
            builder.add_file(path, &self.yaml([case.as_str()]), profiles);
            match builder.finish() {
                Ok(_) => self.cases.push((input, case)),
                Err(e) => self.skipped.push(format!(
                    "{input}: it would not load: {}",
                    e.to_string().lines().next().unwrap_or_default()
                )),
            }
        }
    }
}

/// The line every emitted file starts its comment with: a file without it was not written by
/// `sweep`, and `--emit` replaces it only with `--force`.
pub const WRITTEN_BY: &str = "# Written by `plc-conformance sweep`";

/// The vector file of a sweep's shrunk inputs.
pub fn emit(sweep: &Sweep, results: &Results, corpus: &Corpus) -> Emitted {
    let mut cases = Vec::new();
    let mut skipped = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for s in &results.shrunk {
        if !seen.insert(s.to.point.clone()) {
            continue;
        }
        let made = match &sweep.settings.target {
            Target::Operation { operation } => {
                cross_vendor_case(sweep, results, *operation, &s.from, &s.to)
            }
            Target::Instruction { .. } => native_case(sweep, results, &s.from, &s.to),
        };
        match made {
            Ok(text) => cases.push((s.to.point.to_string(), text)),
            Err(NotEmitted(why)) => skipped.push(format!("{}: {why}", s.to.point)),
        }
    }
    let header = match &sweep.settings.target {
        Target::Operation { operation } => format!(
            "# yaml-language-server: $schema=../../schema/cross-vendor.schema.json\n\
             {WRITTEN_BY}: {}.\n\
             operation: {operation}\n\
             source: \"plc-conformance sweep of the reference models; their rules: docs/semantics.md#cross-vendor\"\n\
             cases:\n",
            settings_line(results)
        ),
        Target::Instruction {
            profile,
            instruction,
        } => {
            let (manual, page) = corpus
                .cases
                .iter()
                .find(|c| c.instructions.iter().any(|i| i == instruction) && c.profiles.iter().any(|p| p == profile))
                .map(|c| (c.citation.manual.clone(), c.citation.page.clone()))
                .or_else(|| {
                    sweep
                        .shape
                        .as_ref()
                        .and_then(|s| s.profile.manuals.keys().next().cloned())
                        .map(|m| (m, "see the cite".to_string()))
                })
                .unwrap_or_default();
            format!(
                "# yaml-language-server: $schema=../../schema/vectors.schema.json\n\
                 {WRITTEN_BY}: {}.\n\
                 instructions: [{instruction}]\n\
                 profiles: [{profile}]\n\
                 source: {{manual: {manual}, page: {}}}\n\
                 cases:\n",
                settings_line(results),
                quote_str(&page)
            )
        }
    };
    Emitted {
        header,
        cases,
        skipped,
    }
}

fn settings_line(results: &Results) -> String {
    let s = &results.settings;
    format!(
        "{} generator, seed {}, shard {}/{}",
        s.generator.name(),
        s.seed,
        s.shard.0,
        s.shard.1
    )
}

/// A stable id from the input (and the shard, when the sweep is one of several: two shards can
/// shrink to the same input, and their files are loaded together).
fn id(prefix: &str, point: &Point, sweep: &Sweep) -> String {
    let mut h: u64 = 0xCBF2_9CE4_8422_2325;
    for b in format!("{point}").bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01B3);
    }
    let id = format!("sweep-{prefix}-{:08x}", h as u32);
    match sweep.settings.shard {
        (_, 1) => id,
        (k, n) => format!("{id}-shard-{k}-of-{n}"),
    }
}

fn answers_line(columns: &[Column], replies: &[Reply]) -> String {
    columns
        .iter()
        .zip(replies)
        .map(|(c, r)| format!("{} {r}", c.name))
        .collect::<Vec<_>>()
        .join("; ")
}

fn provenance(results: &Results, from: &Found, to: &Found, columns: &[Column]) -> String {
    let s = &results.settings;
    let shrunk = if from.point == to.point {
        String::new()
    } else {
        format!(", shrunk from {}", from.point)
    };
    format!(
        "found by plc-conformance sweep ({} generator, seed {}, input {}{shrunk}); answers: {}",
        s.generator.name(),
        s.seed,
        from.index,
        answers_line(columns, &to.replies)
    )
}

/// Why a found input is not written as a vector.
struct NotEmitted(String);

fn cross_vendor_case(
    sweep: &Sweep,
    results: &Results,
    operation: Operation,
    from: &Found,
    to: &Found,
) -> Result<String, NotEmitted> {
    // The reference models' answers, by lowering key; those that depend on memory the case
    // does not set are `unspecified` for that lowering.
    let mut by_key: Vec<(String, Answer)> = Vec::new();
    let mut unset: Vec<String> = Vec::new();
    for (c, r) in sweep.columns.iter().zip(&to.replies) {
        let Ask::Lowering(l) = &c.ask else { continue };
        if !c.in_process {
            continue;
        }
        match r {
            Reply::Answer {
                answer,
                fill_dependent: false,
            } if !matches!(answer, Answer::OtherError(_)) => {
                by_key.push((l.key.clone(), answer.clone()))
            }
            Reply::Answer {
                fill_dependent: true,
                ..
            } => unset.push(l.key.clone()),
            other => {
                return Err(NotEmitted(format!(
                    "{} answered {other}, which a vector cannot expect",
                    c.name
                )))
            }
        }
    }
    if by_key.is_empty() {
        return Err(NotEmitted(
            "no reference model answered it: nothing to expect".into(),
        ));
    }
    // The expectation is the reading the sweep judged its codecs against (what `run` then
    // holds a codec to): the first judged codec column's oracle. Without one, the answer most
    // readings give; the others are the lowerings' exceptions either way.
    let oracle = (sweep.columns.iter())
        .filter(|c| matches!(c.ask, Ask::Codec))
        .find_map(|c| c.oracle)
        .and_then(|j| match &sweep.columns[j].ask {
            Ask::Lowering(l) => by_key.iter().find(|(key, _)| *key == l.key),
            _ => None,
        });
    let (most, chosen) = match oracle {
        Some((key, answer)) => (
            answer.clone(),
            format!("the expectation is {key}'s answer, the reading the sweep judged against"),
        ),
        None => {
            let mut counts: BTreeMap<&Answer, usize> = BTreeMap::new();
            for (_, a) in &by_key {
                *counts.entry(a).or_default() += 1;
            }
            let most = (by_key.iter().map(|(_, a)| a))
                .max_by_key(|a| counts[a])
                .cloned()
                .unwrap_or(Answer::Value(0));
            (
                most,
                "the expectation is the answer most readings give".to_string(),
            )
        }
    };
    let mut y = String::new();
    let _ = writeln!(
        y,
        "  - id: {}",
        id(&operation.to_string(), &to.point, sweep)
    );
    let _ = writeln!(y, "    basis: inferred");
    let _ = writeln!(
        y,
        "    cite: {}",
        quote_str(&format!(
            "each lowering's answer is its reference model's (docs/semantics.md#cross-vendor); \
             {chosen}; {}",
            provenance(results, from, to, &sweep.columns)
        ))
    );
    match &to.point.data {
        Data::Text(t) => {
            let _ = writeln!(y, "    text: {}", quote(t));
        }
        Data::Value(v) => {
            let _ = writeln!(y, "    value: {}", hex_value(*v));
        }
    }
    let _ = writeln!(y, "    digits: {}", to.point.digits);
    let _ = writeln!(y, "    expect: {{{}}}", answer(&most));
    let except: Vec<&(String, Answer)> = by_key.iter().filter(|(_, a)| *a != most).collect();
    if !except.is_empty() || !unset.is_empty() {
        let _ = writeln!(y, "    except:");
        for (key, a) in except {
            let _ = writeln!(
                y,
                "      {key}: {{{}, why: {}}}",
                answer(a),
                quote_str(&format!("the reference model's answer through {key}"))
            );
        }
        for key in &unset {
            let _ = writeln!(
                y,
                "      {key}: {{unspecified: true, why: {}}}",
                quote_str(&format!(
                    "through {key} the answer depends on memory the case does not set"
                ))
            );
        }
    }
    Ok(y)
}

fn native_case(
    sweep: &Sweep,
    results: &Results,
    from: &Found,
    to: &Found,
) -> Result<String, NotEmitted> {
    let shape = sweep
        .shape
        .as_ref()
        .ok_or(NotEmitted("no instruction".into()))?;
    // The variants where a column differs from its oracle, with the oracle's effect there.
    let mut expect: Option<&crate::judge::Effect> = None;
    let mut variants = Vec::new();
    for (i, c) in sweep.columns.iter().enumerate() {
        let Some(o) = c.oracle else { continue };
        let (mine, theirs) = (&to.replies[i], &to.replies[o]);
        if mine.is_skipped() || theirs.is_skipped() || mine == theirs {
            continue;
        }
        let Reply::Memory {
            effect,
            fill_dependent: false,
        } = theirs
        else {
            return Err(NotEmitted(format!(
                "the oracle {} answered {theirs}",
                sweep.columns[o].name
            )));
        };
        match expect {
            None => expect = Some(effect),
            Some(e) if e != effect => continue,
            Some(_) => {}
        }
        if !variants.contains(&c.variant) {
            variants.push(c.variant.clone());
        }
    }
    let effect = expect.ok_or(NotEmitted("no column differs from its oracle".into()))?;
    let input = shape.input(&to.point);
    let mut y = String::new();
    let _ = writeln!(
        y,
        "  - id: {}",
        id(&shape.instruction.to_lowercase(), &to.point, sweep)
    );
    let _ = writeln!(y, "    basis: inferred");
    let _ = writeln!(
        y,
        "    cite: {}",
        quote_str(&format!(
            "the expectation is the reference model of {} (its rules: docs/semantics.md#evidence); {}",
            shape.profile.id,
            provenance(results, from, to, &sweep.columns)
        ))
    );
    let _ = writeln!(y, "    variants: [{}]", variants.join(", "));
    if !input.flags.is_empty() {
        let flags: Vec<String> = input
            .flags
            .iter()
            .map(|(f, on)| format!("{f}: {}", if *on { "on" } else { "off" }))
            .collect();
        let _ = writeln!(y, "    flags: {{{}}}", flags.join(", "));
    }
    let operands: Vec<String> = input
        .operands
        .iter()
        .map(|(n, o)| match o {
            Operand::Device(d) => format!("{n}: {d}"),
            Operand::Constant(k) => format!("{n}: K{k}"),
        })
        .collect();
    let _ = writeln!(y, "    operands: {{{}}}", operands.join(", "));
    let source = input
        .operands
        .get(&shape.source)
        .and_then(|o| match o {
            Operand::Device(d) => Some(d.clone()),
            Operand::Constant(_) => None,
        })
        .ok_or(NotEmitted("the source is not a device".into()))?;
    // Words past the device range cannot be set by a vector (a CPU has none): they are left out,
    // and the text is then given word by word.
    let exists = |d: &crate::device::Device| shape.profile.word_exists_anywhere(d);
    let whole = input.before.keys().all(exists);
    if input.before.keys().any(exists) {
        let _ = writeln!(y, "    before:");
    } else {
        let _ = writeln!(y, "    before: {{}}");
    }
    // The notations `ascii` and `ascii_words` read two characters a word low byte first, or one
    // a word; a text stored high byte first is written as its words.
    let key = shape.layout(&to.point.flags).notation();
    match &to.point.data {
        Data::Text(t) if whole && key.is_some() => {
            let mut text = t.clone();
            text.push(0);
            let _ = writeln!(
                y,
                "      {source}: {{{}: {}}}",
                key.unwrap_or_default(),
                quote(&text)
            );
        }
        _ => {
            for (d, w) in input.before.iter().filter(|(d, _)| exists(d)) {
                let _ = writeln!(y, "      {d}: {}", shape.profile.unit.hex(*w));
            }
        }
    }
    let _ = writeln!(y, "{}", expect_lines(effect, "    "));
    Ok(y)
}
