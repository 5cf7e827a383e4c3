//! A validated vendor profile: what the backends and the planner read at run time.
//!
//! Everything a profile writes as a string that means something — the error flag and register,
//! the error classes of the cross-vendor section, the lowerings' operands — is parsed when the
//! profile is loaded, so nothing is re-parsed (or guessed) while trials run. The plain data
//! (device ranges, instruction operand lists, variants) is the same as on disk.

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use super::cross_vendor::CrossVendorSection;
use super::ErrorSignal;
use crate::device::{code_matches, Device, DeviceSyntaxError};
use crate::memory::Unit;
pub use crate::spec::profile::Variant;
pub(crate) use crate::spec::profile::{Bench, LinkKind, ModbusRange, ProgramForm};
pub(crate) use crate::spec::profile::{
    CallBasis, DeviceDef, FlagDef, InstructionDef, Manual, Numbering, SignalKind,
};
pub(crate) use crate::spec::profile::{DeviceRange, DeviceRanges};

/// A vendor family as its profile (`vendors/<id>.yaml`) describes it: its manuals and what
/// each covers, devices and their ranges, instructions and their operands, error signalling,
/// variants (CPU models and firmware), and how it answers the cross-vendor operations. What a
/// request carries so that an emulator can read the family's rules instead of hard-coding them.
#[derive(Debug, Clone)]
pub struct Profile {
    /// The id vectors name in `profiles:`, e.g. `mitsubishi-iqr`.
    pub id: String,
    /// The vendor's name for the family.
    pub name: String,
    /// The short name used for its reference backend and cross-vendor columns, e.g. `iqr`.
    pub short: String,
    pub(crate) manuals: BTreeMap<String, Manual>,
    pub(crate) errors: ErrorSignalling,
    pub(crate) flags: BTreeMap<String, FlagDef>,
    /// What one device holds: a byte or a word.
    pub unit: Unit,
    pub(crate) devices: DeviceTable,
    pub(crate) instructions: BTreeMap<String, InstructionDef>,
    /// The CPU models and firmware the profile describes; each runs its own trials.
    pub variants: Vec<Variant>,
    /// How the profile answers the cross-vendor operations (empty when it does not).
    pub(crate) cross_vendor: CrossVendorSection,
    /// The structured-text call of each instruction a program on the CPU writes, by
    /// instruction.
    pub(crate) calls: BTreeMap<String, CallForm>,
    /// How a bench runs the corpus on one of the family's CPUs, if it can.
    pub(crate) bench: Option<Bench>,
}

/// An instruction's structured-text call, read from the form the manual prints
/// (`ENO:=ASCI(EN,s,n,d);`): the one place the live CPU's program takes its operand order from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CallForm {
    pub instruction: String,
    /// The operand names after `EN`, in the manual's order.
    pub operands: Vec<String>,
    pub basis: CallBasis,
    /// The quoted page, or the reasoning of an inferred form.
    pub source: String,
}

impl CallForm {
    /// Reads `ENO:=NAME(EN,a,b,...);` (blanks allowed between the parts). `Err` says what is
    /// wrong with the form.
    pub(crate) fn parse(
        form: &str,
        basis: CallBasis,
        source: &str,
    ) -> Result<CallForm, CallFormError> {
        let compact: String = form.chars().filter(|c| !c.is_whitespace()).collect();
        let error = |enable_first| CallFormError {
            form: form.to_string(),
            enable_first,
        };
        let call = compact
            .strip_prefix("ENO:=")
            .and_then(|c| c.strip_suffix(");"))
            .ok_or_else(|| error(false))?;
        let (instruction, arguments) = call.split_once('(').ok_or_else(|| error(false))?;
        let mut names = arguments.split(',');
        if names.next() != Some("EN") {
            return Err(error(true));
        }
        let operands: Vec<String> = names.map(str::to_string).collect();
        if instruction.is_empty() || operands.iter().any(String::is_empty) {
            return Err(error(false));
        }
        Ok(CallForm {
            instruction: instruction.to_string(),
            operands,
            basis,
            source: source.to_string(),
        })
    }

    /// The call with the enable and each operand's text in the form's order, as a statement:
    /// `ENO := ASCI(enable, D100, 4, D200);` with `eno` for ENO. `None` when `operands` does
    /// not name exactly the form's operands.
    pub(crate) fn render(
        &self,
        eno: &str,
        enable: &str,
        operands: &BTreeMap<String, String>,
    ) -> Option<String> {
        if operands.len() != self.operands.len() {
            return None;
        }
        let mut args = vec![enable.to_string()];
        for name in &self.operands {
            args.push(operands.get(name)?.clone());
        }
        Some(format!(
            "{eno} := {}({});",
            self.instruction,
            args.join(", ")
        ))
    }
}

