//! Planning: which trials a run has, and what each one asks of its backend.
//!
//! A trial is one check on one backend, on one variant of the backend's profile. The check is a
//! native case run as one of its file's instructions, or a cross-vendor case run through one of
//! the profile's lowerings; either way the plan turns it into the same [`Input`] (instruction,
//! flags, operands, memory set), so everything after planning — executing, judging, reporting —
//! has one path for both. What is known when planning is decided here: a trial the backend does
//! not claim is skipped with the reason, and a trial whose outcome cannot fail (an `unspecified`
//! case, a listed known difference) is marked so that a test runner can count it as ignored.

pub(crate) mod lowering;

pub(crate) use lowering::input as lowered_input;

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::backend::{Backend, Setting};
use crate::device::Device;
use crate::memory::{Fill, Image, Unit, Value};
use crate::model::cross_vendor::{Answer, CrossVendorCase, ErrorClass, Lowering};
use crate::model::known::{Entry, KnownDifferences, Subject};
use crate::model::profile::{Profile, Profiles};
use crate::model::{Basis, Case, Citation, Corpus, Indirect, Location, Operand};

/// What a trial checks.
#[derive(Debug, Clone)]
pub(crate) enum Check {
    /// A case of the corpus, run as one of its file's instructions.
    Native {
        instruction: String,
        case: Arc<Case>,
    },
    /// A cross-vendor case, run through one of the profile's lowerings.
    CrossVendor {
        lowering: Arc<Lowering>,
        case: Arc<CrossVendorCase>,
    },
    /// A cross-vendor case, asked of a codec-level backend directly.
    Codec { case: Arc<CrossVendorCase> },
}

/// What a trial asks its backend to execute, under every fill.
#[derive(Debug, Clone, Default)]
pub struct Input {
    pub instruction: String,
    /// The flags set; the rest hold the profile default.
    pub flags: BTreeMap<String, bool>,
    pub operands: BTreeMap<String, Operand>,
    /// The operands given by indirect specification, with their pointers.
    pub indirect: Indirect,
    /// The memory set before execution; every other word holds the fill.
    pub before: BTreeMap<Device, Value>,
}

/// One check on one backend and variant.
#[derive(Clone)]
pub struct Trial {
    /// The backend the trial runs on.
    pub backend: Arc<dyn Backend>,
    /// The profile the trial runs on; a codec-level trial has none.
    pub profile: Option<Arc<Profile>>,
    /// The profile variant (empty for a codec-level trial).
    pub variant: String,
    pub(crate) check: Check,
    pub(crate) input: Arc<Input>,
    /// Why the trial is not run, when the backend does not claim it.
    pub skip: Option<String>,
    /// The known-differences entry covering the trial, if any.
    pub(crate) known: Option<Entry>,
}

impl Trial {
    /// What the trial asks, for this repository's benchmarks.
    #[cfg(feature = "cli")]
    #[doc(hidden)]
    pub fn input(&self) -> &Input {
        &self.input
    }

    /// `backend::instruction::case-id::variant`, `cross-vendor::backend::lowering::case-id::
    /// variant`, or for a protocol's codec `protocol::backend::protocol::case-id`: filtering on
    /// a prefix selects a backend, an instruction or a case across variants. The basis is not
    /// part of the name, so a name survives a change of basis.
    pub fn name(&self) -> String {
        match &self.check {
            Check::Native { instruction, case } => format!(
                "{}::{}::{}::{}",
                self.backend.name(),
                instruction.to_lowercase(),
                case.id,
                self.variant
            ),
            Check::CrossVendor { lowering, case } => format!(
                "cross-vendor::{}::{}::{}::{}",
                self.backend.name(),
                lowering.name,
                case.id,
                self.variant
            ),
            Check::Codec { case } => match &case.protocol {
                Some(from) => format!(
                    "protocol::{}::{}::{}",
                    self.backend.name(),
                    from.protocol,
                    case.id
                ),
                None => format!("cross-vendor::{}::codec::{}", self.backend.name(), case.id),
            },
        }
    }

    /// The memory before the trial under a fill, in the units of its profile's memory.
    pub fn image(&self, fill: Fill) -> Image {
        let unit = self.profile.as_ref().map_or(Unit::Word, |p| p.unit);
        Image::of_units(self.input.before.clone(), fill, unit)
    }

    /// The id of the case the trial checks.
    pub fn case_id(&self) -> &str {
        match &self.check {
            Check::Native { case, .. } => &case.id,
            Check::CrossVendor { case, .. } | Check::Codec { case } => &case.id,
        }
    }

