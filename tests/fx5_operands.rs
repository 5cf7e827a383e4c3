//! The operands FX5 ASCI(P) refuses, as its page's applicable devices table gives them: LC, LZ,
//! real constants (E) and character strings ($) as (s); T, ST and C as (d) ("*1 T, ST, and C
//! cannot be used"). A vector that names one is refused at load, with the operand's key.

use std::path::Path;

use plc_conformance::load::{load_profiles, CorpusBuilder};
use rstest::rstest;

/// An ASCI vector with the given source and destination, loaded against the real profile.
fn load_asci(s: &str, d: &str) -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let profiles = load_profiles(&root.join("vendors")).map_err(|e| e.to_string())?;
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
    expect:
      error: none
"#
    );
    let mut builder = CorpusBuilder::default();
    builder.add_file(Path::new("probe.yaml"), &text, &profiles);
    builder.finish().map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn a_data_register_and_a_constant_are_accepted() {
    assert_eq!(load_asci("D100", "D200"), Ok(()));
    assert_eq!(load_asci("H0ABC", "D200"), Ok(()));
}

#[rstest]
#[case::long_counter_as_s("LC0", "D200", "operands.s")]
#[case::long_index_as_s("LZ0", "D200", "operands.s")]
#[case::real_constant_as_s("E1.5", "D200", "operands.s")]
#[case::string_as_s("$ABCD", "D200", "operands.s")]
#[case::timer_as_d("D100", "T0", "operands.d")]
#[case::retentive_timer_as_d("D100", "ST0", "operands.d")]
#[case::counter_as_d("D100", "C0", "operands.d")]
fn a_forbidden_operand_is_refused(#[case] s: &str, #[case] d: &str, #[case] key: &str) {
    let errors = load_asci(s, d).expect_err("the vector is refused");
    assert!(errors.contains(key), "{errors}");
}
