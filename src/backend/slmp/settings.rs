//! How to run one live CPU backend, and its command-line form
//! `slmp:NAME=HOST:PORT?manifest=PATH&confirm=TYPE&sandbox=RANGES[&...]`.

use std::path::Path;
use std::time::Duration;

use super::client::{ClientSettings, Code};
use super::fence::{parse_ranges, Kind, WordRange};
use super::frame::{DeviceForm, FrameKind};
use super::limits::{self, Family};
use super::manifest::Manifest;
use crate::backend::slmp::error::{refused, LiveError};

/// The case time limit unless configured: the program needs three or four scans.
pub(crate) const DEFAULT_CASE_TIMEOUT: Duration = Duration::from_secs(2);
/// Faults in a row after which the remaining trials are not run, unless configured.
pub(crate) const DEFAULT_MAX_FAULTS: usize = 3;

/// One live CPU backend's settings.
#[derive(Debug, Clone)]
pub struct SlmpSettings {
    /// The name in trial names and on the command line.
    pub name: String,
    pub client: ClientSettings,
    /// The generated program's manifest.
    pub manifest: Manifest,
    /// The one profile variant the CPU is: its trials alone run.
    pub variant: String,
    /// What the CPU's type name (0101) must be before anything is written.
    pub confirm: String,
    /// The words case windows may be written to (the mailbox's PC words are added).
    pub sandbox: Vec<WordRange>,
    /// How long the program may take to acknowledge a case.
    pub case_timeout: Duration,
    /// The circuit breaker: faults in a row after which the remaining trials are not run.
    pub max_consecutive_faults: usize,
    /// The first wait between status polls; it doubles up to `max_poll`.
    pub first_poll: Duration,
    pub max_poll: Duration,
}

impl SlmpSettings {
    /// The limits of the port as now configured: to call after changing the code or the form.
    pub fn fit_limits(&mut self) {
        let family = Family::of_profile(&self.manifest.profile);
        self.client.limits = limits::limits(family, self.client.code, self.client.form);
    }

    /// Settings with the defaults of the manifest's family: FX5 CPUs get 3E frames, the
    /// Q-compatible device form (an FX5U refuses the long form) and the monitoring timer 0;
    /// others 4E, the long form and 2 s. The limits follow the code and the form
    /// ([`SlmpSettings::fit_limits`]).
    pub fn new(
        name: impl Into<String>,
        address: impl Into<String>,
        manifest: Manifest,
        variant: impl Into<String>,
        confirm: impl Into<String>,
        sandbox: Vec<WordRange>,
    ) -> Self {
        let mut client = ClientSettings::new(address);
        let family = Family::of_profile(&manifest.profile);
        if family == Family::Fx5 {
            client.frame = FrameKind::E3;
            client.form = DeviceForm::Short;
        }
        client.timer = limits::monitoring_timer(family);
        let mut settings = SlmpSettings {
            name: name.into(),
            client,
            manifest,
            variant: variant.into(),
            confirm: confirm.into(),
            sandbox,
            case_timeout: DEFAULT_CASE_TIMEOUT,
            max_consecutive_faults: DEFAULT_MAX_FAULTS,
            first_poll: Duration::from_millis(2),
            max_poll: Duration::from_millis(20),
        };
        settings.fit_limits();
        settings
    }

