//! Teeth for the corpus: each reference model held to the corpus by mutation. Every file here
//! builds deliberately wrong backends around one family's reference model, each with one
//! behaviour changed, and checks that the corpus tells each of them apart from the manual; this
//! module holds what they share.

#[cfg(test)]
pub(super) use crate::test_support::{
    assert_corpus_kills, failing_trials, map_done, reference, session, with_constant, with_memory,
    Mutant,
};

mod fc4a;
mod fp;
mod fx3;
mod fx5;
mod iqr;
mod kv;
mod omron;
mod s7;
mod s7_200;
