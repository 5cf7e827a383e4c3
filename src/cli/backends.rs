//! Loading a project for a command and starting the backends it names.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::{BackendArgs, Cli, CliError};
use crate::backend::Backend;
use crate::load::{
    embedded_files, find_project_root, is_project_root, load_project, locate_project, FILE_NAME,
};
use crate::model::project::ProjectBackends;
use crate::project::{Paths, Project};
use crate::session::{Asked, Session};

/// The project folder of the command: `--root`, else the nearest project folder at or above the
/// current one (as a relative path, so that messages stay short), else none: the data built into
/// the binary.
pub(super) fn project_root(cli: &Cli) -> Result<Option<PathBuf>, CliError> {
    if let Some(root) = &cli.root {
        if is_project_root(root) {
            return Ok(Some(root.clone()));
        }
        let shown = root.display();
        return Err(CliError::input(format!(
            "--root {shown}: not a plc-conformance project (looked for {}, and for {} \
             with {})\n  hint: pass the folder that holds them, or leave out --root: the nearest \
             project folder at or above the current one is used, else the profiles and corpus \
             built into plc-conformance",
            root.join(FILE_NAME).display(),
            root.join("vendors/").display(),
            root.join("vectors/").display(),
        )));
    }
    let Ok(here) = std::env::current_dir() else {
        return Ok(None);
    };
    Ok(find_project_root(&here).map(|found| {
        let up = here.components().count() - found.components().count();
        if up == 0 {
            // Paths below the current folder read as `vectors/...`.
            PathBuf::new()
        } else {
            std::iter::repeat_n("..", up).collect()
        }
    }))
}

/// Where the command's data is: the project's (or the built-in) `vendors/` and `vectors/`,
/// `--vendors`, and the given vector paths. A folder or file named but missing is reported
/// here, with where it was looked for and what to pass instead.
pub(super) fn paths(cli: &Cli, vectors: &[PathBuf], flag: &str) -> Result<Paths, CliError> {
    let mut paths = match project_root(cli)? {
        Some(root) => Paths::of_project(&root),
        None => Paths::embedded(),
    };
    if let Some(v) = &cli.vendors {
        if !v.is_dir() && embedded_files(v).is_none_or(|f| f.is_empty()) {
            return Err(CliError::input(format!(
                "--vendors {}: no such folder (looked at {})\n  hint: pass the folder \
                 of vendor profiles (*.yaml), or leave out --vendors to use {}",
                v.display(),
                absolute(v).display(),
                paths.vendors.display()
            )));
        }
        paths.vendors = v.clone();
    }
    for v in vectors {
        if !v.exists() && embedded_files(v).is_none_or(|f| f.is_empty()) {
            return Err(CliError::input(format!(
                "{flag} {}: no such file or folder (looked at {})\n  hint: pass a vector \
                 file (*.yaml) or a folder of them, or leave it out to use {}",
                v.display(),
                absolute(v).display(),
                paths
                    .vectors
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    if !vectors.is_empty() {
        paths.vectors = vectors.to_vec();
    }
    Ok(paths)
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

pub(super) fn load(paths: &Paths) -> Result<Project, CliError> {
    Ok(Project::load(paths)?)
}

/// The binary that backends see as `$PLC_CONFORMANCE`.
pub(super) fn this_binary() -> PathBuf {
    std::env::current_exe().unwrap_or_else(|_| PathBuf::from("plc-conformance"))
}

/// The project file, and whether it was named (then it must exist): `--config`,
/// `$PLC_CONFORMANCE_CONFIG`, else the project folder's, else none.
pub(super) fn project_file_path(cli: &Cli) -> Result<Option<(PathBuf, bool)>, CliError> {
    if let Some(f) = &cli.config {
        return Ok(Some((f.clone(), true)));
    }
    Ok(match project_root(cli)? {
        Some(root) => Some(locate_project(&root)),
        // Without a project folder only an explicitly named file counts.
        None => Some(locate_project(Path::new("."))).filter(|(_, explicit)| *explicit),
    })
}

/// The project file's backends; a bad file is reported here.
pub(super) fn project_file(cli: &Cli) -> Result<ProjectBackends, CliError> {
    match project_file_path(cli)? {
        Some((file, explicit)) => Ok(load_project(&file, explicit, &this_binary())?),
        None => Ok(ProjectBackends::default()),
    }
}

/// Sets up the backends a command asks for in `session` (every external backend has agreed on
/// the protocol before a case runs) and returns them, in the order given.
pub(super) fn start(
    session: &mut Session,
    cli: &Cli,
    file: &ProjectBackends,
    args: &BackendArgs,
) -> Result<Vec<Arc<dyn Backend>>, CliError> {
    set_up(session, cli, file, args, false)
}

fn set_up(
    session: &mut Session,
    cli: &Cli,
    file: &ProjectBackends,
    args: &BackendArgs,
    references: bool,
) -> Result<Vec<Arc<dyn Backend>>, CliError> {
    // A command that reads another corpus (`--vectors`) need not have every case a
    // known-differences file names.
    let own_corpus = args.vectors.is_empty();
    let before = session.backends.len();
    let binary = this_binary();
    let chosen = Asked {
        texts: &args.backends,
        known_differences: &args.known_differences,
        in_process: &cli.in_process.0,
        file,
        timeout: args.timeout,
        max_faults: args.max_faults,
        binary: &binary,
        references,
    }
    .sources(session)?;
    for source in chosen.sources {
        session.add(source, own_corpus)?;
    }
    Ok(match args.backends.is_empty() {
        true => session.backends[before..].to_vec(),
        false => (chosen.names.iter())
            .filter_map(|name| session.backend(name).cloned())
            .collect(),
    })
}

/// A loaded project with the chosen backends set up, and the project file they came from.
pub(super) struct Prepared {
    pub session: Session,
    pub file: ProjectBackends,
    pub backends: Vec<Arc<dyn Backend>>,
}

pub(super) fn prepare(cli: &Cli, args: &BackendArgs) -> Result<Prepared, CliError> {
    prepare_with(cli, args, false)
}

/// [`prepare`] with the reference models always there, and first.
pub(super) fn prepare_with_references(cli: &Cli, args: &BackendArgs) -> Result<Prepared, CliError> {
    prepare_with(cli, args, true)
}

fn prepare_with(cli: &Cli, args: &BackendArgs, references: bool) -> Result<Prepared, CliError> {
    let mut session = Session::new(load(&paths(cli, &args.vectors, "--vectors")?)?);
    // Only a command that names backends, or runs them all, starts the project file's.
    let file = match references && args.backends.is_empty() {
        true => ProjectBackends::default(),
        false => project_file(cli)?,
    };
    let backends = set_up(&mut session, cli, &file, args, references)?;
    Ok(Prepared {
        session,
        file,
        backends,
    })
}
