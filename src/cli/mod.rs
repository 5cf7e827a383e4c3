//! The `plc-conformance` command line: argument parsing here, each command in its own file, all
//! of them calling into the library. Errors are rendered once, at this edge.
//!
//! Exit codes: 0 when everything ran conforms (or the input is valid), 1 when a backend differs
//! from the corpus, 2 for bad input or usage, 128 + the signal when SIGINT (130) or SIGTERM
//! (143) interrupted a run.

mod backends;
mod error;
mod hil;
mod info;
mod init;
mod output;
mod record;
mod results;
mod run;
mod sweep;

use std::path::PathBuf;
use std::process::ExitCode;

use crate::spec::SchemaKind;
use clap::{Parser, Subcommand, ValueEnum};

pub(crate) use error::CliError;

pub(crate) const EXIT_OK: u8 = 0;
pub(crate) const EXIT_DIFFERENCES: u8 = 1;
pub(crate) const EXIT_BAD_INPUT: u8 = 2;

/// What a command ends with: its exit status (0 or 1), or the error that stopped it (2).
pub(crate) type Outcome = Result<u8, CliError>;

use crate::report::console;
pub(crate) use crate::report::document::Format;

#[derive(Debug, Parser)]
#[command(
    name = "plc-conformance",
    version,
    about = "Differential conformance harness for PLC instructions",
    long_about = "Runs a corpus of test vectors taken from vendor manuals against reference models \
                  of ten families (MELSEC iQ-R, MELSEC iQ-F FX5, MELSEC FX3, IDEC MicroSmart \
                  FC4A, Siemens S7-1200/S7-1500, Siemens S7-200/S7-200 SMART, Delta DVP, \
                  Panasonic FP, KEYENCE KV and Omron CS/CJ/CP), against emulators and libraries \
                  plugged in from outside, and against a live CPU on a bench (MELSEC over SLMP, \
                  IDEC over Modbus TCP), and reports every \
                  semantic difference as a diff.\n\n\
                  Exit status: 0 conforms / valid, 1 differences found, 2 bad input or usage."
)]
pub(crate) struct Cli {
    /// Project folder holding `plc-conformance.yaml`, or `vendors/` and `vectors/` [default: the
    /// nearest such folder at or above the current one, else the profiles and corpus built into
    /// plc-conformance].
    #[arg(long, global = true, value_name = "DIR", help_heading = GLOBAL)]
    pub root: Option<PathBuf>,
    /// Vendor profile folder [default: ROOT/vendors].
    #[arg(long, global = true, value_name = "DIR", help_heading = GLOBAL)]
    pub vendors: Option<PathBuf>,
    /// Project file listing external backends [default: $PLC_CONFORMANCE_CONFIG, else
    /// ROOT/plc-conformance.yaml when it exists].
    #[arg(long, global = true, value_name = "FILE", help_heading = GLOBAL)]
    pub config: Option<PathBuf>,
    /// When to colour the output.
    #[arg(long, global = true, value_enum, default_value_t = Color::Auto, help_heading = GLOBAL)]
    pub color: Color,
    /// Print only failures and the closing counts: no progress, notes or lists of known
    /// differences and skips.
    #[arg(short, long, global = true, help_heading = GLOBAL)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
    /// Backends written in Rust that the binary was built with ([`main_with`]).
    #[arg(skip)]
    pub in_process: InProcess,
}

/// Backends in process, chosen by name with `--backend`.
#[derive(Clone, Default)]
pub(crate) struct InProcess(pub Vec<std::sync::Arc<dyn crate::backend::Backend>>);

impl std::fmt::Debug for InProcess {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|b| b.name()))
            .finish()
    }
}

