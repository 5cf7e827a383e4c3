//! Loading and checking vendor profiles.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::checks::unknown;
use super::{read_file, yaml_files, FileContext, LoadError, LoadErrorKind, LoadErrors};
use crate::model::profile::{CallForm, DeviceTable, ErrorSignalling, Profile, Profiles};
use crate::spec::profile::{CallBasis, DeviceDef, DeviceRanges, ProfileSpec, SignalKind};

/// Loads every profile in a folder.
pub fn load_profiles(dir: &Path) -> Result<Profiles, LoadErrors> {
    let mut errors = Vec::new();
    let mut profiles: Vec<Profile> = Vec::new();
    let mut protocols: Vec<crate::model::protocol::Protocol> = Vec::new();
    let files = yaml_files(dir).map_err(|e| LoadErrors(vec![e]))?;
    for file in files {
        let text = match read_file(&file) {
            Ok(t) => t,
            Err(e) => {
                errors.push(e);
                continue;
            }
        };
        // One context per file: its text checked, indexed and parsed once, whichever kind it is.
        let mut cx = FileContext::new(&file, &text, &mut errors);
        if super::protocols::is_protocol_profile(&cx.index) {
            if let Some(p) = super::protocols::parse_protocol(&text, &mut cx) {
                if protocols.iter().any(|q| q.id == p.id) {
                    cx.error(
                        "protocol",
                        LoadErrorKind::Invalid(format!(
                            "protocol id `{}` is also used by another protocol profile",
                            p.id
                        )),
                    );
                }
                protocols.push(p);
            }
            continue;
        }
        if let Some(profile) = read_profile(&text, &mut cx) {
            if let Some(other) = profiles.iter().find(|p| p.id == profile.id) {
                cx.error(
                    "id",
                    LoadErrorKind::Invalid(format!(
                        "profile id `{}` is also used by another profile ({})",
                        profile.id, other.name
                    )),
                );
            }
            profiles.push(profile);
        }
    }
    if profiles.is_empty() && errors.is_empty() {
        errors.push(LoadError {
            file: dir.to_path_buf(),
            line: None,
            key: None,
            kind: LoadErrorKind::Invalid("no vendor profile (*.yaml) found".into()).into(),
        });
    }
    if errors.is_empty() {
        let mut loaded = Profiles::new(profiles);
        loaded.protocols = crate::model::protocol::Protocols::new(protocols);
        Ok(loaded)
    } else {
        Err(LoadErrors(errors))
    }
}

/// Parses and checks one profile; problems go to `errors`.
#[cfg(test)]
pub(crate) fn parse_profile(
    file: &Path,
    text: &str,
    errors: &mut Vec<LoadError>,
) -> Option<Profile> {
    read_profile(text, &mut FileContext::new(file, text, errors))
}

/// Reads and checks one profile in its file's context.
fn read_profile(text: &str, cx: &mut FileContext<'_>) -> Option<Profile> {
    let before = cx.errors.len();
    let spec = super::parse_document::<ProfileSpec>(text, cx)?;
    // One table serves the checks and the profile, so every device name of the profile is
    // read with the same numbering.
    let devices = DeviceTable::new(spec.devices.clone());
    check_profile(&spec, &devices, cx);
    let cross_vendor = super::cross_vendor::read_section(&spec, &devices, cx);
    let calls = read_calls(&spec, cx);
    check_bench(&spec, &devices, cx);
    if cx.errors.len() != before {
        return None;
    }
    let device = |name: &str| devices.parse(name).ok();
    let errors = ErrorSignalling {
        signal: spec.errors.signal,
        flag: spec.errors.flag.as_deref().and_then(device),
        register: spec.errors.register.as_deref().and_then(device),
        returned: spec.errors.returned.clone(),
        also: spec.errors.also.iter().filter_map(|d| device(d)).collect(),
    };
    Some(Profile {
        id: spec.id,
        name: spec.name,
        short: spec.short,
        manuals: spec.manuals,
        errors,
        flags: spec.flags,
        unit: spec.memory_unit,
        devices,
        instructions: spec.instructions,
        variants: spec.variants,
        cross_vendor,
        calls,
        bench: spec.bench,
    })
}

