//! Backends started on the first trial that needs them: planned from what their project-file
//! entry declares, so that listing trials, or running one trial of another backend, starts no
//! process.

use std::sync::{Arc, OnceLock};

use crate::backend::external::{ExternalBackend, ExternalError};
use crate::backend::{Backend, Fault, Request, Response};
use crate::model::cross_vendor::{CodecAbilities, OperationAbilities, ProtocolClaim};
use crate::model::profile::Profiles;
use crate::model::project::ExternalSettings;
use crate::plan::Trial;

/// An external backend started on first use, once per process.
pub(crate) struct LazyStart {
    settings: ExternalSettings,
    profiles: Profiles,
    started: OnceLock<Result<Arc<dyn Backend>, Arc<ExternalError>>>,
}

impl LazyStart {
    pub(super) fn new(settings: ExternalSettings, profiles: Profiles) -> Self {
        LazyStart {
            settings,
            profiles,
            started: OnceLock::new(),
        }
    }

    pub(crate) fn name(&self) -> &str {
        &self.settings.name
    }

    /// The started backend, starting it the first time.
    pub(crate) fn get(&self) -> Result<Arc<dyn Backend>, Arc<ExternalError>> {
        self.started
            .get_or_init(|| {
                ExternalBackend::start(self.settings.clone(), &self.profiles)
                    .map(|b| Arc::new(b) as Arc<dyn Backend>)
                    .map_err(Arc::new)
            })
            .clone()
    }

    /// Makes a planned trial of the placeholder a trial of the started backend, with the
    /// started backend's own skip decision.
    pub(crate) fn bind(&self, trial: &mut Trial) -> Result<(), Arc<ExternalError>> {
        let real = self.get()?;
        trial.skip = crate::plan::skip_reason(trial, real.as_ref());
        trial.backend = real;
        Ok(())
    }
}

/// Stands in for a backend started on first use while planning: it claims everything its
/// profile has, and each trial asks the started backend ([`LazyStart::bind`]) before running.
pub(super) struct Placeholder {
    name: String,
    profile: String,
    /// For a codec-level backend.
    codec: Option<CodecAbilities>,
    lazy: Arc<LazyStart>,
}

impl Placeholder {
    /// `protocol` is a codec's declared protocol and whether it asks for the cross-vendor view
    /// too.
    pub(super) fn new(
        name: String,
        profile: Option<String>,
        protocol: Option<(String, bool)>,
        lazy: Arc<LazyStart>,
    ) -> Self {
        Placeholder {
            name,
            // Planned as able to answer anything; the started backend's own capabilities
            // decide each trial's skip before it runs.
            codec: profile.is_none().then(|| {
                let any = OperationAbilities {
                    digits: Some((0..=16).collect()),
                    width: 64,
                    reading: None,
                    shape: Default::default(),
                };
                CodecAbilities {
                    hex_to_value: Some(any.clone()),
                    value_to_hex: Some(any.clone()),
                    check: Some(any.clone()),
                    verify: Some(any),
                    protocol: protocol.map(|(id, cross_vendor)| ProtocolClaim {
                        id,
                        fields: None,
                        cross_vendor,
                    }),
                }
            }),
            profile: profile.unwrap_or_default(),
            lazy,
        }
    }
}

impl Backend for Placeholder {
    fn name(&self) -> &str {
        &self.name
    }
    fn profile(&self) -> &str {
        &self.profile
    }
    fn describe(&self) -> String {
        format!(
            "external, started on first use ({})",
            self.lazy.settings.launch
        )
    }
    fn claims(&self, _instruction: &str, _variant: &str) -> bool {
        true
    }
    fn execute(&self, _request: &Request<'_>) -> Result<Response, Fault> {
        Err(Fault::Unreachable("the backend was not started".into()))
    }
    fn codec(&self) -> Option<&CodecAbilities> {
        self.codec.as_ref()
    }
}
