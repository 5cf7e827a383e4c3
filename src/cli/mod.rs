//! The `plc-conformance` command line.
//!
//! Exit codes: 0 when everything ran conforms (or the input is valid), 1 when a backend differs
//! from the corpus, 2 for bad input or usage.

mod commands;
mod diff;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

#[derive(Debug, Parser)]
#[command(
    name = "plc-conformance",
    version,
    about = "Differential conformance harness for PLC instructions",
    long_about = "Runs a corpus of test vectors taken from vendor manuals against reference models \
                  of MELSEC iQ-R, MELSEC iQ-F FX5 and IDEC MicroSmart, and against emulators \
                  plugged in from outside, and reports every semantic difference as a diff.\n\n\
                  Exit status: 0 conforms / valid, 1 differences found, 2 bad input or usage."
)]
pub struct Cli {
    /// Project root holding `vendors/` and `vectors/`.
    #[arg(long, global = true, default_value = ".", value_name = "DIR")]
    pub root: PathBuf,
    /// Vendor profile folder [default: ROOT/vendors].
    #[arg(long, global = true, value_name = "DIR")]
    pub vendors: Option<PathBuf>,
    /// Project file listing external backends [default: $PLC_CONFORMANCE_CONFIG, else
    /// ROOT/plc-conformance.yaml when it exists].
    #[arg(long, global = true, value_name = "FILE")]
    pub config: Option<PathBuf>,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the corpus against backends and report differences.
    Run(RunArgs),
    /// Compare backends: matrices of cases x backends with rows grouped by behaviour.
    Diff(diff::DiffArgs),
    /// Check vector files (and the vendor profiles) without running anything.
    Validate {
        /// Vector files or folders [default: ROOT/vectors].
        paths: Vec<PathBuf>,
    },
    /// List backends, profiles with their variants, and cases.
    List {
        /// Only cases whose id, instruction or file contains this text.
        #[arg(long)]
        filter: Option<String>,
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
}

#[derive(Debug, clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub backends: BackendArgs,
    /// Only trials whose name (`backend::instruction::case::variant`) contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Vector files or folders [default: ROOT/vectors].
    #[arg(long = "vectors", value_name = "PATH")]
    pub vectors: Vec<PathBuf>,
    /// Also print what each backend did on `unspecified` cases.
    #[arg(long)]
    pub show_recorded: bool,
}

/// Which backends a command runs, shared by `run` and `diff`.
#[derive(Debug, Clone, clap::Args)]
pub struct BackendArgs {
    /// Backends to run: a name (see `list`), or `external:NAME=COMMAND` to start a process that
    /// speaks the external-backend protocol (COMMAND is run by `sh -c`); repeat for several
    /// [default: the built-in ones and those of the project file].
    #[arg(long = "backend", value_name = "NAME")]
    pub backends: Vec<String>,
    /// Seconds an `external:` backend given here may take to answer one case.
    #[arg(long, value_name = "SECONDS", default_value_t = 5.0)]
    pub timeout: f64,
    /// A known-differences file for an `external:` backend given here.
    #[arg(long = "known-differences", value_name = "NAME=FILE")]
    pub known_differences: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Text,
    Json,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SchemaKind {
    /// Vector files (`vectors/<family>/*.yaml`).
    Vectors,
    /// Vendor profiles (`vendors/*.yaml`).
    Profile,
    /// Cross-vendor vector files (`vectors/cross-vendor/*.yaml`).
    CrossVendor,
    /// The messages of the external-backend protocol.
    Protocol,
    /// The project file, `plc-conformance.yaml`.
    Project,
    /// A known-differences file.
    Known,
}

/// Parses the arguments, runs the command and returns its exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    ExitCode::from(commands::dispatch(&cli))
}
