//! The `plc-conformance` command with rmodbus in process as the backend `rmodbus`:
//!
//! ```text
//! cargo run --release -p rmodbus-codec --bin plc-conformance-rmodbus -- \
//!     sweep --operation hex-to-value --generator full --each-text --backend rmodbus
//! ```
//!
//! Every command works on it (`run`, `diff`, `list`, `sweep`); a sweep of every 4-byte text calls
//! rmodbus directly, text by text.

use std::process::ExitCode;

fn main() -> ExitCode {
    plc_conformance::command_line(vec![plc_conformance::codec_backend(rmodbus_codec::Rmodbus)])
}
