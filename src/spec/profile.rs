//! Vendor profiles as written on disk: what a vendor varies, as data.
//!
//! A profile (one file in `vendors/`) lists the manuals the vectors cite, the device codes and
//! their ranges, how errors are signalled, the mode flags with their defaults, the instructions
//! with their operands, and the variants (CPU models, firmware generations) that differ in any of
//! these. Backends read these facts from here rather than from constants, so that a new model or
//! a configured device range is an edit to a YAML file.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::cross_vendor::CrossVendorSectionSpec;

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "plc-conformance vendor profile")]
pub(crate) struct ProfileSpec {
    /// The id vectors name in `profiles:`, e.g. `mitsubishi-iqr`.
    pub id: String,
    /// The vendor's name for the family.
    pub name: String,
    /// The short name used in trial names, e.g. `iqr`.
    pub short: String,
    /// The manuals vectors may cite, by id.
    pub manuals: BTreeMap<String, Manual>,
    /// How the CPU signals an operation error.
    pub errors: ErrorSignallingSpec,
    /// How characters are stored in words (for readers; the instructions' semantics say it too).
    pub text_layout: Option<String>,
    /// Mode flags the instructions read.
    #[serde(default)]
    pub flags: BTreeMap<String, FlagDef>,
    /// What one device holds: `word` (16 bits, MELSEC, IDEC, Panasonic, Omron, KEYENCE),
    /// `byte` (Siemens markers and data blocks, where `MB20` and `MB21` are neighbouring
    /// bytes) or `dword` (32 bits). Values, fills, text and diffs follow it.
    #[serde(default)]
    pub memory_unit: crate::memory::Unit,
    /// Device codes and their ranges, for every variant unless a variant overrides them. A
    /// code may hold `#` for a block number (`DB#.DBB`: the bytes of any data block).
    pub devices: BTreeMap<String, DeviceDef>,
    /// The instructions the profile covers.
    pub instructions: BTreeMap<String, InstructionDef>,
    /// The variants; every case runs on each one unless the case restricts it.
    pub variants: Vec<Variant>,
    /// How the profile answers the cross-vendor operations.
    pub cross_vendor: Option<CrossVendorSectionSpec>,
    /// The structured-text call of each instruction a program on the CPU writes (the
    /// instructions under test, and helpers such as ADRSET), as the manual prints it: the
    /// live CPU's test program writes every call with its operands in this order, and a
    /// program that passed (n) where the manual has (d) would convert the wrong words.
    #[serde(default)]
    pub structured_text: BTreeMap<String, CallFormSpec>,
    /// How a bench with one of the family's CPUs runs the corpus (`plc-conformance hil`): the
    /// link the PC reaches the CPU by, the form of the test program, and how the program
    /// resets the error flag. A family without it has no bench support.
    pub bench: Option<Bench>,
}

/// How a bench reaches a family's CPUs and what program they run.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct Bench {
    /// `slmp` (MELSEC SLMP, `slmp:` backends) or `modbus-tcp` (IDEC's Modbus TCP map,
    /// `modbus:` backends).
    pub link: LinkKind,
    /// `structured-text` (the calls of `structured_text`, for GX Works3) or `ladder` (a rung
    /// list entered by hand, for WindLDR).
    pub program: ProgramForm,
    /// The flag whose rising edge resets the error state (`SM50`), or the error flag itself
    /// where the program resets it directly (`M8004`, reset by `RST`).
    pub error_reset: String,
    /// The evidence for the reset: the manual page, or why it is inferred.
    pub source: String,
    /// For `modbus-tcp`: where the CPU's Modbus TCP server puts its devices.
    pub modbus: Option<ModbusMap>,
}

/// A CPU's Modbus map, as its communication manual gives it.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ModbusMap {
    /// Word devices as holding registers (read with function 03, written with 16, or 06 for a
    /// word alone).
    pub registers: Vec<ModbusRange>,
    /// Bit devices as coils (read with function 01; never written), counted in points of the
    /// device's numbering (M8000-M8317 with an octal last digit are 256 coils).
    pub coils: Vec<ModbusRange>,
    /// The register whose value names the CPU: what a backend's `confirm=` is compared with.
    pub identity: String,
    /// The relay that is on while the CPU runs.
    pub running: String,
    /// The manual pages the map comes from, and what is unconfirmed.
    pub source: String,
}

