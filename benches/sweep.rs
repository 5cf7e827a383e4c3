//! How fast sweeps go.
//!
//! `cargo bench --bench sweep` (add `-- --quick` for a smoke run, or a word to run only the
//! measurements whose name contains it: `overhead`, `values`, `protocol`, `full`).
//!
//! - overhead: the same inputs through the sweep (plan, execute, judge, group) and through a
//!   bare loop that only builds each request's memory and calls the reference model;
//! - values: all 65,536 values through each value-to-hex instruction on every built-in variant;
//! - protocol: generated inputs through `plc-conformance serve` (the native adapter), batched;
//! - full: all 2^32 four-byte texts through every built-in hex-to-value lowering by byte class;
//!   and a shard asked text by text through the models, and a larger one through the lowerings'
//!   rules (`--each-text`), with the whole space extrapolated from each;
//! - codecs: a Python and a JavaScript codec whose decode is one line (`benches/int_codec.py`,
//!   `benches/int_codec.js`), swept beside the built-in models over random texts: the time their
//!   column adds against the codec's own bare loop over the same texts, side by side.
//!
//! Results: `docs/performance.md`, section "Sweeps".

/// The allocator the `plc-conformance` binary uses, so that both sides measure alike.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use plc_conformance::testing::model::project::{ExternalSettings, Launch};
use plc_conformance::testing::plan::Input;
use plc_conformance::testing::session::{BackendSource, Session};
use plc_conformance::testing::sweep::generate::Generator;
use plc_conformance::testing::sweep::group::Groups;
use plc_conformance::testing::sweep::input::{Data, Point};
use plc_conformance::testing::sweep::target::{Cases, Target};
use plc_conformance::testing::sweep::{Settings, Sweep};
use plc_conformance::Operation;
use plc_conformance::Request;
use plc_conformance::{Fill, Image};
use plc_conformance::{Paths, Project};

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    let wanted = |name: &str| filter.as_deref().is_none_or(|f| name.contains(f));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut project = match Project::load(&Paths::under(root)) {
        Ok(p) => Session::with_references(p),
        Err(e) => {
            eprintln!("the corpus does not load:\n{e}");
            std::process::exit(2);
        }
    };
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    println!("{cores} core(s); figures are the best of 3 rounds unless said otherwise");
    if wanted("overhead") {
        overhead(&project, if quick { 20_000 } else { 200_000 });
    }
    if wanted("values") {
        values(&project, cores);
    }
    if wanted("full") {
        full(&project, cores, if quick { 1 << 16 } else { 1 << 22 });
    }
    // Last: these add external backends to the project.
    if wanted("codecs") {
        codecs(&mut project, root, if quick { 20_000 } else { 200_000 });
    }
    if wanted("protocol") {
        protocol(&mut project, root, if quick { 10_000 } else { 100_000 });
    }
}