/// The heading of the options every command takes.
const GLOBAL: &str = "Global options";

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Color {
    /// On a terminal, unless NO_COLOR is set.
    Auto,
    Always,
    Never,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Run the corpus against backends and report differences.
    Run(RunArgs),
    /// Compare backends: matrices of cases x backends with rows grouped by behaviour.
    Diff(DiffArgs),
    /// Check vector files (and the vendor profiles) without running anything.
    Validate {
        /// Vector files or folders [default: ROOT/vectors].
        paths: Vec<PathBuf>,
    },
    /// List backends, profiles with their variants, and cases; with `--backend`, the trials a
    /// backend would run and why it would not run the others.
    List {
        /// Only cases whose id, instruction or file contains this text (with `--backend`: only
        /// trials whose name contains it).
        #[arg(long)]
        filter: Option<String>,
        /// Show this backend's trials instead: a name (see `list`) or `external:NAME=COMMAND`
        /// (started, to hear what it implements); repeat for several.
        #[arg(long = "backend", value_name = "NAME")]
        backends: Vec<String>,
    },
    /// Print the JSON Schema (draft-07) of vector files, vendor profiles, cross-vendor files,
    /// the external-backend protocol's messages, the project file or a known-differences file.
    Schema {
        #[arg(long, value_enum, default_value_t = SchemaKind::Vectors)]
        kind: SchemaKind,
    },
    /// Speak the external-backend protocol on stdin/stdout with a built-in reference model:
    /// proves the protocol path end to end, and serves as a native adapter for benchmarks.
    Serve {
        /// The profile whose reference model answers.
        #[arg(long, value_name = "ID")]
        profile: String,
    },
    /// Print a completion script for a shell, e.g.
    /// `plc-conformance completions bash > ~/.local/share/bash-completion/completions/plc-conformance`.
    Completions {
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff), e.g. `plc-conformance man | man -l -`; with --dir, write
    /// it and the page of every command it names (`plc-conformance-run.1`, ...) into a folder.
    Man {
        /// The folder to write every page into (`man1/` of a MANPATH entry, say).
        #[arg(long, value_name = "DIR")]
        dir: Option<PathBuf>,
    },
    /// Generate inputs for an operation or an instruction, run them on several backends, group
    /// the inputs they disagree on by behaviour and shrink each group to a minimal vector.
    Sweep(sweep::SweepArgs),
    /// Write what a backend did into the vectors as `observed` expectations, with provenance;
    /// fill in the outcome of `unspecified` cases; never overwrite a `manual` expectation.
    Record(record::RecordArgs),
    /// Start checking a library: write a commented adapter (Python, JavaScript or Rust), an
    /// empty known-differences file and a CI job.
    Init {
        #[command(subcommand)]
        command: init::InitCommand,
    },
    /// The results table of real libraries (docs/results.md): one row per library, one column
    /// per class of rule of its protocol, from the libraries' saved runs; with --check, whether
    /// the committed table is stale.
    Results(results::ResultsArgs),
    /// A real CPU on a bench (MELSEC over SLMP, IDEC over Modbus TCP): generate its test program,
    /// look at the bench read-only, dry-run a live backend, or serve a simulated CPU on
    /// 127.0.0.1.
    Hil {
        #[command(subcommand)]
        command: hil::HilCommand,
    },
}

#[derive(Debug, clap::Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    pub backends: BackendArgs,
    #[command(flatten)]
    pub report: ReportArgs,
    /// Output format: `text` lists each failure as it happens, then the counts.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Also print what each backend did on `unspecified` cases (text format).
    #[arg(long)]
    pub show_recorded: bool,
    /// Only the probes of the open questions (docs/open-questions.yaml): the cases whose
    /// outcome on a real CPU settles a question; give a question id for its probes alone.
    #[arg(long, value_name = "QUESTION", num_args = 0..=1, default_missing_value = "")]
    pub probes: Option<String>,
}

#[derive(Debug, clap::Args)]
pub(crate) struct DiffArgs {
    #[command(flatten)]
    pub backends: BackendArgs,
    #[command(flatten)]
    pub report: ReportArgs,
    /// Report format: `text` is the grouped matrices (coloured on a terminal).
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Compare the (first) chosen backend directly with this one, word by word.
    #[arg(long, value_name = "NAME")]
    pub against: Option<String>,
}

