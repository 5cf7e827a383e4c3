//! `hil`: what a bench with a real CPU needs around the live backend (`slmp:` for MELSEC,
//! `modbus:` for IDEC): the test program to write to the CPU, a read-only look at the bench, a
//! dry run that opens no socket, and the simulated CPU that stands in for a bench in tests and
//! demonstrations.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::backends::{load, paths};
use super::{output, Cli, CliError, Outcome, EXIT_DIFFERENCES, EXIT_OK};
use crate::backend::bench::doctor::doctor;
use crate::backend::bench::{fence, mailbox};
use crate::backend::bench::{Addressing, BenchSettings};
use crate::backend::simulate::{simulate, SimRequest};
use crate::backend::slmp;
use crate::hil::{dry_run, generate, GenerateOptions, SelfTest};
use crate::session::Session;

#[derive(Debug, clap::Subcommand)]
pub(crate) enum HilCommand {
    /// Write the test program (structured text for GX Works3, a rung list for WindLDR), its
    /// manifest and a setup checklist for a profile, from the corpus's own operands.
    Generate(GenerateArgs),
    /// Look at a bench without writing anything: the CPU's name, its operating status, the
    /// program's signature in the mailbox, its state, and whether its scan counter moves.
    Doctor {
        /// The live backend: slmp:NAME=HOST:PORT?manifest=FILE&confirm=TYPE&sandbox=RANGES, or
        /// modbus:NAME=HOST:PORT?manifest=FILE&confirm=CODE&sandbox=RANGES.
        #[arg(long, value_name = "SPEC")]
        backend: String,
        /// Then, once every check passed, run one pulse-form case twice and check that both
        /// executions did the same: writes that case's window (inside the sandbox) and the
        /// mailbox.
        #[arg(long)]
        self_test: bool,
    },
    /// Every trial a live backend would run and every word it would write, checked against its
    /// write fence; no socket is opened.
    DryRun {
        /// The live backend: slmp:NAME=HOST:PORT?manifest=FILE&confirm=TYPE&sandbox=RANGES, or
        /// modbus:NAME=HOST:PORT?manifest=FILE&confirm=CODE&sandbox=RANGES.
        #[arg(long, value_name = "SPEC")]
        backend: String,
    },
    /// Ask a MELSEC CPU's MC protocol (SLMP) port, set to ASCII code, read requests whose point
    /// count or device number carries what the manual does not cover (a lowercase letter, a
    /// leading blank) or refuses (a character that is not a hex digit), and print the end code
    /// it answers to each beside what the manual says. Only reads: nothing is written.
    Probe {
        /// The CPU's port, HOST:PORT (its SLMP connection in ASCII code, 3E frames).
        #[arg(long, value_name = "HOST:PORT")]
        address: String,
        /// Seconds to wait for each answer.
        #[arg(long, value_name = "S", default_value_t = 5.0)]
        timeout: f64,
    },
    /// Serve a simulated CPU on 127.0.0.1 running the manifest's program with the built-in
    /// reference model, until interrupted, over the link of the manifest's profile (SLMP for
    /// MELSEC, Modbus TCP for IDEC); prints `listening on 127.0.0.1:PORT`. Its SLMP port also
    /// reads 0101 and 0401 in ASCII code, as the manual writes fields (what `hil probe` asks).
    Sim(SimArgs),
}

