//! FC4A device numbers as the profile describes them: the octal last digit of M, the 16 points a
//! bit device takes as a word, and the slim types' second data register range.

#[cfg(test)]
use std::path::Path;

use super::{load_probe, profiles};
use crate::load::{parse_profile, CorpusBuilder};
use crate::Device;
use rstest::rstest;

/// An ATOH vector with the given destination, loaded against the real profile.
fn load_with_d1(d1: &str) -> Result<(), String> {
    let text = format!(
        r#"
instructions: [ATOH]
profiles: [idec-fc4a]
source: {{manual: fc4a-user, page: "14-5"}}
cases:
  - id: atoh-d1-probe
    basis: manual
    cite: "p.14-5"
    operands: {{S1: D100, S2: 4, D1: {d1}}}
    before:
      D100: {{ascii_words: "1234"}}
    expect:
      after: {{{d1}: 1234H}}
"#
    );
    load_probe(&text)
}

#[rstest]
#[case("M0")]
#[case("M80")]
#[case("M1260")]
#[case("D1299")]
#[case("D7999")]
#[case("T255")]
fn accepts(#[case] d1: &str) {
    assert_eq!(load_with_d1(d1), Ok(()));
}

#[rstest]
#[case("M8", "M8 is not a valid M number: the last digit is octal")]
#[case("M1278", "M1278 is not a valid M number")]
#[case(
    "M1270",
    "M1270 does not exist on any idec-fc4a variant: a word of M is the 16 points"
)]
#[case("M1300", "M1300 does not exist on any idec-fc4a variant")]
#[case("D1500", "D1500 does not exist on any idec-fc4a variant")]
#[case("D8000", "D8000 does not exist on any idec-fc4a variant")]
#[case("I0", "unknown device for this operand `I`")]
// "Special internal relays cannot be designated as D1" (fc4a-user p.14-5).
#[case("M8000", "M8000 does not exist on any idec-fc4a variant")]
#[case("M8004", "M8004 does not exist on any idec-fc4a variant")]
fn rejects(#[case] d1: &str, #[case] message: &str) {
    let errors = load_with_d1(d1).expect_err("the vector is rejected");
    assert!(errors.contains(message), "{errors}");
}

#[test]
fn a_bit_word_is_not_given_as_a_list() {
    let text = r#"
instructions: [ATOH]
profiles: [idec-fc4a]
source: {manual: fc4a-user, page: "14-5"}
cases:
  - id: atoh-m-list
    basis: manual
    cite: "p.14-5"
    operands: {S1: D100, S2: M0, D1: D200}
    before:
      M0: [4, 4]
      D100: {ascii_words: "1234"}
    expect:
      after: {D200: 1234H}
"#;
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("list.yaml"), text, &profiles());
    let errors = builder.finish().expect_err("rejected").to_string();
    assert!(
        errors.contains("list.yaml:11: cases[0].before.M0: a word of M is 16 points from its head"),
        "{errors}"
    );
}

#[rstest]
#[case::c10("c10r2", "D399", 1, true)]
#[case::c10_past("c10r2", "D399", 2, false)]
#[case::c10_expansion("c10r2", "D2000", 1, false)]
#[case::c24("c24r2", "D1296", 4, true)]
#[case::c24_past("c24r2", "D1297", 4, false)]
#[case::slim_gap("d20k3", "D1299", 2, false)]
#[case::slim_expansion("d40k3", "D2000", 6000, true)]
#[case::slim_past("d40k3", "D2000", 6001, false)]
#[case::m_last_word("c10r2", "M1260", 1, true)]
#[case::m_two_words("c10r2", "M1240", 2, true)]
#[case::m_past("c10r2", "M1250", 2, false)]
#[case::m_unaligned("c10r2", "M1265", 1, false)]
#[case::m_not_octal("c10r2", "M19", 1, false)]
fn words_exist(
    #[case] variant: &str,
    #[case] head: &str,
    #[case] count: u32,
    #[case] exists: bool,
) {
    let profiles = profiles();
    let p = profiles.get("idec-fc4a").expect("the FC4A profile");
    let v = p.variant(variant).expect("the variant");
    let head: Device = head.parse().expect("a device name");
    assert_eq!(p.words_exist(v, &head, count), exists);
}

