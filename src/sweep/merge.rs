//! The shards of a sweep put back together: `sweep --merge SHARD.json...` with the sweep's own
//! arguments reads each shard's JSON results and makes the results of the whole sweep, equal to
//! those of the sweep run in one piece (groups, counts, first inputs, classes, shrunk inputs).
//!
//! A shard's file says, per group, how many inputs it had and the number of its first input and
//! of each class's; those add up across shards. The inputs themselves are not read back from
//! the files: each first input is made again from its number (a sweep's space is numbered the
//! same way every time) and asked again of the backends, which must answer it as they did in
//! its shard — a backend that changed between the shards and the merge is an error, not a
//! merged report. The groups are then shrunk as the whole sweep shrinks them (its largest
//! classes, which no single shard knows), and known differences are applied by the caller as
//! for any sweep. So the CI service that runs the shards in parallel is the distributed engine:
//! `docs/sweeps.md` shows a GitHub Actions matrix that does it.
//!
//! A shard keeps every class of its groups (`Settings::class_cap`), so that the merge keeps
//! exactly the classes the whole sweep keeps: the first `max_classes` of each group met in the
//! order of their numbers. What differs from a sweep run in one piece is only how the work was
//! done: the seconds (the shards' added up), and for the full generator by class, the random
//! texts checked (each shard checks its own).

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use serde::Deserialize;

use super::generate::Generator;
use super::group::{differing, disagree, labels_read, Class, Found, Group, Groups, Key};
use super::input::Point;
use super::{classes, exhaustive, Results, Sweep, SweepError};

/// The parts of a shard's JSON results a merge reads (the rest is rendered from them again).
#[derive(Debug, Deserialize)]
pub(crate) struct ShardFile {
    pub(crate) tool: String,
    pub(crate) settings: serde_json::Value,
    pub(crate) columns: Vec<ColumnFile>,
    pub(crate) shard_inputs: u64,
    pub(crate) swept: u64,
    pub(crate) interrupted: bool,
    pub(crate) elapsed_seconds: f64,
    pub(crate) groups: Vec<GroupFile>,
    #[serde(default)]
    pub(crate) byte_classes: Option<ByteClassesFile>,
    #[serde(default)]
    pub(crate) each_text: Option<EachTextFile>,
}

#[derive(Debug, Deserialize)]
pub(crate) struct ColumnFile {
    pub(crate) name: String,
}

#[derive(Debug, Deserialize)]
pub(crate) struct GroupFile {
    pub(crate) inputs: u64,
    pub(crate) features: Vec<String>,
    /// Column name -> the class of its answer.
    pub(crate) signature: BTreeMap<String, String>,
    pub(crate) representative: Numbered,
    pub(crate) classes: Vec<ClassFile>,
}

#[derive(Debug, Deserialize)]
pub(crate) struct ClassFile {
    pub(crate) name: String,
    pub(crate) inputs: u64,
    pub(crate) first: Numbered,
}

/// An input by its number in the sweep's space.
#[derive(Debug, Deserialize)]
pub(crate) struct Numbered {
    pub(crate) index: u64,
}

#[derive(Debug, Deserialize)]
pub(crate) struct ByteClassesFile {
    pub(crate) tuples: u64,
    pub(crate) checked: u64,
    pub(crate) mismatch: Option<serde_json::Value>,
}

#[derive(Debug, Deserialize)]
pub(crate) struct EachTextFile {
    pub(crate) texts: u64,
    pub(crate) classes: Vec<String>,
    pub(crate) tuples: u64,
    pub(crate) apart: u64,
    pub(crate) seconds: f64,
    pub(crate) disagreement: Option<serde_json::Value>,
}

/// A group as the shards add it up.
struct Tally {
    inputs: u64,
    first: u64,
    classes: BTreeMap<String, (u64, u64)>,
    /// The shard of its first input, for the error if it answers differently now.
    shard: usize,
}

impl ShardFile {
    /// Which shard of how many the file says it is (`settings.shard`).
    fn shard(&self) -> Option<(u64, u64)> {
        let shard = self.settings.get("shard")?;
        serde_json::from_value(shard.clone()).ok()
    }
}

/// The largest shard file a merge reads.
pub(crate) const MAX_SHARD_BYTES: u64 = 1 << 30;

/// The longest time a shard may say it took: more is no time a sweep took.
const MAX_SHARD_SECONDS: f64 = 1e9;

