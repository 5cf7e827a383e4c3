//! Every class of bad vector is a load error naming the file, the line and the key, and saying
//! what was expected. Nothing panics and nothing is skipped.

#[cfg(test)]
use std::path::Path;

use super::profiles;
use crate::error_chain::chain;
use crate::load::{load_profiles, CorpusBuilder, LoadError};
use crate::model::profile::Profiles;
use rstest::rstest;

const HEADER: &str = "\
instructions: [HABIN]
profiles: [mitsubishi-iqr]
source: {manual: iqr-instructions-ja, page: 478}
cases:
";

/// A valid case; each row below breaks one thing in it.
const GOOD_CASE: &str = "  - id: good
    basis: manual
    cite: example
    flags: {SM705: off}
    operands: {s: D100, d: D200}
    before:
      D100: 4135H
      D101: 4438H
    expect:
      after: {D200: 5A8DH}
";

fn load(text: &str) -> Result<usize, Vec<LoadError>> {
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("bad.yaml"), text, &profiles());
    builder.finish().map(|c| c.cases.len()).map_err(|e| e.0)
}

/// The good case with each `(from, to)` of `changes` replaced once, in order, loaded.
fn load_changed(changes: &[(&str, &str)]) -> Result<usize, Vec<LoadError>> {
    let case = changes
        .iter()
        .fold(GOOD_CASE.to_string(), |case, (from, to)| {
            case.replacen(*from, to, 1)
        });
    load(&format!("{HEADER}{case}"))
}

#[test]
fn the_good_case_loads() {
    assert_eq!(load(&format!("{HEADER}{GOOD_CASE}")), Ok(1));
}

