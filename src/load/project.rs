//! The project file, `plc-conformance.yaml`: the external backends a project runs alongside the
//! built-in ones, under `plc-conformance run` and `cargo test` alike.
//!
//! ```yaml
//! backends:
//!   - name: my-emulator
//!     command: ./target/release/my-emulator --conformance   # run by `sh -c`
//!     profile: mitsubishi-iqr        # the family it implements; the handshake must agree
//!     timeout: 5                     # seconds per case
//!     known_differences: conformance/my-emulator.known.yaml
//!     requires: [./target/release/my-emulator]
//! ```
//!
//! Paths are relative to the file's folder, which is also the backends' working directory.
//! `$PLC_CONFORMANCE` in a command is the plc-conformance binary itself, so a project can serve
//! a built-in model through the protocol.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::{LoadError, LoadErrorKind, LoadErrors};
use crate::model::project::{
    Configured, ExternalSettings, Launch, ProjectBackends, DEFAULT_BATCH,
    DEFAULT_MAX_CONSECUTIVE_FAULTS, DEFAULT_STARTUP_TIMEOUT, DEFAULT_TIMEOUT,
};
use crate::model::Location;
use crate::spec::project::{CommandSpec, ProjectFileSpec};

/// The file name looked for in the project root.
pub const FILE_NAME: &str = "plc-conformance.yaml";
/// The environment variable naming another project file.
pub const ENV_CONFIG: &str = "PLC_CONFORMANCE_CONFIG";
/// The environment variable that turns a backend whose `requires` are missing from a skip into
/// an error: CI sets it, so that a backend it should run is never silently left out.
pub const ENV_REQUIRE: &str = "PLC_CONFORMANCE_REQUIRE_BACKENDS";
/// The environment variable a backend's command sees naming the plc-conformance binary.
pub const ENV_SELF: &str = "PLC_CONFORMANCE";

/// Where the project file is: `PLC_CONFORMANCE_CONFIG`, else `ROOT/plc-conformance.yaml`. The
/// flag says whether it was named explicitly (then it must exist).
pub(crate) fn locate_project(root: &Path) -> (PathBuf, bool) {
    match std::env::var_os(ENV_CONFIG) {
        Some(p) if !p.is_empty() => (PathBuf::from(p), true),
        _ => (root.join(FILE_NAME), false),
    }
}

