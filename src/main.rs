/// Sweeps and batched protocol runs build and drop millions of small maps, strings and
/// vectors; mimalloc handles that churn at about half the cost of the system allocator
/// (`docs/performance.md`).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    plc_conformance::cli::main()
}