/// Devices `first` to `last` of one code at wire addresses `address` on.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ModbusRange {
    pub device: String,
    pub first: u32,
    pub last: u32,
    /// The wire address (0-based, as in the frame) of `first`.
    pub address: u16,
    /// The CPU's own words (special registers): a sandbox holds them only where named.
    #[serde(default)]
    pub special: bool,
}

/// The link a bench reaches a CPU by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
// `pub` for the bench's link settings, which only this repository's tests reach (`testing`).
#[allow(unnameable_types)]
pub enum LinkKind {
    Slmp,
    ModbusTcp,
}

impl std::fmt::Display for LinkKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinkKind::Slmp => "SLMP (`slmp:`)",
            LinkKind::ModbusTcp => "Modbus TCP (`modbus:`)",
        })
    }
}

/// The form of a bench's test program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum ProgramForm {
    StructuredText,
    Ladder,
}

/// One instruction's structured-text call and the evidence for its operand order.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct CallFormSpec {
    /// The call as the manual prints it, e.g. `ENO:=ASCI(EN,s,n,d);`: `ENO:=`, the
    /// instruction, `EN` first, then the operands by the names the instruction's operands have.
    pub form: String,
    /// `manual` where a quoted page prints this form, `inferred` where it is read from a
    /// neighbouring page or the family's convention (unconfirmed on a CPU).
    pub basis: CallBasis,
    /// For `manual`, the manual id and page with the quoted form; for `inferred`, the
    /// reasoning.
    pub source: String,
}

/// What a structured-text call form rests on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub(crate) enum CallBasis {
    Manual,
    Inferred,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct Manual {
    pub title: String,
    pub number: Option<String>,
    pub language: Option<String>,
    /// The variants whose own manual this is, said for every manual (`[]`: a manual of other
    /// CPUs, read for inferences only): a `manual` case citing it may run only on these, since
    /// what one CPU's page states is an inference for another CPU.
    pub covers: Vec<String>,
}

/// How an operation error becomes visible to a program.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct ErrorSignallingSpec {
    /// Whether a program sees an error code or only a flag.
    pub signal: SignalKind,
    /// The flag an error turns on (MELSEC SM0, IDEC M8004); required when `signal: flag`.
    pub flag: Option<String>,
    /// The register holding the code (MELSEC SD0); with `signal: code`, this or `returned`.
    pub register: Option<String>,
    /// Where the code is returned when no register holds it, in words (Siemens: the
    /// instruction's RET_VAL, with ENO FALSE).
    pub returned: Option<String>,
    /// Further registers that receive the code (FX5: SD8067 for FX compatibility).
    #[serde(default)]
    pub also: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub(crate) enum SignalKind {
    /// An error code stored in a register, compared by value.
    Code,
    /// A flag only (IDEC: special internal relay M8004); no code is relied on.
    Flag,
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct FlagDef {
    #[serde(default)]
    pub default: bool,
    pub description: String,
}

/// An inclusive range of device numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct DeviceRange {
    pub first: u32,
    pub last: u32,
}

impl DeviceRange {
    pub(crate) fn contains(&self, index: u32) -> bool {
        (self.first..=self.last).contains(&index)
    }
}

/// The numbers a device code has on one model: a range, plus further ranges when the numbers
/// have a gap (IDEC FC4A slim CPUs: D0-D1299 and D2000-D7999).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct DeviceRanges {
    pub first: u32,
    pub last: u32,
    /// Further ranges of the same code, past a gap.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<DeviceRange>,
}

impl DeviceRanges {
    /// Every range, the first one first.
    pub(crate) fn iter(&self) -> impl Iterator<Item = DeviceRange> + '_ {
        every_range(self.first, self.last, &self.also)
    }
}