/// Whether missing requirements are errors (`PLC_CONFORMANCE_REQUIRE_BACKENDS` set and not `0`).
pub(crate) fn requirements_enforced() -> bool {
    std::env::var(ENV_REQUIRE).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Reads the project file at `file` (see `locate_project`). A missing file that was not named
/// explicitly means no external backends. Backends whose requirements are missing are set aside,
/// or are an error when `requirements_enforced`. `plc_conformance` is the binary backends see
/// as `$PLC_CONFORMANCE`.
pub fn load_project(
    file: &Path,
    explicit: bool,
    plc_conformance: &Path,
) -> Result<ProjectBackends, LoadErrors> {
    if !explicit && !file.exists() {
        return Ok(ProjectBackends::default());
    }
    let all = read_project(file, plc_conformance)?;
    let enforced = requirements_enforced();
    let mut out = ProjectBackends::default();
    let mut errors = Vec::new();
    for c in all {
        match c.missing() {
            None => out.configured.push(c),
            Some(skipped) if enforced => errors.push(LoadError {
                file: c.location.file.clone(),
                line: Some(c.location.line),
                key: Some("requires".into()),
                kind: LoadErrorKind::Invalid(format!(
                    "{skipped} ({ENV_REQUIRE} is set, so every configured backend must run)"
                ))
                .into(),
            }),
            Some(skipped) => out.skipped.push(skipped),
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(LoadErrors(errors))
    }
}

fn read_project(file: &Path, plc_conformance: &Path) -> Result<Vec<Configured>, LoadErrors> {
    super::load_document(file, |spec: ProjectFileSpec, cx| {
        let dir = file
            .parent()
            .map(Path::to_path_buf)
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."));
        let mut out: Vec<Configured> = Vec::new();
        let mut seen: Vec<(String, Location)> = Vec::new();
        for (i, b) in spec.backends.into_iter().enumerate() {
            let key = |k: &str| format!("backends[{i}].{k}");
            if !valid_name(&b.name) {
                cx.error(
                    key("name"),
                    LoadErrorKind::Invalid(format!(
                        "`{}` is not a backend name: use lowercase letters, digits, `-` and `_`",
                        b.name
                    )),
                );
            }
            let location = cx.location(&format!("backends[{i}]"));
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == b.name) {
                cx.error(
                    key("name"),
                    LoadErrorKind::Invalid(format!(
                        "backend name `{}` is already used at {first}",
                        b.name
                    )),
                );
            }
            seen.push((b.name.clone(), location.clone()));
            let launch = match b.command {
                CommandSpec::Shell(s) if !s.trim().is_empty() => Launch::Shell(s),
                CommandSpec::Exec(v) if !v.is_empty() => Launch::Exec(v),
                _ => {
                    cx.error(
                        key("command"),
                        LoadErrorKind::Invalid("empty command".into()),
                    );
                    continue;
                }
            };
            let mut seconds = |k: &str, value: Option<f64>, default: Duration| match value {
                None => default,
                Some(s) if s.is_finite() && s > 0.0 && s <= 86_400.0 => Duration::from_secs_f64(s),
                Some(s) => {
                    cx.error(
                        key(k),
                        LoadErrorKind::Invalid(format!(
                            "{s} is not a time limit: give seconds above 0 and at most a day"
                        )),
                    );
                    default
                }
            };
            let timeout = seconds("timeout", b.timeout, DEFAULT_TIMEOUT);
            let startup_timeout = seconds(
                "startup_timeout",
                b.startup_timeout,
                DEFAULT_STARTUP_TIMEOUT,
            );
            if b.max_consecutive_faults == Some(0) {
                cx.error(
                    key("max_consecutive_faults"),
                    LoadErrorKind::Invalid(
                        "give at least 1: the number of faults in a row after which the \
                         backend's remaining trials are not run"
                            .into(),
                    ),
                );
            }
            if b.batch == Some(0) {
                cx.error(
                    key("batch"),
                    LoadErrorKind::Invalid("a batch holds at least one case".into()),
                );
            }
            let mut settings = ExternalSettings::new(b.name, launch);
            if b.codec && b.profile.is_some() {
                cx.error(
                    key("codec"),
                    LoadErrorKind::Invalid(
                        "a codec-level backend has no profile: give `codec: true` or `profile`"
                            .into(),
                    ),
                );
            }
            if b.protocol.is_some() && b.profile.is_some() {
                cx.error(
                    key("protocol"),
                    LoadErrorKind::Invalid(
                        "a protocol's codec has no profile: give `protocol` or `profile`".into(),
                    ),
                );
            }
            if b.cross_vendor && b.protocol.is_none() {
                cx.error(
                    key("cross_vendor"),
                    LoadErrorKind::Invalid(
                        "`cross_vendor` adds the cross-vendor view to a protocol's codec: give \
                         `protocol` too (a codec of no protocol runs that corpus already)"
                            .into(),
                    ),
                );
            }
            settings.profile = b.profile;
            settings.codec = b.codec || b.protocol.is_some();
            settings.protocol = b.protocol;
            settings.cross_vendor = b.cross_vendor;
            settings.timeout = timeout;
            settings.startup_timeout = startup_timeout;
            settings.known_differences = b.known_differences.map(|p| dir.join(p));
            settings.cwd = Some(dir.clone());
            settings.env = vec![(ENV_SELF.into(), plc_conformance.display().to_string())];
            settings.batch = b.batch.unwrap_or(DEFAULT_BATCH).max(1);
            settings.max_consecutive_faults = b
                .max_consecutive_faults
                .unwrap_or(DEFAULT_MAX_CONSECUTIVE_FAULTS)
                .max(1);
            out.push(Configured {
                on_request: b.on_request,
                settings,
                requires: b.requires.into_iter().map(|p| dir.join(p)).collect(),
                location,
            });
        }
        out
    })
}

/// Backend names end up in trial names and on command lines.
pub(crate) fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A project file in a scratch folder, removed when the folder is dropped.
    fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join(FILE_NAME);
        std::fs::write(&file, text).expect("write");
        (dir, file)
    }

    #[test]
    fn reads_backends_relative_to_the_file() {
        let (_dir, file) = write(
            "backends:\n  - name: emu\n    command: ./emu --serve\n    profile: mitsubishi-iqr\n    \
             timeout: 0.5\n    known_differences: emu.known.yaml\n    requires: [emu]\n  \
             - name: py\n    command: [python3, adapter.py]\n",
        );
        let dir = file.parent().expect("dir").to_path_buf();
        let all = read_project(&file, Path::new("/bin/plc-conformance")).expect("loads");
        assert_eq!(all.len(), 2);
        let emu = &all[0].settings;
        assert_eq!(emu.launch, Launch::Shell("./emu --serve".into()));
        assert_eq!(emu.timeout, Duration::from_millis(500));
        assert_eq!(emu.startup_timeout, DEFAULT_STARTUP_TIMEOUT);
        assert_eq!(emu.known_differences, Some(dir.join("emu.known.yaml")));
        assert_eq!(emu.cwd, Some(dir.clone()));
        assert_eq!(
            emu.env,
            vec![(ENV_SELF.to_string(), "/bin/plc-conformance".to_string())]
        );
        assert_eq!(all[0].location.line, 2);
        assert!(all[0]
            .missing()
            .is_some_and(|m| m.to_string().contains("emu")));
        assert_eq!(
            all[1].settings.launch,
            Launch::Exec(vec!["python3".into(), "adapter.py".into()])
        );
        assert_eq!(all[1].settings.timeout, DEFAULT_TIMEOUT);
        assert!(all[1].missing().is_none());
    }

    #[test]
    fn errors_name_file_line_and_key() {
        let (_dir, file) = write(
            "backends:\n  - name: Emu\n    command: x\n  - name: ok\n    command: []\n  \
             - name: ok\n    command: y\n    timeout: 0\n    max_consecutive_faults: 0\n",
        );
        let errors = read_project(&file, Path::new("p"))
            .expect_err("invalid")
            .to_string();
        let at = |line: usize, rest: &str| format!("{}:{line}: {rest}", file.display());
        for expected in [
            at(2, "backends[0].name: `Emu` is not a backend name"),
            at(5, "backends[1].command: empty command"),
            at(6, "backends[2].name: backend name `ok` is already used at"),
            at(8, "backends[2].timeout: 0 is not a time limit"),
            at(9, "backends[2].max_consecutive_faults: give at least 1"),
        ] {
            assert!(errors.contains(&expected), "{expected}\nin:\n{errors}");
        }
        let (_dir2, file) = write("backends:\n  - name: emu\n    comand: x\n");
        let errors = read_project(&file, Path::new("p"))
            .expect_err("invalid")
            .to_string();
        assert!(
            errors.contains(&format!("{}:3:", file.display())) && errors.contains("comand"),
            "{errors}"
        );
    }
}