#[rstest]
// Shape: unknown keys at every level, wrong types, bad YAML.
#[case::unknown_case_key(
    "    basis: manual",
    "    basis: manual\n    colour: red",
    7,
    "cases[0].colour",
    "unknown field `colour`"
)]
#[case::unknown_expect_key(
    "      after: {D200: 5A8DH}",
    "      after: {D200: 5A8DH}\n      writes: {}",
    15,
    "cases[0].expect.writes",
    "unknown field `writes`"
)]
#[case::unknown_basis(
    "basis: manual",
    "basis: guessed",
    6,
    "cases[0].basis",
    "unknown variant `guessed`"
)]
#[case::bad_text_key(
    "D100: 4135H",
    "D100: {text: \"5A\"}",
    11,
    "cases[0].before.D100",
    "unknown field `text`, expected `ascii` or `ascii_words`"
)]
#[case::yaml_syntax(
    "operands: {s: D100, d: D200}",
    "operands: {s: D100, d: D200",
    10,
    "",
    "did not find expected ',' or '}', while parsing a flow mapping at line 9"
)]
#[case::duplicate_key(
    "      D101: 4438H",
    "      D101: 4438H\n      D101: 4438H",
    13,
    "cases[0].before.D101",
    "duplicate key"
)]
// Devices and values.
#[case::malformed_device_operand(
    "s: D100,",
    "s: d100,",
    9,
    "cases[0].operands.s",
    "`d100` is not a device name"
)]
#[case::malformed_device_key(
    "D100: 4135H",
    "DX: 4135H",
    11,
    "cases[0].before.DX",
    "is not a device name"
)]
#[case::malformed_value(
    "D100: 4135H",
    "D100: 41G5H",
    11,
    "cases[0].before.D100",
    "`41G5H` is not a value"
)]
#[case::value_too_wide(
    "D100: 4135H",
    "D100: 14135H",
    11,
    "cases[0].before.D100",
    "is too wide for 16 bits"
)]
#[case::plain_value_too_wide(
    "D100: 4135H",
    "D100: 70000",
    11,
    "cases[0].before.D100",
    "is too wide for 16 bits"
)]
#[case::list_value_too_wide(
    "D100: 4135H",
    "D100: [4135H, K70000]",
    11,
    "cases[0].before.D100[1]",
    "is too wide for 16 bits"
)]
#[case::non_byte_text(
    "D100: 4135H",
    "D100: {ascii: \"5€\"}",
    11,
    "cases[0].before.D100",
    "above FFH"
)]
#[case::word_set_twice(
    "D101: 4438H",
    "D101: {ascii: \"8D\"}\n      D100: {ascii: \"5A8D\"}",
    12,
    "cases[0].before.D101",
    "D101 is set twice (also by `D100`)"
)]
#[case::device_out_of_range(
    "D200: 5A8DH",
    "D99999: 5A8DH",
    14,
    "cases[0].expect.after.D99999",
    "does not exist on any mitsubishi-iqr variant"
)]
#[case::device_not_in_profile(
    "D100: 4135H",
    "W100: 4135H",
    11,
    "cases[0].before.W100",
    "unknown device `W`"
)]
// Names the profile does not define.
#[case::unknown_flag(
    "SM705: off",
    "SM8161: off",
    8,
    "cases[0].flags.SM8161",
    "unknown flag for these instructions `SM8161`; expected one of: SM705"
)]
#[case::bad_flag_value(
    "SM705: off",
    "SM705: maybe",
    8,
    "cases[0].flags.SM705",
    "expected `on` or `off`"
)]
#[case::unknown_operand(
    "d: D200}",
    "d: D200, n: K4}",
    9,
    "cases[0].operands.n",
    "unknown operand `n`; expected one of: d, s"
)]
#[case::missing_operand(
    ", d: D200}",
    "}",
    9,
    "cases[0].operands",
    "missing operand `d` of HABIN"
)]
#[case::constant_not_allowed(
    "s: D100,",
    "s: K4,",
    9,
    "cases[0].operands.s",
    "takes a device (D), not a constant"
)]
#[case::unknown_variant(
    "    basis: manual",
    "    basis: manual\n    variants: [r99]",
    7,
    "cases[0].variants[0]",
    "unknown variant `r99`; expected one of: rcpu, rcpu-no-sm705"
)]
#[case::error_as_flag(
    "after: {D200: 5A8DH}",
    "error: M8004",
    14,
    "cases[0].expect.error",
    "reports errors as a code in SD0"
)]
#[case::bare_decimal_error_code(
    "after: {D200: 5A8DH}",
    "error: 3401",
    14,
    "cases[0].expect.error",
    "`3401` is a decimal number, but error codes are written in hex as the manuals write them: did you mean `3401H`?"
)]
// Nothing that silently means nothing.
#[case::no_variant(
    "    basis: manual",
    "    basis: manual\n    variants: []",
    7,
    "cases[0].variants",
    "an empty list runs the case on no variant"
)]
#[case::error_zero(
    "after: {D200: 5A8DH}",
    "error: 0",
    14,
    "cases[0].expect.error",
    "`0` is not an error code: mitsubishi-iqr reports no error as 0 in SD0; write `none`"
)]
#[case::error_k0(
    "after: {D200: 5A8DH}",
    "error: K0",
    14,
    "cases[0].expect.error",
    "`K0` is not an error code"
)]
#[case::error_null(
    "after: {D200: 5A8DH}",
    "error: ~",
    14,
    "cases[0].expect",
    "an empty `error:` says nothing: write `none` for no error"
)]
#[case::error_empty(
    "after: {D200: 5A8DH}",
    "error:",
    14,
    "cases[0].expect",
    "an empty `error:` says nothing"
)]
#[case::ascii_number(
    "D100: 4135H",
    "D100: {ascii: 5}",
    11,
    "cases[0].before.D100.ascii",
    "expected a YAML string"
)]
#[case::value_far_too_wide(
    "D100: 4135H",
    "D100: 99999999999999999999H",
    11,
    "cases[0].before.D100",
    "`99999999999999999999H` is too wide for 16 bits"
)]
#[case::control_character(
    "cite: example",
    "cite: exa\u{1b}[31mmple",
    7,
    "",
    "control character U+001B"
)]
#[case::second_document(
    "      after: {D200: 5A8DH}\n",
    "      after: {D200: 5A8DH}\n---\ncases: []\n",
    15,
    "",
    "a second YAML document"
)]
// Rules of the format.
#[case::manual_without_cite(
    "    cite: example\n",
    "",
    5,
    "cases[0]",
    "missing cite: `basis: manual` must say where"
)]
#[case::inferred_with_empty_cite(
    "basis: manual\n    cite: example",
    "basis: inferred\n    cite: \"  \"",
    5,
    "cases[0]",
    "missing cite: `basis: inferred`"
)]
#[case::expect_missing(
    "    expect:\n      after: {D200: 5A8DH}\n",
    "",
    5,
    "cases[0]",
    "missing expect"
)]
#[case::bad_id(
    "id: good",
    "id: Good Case",
    5,
    "cases[0].id",
    "must be lowercase letters"
)]
fn bad_case_is_reported(
    #[case] find: &str,
    #[case] replace: &str,
    #[case] line: usize,
    #[case] key: &str,
    #[case] message: &str,
) {
    assert!(
        GOOD_CASE.contains(find),
        "the row's `find` text is not in the good case"
    );
    let text = format!("{HEADER}{}", GOOD_CASE.replacen(find, replace, 1));
    let errors = load(&text).expect_err("the bad case loaded");
    let rendered: Vec<String> = errors.iter().map(|e| chain(e)).collect();
    let hit = errors.iter().find(|e| chain(*e).contains(message));
    let Some(e) = hit else {
        panic!("no error says `{message}`; got {rendered:#?}");
    };
    assert_eq!(e.file, Path::new("bad.yaml"));
    assert_eq!(e.line, Some(line), "wrong line in {e}");
    assert_eq!(e.key.as_deref().unwrap_or(""), key, "wrong key in {e}");
    assert!(chain(e).starts_with(&format!("bad.yaml:{line}: ")), "{e}");
}