/// The ranges of a code, the first one first.
fn every_range(
    first: u32,
    last: u32,
    also: &[DeviceRange],
) -> impl Iterator<Item = DeviceRange> + '_ {
    std::iter::once(DeviceRange { first, last }).chain(also.iter().copied())
}

/// How a device code's numbers are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum Numbering {
    /// Plain decimal numbers: D0, D1, ... D9, D10.
    #[default]
    Decimal,
    /// The last digit is octal and the digits before it decimal, as IDEC numbers inputs,
    /// outputs and internal relays: M0-M7, M10-M17, ..., M80-M87, ... M1270-M1277. M8 and M1278
    /// do not exist.
    OctalLastDigit,
    /// Hexadecimal numbers, as MELSEC numbers link registers: W0-W9, WA-WF, W10. A vector
    /// writes them so (`W1A`), and `(s)+1` of W9 is WA. Profile ranges give the values (a
    /// YAML integer such as `0x1FF`).
    Hexadecimal,
}

impl Numbering {
    /// The name profiles use.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Numbering::Decimal => "decimal",
            Numbering::OctalLastDigit => "octal-last-digit",
            Numbering::Hexadecimal => "hexadecimal",
        }
    }

    /// The rule in words, for messages about a number that breaks it.
    pub(crate) fn rule(self) -> &'static str {
        match self {
            Numbering::Decimal => "numbers are decimal",
            Numbering::OctalLastDigit => {
                "the last digit is octal (0-7), the digits before it decimal (M0-M7, M10-M17, ...)"
            }
            Numbering::Hexadecimal => "numbers are hexadecimal (W0-W9, WA-WF, W10, ...)",
        }
    }

    /// The position of a device number counted in points from 0, or `None` for a number the
    /// numbering does not have. Ranges and spans are compared in points, so that the 16 points
    /// from M1260 end at M1277 and those from M1270 run past it.
    pub(crate) fn point(self, number: u32) -> Option<u64> {
        match self {
            Numbering::Decimal | Numbering::Hexadecimal => Some(u64::from(number)),
            Numbering::OctalLastDigit => {
                (number % 10 < 8).then(|| u64::from(number / 10) * 8 + u64::from(number % 10))
            }
        }
    }

    /// The device number at a position counted in points from 0: the inverse of
    /// [`Numbering::point`].
    pub(crate) fn number(self, point: u64) -> Option<u32> {
        match self {
            Numbering::Decimal | Numbering::Hexadecimal => u32::try_from(point).ok(),
            Numbering::OctalLastDigit => u32::try_from(point / 8 * 10 + point % 8).ok(),
        }
    }
}

fn one_point() -> u32 {
    1
}

fn is_one_point(points: &u32) -> bool {
    *points == 1
}

/// A device code of a profile: its numbers, and how a word operand of it is made up.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct DeviceDef {
    pub first: u32,
    pub last: u32,
    /// Further ranges of the same code, past a gap.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<DeviceRange>,
    #[serde(default)]
    pub numbering: Numbering,
    /// How many numbers (points) one word operand takes from its head: 1 for a word device,
    /// 16 for a bit device used as a word (IDEC: "16 points are used"). The word is addressed
    /// by its head, and all its points must exist.
    #[serde(default = "one_point", skip_serializing_if = "is_one_point")]
    pub points_per_word: u32,
    /// What a word of this code is when an instruction reads or writes it, where that is not
    /// obvious (IDEC T/C: the preset value when written, the current value when read).
    pub meaning: Option<String>,
}

