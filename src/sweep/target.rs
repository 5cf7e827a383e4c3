//! What a sweep asks and of whom: the target (a cross-vendor operation or one instruction of a
//! profile), its columns (each backend through each lowering, or on each variant), and how one
//! generated [`Point`] becomes the pipeline's [`Trial`] for a column.
//!
//! Nothing here decides an answer: a point becomes a `unspecified` case (cross-vendor or
//! native) without an expectation, the plan's own lowering turns it into memory and operands,
//! and the judge records what the backend did.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use serde::Serialize;

use super::input::{Data, Point};
use super::SweepError;
use crate::backend::Backend;
use crate::device::Device;
use crate::model::cross_vendor::{
    CrossVendorCase, Lowering, Operation, OperationAbilities, TextLayout, ValueOrder,
};
use crate::model::profile::{Profile, Profiles};
use crate::model::{Basis, Case, Citation, Indirect, Location, Operand};
use crate::plan::lowering::value_memory;
use crate::plan::{codec_declined, declined, lowered_input, Check, Input, Trial};

/// What a sweep generates inputs for.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Target {
    /// A cross-vendor operation, through every lowering of every backend (and codecs).
    Operation { operation: Operation },
    /// One instruction of a profile, on every variant of every backend of that profile.
    Instruction {
        profile: String,
        instruction: String,
    },
}

impl Target {
    /// Whether the target reads text (hex-to-value) or a value (value-to-hex).
    pub fn reads(&self, shape: Option<&Shape>) -> Operation {
        match (self, shape) {
            (Target::Operation { operation }, _) => *operation,
            (Target::Instruction { .. }, Some(s)) => s.reads,
            (Target::Instruction { .. }, None) => Operation::HexToValue,
        }
    }
}

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Operation { operation } => write!(f, "{operation}"),
            Target::Instruction {
                profile,
                instruction,
            } => write!(f, "{instruction} ({profile})"),
        }
    }
}

/// How a column asks its question.
#[derive(Debug, Clone)]
pub enum Ask {
    /// A cross-vendor case through one of the profile's lowerings.
    Lowering(Arc<Lowering>),
    /// A cross-vendor case asked of a codec-level backend.
    Codec,
    /// The instruction itself, on one variant.
    Instruction,
}

/// What a codec-level column of an operation sweep is judged against.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Oracle {
    /// The built-in reading the codec declares (`reading` in its capabilities), if any.
    #[default]
    Declared,
    /// A built-in reading by its column name (`fx5/hexa-16bit`).
    Named(String),
    /// None: every column side by side, none judged.
    None,
}

/// One backend asked one way: a column of the sweep's results.
#[derive(Clone)]
pub struct Column {
    /// `iqr/habin-fixed`, `pymcprotocol/habin-fixed`, `pymcprotocol@rcpu`, `aslmp`.
    pub name: String,
    pub backend: Arc<dyn Backend>,
    pub profile: Option<Arc<Profile>>,
    pub variant: String,
    pub ask: Ask,
    /// The column whose answer this one is judged against: the profile's reference model asked
    /// the same way. `None` for the reference model itself and for codecs.
    pub oracle: Option<usize>,
    /// A built-in reference model: run in process, point by point, without batching.
    pub in_process: bool,
    /// Why the backend does not run this lowering, if it does not.
    pub lowering_skip: Option<String>,
    /// A codec's field for the swept operation: its answers are compared with what the field
    /// would give for the oracle's (no leading zeros, the low byte first).
    pub field: Option<(Operation, OperationAbilities)>,
}

impl std::fmt::Debug for Column {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Column").field("name", &self.name).finish()
    }
}

/// What the sweep knows about an instruction, read from the profile's lowerings of it: which
/// operand holds the input, which the result, which the count, how text is laid out under
/// which flags, and how wide the data is. A pulse form (`HABINP`) shares its base's lowerings,
/// a 32-bit form (`DHABIN`) doubles their width.
#[derive(Debug, Clone)]
pub struct Shape {
    pub profile: Arc<Profile>,
    pub instruction: String,
    pub reads: Operation,
    pub source: String,
    pub destination: String,
    pub count: Option<String>,
    pub operands: BTreeMap<String, Operand>,
    /// Text layouts by the flags that select them, the first the default.
    pub layouts: Vec<(BTreeMap<String, bool>, TextLayout)>,
    /// The digits handled when the instruction takes no count.
    pub width: Option<u32>,
    /// Words of binary data (1, or 2 for a 32-bit form).
    pub words: u32,
    /// The order of a value's units in memory.
    pub order: ValueOrder,
    /// The flags the instruction reads.
    pub flags: Vec<String>,
}

