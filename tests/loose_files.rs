//! Every file and handshake the harness reads besides the corpus is checked as strictly as the
//! corpus: nesting refused before the document is built, duplicate and contradictory
//! known-differences entries refused with their line, absurd codec shapes and unknown
//! readings refused at the handshake, and an `--oracle` that names no reading refused.

mod common;

use common::{cli, root, scratch};
use plc_conformance::testing::load::load_known;
use plc_conformance::{Paths, Project};

/// Text nested `levels` flow sequences deep.
fn nested(levels: usize) -> String {
    format!("{}{}", "[".repeat(levels), "]".repeat(levels))
}

const TOO_DEEP: &str = "nested more than 64 levels deep";

#[test]
fn a_deeply_nested_known_differences_file_is_refused_with_its_line() {
    let project = Project::load(&Paths::under(root())).expect("the corpus loads");
    let dir = scratch();
    let file = dir.path().join("known.yaml");
    std::fs::write(&file, format!("differences:\n  - {}\n", nested(100_000))).expect("write");
    let errors = load_known(&file, None, &project.corpus, true)
        .expect_err("refused")
        .to_string();
    assert!(
        errors.contains(&format!("known.yaml:2: {TOO_DEEP}")),
        "{errors}"
    );
}

#[test]
fn a_deeply_nested_project_file_or_profile_is_refused_with_its_line() {
    let dir = scratch();
    let project = dir.path().join("project.yaml");
    std::fs::write(&project, format!("backends:\n  x: {}\n", nested(100_000))).expect("write");
    let out = cli(&["--config", &project.display().to_string(), "list"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("project.yaml:2: {TOO_DEEP}")),
        "{stderr}"
    );

    let vendors = dir.path().join("vendors");
    std::fs::create_dir(&vendors).expect("mkdir");
    std::fs::write(
        vendors.join("deep.yaml"),
        format!("id: deep\nname: {}\n", nested(100_000)),
    )
    .expect("write");
    let out = cli(&["--vendors", &vendors.display().to_string(), "validate"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("deep.yaml:2: {TOO_DEEP}")),
        "{stderr}"
    );
}

/// Loads `text` as a codec-level backend's known-differences file (no profile: the
/// cross-vendor cases only) against the project's corpus.
fn codec_known(text: &str) -> Result<(), String> {
    let project = Project::load(&Paths::under(root())).expect("the corpus loads");
    let dir = scratch();
    let file = dir.path().join("known.yaml");
    std::fs::write(&file, text).expect("write");
    load_known(&file, None, &project.corpus, true)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn a_duplicate_or_contradictory_known_difference_is_refused_with_its_line() {
    // The same cross-vendor case twice, for a codec-level backend.
    let errors = codec_known(
        "differences:\n\
         - {case: xv-h2v-1-digit, reason: one}\n\
         - {case: xv-h2v-1-digit, reason: two}\n",
    )
    .expect_err("a duplicate case");
    assert!(
        errors.contains(":3: differences[1].case: the same trials are already listed at"),
        "{errors}"
    );
    // One cause named twice, and two causes covering the same inputs.
    let errors = codec_known(
        "differences:\n\
         - {cause: takes lowercase, kind: bug, input: [lowercase]}\n\
         - {cause: takes lowercase, kind: bug, cases: [xv-h2v-1-digit]}\n\
         - {cause: another name, kind: bug, input: [lowercase]}\n",
    )
    .expect_err("duplicate causes");
    for expected in [
        ":3: differences[1].cause: the same cause is already listed at",
        ":4: differences[2].cause: the same cause is already listed at",
    ] {
        assert!(errors.contains(expected), "{expected}\nin:\n{errors}");
    }
    // A case and a cause in one entry: which does it list?
    let errors = codec_known(
        "differences:\n  - {case: xv-h2v-1-digit, cause: takes lowercase, kind: bug}\n",
    )
    .expect_err("case and cause");
    assert!(
        errors.contains(":2: differences[0].cause: an entry of one `case` gives its `reason`"),
        "{errors}"
    );
    // The same cause for another variant is another entry.
    codec_known(
        "differences:\n\
         - {case: xv-h2v-1-digit, reason: one}\n\
         - {cause: takes lowercase, kind: bug, input: [lowercase]}\n",
    )
    .expect("distinct entries load");
}

#[test]
fn an_oracle_that_names_no_reading_is_refused_even_with_no_codec() {
    let out = cli(&["sweep", "--operation", "hex-to-value", "--oracle", "nope"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--oracle `nope` is not a built-in reading of hex-to-value"),
        "{stderr}"
    );
}

/// Lists the trials of a codec-level backend that answers hello with `hex_to_value` as its
/// capabilities (a handshake, no request): the exit status and what it said on stderr.
fn hello(hex_to_value: &str) -> (Option<i32>, String) {
    let dir = scratch();
    let script = dir.path().join("hello.sh");
    std::fs::write(
        &script,
        format!(
            "printf '%s\\n' '{{\"type\":\"hello\",\"protocol\":4,\"backend\":{{\"name\":\"odd\",\
             \"version\":\"1\"}},\"capabilities\":{{\"codec\":{{\"hex-to-value\":{hex_to_value}}}}}}}'\n\
             cat > /dev/null\n"
        ),
    )
    .expect("write");
    let backend = format!("external:odd=sh {}", script.display());
    let out = cli(&["list", "--backend", &backend]);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

#[test]
fn a_codec_with_an_absurd_shape_or_an_unknown_reading_is_refused_at_the_handshake() {
    for (capabilities, expected) in [
        (
            r#"{"digits":[4],"widths":{}}"#,
            "claims hex-to-value widths for no digit count",
        ),
        (
            r#"{"digits":[4],"widths":{"4":16,"04":32}}"#,
            "claims hex-to-value widths for `04` digits; give a count from 1 to 16, written as a plain number",
        ),
        (
            r#"{"digits":[1000000000]}"#,
            "claims hex-to-value of 1000000000 digits; give counts from 1 to 16",
        ),
        (r#"{"digits":[]}"#, "claims hex-to-value of no digit count"),
        (r#"{"digits":[4,4]}"#, "claims hex-to-value of 4 digits twice"),
        (
            r#"{"digits":[4],"reading":"fx5/nothing"}"#,
            "declares hex-to-value reading `fx5/nothing`, which is not a built-in reading; the readings are: ",
        ),
    ] {
        let (code, said) = hello(capabilities);
        assert_eq!(code, Some(2), "{capabilities}: {said}");
        assert!(said.contains(expected), "{capabilities}: {said}");
    }
    // A sane hello of the same shape is taken.
    let (code, said) = hello(r#"{"digits":[4],"widths":{"4":16},"reading":"fx5/hexa-16bit"}"#);
    assert_eq!(code, Some(0), "{said}");
}
