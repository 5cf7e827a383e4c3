//! The corpus as tests: see `src/libtest.rs` for what each trial is and how the project file's
//! external backends take part.

use std::path::Path;
use std::process::ExitCode;

/// Listing loads and plans the whole corpus, thousands of small allocations, and nextest lists
/// before every run: the allocator the command uses makes that a quarter quicker
/// (docs/performance.md, "Start-up of the test binary").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    plc_conformance::Harness::new(env!("CARGO_MANIFEST_DIR"))
        .with_builtin()
        .project_file(Path::new(env!("CARGO_BIN_EXE_plc-conformance")))
        // Listing (nextest lists before every run) plans the external backends from their
        // answers to hello kept here instead of starting each.
        .hello_cache(Path::new(env!("CARGO_TARGET_TMPDIR")).join("hellos.json"))
        .run()
}
