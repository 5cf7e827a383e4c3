//! `sweep`: generated inputs on several backends, disagreements grouped, shrunk and written as
//! vectors.

use std::io::{IsTerminal, Write as _};
use std::path::{Path, PathBuf};

use super::backends::{prepare_with_references, Prepared};
use super::output::Sink;
use super::{output, BackendArgs, Cli, CliError, Format, Outcome, EXIT_DIFFERENCES, EXIT_OK};
use crate::model::cross_vendor::Operation;
use crate::report::console;
use crate::sweep::generate::{Digits, Generator, MAX_DIGITS};
use crate::sweep::request::{GeneratorChoice, Request, Swept};
use crate::sweep::{emit, merge, render, Completed, Results, Sweep};

/// What `sweep` takes.
#[derive(Debug, clap::Args)]
pub(crate) struct SweepArgs {
    /// Sweep a cross-vendor operation: every lowering of every backend, and codecs.
    #[arg(long, value_enum, conflicts_with = "instruction")]
    pub operation: Option<OperationArg>,
    /// Sweep one instruction (HABIN, ASCI, ATOH, ...) on every variant of its profile.
    #[arg(long, value_name = "NAME")]
    pub instruction: Option<String>,
    /// The instruction's profile, when several have it.
    #[arg(long, value_name = "ID")]
    pub profile: Option<String>,
    /// The generator [default: text for text-reading targets, values for the others].
    #[arg(long, value_enum)]
    pub generator: Option<GeneratorChoice>,
    /// Seed of the random generator (printed with the results) [default: from the clock].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Inputs of the random generator.
    #[arg(long, default_value_t = 100_000)]
    pub count: u64,
    /// Longest text: the text generator's (default 4) or the random one's (default 8).
    #[arg(long, value_name = "N")]
    pub length: Option<u32>,
    /// The text generator's alphabet: bytes as `20H` or single characters, comma-separated
    /// [default: 00H,20H,2FH,0,9,3AH,40H,A,F,47H,60H,a,f,67H,7FH,80H,FFH].
    #[arg(long, value_name = "LIST")]
    pub alphabet: Option<String>,
    /// Digit counts to give: `natural` (the text's length, the value's width) or a list and
    /// ranges such as `0-6` or `1,4,8`.
    #[arg(long, default_value = "natural")]
    pub digits: String,
    /// The full generator: ask every one of the 2^32 texts rather than one per tuple of byte
    /// classes (minutes over the built-in hex-to-value lowerings, through their rules; hours
    /// with an external backend: split it with --shard).
    #[arg(long)]
    pub each_text: bool,
    /// The full generator by class: random texts asked as they are, each checked against its
    /// class representative.
    #[arg(long, value_name = "N", default_value_t = crate::sweep::DEFAULT_CLASS_CHECK)]
    pub class_check: u64,
    /// Run shard K of N (1-based): every N-th input from the K-th; the shards of a sweep
    /// together are the whole sweep.
    #[arg(long, value_name = "K/N", default_value = "1/1")]
    pub shard: String,
    /// Put the shards of a sweep back together: their JSON results (`--shard K/N --format json
    /// --output FILE`), each shard once. Give the arguments the shards ran with (without
    /// --shard); the first inputs are asked again of the same backends, and the groups shrunk as
    /// the whole sweep shrinks them.
    #[arg(long, value_name = "FILE", num_args = 1.., conflicts_with = "shard")]
    pub merge: Vec<PathBuf>,
    /// Backends to sweep besides the reference models (which are always there, as the oracle):
    /// a name or `external:NAME=COMMAND`, as for `run`; repeat for several.
    #[arg(long = "backend", value_name = "NAME")]
    pub backends: Vec<String>,
    /// What the codec-level backends of an operation sweep are judged against: a built-in
    /// reading such as `fx5/hexa-16bit`, or `none` to judge none [default: the reading each
    /// codec declares]. A judged sweep shows only the groups where a backend parts from its
    /// oracle, and fails when there is one.
    #[arg(long, value_name = "READING")]
    pub oracle: Option<String>,
    /// A known-differences file for an `external:` backend given here (those of the project
    /// file's backends are read as for `run`). A judged column's group is a known difference,
    /// not a failure, when an entry names its cause by the classes of its input (`input:`) or
    /// covers every case (`cases: ['*']`, the only kind that covers a value-to-hex sweep).
    #[arg(long, value_name = "NAME=FILE")]
    pub known_differences: Vec<String>,
    /// Seconds an `external:` backend may take to answer one case.
    #[arg(long, value_name = "SECONDS", default_value = "5", value_parser = super::seconds)]
    pub timeout: std::time::Duration,
    /// Threads for the built-in models [default: the number of CPUs].
    #[arg(short = 'j', long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Classes of each group shrunk to a minimal input (the largest first).
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub shrink: usize,
    /// Results format: text (behaviour groups, counts, first and shrunk inputs), json (the
    /// whole results, versioned), or html (a page of the report).
    #[arg(long, default_value = "text", value_parser = sweep_format())]
    pub format: Format,
    /// Write the results to this file instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write the shrunk inputs as a vector file (cross-vendor for an operation). Every case
    /// written loads; a file not written by `sweep` is replaced only with --force.
    #[arg(long, value_name = "FILE")]
    pub emit: Option<PathBuf>,
    /// Let --emit replace a file that `sweep` did not write.
    #[arg(long, requires = "emit")]
    pub force: bool,
}

