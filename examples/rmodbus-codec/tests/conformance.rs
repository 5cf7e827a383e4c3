//! rmodbus against the cross-vendor corpus, in this crate's own `cargo test`: one libtest trial
//! per cross-vendor case its codec implements, with diffs and known differences.

use std::path::Path;
use std::process::ExitCode;

use plc_conformance::Harness;
use rmodbus_codec::Rmodbus;

fn main() -> ExitCode {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    // The corpus and profiles built into the crate: what a dependent has.
    Harness::embedded()
        .codec(Rmodbus, Some(here.join("rmodbus.known.yaml")))
        .run()
}