#[rstest]
#[case::unknown_profile(
    "profiles: [mitsubishi-iqr]",
    "profiles: [siemens-s7]",
    2,
    "profiles[0]",
    "unknown profile `siemens-s7`"
)]
#[case::unknown_instruction(
    "instructions: [HABIN]",
    "instructions: [HABIM]",
    1,
    "instructions[0]",
    "unknown instruction `HABIM`"
)]
#[case::unknown_manual(
    "manual: iqr-instructions-ja",
    "manual: fx5-manual",
    3,
    "source.manual",
    "unknown manual `fx5-manual`"
)]
#[case::unknown_top_key("cases:", "title: x\ncases:", 4, "title", "unknown field `title`")]
#[case::no_profiles(
    "profiles: [mitsubishi-iqr]",
    "profiles: []",
    2,
    "profiles",
    "missing profile"
)]
fn bad_header_is_reported(
    #[case] find: &str,
    #[case] replace: &str,
    #[case] line: usize,
    #[case] key: &str,
    #[case] message: &str,
) {
    let text = format!("{}{GOOD_CASE}", HEADER.replacen(find, replace, 1));
    let errors = load(&text).expect_err("the bad header loaded");
    let e = errors
        .iter()
        .find(|e| chain(*e).contains(message))
        .unwrap_or_else(|| panic!("no error says `{message}`: {errors:#?}"));
    assert_eq!(e.line, Some(line), "wrong line in {e}");
    assert_eq!(e.key.as_deref().unwrap_or(""), key, "wrong key in {e}");
}

#[test]
fn duplicate_ids_are_reported_within_a_file_and_across_files() {
    let profiles = profiles();
    let text = format!("{HEADER}{GOOD_CASE}{GOOD_CASE}");
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("one.yaml"), &text, &profiles);
    builder.add_file(
        Path::new("two.yaml"),
        &format!("{HEADER}{GOOD_CASE}"),
        &profiles,
    );
    let errors = builder.finish().expect_err("duplicates loaded").0;
    let rendered: Vec<String> = errors.iter().map(|e| chain(e)).collect();
    assert_eq!(
        rendered,
        vec![
            "one.yaml:15: cases[1].id: duplicate case id `good`, first used at one.yaml:5",
            "two.yaml:5: cases[0].id: duplicate case id `good`, first used at one.yaml:5",
        ]
    );
}

