//! How to run one bench backend, whatever its link, and the part of its command-line form
//! `LINK:NAME=HOST:PORT?manifest=PATH&confirm=NAME&sandbox=RANGES[&...]` that every link reads
//! alike (the link reads its own keys).

use std::path::Path;
use std::time::Duration;

use super::addressing::Addressing;
use super::fence::{parse_ranges, Kind};
use super::link::LinkSettings;
use super::manifest::Manifest;
use crate::backend::bench::error::{refused, LiveError};
use crate::backend::bench::fence::WordRange;

/// The case time limit unless configured: the program needs three or four scans.
pub(crate) const DEFAULT_CASE_TIMEOUT: Duration = Duration::from_secs(2);
/// Faults in a row after which the remaining trials are not run, unless configured.
pub(crate) const DEFAULT_MAX_FAULTS: usize = 3;

/// The keys every link reads alike.
const COMMON_KEYS: [&str; 7] = [
    "manifest",
    "confirm",
    "sandbox",
    "variant",
    "timeout",
    "max_faults",
    "poll_ms",
];

/// One bench backend's settings; `L` is how to reach the CPU (a link's own settings while they
/// are being set, any link's once the backend is built).
#[derive(Debug, Clone)]
pub struct BenchSettings<L = Box<dyn LinkSettings>> {
    /// The name in trial names and on the command line.
    pub name: String,
    pub link: L,
    /// The generated program's manifest.
    pub manifest: Manifest,
    /// The one profile variant the CPU is: its trials alone run.
    pub variant: String,
    /// What the CPU must name itself before anything is written.
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

impl<L: LinkSettings + Clone + 'static> BenchSettings<L> {
    /// Settings with the default timings.
    pub fn with_link(
        name: impl Into<String>,
        link: L,
        manifest: Manifest,
        variant: impl Into<String>,
        confirm: impl Into<String>,
        sandbox: Vec<WordRange>,
    ) -> Self {
        BenchSettings {
            name: name.into(),
            link,
            manifest,
            variant: variant.into(),
            confirm: confirm.into(),
            sandbox,
            case_timeout: DEFAULT_CASE_TIMEOUT,
            max_consecutive_faults: DEFAULT_MAX_FAULTS,
            first_poll: Duration::from_millis(2),
            max_poll: Duration::from_millis(20),
        }
    }

    /// The same settings over any link: what a backend is built from.
    pub fn erased(self) -> BenchSettings {
        BenchSettings {
            name: self.name,
            link: Box::new(self.link),
            manifest: self.manifest,
            variant: self.variant,
            confirm: self.confirm,
            sandbox: self.sandbox,
            case_timeout: self.case_timeout,
            max_consecutive_faults: self.max_consecutive_faults,
            first_poll: self.first_poll,
            max_poll: self.max_poll,
        }
    }
}

/// A bench backend's command line, split: the name, the address and the keys, each checked
/// once.
pub(crate) struct Spec<'a> {
    pub(crate) text: &'a str,
    pub(crate) name: &'a str,
    pub(crate) address: &'a str,
    keys: Vec<(&'a str, &'a str)>,
    usage: String,
}

impl<'a> Spec<'a> {
    /// Reads `SCHEME:NAME=HOST:PORT?key=value&...`; `None` when `text` is not of this scheme.
    /// `link_keys` are the keys the link reads besides the common ones.
    pub(crate) fn split(
        text: &'a str,
        scheme: &str,
        link_keys: &[&str],
    ) -> Result<Option<Spec<'a>>, LiveError> {
        let Some(rest) = text.strip_prefix(scheme).and_then(|r| r.strip_prefix(':')) else {
            return Ok(None);
        };
        let usage =
            format!("expected `{scheme}:NAME=HOST:PORT?manifest=PATH&confirm=NAME&sandbox=RANGES`");
        let (name, rest) = rest
            .split_once('=')
            .ok_or_else(|| refused!("`{text}`: {usage}"))?;
        if !crate::load::valid_name(name) {
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
        let known: Vec<&str> = COMMON_KEYS.iter().chain(link_keys).copied().collect();
        if let Some((k, _)) = keys.iter().find(|(k, _)| !known.contains(k)) {
            return Err(refused!(
                "unknown key `{k}` in `{text}`; known keys: {}",
                known.join(", ")
            ));
        }
        Ok(Some(Spec {
            text,
            name,
            address,
            keys,
            usage,
        }))
    }

