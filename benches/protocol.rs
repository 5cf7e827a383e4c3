//! Cases per second through the external-backend protocol.
//!
//! `cargo bench --bench protocol` (add `-- --quick` for a smoke run). The corpus's iQ-R
//! requests (both fills) are sent, over and over, to
//! - the native adapter: `plc-conformance serve` (the reference model behind the protocol);
//! - a trivial Python adapter written with `adapters/python/plc_adapter.py`;
//!
//! each with a persistent process and batched messages (the normal way), a persistent process
//! and one case per message, and one process per case. The built-in model called directly is
//! the ceiling. Each figure is the best of a few rounds. Results: `docs/performance.md`.

/// The allocator the `plc-conformance` binary uses, so that both sides measure alike.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::Path;
use std::time::{Duration, Instant};

use plc_conformance::testing::backend::external::ExternalBackend;
use plc_conformance::testing::execute::{images, requests};
use plc_conformance::testing::model::project::{ExternalSettings, Launch};
use plc_conformance::testing::session::Session;
use plc_conformance::Image;
use plc_conformance::{Backend, Request};
use plc_conformance::{Paths, Project};

struct Setup {
    name: &'static str,
    launch: Launch,
    batch: usize,
    persistent: bool,
    cases: usize,
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    // A word that is not a flag selects setups by name; libtest-style flags (`--bench`) are
    // ignored.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let session = match Project::load(&Paths::under(root)) {
        Ok(s) => Session::with_references(s),
        Err(e) => {
            eprintln!("the corpus does not load:\n{e}");
            std::process::exit(2);
        }
    };
    let reference: Vec<_> = session
        .backends
        .iter()
        .filter(|b| b.name() == "iqr")
        .cloned()
        .collect();
    let trials: Vec<_> = session
        .plan(&reference)
        .into_iter()
        .filter(|t| t.skip.is_none())
        .collect();
    let images: Vec<Vec<Image>> = trials.iter().map(images).collect();
    let base: Vec<Request<'_>> = trials
        .iter()
        .zip(&images)
        .flat_map(|(t, i)| requests(t, i))
        .collect();
    if base.is_empty() {
        eprintln!("the corpus has no iQ-R request to send");
        std::process::exit(2);
    }
    let scale = if quick { 10 } else { 1 };
    let binary = env!("CARGO_BIN_EXE_plc-conformance").to_string();
    let serve = |batch, persistent, cases| {
        (
            Launch::Exec(vec![
                binary.clone(),
                "--root".into(),
                root.display().to_string(),
                "serve".into(),
                "--profile".into(),
                "mitsubishi-iqr".into(),
            ]),
            batch,
            persistent,
            cases,
        )
    };
    // The interpreter itself, not a launcher script in front of it (pyenv's shim adds a
    // shell start to every process).
    let interpreter = std::process::Command::new("python3")
        .args(["-c", "import sys; print(sys.executable)"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .filter(|p| !p.is_empty())
        .unwrap_or_else(|| "python3".into());
    let python = |batch, persistent, cases| {
        (
            Launch::Exec(vec![
                interpreter.clone(),
                root.join("benches/trivial_adapter.py")
                    .display()
                    .to_string(),
            ]),
            batch,
            persistent,
            cases,
        )
    };
    let setups: Vec<Setup> = [
        (
            "native, persistent, batched (256/message)",
            serve(256, true, 400_000),
        ),
        (
            "native, persistent, one case per message",
            serve(1, true, 40_000),
        ),
        ("native, one process per case", serve(1, false, 400)),
        (
            "python, persistent, batched (256/message)",
            python(256, true, 100_000),
        ),
        (
            "python, persistent, one case per message",
            python(1, true, 20_000),
        ),
        ("python, one process per case", python(1, false, 100)),
    ]
    .into_iter()
    .filter(|(name, _)| filter.as_ref().is_none_or(|f| name.contains(f.as_str())))
    .map(|(name, (launch, batch, persistent, cases))| Setup {
        name,
        launch,
        batch,
        persistent,
        cases: (cases / scale).max(10),
    })
    .collect();

    println!("| setup | cases | best time | cases/s |");
    println!("|---|---:|---:|---:|");
    let direct = &reference[0];
    let requests = cycle(&base, if quick { 40_000 } else { 1_000_000 });
    let best = best_of(3, || {
        let start = Instant::now();
        for r in &requests {
            let _ = direct.execute(r);
        }
        start.elapsed()
    });
    row("built-in model, called directly", requests.len(), best);

    for setup in setups {
        let mut spec = ExternalSettings::new("bench", setup.launch);
        spec.batch = setup.batch;
        spec.persistent = setup.persistent;
        spec.timeout = Duration::from_secs(30);
        let backend = match ExternalBackend::start(spec, session.profiles()) {
            Ok(b) => b,
            Err(e) => {
                println!("| {} | - | - | not run: {e} |", setup.name);
                continue;
            }
        };
        let requests = cycle(&base, setup.cases);
        let rounds = if setup.persistent { 3 } else { 1 };
        let best = best_of(rounds, || {
            let start = Instant::now();
            let answers = backend.execute_batch(&requests, &mut |_| {});
            let elapsed = start.elapsed();
            let faults = answers.iter().filter(|a| a.is_err()).count();
            assert_eq!(faults, 0, "{}: {faults} faults", setup.name);
            elapsed
        });
        row(setup.name, requests.len(), best);
        backend.shutdown();
    }
}

fn cycle<'a>(base: &[Request<'a>], n: usize) -> Vec<Request<'a>> {
    base.iter().copied().cycle().take(n).collect()
}

fn best_of(rounds: usize, mut f: impl FnMut() -> Duration) -> Duration {
    (0..rounds).map(|_| f()).min().unwrap_or_default()
}

fn row(name: &str, cases: usize, time: Duration) {
    let rate = cases as f64 / time.as_secs_f64();
    println!(
        "| {name} | {cases} | {:.3} s | {} |",
        time.as_secs_f64(),
        thousands(rate)
    );
}

fn thousands(x: f64) -> String {
    plc_conformance::testing::sweep::render::thousands(x.round() as u64)
}
