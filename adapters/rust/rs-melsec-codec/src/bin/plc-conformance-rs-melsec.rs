//! The `plc-conformance` command with rs-melsec in process as the backend `rs-melsec`:
//!
//! ```text
//! cargo run --release --bin plc-conformance-rs-melsec -- run --backend rs-melsec \
//!     --known-differences rs-melsec=rs-melsec.known.yaml
//! ```
//!
//! Every decode is a TCP exchange with a one-shot peer on 127.0.0.1: fine for the corpus, slow
//! for a sweep.

use std::process::ExitCode;

fn main() -> ExitCode {
    plc_conformance::command_line(vec![plc_conformance::codec_backend(
        rs_melsec_codec::RsMelsec,
    )])
}