/// Refuses to let `--emit` replace a file that `sweep` did not write (a hand-written vector
/// file, or anything else), before the sweep.
fn refuse_hand_written(path: &Path) -> Result<(), CliError> {
    output::check(path)?;
    if !path.is_file() {
        return Ok(());
    }
    let head: String = std::fs::read_to_string(path)
        .map(|t| t.lines().take(3).collect::<Vec<_>>().join("\n"))
        .unwrap_or_default();
    if head.contains(emit::WRITTEN_BY) {
        return Ok(());
    }
    Err(CliError::input(format!(
        "--emit {}: the file exists and was not written by sweep; give --force to replace it, or \
         another file",
        path.display()
    )))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum OperationArg {
    HexToValue,
    ValueToHex,
}

/// The report formats a sweep's results have (the others are a run's: a matrix of trials,
/// JUnit test cases).
const SWEEP_FORMATS: [Format; 3] = [Format::Text, Format::Json, Format::Html];

/// `--format`, restricted to [`SWEEP_FORMATS`].
fn sweep_format() -> impl clap::builder::TypedValueParser<Value = Format> {
    use clap::builder::TypedValueParser as _;
    // The names alone: each format's help speaks of a run.
    let names = (SWEEP_FORMATS.iter())
        .filter_map(clap::ValueEnum::to_possible_value)
        .map(|v| v.help(None::<&'static str>));
    clap::builder::PossibleValuesParser::new(names)
        .try_map(|name| <Format as clap::ValueEnum>::from_str(&name, false))
}

pub(super) fn sweep(cli: &Cli, args: &SweepArgs) -> Outcome {
    let request = request(args)?;
    let backend_args = BackendArgs {
        backends: args.backends.clone(),
        timeout: args.timeout,
        known_differences: args.known_differences.clone(),
        filter: None,
        vectors: Vec::new(),
        jobs: args.jobs,
        max_faults: crate::model::project::DEFAULT_MAX_CONSECUTIVE_FAULTS,
        allow_empty: false,
        fail_fast: false,
    };
    // The reference models are always there, and first: they are the oracle.
    let Prepared { session, .. } = prepare_with_references(cli, &backend_args)?;
    let project = &session.project;
    let sweep = request.sweep(&project.profiles, &session.backends)?;
    // The shards' files are read before anything is swept or asked.
    let shards = match args.merge.is_empty() {
        true => None,
        false => Some(merge::read_files(&args.merge)?),
    };
    // Where the results go is settled before the sweep, not found wrong after it.
    if let (Some(path), false) = (&args.emit, args.force) {
        refuse_hand_written(path)?;
    }
    let open = |path: &Option<PathBuf>| path.as_deref().map(|p| Sink::open(Some(p))).transpose();
    let (output_sink, emit_sink) = (open(&args.output)?, open(&args.emit)?);
    announce(&sweep, shards.as_ref().map(Vec::len));
    // SIGINT and SIGTERM (handled in `cli::main`) stop the sweep after the round under way and
    // kill every backend process group, so a hung backend ends the round too.
    let bar = progress_bar(sweep.space.total());
    let completed = sweep.complete(
        shards.as_deref(),
        &project.known,
        crate::interrupt::stop_flag(),
        &mut |done, of| {
            if let Some(bar) = &bar {
                bar.set_length(of);
                bar.set_position(done);
            }
        },
    );
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let Completed {
        results,
        known_cover_nothing,
    } = completed?;
    if known_cover_nothing {
        console::warning(
            "a value has no input class: of a known-differences file, only an entry for every \
             case (`cases: ['*']`) covers a value-to-hex sweep's inputs, so its other entries \
             cover none of the differences below",
        );
    }
    write_results(&results, args.format, output_sink)?;
    if let Some(why) = results.inexact() {
        // Exit 1: the counts above are not exact.
        console::status(&format!("error: {why}"));
        return Ok(EXIT_DIFFERENCES);
    }
    if let (Some(path), Some(sink)) = (&args.emit, emit_sink) {
        emit_vectors(&sweep, &results, project, path, sink)?;
    }
    Ok(if results.interrupted {
        // As `run`: an interruption, whatever was found before it.
        EXIT_INTERRUPTED
    } else if results.differs() || !results.faulted().is_empty() {
        EXIT_DIFFERENCES
    } else {
        EXIT_OK
    })
}

/// The request the arguments make: each list read, the target named.
fn request(args: &SweepArgs) -> Result<Request, CliError> {
    let swept = match (&args.operation, &args.instruction) {
        (Some(OperationArg::HexToValue), _) => Swept::Operation(Operation::HexToValue),
        (Some(OperationArg::ValueToHex), _) => Swept::Operation(Operation::ValueToHex),
        (None, Some(name)) => Swept::Instruction {
            name: name.clone(),
            profile: args.profile.clone(),
        },
        (None, None) => {
            return Err(CliError::input(
                "give --operation hex-to-value|value-to-hex or --instruction NAME",
            ))
        }
    };
    Ok(Request {
        swept,
        generator: args.generator,
        seed: args.seed,
        count: args.count,
        length: args.length,
        alphabet: args.alphabet.as_deref().map(alphabet).transpose()?,
        digits: digits(&args.digits)?,
        each_text: args.each_text,
        class_check: args.class_check,
        shard: shard(&args.shard)?,
        oracle: args.oracle.clone(),
        jobs: args.jobs,
        shrink: args.shrink,
    })
}

/// What is about to be swept, on stderr.
fn announce(sweep: &Sweep, shards: Option<usize>) {
    let settings = &sweep.settings;
    let seed = settings.seed;
    match shards {
        Some(n) => console::status(&format!(
            "merging {n} shard(s) of {} with the {} generator: their first inputs asked again",
            settings.target,
            settings.generator.name()
        )),
        None => console::status(&format!(
            "sweeping {} with the {} generator{}: {} input(s) in this shard",
            settings.target,
            settings.generator.name(),
            if settings.generator.uses_seed() {
                format!(", seed {seed} (--seed {seed} repeats it)")
            } else {
                String::new()
            },
            render::thousands(sweep.space.total().div_ceil(settings.shard.1))
        )),
    }
    if matches!(settings.generator, Generator::Full { by_class: true }) {
        console::status(&format!(
            "by byte class: the classes are found first, then one text per tuple of classes is \
             asked, then {} random texts check them",
            render::thousands(settings.class_check)
        ));
    }
}

/// A progress bar on a terminal's stderr; none when stderr is not one.
fn progress_bar(total: u64) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {human_pos}/{human_len} inputs ({rate}, eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            // Whole inputs per second, grouped as the other counts are.
            .with_key(
                "rate",
                |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{}/s", render::thousands(state.per_sec() as u64));
                },
            )
            .progress_chars("=> "),
        );
        bar
    })
}

