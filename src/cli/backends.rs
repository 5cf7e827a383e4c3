//! Loading a project for a command and starting the backends it names.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use anstream::eprintln;

use super::{BackendArgs, Cli, EXIT_BAD_INPUT};
use crate::backend::Backend;
use crate::load::{load_project, locate_project, valid_name, LoadErrors, ENV_SELF};
use crate::model::project::{ExternalSettings, Launch, ProjectBackends};
use crate::runner::{Paths, Project};

/// Where the command's data is: `--root`, `--vendors` and the given vector paths.
pub fn paths(cli: &Cli, vectors: &[PathBuf]) -> Paths {
    let mut paths = Paths::under(&cli.root);
    if let Some(v) = &cli.vendors {
        paths.vendors = v.clone();
    }
    if !vectors.is_empty() {
        paths.vectors = vectors.to_vec();
    }
    paths
}

pub fn report_load_errors(errors: &LoadErrors) -> u8 {
    eprintln!("{errors}");
    EXIT_BAD_INPUT
}

pub fn load(paths: &Paths) -> Result<Project, u8> {
    Project::load(paths).map_err(|e| report_load_errors(&e))
}

/// The binary that backends see as `$PLC_CONFORMANCE`.
pub fn this_binary() -> PathBuf {
    std::env::current_exe().unwrap_or_else(|_| PathBuf::from("plc-conformance"))
}

/// The project file's backends; a bad file is reported here.
pub fn project_file(cli: &Cli) -> Result<ProjectBackends, u8> {
    let (file, explicit) = match &cli.config {
        Some(f) => (f.clone(), true),
        None => locate_project(&cli.root),
    };
    load_project(&file, explicit, &this_binary()).map_err(|e| report_load_errors(&e))
}

/// Reads `external:NAME=COMMAND`.
fn command_line_external(
    text: &str,
    args: &BackendArgs,
) -> Result<Option<ExternalSettings>, String> {
    let Some(rest) = text.strip_prefix("external:") else {
        return Ok(None);
    };
    let Some((name, command)) = rest.split_once('=') else {
        return Err(format!(
            "`{text}`: expected `external:NAME=COMMAND`, e.g. `external:my-emu=./my-emu --serve`"
        ));
    };
    if !valid_name(name) {
        return Err(format!(
            "`{name}` is not a backend name: use lowercase letters, digits, `-` and `_`"
        ));
    }
    if command.trim().is_empty() {
        return Err(format!("external backend `{name}` has an empty command"));
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0 && args.timeout <= 86_400.0) {
        return Err(format!(
            "--timeout {}: give seconds above 0 and at most a day",
            args.timeout
        ));
    }
    if args.max_faults == 0 {
        return Err("--max-faults 0: give at least 1".into());
    }
    let mut settings = ExternalSettings::new(name, Launch::Shell(command.to_string()));
    settings.timeout = std::time::Duration::from_secs_f64(args.timeout);
    settings.max_consecutive_faults = args.max_faults;
    settings.env = vec![(ENV_SELF.into(), this_binary().display().to_string())];
    Ok(Some(settings))
}

/// Starts the external backends a command asks for and picks its backends, in the order given.
/// `own_corpus` is false when the command reads another corpus (`--vectors`), which need not
/// have every case a known-differences file names.
fn select(
    project: &mut Project,
    file: &ProjectBackends,
    args: &BackendArgs,
) -> Result<Vec<Arc<dyn Backend>>, String> {
    let own_corpus = args.vectors.is_empty();
    let mut known_files: BTreeMap<&str, PathBuf> = BTreeMap::new();
    for entry in &args.known_differences {
        let Some((name, path)) = entry.split_once('=') else {
            return Err(format!("--known-differences `{entry}`: expected NAME=FILE"));
        };
        known_files.insert(name, PathBuf::from(path));
    }
    let start = |project: &mut Project, settings: ExternalSettings| {
        project
            .add_external(settings, own_corpus)
            .map(|b| b as Arc<dyn Backend>)
            .map_err(|e| e.to_string())
    };
    if args.backends.is_empty() {
        let mut chosen = project.backends.clone();
        for c in file.configured.iter().filter(|c| !c.on_request) {
            chosen.push(start(project, c.settings.clone())?);
        }
        return Ok(chosen);
    }
    let mut chosen = Vec::new();
    for name in &args.backends {
        if let Some(mut settings) = command_line_external(name, args)? {
            settings.known_differences = known_files.remove(settings.name.as_str());
            chosen.push(start(project, settings)?);
        } else if let Some(b) = project.backends.iter().find(|b| b.name() == name) {
            chosen.push(b.clone());
        } else if let Some(c) = file.configured.iter().find(|c| c.settings.name == *name) {
            chosen.push(start(project, c.settings.clone())?);
        } else if let Some(skipped) = file.skipped.iter().find(|s| s.name == *name) {
            return Err(skipped.to_string());
        } else {
            let mut known: Vec<&str> = project.backends.iter().map(|b| b.name()).collect();
            known.extend(file.configured.iter().map(|c| c.settings.name.as_str()));
            return Err(format!(
                "unknown backend `{name}`; expected one of: {}, or external:NAME=COMMAND",
                known.join(", ")
            ));
        }
    }
    if let Some(name) = known_files.keys().next() {
        return Err(format!(
            "--known-differences names `{name}`, which is not an `external:` backend of this run"
        ));
    }
    Ok(chosen)
}

/// A loaded project with the chosen backends started (every external backend has agreed on
/// the protocol before a case runs), and the project file they came from.
pub struct Prepared {
    pub project: Project,
    pub file: ProjectBackends,
    pub backends: Vec<Arc<dyn Backend>>,
}

pub fn prepare(cli: &Cli, args: &BackendArgs) -> Result<Prepared, u8> {
    let mut project = load(&paths(cli, &args.vectors))?;
    let file = project_file(cli)?;
    let backends = start(&mut project, &file, args)?;
    Ok(Prepared {
        project,
        file,
        backends,
    })
}

/// [`select`], with its error reported here.
pub fn start(
    project: &mut Project,
    file: &ProjectBackends,
    args: &BackendArgs,
) -> Result<Vec<Arc<dyn Backend>>, u8> {
    select(project, file, args).map_err(|message| {
        // The message may quote a backend's stderr: nothing in it reaches the terminal raw.
        eprintln!("error: {}", crate::report::sanitize::terminal(&message));
        EXIT_BAD_INPUT
    })
}
