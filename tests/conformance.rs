//! The corpus as tests: see `plc_conformance::testing::libtest` for what each trial is and how the
//! project file's external backends take part.

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    plc_conformance::testing::libtest::main(
        Path::new(env!("CARGO_MANIFEST_DIR")),
        Path::new(env!("CARGO_BIN_EXE_plc-conformance")),
        Vec::new(),
    )
}