    /// Reads `slmp:NAME=HOST:PORT?key=value&...`; `None` when `text` is not of this form.
    /// Keys: `manifest` (path), `confirm` (the CPU type name), `sandbox` (ranges such as
    /// `D0-D4359,D7900-D7999`, where `manifest` stands for the data and link registers of the
    /// manifest's `writes`: `manifest,SD100-SD167` adds special registers), and optionally
    /// `variant`, `frame` (3e, 4e), `code` (binary, ascii), `form` (short, long), `timeout` (case seconds), `monitor`
    /// (monitoring timer, units of 250 ms), `max_faults`, `poll_ms`.
    pub fn parse(text: &str, base: &Path) -> Result<Option<SlmpSettings>, LiveError> {
        let Some(rest) = text.strip_prefix("slmp:") else {
            return Ok(None);
        };
        let usage = "expected `slmp:NAME=HOST:PORT?manifest=PATH&confirm=TYPE&sandbox=RANGES`";
        let (name, rest) = rest
            .split_once('=')
            .ok_or_else(|| refused!("`{text}`: {usage}"))?;
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_')
        {
            return Err(refused!(
                "`{name}` is not a backend name: use lowercase letters, digits, `-` and `_`"
            ));
        }
        let (address, query) = rest.split_once('?').unwrap_or((rest, ""));
        if !address.contains(':') {
            return Err(refused!("`{text}`: `{address}` has no port; {usage}"));
        }
        let mut keys: Vec<(&str, &str)> = Vec::new();
        for pair in query.split('&').filter(|p| !p.is_empty()) {
            let (k, v) = pair
                .split_once('=')
                .ok_or_else(|| refused!("`{pair}` in `{text}`: expected key=value"))?;
            if keys.iter().any(|(seen, _)| *seen == k) {
                return Err(refused!("`{k}` is given twice in `{text}`"));
            }
            keys.push((k, v));
        }
        let get = |k: &str| keys.iter().find(|(key, _)| *key == k).map(|(_, v)| *v);
        let known = [
            "manifest",
            "confirm",
            "sandbox",
            "variant",
            "frame",
            "code",
            "form",
            "timeout",
            "monitor",
            "max_faults",
            "poll_ms",
        ];
        if let Some((k, _)) = keys.iter().find(|(k, _)| !known.contains(k)) {
            return Err(refused!(
                "unknown key `{k}` in `{text}`; known keys: {}",
                known.join(", ")
            ));
        }
        let need = |k: &str| get(k).ok_or_else(|| refused!("`{text}` has no `{k}=`; {usage}"));
        let manifest_path = base.join(need("manifest")?);
        let manifest = Manifest::load(&manifest_path)?;
        let variant = match get("variant") {
            Some(v) => v.to_string(),
            None if manifest.variants.len() == 1 => manifest.variants[0].clone(),
            None => {
                return Err(refused!(
                    "`{text}` has no `variant=`, and the manifest has several: {}",
                    manifest.variants.join(", ")
                ))
            }
        };
        // `manifest` stands for the data and link registers of the manifest's `writes`; special
        // registers (SD, SW) are written only where the user names them.
        let mut sandbox = Vec::new();
        for token in need("sandbox")?.split(',').map(str::trim) {
            match token {
                "" => {}
                "manifest" => sandbox.extend(
                    parse_ranges(&manifest.writes.join(","))
                        .map_err(|e| {
                            LiveError::within(format!("{}: `writes`", manifest_path.display()), e)
                        })?
                        .into_iter()
                        .filter(|r| Kind::of(&r.code) == Kind::Data),
                ),
                range => sandbox.push(
                    range
                        .parse::<WordRange>()
                        .map_err(|e| LiveError::within("`sandbox`", e))?,
                ),
            }
        }
        let confirm = need("confirm")?.to_string();
        let mut s = SlmpSettings::new(name, address, manifest, variant, confirm, sandbox);
        if let Some(f) = get("frame") {
            s.client.frame = match f {
                "3e" | "3E" => FrameKind::E3,
                "4e" | "4E" => FrameKind::E4,
                _ => return Err(refused!("`frame={f}`: give 3e or 4e")),
            };
        }
        if let Some(c) = get("code") {
            s.client.code = match c {
                "binary" => Code::Binary,
                "ascii" => Code::Ascii,
                _ => return Err(refused!("`code={c}`: give binary or ascii")),
            };
        }
        if let Some(f) = get("form") {
            s.client.form = match f {
                "short" => DeviceForm::Short,
                "long" => DeviceForm::Long,
                _ => {
                    return Err(refused!(
                        "`form={f}`: give short (subcommand 0000) or long (0002)"
                    ))
                }
            };
        }
        let number = |k: &str, v: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|n| n.is_finite() && *n > 0.0 && *n <= 3600.0)
                .ok_or_else(|| refused!("`{k}={v}`: give a number above 0 and at most 3600"))
        };
        if let Some(v) = get("timeout") {
            s.case_timeout = Duration::from_secs_f64(number("timeout", v)?);
        }
        s.fit_limits();
        if let Some(v) = get("monitor") {
            let units = v.parse::<u16>().ok().filter(|n| *n <= 240).ok_or_else(|| {
                refused!("`monitor={v}`: give 0 (the FX5 value) to 240 (units of 250 ms)")
            })?;
            s.client.timer = units;
            // With 0 the CPU does not time itself, and the client's default reply time holds.
            if units > 0 {
                s.client.reply_timeout =
                    Duration::from_millis(250 * u64::from(units)) + Duration::from_millis(500);
            }
        }
        if let Some(v) = get("max_faults") {
            s.max_consecutive_faults = v
                .parse::<usize>()
                .ok()
                .filter(|n| *n > 0)
                .ok_or_else(|| refused!("`max_faults={v}`: give at least 1"))?;
        }
        if let Some(v) = get("poll_ms") {
            s.first_poll = Duration::from_secs_f64(number("poll_ms", v)? / 1000.0);
        }
        Ok(Some(s))
    }
}
