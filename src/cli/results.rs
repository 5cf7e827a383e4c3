//! `results`: the results table of the libraries' saved runs (`docs/results.md` and its HTML
//! page), written, or checked against the committed files.

use std::path::{Path, PathBuf};

use super::backends::{paths, project_root};
use super::output;
use super::{Cli, CliError, Outcome, EXIT_DIFFERENCES, EXIT_OK};
use crate::load::{load_corpus, load_libraries, load_profiles};
use crate::report::{baseline, console, results};

#[derive(Debug, clap::Args)]
pub(crate) struct ResultsArgs {
    /// The libraries' saved runs: JSON reports (`run --format json` or `--save`), any number of
    /// backends in each.
    #[arg(required = true, value_name = "RUN")]
    pub runs: Vec<PathBuf>,
    /// The list of libraries, in the table's order [default: ROOT/libraries.yaml].
    #[arg(long, value_name = "FILE")]
    pub libraries: Option<PathBuf>,
    /// Write the table and its reproductions as markdown to this file.
    #[arg(long, value_name = "FILE")]
    pub markdown: Option<PathBuf>,
    /// Write the same page as self-contained HTML to this file.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
    /// Compare with the files given instead of writing them: exit 1, with the first lines
    /// that differ, when one is stale.
    #[arg(long)]
    pub check: bool,
}

pub(super) fn results(cli: &Cli, args: &ResultsArgs) -> Outcome {
    let root = project_root(cli)?;
    let list = match (&args.libraries, &root) {
        (Some(file), _) => file.clone(),
        (None, Some(root)) => root.join("libraries.yaml"),
        (None, None) => {
            return Err(CliError::input(
                "--libraries: no project folder, so no libraries.yaml (pass --libraries FILE)",
            ))
        }
    };
    if args.markdown.is_none() && args.html.is_none() {
        return Err(CliError::input(
            "results: give --markdown FILE and/or --html FILE (to write, or with --check to \
             compare)",
        ));
    }
    let paths = paths(cli, &[], "results")?;
    let profiles = load_profiles(&paths.vendors)?;
    let corpus = load_corpus(&paths.vectors, &profiles)?;
    let libraries = load_libraries(&list, &profiles.protocols)?;
    let runs = args
        .runs
        .iter()
        .map(|p| baseline::load(p))
        .collect::<Result<Vec<_>, _>>()?;
    let table = results::table(&libraries, &runs, &corpus, &profiles.protocols)
        .map_err(|e| CliError::within(list.display().to_string(), e))?;
    let documents = [
        (args.markdown.as_deref(), results::markdown(&table)),
        (args.html.as_deref(), results::html(&table)),
    ];
    let mut stale = false;
    for (path, text) in documents {
        let Some(path) = path else { continue };
        if args.check {
            stale |= !same(path, &text);
        } else {
            output::write(Some(path), &text)?;
        }
    }
    Ok(if stale { EXIT_DIFFERENCES } else { EXIT_OK })
}

/// Lines of the stale file's diff shown at most.
const DIFF_LINES: usize = 40;

/// Whether the file holds `text`; if not, says so with the start of a unified diff of the
/// committed file against what the runs give.
fn same(path: &Path, text: &str) -> bool {
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    if committed == text {
        return true;
    }
    let diff = similar::TextDiff::from_lines(committed.as_str(), text);
    let shown = diff
        .unified_diff()
        .context_radius(1)
        .header("committed", "from the runs")
        .to_string();
    let lines: Vec<&str> = shown.lines().collect();
    console::status(&format!(
        "{} is stale (regenerate it with .ci/results):\n{}{}",
        path.display(),
        lines[..lines.len().min(DIFF_LINES)].join("\n"),
        if lines.len() > DIFF_LINES {
            format!("\n... {} more diff lines", lines.len() - DIFF_LINES)
        } else {
            String::new()
        }
    ));
    false
}