/// The bench section: a Modbus TCP link needs its map, whose devices are the profile's codes
/// numbered as it numbers them, whose ranges are in order, and whose identity register and
/// running relay lie in the map.
fn check_bench(p: &ProfileSpec, table: &DeviceTable, cx: &mut FileContext<'_>) {
    let Some(bench) = &p.bench else {
        return;
    };
    if let Err(e) = table.parse(&bench.error_reset) {
        cx.error("bench.error_reset", LoadErrorKind::Device(e));
    }
    let map = match (&bench.link, &bench.modbus) {
        (crate::spec::profile::LinkKind::ModbusTcp, Some(map)) => map,
        (crate::spec::profile::LinkKind::ModbusTcp, None) => {
            cx.error(
                "bench",
                LoadErrorKind::Missing("modbus: a `modbus-tcp` link needs the CPU's Modbus map"),
            );
            return;
        }
        (_, Some(_)) => {
            cx.error(
                "bench.modbus",
                LoadErrorKind::Invalid("a Modbus map is for a `modbus-tcp` link".into()),
            );
            return;
        }
        (_, None) => return,
    };
    let mut check = |key: String, r: &crate::spec::profile::ModbusRange| -> bool {
        let Some(def) = table.get(&r.device) else {
            cx.error(
                format!("{key}.device"),
                LoadErrorKind::Invalid(format!(
                    "`{}` is not a device code of the profile",
                    r.device
                )),
            );
            return false;
        };
        let span = (def.numbering.point(r.first), def.numbering.point(r.last));
        let fits = match span {
            (Some(a), Some(b)) => a <= b && b - a + u64::from(r.address) <= 0xFFFF,
            _ => false,
        };
        if !fits {
            cx.error(
                key,
                LoadErrorKind::Invalid(format!(
                    "{}{}-{}{} at {}: the first must come before the last ({}) and the range \
                     end below wire address 65536",
                    r.device,
                    r.first,
                    r.device,
                    r.last,
                    r.address,
                    def.numbering.rule()
                )),
            );
        }
        fits
    };
    let registers_ok = (map.registers.iter().enumerate())
        .all(|(i, r)| check(format!("bench.modbus.registers[{i}]"), r));
    let coils_ok =
        (map.coils.iter().enumerate()).all(|(i, r)| check(format!("bench.modbus.coils[{i}]"), r));
    for (key, name, ranges, ok) in [
        ("identity", &map.identity, &map.registers, registers_ok),
        ("running", &map.running, &map.coils, coils_ok),
    ] {
        match table.parse(name) {
            Err(e) => cx.error(format!("bench.modbus.{key}"), LoadErrorKind::Device(e)),
            Ok(d)
                if ok
                    && !ranges
                        .iter()
                        .any(|r| r.device == d.code() && (r.first..=r.last).contains(&d.index)) =>
            {
                cx.error(
                    format!("bench.modbus.{key}"),
                    LoadErrorKind::Invalid(format!("{name} lies in none of the map's ranges")),
                )
            }
            Ok(_) => {}
        }
    }
}

/// The structured-text call table: each form read, named after its key, and holding exactly
/// the operands of the instruction it calls; a `manual` form cites one of the profile's manuals.
fn read_calls(p: &ProfileSpec, cx: &mut FileContext<'_>) -> BTreeMap<String, CallForm> {
    let mut calls = BTreeMap::new();
    for (name, spec) in &p.structured_text {
        let key = format!("structured_text.{name}");
        let form = match CallForm::parse(&spec.form, spec.basis, &spec.source) {
            Ok(form) => form,
            Err(why) => {
                cx.error(
                    format!("{key}.form"),
                    LoadErrorKind::Invalid(why.to_string()),
                );
                continue;
            }
        };
        if form.instruction != *name {
            cx.error(
                format!("{key}.form"),
                LoadErrorKind::Invalid(format!(
                    "the form calls {}, but it stands under {name}",
                    form.instruction
                )),
            );
            continue;
        }
        let mut sorted = form.operands.clone();
        sorted.sort();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            cx.error(
                format!("{key}.form"),
                LoadErrorKind::Invalid(format!("`{}` names an operand twice", spec.form)),
            );
            continue;
        }
        if let Some(def) = p.instructions.get(name) {
            let expected: Vec<String> = def.operands.keys().cloned().collect();
            if sorted != expected {
                cx.error(
                    format!("{key}.form"),
                    LoadErrorKind::Invalid(format!(
                        "`{}` names the operands {}, but {name} has {}",
                        spec.form,
                        form.operands.join(", "),
                        expected.join(", ")
                    )),
                );
                continue;
            }
        }
        let cites_a_manual = p
            .manuals
            .keys()
            .any(|id| spec.source.split_whitespace().next() == Some(id.as_str()));
        if spec.basis == CallBasis::Manual && !cites_a_manual {
            cx.error(
                format!("{key}.source"),
                LoadErrorKind::Invalid(format!(
                    "a `manual` form starts its source with the manual's id ({}) and page",
                    p.manuals.keys().cloned().collect::<Vec<_>>().join(", ")
                )),
            );
            continue;
        }
        calls.insert(name.clone(), form);
    }
    calls
}