impl Shape {
    pub fn of(profile: &Arc<Profile>, instruction: &str) -> Result<Shape, SweepError> {
        let def = profile.instructions.get(instruction).ok_or_else(|| {
            SweepError(format!(
                "{} has no instruction {instruction}; it has {}",
                profile.id,
                profile
                    .instructions
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let base = |l: &Lowering| -> Option<bool> {
            let name = instruction;
            let same = |n: &str| n == l.instruction || n == format!("{}P", l.instruction);
            if same(name) {
                Some(false)
            } else {
                name.strip_prefix('D').filter(|n| same(n)).map(|_| true)
            }
        };
        let matching: Vec<(&Arc<Lowering>, bool)> = profile
            .cross_vendor
            .lowerings
            .iter()
            .filter_map(|l| base(l).map(|double| (l, double)))
            .collect();
        let Some(&(first, double)) = matching.first() else {
            return Err(SweepError(format!(
                "no lowering of {} describes {instruction}'s operands (its `neutral` section): a \
                 sweep needs one to know where the input and the result are",
                profile.id
            )));
        };
        Ok(Shape {
            profile: profile.clone(),
            instruction: instruction.to_string(),
            reads: first.operation,
            source: first.lowering_operand(&first.source),
            destination: first.lowering_operand(&first.destination),
            count: first.count.clone(),
            operands: first.operands.clone(),
            layouts: matching
                .iter()
                .map(|(l, _)| (l.flags.clone(), l.text))
                .collect(),
            width: first.width.map(|w| if double { w * 2 } else { w }),
            words: if double { 2 } else { 1 },
            order: first.order,
            flags: def.flags.clone(),
        })
    }

    /// The text layout under these flags: the lowering whose flags they match.
    pub fn layout(&self, flags: &BTreeMap<String, bool>) -> TextLayout {
        self.layouts
            .iter()
            .find(|(set, _)| set.iter().all(|(f, on)| flags.get(f) == Some(on)))
            .or(self.layouts.first())
            .map_or(TextLayout::Packed, |(_, t)| *t)
    }

    /// The default device of an operand.
    pub fn device(&self, operand: &str) -> Option<&Device> {
        match self.operands.get(operand) {
            Some(Operand::Device(d)) => Some(d),
            _ => None,
        }
    }

    /// The instruction input for a point.
    pub fn input(&self, point: &Point) -> Input {
        let mut operands = self.operands.clone();
        let source = point
            .source
            .clone()
            .or_else(|| self.device(&self.source).cloned())
            .unwrap_or_else(|| Device::new("D", 100));
        if let Some(d) = &point.destination {
            operands.insert(self.destination.clone(), Operand::Device(d.clone()));
        }
        operands.insert(self.source.clone(), Operand::Device(source.clone()));
        if let Some(count) = &self.count {
            operands.insert(count.clone(), Operand::Constant(i64::from(point.digits)));
        }
        let unit = self.profile.unit;
        let words: Vec<crate::memory::Value> = match &point.data {
            Data::Text(t) => self.layout(&point.flags).units(unit, t),
            Data::Value(v) => value_memory(
                *v,
                point.digits,
                self.words * 16 / unit.bits(),
                unit,
                self.order,
            ),
        };
        let before = words
            .into_iter()
            .enumerate()
            .filter_map(|(i, w)| source.offset(i as u32).map(|d| (d, w)))
            .collect();
        Input {
            instruction: self.instruction.clone(),
            flags: point.flags.clone(),
            operands,
            indirect: Indirect::new(),
            before,
        }
    }
}

trait OperandName {
    fn lowering_operand(&self, head: &Device) -> String;
}

impl OperandName for Lowering {
    /// The operand name whose fixed device is `head` (`s` for D100).
    fn lowering_operand(&self, head: &Device) -> String {
        self.operands
            .iter()
            .find(|(_, o)| matches!(o, Operand::Device(d) if d == head))
            .map_or_else(|| "s".to_string(), |(name, _)| name.clone())
    }
}

/// Judges each codec column against a built-in reading: the one `oracle` names, or the one the
/// codec declares. A reading that is not a built-in column is an error that lists them.
fn codec_oracles(
    out: &mut [Column],
    operation: Operation,
    oracle: &Oracle,
) -> Result<(), SweepError> {
    let readings = (out.iter().filter(|c| c.in_process))
        .map(|c| c.name.clone())
        .collect::<Vec<_>>()
        .join(", ");
    // Named, the reading must exist whether or not a codec is swept: a typo judges nothing.
    if let Oracle::Named(name) = oracle {
        if !out.iter().any(|c| c.in_process && c.name == *name) {
            return Err(SweepError(format!(
                "--oracle `{name}` is not a built-in reading of {operation}; the readings are: \
                 {readings}"
            )));
        }
    }
    for i in 0..out.len() {
        if !matches!(out[i].ask, Ask::Codec) {
            continue;
        }
        let declared = out[i]
            .backend
            .codec()
            .and_then(|c| c.of(operation))
            .and_then(|a| a.reading.clone());
        let (name, from) = match (oracle, declared) {
            (Oracle::None, _) | (Oracle::Declared, None) => continue,
            (Oracle::Named(name), _) => (name.clone(), "--oracle"),
            (Oracle::Declared, Some(name)) => (name, "its capabilities (--oracle overrides)"),
        };
        let Some(j) = (0..out.len()).find(|&j| out[j].in_process && out[j].name == name) else {
            return Err(SweepError(format!(
                "{} is judged against `{name}` (from {from}), which is not a built-in reading of \
                 {operation}; the readings are: {}",
                out[i].name, readings
            )));
        };
        out[i].oracle = Some(j);
    }
    Ok(())
}

/// The columns of a sweep over `backends`. An instruction sweep runs every backend of the
/// profile on every variant it claims the instruction on; an operation sweep runs every lowering
/// of every backend's profile, and codecs directly. Each column that is not the profile's
/// reference model is judged against the reference model asked the same way, when that is among
/// the backends.
pub(crate) fn columns(
    target: &Target,
    profiles: &Profiles,
    backends: &[Arc<dyn Backend>],
    oracle: &Oracle,
) -> Result<Vec<Column>, SweepError> {
    let reference = |b: &Arc<dyn Backend>| {
        profiles
            .get(b.profile())
            .is_some_and(|p| p.short == b.name())
    };
    let mut out: Vec<Column> = Vec::new();
    for backend in backends {
        match target {
            Target::Operation { operation } => {
                if let Some(abilities) = backend.codec() {
                    let implemented = abilities.of(*operation).is_some();
                    if implemented {
                        out.push(Column {
                            name: backend.name().to_string(),
                            backend: backend.clone(),
                            profile: None,
                            variant: String::new(),
                            ask: Ask::Codec,
                            oracle: None,
                            in_process: false,
                            lowering_skip: None,
                            field: abilities.of(*operation).cloned().map(|a| (*operation, a)),
                        });
                    }
                    continue;
                }
                let Some(profile) = profiles.get(backend.profile()) else {
                    continue;
                };
                for l in profile
                    .cross_vendor
                    .lowerings
                    .iter()
                    .filter(|l| l.operation == *operation)
                {
                    out.push(Column {
                        name: format!("{}/{}", backend.name(), l.name),
                        backend: backend.clone(),
                        profile: Some(profile.clone()),
                        variant: l.variant.clone(),
                        ask: Ask::Lowering(l.clone()),
                        oracle: None,
                        in_process: reference(backend),
                        lowering_skip: lowering_skip(backend, profile, l),
                        field: None,
                    });
                }
            }
            Target::Instruction {
                profile: id,
                instruction,
            } => {
                if backend.profile() != id || backend.codec().is_some() {
                    continue;
                }
                let Some(profile) = profiles.get(id) else {
                    return Err(SweepError(format!("no profile {id}")));
                };
                for v in &profile.variants {
                    if backend.claims(instruction, &v.id) {
                        out.push(Column {
                            name: format!("{}@{}", backend.name(), v.id),
                            backend: backend.clone(),
                            profile: Some(profile.clone()),
                            variant: v.id.clone(),
                            ask: Ask::Instruction,
                            oracle: None,
                            in_process: reference(backend),
                            lowering_skip: None,
                            field: None,
                        });
                    }
                }
            }
        }
    }
    // Oracles: the reference model of the column's profile, asked the same way.
    let keys: Vec<(Option<String>, String, String)> = out
        .iter()
        .map(|c| {
            let how = match &c.ask {
                Ask::Lowering(l) => l.name.clone(),
                _ => String::new(),
            };
            (
                c.profile.as_ref().map(|p| p.id.clone()),
                how,
                c.variant.clone(),
            )
        })
        .collect();
    for i in 0..out.len() {
        if out[i].in_process || matches!(out[i].ask, Ask::Codec) {
            continue;
        }
        out[i].oracle = (0..out.len()).find(|&j| out[j].in_process && keys[j] == keys[i]);
    }
    if let Target::Operation { operation } = target {
        codec_oracles(&mut out, *operation, oracle)?;
    }
    if out.is_empty() {
        return Err(SweepError(format!(
            "no chosen backend answers {target}: check --backend (`plc-conformance list` shows \
             what exists)"
        )));
    }
    Ok(out)
}

/// Why a backend does not run a lowering: the plan's rule, with the lowering's instruction,
/// variant, flags and operands (fixed, so asked once per column).
fn lowering_skip(backend: &Arc<dyn Backend>, profile: &Profile, l: &Lowering) -> Option<String> {
    let input = Input {
        instruction: l.instruction.clone(),
        flags: l.flags.clone(),
        operands: l.operands.clone(),
        indirect: Indirect::new(),
        before: BTreeMap::new(),
    };
    declined(backend.as_ref(), profile, &l.variant, &input)
}

/// The sweep's cases for one point: shared by every column that asks it.
pub struct Cases {
    pub cross_vendor: Option<Arc<CrossVendorCase>>,
    pub native: Option<Arc<Case>>,
}

fn citation() -> Citation {
    Citation {
        manual: "sweep".into(),
        page: String::new(),
        text: None,
    }
}

fn location() -> Location {
    Location {
        file: PathBuf::new(),
        line: 0,
    }
}

/// The id of the point at `index` of a sweep.
pub(crate) fn case_id(index: u64) -> String {
    format!("sweep-{index}")
}

impl Cases {
    /// No case: for a column asked directly from the instruction input.
    pub fn none() -> Cases {
        Cases {
            cross_vendor: None,
            native: None,
        }
    }

    pub fn new(target: &Target, shape: Option<&Shape>, index: u64, point: &Point) -> Cases {
        let id = case_id(index);
        match (target, shape) {
            (Target::Instruction { .. }, Some(shape)) => {
                let input = shape.input(point);
                Cases {
                    cross_vendor: None,
                    native: Some(Arc::new(Case {
                        id,
                        basis: Basis::Unspecified,
                        citation: citation(),
                        location: location(),
                        instructions: Arc::from(vec![shape.instruction.clone()]),
                        profiles: Arc::from(vec![shape.profile.id.clone()]),
                        variants: None,
                        flags: input.flags,
                        operands: input.operands,
                        indirect: input.indirect,
                        before: input.before,
                        expect: None,
                        note: None,
                    })),
                }
            }
            _ => {
                let operation = target.reads(shape);
                let (text, value) = match &point.data {
                    Data::Text(t) => (t.clone(), 0),
                    Data::Value(v) => (Vec::new(), *v),
                };
                Cases {
                    cross_vendor: Some(Arc::new(CrossVendorCase {
                        id,
                        operation,
                        basis: Basis::Unspecified,
                        citation: citation(),
                        location: location(),
                        text,
                        value,
                        digits: point.digits,
                        expect: None,
                        except: BTreeMap::new(),
                        note: None,
                        protocol: None,
                    })),
                    native: None,
                }
            }
        }
    }

    /// The trial that asks this point of a column.
    pub fn trial(&self, column: &Column) -> Option<Trial> {
        let (check, input) = match (&column.ask, &self.cross_vendor, &self.native) {
            (Ask::Lowering(l), Some(case), _) => (
                Check::CrossVendor {
                    lowering: l.clone(),
                    case: case.clone(),
                },
                Arc::new(lowered_input(l, case)),
            ),
            (Ask::Codec, Some(case), _) => (
                Check::Codec { case: case.clone() },
                Arc::new(Input::default()),
            ),
            (Ask::Instruction, _, Some(case)) => (
                Check::Native {
                    instruction: case.instructions[0].clone(),
                    case: case.clone(),
                },
                Arc::new(Input {
                    instruction: case.instructions[0].clone(),
                    flags: case.flags.clone(),
                    operands: case.operands.clone(),
                    indirect: case.indirect.clone(),
                    before: case.before.clone(),
                }),
            ),
            _ => return None,
        };
        let skip = match (&check, &column.profile) {
            // A lowering's instruction, variant and flags are fixed: asked once per column.
            (Check::CrossVendor { .. }, _) => column.lowering_skip.clone(),
            (Check::Codec { case }, _) => codec_declined(column.backend.as_ref(), case),
            (_, Some(profile)) => {
                declined(column.backend.as_ref(), profile, &column.variant, &input)
            }
            _ => None,
        };
        Some(Trial {
            backend: column.backend.clone(),
            profile: column.profile.clone(),
            variant: column.variant.clone(),
            check,
            input,
            skip,
            known: None,
        })
    }
}
