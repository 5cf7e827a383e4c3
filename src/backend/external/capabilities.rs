//! What a backend must claim before a case runs: its profile, instructions, operands and flags,
//! or its codec operations and protocol, checked against the profiles and its configuration.
//! Kept apart so that every refusal of a handshake's claims reads in one place.

use std::sync::Arc;

use super::protocol::{self, first_version_for, Capabilities, MemoryRange};
use super::ExternalErrorKind;
use crate::model::cross_vendor::{
    CodecAbilities, FieldShape, Operation, OperationAbilities, ProtocolClaim,
};
use crate::model::profile::{Profile, Profiles};
use crate::model::project::ExternalSettings;

/// Checks a codec-level handshake: no instruction-level claims beside it, no profile configured,
/// every digit count and width one a field can have (each count once), and a declared reading
/// one of the built-in lowerings of its operation (`fx5/hexa-16bit`).
pub(super) fn check_codec(
    spec: &ExternalSettings,
    caps: &Capabilities,
    codec: &protocol::CodecCapabilities,
    profiles: &Profiles,
) -> Result<CodecAbilities, ExternalErrorKind> {
    if let Some(configured) = &spec.profile {
        return Err(ExternalErrorKind::Capabilities(format!(
            "is configured as implementing profile `{configured}` but its handshake claims the \
             codec level; leave `profile` out for a codec-level backend"
        )));
    }
    if !caps.profile.is_empty()
        || !caps.instructions.is_empty()
        || caps.variants.is_some()
        || !caps.flags.is_empty()
        || !caps.operands.is_empty()
        || caps.device_ranges.is_some()
    {
        return Err(ExternalErrorKind::Capabilities(
            "claims the codec level and instruction-level capabilities at once; give either \
             `codec` or `profile` and `instructions`"
                .into(),
        ));
    }
    let refuse = |why: String| Err(ExternalErrorKind::Capabilities(why));
    let ability = |operation: Operation, c: &Option<protocol::OperationCapabilities>| match c {
        None => Ok(None),
        Some(c) => {
            let name = operation.to_string();
            let width = c.width.unwrap_or(16);
            if width != 16 && width != 32 {
                return refuse(format!("claims {name} of width {width}; give 16 or 32"));
            }
            if let Some(digits) = &c.digits {
                if digits.is_empty() {
                    return refuse(format!(
                        "claims {name} of no digit count (`digits: []`); list the counts it \
                         reads, or leave `digits` out for any"
                    ));
                }
                if let Some(d) = digits.iter().find(|d| !(1..=16).contains(*d)) {
                    return refuse(format!(
                        "claims {name} of {d} digits; give counts from 1 to 16"
                    ));
                }
                let mut sorted = digits.clone();
                sorted.sort_unstable();
                if let Some(d) = sorted.windows(2).find(|w| w[0] == w[1]) {
                    return refuse(format!("claims {name} of {} digits twice", d[0]));
                }
            }
            if c.widths.as_ref().is_some_and(|w| w.is_empty()) {
                return refuse(format!(
                    "claims {name} widths for no digit count (`widths: {{}}`); map counts to \
                     widths, or leave `widths` out"
                ));
            }
            let mut widths = std::collections::BTreeMap::new();
            for (d, w) in c.widths.iter().flatten() {
                let count = d.parse::<u32>().ok().filter(|n| (1..=16).contains(n));
                let Some(count) = count.filter(|n| n.to_string() == *d) else {
                    return refuse(format!(
                        "claims {name} widths for `{d}` digits; give a count from 1 to 16, \
                         written as a plain number"
                    ));
                };
                if ![8, 16, 32].contains(w) {
                    return refuse(format!(
                        "claims {name} of width {w} for {count} digits; give 8, 16 or 32"
                    ));
                }
                widths.insert(count, *w);
            }
            if c.blanks_between_pairs == Some(true) && operation == Operation::ValueToHex {
                return refuse(format!(
                    "claims {name} skips blanks between byte pairs; only a text is read, so \
                     give `blanks-between-pairs` for hex-to-value"
                ));
            }
            if let Some(reading) = &c.reading {
                let readings: Vec<String> = (profiles.iter())
                    .flat_map(|p| {
                        (p.cross_vendor.lowerings.iter())
                            .filter(|l| l.operation == operation)
                            .map(|l| l.key.clone())
                    })
                    .collect();
                if !readings.contains(reading) {
                    return refuse(format!(
                        "declares {name} reading `{reading}`, which is not a built-in reading; \
                         the readings are: {}",
                        readings.join(", ")
                    ));
                }
            }
            Ok(Some(OperationAbilities {
                digits: c.digits.clone(),
                width,
                reading: c.reading.clone(),
                shape: FieldShape {
                    widths,
                    variable: c.variable.unwrap_or(false),
                    leading_zeros: c.leading_zeros.unwrap_or(true),
                    low_byte_first: c.byte_order == Some(protocol::ByteOrder::LowFirst),
                    whole_frame: c.whole_frame.unwrap_or(false),
                    blanks_between_pairs: c.blanks_between_pairs.unwrap_or(false),
                },
            }))
        }
    };
    let abilities = CodecAbilities {
        hex_to_value: ability(Operation::HexToValue, &codec.hex_to_value)?,
        value_to_hex: ability(Operation::ValueToHex, &codec.value_to_hex)?,
        check: ability(Operation::Check, &codec.check)?,
        verify: ability(Operation::Verify, &codec.verify)?,
        protocol: protocol_claim(spec, codec, profiles)?,
    };
    if [
        Operation::HexToValue,
        Operation::ValueToHex,
        Operation::Check,
        Operation::Verify,
    ]
    .iter()
    .all(|o| abilities.of(*o).is_none())
    {
        return Err(ExternalErrorKind::Capabilities(
            "claims the codec level but no operation".into(),
        ));
    }
    Ok(abilities)
}

