//! An error and its causes as one line, for the places that show an error as text: the
//! command line's edge, and reports that list why a case did not run.
//!
//! A wrapping error says only what it adds (`rung 3 operand `s``, `cannot write out.json`) and
//! returns the error underneath from `source()`; this joins the chain with `: `, so that no
//! message repeats its cause and no cause is lost.

use std::error::Error;

/// `error: cause: cause of the cause`, each link once.
pub fn chain(error: &(dyn Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut next = error.source();
    while let Some(cause) = next {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        next = cause.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fmt;

    #[derive(Debug)]
    struct Outer(std::io::Error);
    impl fmt::Display for Outer {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("cannot read manifest.json")
        }
    }
    impl Error for Outer {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn every_cause_is_shown_once_in_order() {
        let e = Outer(std::io::Error::other("permission denied"));
        assert_eq!(chain(&e), "cannot read manifest.json: permission denied");
    }
}