/// A call form that is not `ENO:=NAME(EN,s,d);`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CallFormError {
    form: String,
    /// The enable is missing or not first.
    enable_first: bool,
}

impl fmt::Display for CallFormError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let shape = "a form is written `ENO:=NAME(EN,s,d);`";
        match self.enable_first {
            true => write!(f, "`{}`: the enable `EN` comes first; {shape}", self.form),
            false => write!(f, "`{}`: {shape}", self.form),
        }
    }
}

impl std::error::Error for CallFormError {}

/// A profile's device codes, looked up by the code a device has: an entry is a code (`D`) or a
/// pattern with `#` for a block number (`DB#.DBB`, see [`code_matches`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct DeviceTable {
    defs: BTreeMap<String, DeviceDef>,
}

impl DeviceTable {
    pub(crate) fn new(defs: BTreeMap<String, DeviceDef>) -> Self {
        DeviceTable { defs }
    }

    /// The entry that names `code`, and its key.
    pub(crate) fn entry(&self, code: &str) -> Option<(&str, &DeviceDef)> {
        if let Some((key, def)) = self.defs.get_key_value(code) {
            return Some((key, def));
        }
        self.defs
            .iter()
            .find(|(key, _)| key.contains('#') && code_matches(key, code))
            .map(|(key, def)| (key.as_str(), def))
    }

    pub(crate) fn get(&self, code: &str) -> Option<&DeviceDef> {
        self.entry(code).map(|(_, def)| def)
    }

    /// Whether the code's numbers are hexadecimal (MELSEC W, SW).
    pub(crate) fn is_hexadecimal(&self, code: &str) -> bool {
        self.get(code)
            .is_some_and(|d| d.numbering == Numbering::Hexadecimal)
    }

    /// A device name read with this table's numbering (`W1A` is W 26 where W is hexadecimal).
    pub(crate) fn parse(&self, text: &str) -> Result<Device, DeviceSyntaxError> {
        Device::parse_numbered(text, |code| self.is_hexadecimal(code))
    }

    /// The codes numbered in hexadecimal, as the protocol tells an external backend.
    pub(crate) fn hexadecimal_codes(&self) -> Vec<String> {
        self.defs
            .iter()
            .filter(|(_, d)| d.numbering == Numbering::Hexadecimal)
            .map(|(code, _)| code.clone())
            .collect()
    }

    pub(crate) fn contains_key(&self, code: &str) -> bool {
        self.entry(code).is_some()
    }

    /// The codes and patterns, for messages.
    pub(crate) fn keys(&self) -> impl Iterator<Item = &String> {
        self.defs.keys()
    }
}

/// How an operation error becomes visible to a program, with its devices parsed.
#[derive(Debug, Clone)]
pub(crate) struct ErrorSignalling {
    pub signal: SignalKind,
    /// The flag an error turns on (MELSEC SM0, IDEC M8004); always there with `signal: flag`.
    pub flag: Option<Device>,
    /// The register holding the code (MELSEC SD0).
    pub register: Option<Device>,
    /// Where the code is returned when no register holds it (Siemens RET_VAL).
    pub returned: Option<String>,
    /// Further registers that receive the code (FX5: SD8067).
    pub also: Vec<Device>,
}

impl ErrorSignalling {
    /// Every register an operation error's code lands in: `register`, then `also`.
    pub(crate) fn code_registers(&self) -> Vec<Device> {
        self.register.iter().chain(&self.also).cloned().collect()
    }
}

impl Profile {
    /// A variant of this family by id (`rcpu`), if the profile has it.
    pub fn variant(&self, id: &str) -> Option<&Variant> {
        self.variants.iter().find(|v| v.id == id)
    }

    /// The ranges of a device code on a variant.
    pub(crate) fn ranges(&self, variant: &Variant, code: &str) -> Option<DeviceRanges> {
        let (key, def) = self.devices.entry(code)?;
        Some(
            variant
                .devices
                .get(key)
                .cloned()
                .unwrap_or_else(|| def.ranges()),
        )
    }