#[test]
fn every_problem_in_a_file_is_reported_not_just_the_first() {
    let text = format!(
        "{HEADER}{}",
        GOOD_CASE.replacen("SM705: off", "SM999: off", 1).replacen(
            "D200: 5A8DH",
            "D200: 15A8DH",
            1
        )
    );
    let errors = load(&text).expect_err("loaded");
    assert_eq!(errors.len(), 2, "{errors:#?}");
}

#[test]
fn unspecified_cases_need_no_cite_or_expectation() {
    let changes = [
        ("basis: manual", "basis: unspecified"),
        ("    cite: example\n", ""),
        ("    expect:\n      after: {D200: 5A8DH}\n", ""),
    ];
    assert_eq!(load_changed(&changes), Ok(1));
}

/// A constant the manual does not allow for an operand describes a program that cannot exist:
/// IDEC ATOH takes S2 as a constant 1-4 only, so a count of 5 must come from a register.
#[test]
fn an_unprogrammable_constant_is_a_load_error() {
    let text = "\
instructions: [ATOH]
profiles: [idec-fc4a]
source: {manual: fc4a-user, page: 14-5}
cases:
  - id: s2-five
    basis: manual
    cite: x
    operands: {S1: D100, S2: K5, D1: D200}
    before: {D100: 31H}
    expect: {error: M8004}
  - id: s2-five-from-a-register
    basis: manual
    cite: x
    operands: {S1: D100, S2: D10, D1: D200}
    before: {D100: 31H, D10: 5}
    expect: {error: M8004}
";
    let errors = load(text).expect_err("K5 loaded");
    assert_eq!(errors.len(), 1, "{errors:#?}");
    let e = &errors[0];
    assert_eq!(e.line, Some(8), "{e}");
    assert_eq!(e.key.as_deref(), Some("cases[0].operands.S2"), "{e}");
    assert!(
        chain(e).contains("K5 cannot be programmed: ATOH operand `S2` takes constants 1-4 only"),
        "{e}"
    );
}

/// Shape errors do not stop at the first: a file with three of them reports three, each with
/// its line and key, and an unknown key that is a typo names the key meant.
#[test]
fn three_shape_errors_are_reported_in_one_pass() {
    let errors = load_changed(&[
        ("    operands:", "    oprands:"),
        ("    cite: example", "    cite: example\n    colour: red"),
        ("      after: {D200: 5A8DH}", "      after: [D200]"),
    ])
    .expect_err("loaded");
    let rendered: Vec<String> = errors.iter().map(|e| chain(e)).collect();
    assert_eq!(errors.len(), 3, "{rendered:#?}");
    for (line, needle) in [
        (8, "cases[0].colour: unknown field `colour`"),
        (
            10,
            "cases[0].oprands: unknown field `oprands`: did you mean `operands`?",
        ),
        (15, "cases[0].expect.after: expected a mapping"),
    ] {
        let e = errors
            .iter()
            .find(|e| chain(*e).contains(needle))
            .unwrap_or_else(|| panic!("no error says `{needle}`: {rendered:#?}"));
        assert_eq!(e.line, Some(line), "{e}");
    }
}

#[test]
fn a_file_without_cases_is_an_error() {
    let errors = load(&format!("{HEADER}  []\n")).expect_err("no case loaded");
    let rendered: Vec<String> = errors.iter().map(|e| chain(e)).collect();
    assert_eq!(
        rendered,
        vec!["bad.yaml:4: cases: missing case: a vector file holds at least one"]
    );
    let cross_vendor = "operation: hex-to-value\nsource: x\ncases: []\n";
    let errors = load(cross_vendor).expect_err("no cross-vendor case loaded");
    assert!(
        chain(&errors[0]).starts_with("bad.yaml:3: cases: missing case"),
        "{errors:?}"
    );
}

