//! `validate`, `list`, `schema` and `serve`: the commands that run no trial.

use std::collections::BTreeSet;
use std::path::PathBuf;

use std::fmt::Write as _;

use clap::{CommandFactory, Parser};

use super::backends::{load, paths, prepare, project_file, project_file_path, Prepared};
use super::{output, BackendArgs, Cli, CliError, Outcome, EXIT_OK};
use crate::backend::external::{protocol, serve as protocol_serve};
use crate::load::{load_corpus, load_open_questions, load_profiles, OPEN_QUESTIONS};
use crate::report::text::case_line;
use crate::session::Session;
use crate::spec;
use crate::spec::SchemaKind;

pub(super) fn validate(cli: &Cli, given: &[PathBuf]) -> Outcome {
    let paths = paths(cli, given, "validate")?;
    let profiles = load_profiles(&paths.vendors)?;
    let corpus = load_corpus(&paths.vectors, &profiles)?;
    let questions = super::backends::project_root(cli)?.map(|r| r.join(OPEN_QUESTIONS));
    let mut open = 0;
    if let (true, Some(questions)) = (given.is_empty(), questions.filter(|q| q.exists())) {
        open = load_open_questions(&questions, &profiles, &corpus)?.len();
    }
    let files: BTreeSet<&PathBuf> = corpus
        .cases
        .iter()
        .map(|c| &c.location.file)
        .chain(corpus.cross_vendor.iter().map(|c| &c.location.file))
        .chain(corpus.protocol_fields.iter().map(|c| &c.location.file))
        .collect();
    output::write(
        None,
        &format!(
            "ok: {}, {} and {} in {}, {}, {}, {}",
            counted(corpus.cases.len(), "case"),
            counted(corpus.cross_vendor.len(), "cross-vendor case"),
            counted(corpus.protocol_fields.len(), "protocol-field case"),
            counted(files.len(), "file"),
            counted(profiles.iter().count(), "profile"),
            counted(profiles.protocols.iter().count(), "protocol"),
            counted(open, "open question"),
        ),
    )?;
    Ok(EXIT_OK)
}

/// `1 file`, `2 files`: English nouns of the summary line, all of which take an `s`.
fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// The trials the named backends would run, and why each of the others would not run: skipped
/// (not claimed, declined, a variant or device the backend lacks) or ignored (recorded only,
/// a listed known difference), as `run` and `cargo test` would treat them.
pub(super) fn trials(cli: &Cli, filter: Option<&str>, names: &[String]) -> Outcome {
    // The backends as `run --backend` takes them, with its defaults for everything else.
    let argv = ["list"]
        .into_iter()
        .chain(names.iter().flat_map(|n| ["--backend", n.as_str()]));
    let args = BackendOnly::try_parse_from(argv)
        .map_err(|e| CliError::input(e.to_string()))?
        .args;
    let Prepared {
        session, backends, ..
    } = prepare(cli, &args)?;
    let trials = session.plan(&backends);
    let mut out = String::new();
    for backend in &backends {
        let mine: Vec<_> = (trials.iter())
            .filter(|t| t.backend.name() == backend.name())
            .filter(|t| filter.is_none_or(|f| t.name().contains(f)))
            .collect();
        let run = mine
            .iter()
            .filter(|t| t.ignored_because().is_none())
            .count();
        let _ = writeln!(
            out,
            "{}: {} trials, {run} run, {} skipped or ignored",
            backend.name(),
            mine.len(),
            mine.len() - run
        );
        for t in mine {
            let _ = match (&t.skip, t.ignored_because()) {
                (Some(why), _) => writeln!(out, "  skip    {}: {why}", t.name()),
                (None, Some(why)) => writeln!(out, "  ignore  {}: {why}", t.name()),
                (None, None) => writeln!(out, "  run     {}", t.name()),
            };
        }
    }
    output::write(None, &out)?;
    Ok(EXIT_OK)
}

/// `run`'s backend arguments alone, parsed for `list --backend`.
#[derive(clap::Parser)]
struct BackendOnly {
    #[command(flatten)]
    args: BackendArgs,
}