    /// The case's basis for this trial (a lowering's `except` entry can make it unspecified).
    pub fn basis(&self) -> Basis {
        match &self.check {
            Check::Native { case, .. } => case.basis,
            Check::CrossVendor { case, lowering } => case.basis_for(&lowering.key),
            Check::Codec { case } => case.basis,
        }
    }

    /// Where the trial's case is written.
    pub fn location(&self) -> &Location {
        match &self.check {
            Check::Native { case, .. } => &case.location,
            Check::CrossVendor { case, .. } | Check::Codec { case } => &case.location,
        }
    }

    /// What the trial's case cites for its expectation.
    pub fn citation(&self) -> &Citation {
        match &self.check {
            Check::Native { case, .. } => &case.citation,
            Check::CrossVendor { case, .. } | Check::Codec { case } => &case.citation,
        }
    }

    /// What a known-differences entry and a report name the check by: the instruction of a
    /// native case, the lowering of a cross-vendor one.
    pub fn check_name(&self) -> &str {
        match &self.check {
            Check::Native { instruction, .. } => instruction,
            Check::CrossVendor { lowering, .. } => &lowering.name,
            Check::Codec { .. } => "codec",
        }
    }

    /// Whether the trial asks a cross-vendor question (through a lowering or of a codec).
    pub fn is_cross_vendor(&self) -> bool {
        matches!(self.check, Check::CrossVendor { .. } | Check::Codec { .. })
    }

    /// The cross-vendor case a trial asks, if it asks one.
    pub fn cross_vendor_case(&self) -> Option<&Arc<CrossVendorCase>> {
        match &self.check {
            Check::Native { .. } => None,
            Check::CrossVendor { case, .. } | Check::Codec { case } => Some(case),
        }
    }

    /// Why the outcome of this trial can be told before it runs: skipped, recorded only
    /// (`unspecified`), or a listed known difference. A test runner shows such a trial as
    /// ignored; it still runs when asked, and a known difference that conforms then fails as a
    /// stale entry.
    pub fn ignored_because(&self) -> Option<String> {
        if let Some(skip) = &self.skip {
            return Some(skip.clone());
        }
        if self.basis() == Basis::Unspecified {
            return Some("unspecified: what the backend does is recorded, never judged".into());
        }
        self.known
            .as_ref()
            .map(|e| format!("known difference ({}): {}", e.location, e.reason))
    }
}

/// Every trial of the corpus on the given backends, in corpus order: native cases first, then
/// cross-vendor ones. A native case runs on a backend when the backend implements one of the
/// case's profiles, on every variant the case allows and as every instruction of its file; a
/// cross-vendor case runs through every lowering of its operation in the backend's profile.
pub(crate) fn plan(
    corpus: &Corpus,
    profiles: &Profiles,
    backends: &[Arc<dyn Backend>],
    known: &BTreeMap<String, KnownDifferences>,
) -> Vec<Trial> {
    let mut trials = Vec::new();
    for backend in backends.iter().filter(|b| b.codec().is_none()) {
        let Some(profile) = profiles.get(backend.profile()) else {
            continue;
        };
        let list = known.get(backend.name());
        for case in &corpus.cases {
            if !case.profiles.iter().any(|p| *p == profile.id) {
                continue;
            }
            for instruction in case.instructions.iter() {
                let input = Arc::new(Input {
                    instruction: instruction.clone(),
                    flags: case.flags.clone(),
                    operands: case.operands.clone(),
                    indirect: case.indirect.clone(),
                    before: case.before.clone(),
                });
                for variant in profile.variants.iter().filter(|v| case.runs_on(&v.id)) {
                    trials.push(trial(
                        backend,
                        profile,
                        &variant.id,
                        Check::Native {
                            instruction: instruction.clone(),
                            case: case.clone(),
                        },
                        input.clone(),
                        list,
                    ));
                }
            }
        }
    }
    for backend in backends {
        let list = known.get(backend.name());
        if let Some(abilities) = backend.codec() {
            // A protocol's codec is judged by its protocol's cases, and by the cross-vendor
            // (instruction) view only when it asks; a codec of no protocol by the latter.
            let protocol = abilities.protocol.as_ref();
            let fields = (corpus.protocol_fields.iter()).filter(|c| {
                protocol.is_some_and(|p| c.protocol.as_ref().is_some_and(|f| f.protocol == p.id))
            });
            let cross_vendor =
                (corpus.cross_vendor.iter()).filter(|_| abilities.takes_cross_vendor());
            for case in fields.chain(cross_vendor) {
                let mut t = Trial {
                    backend: backend.clone(),
                    profile: None,
                    variant: String::new(),
                    check: Check::Codec { case: case.clone() },
                    input: Arc::new(Input::default()),
                    skip: None,
                    known: None,
                };
                t.skip = skip_reason(&t, backend.as_ref());
                t.known = list.and_then(|k| {
                    k.covering(&Subject {
                        case: &case.id,
                        text: Some(&case.text),
                        instruction: "codec",
                        variant: "",
                    })
                });
                trials.push(t);
            }
            continue;
        }
        let Some(profile) = profiles.get(backend.profile()) else {
            continue;
        };
        for case in &corpus.cross_vendor {
            for lowering in profile
                .cross_vendor
                .lowerings
                .iter()
                .filter(|l| l.operation == case.operation)
            {
                let input = Arc::new(lowering::input(lowering, case));
                trials.push(trial(
                    backend,
                    profile,
                    &lowering.variant,
                    Check::CrossVendor {
                        lowering: lowering.clone(),
                        case: case.clone(),
                    },
                    input,
                    list,
                ));
            }
        }
    }
    trials
}