#[test]
fn deep_nesting_is_refused_before_it_is_built() {
    for deep in [
        format!("{HEADER}{}1{}\n", "[".repeat(100_000), "]".repeat(100_000)),
        format!("{HEADER}  - {}1\n", "- ".repeat(100_000)),
        format!("{HEADER}  - {}1\n", "{a: ".repeat(100_000)),
    ] {
        let errors = load(&deep).expect_err("a deep document loaded");
        assert!(
            chain(&errors[0]).contains("nested more than 64 levels deep"),
            "{errors:?}"
        );
    }
}

/// A vendor profile as the project ships it.
fn vendor_profile(file: &str) -> String {
    let vendors = Path::new(env!("CARGO_MANIFEST_DIR")).join("vendors");
    std::fs::read_to_string(vendors.join(file)).expect("profile")
}

/// The profiles of a folder holding only `file`, with this text; the load errors as text.
fn load_profile_text(file: &str, text: &str) -> Result<Profiles, String> {
    let scratch = tempfile::tempdir().expect("temp dir");
    std::fs::write(scratch.path().join(file), text).expect("write");
    load_profiles(scratch.path()).map_err(|e| e.to_string())
}

/// A vendor profile as the project ships it, which must hold `marker` (else the `which`
/// profile changed), and the line on which `marker`, which opens a line, starts.
fn vendor_profile_at(file: &str, marker: &str, which: &str) -> (String, usize) {
    let text = vendor_profile(file);
    assert!(text.contains(marker), "the {which} profile changed");
    let line = text[..text.find(marker).expect("found")].lines().count() + 1;
    (text, line)
}

/// Asserts that the profile load errors `errors` say `message` at `at`: `file:line`, and the key
/// where `message` does not name it.
fn assert_reported(errors: &str, at: &str, message: &str) {
    assert!(
        errors.contains(&format!("{at}: {message}")),
        "{message}\nin:\n{errors}"
    );
}

#[test]
fn a_lowering_on_a_device_the_variant_lacks_is_a_profile_error() {
    let lowering = "      operands: {s: D100, d: D200}\n      source: s\n      destination: d\n      text: packed\n      width: 4\n    - name: habin-terminated";
    let (iqr, line) = vendor_profile_at("mitsubishi-iqr.yaml", lowering, "iQ-R");
    for (operands, message) in [
        (
            "{s: D99999, d: D200}",
            "cross_vendor.lowerings[0].operands.s: D99999 does not exist on variant `rcpu`, which the lowering runs on",
        ),
        (
            "{s: D100, d: W200}",
            "cross_vendor.lowerings[0].operands.d: unknown device `W`",
        ),
    ] {
        let changed = iqr.replacen(
            lowering,
            &lowering.replacen("{s: D100, d: D200}", operands, 1),
            1,
        );
        let errors = load_profile_text("mitsubishi-iqr.yaml", &changed).expect_err("the profile loaded");
        assert_reported(&errors, &format!("mitsubishi-iqr.yaml:{line}"), message);
    }
}

/// A lowering's operand is numbered as the profile numbers its code: FX5 W is hexadecimal, so
/// `W1F0` is W 496 (which exists) and `W200` is W 512 (past W1FF), not W 200.
#[test]
fn a_lowering_reads_device_numbers_as_the_profile_numbers_them() {
    let fx5 = vendor_profile("mitsubishi-fx5.yaml");
    let lowering = "    - name: asci-16bit\n";
    let at = fx5
        .find(lowering)
        .expect("the FX5 profile has the asci-16bit lowering");
    let operands = "operands: {s: D100, d: D200}";
    let offset = at + fx5[at..].find(operands).expect("its operands");
    let line = fx5[..offset].lines().count();
    let with = |d: &str| {
        let mut changed = fx5.clone();
        changed.replace_range(
            offset..offset + operands.len(),
            &operands.replace("D200", d),
        );
        load_profile_text("mitsubishi-fx5.yaml", &changed)
    };
    with("W1F0").expect("W1F0 is W 496, which exists");
    let errors = with("W200").expect_err("W200 is W 512");
    let at = format!("mitsubishi-fx5.yaml:{line}: cross_vendor.lowerings[2].operands.d");
    assert_reported(&errors, &at, "W200 does not exist");
}

