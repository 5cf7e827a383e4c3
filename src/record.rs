//! Recording what a backend does into the vectors: the way an engineer pins what a real CPU (or
//! an emulator) does, so that a firmware update or a port shows what changed.
//!
//! Each native case the backend runs is executed through the pipeline (under both fills); where
//! it did the same on every variant and instruction of the case, the case becomes `observed`:
//! its expectation is what the backend did, its `provenance` says which backend, when and on
//! which model or firmware, and its cite keeps what the expectation rested on before. An
//! `unspecified` case gets the outcome it only recorded until now. A `manual` expectation is
//! never overwritten. The vector files are edited in place, line by line, so comments and
//! layout stay as they were.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::backend::{Backend, Response};
use crate::corpus_yaml::{expect_lines, quote_str};
use crate::execute::Observation;
use crate::judge::Effect;
use crate::model::{Basis, Case, Expectation};
use crate::plan::{Check, Trial};
use crate::project::Project;
use crate::session::observe;

/// What recording did to one case.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Change {
    /// An `unspecified` case now expects what the backend did.
    Filled { effect: Effect },
    /// An `inferred` or `observed` expectation replaced; `same` when the backend did what it
    /// said.
    Replaced {
        was: Basis,
        effect: Effect,
        same: bool,
    },
    /// A `manual` expectation, kept; `differs` when the backend did something else.
    KeptManual { effect: Effect, differs: bool },
    /// Not recorded, and why.
    NotRecorded(String),
    /// Not recorded because the backend faulted (crashed, hung, answered garbage): a failure.
    Faulted(String),
}

/// One case and what happened to it.
#[derive(Debug, Clone)]
pub(crate) struct Entry {
    pub case: Arc<Case>,
    pub change: Change,
}

/// The result of recording: what changed, and the new text of every file that changed.
#[derive(Debug, Default)]
pub(crate) struct Recording {
    pub entries: Vec<Entry>,
    pub files: BTreeMap<PathBuf, String>,
}

/// Who recorded, when: what goes into each `provenance`.
#[derive(Debug, Clone)]
pub(crate) struct Provenance {
    pub backend: String,
    pub version: String,
    pub date: String,
}

/// What a backend did on one variant (and instruction) of a case, or why it cannot be recorded.
type VariantEffect = (String, Result<Effect, NoEffect>);

/// Why a trial gave nothing to record.
#[derive(Debug, Clone, PartialEq, Eq)]
enum NoEffect {
    /// The backend faulted.
    Fault(String),
    /// It answered, but not something a vector can hold.
    Unrecordable(Unrecordable),
}

/// Why what a backend did on a case cannot be written into the vector.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Unrecordable(pub String);

impl std::fmt::Display for Unrecordable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Why a recording could not be made at all.
#[derive(Debug)]
pub(crate) enum RecordError {
    /// A vector file to edit could not be read.
    Read {
        file: PathBuf,
        source: std::io::Error,
    },
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordError::Read { file, .. } => write!(f, "cannot read {}", file.display()),
        }
    }
}

impl std::error::Error for RecordError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RecordError::Read { source, .. } => Some(source),
        }
    }
}

