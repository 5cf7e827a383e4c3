//! `validate`, `list`, `schema` and `serve`: the commands that run no trial.

use std::collections::BTreeSet;
use std::path::PathBuf;

use anstream::{eprintln, println};

use clap::CommandFactory;

use super::backends::{load, paths, project_file, project_file_path, report_load_errors};
use super::{Cli, SchemaKind, EXIT_BAD_INPUT, EXIT_OK};
use crate::backend::external::{protocol, serve as protocol_serve};
use crate::load::{load_corpus, load_open_questions, load_profiles, OPEN_QUESTIONS};
use crate::report::text::case_line;
use crate::spec;

pub fn validate(cli: &Cli, given: &[PathBuf]) -> u8 {
    let paths = match paths(cli, given, "validate") {
        Ok(p) => p,
        Err(code) => return code,
    };
    let profiles = match load_profiles(&paths.vendors) {
        Ok(p) => p,
        Err(e) => return report_load_errors(&e),
    };
    match load_corpus(&paths.vectors, &profiles) {
        Ok(corpus) => {
            let questions = match super::backends::project_root(cli) {
                Ok(root) => root.map(|r| r.join(OPEN_QUESTIONS)),
                Err(code) => return code,
            };
            let mut open = 0;
            if let (true, Some(questions)) = (given.is_empty(), questions.filter(|q| q.exists())) {
                match load_open_questions(&questions, &profiles, &corpus) {
                    Ok(q) => open = q.len(),
                    Err(e) => return report_load_errors(&e),
                }
            }
            let files: BTreeSet<&PathBuf> = corpus
                .cases
                .iter()
                .map(|c| &c.location.file)
                .chain(corpus.cross_vendor.iter().map(|c| &c.location.file))
                .collect();
            println!(
                "ok: {} cases and {} cross-vendor cases in {} files, {} profiles, {open} open \
                 questions",
                corpus.cases.len(),
                corpus.cross_vendor.len(),
                files.len(),
                profiles.iter().count()
            );
            EXIT_OK
        }
        Err(e) => report_load_errors(&e),
    }
}

pub fn list(cli: &Cli, filter: Option<&str>) -> u8 {
    let paths = match paths(cli, &[], "--vectors") {
        Ok(p) => p,
        Err(code) => return code,
    };
    let project = match load(&paths) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let (file, file_path) = match (project_file(cli), project_file_path(cli)) {
        (Ok(p), Ok(path)) => (p, path),
        (Err(code), _) | (_, Err(code)) => return code,
    };
    println!(
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
    println!("backends:");
    let width = project
        .backends
        .iter()
        .map(|b| b.name().len())
        .chain(file.configured.iter().map(|c| c.settings.name.len()))
        .max()
        .unwrap_or(0)
        .max(10);
    for b in &project.backends {
        println!(
            "  {:<width$} profile {:<18} {}",
            b.name(),
            b.profile(),
            b.describe()
        );
    }
    for c in &file.configured {
        println!(
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
        println!("  (skipped: {skipped})");
    }
    println!("profiles:");
    for p in project.profiles.iter() {
        println!(
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
            println!("    variant {:<22} {}", v.id, v.description);
        }
    }
    println!("cases:");
    let mut shown = 0;
    for case in &project.corpus.cases {
        let line = case_line(case);
        if filter.is_none_or(|f| line.contains(f)) {
            println!("  {line}");
            shown += 1;
        }
    }
    println!("{shown} of {} cases", project.corpus.cases.len());
    EXIT_OK
}

pub fn schema(kind: SchemaKind) -> u8 {
    let schema = match kind {
        SchemaKind::Vectors => spec::schema(spec::SchemaKind::Vectors),
        SchemaKind::Profile => spec::schema(spec::SchemaKind::Profile),
        SchemaKind::CrossVendor => spec::schema(spec::SchemaKind::CrossVendor),
        SchemaKind::Project => spec::schema(spec::SchemaKind::Project),
        SchemaKind::Known => spec::schema(spec::SchemaKind::Known),
        SchemaKind::OpenQuestions => spec::schema(spec::SchemaKind::OpenQuestions),
        SchemaKind::Protocol => protocol::protocol_schema(),
    };
    println!(
        "{}",
        serde_json::to_string_pretty(&schema).unwrap_or_default()
    );
    EXIT_OK
}

/// `serve`: the reference model of a profile, over the protocol on stdin/stdout.
pub fn serve(cli: &Cli, profile_id: &str) -> u8 {
    let paths = match paths(cli, &[], "--vectors") {
        Ok(p) => p,
        Err(code) => return code,
    };
    let profiles = match load_profiles(&paths.vendors) {
        Ok(p) => p,
        Err(e) => return report_load_errors(&e),
    };
    let Some(profile) = profiles.get(profile_id) else {
        eprintln!(
            "error: unknown profile `{profile_id}`; expected one of: {}",
            profiles.ids().join(", ")
        );
        return EXIT_BAD_INPUT;
    };
    let backends = crate::backend::reference_backends(&profiles);
    let Some(backend) = backends.iter().find(|b| b.profile() == profile_id) else {
        eprintln!("error: profile `{profile_id}` has no built-in reference model");
        return EXIT_BAD_INPUT;
    };
    let stdin = std::io::stdin().lock();
    let stdout = std::io::BufWriter::with_capacity(64 * 1024, std::io::stdout().lock());
    match protocol_serve::serve(backend.as_ref(), profile, stdin, stdout) {
        Ok(()) => EXIT_OK,
        Err(message) => {
            eprintln!("error: {message}");
            EXIT_BAD_INPUT
        }
    }
}

/// `completions SHELL`: the completion script of every command and option.
pub fn completions(shell: clap_complete::Shell) -> u8 {
    let mut command = Cli::command();
    clap_complete::generate(
        shell,
        &mut command,
        "plc-conformance",
        &mut std::io::stdout(),
    );
    EXIT_OK
}

/// `man`: the manual page, in roff.
pub fn man() -> u8 {
    let page = clap_mangen::Man::new(Cli::command());
    let mut out = Vec::new();
    if let Err(e) = page.render(&mut out) {
        eprintln!("error: cannot write the manual page: {e}");
        return EXIT_BAD_INPUT;
    }
    let _ = std::io::Write::write_all(&mut std::io::stdout(), &out);
    EXIT_OK
}