    pub(crate) fn get(&self, key: &str) -> Option<&'a str> {
        self.keys.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }

    fn need(&self, key: &str) -> Result<&'a str, LiveError> {
        self.get(key)
            .ok_or_else(|| refused!("`{}` has no `{key}=`; {}", self.text, self.usage))
    }

    /// A number of seconds (or milliseconds) above 0 and at most 3600.
    pub(crate) fn number(&self, key: &str) -> Result<Option<f64>, LiveError> {
        self.get(key)
            .map(|v| {
                v.parse::<f64>()
                    .ok()
                    .filter(|n| n.is_finite() && *n > 0.0 && *n <= 3600.0)
                    .ok_or_else(|| refused!("`{key}={v}`: give a number above 0 and at most 3600"))
            })
            .transpose()
    }

    /// The manifest, the variant, the confirmation, the sandbox and the link's addressing
    /// (`addressing` makes it from the manifest, whose profile it may need): `manifest` in the
    /// sandbox stands for the data registers of the manifest's `writes` (special registers are
    /// written only where the user names them).
    pub(crate) fn parts<A: Addressing>(
        &self,
        base: &Path,
        addressing: impl FnOnce(&Manifest) -> Result<A, LiveError>,
    ) -> Result<(Manifest, String, String, Vec<WordRange>, A), LiveError> {
        let manifest_path = base.join(self.need("manifest")?);
        let manifest = Manifest::read(&manifest_path)?;
        let owned = addressing(&manifest)?;
        let manifest = manifest
            .validated(&owned)
            .map_err(|e| LiveError::within(manifest_path.display().to_string(), e))?;
        let addressing = &owned;
        let variant = match self.get("variant") {
            Some(v) => v.to_string(),
            None if manifest.variants.len() == 1 => manifest.variants[0].clone(),
            None => {
                return Err(refused!(
                    "`{}` has no `variant=`, and the manifest has several: {}",
                    self.text,
                    manifest.variants.join(", ")
                ))
            }
        };
        let mut sandbox = Vec::new();
        for token in self.need("sandbox")?.split(',').map(str::trim) {
            match token {
                "" => {}
                "manifest" => sandbox.extend(
                    parse_ranges(&manifest.writes.join(","), addressing)
                        .map_err(|e| {
                            LiveError::within(format!("{}: `writes`", manifest_path.display()), e)
                        })?
                        .into_iter()
                        .filter(|r| addressing.kind(&r.head()) == Kind::Data),
                ),
                range => sandbox.push(
                    WordRange::parse(range, addressing)
                        .map_err(|e| LiveError::within("`sandbox`", e))?,
                ),
            }
        }
        let confirm = self.need("confirm")?.to_string();
        Ok((manifest, variant, confirm, sandbox, owned))
    }

    /// The common timings and the breaker, read onto settings built from [`Spec::parts`].
    pub(crate) fn timings<L>(&self, s: &mut BenchSettings<L>) -> Result<(), LiveError> {
        if let Some(seconds) = self.number("timeout")? {
            s.case_timeout = Duration::from_secs_f64(seconds);
        }
        if let Some(v) = self.get("max_faults") {
            s.max_consecutive_faults = v
                .parse::<usize>()
                .ok()
                .filter(|n| *n > 0)
                .ok_or_else(|| refused!("`max_faults={v}`: give at least 1"))?;
        }
        if let Some(ms) = self.number("poll_ms")? {
            s.first_poll = Duration::from_secs_f64(ms / 1000.0);
        }
        Ok(())
    }
}
