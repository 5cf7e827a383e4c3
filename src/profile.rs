//! Vendor profiles: what a vendor varies, as data.
//!
//! A profile (one file in `vendors/`) lists the manuals the vectors cite, the device codes and
//! their ranges, how errors are signalled, the mode flags with their defaults, the instructions
//! with their operands, and the variants (CPU models, firmware generations) that differ in any of
//! these. Backends read these facts from here rather than from constants, so that a new model or
//! a configured device range is an edit to a YAML file.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::device::Device;

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// The id vectors name in `profiles:`, e.g. `mitsubishi-iqr`.
    pub id: String,
    /// The vendor's name for the family.
    pub name: String,
    /// The short name used in trial names, e.g. `iqr`.
    pub short: String,
    /// The manuals vectors may cite, by id.
    pub manuals: BTreeMap<String, Manual>,
    /// How the CPU signals an operation error.
    pub errors: ErrorSignalling,
    /// How characters are stored in words (for readers; the instructions' semantics say it too).
    #[serde(default)]
    pub text_layout: Option<String>,
    /// Mode flags the instructions read.
    #[serde(default)]
    pub flags: BTreeMap<String, FlagDef>,
    /// Device codes and their ranges, for every variant unless a variant overrides them.
    pub devices: BTreeMap<String, DeviceRange>,
    /// The instructions the profile covers.
    pub instructions: BTreeMap<String, InstructionDef>,
    /// The variants; every case runs on each one unless the case restricts it.
    pub variants: Vec<Variant>,
    /// How the profile answers the cross-vendor operations.
    #[serde(default)]
    pub neutral: Option<crate::neutral::NeutralSection>,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Manual {
    pub title: String,
    #[serde(default)]
    pub number: Option<String>,
    #[serde(default)]
    pub language: Option<String>,
}

/// How an operation error becomes visible to a program.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ErrorSignalling {
    /// Whether a program sees an error code or only a flag.
    pub signal: SignalKind,
    /// The flag an error turns on (MELSEC SM0, IDEC M8004).
    pub flag: String,
    /// The register holding the code (MELSEC SD0); required when `signal: code`.
    #[serde(default)]
    pub register: Option<String>,
    /// Further registers that receive the code (FX5: SD8067 for FX compatibility).
    #[serde(default)]
    pub also: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum SignalKind {
    /// An error code stored in a register, compared by value.
    Code,
    /// A flag only (IDEC: special internal relay M8004); no code is relied on.
    Flag,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FlagDef {
    #[serde(default)]
    pub default: bool,
    pub description: String,
}

/// An inclusive range of device numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DeviceRange {
    pub first: u32,
    pub last: u32,
}

impl DeviceRange {
    pub fn contains(&self, index: u32) -> bool {
        (self.first..=self.last).contains(&index)
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InstructionDef {
    /// What the instruction does, in a line.
    pub summary: String,
    /// The operands by the names the manual gives them.
    pub operands: BTreeMap<String, OperandDef>,
    /// The mode flags it reads.
    #[serde(default)]
    pub flags: Vec<String>,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OperandDef {
    /// Device codes allowed for this operand.
    #[serde(default)]
    pub devices: Vec<String>,
    /// Whether a constant (`K4`, `H0ABC`) is allowed.
    #[serde(default)]
    pub constant: bool,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub id: String,
    pub description: String,
    /// Device ranges that differ from the profile's.
    #[serde(default)]
    pub devices: BTreeMap<String, DeviceRange>,
    /// Flags this variant does not implement: it behaves as if they held their default.
    #[serde(default)]
    pub ignores_flags: Vec<String>,
    /// The instructions this variant has; all of the profile's when absent.
    #[serde(default)]
    pub instructions: Option<Vec<String>>,
}

impl Profile {
    pub fn variant(&self, id: &str) -> Option<&Variant> {
        self.variants.iter().find(|v| v.id == id)
    }

    /// The range of a device code on a variant.
    pub fn range(&self, variant: &Variant, code: &str) -> Option<DeviceRange> {
        variant
            .devices
            .get(code)
            .or_else(|| self.devices.get(code))
            .copied()
    }

    /// Whether `count` consecutive words from `head` all exist on the variant.
    pub fn words_exist(&self, variant: &Variant, head: &Device, count: u32) -> bool {
        let Some(range) = self.range(variant, &head.code) else {
            return false;
        };
        count == 0
            || head
                .index
                .checked_add(count - 1)
                .is_some_and(|last| range.contains(head.index) && range.contains(last))
    }

    /// Whether any variant has this word; memory a vector sets must exist somewhere.
    pub fn word_exists_anywhere(&self, device: &Device) -> bool {
        self.variants.iter().any(|v| self.words_exist(v, device, 1))
    }

    /// Whether a variant has an instruction.
    pub fn has_instruction(&self, variant: &Variant, instruction: &str) -> bool {
        self.instructions.contains_key(instruction)
            && variant
                .instructions
                .as_ref()
                .is_none_or(|list| list.iter().any(|i| i == instruction))
    }
}

/// The JSON Schema (draft-07) of a vendor profile.
pub fn profile_schema() -> serde_json::Value {
    let generator = schemars::generate::SchemaSettings::draft07().into_generator();
    serde_json::to_value(generator.into_root_schema_for::<Profile>()).unwrap_or_default()
}

/// The loaded profiles, by id.
#[derive(Debug, Clone, Default)]
pub struct Profiles {
    by_id: BTreeMap<String, std::sync::Arc<Profile>>,
}

impl Profiles {
    pub fn new(profiles: impl IntoIterator<Item = Profile>) -> Self {
        Profiles {
            by_id: profiles
                .into_iter()
                .map(|p| (p.id.clone(), std::sync::Arc::new(p)))
                .collect(),
        }
    }
    pub fn get(&self, id: &str) -> Option<&std::sync::Arc<Profile>> {
        self.by_id.get(id)
    }
    pub fn iter(&self) -> impl Iterator<Item = &std::sync::Arc<Profile>> {
        self.by_id.values()
    }
    pub fn ids(&self) -> Vec<String> {
        self.by_id.keys().cloned().collect()
    }
}
