//! The `plc-conformance` command with oms-modbus in process as the backend `oms-modbus`:
//!
//! ```text
//! cargo run --release --bin plc-conformance-oms-modbus -- run --backend oms-modbus \
//!     --known-differences oms-modbus=oms-modbus.known.yaml
//! ```
//!
//! Every decode goes through an async client and costs at least its 1 ms stale-data poll
//! (src/transport/send_recv.rs:59): fine for the corpus, slow for a sweep.

use std::process::ExitCode;

fn main() -> ExitCode {
    plc_conformance::command_line(vec![plc_conformance::codec_backend(
        oms_modbus_codec::OmsModbus::new(),
    )])
}