pub(super) fn list(cli: &Cli, filter: Option<&str>) -> Outcome {
    let paths = paths(cli, &[], "--vectors")?;
    let session = Session::with_references(load(&paths)?);
    let (file, file_path) = (project_file(cli)?, project_file_path(cli)?);
    // Written whole at the end: a closed pipe is then one error, not a panic mid-list.
    let mut out = String::new();
    let _ = writeln!(
        out,
        "data: profiles {}, vectors {}, project file {}",
        paths.vendors.display(),
        paths
            .vectors
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        file_path
            .filter(|(f, explicit)| *explicit || f.exists())
            .map_or_else(|| "none".to_string(), |(f, _)| f.display().to_string())
    );
    let _ = writeln!(out, "backends:");
    let width = session
        .backends
        .iter()
        .map(|b| b.name().len())
        .chain(file.configured.iter().map(|c| c.settings.name.len()))
        .max()
        .unwrap_or(0)
        .max(10);
    for b in &session.backends {
        let _ = writeln!(
            out,
            "  {:<width$} profile {:<18} {}",
            b.name(),
            b.profile(),
            b.describe()
        );
    }
    for c in &file.configured {
        let _ = writeln!(
            out,
            "  {:<width$} profile {:<18} external{}, configured at {} (`{}`)",
            c.settings.name,
            c.settings
                .profile
                .as_deref()
                .unwrap_or("(from its handshake)"),
            if c.on_request { " (on request)" } else { "" },
            c.location,
            c.settings.launch
        );
    }
    for skipped in &file.skipped {
        let _ = writeln!(out, "  (skipped: {skipped})");
    }
    list_profiles(&mut out, &session.profiles);
    let _ = writeln!(out, "cases:");
    let mut shown = 0;
    for case in &session.corpus.cases {
        let line = case_line(case);
        if filter.is_none_or(|f| line.contains(f)) {
            let _ = writeln!(out, "  {line}");
            shown += 1;
        }
    }
    let _ = write!(out, "{shown} of {} cases", session.corpus.cases.len());
    output::write(None, &out)?;
    Ok(EXIT_OK)
}

/// The profiles with their instructions and variants, and the protocols with their fields.
fn list_profiles(out: &mut String, profiles: &crate::model::profile::Profiles) {
    let _ = writeln!(out, "profiles:");
    for p in profiles.iter() {
        let _ = writeln!(
            out,
            "  {:<18} {} — instructions: {}",
            p.id,
            p.name,
            p.instructions
                .keys()
                .cloned()
                .collect::<Vec<_>>()
                .join(", ")
        );
        for v in &p.variants {
            let _ = writeln!(out, "    variant {:<22} {}", v.id, v.description);
        }
    }
    let _ = writeln!(out, "protocols:");
    for p in profiles.protocols.iter() {
        let fields: Vec<&str> = p.fields.keys().map(String::as_str).collect();
        let _ = writeln!(
            out,
            "  {:<18} {} — fields: {}",
            p.id,
            p.name,
            fields.join(", ")
        );
    }
}

pub(super) fn schema(kind: SchemaKind) -> Outcome {
    let schema = spec::schema(kind).unwrap_or_else(protocol::protocol_schema);
    output::write(
        None,
        &serde_json::to_string_pretty(&schema).unwrap_or_default(),
    )?;
    Ok(EXIT_OK)
}

/// `serve`: the reference model of a profile, over the protocol on stdin/stdout.
pub(super) fn serve(cli: &Cli, profile_id: &str) -> Outcome {
    let paths = paths(cli, &[], "--vectors")?;
    let profiles = load_profiles(&paths.vendors)?;
    let Some(profile) = profiles.get(profile_id) else {
        return Err(CliError::input(format!(
            "unknown profile `{profile_id}`; expected one of: {}",
            profiles.ids().join(", ")
        )));
    };
    let Some(backend) = crate::backend::reference_model(&profiles, profile_id) else {
        return Err(CliError::input(format!(
            "profile `{profile_id}` has no built-in reference model"
        )));
    };
    let stdin = std::io::stdin().lock();
    let stdout = std::io::BufWriter::with_capacity(64 * 1024, std::io::stdout().lock());
    protocol_serve::serve(backend.as_ref(), profile, stdin, stdout)?;
    Ok(EXIT_OK)
}

/// `completions SHELL`: the completion script of every command and option.
pub(super) fn completions(shell: clap_complete::Shell) -> Outcome {
    let mut command = Cli::command();
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command, "plc-conformance", &mut script);
    let mut out = output::Sink::open(None)?;
    std::io::Write::write_all(&mut out, &script).map_err(|e| out.error(e))?;
    out.finish()?;
    Ok(EXIT_OK)
}

/// `man`: the manual page, in roff.
/// The command as the manual describes it: `help` is clap's, with no page of its own.
fn manual_command() -> clap::Command {
    Cli::command().disable_help_subcommand(true)
}

/// The main page names a page per command (`plc-conformance-run(1)`): `--dir` writes them all,
/// so that every page named exists.
pub(super) fn man(dir: Option<&std::path::Path>) -> Outcome {
    if let Some(dir) = dir {
        if !dir.is_dir() {
            return Err(CliError::input(format!(
                "{}: not a folder; create it first",
                dir.display()
            )));
        }
        clap_mangen::generate_to(manual_command(), dir)
            .map_err(|e| CliError::write(Some(dir), e))?;
        return Ok(EXIT_OK);
    }
    let page = clap_mangen::Man::new(manual_command());
    let mut roff = Vec::new();
    page.render(&mut roff)
        .map_err(|e| CliError::write(None, e))?;
    let mut out = output::Sink::open(None)?;
    std::io::Write::write_all(&mut out, &roff).map_err(|e| out.error(e))?;
    out.finish()?;
    Ok(EXIT_OK)
}