#[test]
fn written_on_error_must_name_one_of_the_section_s_errors() {
    let declared = "  written_on_error: [0007H]\n";
    let (s7, line) = vendor_profile_at("siemens-s7-1200.yaml", declared, "S7-1200");
    for (listed, message) in [
        ("[0008H]", "`0008H` is not one of this section's `errors`"),
        ("[M8004]", "`M8004` is not one of this section's `errors`"),
    ] {
        let changed = s7.replacen(declared, &format!("  written_on_error: {listed}\n"), 1);
        let errors =
            load_profile_text("siemens-s7-1200.yaml", &changed).expect_err("the profile loaded");
        let at = format!("siemens-s7-1200.yaml:{line}: cross_vendor.written_on_error[0]");
        assert_reported(&errors, &at, message);
    }
}

/// The structured-text call table: a form that is not `ENO:=NAME(EN,...);`, one under another
/// instruction's name, one that names other operands than the instruction has, and a `manual`
/// form whose source names none of the profile's manuals are refused, each at its key.
#[test]
fn a_structured_text_form_is_checked_against_its_instruction() {
    let fx5 = vendor_profile("mitsubishi-fx5.yaml");
    let quoted = r#"  ASCI: {form: "ENO:=ASCI(EN,s,n,d);", basis: manual, source: &asci-quoted "fx5-instructions"#;
    assert!(fx5.contains(quoted), "the FX5 profile changed");
    for (form, message) in [
        (
            r#"  ASCI: {form: "ASCI(EN,s,n,d)", basis: manual, source: &asci-quoted "fx5-instructions"#,
            "fx5.yaml:109: structured_text.ASCI.form: `ASCI(EN,s,n,d)`: a form is written",
        ),
        (
            r#"  ASCI: {form: "ENO:=ASCI(s,n,d,EN);", basis: manual, source: &asci-quoted "fx5-instructions"#,
            "the enable `EN` comes first",
        ),
        (
            r#"  ASCI: {form: "ENO:=HEXA(EN,s,n,d);", basis: manual, source: &asci-quoted "fx5-instructions"#,
            "the form calls HEXA, but it stands under ASCI",
        ),
        (
            r#"  ASCI: {form: "ENO:=ASCI(EN,s,d);", basis: manual, source: &asci-quoted "fx5-instructions"#,
            "names the operands s, d, but ASCI has d, n, s",
        ),
        (
            r#"  ASCI: {form: "ENO:=ASCI(EN,s,n,d);", basis: manual, source: &asci-quoted "a forum post"#,
            "structured_text.ASCI.source: a `manual` form starts its source with the manual's id",
        ),
    ] {
        let e = load_profile_text("fx5.yaml", &fx5.replacen(quoted, form, 1))
            .err()
            .unwrap_or_else(|| panic!("accepted: {form}"));
        assert!(e.contains(message), "{form}: {e}");
    }
}

/// A `manual` expectation holds for the variants its manual covers: a case citing the S7-1200
/// System Manual that also runs on the S7-1500 is refused at its key, and loads once it is
/// restricted to the S7-1200 (the S7-1500 then needs an `inferred` case of its own).
#[test]
fn a_manual_case_runs_only_on_the_variants_its_manual_covers() {
    let s7 = vendor_profile("siemens-s7-1200.yaml");
    let title = "    title: \"S7-1200 Programmable controller System Manual, A5E02486680-05, edition 11/2011";
    assert!(s7.contains(title), "the S7 profile changed");
    // The shipped profile says so already or not: the manual covers the S7-1200 alone here.
    let s7 = s7.replacen("    covers: [s7-1200]\n", "", 1);
    let marked = s7.replacen(
        "  s7-1200-2011:\n",
        "  s7-1200-2011:\n    covers: [s7-1200]\n",
        1,
    );
    let profiles = load_profile_text("siemens-s7-1200.yaml", &marked).expect("profile loads");
    let case = |variants: &str| s7_case("the example row", variants);
    let load_with = |text: &str| load_s7(text, &profiles);
    let e = load_with(&case("")).expect_err("runs on the S7-1500 too");
    assert!(
        e.contains("cases[0].basis: `basis: manual` rests on s7-1200-2011, the manual of s7-1200, and the case also runs on s7-1500"),
        "{e}"
    );
    assert_eq!(load_with(&case("    variants: [s7-1200]\n")), Ok(1));
    let unknown = marked.replacen("covers: [s7-1200]", "covers: [s7-1300]", 1);
    let e = load_profile_text("siemens-s7-1200.yaml", &unknown).expect_err("no such variant");
    assert!(e.contains("manuals.s7-1200-2011.covers[0]"), "{e}");
    // A manual that does not say what it covers is refused: no manual covers every variant by
    // default.
    let shipped = vendor_profile("siemens-s7-1200.yaml");
    let unsaid = shipped.replacen(
        "    covers: [s7-1200]\n  s7-1200-2012:",
        "  s7-1200-2012:",
        1,
    );
    assert_ne!(unsaid, shipped, "the S7 profile changed");
    let e = load_profile_text("siemens-s7-1200.yaml", &unsaid).expect_err("covers unsaid");
    assert!(
        e.contains("manuals.s7-1200-2011") && e.contains("covers"),
        "{e}"
    );
}