/// Checks a codec's protocol: one a protocol profile defines, the one its configuration names
/// (a backend planned before it starts is planned by that), with fields the profile has.
fn protocol_claim(
    spec: &ExternalSettings,
    codec: &protocol::CodecCapabilities,
    profiles: &Profiles,
) -> Result<Option<ProtocolClaim>, ExternalErrorKind> {
    let refuse = |why: String| Err(ExternalErrorKind::Capabilities(why));
    let Some(id) = &codec.protocol else {
        if codec.fields.is_some() || codec.cross_vendor.is_some() {
            return refuse(
                "gives `fields` or `cross-vendor` but no `protocol`; name the protocol whose \
                 fields it implements"
                    .into(),
            );
        }
        if let Some(configured) = &spec.protocol {
            return refuse(format!(
                "is configured as implementing protocol `{configured}` but its handshake names \
                 no protocol"
            ));
        }
        if codec.check.is_some() || codec.verify.is_some() {
            return refuse(
                "claims `check` or `verify` but no `protocol`: a check character is a \
                 protocol's"
                    .into(),
            );
        }
        return Ok(None);
    };
    let Some(found) = profiles.protocols.get(id) else {
        return refuse(format!(
            "names protocol `{id}`, which no protocol profile defines; the protocols are: {}",
            profiles.protocols.ids().join(", ")
        ));
    };
    match &spec.protocol {
        Some(configured) if configured != id => {
            return refuse(format!(
                "is configured as implementing protocol `{configured}` but its handshake names \
                 `{id}`"
            ))
        }
        None if spec.codec => {
            return refuse(format!(
                "names protocol `{id}` but its configuration does not: add `protocol: {id}` to \
                 its entry in the project file, so that its trials are planned by that protocol"
            ))
        }
        _ => {}
    }
    let cross_vendor = codec.cross_vendor.unwrap_or(false);
    if spec.protocol.is_some() && cross_vendor != spec.cross_vendor {
        return refuse(format!(
            "asks for the cross-vendor view {} but its configuration {}; make `cross_vendor` in \
             the project file and `cross-vendor` in the handshake agree",
            if cross_vendor { "too" } else { "not" },
            if spec.cross_vendor {
                "does"
            } else {
                "does not"
            }
        ));
    }
    if let Some(fields) = &codec.fields {
        if fields.is_empty() {
            return refuse(format!(
                "implements no field of {id} (`fields: []`); list them, or leave `fields` out for \
                 every one"
            ));
        }
        if let Some(unknown) = fields.iter().find(|f| !found.fields.contains_key(*f)) {
            let known: Vec<&str> = found.fields.keys().map(String::as_str).collect();
            return refuse(format!(
                "claims field `{unknown}` of {id}, which has: {}",
                known.join(", ")
            ));
        }
    }
    Ok(Some(ProtocolClaim {
        id: id.clone(),
        fields: codec.fields.clone(),
        cross_vendor,
    }))
}

