//! rs-melsec against the MC protocol ASCII corpus, in this crate's own `cargo test`: one
//! libtest trial per protocol-field case its codec implements, with diffs and known differences.

use std::path::Path;
use std::process::ExitCode;

use plc_conformance::Harness;
use rs_melsec_codec::RsMelsec;

fn main() -> ExitCode {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    Harness::new(here.join("../../.."))
        .codec(RsMelsec, Some(here.join("rs-melsec.known.yaml")))
        .run()
}
