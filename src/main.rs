/// Sweeps and batched protocol runs build and drop millions of small maps, strings and
/// vectors; with mimalloc the batched protocol benchmark goes from about 73,000 to 114,000
/// cases/s (`docs/performance.md`, "What made it fast").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    plc_conformance::main()
}