/// Checks a handshake's capabilities against the profiles and the configured family.
pub(super) fn check_capabilities(
    spec: &ExternalSettings,
    caps: &Capabilities,
    profiles: &Profiles,
    version: u32,
) -> Result<Arc<Profile>, ExternalErrorKind> {
    if let Some(configured) = &spec.profile {
        if configured != &caps.profile {
            return Err(ExternalErrorKind::Capabilities(format!(
                "is configured as implementing profile `{configured}` but its handshake claims `{}`",
                caps.profile
            )));
        }
    }
    let profile = profiles.get(&caps.profile).ok_or_else(|| {
        ExternalErrorKind::Capabilities(format!(
            "claims profile `{}`, which is not loaded; known profiles: {}",
            caps.profile,
            profiles.ids().join(", ")
        ))
    })?;
    let needs = first_version_for(profile.unit);
    if version < needs {
        return Err(ExternalErrorKind::Capabilities(format!(
            "answers hello with protocol version {version}, but profile `{}`'s memory unit is a \
             {}: its memory ranges carry `{}`, which needs version {needs}",
            profile.id,
            profile.unit.name(),
            MemoryRange::field(profile.unit)
        )));
    }
    let unknown = |what: &str, name: &str, known: Vec<String>| {
        format!(
            "claims {what} `{name}`, which profile `{}` does not define; it defines: {}",
            profile.id,
            known.join(", ")
        )
    };
    for i in &caps.instructions {
        if !profile.instructions.contains_key(i) {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "instruction",
                i,
                profile.instructions.keys().cloned().collect(),
            )));
        }
    }
    for v in caps.variants.iter().flatten() {
        if profile.variant(v).is_none() {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "variant",
                v,
                profile.variants.iter().map(|v| v.id.clone()).collect(),
            )));
        }
    }
    for (op, forms) in &caps.operands {
        let claimed = caps.instructions.iter().any(|i| {
            profile
                .instructions
                .get(i)
                .is_some_and(|d| d.operands.contains_key(op))
        });
        if !claimed {
            return Err(ExternalErrorKind::Capabilities(format!(
                "claims forms of operand `{op}`, which no instruction it claims has"
            )));
        }
        for code in forms.devices.iter().flatten() {
            if !profile.devices.contains_key(code) {
                return Err(ExternalErrorKind::Capabilities(unknown(
                    "device",
                    code,
                    profile.devices.keys().cloned().collect(),
                )));
            }
        }
    }
    for (f, settings) in &caps.flags {
        if !profile.flags.contains_key(f) {
            return Err(ExternalErrorKind::Capabilities(unknown(
                "flag",
                f,
                profile.flags.keys().cloned().collect(),
            )));
        }
        if settings.is_empty() {
            return Err(ExternalErrorKind::Capabilities(format!(
                "lists no setting for flag `{f}`; leave a flag out to claim both settings"
            )));
        }
    }
    Ok(profile.clone())
}
