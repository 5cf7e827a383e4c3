//! A protocol codec served by a process, run from the command line, is judged by its protocol's
//! own manual: each failure names the rule it breaks and its page. The codecs written in Rust
//! that hold the protocol-field corpora to the rules, with no binary, are in
//! src/session/white_box/protocols.rs.

mod common;

use common::root;
use rstest::rstest;

/// A Modbus ASCII codec served by the Python helper, run from the command line: written from
/// the rules it conforms on every protocol-field case it is asked (and on no cross-vendor one);
/// reading with `bytes.fromhex` it fails on B3 and LEN, naming them; never comparing its LRC
/// it fails on B7.
#[rstest]
#[case::strict("strict", 0, &[])]
#[case::fromhex("fromhex", 1, &["modbus-ascii/B3 (mbsl p.17", "modbus-ascii/LEN"])]
#[case::never_compares("never-compares", 1, &["modbus-ascii/B7 (mbsl p.18"])]
fn a_python_codec_is_judged_by_its_protocol(
    #[case] mode: &str,
    #[case] status: i32,
    #[case] rules: &[&str],
) {
    if !common::python() {
        return;
    }
    let script = root().join("tests/fixtures/external/modbus_ascii_codec.py");
    let backend = format!("external:mb=python3 {} {mode}", script.display());
    let out = common::cli(&["run", "--backend", &backend]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(status), "{stdout}");
    assert!(!stdout.contains("cross-vendor"), "{stdout}");
    for rule in rules {
        assert!(
            stdout.contains(&format!("rule:        {rule}")),
            "{rule}: {stdout}"
        );
        assert!(stdout.contains("protocol::mb::modbus-ascii::"), "{stdout}");
    }
    let passed: usize = stdout
        .lines()
        .find_map(|l| {
            (l.strip_prefix("protocol modbus-ascii: ")?
                .split(' ')
                .next()?)
            .parse()
            .ok()
        })
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(passed >= 20, "{passed} passed: {stdout}");
}