/// The shards' JSON results, each a regular file of bounded size (a FIFO, a device or a runaway
/// file is refused before anything is read), read and parsed (file, line and column on a bad
/// one).
pub(crate) fn read_files(paths: &[PathBuf]) -> Result<Vec<(PathBuf, ShardFile)>, SweepError> {
    paths
        .iter()
        .map(|p| {
            let bytes = crate::load::read_regular_limited(p, MAX_SHARD_BYTES)
                .map_err(|e| SweepError(format!("--merge {}: cannot be read: {e}", p.display())))?;
            let text = String::from_utf8(bytes)
                .map_err(|_| SweepError(format!("--merge {}: not UTF-8 text", p.display())))?;
            Ok((p.clone(), read(p, &text)?))
        })
        .collect()
}

/// Reads one shard's JSON results (`sweep --format json`).
fn read(path: &std::path::Path, text: &str) -> Result<ShardFile, SweepError> {
    serde_json::from_str(text).map_err(|e| {
        SweepError(format!(
            "{}:{}:{}: not the JSON results of a sweep (`sweep --format json --output FILE`): {e}",
            path.display(),
            e.line(),
            e.column()
        ))
    })
}

/// The results of the whole of `sweep` from its shards' files.
pub(crate) fn merge(
    sweep: &Sweep,
    files: &[(PathBuf, ShardFile)],
    stop: &AtomicBool,
) -> Result<Results, SweepError> {
    let started = Instant::now();
    check(sweep, files)?;
    let columns: Vec<&str> = sweep.columns.iter().map(|c| c.name.as_str()).collect();
    let mut tallies: HashMap<Key, Tally> = HashMap::new();
    for (f, (_, file)) in files.iter().enumerate() {
        for g in &file.groups {
            let signature = columns
                .iter()
                .map(|c| g.signature.get(*c).cloned().unwrap_or_default())
                .collect();
            let key = Key {
                signature,
                features: g.features.clone(),
            };
            let t = tallies.entry(key).or_insert(Tally {
                inputs: 0,
                first: u64::MAX,
                classes: BTreeMap::new(),
                shard: f,
            });
            t.inputs = t.inputs.saturating_add(g.inputs);
            if g.representative.index < t.first {
                t.first = g.representative.index;
                t.shard = f;
            }
            for c in &g.classes {
                let e = t.classes.entry(c.name.clone()).or_insert((0, u64::MAX));
                e.0 = e.0.saturating_add(c.inputs);
                e.1 = e.1.min(c.first.index);
            }
        }
    }
    // Every first input asked again, as the whole sweep would have found it.
    let (space, split_texts) = sweep.space_to_run(stop);
    // A space weighted by class is known only now: each shard holds the weight of every N-th
    // class tuple from the K-th, and counts that say otherwise are another sweep's.
    if space.classes.is_some() {
        for (path, file) in files {
            // Every file's shard was read when the files were checked.
            let shard = file.shard().unwrap_or((1, 1));
            let holds = space.held_by(shard);
            if file.shard_inputs != holds {
                return Err(SweepError(format!(
                    "{}: it says shard {}/{} holds {} input(s), where this sweep's holds \
                     {holds} by class: its counts are not this sweep's",
                    path.display(),
                    shard.0,
                    shard.1,
                    file.shard_inputs
                )));
            }
        }
    }
    let mut wanted: Vec<u64> = tallies
        .values()
        .flat_map(|t| std::iter::once(t.first).chain(t.classes.values().map(|c| c.1)))
        .collect();
    wanted.sort_unstable();
    wanted.dedup();
    let mut found: HashMap<u64, Found> = HashMap::new();
    for chunk in wanted.chunks(4096) {
        let points: Vec<(u64, Point)> = chunk.iter().map(|&i| (i, space.point(i))).collect();
        let answers = sweep.answers(&points, stop);
        for ((index, point), replies) in points.into_iter().zip(answers) {
            let Some(replies) = replies else {
                return Err(SweepError(
                    "interrupted while asking the first inputs again".into(),
                ));
            };
            found.insert(
                index,
                Found {
                    index,
                    point,
                    replies,
                },
            );
        }
    }
    let mut groups = Groups::new(sweep.settings.max_classes);
    for (key, t) in tallies {
        let rep = found[&t.first].clone();
        let now = Key {
            signature: labels_read(&sweep.columns, rep.point.digits, &rep.replies),
            features: rep.point.features(sweep.counted()),
        };
        if now != key {
            return Err(SweepError(format!(
                "input {} ({}) answers differently now than in {}: {} there, {} now; merge \
                 with the backends the shards ran",
                t.first,
                rep.point,
                files[t.shard].0.display(),
                key.signature.join(" "),
                now.signature.join(" ")
            )));
        }
        let mut kept: Vec<(String, (u64, u64))> = t.classes.into_iter().collect();
        kept.sort_by_key(|(_, (_, first))| *first);
        kept.truncate(sweep.settings.max_classes);
        let classes = kept
            .into_iter()
            .map(|(name, (inputs, first))| {
                let first = found[&first].clone();
                (
                    name.clone(),
                    Class {
                        name,
                        inputs,
                        first,
                    },
                )
            })
            .collect();
        let digits = rep.point.digits;
        groups.by_key.insert(
            key.clone(),
            Group {
                key,
                inputs: t.inputs,
                differing: differing(&sweep.columns, digits, &rep.replies)
                    .into_iter()
                    .map(|i| sweep.columns[i].name.clone())
                    .collect(),
                known: Vec::new(),
                disagree: disagree(&sweep.columns, digits, &rep.replies),
                representative: rep,
                classes,
            },
        );
    }
    // The counts were checked to add up within each shard and across them ([`check`]).
    let sum = |f: fn(&ShardFile) -> u64| {
        (files.iter()).fold(0u64, |total, (_, file)| total.saturating_add(f(file)))
    };
    let mut results = sweep.results(
        sum(|f| f.shard_inputs),
        sum(|f| f.swept),
        false,
        groups,
        started,
    );
    if let Some(c) = &space.classes {
        results.classes = Some(classes::Report {
            classes: c.describe(),
            split_texts,
            tuples: files
                .iter()
                .filter_map(|(_, f)| f.byte_classes.as_ref().map(|b| b.tuples))
                .sum(),
            checked: files
                .iter()
                .filter_map(|(_, f)| f.byte_classes.as_ref().map(|b| b.checked))
                .sum(),
            mismatch: None,
        });
    }
    let each: Vec<&EachTextFile> = files
        .iter()
        .filter_map(|(_, f)| f.each_text.as_ref())
        .collect();
    if let Some(first) = each.first() {
        results.exhaustive = Some(exhaustive::Report {
            texts: each.iter().map(|e| e.texts).sum(),
            classes: first.classes.clone(),
            tuples: each.iter().map(|e| e.tuples).sum(),
            apart: each.iter().map(|e| e.apart).sum(),
            seconds: each.iter().map(|e| e.seconds).sum(),
            disagreement: None,
        });
    }
    results.shrunk = super::shrink::shrink_groups(sweep, &results, stop);
    // Each shard's time was checked to be a time ([`check`]).
    let shards_took = files.iter().map(|(_, f)| f.elapsed_seconds).sum::<f64>();
    results.elapsed =
        Duration::try_from_secs_f64(shards_took).unwrap_or(Duration::MAX) + started.elapsed();
    Ok(results)
}