/// The results in their format, to `--output` or stdout.
fn write_results(results: &Results, format: Format, sink: Option<Sink>) -> Result<(), CliError> {
    if results.interrupted {
        console::status(&format!(
            "interrupted: {} of {} inputs swept; what was found so far follows",
            render::thousands(results.swept),
            render::thousands(results.shard_inputs)
        ));
    }
    let rendered = match format {
        Format::Json => render::json(results),
        Format::Html => render::html(results),
        // Text; the parser takes SWEEP_FORMATS only.
        _ => render::text(results),
    };
    match sink {
        Some(mut sink) => {
            sink.write_all(rendered.as_bytes())
                .map_err(|e| sink.error(e))?;
            sink.finish()
        }
        None => output::write(None, rendered.trim_end()),
    }
}

/// The shrunk inputs that load, written as a vector file through `sink`.
fn emit_vectors(
    sweep: &Sweep,
    results: &Results,
    project: &crate::project::Project,
    path: &Path,
    mut sink: Sink,
) -> Result<(), CliError> {
    let mut emitted = emit::emit(sweep, results, &project.corpus);
    emitted.keep_loadable(path, &project.profiles);
    for why in &emitted.skipped {
        console::note(&format!("not written as a vector: {why}"));
    }
    if emitted.cases.is_empty() {
        // Dropped unfinished: a staged file is removed and the target left as it was.
        drop(sink);
        console::status(&format!(
            "nothing to write to {}: no shrunk input makes a vector",
            path.display()
        ));
        return Ok(());
    }
    let yaml = schema_line_that_resolves(
        path,
        emitted.yaml(emitted.cases.iter().map(|(_, c)| c.as_str())),
    );
    sink.write_all(yaml.as_bytes()).map_err(|e| sink.error(e))?;
    sink.finish()?;
    console::status(&format!(
        "wrote {} vector(s) to {}",
        emitted.cases.len(),
        path.display()
    ));
    Ok(())
}

