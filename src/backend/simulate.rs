//! A simulated CPU for a program manifest, whatever its profile's link: the manifest read and
//! checked as a bench would check it, the variant settled, the fault rules read in the link's
//! own words, and the link's server started over the profile's reference model. The one place
//! (beside [`super::addressing`]) where a link kind meets its folder for `hil sim`.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use super::bench::error::{refused, LiveError};
use super::bench::manifest::Manifest;
use super::bench::sim::Running;
use super::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use super::slmp::limits::Family;
use super::slmp::sim::{self as slmp_sim, FaultRule, SlmpSimSettings, SlmpSimulator};
use crate::model::profile::{LinkKind, Profiles};

/// A simulated CPU as asked for.
pub(crate) struct SimRequest {
    pub manifest: PathBuf,
    /// `None`: the manifest's one variant.
    pub variant: Option<String>,
    /// The CPU type name an SLMP CPU answers 0101 with [default: the family's usual CPU].
    pub type_name: Option<String>,
    /// Its model code, four hexadecimal digits [default: the type name's, when known].
    pub model_code: Option<String>,
    /// The type code an IDEC CPU's identity register holds.
    pub type_code: u16,
    /// 0: any free port.
    pub port: u16,
    pub scan: Duration,
    /// In RUN (else STOP).
    pub run: bool,
    /// Fault rules, in the link's words (`0101:1:end=C059`, `fc03:2:drop`).
    pub faults: Vec<String>,
}

/// A simulated CPU serving on 127.0.0.1 until dropped.
pub(crate) trait Serving {
    fn address(&self) -> SocketAddr;
}

impl<L: Send + Sync + 'static> Serving for Running<L> {
    fn address(&self) -> SocketAddr {
        Running::address(self)
    }
}

/// Starts the simulated CPU `request` asks for, over the link of its manifest's profile.
pub(crate) fn simulate(
    profiles: &Profiles,
    request: &SimRequest,
) -> Result<Box<dyn Serving>, LiveError> {
    let m = Manifest::read(&request.manifest)?;
    let profile = (profiles.get(&m.profile).cloned())
        .ok_or_else(|| refused!("profile `{}` is not loaded", m.profile))?;
    let link = (profile.bench.as_ref().map(|b| b.link)).ok_or_else(|| {
        refused!(
            "{} has no `bench` section in its profile: no simulated CPU runs its program",
            profile.id
        )
    })?;
    let fault = match link {
        LinkKind::Slmp => FaultRule::slmp,
        LinkKind::ModbusTcp => FaultRule::modbus,
    };
    let faults = (request.faults.iter())
        .map(|f| fault(f).map_err(|e| LiveError::within("--fault", e)))
        .collect::<Result<Vec<_>, _>>()?;
    let addressing = super::addressing(&profile)?;
    let m = (m.validated(addressing.as_ref()))
        .map_err(|e| LiveError::within(request.manifest.display().to_string(), e))?;
    let variant = match &request.variant {
        Some(v) => v.clone(),
        None if m.variants.len() == 1 => m.variants[0].clone(),
        None => {
            return Err(refused!(
                "the manifest has several variants ({}): give --variant",
                m.variants.join(", ")
            ))
        }
    };
    // A simulated CPU serves only what the backend would run against.
    super::bench::mailbox_on(&profile, &variant, &m, addressing.as_ref())?;
    let model = super::reference_model(profiles, &m.profile)
        .ok_or_else(|| refused!("no built-in reference model for {}", m.profile))?;
    Ok(match link {
        LinkKind::Slmp => {
            let type_name =
                (request.type_name.clone()).unwrap_or_else(|| {
                    match Family::of_profile(&m.profile) {
                        Family::Fx5 => "FX5U-32MT/DS".into(),
                        Family::Iqr => "R04CPU".into(),
                    }
                });
            let model_code = match &request.model_code {
                Some(hex) => u16::from_str_radix(hex.trim_end_matches('H'), 16)
                    .map_err(|_| refused!("--model-code {hex}: give four hexadecimal digits"))?,
                None => slmp_sim::model_code(&type_name).ok_or_else(|| {
                    refused!("no model code is known for `{type_name}`: give --model-code")
                })?,
            };
            let mut settings = SlmpSimSettings::new(m, variant, type_name);
            settings.link.model_code = model_code;
            settings.port = request.port;
            settings.scan = request.scan;
            settings.run = request.run;
            settings.faults = faults;
            Box::new(SlmpSimulator::start(settings, profile, model)?)
        }
        LinkKind::ModbusTcp => {
            let mut settings = ModbusSimSettings::idec(m, variant, request.type_code);
            settings.port = request.port;
            settings.scan = request.scan;
            settings.run = request.run;
            settings.faults = faults;
            Box::new(ModbusSimulator::start(settings, profile, model)?)
        }
    })
}
