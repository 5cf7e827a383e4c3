//! Hardware in the loop: what a bench with a real CPU needs around the bench backend
//! (`backend::bench`, over the link the profile's `bench` section names).
//!
//! - [`generate`]: the test program the CPU runs, from the corpus's own operands: one rung per
//!   instruction and operand tuple the trials use, the manifest (rung table, mailbox, hash, the
//!   words case windows write) and a setup checklist;
//! - [`dry_run`]: every trial a live backend would run, with what it would write, checked
//!   against its write fence, without a socket.

mod ladder;
mod program;
mod setup;

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::fence::{self, WordRange};
use crate::backend::bench::mailbox;
use crate::backend::bench::manifest::{self, Call, ErrorDevices, Manifest, Rung, Unrealisable};
use crate::backend::bench::{Addressing, BenchBackend};
use crate::backend::external::window;
use crate::backend::Backend;
use crate::device::Device;
use crate::execute::{images, requests};
use crate::model::profile::{Bench, Profile, ProgramForm, Variant};
use crate::model::Operand;
use crate::project::Project;

pub(crate) use program::{setup_text, structured_text};

/// What to generate a program for.
#[derive(Debug, Clone, Default)]
pub struct GenerateOptions {
    /// The profile id.
    pub profile: String,
    /// Only these variants' trials (default: every variant).
    pub variants: Vec<String>,
    /// The mailbox's first word (default: chosen clear of every case window).
    pub mailbox: Option<Device>,
    /// Only trials whose name contains this.
    pub filter: Option<String>,
}

/// A generated program: the manifest, the structured text and the setup checklist.
#[derive(Debug, Clone)]
pub struct Generated {
    pub manifest: Manifest,
    pub program: String,
    /// The program's file name: `executive.st` (structured text), `executive.txt` (a rung list).
    pub program_file: &'static str,
    pub setup: String,
    /// Trials the rung table covers.
    pub trials: usize,
}

/// Why a constant cannot be written into the program: it must fit the operand as a signed
/// decimal constant of its width (16 bits, or 32 for the data operand of a D-prefixed form).
pub(crate) fn unrealisable(instruction: &str, operand: &str, value: i64) -> Option<String> {
    let bits = if instruction.starts_with('D') && operand != "n" {
        32
    } else {
        16
    };
    let (lo, hi) = (-(1i64 << (bits - 1)), (1i64 << (bits - 1)) - 1);
    (!(lo..=hi).contains(&value)).then(|| {
        format!(
            "operand {operand} = K{value} does not fit a {bits}-bit constant (K{lo} to K{hi}), so \
             no program can hold it as written"
        )
    })
}

/// Why a device operand cannot be part of a live case (the link's `unaddressable`): the case's
/// memory could be neither set nor read back.
fn unaddressable(addressing: &dyn Addressing, operand: &str, device: &Device) -> Option<String> {
    addressing.unaddressable(device).map(|why| {
        format!("operand {operand} = {device}: {why}, so no program can hold it as written")
    })
}

