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
    /// Print the JSON Schema (draft-07) of vector files, vendor profiles or cross-vendor files.
    Schema {
        #[arg(long, value_enum, default_value_t = SchemaKind::Vectors)]
        kind: SchemaKind,
    },
}

#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Backends to run, by name (see `list`); repeat for several [default: all built-in].
    #[arg(long = "backend", value_name = "NAME")]
    pub backends: Vec<String>,
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
}

/// Parses the arguments, runs the command and returns its exit status.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    ExitCode::from(commands::dispatch(&cli))
}