/// The files are the shards of this sweep, each once, complete and exact.
fn check(sweep: &Sweep, files: &[(PathBuf, ShardFile)]) -> Result<(), SweepError> {
    let tool = format!("plc-conformance {}", env!("CARGO_PKG_VERSION"));
    let mut settings = serde_json::to_value(&sweep.settings).unwrap_or_default();
    // The shard is each file's own; a seed the generator does not use (the clock's) is no
    // difference.
    let seeded = sweep.settings.generator.uses_seed();
    let without_shard = |v: &mut serde_json::Value| {
        if let Some(o) = v.as_object_mut() {
            o.remove("shard");
            if !seeded {
                o.remove("seed");
            }
        }
    };
    without_shard(&mut settings);
    let columns: Vec<&str> = sweep.columns.iter().map(|c| c.name.as_str()).collect();
    let mut shards: BTreeMap<u64, (&PathBuf, &ShardFile)> = BTreeMap::new();
    let mut of = None;
    for (path, file) in files {
        let at = |what: String| SweepError(format!("{}: {what}", path.display()));
        if file.tool != tool {
            return Err(at(format!(
                "written by {}; this is {tool}: run every shard and the merge with one version",
                file.tool
            )));
        }
        let shard = file
            .shard()
            .ok_or_else(|| at("no shard in its settings".into()))?;
        let mut theirs = file.settings.clone();
        without_shard(&mut theirs);
        if theirs != settings {
            let key = settings
                .as_object()
                .and_then(|o| {
                    o.iter()
                        .find(|(k, v)| theirs.get(k.as_str()) != Some(*v))
                        .map(|(k, _)| k.clone())
                })
                .unwrap_or_else(|| "settings".into());
            return Err(at(format!(
                "another sweep: its `{key}` is {}, this merge's is {}; give the merge the \
                 arguments the shards ran with",
                theirs
                    .get(&key)
                    .map_or("absent".into(), ToString::to_string),
                settings
                    .get(&key)
                    .map_or("absent".into(), ToString::to_string),
            )));
        }
        let names: Vec<&str> = file.columns.iter().map(|c| c.name.as_str()).collect();
        if names != columns {
            return Err(at(format!(
                "its columns are {}; this merge's are {}: give the merge the backends the shards \
                 ran",
                names.join(", "),
                columns.join(", ")
            )));
        }
        if shard.0 == 0 || shard.0 > shard.1 {
            return Err(at(format!(
                "shard {}/{} is no shard of {}",
                shard.0, shard.1, shard.1
            )));
        }
        if !(0.0..=MAX_SHARD_SECONDS).contains(&file.elapsed_seconds) {
            return Err(at(format!(
                "it says it took {:?} s, which is no time a shard took",
                file.elapsed_seconds
            )));
        }
        let grouped = (file.groups.iter()).try_fold(0u64, |t, g| t.checked_add(g.inputs));
        if file.swept > file.shard_inputs || grouped != Some(file.swept) {
            return Err(at(format!(
                "its counts do not add up: {} input(s) swept of {}, its groups hold {}",
                file.swept,
                file.shard_inputs,
                grouped.map_or("more than 2^64".into(), |g| g.to_string())
            )));
        }
        if file.interrupted {
            return Err(at(format!(
                "shard {}/{} was interrupted ({} of {} inputs): run it again",
                shard.0, shard.1, file.swept, file.shard_inputs
            )));
        }
        if file
            .byte_classes
            .as_ref()
            .is_some_and(|b| b.mismatch.is_some())
            || file
                .each_text
                .as_ref()
                .is_some_and(|e| e.disagreement.is_some())
        {
            return Err(at(
                "its counts are not exact (its check failed): fix what it reports first".into(),
            ));
        }
        if *of.get_or_insert(shard.1) != shard.1 {
            return Err(at(format!(
                "shard {}/{}, where the others are of {}",
                shard.0,
                shard.1,
                of.unwrap_or_default()
            )));
        }
        if let Some((other, _)) = shards.insert(shard.0, (path, file)) {
            return Err(at(format!(
                "shard {}/{} again (also {})",
                shard.0,
                shard.1,
                other.display()
            )));
        }
    }
    let n = of.unwrap_or(0);
    // Every shard is in 1..=n and given once, so the count tells whether one is missing; the
    // list of those missing is cut short (n may be any number a file claims).
    let absent = n.saturating_sub(shards.len() as u64);
    if n == 0 || absent > 0 {
        let shown: Vec<String> = (1..=n)
            .filter(|k| !shards.contains_key(k))
            .take(10)
            .map(|k| format!("{k}/{n}"))
            .collect();
        return Err(SweepError(format!(
            "the shards are not the whole sweep: missing {}",
            match (shown.is_empty(), absent > shown.len() as u64) {
                (true, _) => "every shard".to_string(),
                (false, true) => format!(
                    "{} and {} more",
                    shown.join(", "),
                    absent - shown.len() as u64
                ),
                (false, false) => shown.join(", "),
            }
        )));
    }
    // Counts that add up can still be another sweep's: a shard of a space that is not weighted
    // by class holds exactly every N-th input from the K-th.
    if sweep.space.classes.is_none() && !matches!(sweep.settings.generator, Generator::Full { .. })
    {
        for (k, (path, file)) in &shards {
            let holds = sweep.space.held_by((*k, n));
            if file.shard_inputs != holds {
                return Err(SweepError(format!(
                    "{}: it says shard {k}/{n} holds {} input(s), where this sweep's holds \
                     {holds}: its counts are not this sweep's",
                    path.display(),
                    file.shard_inputs
                )));
            }
        }
    }
    Ok(())
}