    /// Whether `count` consecutive word operands from `head` all exist on the variant: every
    /// point they take lies in one range (a span across a gap does not exist).
    pub fn words_exist(&self, variant: &Variant, head: &Device, count: u32) -> bool {
        words_exist(&self.devices, variant, head, count)
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

    /// A flag's default.
    pub fn flag_default(&self, flag: &str) -> bool {
        self.flags.get(flag).is_some_and(|f| f.default)
    }

    /// Why `name` is no flag of this profile, with the nearest one and the profile's flags.
    pub(crate) fn unknown_flag(&self, name: &str) -> String {
        let known = self.flags.keys().map(String::as_str);
        let hint = crate::nearest::nearest(name, known.clone())
            .map(|k| format!(" (did you mean `{k}`?)"))
            .unwrap_or_default();
        let listed: Vec<&str> = known.collect();
        format!(
            "`{name}` is no flag of profile {}{hint}; its flags are: {}",
            self.id,
            if listed.is_empty() {
                "none".to_string()
            } else {
                listed.join(", ")
            }
        )
    }

    /// A flag as the CPU of a variant sees it: the setting, or the profile default, except that
    /// a variant which does not implement the flag always sees the default. The one place this
    /// rule lives: the reference models, the external-backend capabilities and the reports all
    /// ask here.
    pub fn flag_seen(&self, variant: &Variant, set: &BTreeMap<String, bool>, flag: &str) -> bool {
        if variant.ignores_flags.iter().any(|f| f == flag) {
            return self.flag_default(flag);
        }
        set.get(flag)
            .copied()
            .unwrap_or_else(|| self.flag_default(flag))
    }

    /// Every flag an instruction reads, as set or defaulted (before the variant's view).
    pub fn flags_of(
        &self,
        instruction: &str,
        set: &BTreeMap<String, bool>,
    ) -> BTreeMap<String, bool> {
        self.instructions
            .get(instruction)
            .map(|def| {
                def.flags
                    .iter()
                    .map(|f| {
                        let on = set.get(f).copied().unwrap_or_else(|| self.flag_default(f));
                        (f.clone(), on)
                    })
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The signal for an operation error with the vendor's code. For a profile that signals
    /// with a flag only, the code is not visible and the flag is what the program sees.
    pub fn error(&self, code: u16) -> ErrorSignal {
        match self.errors.signal {
            SignalKind::Code => ErrorSignal::Code(code),
            SignalKind::Flag => match &self.errors.flag {
                Some(flag) => ErrorSignal::Flag(flag.clone()),
                // The loader requires the flag of a flag-signalling profile.
                None => ErrorSignal::Code(code),
            },
        }
    }
}

/// [`Profile::words_exist`] over a profile's device table, for the loader, which checks a
/// profile before it is one.
pub(crate) fn words_exist(
    devices: &DeviceTable,
    variant: &Variant,
    head: &Device,
    count: u32,
) -> bool {
    let Some((key, def)) = devices.entry(head.code()) else {
        return false;
    };
    let Some(first) = def.numbering.point(head.index) else {
        return false;
    };
    if count == 0 {
        return true;
    }
    let last = first + u64::from(count) * u64::from(def.points_per_word.max(1)) - 1;
    let holds = |r: DeviceRange| match (def.numbering.point(r.first), def.numbering.point(r.last)) {
        (Some(lo), Some(hi)) => lo <= first && last <= hi,
        _ => false,
    };
    // Asked for every operand of every execution: the ranges are read where they are, not
    // copied.
    match variant.devices.get(key) {
        Some(ranges) => ranges.iter().any(holds),
        None => def.iter_ranges().any(holds),
    }
}

/// The loaded profiles, by id.
#[derive(Debug, Clone, Default)]
pub struct Profiles {
    by_id: BTreeMap<String, Arc<Profile>>,
    /// The protocol profiles found beside them (`vendors/protocols/`).
    pub protocols: super::protocol::Protocols,
}

impl Profiles {
    pub fn new(profiles: impl IntoIterator<Item = Profile>) -> Self {
        Profiles {
            by_id: profiles
                .into_iter()
                .map(|p| (p.id.clone(), Arc::new(p)))
                .collect(),
            protocols: Default::default(),
        }
    }
    pub fn get(&self, id: &str) -> Option<&Arc<Profile>> {
        self.by_id.get(id)
    }
    pub fn iter(&self) -> impl Iterator<Item = &Arc<Profile>> {
        self.by_id.values()
    }
    pub fn ids(&self) -> Vec<String> {
        self.by_id.keys().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn an_unknown_flag_is_named_with_the_nearest_one_and_the_profile_s_flags() {
        let session = crate::test_support::session();
        let fx5 = session.profiles.get("mitsubishi-fx5").expect("fx5");
        let why = fx5.unknown_flag("SM7O1");
        assert!(
            why.contains("`SM7O1` is no flag of profile mitsubishi-fx5"),
            "{why}"
        );
        assert!(why.contains("did you mean `SM701`?"), "{why}");
        assert!(why.contains("its flags are: "), "{why}");
    }
}