/// Which backends and trials a command runs, shared by `run` and `diff`.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct BackendArgs {
    /// Backends to run: a name (see `list`), or `external:NAME=COMMAND` to start a process that
    /// speaks the external-backend protocol (COMMAND is run by `sh -c`); repeat for several
    /// [default: the built-in ones and those of the project file].
    #[arg(long = "backend", value_name = "NAME")]
    pub backends: Vec<String>,
    /// Seconds an `external:` backend given here may take to answer one case.
    #[arg(long, value_name = "SECONDS", default_value = "5", value_parser = seconds)]
    pub timeout: std::time::Duration,
    /// Faults (crash, timeout, protocol error) in a row after which an `external:` backend
    /// given here is not asked any more: its remaining trials fail as not run.
    #[arg(long, value_name = "N", default_value_t = crate::model::project::DEFAULT_MAX_CONSECUTIVE_FAULTS)]
    pub max_faults: usize,
    /// Let a named or configured backend run no trial (every one skipped) without failing.
    #[arg(long)]
    pub allow_empty: bool,
    /// A known-differences file for an `external:` backend given here.
    #[arg(long = "known-differences", value_name = "NAME=FILE")]
    pub known_differences: Vec<String>,
    /// Only trials whose name (`backend::instruction::case::variant`, or
    /// `cross-vendor::backend::lowering::case::variant`) contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// Vector files or folders [default: ROOT/vectors].
    #[arg(long = "vectors", value_name = "PATH")]
    pub vectors: Vec<PathBuf>,
    /// Backends run side by side [default: the number of CPUs].
    #[arg(short = 'j', long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Stop at the first failing trial: no further batch starts (trials already sent to a
    /// backend finish and are reported).
    #[arg(long)]
    pub fail_fast: bool,
}

impl BackendArgs {
    /// Backends run side by side: `--jobs`, or one per CPU.
    pub(crate) fn jobs(&self) -> usize {
        self.jobs.unwrap_or_else(crate::execute::default_jobs)
    }
}

/// Where a report goes and how it is compared, shared by `run` and `diff`.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct ReportArgs {
    /// Write the report to this file instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also save the results (the JSON report) for a later `--baseline`.
    #[arg(long, value_name = "FILE")]
    pub save: Option<PathBuf>,
    /// Compare with a saved run: list new, fixed and changed differences, and fail only on new
    /// ones.
    #[arg(long, value_name = "FILE")]
    pub baseline: Option<PathBuf>,
}

/// `--timeout SECONDS` of a case: above 0 and at most a day, read the same way by every
/// command that takes it.
pub(crate) fn seconds(text: &str) -> Result<std::time::Duration, CliError> {
    text.parse::<f64>()
        .ok()
        .filter(|s| s.is_finite() && *s > 0.0 && *s <= 86_400.0)
        .map(std::time::Duration::from_secs_f64)
        .ok_or_else(|| CliError::input(format!("`{text}`: give seconds above 0 and at most a day")))
}

/// Parses the arguments, runs the command and returns its exit status.
pub(crate) fn main() -> ExitCode {
    main_with(Vec::new())
}

/// The command line with backends written in Rust beside the built-in ones.
pub(crate) fn main_with(in_process: Vec<std::sync::Arc<dyn crate::backend::Backend>>) -> ExitCode {
    let mut cli = Cli::parse();
    cli.in_process = InProcess(in_process);
    match cli.color {
        Color::Always => anstream::ColorChoice::Always.write_global(),
        Color::Never => anstream::ColorChoice::Never.write_global(),
        Color::Auto => {}
    }
    if matches!(
        cli.command,
        Command::Run(_) | Command::Diff(_) | Command::Sweep(_) | Command::Record(_)
    ) {
        if let Err(e) = crate::interrupt::install(crate::interrupt::OnSignal::Finish) {
            console::warning(&format!("SIGINT and SIGTERM are not handled: {e}"));
        }
        crate::backend::external::adopt_orphans();
    }
    let outcome = match &cli.command {
        Command::Run(args) => run::run(&cli, args),
        Command::Diff(args) => run::diff(&cli, args),
        Command::Validate { paths } => info::validate(&cli, paths),
        Command::List { filter, backends } if !backends.is_empty() => {
            info::trials(&cli, filter.as_deref(), backends)
        }
        Command::List { filter, .. } => info::list(&cli, filter.as_deref()),
        Command::Schema { kind } => info::schema(*kind),
        Command::Serve { profile } => info::serve(&cli, profile),
        Command::Completions { shell } => info::completions(*shell),
        Command::Man { dir } => info::man(dir.as_deref()),
        Command::Sweep(args) => sweep::sweep(&cli, args),
        Command::Record(args) => record::record_command(&cli, args),
        Command::Results(args) => results::results(&cli, args),
        Command::Hil { command } => hil::hil(&cli, command),
        Command::Init { command } => init::init(command),
    };
    // Errors are rendered here and nowhere else.
    let code = outcome.unwrap_or_else(|e| {
        console::error(&crate::error_chain::chain(&e));
        e.exit_status()
    });
    // An interrupted run ends as an interruption, whatever it found before.
    ExitCode::from(crate::interrupt::exit_status().unwrap_or(code))
}