/// Runs every native case of the corpus that `backend` runs (and whose trial name contains
/// `filter`) and works out the edits.
pub(crate) fn record(
    project: &Project,
    backend: &Arc<dyn Backend>,
    filter: Option<&str>,
    provenance: &Provenance,
    stop: &AtomicBool,
) -> Result<Recording, RecordError> {
    let trials: Vec<Trial> = project
        .plan(std::slice::from_ref(backend))
        .into_iter()
        .filter(|t| matches!(t.check, Check::Native { .. }))
        .filter(|t| t.skip.is_none())
        .filter(|t| filter.is_none_or(|f| t.name().contains(f)))
        .collect();
    // Per case: what the backend did on each trial.
    let mut by_case: Vec<(Arc<Case>, Vec<VariantEffect>)> = Vec::new();
    // Executed as a run executes them (batched), not judged. An interrupted recording records
    // what it observed.
    for (trial, observations) in trials.iter().zip(observe(&trials, 1, stop)) {
        let (Check::Native { case, .. }, Some(observations)) = (&trial.check, observations) else {
            continue;
        };
        let effect = effect_of(trial, &observations);
        match by_case.iter_mut().find(|(c, _)| Arc::ptr_eq(c, case)) {
            Some((_, list)) => list.push((trial.variant.clone(), effect)),
            None => by_case.push((case.clone(), vec![(trial.variant.clone(), effect)])),
        }
    }
    let mut out = Recording::default();
    let mut texts: BTreeMap<PathBuf, String> = BTreeMap::new();
    for (case, results) in by_case {
        let change = decide(&case, &results);
        let write = match &change {
            Change::Filled { effect } | Change::Replaced { effect, .. } => Some(effect.clone()),
            _ => None,
        };
        if let Some(effect) = write {
            let file = case.location.file.clone();
            if !texts.contains_key(&file) {
                let text = std::fs::read_to_string(&file).map_err(|source| RecordError::Read {
                    file: file.clone(),
                    source,
                })?;
                texts.insert(file.clone(), text);
            }
            let mut variants: Vec<String> = Vec::new();
            for (v, _) in &results {
                if !variants.contains(v) {
                    variants.push(v.clone());
                }
            }
            let profile = project.profiles.get(&case.profiles[0]);
            let model = variants
                .iter()
                .filter_map(|v| profile.and_then(|p| p.variant(v)))
                .map(|v| v.description.clone())
                .collect::<Vec<_>>()
                .join("; ");
            let Some(text) = texts.get_mut(&file) else {
                continue;
            };
            match edit(text, &case, &effect, &variants, &model, provenance) {
                Ok(new) => *text = new,
                Err(Unrecordable(why)) => {
                    out.entries.push(Entry {
                        case,
                        change: Change::NotRecorded(why),
                    });
                    continue;
                }
            }
        }
        out.entries.push(Entry { case, change });
    }
    out.files = texts;
    Ok(out)
}

/// What the backend did on a trial (fill A), or why it cannot be recorded.
fn effect_of(trial: &Trial, observations: &[Observation]) -> Result<Effect, NoEffect> {
    let not = |why: &str| NoEffect::Unrecordable(Unrecordable(why.to_string()));
    let mut effects = Vec::new();
    for o in observations {
        match &o.result {
            Ok(Response::Done(outcome)) => {
                let image = trial.image(o.fill);
                effects.push(Effect::of(&image, outcome));
            }
            Ok(Response::Unsupported(r)) => return Err(not(&format!("unsupported: {r}"))),
            Ok(Response::Answer(_)) => return Err(not("a codec answer")),
            Err(f) => return Err(NoEffect::Fault(f.to_string())),
        }
    }
    match effects.as_slice() {
        [first, rest @ ..] if rest.iter().all(|e| e == first) => Ok(first.clone()),
        [_, ..] => Err(not(
            "the outcome depends on the fill: the backend reads memory the case does not set",
        )),
        [] => Err(not("no answer")),
    }
}

fn decide(case: &Case, results: &[VariantEffect]) -> Change {
    let mut effect: Option<&Effect> = None;
    for (variant, r) in results {
        match r {
            Err(NoEffect::Fault(why)) => return Change::Faulted(format!("on {variant}: {why}")),
            Err(NoEffect::Unrecordable(why)) => {
                return Change::NotRecorded(format!("on {variant}: {why}"))
            }
            Ok(e) => match effect {
                None => effect = Some(e),
                Some(first) if first != e => {
                    return Change::NotRecorded(format!(
                        "the backend did different things on different variants or instructions \
                         ({first} and, on {variant}, {e}); give --filter to record one"
                    ))
                }
                Some(_) => {}
            },
        }
    }
    let Some(effect) = effect.cloned() else {
        return Change::NotRecorded("not run".into());
    };
    let same = case
        .expect
        .as_ref()
        .is_some_and(|x| expectation_matches(x, &effect));
    match case.basis {
        Basis::Manual => Change::KeptManual {
            differs: !same,
            effect,
        },
        Basis::Unspecified => Change::Filled { effect },
        was => Change::Replaced { was, effect, same },
    }
}

fn expectation_matches(x: &Expectation, e: &Effect) -> bool {
    x.after == e.changed && x.error == e.error
}

/// Where a recorded cite says what the expectation rested on before.
const BEFORE: &str = "; before, ";

/// The indent of a line (spaces).
fn indent(line: &str) -> usize {
    line.len() - line.trim_start_matches(' ').len()
}