fn check_profile(p: &ProfileSpec, table: &DeviceTable, cx: &mut FileContext<'_>) {
    let flags: Vec<String> = p.flags.keys().cloned().collect();
    let devices: Vec<String> = p.devices.keys().cloned().collect();
    let instructions: Vec<String> = p.instructions.keys().cloned().collect();
    let device_names = |key: &str, name: &str, cx: &mut FileContext<'_>| {
        if let Err(e) = table.parse(name) {
            cx.error(key, LoadErrorKind::Device(e));
        }
    };
    let e = &p.errors;
    if let Some(f) = &e.flag {
        device_names("errors.flag", f, cx);
    } else if e.signal == SignalKind::Flag {
        cx.error(
            "errors",
            LoadErrorKind::Missing("flag: `signal: flag` needs the flag an error turns on"),
        );
    }
    if let Some(r) = &e.register {
        device_names("errors.register", r, cx);
    } else if e.signal == SignalKind::Code && e.returned.is_none() {
        cx.error(
            "errors",
            LoadErrorKind::Missing(
                "register: `signal: code` needs the register holding the code (or `returned`, \
                 where the instruction returns it)",
            ),
        );
    }
    for (i, r) in e.also.iter().enumerate() {
        device_names(&format!("errors.also[{i}]"), r, cx);
    }
    for (code, def) in &p.devices {
        // A `#` stands for a block number.
        if let Err(e) = format!("{}0", code.replace('#', "1")).parse::<crate::device::Device>() {
            cx.error(
                format!("devices.{code}"),
                LoadErrorKind::Invalid(format!(
                    "not a device code ({e}; at most {} characters)",
                    crate::device::MAX_CODE_LEN
                )),
            );
        }
        check_ranges(&format!("devices.{code}"), &def.ranges(), def, cx);
        if def.points_per_word == 0 {
            cx.error(
                format!("devices.{code}.points_per_word"),
                LoadErrorKind::Invalid("a word takes at least one point".into()),
            );
        }
        // A digit designation's unit is its points (`K4M0`, then `K4M16`): only one that is
        // exactly a word is a unit the models and the protocol know.
        let points = crate::device::Device::new(code, 0).points();
        if points > 1 && (points != 16 || def.points_per_word != 16) {
            cx.error(
                format!("devices.{code}"),
                LoadErrorKind::Invalid(format!(
                    "a digit designation is modelled as one 16-bit word: K4 and a bit device \
                     (16 points), with `points_per_word: 16` ({code} is {points} points)"
                )),
            );
        }
    }
    for (name, def) in &p.instructions {
        for (i, flag) in def.flags.iter().enumerate() {
            if !p.flags.contains_key(flag) {
                cx.error(
                    format!("instructions.{name}.flags[{i}]"),
                    unknown("flag", flag, &flags),
                );
            }
        }
        for (op, def) in &def.operands {
            if def.constants.is_some() && !def.constant {
                cx.error(
                    format!("instructions.{name}.operands.{op}.constants"),
                    LoadErrorKind::Invalid("`constants` needs `constant: true`".into()),
                );
            }
            if def.count && !def.constant {
                cx.error(
                    format!("instructions.{name}.operands.{op}.count"),
                    LoadErrorKind::Invalid(
                        "`count` needs `constant: true`: only a constant is a length".into(),
                    ),
                );
            }
            for code in def.limits.keys() {
                if !def.devices.contains(code) {
                    cx.error(
                        format!("instructions.{name}.operands.{op}.limits.{code}"),
                        unknown("device of this operand", code, &def.devices),
                    );
                }
            }
            let listed = (def.devices.iter().map(|c| ("devices", c)))
                .chain(def.indirect.iter().map(|c| ("indirect", c)));
            for (i, (list, code)) in listed.enumerate() {
                if !p.devices.contains_key(code) {
                    let i = if list == "devices" {
                        i
                    } else {
                        i - def.devices.len()
                    };
                    cx.error(
                        format!("instructions.{name}.operands.{op}.{list}[{i}]"),
                        unknown("device", code, &devices),
                    );
                }
            }
        }
    }
    if p.variants.is_empty() {
        cx.error(
            "variants",
            LoadErrorKind::Missing("variant: a profile needs at least one"),
        );
    }
    let variants: Vec<String> = p.variants.iter().map(|v| v.id.clone()).collect();
    for (id, manual) in &p.manuals {
        for (i, v) in manual.covers.iter().enumerate() {
            if !variants.contains(v) {
                cx.error(
                    format!("manuals.{id}.covers[{i}]"),
                    unknown("variant", v, &variants),
                );
            }
        }
    }
    let mut seen = BTreeSet::new();
    for (v, variant) in p.variants.iter().enumerate() {
        if !seen.insert(&variant.id) {
            cx.error(
                format!("variants[{v}].id"),
                LoadErrorKind::Invalid(format!("variant id `{}` is used twice", variant.id)),
            );
        }
        for (i, flag) in variant.ignores_flags.iter().enumerate() {
            if !p.flags.contains_key(flag) {
                cx.error(
                    format!("variants[{v}].ignores_flags[{i}]"),
                    unknown("flag", flag, &flags),
                );
            }
        }
        for (code, ranges) in &variant.devices {
            let key = format!("variants[{v}].devices.{code}");
            match p.devices.get(code) {
                Some(def) => check_ranges(&key, ranges, def, cx),
                None => cx.error(key, unknown("device", code, &devices)),
            }
        }
        for (i, instr) in variant.instructions.iter().flatten().enumerate() {
            if !p.instructions.contains_key(instr) {
                cx.error(
                    format!("variants[{v}].instructions[{i}]"),
                    unknown("instruction", instr, &instructions),
                );
            }
        }
    }
}

