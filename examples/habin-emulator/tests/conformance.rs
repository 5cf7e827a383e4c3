//! The emulator against the corpus, in this crate's own `cargo test`: one libtest trial per
//! HABIN case and per cross-vendor case lowered onto HABIN, with diffs; the instructions it
//! does not claim are listed as skipped with the reason.

use std::process::ExitCode;

use habin_emulator::HabinEmulator;
use plc_conformance::Harness;

fn main() -> ExitCode {
    // The corpus and profiles built into the crate: what a dependent has.
    Harness::embedded().emulator(HabinEmulator, None).run()
}