/// Rewrites one case in a vector file's text: `basis: observed`, the cite with the provenance
/// and what it rested on before, `provenance`, and `expect`.
fn edit(
    text: &str,
    case: &Case,
    effect: &Effect,
    variants: &[String],
    model: &str,
    p: &Provenance,
) -> Result<String, Unrecordable> {
    let lines: Vec<&str> = text.lines().collect();
    let head = format!("- id: {}", case.id);
    let start = lines.iter().position(|l| l.trim() == head).ok_or_else(|| {
        Unrecordable(format!(
            "`{head}` is not on a line of its own in {}",
            case.location.file.display()
        ))
    })?;
    let dash = indent(lines[start]);
    let key_indent = dash + 2;
    let mut end = start + 1;
    while end < lines.len() {
        let l = lines[end];
        if !l.trim().is_empty() && indent(l) <= dash {
            break;
        }
        end += 1;
    }
    // Trailing blank lines and comments belong to what follows.
    while end > start + 1 && {
        let t = lines[end - 1].trim();
        t.is_empty() || t.starts_with('#')
    } {
        end -= 1;
    }
    // The keys of the case and the lines each spans.
    let mut keys: Vec<(String, usize, usize)> = Vec::new();
    let mut i = start;
    while i < end {
        let l = lines[i];
        let body = if i == start {
            &l[dash + 2..]
        } else {
            l.trim_start()
        };
        let at = if i == start { key_indent } else { indent(l) };
        if at == key_indent && !body.starts_with('#') {
            if let Some((k, _)) = body.split_once(':') {
                let mut j = i + 1;
                while j < end && (lines[j].trim().is_empty() || indent(lines[j]) > key_indent) {
                    j += 1;
                }
                keys.push((k.trim().to_string(), i, j));
                i = j;
                continue;
            }
        }
        i += 1;
    }
    let pad = " ".repeat(key_indent);
    // Recording again keeps what the expectation rested on before it was first observed,
    // rather than stacking "before, observed" on it each time.
    let was = match (&case.citation.text, case.basis) {
        (Some(t), Basis::Observed) => t
            .find(BEFORE)
            .map_or_else(String::new, |at| t[at..].to_string()),
        (Some(t), basis) => format!("{BEFORE}{basis}: {t}"),
        (None, basis) => format!("{BEFORE}{basis}"),
    };
    let cite = format!("observed on {} ({}), {}{was}", p.backend, p.version, p.date);
    let mut replacement: BTreeMap<&str, String> = BTreeMap::new();
    replacement.insert("basis", format!("{pad}basis: observed"));
    replacement.insert("cite", format!("{pad}cite: {}", quote_str(&cite)));
    replacement.insert(
        "provenance",
        format!(
            "{pad}provenance:\n{pad}  backend: {}\n{pad}  version: {}\n{pad}  date: \"{}\"\n{pad}  variants: [{}]\n{pad}  model: {}",
            p.backend,
            quote_str(&p.version),
            p.date,
            variants.join(", "),
            quote_str(model)
        ),
    );
    replacement.insert("expect", expect_lines(effect, &pad));
    let mut out: Vec<String> = lines[..start].iter().map(|s| s.to_string()).collect();
    let mut done: Vec<&str> = Vec::new();
    let mut cursor = start;
    for (k, from, to) in &keys {
        out.extend(lines[cursor..*from].iter().map(|s| s.to_string()));
        cursor = *to;
        // Blank lines inside a span stay after it.
        let trailing: Vec<String> = lines[*from..*to]
            .iter()
            .rev()
            .take_while(|l| l.trim().is_empty())
            .map(|s| s.to_string())
            .collect();
        match replacement.get(k.as_str()) {
            Some(new) => {
                let mut new = new.clone();
                if *from == start {
                    new = format!("{}- {}", " ".repeat(dash), new.trim_start());
                }
                out.push(new);
                done.push(k.as_str());
            }
            None => out.extend(
                lines[*from..*to - trailing.len()]
                    .iter()
                    .map(|s| s.to_string()),
            ),
        }
        out.extend(trailing);
    }
    // Keys the case did not have yet, after its last line.
    let mut tail: Vec<String> = Vec::new();
    for k in ["cite", "provenance", "expect"] {
        if !done.contains(&k) {
            tail.push(replacement[k].clone());
        }
    }
    let last_content = out
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(out.len(), |i| i + 1);
    let rest: Vec<String> = out.split_off(last_content);
    out.extend(tail);
    out.extend(rest);
    out.extend(lines[cursor..].iter().map(|s| s.to_string()));
    let mut joined = out.join("\n");
    if text.ends_with('\n') {
        joined.push('\n');
    }
    Ok(joined)
}
