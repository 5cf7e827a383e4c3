//! Loading the list of libraries of the results table (`libraries.yaml`).

use std::collections::BTreeSet;
use std::path::Path;

use super::{LoadErrorKind, LoadErrors};
use crate::model::library::Library;
use crate::model::protocol::Protocols;
use crate::spec::libraries::LibrariesFileSpec;

/// The list's libraries in its order; every problem with its line and key: a backend named
/// twice, a protocol no profile defines.
pub(crate) fn load_libraries(
    file: &Path,
    protocols: &Protocols,
) -> Result<Vec<Library>, LoadErrors> {
    super::load_document(file, |spec: LibrariesFileSpec, cx| {
        let mut seen = BTreeSet::new();
        let mut libraries = Vec::new();
        for (i, l) in spec.libraries.into_iter().enumerate() {
            if !seen.insert(l.backend.clone()) {
                cx.error(
                    format!("libraries[{i}].backend"),
                    LoadErrorKind::Invalid(format!("backend `{}` is listed twice", l.backend)),
                );
            }
            if let Some(p) = l.protocol.as_deref().filter(|p| protocols.get(p).is_none()) {
                cx.error(
                    format!("libraries[{i}].protocol"),
                    LoadErrorKind::Invalid(format!(
                        "no protocol `{p}`; the protocols are: {}",
                        protocols.ids().join(", ")
                    )),
                );
            }
            libraries.push(Library {
                backend: l.backend,
                package: l.package,
                language: l.language,
                licence: l.licence,
                protocol: l.protocol,
                wired: l.wired,
                also: l.also,
            });
        }
        libraries
    })
}
