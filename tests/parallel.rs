//! `-j/--jobs`: backends run side by side, at most `jobs` at once, and a backend starts as soon
//! as a worker is free.

mod common;

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use common::{reference, session};
use plc_conformance::testing::execute::{execute_all, Pace};
use plc_conformance::{Backend, Fault, Request, Response};

/// The reference model answering each batch after a pause, counting how many backends are
/// answering at the same moment.
struct Slow {
    name: String,
    base: Arc<dyn Backend>,
    pause: Duration,
    running: Arc<AtomicUsize>,
    most: Arc<AtomicUsize>,
}

impl Backend for Slow {
    fn name(&self) -> &str {
        &self.name
    }
    fn profile(&self) -> &str {
        self.base.profile()
    }
    fn describe(&self) -> String {
        "slow".into()
    }
    fn claims(&self, instruction: &str, variant: &str) -> bool {
        self.base.claims(instruction, variant)
    }
    fn execute(&self, request: &Request<'_>) -> Result<Response, Fault> {
        self.base.execute(request)
    }
    fn execute_batch(
        &self,
        requests: &[Request<'_>],
        answered: &mut dyn FnMut(usize),
    ) -> Vec<Result<Response, Fault>> {
        let now = self.running.fetch_add(1, Ordering::SeqCst) + 1;
        self.most.fetch_max(now, Ordering::SeqCst);
        std::thread::sleep(self.pause);
        self.running.fetch_sub(1, Ordering::SeqCst);
        self.base.execute_batch(requests, answered)
    }
}

/// Runs three slow backends (one batch each) with `jobs` workers: the most that ran at once.
fn run(jobs: usize) -> usize {
    let project = session();
    let base = reference(&project, "mitsubishi-iqr");
    let (running, most) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
    let backends: Vec<Arc<dyn Backend>> = ["a", "b", "c"]
        .iter()
        .map(|n| {
            Arc::new(Slow {
                name: format!("slow-{n}"),
                base: base.clone(),
                pause: Duration::from_millis(300),
                running: running.clone(),
                most: most.clone(),
            }) as Arc<dyn Backend>
        })
        .collect();
    let trials: Vec<_> = project
        .plan(&backends)
        .into_iter()
        .filter(|t| t.name().contains("habin-fixed-4-digits-example::rcpu"))
        .filter(|t| !t.is_cross_vendor())
        .collect();
    assert_eq!(
        trials.len(),
        12,
        "HABIN(P) on two variants of three backends"
    );
    let indices: Vec<usize> = (0..trials.len()).collect();
    let mut observed = 0;
    execute_all(
        &trials,
        &indices,
        jobs,
        &AtomicBool::new(false),
        Pace::Ahead,
        |p| {
            if matches!(p, plc_conformance::testing::execute::Progress::Observed(..)) {
                observed += 1;
            }
            std::ops::ControlFlow::Continue(())
        },
    );
    assert_eq!(observed, trials.len());
    most.load(Ordering::SeqCst)
}

#[test]
fn backends_run_side_by_side_up_to_jobs() {
    // How many ran at once is what "side by side, up to jobs" means; how long that took depends
    // on the machine.
    assert_eq!(run(3), 3, "three backends, three workers");
    assert_eq!(run(2), 2);
    assert_eq!(run(1), 1);
}

/// With `Pace::Judged` a stop set while the first chunk's observations are handed on holds
/// every later chunk back, however slowly they are handed on; with `Pace::Ahead` execution may
/// run past it (the executor does not wait), which is why `--fail-fast` asks for `Judged`.
#[test]
fn a_judged_pace_starts_no_chunk_after_a_stop_set_while_judging() {
    let project = session();
    let model = reference(&project, "mitsubishi-iqr");
    let trials: Vec<_> = project
        .plan(std::slice::from_ref(&model))
        .into_iter()
        .filter(|t| t.skip.is_none() && !t.is_cross_vendor())
        .collect();
    let chunk = model.chunk_trials();
    assert!(trials.len() > 3 * chunk, "{} trials", trials.len());
    let indices: Vec<usize> = (0..trials.len()).collect();
    let observed = |pace: Pace| {
        let stop = AtomicBool::new(false);
        let mut observed = 0;
        execute_all(&trials, &indices, 1, &stop, pace, |p| {
            if matches!(p, plc_conformance::testing::execute::Progress::Observed(..)) {
                observed += 1;
                // A slow reporter: the first verdict is a failure, and writing it takes time.
                if observed == 1 {
                    std::thread::sleep(Duration::from_millis(200));
                    stop.store(true, Ordering::Relaxed);
                }
            }
            std::ops::ControlFlow::Continue(())
        });
        observed
    };
    assert_eq!(observed(Pace::Judged), chunk);
    assert!(observed(Pace::Ahead) > chunk);
}