/// The emitted file's `$schema` line as written (`../../schema/...`, right inside a checkout's
/// `vectors/<family>/`) when that schema is there from where the file goes; else a line that says
/// how to get the schema, since a path to nothing would only make an editor complain.
fn schema_line_that_resolves(path: &Path, yaml: String) -> String {
    const PREFIX: &str = "# yaml-language-server: $schema=";
    let Some((first, rest)) = yaml.split_once('\n') else {
        return yaml;
    };
    let Some(schema) = first.strip_prefix(PREFIX) else {
        return yaml;
    };
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
    if folder.unwrap_or(Path::new(".")).join(schema).is_file() {
        return yaml;
    }
    let kind = Path::new(schema)
        .file_name()
        .and_then(|n| n.to_str())
        .and_then(|n| n.strip_suffix(".schema.json"))
        .unwrap_or("vectors");
    format!("# Schema: `plc-conformance schema --kind {kind}`.\n{rest}")
}

/// 128 + SIGINT, as a shell reports a command Ctrl-C ended.
const EXIT_INTERRUPTED: u8 = 130;

/// `20H,0,9,a` -> bytes.
pub(super) fn alphabet(list: &str) -> Result<Vec<u8>, CliError> {
    let mut out = Vec::new();
    for item in list.split(',').filter(|s| !s.is_empty()) {
        let byte = if item.chars().count() == 1 {
            u8::try_from(item.chars().next().unwrap_or('\0'))
                .map_err(|_| format!("`{item}` is not one byte"))?
        } else {
            let hex = item
                .strip_suffix('H')
                .or_else(|| item.strip_suffix('h'))
                .ok_or_else(|| format!("`{item}`: give a byte as `20H` or one character"))?;
            u8::from_str_radix(hex, 16).map_err(|_| format!("`{item}` is not a byte"))?
        };
        if !out.contains(&byte) {
            out.push(byte);
        }
    }
    if out.is_empty() {
        return Err(CliError::input("the alphabet is empty"));
    }
    Ok(out)
}

/// `natural`, or `0-6`, `1,4,8`: counts from 0 to [`MAX_DIGITS`], at least one.
pub(super) fn digits(spec: &str) -> Result<Digits, CliError> {
    if spec == "natural" {
        return Ok(Digits::Natural);
    }
    let mut out = Vec::new();
    for part in spec.split(',').filter(|s| !s.trim().is_empty()) {
        let bad = || format!("--digits `{part}`: expected a count, a range `0-6` or `natural`");
        let count = |text: &str| -> Result<u32, CliError> {
            let d: u32 = text.trim().parse().map_err(|_| bad())?;
            if d > MAX_DIGITS {
                return Err(CliError::input(format!(
                    "--digits `{part}`: a count is at most {MAX_DIGITS}"
                )));
            }
            Ok(d)
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (count(a)?, count(b)?);
                if a > b {
                    return Err(CliError::input(format!(
                        "--digits `{part}`: an empty range; give the smaller count first"
                    )));
                }
                out.extend((a..=b).filter(|d| !out.contains(d)).collect::<Vec<_>>());
            }
            None => {
                let d = count(part)?;
                if !out.contains(&d) {
                    out.push(d);
                }
            }
        }
    }
    if out.is_empty() {
        return Err(CliError::input(format!(
            "--digits `{spec}`: no count given; give counts such as `4`, `0-6`, or `natural`"
        )));
    }
    Ok(Digits::Each(out))
}