/// Every manual a cite names counts, with the file's source when the cite opens with a quote:
/// two manuals of two CPUs together cover both; a manual of other CPUs (`covers: []`) none.
#[test]
fn every_manual_a_cite_names_counts_toward_its_variants() {
    let s7 = vendor_profile("siemens-s7-1200.yaml");
    let edition_2016 = "section 9.2.3.3\"\n    language: en\n    covers: [s7-1200]";
    let two = s7.replacen(
        edition_2016,
        &edition_2016.replace("s7-1200]", "s7-1500]"),
        1,
    );
    assert_ne!(two, s7, "the S7 profile changed");
    let profiles = load_profile_text("siemens-s7-1200.yaml", &two).expect("profile loads");
    let case = |cite: &str| s7_case(&format!("\"{cite}\""), "");
    let load_with = |text: &str| load_s7(text, &profiles);
    // The source (s7-1200-2011) and the 2016 edition named later: both variants covered.
    assert_eq!(
        load_with(&case("the example row; s7-1200-2016 p.359")),
        Ok(1)
    );
    // Opening with the 2011 edition alone: the S7-1500 is not covered.
    let e = load_with(&case("s7-1200-2011 p.253: the example row")).expect_err("s7-1500");
    assert!(e.contains("also runs on s7-1500"), "{e}");
    // A manual of other CPUs covers none.
    let none = s7.replacen("    covers: [s7-1200]\n", "    covers: []\n", 1);
    let profiles_none = load_profile_text("siemens-s7-1200.yaml", &none).expect("loads");
    let e = load_s7(&case("s7-1200-2011 p.253: the example row"), &profiles_none)
        .expect_err("covers none");
    assert!(e.contains("which covers no variant of this profile"), "{e}");
}

/// An S7-1200 vector file of one `manual` ATH case with this cite (YAML, quoted or not) and
/// these `variants:` lines.
fn s7_case(cite: &str, variants: &str) -> String {
    format!(
        "instructions: [ATH]\nprofiles: [siemens-s7-1200]\nsource: {{manual: s7-1200-2011, page: 253}}\n\
         cases:\n  - id: example\n    basis: manual\n    cite: {cite}\n{variants}\
         \x20   operands: {{IN: DB1.DBB0, N: 2, OUT: DB2.DBB0}}\n    before:\n      DB1.DBB0: {{ascii: \"01\"}}\n\
         \x20   expect:\n      after: {{DB2.DBB0: 01H}}\n      error: none\n"
    )
}

/// The cases an S7 vector file loads to under `profiles`, or every error.
fn load_s7(text: &str, profiles: &crate::model::profile::Profiles) -> Result<usize, String> {
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("s7.yaml"), text, profiles);
    builder
        .finish()
        .map(|c| c.cases.len())
        .map_err(|e| e.0.iter().map(|e| chain(e)).collect::<Vec<_>>().join("\n"))
}