/// What `hil generate` takes.
#[derive(Debug, clap::Args)]
pub(crate) struct GenerateArgs {
    /// The profile (mitsubishi-iqr, mitsubishi-fx5, idec-fc4a).
    #[arg(long, value_name = "ID")]
    profile: String,
    /// Only this variant's trials; repeat for several [default: every variant].
    #[arg(long = "variant", value_name = "ID")]
    variants: Vec<String>,
    /// The mailbox's first word, e.g. D12000, or W100 (W, SW, X, Y, B, SB are hexadecimal)
    /// [default: data registers clear of every case window].
    #[arg(long, value_name = "DEVICE")]
    mailbox: Option<String>,
    /// Only trials whose name contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// The folder to write the program (executive.st or executive.txt), manifest.json and
    /// SETUP.md into.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// What `hil sim` takes.
#[derive(Debug, clap::Args)]
pub(crate) struct SimArgs {
    /// The manifest of the generated program.
    #[arg(long, value_name = "FILE")]
    manifest: PathBuf,
    /// The profile variant the simulated CPU is [default: the manifest's only one].
    #[arg(long, value_name = "ID")]
    variant: Option<String>,
    /// SLMP: the type name 0101 answers [default: R04CPU, FX5U-32MT/DS for an FX5
    /// manifest].
    #[arg(long, value_name = "NAME")]
    type_name: Option<String>,
    /// SLMP: the model code 0101 answers, in hexadecimal [default: the one the manuals give
    /// the type name].
    #[arg(long, value_name = "HEX")]
    model_code: Option<String>,
    /// Modbus TCP (IDEC): the type code the CPU holds in D8002, what `confirm=` names.
    #[arg(long, value_name = "CODE", default_value_t = 0)]
    type_code: u16,
    /// The port on 127.0.0.1 [default: any free one].
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// Microseconds between scans.
    #[arg(long, value_name = "US", default_value_t = 200)]
    scan_us: u64,
    /// Start in STOP (SD203 or M8000 says so, the program does not scan).
    #[arg(long)]
    stop: bool,
    /// A port fault, COMMAND:NTH:ACTION: `1401:3:drop` closes the connection on the third
    /// SLMP write (`10:3:drop` on the third Modbus write of several registers); actions
    /// drop, delay=MS, end=CODE (an end code, or a Modbus exception), garbage, serial
    /// (another serial or transaction id), stop. Repeat for several.
    #[arg(long = "fault", value_name = "RULE")]
    faults: Vec<String>,
}

pub(super) fn hil(cli: &Cli, command: &HilCommand) -> Outcome {
    match command {
        HilCommand::Generate(args) => generate_command(cli, args),
        HilCommand::Doctor { backend, self_test } => doctor_command(cli, backend, *self_test),
        HilCommand::DryRun { backend } => dry_run_command(cli, backend),
        HilCommand::Probe { address, timeout } => probe(address, *timeout),
        HilCommand::Sim(args) => sim_command(cli, args),
    }
}

/// `hil generate`: the program, its manifest and the setup checklist, written to `--out`.
fn generate_command(cli: &Cli, args: &GenerateArgs) -> Outcome {
    let GenerateArgs {
        profile,
        variants,
        mailbox,
        filter,
        out,
    } = args;
    let project = load(&paths(cli, &[], "--vectors")?)?;
    // The mailbox is numbered as the profile's link numbers its code (`generate`
    // refuses a profile with no bench).
    let addressing: Box<dyn Addressing> = match project.profiles.get(profile) {
        Some(p) if p.bench.is_some() => crate::backend::addressing(p)?,
        _ => Box::new(slmp::Slmp),
    };
    let mailbox = mailbox
        .as_deref()
        .map(|m| {
            mailbox::head(m, addressing.as_ref())
                .map_err(|e| CliError::within(format!("--mailbox {m}"), e))
        })
        .transpose()?;
    let generated = generate(
        &project,
        &GenerateOptions {
            profile: profile.clone(),
            variants: variants.clone(),
            mailbox,
            filter: filter.clone(),
        },
    )?;
    let manifest = serde_json::to_string_pretty(&generated.manifest)
        .map_err(|e| CliError::within("the manifest does not serialize", e))?;
    std::fs::create_dir_all(out).map_err(|e| CliError::write(Some(out), e))?;
    let files = [
        (out.join(generated.program_file), generated.program.clone()),
        (out.join("manifest.json"), manifest + "\n"),
        (out.join("SETUP.md"), generated.setup.clone()),
    ];
    output::write_every(files.iter().map(|(p, t)| (p.as_path(), t.as_str())))?;
    let m = &generated.manifest;
    output::write(
        None,
        &format!(
            "{} rungs for {} trials ({} operand tuples no program can hold), mailbox {}, \
             program {}; wrote {}",
            m.rungs.len(),
            generated.trials,
            m.unrealisable.len(),
            m.mailbox,
            m.hash,
            files
                .iter()
                .map(|(p, _)| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )?;
    Ok(EXIT_OK)
}

/// `hil doctor`: the bench looked at read-only, and with `--self-test` one pulse case twice.
fn doctor_command(cli: &Cli, backend: &str, self_test: bool) -> Outcome {
    let project = load(&paths(cli, &[], "--vectors")?)?;
    let settings = live_settings(backend, &project.profiles)?;
    let (findings, requests) = doctor(&settings);
    let mut text = String::new();
    for f in &findings {
        let _ = match &f.result {
            Ok(s) => writeln!(text, "ok    {}: {s}", f.what),
            Err(s) => writeln!(text, "FAIL  {}: {s}", f.what),
        };
    }
    let _ = write!(text, "{requests} read requests sent, nothing written");
    let mut ok = findings.iter().all(|f| f.result.is_ok());
    if self_test && ok {
        let session = Session::new(project);
        let live = session.live(settings)?;
        live.connect()?;
        let _ = writeln!(text);
        match crate::hil::self_test(&session, &live) {
            Ok(SelfTest::NoPulseForms { profile }) => {
                let _ = write!(
                    text,
                    "ok    pulse self-test: nothing to fire twice: {profile} has no pulse-form \
                     instruction, every rung runs its case while its enable is on"
                );
            }
            Ok(SelfTest::Ran(check)) => {
                ok = check.fired_twice;
                let _ = write!(
                    text,
                    "{}  pulse self-test: {} run twice: {} / {}{}",
                    if ok { "ok  " } else { "FAIL" },
                    check.trial,
                    check.first,
                    check.second,
                    if ok {
                        ""
                    } else {
                        "; the second execution differs: a pulse rung fires once \
                         only, so its later cases would be judged on a stale result"
                    }
                );
            }
            Err(why) => {
                ok = false;
                let _ = write!(text, "FAIL  pulse self-test: {why}");
            }
        }
    }
    output::write(None, &text)?;
    Ok(if ok { EXIT_OK } else { EXIT_DIFFERENCES })
}

/// `hil dry-run`: every trial and write a live backend would make, with no socket.
fn dry_run_command(cli: &Cli, backend: &str) -> Outcome {
    let session = Session::new(load(&paths(cli, &[], "--vectors")?)?);
    let settings = live_settings(backend, &session.profiles)?;
    let live = session.live(settings)?;
    let found = dry_run(&session, &live);
    let mut text = String::new();
    for (trial, why) in &found.refused {
        let _ = writeln!(text, "refused {trial}: {why}");
    }
    let _ = write!(
        text,
        "dry run, no socket opened: {} trials ({} executions) on {} rungs would run, {} \
         skipped, {} refused by the write fence; words written: {}",
        found.trials,
        found.executions,
        found.rungs,
        found.skipped.len(),
        found.refused.len(),
        fence::list(&found.writes)
    );
    output::write(None, &text)?;
    Ok(if found.refused.is_empty() {
        EXIT_OK
    } else {
        EXIT_DIFFERENCES
    })
}

/// `hil sim`: a simulated CPU over the manifest's profile's link, serving until ended.
fn sim_command(cli: &Cli, args: &SimArgs) -> Outcome {
    let project = load(&paths(cli, &[], "--vectors")?)?;
    let request = SimRequest {
        manifest: args.manifest.clone(),
        variant: args.variant.clone(),
        type_name: args.type_name.clone(),
        model_code: args.model_code.clone(),
        type_code: args.type_code,
        port: args.port,
        scan: Duration::from_micros(args.scan_us),
        run: !args.stop,
        faults: args.faults.clone(),
    };
    // The simulator serves until the process is ended.
    let serving = simulate(&project.profiles, &request)?;
    output::write(None, &format!("listening on {}", serving.address()))?;
    loop {
        std::thread::sleep(Duration::from_secs(3600));
    }
}

fn live_settings(
    spec: &str,
    profiles: &crate::model::profile::Profiles,
) -> Result<BenchSettings, CliError> {
    crate::backend::bench_settings(spec, Path::new("."), profiles)?.ok_or_else(|| {
        CliError::input(format!(
            "`{spec}` is not a live backend: give {}",
            crate::backend::BENCH_FORMS
        ))
    })
}

/// `hil probe`: each probe's request, the end code answered and what the manual says; exit 1
/// when an answer differs from an end code the manual states.
fn probe(address: &str, timeout: f64) -> Outcome {
    use crate::backend::slmp::probe::{ask_all, Manual};
    let limit = std::time::Duration::try_from_secs_f64(timeout)
        .ok()
        .filter(|d| !d.is_zero() && d.as_secs() <= 600)
        .ok_or_else(|| CliError::input(format!("--timeout {timeout}: give 0.001 to 600 s")))?;
    let answers = ask_all(address, limit)
        .map_err(|e| CliError::input(format!("{address}: no connection: {e}")))?;
    let mut text = format!(
        "{:<22} {:<30} {:<17} {:<11} the manual\n",
        "probe", "field", "device, points", "answered"
    );
    for (p, heard) in &answers {
        let sent = format!("`{}` `{}`", p.device, p.points);
        let manual = match p.manual {
            Manual::EndCode(code, rule) => format!("{code:04X}H ({rule})"),
            Manual::Open(question) => format!("not settled: open question {question}"),
        };
        text.push_str(&format!(
            "{:<22} {:<30} {sent:<17} {:<11} {manual}\n",
            p.id,
            p.field,
            heard.to_string(),
        ));
    }
    let stated: Vec<bool> = (answers.iter())
        .filter_map(|(p, heard)| p.manual.agrees(heard))
        .collect();
    let against = stated.iter().filter(|agrees| !**agrees).count();
    text.push_str(&format!(
        "{} of {} answers as the manual states; the open ones are what this CPU does. A real \
         CPU's answers settle the open questions: record them under `observed` in \
         docs/open-questions.yaml with the CPU's model, firmware, the date and who ran the \
         probe. A simulated CPU's (hil sim) are its own reading of the manual, never an \
         observation.",
        stated.len() - against,
        stated.len()
    ));
    output::write(None, &text)?;
    Ok(if against == 0 {
        EXIT_OK
    } else {
        EXIT_DIFFERENCES
    })
}