/// `K/N`.
pub(super) fn shard(spec: &str) -> Result<(u64, u64), CliError> {
    let bad = || format!("--shard `{spec}`: expected K/N with 1 <= K <= N, like 2/8");
    let (k, n) = spec.split_once('/').ok_or_else(bad)?;
    let (k, n): (u64, u64) = (k.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if k == 0 || n == 0 || k > n {
        return Err(bad().into());
    }
    Ok((k, n))
}

#[cfg(test)]
mod schema_line {
    use super::*;

    #[test]
    fn a_schema_path_that_leads_nowhere_becomes_the_command_that_prints_it() {
        let yaml = "# yaml-language-server: $schema=../../schema/cross-vendor.schema.json\nx: 1\n";
        let outside = schema_line_that_resolves(Path::new("/tmp/nowhere/swept.yaml"), yaml.into());
        assert_eq!(
            outside,
            "# Schema: `plc-conformance schema --kind cross-vendor`.\nx: 1\n"
        );
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let inside = root.join("vectors/cross-vendor/swept.yaml");
        assert_eq!(schema_line_that_resolves(&inside, yaml.into()), yaml);
    }
}

#[cfg(test)]
mod tests {
    //! The sweep's argument parsing, fuzzed: whatever a user types, a list is bounded or refused
    //! with a message, never a panic, an allocation past reason or a silent default. Run longer
    //! with `PROPTEST_CASES=100000 cargo test --lib cli::sweep`.

    use super::*;
    use clap::Parser;
    use proptest::prelude::*;

    /// What the list arguments are made of, hostile pieces included.
    fn piece() -> impl Strategy<Value = String> {
        prop_oneof![
            "[0-9]{1,22}",
            Just("-".to_string()),
            Just(",".to_string()),
            Just("/".to_string()),
            Just(" ".to_string()),
            Just("H".to_string()),
            Just("natural".to_string()),
            Just("4294967295".to_string()),
            Just("18446744073709551616".to_string()),
            "\\PC{0,3}",
        ]
    }

    fn spec() -> impl Strategy<Value = String> {
        prop::collection::vec(piece(), 0..8).prop_map(|v| v.concat())
    }

    proptest! {
        #[test]
        fn digits_are_bounded_or_refused(spec in spec()) {
            match digits(&spec) {
                Ok(Digits::Each(d)) => {
                    prop_assert!(!d.is_empty());
                    prop_assert!(d.len() <= MAX_DIGITS as usize + 1);
                    prop_assert!(d.iter().all(|x| *x <= MAX_DIGITS));
                }
                Ok(Digits::Natural) => prop_assert_eq!(spec.as_str(), "natural"),
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
        }

        #[test]
        fn shards_are_k_of_n_or_refused(spec in spec()) {
            if let Ok((k, n)) = shard(&spec) {
                prop_assert!(1 <= k && k <= n);
            }
        }

        #[test]
        fn alphabets_are_bytes_or_refused(spec in spec()) {
            if let Ok(a) = alphabet(&spec) {
                prop_assert!(!a.is_empty() && a.len() <= 256);
            }
        }

        #[test]
        fn sweep_command_lines_parse_or_are_refused(
            args in prop::collection::vec(
                prop_oneof![
                    Just("--digits".to_string()),
                    Just("--shard".to_string()),
                    Just("--alphabet".to_string()),
                    Just("--length".to_string()),
                    Just("--count".to_string()),
                    Just("--class-check".to_string()),
                    Just("--generator".to_string()),
                    Just("full".to_string()),
                    spec(),
                ],
                0..10,
            )
        ) {
            let mut argv = vec!["plc-conformance".to_string(), "sweep".to_string()];
            argv.extend(args);
            if let Ok(cli) = crate::cli::Cli::try_parse_from(argv) {
                if let crate::cli::Command::Sweep(a) = &cli.command {
                    let _ = digits(&a.digits);
                    let _ = shard(&a.shard);
                    let _ = a.alphabet.as_deref().map(alphabet);
                }
            }
        }
    }
}