fn trial(
    backend: &Arc<dyn Backend>,
    profile: &Arc<Profile>,
    variant: &str,
    check: Check,
    input: Arc<Input>,
    known: Option<&KnownDifferences>,
) -> Trial {
    let mut t = Trial {
        backend: backend.clone(),
        profile: Some(profile.clone()),
        variant: variant.to_string(),
        check,
        input,
        skip: None,
        known: None,
    };
    t.skip = skip_reason(&t, backend.as_ref());
    let text = match &t.check {
        Check::CrossVendor { case, .. } | Check::Codec { case } => Some(case.text.as_slice()),
        Check::Native { .. } => None,
    };
    t.known = known.and_then(|k| {
        k.covering(&Subject {
            case: t.case_id(),
            text,
            instruction: t.check_name(),
            variant: &t.variant,
        })
    });
    t
}

/// Why a backend does not run an instruction input on a variant: it does not claim the
/// instruction there, or declines the setting (a flag value, an operand form). The rule every
/// planner asks: the corpus plan, the sweep's columns and its direct path.
pub(crate) fn declined(
    backend: &dyn Backend,
    profile: &Profile,
    variant: &str,
    input: &Input,
) -> Option<String> {
    let instruction = &input.instruction;
    if !backend.claims(instruction, variant) {
        return Some(format!(
            "{} does not implement {instruction} on {variant}",
            backend.name(),
        ));
    }
    backend.declines(&Setting {
        instruction,
        variant: profile.variant(variant)?,
        flags: &input.flags,
        operands: &input.operands,
        indirect: &input.indirect,
    })
}

/// Why a backend does not answer a cross-vendor case at the codec level.
pub(crate) fn codec_declined(backend: &dyn Backend, case: &CrossVendorCase) -> Option<String> {
    match backend.codec() {
        Some(abilities) => abilities
            .declines(case)
            .map(|why| format!("{} {why}", backend.name())),
        None => Some(format!("{} is not a codec-level backend", backend.name())),
    }
}

/// Why a backend will not run a trial, if it will not: it does not claim the instruction on the
/// variant, declines the setting (a flag value, an operand form), or does not check device
/// ranges and the trial expects a device-range error.
pub(crate) fn skip_reason(t: &Trial, backend: &dyn Backend) -> Option<String> {
    if let Check::Codec { case } = &t.check {
        return codec_declined(backend, case);
    }
    let profile = t.profile.as_ref()?;
    if let Some(why) = declined(backend, profile, &t.variant, &t.input) {
        return Some(why);
    }
    let expects_range_error = match &t.check {
        Check::Native { case, .. } => case
            .expect
            .as_ref()
            .and_then(|e| e.error.as_ref())
            .is_some_and(|e| {
                profile.cross_vendor.classify(e) == Answer::Error(ErrorClass::DeviceRange)
            }),
        Check::CrossVendor { case, lowering } => {
            case.expected_for(&lowering.key) == Some(&Answer::Error(ErrorClass::DeviceRange))
        }
        Check::Codec { .. } => false,
    };
    (expects_range_error && !backend.checks_device_ranges()).then(|| {
        format!(
            "{} does not check device ranges, and the case expects a device-range error",
            backend.name()
        )
    })
}
