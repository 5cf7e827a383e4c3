//! oms-modbus against the Modbus ASCII protocol corpus, in this crate's own `cargo test`: one
//! libtest trial per protocol-field case its codec implements, with diffs and known differences.

use std::path::Path;
use std::process::ExitCode;

use oms_modbus_codec::OmsModbus;
use plc_conformance::Harness;

fn main() -> ExitCode {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    Harness::new(here.join("../../.."))
        .codec(OmsModbus::new(), Some(here.join("oms-modbus.known.yaml")))
        .run()
}
