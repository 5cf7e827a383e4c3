//! The operands FX5 ASCI(P) refuses, as its page's applicable devices table gives them: LC, LZ,
//! real constants (E) and character strings ($) as (s); T, ST and C as (d) ("*1 T, ST, and C
//! cannot be used"), and Z as (d). A vector that names one is refused at load, with the
//! operand's key; so is one naming a device the table allows but the profile does not model,
//! and one whose digit-designated words share points (K4M0 with K4M8). Indirect specification
//! (`@D10`) is accepted with the device its pointer addresses, and refused without it.

#[cfg(test)]
use rstest::rstest;

use super::load_probe;

/// An ASCI vector with the given source and destination, loaded against the real profile.
fn load_asci(s: &str, d: &str) -> Result<(), String> {
    load_asci_with(s, d, "")
}

/// The same with more keys for the case (`addresses: ...`), one per line.
fn load_asci_with(s: &str, d: &str, more: &str) -> Result<(), String> {
    let expect = if more.contains("expect:") {
        ""
    } else {
        "expect: {error: none}"
    };
    let more: String = (more.lines().chain([expect]))
        .map(|l| format!("    {l}\n"))
        .collect();
    let text = format!(
        r#"
instructions: [ASCI]
profiles: [mitsubishi-fx5]
source: {{manual: fx5-instructions, page: "ASCI(P)"}}
cases:
  - id: asci-operand-probe
    basis: inferred
    cite: "the applicable devices table"
    flags: {{SM701: on}}
    operands: {{s: '{s}', d: '{d}', n: K4}}
{more}"#
    );
    load_probe(&text)
}

#[test]
fn a_data_register_and_a_constant_are_accepted() {
    assert_eq!(load_asci("D100", "D200"), Ok(()));
    assert_eq!(load_asci("H0ABC", "D200"), Ok(()));
}

/// The table's other word devices: T, ST, C, SD, R and Z as (s); SD and R as (d).
#[rstest]
#[case("T5", "D200")]
#[case("ST3", "D200")]
#[case("C7", "D200")]
#[case("SD100", "D200")]
#[case("R100", "D200")]
#[case("Z2", "D200")]
#[case("D100", "R200")]
#[case("D100", "SD100")]
// The table's bit column, as 16 points by digit designation (K4), the link registers W and
// SW (numbered in hexadecimal), and module buffer memory (U□\G□), for (s) and (d).
#[case("K4M0", "D200")]
#[case("K4L100", "D200")]
#[case("K4F0", "D200")]
#[case("K4S16", "D200")]
#[case("D100", "K4M0")]
#[case("D100", "K4L20")]
#[case("K4M0", "K4M32")]
#[case("U1\\G10", "D200")]
#[case("D100", "U1\\G100")]
#[case("U1\\G10", "U2\\G10")]
#[case("W1FF", "D200")]
#[case("W1A", "SW0F")]
#[case("WA", "SW10")]
#[case("K4B10", "K4SB1F0")]
fn the_other_devices_the_table_allows_are_accepted(#[case] s: &str, #[case] d: &str) {
    assert_eq!(load_asci(s, d), Ok(()));
}

#[rstest]
#[case::long_counter_as_s("LC0", "D200", "operands.s")]
#[case::long_index_as_s("LZ0", "D200", "operands.s")]
#[case::real_constant_as_s("E1.5", "D200", "operands.s")]
#[case::string_as_s("$ABCD", "D200", "operands.s")]
#[case::timer_as_d("D100", "T0", "operands.d")]
#[case::retentive_timer_as_d("D100", "ST0", "operands.d")]
#[case::counter_as_d("D100", "C0", "operands.d")]
#[case::index_register_as_d("D100", "Z0", "operands.d")]
// Allowed by the table but not modelled (docs/semantics.md#fx5-asci-operands): refused, never
// read as something else.
#[case::digit_count_other_than_4_as_s("K2M0", "D200", "operands.s")]
#[case::octal_bit_device_as_s("K4X0", "D200", "operands.s")]
#[case::link_register_past_its_range_as_s("W200", "D200", "operands.s")]
#[case::no_hexadecimal_digit_as_s("W1G", "D200", "operands.s")]
#[case::decimal_device_with_hexadecimal_digits_as_s("D1A", "D200", "operands.s")]
#[case::module_number_in_hexadecimal_as_s("U1A\\G10", "D200", "operands.s")]
#[case::indirect_without_an_address_as_d("D100", "@D0", "operands.d")]
// Two digit-designated words of one case that share points.
#[case::bit_words_off_one_grid("K4M0", "K4M8", "operands.s")]
fn a_forbidden_operand_is_refused(#[case] s: &str, #[case] d: &str, #[case] key: &str) {
    let errors = load_asci(s, d).expect_err("the vector is refused");
    assert!(errors.contains(key), "{errors}");
}

/// Indirect specification: `@D10` with the device D10 addresses, for (s) and (d), to any
/// device the operand takes.
#[rstest]
#[case("@D10", "D200", "addresses: {D10: D100}")]
#[case("D100", "@D20", "addresses: {D20: R200}")]
#[case("@D10", "@D20", "addresses: {D10: K4M0, D20: D200}")]
#[case("@D7998", "D200", "addresses: {D7998: D100}")]
fn an_indirect_operand_with_its_address_is_accepted(
    #[case] s: &str,
    #[case] d: &str,
    #[case] addresses: &str,
) {
    assert_eq!(load_asci_with(s, d, addresses), Ok(()));
}

#[rstest]
#[case::pointer_not_a_data_register("@R10", "D200", "addresses: {R10: D100}", "operands.s")]
#[case::pointer_past_the_last_word("@D7999", "D200", "addresses: {D7999: D100}", "operands.s")]
#[case::address_of_a_forbidden_destination("D100", "@D20", "addresses: {D20: T0}", "operands.d")]
#[case::address_for_no_operand("D100", "D200", "addresses: {D10: D100}", "addresses.D10")]
#[case::address_not_a_device("@D10", "D200", "addresses: {D10: 100}", "addresses.D10")]
#[case::address_off_the_grid_of_another_operand(
    "K4M0",
    "@D20",
    "addresses: {D20: K4M8}",
    "addresses.D20"
)]
#[case::pointer_word_set_before(
    "@D10",
    "D200",
    "addresses: {D10: D100}\nbefore: {D11: 5}",
    "before"
)]
#[case::pointer_word_expected_after(
    "D100",
    "@D20",
    "addresses: {D20: D200}\nexpect: {after: {D20: 5}, error: none}",
    "expect.after"
)]
fn a_wrong_indirect_operand_is_refused(
    #[case] s: &str,
    #[case] d: &str,
    #[case] more: &str,
    #[case] key: &str,
) {
    let errors = load_asci_with(s, d, more).expect_err("the vector is refused");
    assert!(errors.contains(key), "{errors}");
}
