//! What a sweep is asked for, built once from a command's arguments (as ripgrep builds its
//! `HiArgs`), and turned here into the sweep itself: the target resolved against the profiles,
//! the generator chosen for what the target reads, every bound checked before an input is made.

use std::sync::Arc;

use super::generate::{Digits, Generator, BOUNDARIES};
use super::target::{Oracle, Shape, Target};
use super::{Settings, Sweep, SweepError};
use crate::backend::Backend;
use crate::model::cross_vendor::Operation;
use crate::model::profile::Profiles;

/// What is swept: an operation of every lowering and codec, or one instruction.
#[derive(Debug, Clone)]
pub(crate) enum Swept {
    Operation(Operation),
    /// An instruction, in the profile given, or the one profile that has it.
    Instruction {
        name: String,
        profile: Option<String>,
    },
}

/// Which generator, when one is named (the command line's `--generator` takes these names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub(crate) enum GeneratorChoice {
    /// Every 16-bit value.
    Values,
    /// 32-bit values: the lattice of digits 0, 1, 9, A, F and every boundary.
    Values32,
    /// Every text of length 1..--length over --alphabet.
    Text,
    /// --count random inputs from --seed.
    Random,
    /// All 2^32 texts of 4 bytes, by byte class (--each-text asks every text).
    Full,
}

/// A sweep as asked for.
#[derive(Debug, Clone)]
pub(crate) struct Request {
    pub swept: Swept,
    /// `None`: text for a target that reads text, values for the others.
    pub generator: Option<GeneratorChoice>,
    /// `None`: from the clock.
    pub seed: Option<u64>,
    pub count: u64,
    pub length: Option<u32>,
    /// `None`: the boundary bytes.
    pub alphabet: Option<Vec<u8>>,
    pub digits: Digits,
    pub each_text: bool,
    pub class_check: u64,
    pub shard: (u64, u64),
    /// `None`: the reading each codec declares; `none`: judge none; else a built-in reading.
    pub oracle: Option<String>,
    pub jobs: Option<usize>,
    pub shrink: usize,
}

/// The most random texts a class check asks: the whole 4-byte space.
pub(crate) const MAX_CLASS_CHECK: u64 = 1 << 32;

impl Request {
    /// The sweep of this request on `backends` (the reference models among them, the oracle),
    /// or why it cannot be made.
    pub(crate) fn sweep(
        &self,
        profiles: &Profiles,
        backends: &[Arc<dyn Backend>],
    ) -> Result<Sweep, SweepError> {
        let refused = |message: String| Err(SweepError(message));
        let target = self.target(profiles)?;
        let reads_text = match &target {
            Target::Operation { operation } => *operation == Operation::HexToValue,
            Target::Instruction {
                profile,
                instruction,
            } => profiles
                .get(profile)
                .and_then(|p| Shape::of(p, instruction).ok())
                .is_none_or(|s| s.reads == Operation::HexToValue),
        };
        let generator = match (self.generator, reads_text) {
            (Some(GeneratorChoice::Values), _) | (None, false) => Generator::Values { bits: 16 },
            (Some(GeneratorChoice::Values32), _) => Generator::Values { bits: 32 },
            (Some(GeneratorChoice::Text), _) | (None, true) => Generator::Text {
                alphabet: self.alphabet.clone().unwrap_or_else(|| BOUNDARIES.to_vec()),
                max_len: self.length.unwrap_or(4),
            },
            (Some(GeneratorChoice::Random), _) => Generator::Random {
                count: self.count,
                max_len: self.length.unwrap_or(8),
            },
            (Some(GeneratorChoice::Full), _) => Generator::Full {
                by_class: !self.each_text,
            },
        };
        if self.each_text && !matches!(generator, Generator::Full { .. }) {
            return refused("--each-text applies to --generator full".into());
        }
        if self.class_check > MAX_CLASS_CHECK {
            return refused(format!(
                "--class-check {}: at most {} random texts (2^32, the whole space)",
                self.class_check,
                super::render::thousands(MAX_CLASS_CHECK)
            ));
        }
        if self.oracle.is_some() && !matches!(self.swept, Swept::Operation(_)) {
            return refused(
                "--oracle applies to --operation: an instruction sweep judges each backend \
                 against its profile's reference model"
                    .into(),
            );
        }
        let seed = self.seed.unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_secs())
        });
        let mut settings = Settings::new(target, generator, seed);
        settings.digits = self.digits.clone();
        settings.shard = self.shard;
        settings.shrink = self.shrink;
        settings.class_check = self.class_check;
        settings.oracle = match self.oracle.as_deref() {
            None => Oracle::Declared,
            Some("none") => Oracle::None,
            Some(reading) => Oracle::Named(reading.to_string()),
        };
        if let Some(j) = self.jobs {
            settings.jobs = j.max(1);
        }
        let sweep = Sweep::new(settings, profiles, backends)?;
        // A space past 2^64 inputs cannot be numbered, let alone swept.
        if sweep.space.total() == u64::MAX {
            return refused(
                "the inputs asked for are more than 2^64: give a shorter --length, a smaller \
                 --alphabet or fewer --digits"
                    .into(),
            );
        }
        Ok(sweep)
    }

    /// The target: an instruction's profile is the one given, or the only one that has it.
    fn target(&self, profiles: &Profiles) -> Result<Target, SweepError> {
        let (name, profile) = match &self.swept {
            Swept::Operation(operation) => {
                return Ok(Target::Operation {
                    operation: *operation,
                })
            }
            Swept::Instruction { name, profile } => (name, profile),
        };
        let profile = match profile {
            Some(p) => p.clone(),
            None => {
                let having: Vec<String> = profiles
                    .iter()
                    .filter(|p| p.instructions.contains_key(name))
                    .map(|p| p.id.clone())
                    .collect();
                match having.as_slice() {
                    [one] => one.clone(),
                    [] => {
                        return Err(SweepError(format!(
                            "no profile has an instruction `{name}`"
                        )))
                    }
                    many => {
                        return Err(SweepError(format!(
                            "several profiles have {name} ({}): give --profile",
                            many.join(", ")
                        )))
                    }
                }
            }
        };
        Ok(Target::Instruction {
            profile,
            instruction: name.clone(),
        })
    }
}