fn best<T>(rounds: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..rounds {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    (best, last.expect("one round"))
}

/// The sweep against the bare model loop, one thread each.
fn overhead(project: &Session, count: u64) {
    let mut settings = Settings::new(
        Target::Operation {
            operation: Operation::HexToValue,
        },
        Generator::Random { count, max_len: 8 },
        1,
    );
    settings.jobs = 1;
    settings.shrink = 0;
    let sweep = Sweep::new(settings, project.profiles(), &project.backends).expect("sweep");
    let points: Vec<(u64, Point)> = (0..count).map(|i| (i, sweep.space.point(i))).collect();
    // The bare loop's inputs, made before timing: per point and column, the profile, variant,
    // instruction, flags, operands and memory the plan gives.
    let mut inputs: Vec<(usize, Input)> = Vec::new();
    for (i, p) in &points {
        let cases = Cases::new(&sweep.settings.target, None, *i, p);
        for (c, column) in sweep.columns.iter().enumerate() {
            if let Some(t) = cases.trial(column) {
                inputs.push((c, t.input().clone()));
            }
        }
    }
    let (bare, answers) = best(3, || {
        let mut n = 0usize;
        for (c, input) in &inputs {
            let column = &sweep.columns[*c];
            let profile = column.profile.as_ref().expect("a lowering has a profile");
            let variant = profile.variant(&column.variant).expect("variant");
            for fill in Fill::ALL {
                let image = Image::new(input.before.clone(), fill);
                let req = Request {
                    profile,
                    variant,
                    instruction: &input.instruction,
                    case_id: "bench",
                    flags: &input.flags,
                    operands: &input.operands,
                    indirect: &input.indirect,
                    memory: &image,
                };
                if column.backend.execute(&req).is_ok() {
                    n += 1;
                }
            }
        }
        n
    });
    let stop = AtomicBool::new(false);
    let (answering, _) = best(3, || sweep.answers(&points, &stop).len());
    println!("overhead: of which answering (trials, execute, judge) {answering:.3} s");
    let (swept, _) = best(3, || {
        let mut groups = Groups::new(64);
        let answers = sweep.answers(&points, &stop);
        for ((i, p), r) in points.iter().zip(answers) {
            if let Some(r) = r {
                groups.add(&sweep.columns, true, *i, p, r, 1);
            }
        }
        groups.by_key.len()
    });
    println!(
        "overhead: {count} random hex-to-value inputs x {} lowerings ({answers} model calls), one thread: \
         bare model loop {bare:.3} s, sweep (trials, judge, grouping) {swept:.3} s: {:.2}x",
        sweep.columns.len(),
        swept / bare
    );
}

/// Every 16-bit value through each value-to-hex instruction on every variant.
fn values(project: &Session, cores: usize) {
    let mut total = 0.0;
    let mut all_flags = 0.0;
    for (profile, instruction) in [
        ("mitsubishi-iqr", "BINHA"),
        ("mitsubishi-iqr", "DBINHA"),
        ("mitsubishi-fx5", "ASCI"),
        ("idec-fc4a", "HTOA"),
    ] {
        let mut settings = Settings::new(
            Target::Instruction {
                profile: profile.into(),
                instruction: instruction.into(),
            },
            Generator::Values { bits: 16 },
            1,
        );
        settings.jobs = cores;
        settings.shrink = 0;
        let mut sweep = Sweep::new(settings, project.profiles(), &project.backends).expect("sweep");
        let flags = std::mem::take(&mut sweep.space.flags);
        let (t, r) = best(3, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
        total += t;
        println!(
            "values: {instruction}: 65,536 values, default flags, on {} variant(s): {t:.3} s, {} groups",
            sweep.columns.len(),
            r.groups.by_key.len()
        );
        sweep.space.flags = flags;
        let (t, r) = best(3, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
        all_flags += t;
        println!(
            "values: {instruction}: {} inputs (65,536 values x {} flag setting(s)) on {} variant(s): {t:.3} s, {} groups",
            r.swept,
            r.swept / 65_536,
            sweep.columns.len(),
            r.groups.by_key.len()
        );
    }
    println!(
        "values: all four instructions: {total:.3} s with default flags, {all_flags:.3} s with every flag setting"
    );
}

/// Generated inputs through the native adapter, batched.
fn protocol(project: &mut Session, root: &Path, count: u64) {
    let mut settings = ExternalSettings::new(
        "native",
        Launch::Exec(vec![
            env!("CARGO_BIN_EXE_plc-conformance").to_string(),
            "--root".into(),
            root.display().to_string(),
            "serve".into(),
            "--profile".into(),
            "mitsubishi-iqr".into(),
        ]),
    );
    settings.timeout = std::time::Duration::from_secs(30);
    let native = project
        .add(BackendSource::Process(settings), false)
        .expect("serve starts")[0]
        .clone();
    let mut s = Settings::new(
        Target::Instruction {
            profile: "mitsubishi-iqr".into(),
            instruction: "HABIN".into(),
        },
        Generator::Random { count, max_len: 8 },
        1,
    );
    s.shrink = 0;
    let sweep = Sweep::new(s, project.profiles(), &[native]).expect("sweep");
    let (t, r) = best(3, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
    let trials = r.swept * sweep.columns.len() as u64;
    println!(
        "protocol: {} HABIN inputs x {} variants through `serve`, batched: {t:.3} s, {:.0} trials/s, {:.0} cases/s (a case is one request: a trial under one fill)",
        r.swept,
        sweep.columns.len(),
        trials as f64 / t,
        2.0 * trials as f64 / t
    );
}

/// All 2^32 four-byte texts through every built-in hex-to-value lowering, by byte class (with
/// the classes found and checked as in any such sweep); then a shard asked text by text, and the
/// whole space at that rate.
fn full(project: &Session, cores: usize, texts: u64) {
    let mut settings = Settings::new(
        Target::Operation {
            operation: Operation::HexToValue,
        },
        Generator::Full { by_class: true },
        1,
    );
    settings.jobs = cores;
    settings.shrink = 0;
    let sweep = Sweep::new(settings.clone(), project.profiles(), &project.backends).expect("sweep");
    let (t, r) = best(3, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
    let c = r.classes.as_ref().expect("by class");
    println!(
        "full: all {} texts x {} lowerings by class: {t:.2} s ({} byte classes found with {} texts, \
         {} texts asked, {} random texts checked, {}), {} groups",
        r.swept,
        sweep.columns.len(),
        c.classes.len(),
        c.split_texts,
        c.tuples,
        c.checked,
        if c.mismatch.is_none() { "all alike" } else { "A MISMATCH" },
        r.groups.by_key.len()
    );
    // Each text through the models (the general path, as with an external backend's columns),
    // then through the lowerings' rules (what `--each-text` does over the built-ins), each on a
    // shard and extrapolated.
    for (exhaustive, texts) in [(false, texts), (true, texts * 64)] {
        let shards = ((1u64 << 32) / texts).max(1);
        settings.generator = Generator::Full { by_class: false };
        settings.shard = (1, shards);
        settings.exhaustive = exhaustive;
        let sweep =
            Sweep::new(settings.clone(), project.profiles(), &project.backends).expect("sweep");
        let (t, r) = best(1, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
        println!(
            "full: each text through the {}, shard 1/{shards} ({} texts) x {} lowerings: {t:.2} s, \
             {:.0} texts/s; the whole space at this rate: {:.0} s ({:.1} h), {} groups",
            if exhaustive { "rules" } else { "models" },
            r.swept,
            sweep.columns.len(),
            r.swept as f64 / t,
            t * shards as f64,
            t * shards as f64 / 3600.0,
            r.groups.by_key.len()
        );
    }
}

/// A Python and a JavaScript codec's columns against their own bare loops over the same texts:
/// the sweep with the built-in models alone, then with the codec beside them; the difference is
/// what the codec's column adds, to be at most twice the codec's bare loop.
fn codecs(project: &mut Session, root: &Path, count: u64) {
    let mut settings = Settings::new(
        Target::Operation {
            operation: Operation::HexToValue,
        },
        Generator::Random { count, max_len: 8 },
        1,
    );
    settings.shrink = 0;
    let references: Vec<_> = project.backends.clone();
    let base = Sweep::new(settings.clone(), project.profiles(), &references).expect("sweep");
    // Best of 5: the column's cost is the difference of two times that vary from run to run.
    let (alone, _) = best(5, || base.run(&AtomicBool::new(false), &mut |_, _| {}));
    // The texts a codec of 1 to 8 digits is asked, for the bare loops.
    let file =
        std::env::temp_dir().join(format!("plc-conformance-bench-{}.txt", std::process::id()));
    let mut lines = String::new();
    for i in 0..count {
        let p = base.space.point(i);
        if let Data::Text(t) = &p.data {
            if (1..=8).contains(&p.digits) && !t.is_empty() {
                let hex: String = t.iter().map(|b| format!("{b:02x}")).collect();
                lines.push_str(&format!("{hex} {}\n", p.digits));
            }
        }
    }
    std::fs::write(&file, lines).expect("texts written");
    for (name, program) in [("python", "python3"), ("javascript", "node")] {
        let script = root.join(if program == "node" {
            "benches/int_codec.js"
        } else {
            "benches/int_codec.py"
        });
        let script = script.display().to_string();
        let bare = (0..5)
            .filter_map(|_| {
                let out = std::process::Command::new(program)
                    .args([script.as_str(), "--bare", &file.display().to_string()])
                    .output()
                    .ok()?;
                String::from_utf8_lossy(&out.stdout)
                    .trim()
                    .parse::<f64>()
                    .ok()
            })
            .fold(f64::INFINITY, f64::min);
        if !bare.is_finite() {
            println!("codecs: {name}: skipped, `{program}` does not run here");
            continue;
        }
        let mut external = ExternalSettings::new(
            format!("int-{name}"),
            Launch::Exec(vec![program.into(), script]),
        );
        external.timeout = std::time::Duration::from_secs(30);
        let codec = project
            .add(BackendSource::Process(external), false)
            .expect("the codec starts")[0]
            .clone();
        let mut backends = references.clone();
        backends.push(codec);
        let sweep = Sweep::new(settings.clone(), project.profiles(), &backends).expect("sweep");
        let (with, r) = best(5, || sweep.run(&AtomicBool::new(false), &mut |_, _| {}));
        let added = with - alone;
        println!(
            "codecs: {name}: {} random texts (1-8 bytes): the built-in models alone {alone:.3} s, \
             with the codec's column {with:.3} s: the column adds {added:.3} s; the codec's bare \
             loop over the same texts {bare:.3} s: {:.2}x (target <= 2x)",
            r.swept,
            added / bare
        );
    }
    if std::env::var_os("PLC_CONFORMANCE_BENCH_KEEP").is_none() {
        let _ = std::fs::remove_file(&file);
    }
}