impl DeviceDef {
    /// Every range of the code, the first one first, as [`DeviceRanges::iter`] gives them.
    pub(crate) fn iter_ranges(&self) -> impl Iterator<Item = DeviceRange> + '_ {
        every_range(self.first, self.last, &self.also)
    }

    pub(crate) fn ranges(&self) -> DeviceRanges {
        DeviceRanges {
            first: self.first,
            last: self.last,
            also: self.also.clone(),
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct InstructionDef {
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
pub(crate) struct OperandDef {
    /// Device codes allowed for this operand.
    #[serde(default)]
    pub devices: Vec<String>,
    /// Whether a constant (`K4`, `H0ABC`) is allowed.
    #[serde(default)]
    pub constant: bool,
    /// The constants a program can give, where the manual allows fewer than any value (IDEC
    /// ATOH S2: 1-4): a vector with another constant describes a program that cannot exist,
    /// and takes the value from a register instead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constants: Option<ConstantRange>,
    /// A constant here is a length (characters or digits, FX5 ASCI's `n`, IDEC ATOH's S2), so
    /// the memory a case may touch reaches that many units past each device operand; a constant
    /// that is a value (IDEC HTOA's S1) reaches nothing.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub count: bool,
    /// Numbers a device code may have in this operand, where the manual allows fewer than the
    /// device has (IDEC ATOH D1: M0-M1277 only).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub limits: BTreeMap<String, DeviceRange>,
    /// Device codes that can hold the operand's address for indirect specification (`@D10`:
    /// the device whose address D10 and D11 hold, as ADRSET stores it). Empty when the
    /// manual's table does not allow it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub indirect: Vec<String>,
}

/// An inclusive range of constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstantRange {
    pub min: i64,
    pub max: i64,
}

impl ConstantRange {
    pub fn contains(&self, k: i64) -> bool {
        (self.min..=self.max).contains(&k)
    }
}

/// A CPU model or firmware of a family (`rcpu`, `fx5u`, `c200h`): its own device ranges, the
/// flags it ignores and the features it has, where the family's CPUs differ.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// The id cases and trial names use (`rcpu`, `fx5u`).
    pub id: String,
    /// What the variant is, for readers: the CPU models or firmware it stands for.
    pub description: String,
    /// Device ranges that differ from the profile's (numbering and word size stay the
    /// profile's).
    #[serde(default)]
    pub(crate) devices: BTreeMap<String, DeviceRanges>,
    /// Flags this variant does not implement: it behaves as if they held their default.
    #[serde(default)]
    pub ignores_flags: Vec<String>,
    /// The instructions this variant has; all of the profile's when absent.
    pub instructions: Option<Vec<String>>,
    /// Rules in which this variant's instructions differ from the rest of its family, by name,
    /// for the family's reference model to read (Omron C200H-series HEX: `lowercase-hex`,
    /// 61H-66H taken as digits). A manual states such a rule per CPU model, so which models
    /// have it is data in the profile, and adding a model is an edit to the profile.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub features: Vec<String>,
}

impl Variant {
    /// Whether the variant has a rule the profile names in its `features`.
    pub fn has_feature(&self, feature: &str) -> bool {
        self.features.iter().any(|f| f == feature)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octal_last_digit_counts_eight_points_per_ten() {
        let n = Numbering::OctalLastDigit;
        assert_eq!(n.point(0), Some(0));
        assert_eq!(n.point(7), Some(7));
        assert_eq!(n.point(8), None);
        assert_eq!(n.point(10), Some(8));
        assert_eq!(n.point(80), Some(64));
        assert_eq!(n.point(1277), Some(1023));
        assert_eq!(n.point(1278), None);
        assert_eq!(Numbering::Decimal.point(1278), Some(1278));
    }

    #[test]
    fn a_variant_names_its_features() {
        let v: Variant =
            serde_yaml::from_str("id: c200h\ndescription: d\nfeatures: [lowercase-hex]\n")
                .expect("a variant with features");
        assert!(v.has_feature("lowercase-hex"));
        assert!(!v.has_feature("lowercase"));
        let plain: Variant = serde_yaml::from_str("id: cs-cj\ndescription: d\n").expect("plain");
        assert!(plain.features.is_empty() && !plain.has_feature("lowercase-hex"));
    }

    #[test]
    fn ranges_list_the_first_range_first() {
        let r = DeviceRanges {
            first: 0,
            last: 1299,
            also: vec![DeviceRange {
                first: 2000,
                last: 7999,
            }],
        };
        let all: Vec<(u32, u32)> = r.iter().map(|r| (r.first, r.last)).collect();
        assert_eq!(all, vec![(0, 1299), (2000, 7999)]);
    }
}
