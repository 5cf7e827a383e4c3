//! The corpus through the backends: the cross-vendor cases against the reference models and
//! wrong ones, and the protocol-field corpora against codecs written here from each protocol's
//! rules. White-box tests of the crate's own parts, with no binary to run, so they live beside
//! the code they reach into.

#[cfg(test)]
pub(super) use crate::test_support::{reference, root, session, Mutant};

mod cross_vendor;
mod fc4a_errors;
mod protocols;