/// Each range runs forward and its ends are numbers the code's numbering has.
fn check_ranges(key: &str, ranges: &DeviceRanges, def: &DeviceDef, cx: &mut FileContext<'_>) {
    for (i, range) in ranges.iter().enumerate() {
        let key = if i == 0 {
            key.to_string()
        } else {
            format!("{key}.also[{}]", i - 1)
        };
        if range.first > range.last {
            cx.error(
                &key,
                LoadErrorKind::Invalid(format!(
                    "first {} is after last {}",
                    range.first, range.last
                )),
            );
        }
        for end in [range.first, range.last] {
            if def.numbering.point(end).is_none() {
                cx.error(
                    &key,
                    LoadErrorKind::Invalid(format!(
                        "{end} is not a number in {} numbering",
                        def.numbering.name()
                    )),
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only a constant is a length: `count` on an operand that takes none is refused with its key.
    #[test]
    fn a_count_needs_a_constant() {
        let text = |operand: &str| {
            format!(
                "id: p\nname: P\nshort: p\nmanuals: {{}}\n\
                 errors: {{signal: code, flag: SM0, register: SD0}}\n\
                 devices: {{D: {{first: 0, last: 100}}}}\n\
                 instructions: {{X: {{summary: x, operands: {{n: {operand}}}}}}}\n\
                 variants: [{{id: v, description: v}}]\n"
            )
        };
        let mut errors = Vec::new();
        let good = "{devices: [D], constant: true, count: true}";
        assert!(parse_profile(Path::new("p.yaml"), &text(good), &mut errors).is_some());
        assert!(errors.is_empty(), "{errors:?}");
        let bad = "{devices: [D], count: true}";
        parse_profile(Path::new("p.yaml"), &text(bad), &mut errors);
        let shown: Vec<String> = errors.iter().map(ToString::to_string).collect();
        assert!(
            shown
                .iter()
                .any(|e| e.contains("instructions.X.operands.n.count")
                    && e.contains("`count` needs `constant: true`")),
            "{shown:?}"
        );
    }
}