/// Generates the program for a profile from the project's corpus.
pub fn generate(project: &Project, options: &GenerateOptions) -> Result<Generated, LiveError> {
    let profile = project
        .profiles
        .get(&options.profile)
        .cloned()
        .ok_or_else(|| {
            refused!(
                "profile `{}` is not loaded; known profiles: {}",
                options.profile,
                project.profiles.ids().join(", ")
            )
        })?;
    let bench = profile.bench.clone().ok_or_else(|| {
        refused!(
            "{} has no `bench` section in its profile: no bench runs its corpus on a CPU \
             (profiles with one: {})",
            profile.id,
            (project.profiles.iter())
                .filter(|p| p.bench.is_some())
                .map(|p| p.id.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    let addressing = crate::backend::addressing(&profile)?;
    let addressing = addressing.as_ref();
    let errors = error_devices(&profile, &bench)?;
    for v in &options.variants {
        if profile.variant(v).is_none() {
            return Err(refused!("`{v}` is not a variant of {}", profile.id));
        }
    }
    let variants: Vec<String> = if options.variants.is_empty() {
        profile.variants.iter().map(|v| v.id.clone()).collect()
    } else {
        options.variants.clone()
    };
    let model: Arc<dyn Backend> =
        crate::backend::reference_model(&project.profiles, &profile.id)
            .ok_or_else(|| refused!("no built-in reference model for {}", profile.id))?;
    let trials: Vec<_> = project
        .plan(std::slice::from_ref(&model))
        .into_iter()
        .filter(|t| t.skip.is_none() && variants.contains(&t.variant))
        .filter(|t| {
            options
                .filter
                .as_ref()
                .is_none_or(|f| t.name().contains(f.as_str()))
        })
        .collect();
    if trials.is_empty() {
        return Err(refused!(
            "no trial of the corpus matches: nothing to generate"
        ));
    }
    // Whether each instruction and operand tuple can be a rung.
    let mut seen: BTreeMap<String, bool> = BTreeMap::new();
    let mut rungs: Vec<Rung> = Vec::new();
    let mut unrealisables: Vec<Unrealisable> = Vec::new();
    let mut windows: Vec<WordRange> = Vec::new();
    for t in &trials {
        let input = &t.input;
        let call = Call::new(&input.operands, &input.indirect);
        let key = call.key(&input.instruction);
        if !seen.contains_key(&key) {
            let why = input
                .operands
                .iter()
                .find_map(|(name, o)| match o {
                    Operand::Constant(k) => unrealisable(&input.instruction, name, *k),
                    Operand::Device(d) => unaddressable(addressing, name, d),
                })
                .or_else(|| {
                    (input.indirect.iter()).find_map(|(name, p)| {
                        unaddressable(addressing, &format!("{name}'s pointer"), p)
                    })
                });
            seen.insert(key.clone(), why.is_none());
            let Call {
                operands,
                addresses,
            } = call;
            match why {
                Some(reason) => unrealisables.push(Unrealisable {
                    instruction: input.instruction.clone(),
                    operands,
                    addresses,
                    reason,
                }),
                None => rungs.push(Rung {
                    id: rungs.len() as u16 + 1,
                    instruction: input.instruction.clone(),
                    operands,
                    addresses,
                }),
            }
        }
        // An unrealisable case never runs, so its window is never written.
        if seen.get(&key) != Some(&true) {
            continue;
        }
        let imgs = images(t);
        for req in requests(t, &imgs) {
            // Words the client cannot address are never written: such a case is not run
            // (`BenchBackend::plan` says why), so they take no part in the sandbox.
            windows.extend(
                window::ranges(&req)
                    .into_iter()
                    .filter(|(head, _)| addressing.unaddressable(head).is_none())
                    .map(|(head, last)| WordRange::within(&head, head.index, last)),
            );
        }
    }
    if rungs.len() > usize::from(u16::MAX) {
        return Err(refused!(
            "{} rungs do not fit the mailbox's rung word",
            rungs.len()
        ));
    }
    let writes = fence::merged(windows);
    let mailbox = match &options.mailbox {
        Some(m) => m.clone(),
        None => choose_mailbox(&profile, &variants, &writes)?,
    };
    if let Some(why) = addressing.unaddressable(&mailbox) {
        return Err(refused!("the mailbox cannot be at {mailbox}: {why}"));
    }
    let whole = mailbox::range(&mailbox);
    if let Some(w) = writes.iter().find(|w| w.overlaps(&whole)) {
        return Err(refused!(
            "the mailbox {whole} overlaps the case windows {w}; choose a mailbox clear of every \
             window ({})",
            fence::list(&writes)
        ));
    }
    for v in &variants {
        let variant = profile
            .variant(v)
            .ok_or_else(|| refused!("no variant {v}"))?;
        if !profile.words_exist(variant, &mailbox, mailbox::WORDS) {
            return Err(refused!(
                "the mailbox {whole} does not exist on variant {v} of {}",
                profile.id
            ));
        }
    }
    let mut flags: Vec<String> = rungs
        .iter()
        .filter_map(|r| profile.instructions.get(&r.instruction))
        .flat_map(|def| def.flags.iter().cloned())
        .collect();
    flags.sort();
    flags.dedup();
    let mut manifest = Manifest {
        format: manifest::FORMAT,
        generator: format!("plc-conformance {}", env!("CARGO_PKG_VERSION")),
        profile: profile.id.clone(),
        variants,
        mailbox: mailbox.to_string(),
        layout: mailbox::LAYOUT,
        flags,
        error: errors,
        rungs,
        unrealisable: unrealisables,
        writes: writes.iter().map(ToString::to_string).collect(),
        hash: String::new(),
    };
    manifest.hash = manifest.compute_hash();
    manifest.validate(addressing)?;
    let (program, setup, program_file) = match bench.program {
        ProgramForm::StructuredText => (
            structured_text(&manifest, &profile)?,
            setup_text(&manifest, &profile, trials.len()),
            "executive.st",
        ),
        ProgramForm::Ladder => {
            let (program, setup) = ladder::ladder(&manifest, &profile, trials.len())?;
            (program, setup, ladder::PROGRAM_FILE)
        }
    };
    Ok(Generated {
        manifest,
        program,
        program_file,
        setup,
        trials: trials.len(),
    })
}

/// Where the program finds an error: the profile's error flag, its register and first further
/// register where it has them, and the bench's error reset.
fn error_devices(profile: &Profile, bench: &Bench) -> Result<ErrorDevices, LiveError> {
    let errors = &profile.errors;
    let flag = errors.flag.as_ref().ok_or_else(|| {
        refused!(
            "{} signals errors without a flag; the test program reads an error flag",
            profile.id
        )
    })?;
    Ok(ErrorDevices {
        flag: flag.to_string(),
        register: errors.register.as_ref().map(ToString::to_string),
        extra: errors.also.first().map(ToString::to_string),
        reset: bench.error_reset.clone(),
    })
}

/// A mailbox clear of every window and on every variant: the highest round number in D (a
/// multiple of 1000, else of 100, 10, 1) whose 32 words every variant has and no case window
/// touches. The highest, so that a program generated for fewer cases (`--filter`, one variant)
/// keeps the place of the whole one.
fn choose_mailbox(
    profile: &Profile,
    variants: &[String],
    writes: &[WordRange],
) -> Result<Device, LiveError> {
    let variants: Vec<&Variant> = variants.iter().filter_map(|v| profile.variant(v)).collect();
    let last = (variants.iter())
        .filter_map(|v| profile.ranges(v, "D"))
        .filter_map(|r| r.iter().map(|r| r.last).max())
        .max()
        .ok_or_else(|| refused!("{} has no data registers (D) for a mailbox", profile.id))?;
    let taken: Vec<(u32, u32)> = (writes.iter())
        .filter(|w| w.code == "D")
        .map(|w| (w.first, w.last))
        .collect();
    let fits = |at: u32| {
        let end = at + (mailbox::WORDS - 1);
        end <= last
            && taken.iter().all(|&(first, l)| end < first || at > l)
            && (variants.iter())
                .all(|v| profile.words_exist(v, &Device::new("D", at), mailbox::WORDS))
    };
    [1000, 100, 10, 1]
        .into_iter()
        .find_map(|step| {
            (0..=last / step)
                .rev()
                .map(|k| k * step)
                .find(|at| fits(*at))
        })
        .map(|at| Device::new("D", at))
        .ok_or_else(|| {
            refused!(
                "no 32 free data registers outside the case windows for the mailbox on every \
                 variant ({}); give --variant to generate for fewer, or --mailbox",
                variants
                    .iter()
                    .map(|v| v.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}

/// What a dry run found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct DryRun {
    /// Trials the backend would run.
    pub trials: usize,
    /// Executions (trials times fills).
    pub executions: usize,
    /// Trials it would not run, with why (no rung, unrealisable, not claimed, ...).
    pub skipped: Vec<(String, String)>,
    /// Executions the fence refuses, by trial name.
    pub refused: Vec<(String, String)>,
    /// Every word it would write, merged.
    pub writes: Vec<WordRange>,
    /// Rungs it would select.
    pub rungs: usize,
}

/// Every trial of the corpus the backend would run, with what it would write: the plan the
/// live backend makes for each execution, fence checked, and nothing sent (the backend opens no
/// socket before its first case).
pub(crate) fn dry_run(project: &Project, backend: &Arc<BenchBackend>) -> DryRun {
    let as_backend: Arc<dyn Backend> = backend.clone();
    let mut out = DryRun::default();
    let mut writes = Vec::new();
    let mut rungs = std::collections::BTreeSet::new();
    let mailbox_words = backend
        .settings()
        .manifest
        .mailbox_head(backend.settings().link.addressing())
        .map(|m| mailbox::pc_words(&m))
        .unwrap_or_default();
    for t in project.plan(&[as_backend]) {
        if let Some(why) = &t.skip {
            out.skipped.push((t.name(), why.clone()));
            continue;
        }
        out.trials += 1;
        let imgs = images(&t);
        for req in requests(&t, &imgs) {
            out.executions += 1;
            match backend.plan(&req) {
                Ok(plan) => {
                    rungs.insert(plan.rung);
                    writes.extend(
                        plan.window
                            .iter()
                            .map(|(head, words)| WordRange::of(head, words.len() as u32)),
                    );
                    writes.extend(mailbox_words.iter().cloned());
                }
                Err(why) => out
                    .refused
                    .push((t.name(), crate::error_chain::chain(&why))),
            }
        }
    }
    out.writes = fence::merged(writes);
    out.rungs = rungs.len();
    out
}

/// Whether a trial is a corpus case that expects words to change without an error: two
/// executions of it can be told apart from one that did nothing.
fn expects_writes(t: &crate::plan::Trial) -> bool {
    match &t.check {
        crate::plan::Check::Native { case, .. } => case
            .expect
            .as_ref()
            .is_some_and(|e| !e.after.is_empty() && e.error.is_none()),
        _ => false,
    }
}

/// What the pulse self-test found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PulseCheck {
    /// The trial it ran twice.
    pub trial: String,
    /// Whether the second execution did what the first did.
    pub fired_twice: bool,
    /// What each execution did, for the message.
    pub first: String,
    pub second: String,
}

/// What `hil doctor --self-test` found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum SelfTest {
    /// The profile has no pulse-form instruction (IDEC ATOH and HTOA run on every scan their
    /// enable is on): no rung can fire once only, so there is nothing to run twice.
    NoPulseForms { profile: String },
    /// A pulse-form case run twice.
    Ran(PulseCheck),
}

/// The pulse self-test where the profile has pulse forms ([`pulse_self_test`]); a profile
/// without any passes with the reason.
pub(crate) fn self_test(
    project: &Project,
    backend: &Arc<BenchBackend>,
) -> Result<SelfTest, LiveError> {
    let profile = (project.profiles.get(backend.profile()))
        .ok_or_else(|| refused!("profile `{}` is not loaded", backend.profile()))?;
    let pulse_forms = (profile.instructions.keys())
        .filter_map(|name| name.strip_suffix('P'))
        .any(|base| profile.instructions.contains_key(base));
    if !pulse_forms {
        return Ok(SelfTest::NoPulseForms {
            profile: profile.id.clone(),
        });
    }
    pulse_self_test(project, backend).map(SelfTest::Ran)
}

/// Runs one pulse-form case twice in a row on a connected live backend and compares what the
/// two executions did. A pulse form executes on its enable's rising edge; if the program on the
/// CPU did not let the enable fall between two cases (rungs inside IF or CASE, or an engineering
/// tool that treats pulse calls in structured text otherwise), the second execution does
/// nothing and every later case of that rung would be judged on a stale result. Writes only
/// what a case writes: its window (inside the fence) and the mailbox's PC words.
pub(crate) fn pulse_self_test(
    project: &Project,
    backend: &Arc<BenchBackend>,
) -> Result<PulseCheck, LiveError> {
    let as_backend: Arc<dyn Backend> = backend.clone();
    let profile = project
        .profiles
        .get(backend.profile())
        .ok_or_else(|| refused!("profile `{}` is not loaded", backend.profile()))?;
    let trials = project.plan(&[as_backend]);
    let trial = trials
        .iter()
        .filter(|t| t.skip.is_none())
        .find(|t| {
            t.input
                .instruction
                .strip_suffix('P')
                .is_some_and(|base| profile.instructions.contains_key(base))
                && expects_writes(t)
        })
        .ok_or_else(|| {
            refused!("the program has no pulse-form rung whose case writes something to compare")
        })?;
    let imgs = images(trial);
    let reqs = requests(trial, &imgs);
    let req = reqs
        .first()
        .ok_or_else(|| refused!("{}: no request", trial.name()))?;
    let show = |r: &Result<crate::backend::Response, crate::backend::Fault>| match r {
        Ok(crate::backend::Response::Done(o)) if o.writes.is_empty() && o.error.is_none() => {
            "nothing".to_string()
        }
        Ok(crate::backend::Response::Done(o)) => {
            let mut words: Vec<String> = o
                .writes
                .iter()
                .map(|(d, v)| format!("{d}={v:04X}H"))
                .collect();
            if let Some(e) = &o.error {
                words.push(format!("error {e}"));
            }
            words.join(" ")
        }
        Ok(other) => format!("{other:?}"),
        Err(fault) => fault.to_string(),
    };
    let first = backend.execute(req);
    if let Err(fault) = &first {
        return Err(refused!("{}: {fault}", trial.name()));
    }
    let second = backend.execute(req);
    // A second execution the rung's proof shows did not happen is the finding, not a fault of
    // the self-test.
    if let Err(fault) = &second {
        if backend.take_not_executed().is_none() {
            return Err(refused!("{}: {fault}", trial.name()));
        }
    }
    Ok(PulseCheck {
        trial: trial.name(),
        fired_twice: second.is_ok() && first == second,
        first: show(&first),
        second: show(&second),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::project::Paths;

    /// Every variant of every profile with a bench gets a program, alone and with the others:
    /// the mailbox finds 32 free words on the smallest CPU (an FC4A-C10R2 has D0-D399).
    #[test]
    fn every_bench_variant_gets_a_program() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let project = Project::load(&Paths::under(root)).expect("the project loads");
        let benches: Vec<&Arc<Profile>> = (project.profiles.iter())
            .filter(|p| p.bench.is_some())
            .collect();
        assert!(benches.len() >= 3, "{} bench profiles", benches.len());
        for profile in benches {
            let each = profile.variants.iter().map(|v| vec![v.id.clone()]);
            for variants in std::iter::once(Vec::new()).chain(each) {
                let options = GenerateOptions {
                    profile: profile.id.clone(),
                    variants: variants.clone(),
                    mailbox: None,
                    filter: None,
                };
                let generated = generate(&project, &options).unwrap_or_else(|e| {
                    panic!(
                        "{} {variants:?}: {}",
                        profile.id,
                        crate::error_chain::chain(&e)
                    )
                });
                assert!(generated.trials > 0, "{} {variants:?}", profile.id);
            }
        }
    }
}