#[rstest]
#[case(
    "{first: 0, last: 1278, numbering: octal-last-digit}",
    "1278 is not a number in octal-last-digit numbering"
)]
#[case("{first: 10, last: 7}", "first 10 is after last 7")]
#[case(
    "{first: 0, last: 7, points_per_word: 0}",
    "a word takes at least one point"
)]
#[case(
    "{first: 0, last: 7, also: [{first: 20, last: 19}]}",
    "devices.M.also[0]: first 20 is after last 19"
)]
fn profile_ranges_are_checked(#[case] m: &str, #[case] message: &str) {
    let (parsed, all) = probe_profile(&format!("  M: {m}"), "");
    assert!(!parsed);
    assert!(all.iter().any(|e| e.contains(message)), "{all:?}");
}

/// A profile `probe` with these device lines and more top-level text, as `parse_profile` reads
/// it: whether it was accepted, and its errors.
fn probe_profile(devices: &str, more: &str) -> (bool, Vec<String>) {
    let text = format!(
        r#"
id: probe
name: probe
short: probe
manuals: {{m: {{title: t, covers: [v]}}}}
errors: {{signal: flag, flag: M8004}}
devices:
{devices}
instructions: {{}}
variants: [{{id: v, description: d}}]
{more}"#
    );
    let mut errors = Vec::new();
    let parsed = parse_profile(Path::new("probe.yaml"), &text, &mut errors);
    (
        parsed.is_some(),
        errors.iter().map(ToString::to_string).collect(),
    )
}

/// A bench section is checked when the profile loads: a Modbus TCP link needs its map, the map's
/// ranges are in the profile's numbering and in order, and its identity register and running
/// relay lie in it.
#[rstest::rstest]
#[case::no_map("", "a `modbus-tcp` link needs the CPU's Modbus map")]
#[case::unknown_code(
    "modbus: {registers: [{device: W, first: 0, last: 9, address: 0}], coils: [{device: M, first: 8000, last: 8017, address: 9000}], identity: D8002, running: M8000, source: s}",
    "`W` is not a device code of the profile"
)]
#[case::reversed(
    "modbus: {registers: [{device: D, first: 9, last: 0, address: 0}], coils: [{device: M, first: 8000, last: 8017, address: 9000}], identity: D8002, running: M8000, source: s}",
    "the first must come before the last"
)]
#[case::octal(
    "modbus: {registers: [{device: D, first: 0, last: 8499, address: 0}], coils: [{device: M, first: 8000, last: 8018, address: 9000}], identity: D8002, running: M8000, source: s}",
    "the last digit is octal"
)]
#[case::identity_outside(
    "modbus: {registers: [{device: D, first: 0, last: 7999, address: 0}], coils: [{device: M, first: 8000, last: 8017, address: 9000}], identity: D8002, running: M8000, source: s}",
    "D8002 lies in none of the map's ranges"
)]
fn a_bench_section_is_checked_when_the_profile_loads(#[case] map: &str, #[case] message: &str) {
    let devices = r#"
  M: {first: 0, last: 1277, numbering: octal-last-digit, points_per_word: 16}
  D: {first: 0, last: 1299}"#;
    let bench = format!(
        r#"
bench:
  link: modbus-tcp
  program: ladder
  error_reset: M8004
  source: s
  {map}
"#
    );
    let (parsed, all) = probe_profile(devices, &bench);
    assert!(!parsed, "accepted: {all:?}");
    assert!(all.iter().any(|e| e.contains(message)), "{all:?}");
}
