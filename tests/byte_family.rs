//! A byte-addressed family end to end: a toy family in a test fixture (`tests/fixtures/
//! byte-family`: a profile with `memory_unit: byte`, Siemens-style devices `MB20` and
//! `DB1.DBB10`, vectors, and a Python backend speaking protocol version 3) loads, runs, is
//! judged and is reported in every format, with values shown as bytes.

mod common;

use std::path::PathBuf;

use plc_conformance::testing::session::Session;
use plc_conformance::Device;
use plc_conformance::Unit;
use plc_conformance::{Paths, Project};

fn fixture() -> PathBuf {
    common::root().join("tests/fixtures/byte-family")
}

fn backend() -> String {
    let script = fixture().join("toy_ath.py");
    format!("external:toy=python3 {}", script.display())
}

/// The binary on the fixture with the toy backend, extra environment and arguments.
fn run(env: &[(&str, &str)], args: &[&str]) -> (i32, String, String) {
    let mut command = common::bin();
    command
        .args(["--root", fixture().to_str().unwrap_or(".")])
        .args(["run", "--backend", &backend()])
        .args(args);
    for (k, v) in env {
        command.env(k, v);
    }
    let out = command.output().expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_toy_family_loads_in_bytes() {
    let project = match Project::load(&Paths::under(&fixture())) {
        Ok(p) => Session::with_references(p),
        Err(e) => panic!("the fixture does not load:\n{e}"),
    };
    let profile = project
        .profiles()
        .get("toy-bytes")
        .expect("the toy profile");
    assert_eq!(profile.unit, Unit::Byte);
    let block: Device = "DB7.DBB3".parse().expect("a data block byte");
    assert_eq!(block.code(), "DB7.DBB");
    // DB#.DBB names DB7.DBB, and its byte 3 exists.
    assert!(profile.word_exists_anywhere(&block));
    assert!(!profile.word_exists_anywhere(&"DB7.DBB64".parse().expect("device")));
    assert_eq!(project.corpus.cases.len(), 4);
    let odd = project
        .corpus
        .cases
        .iter()
        .find(|c| c.id == "ath-odd-count")
        .expect("the odd-count case");
    // `ascii` is one character per byte in byte memory, not two per word.
    let before: Vec<(String, u32)> = odd
        .before
        .iter()
        .map(|(d, v)| (d.to_string(), *v))
        .collect();
    assert_eq!(
        before,
        [
            ("MB10".into(), 0x35),
            ("MB11".into(), 0x41),
            ("MB12".into(), 0x38)
        ]
    );
}

#[test]
fn a_value_wider_than_a_byte_is_a_load_error() {
    let dir = common::scratch();
    common::copy_dir(&fixture().join("vendors"), &dir.path().join("vendors"));
    let vectors = dir.path().join("vectors/toy-bytes");
    std::fs::create_dir_all(&vectors).expect("mkdir");
    let text = std::fs::read_to_string(fixture().join("vectors/toy-bytes/ath.yaml"))
        .expect("the fixture vectors")
        .replace("MB20: [41H, 46H]", "MB20: [141H, 46H]");
    std::fs::write(vectors.join("ath.yaml"), text).expect("write");
    let err = match Project::load(&Paths::under(dir.path())) {
        Ok(_) => panic!("a 9-bit value in byte memory loaded"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("`141H` is too wide for 8 bits"), "{err}");
}

#[test]
fn a_conforming_toy_passes_in_every_format() {
    if !common::python() {
        return;
    }
    for format in ["text", "json", "junit", "html", "matrix"] {
        let (code, stdout, stderr) = run(&[], &["--format", format]);
        assert_eq!(code, 0, "--format {format}: {stdout}\n{stderr}");
        match format {
            "text" => assert!(stdout.contains("4 passed, 0 failed"), "{stdout}"),
            "json" => {
                let doc: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
                assert_eq!(doc["summary"]["passed"], 4, "{stdout}");
            }
            "junit" => assert!(stdout.contains("tests=\"4\""), "{stdout}"),
            "html" => assert!(stdout.contains("ath-four-characters"), "{stdout}"),
            _ => assert!(!stdout.is_empty(), "--format {format} wrote nothing"),
        }
    }
}

#[test]
fn a_wrong_toy_shows_byte_differences_in_every_format() {
    if !common::python() {
        return;
    }
    let wrong = [("TOY_WRONG", "1")];
    let (code, text, _) = run(&wrong, &[]);
    assert_eq!(code, 1, "{text}");
    for line in [
        "operands:    IN=MB10 N=K4 OUT=DB1.DBB0",
        "memory set:  MB10=30H MB11=31H MB12=32H MB13=33H",
        "-DB1.DBB0 01H  \"\\x01\"",
        "+DB1.DBB0 10H  \"\\x10\"",
        "-MB30     AFH  \"\\xAF\"",
        "1 passed, 3 failed",
    ] {
        assert!(text.contains(line), "missing `{line}` in:\n{text}");
    }
    let (code, json, _) = run(&wrong, &["--format", "json"]);
    assert_eq!(code, 1);
    let rows = r#""device":"DB1.DBB0","unit":"byte","before":"#;
    assert!(json.replace([' ', '\n'], "").contains(rows), "{json}");
    assert!(json.contains("\"10H\""), "{json}");
    let (code, junit, _) = run(&wrong, &["--format", "junit"]);
    assert_eq!(code, 1);
    assert!(junit.contains("failures=\"3\""), "{junit}");
    let (code, html, _) = run(&wrong, &["--format", "html"]);
    assert_eq!(code, 1);
    assert!(html.contains("DB1.DBB0"), "the HTML report names the byte");
}

#[test]
fn a_backend_of_protocol_2_is_refused_for_byte_memory() {
    if !common::python() {
        return;
    }
    let (code, stdout, stderr) = run(&[("TOY_PROTOCOL", "2")], &[]);
    assert_eq!(code, 2, "{stdout}\n{stderr}");
    assert!(
        stderr.contains("profile `toy-bytes`'s memory unit is a byte")
            && stderr.contains("needs version 3"),
        "{stderr}"
    );
}
