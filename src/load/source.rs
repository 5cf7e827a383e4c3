//! Where a project's data comes from: a project folder found upward from the current one, as
//! cargo finds its manifest, or the vendor profiles and corpus shipped inside the binary.
//!
//! The shipped files are named `<embedded>/vendors/...` and `<embedded>/vectors/...`: those are
//! the names every message shows, and a path under `<embedded>` given to the loader (for
//! example `--vectors '<embedded>/vectors/mitsubishi-iqr'`) reads the shipped copy.

use std::path::{Component, Path, PathBuf};

use super::FILE_NAME;

mod files {
    include!(concat!(env!("OUT_DIR"), "/embedded.rs"));
}

/// The first component of the name of every embedded file.
pub(crate) const EMBEDDED: &str = "<embedded>";

/// The shipped vendor profiles.
pub(crate) fn embedded_vendors() -> PathBuf {
    Path::new(EMBEDDED).join("vendors")
}

/// The shipped corpus.
pub(crate) fn embedded_vectors() -> PathBuf {
    Path::new(EMBEDDED).join("vectors")
}

/// The path below `<embedded>`, `/`-separated, when `path` names embedded data.
fn inside(path: &Path) -> Option<String> {
    let mut components = path.components();
    match components.next() {
        Some(Component::Normal(first)) if first == EMBEDDED => {}
        _ => return None,
    }
    let rest: Vec<String> = components
        .filter(|c| !matches!(c, Component::CurDir))
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    Some(rest.join("/"))
}

/// The embedded YAML files at or below `path`, in a stable order; `None` when `path` is not
/// under `<embedded>` (an empty list when nothing is shipped there).
pub(crate) fn embedded_files(path: &Path) -> Option<Vec<PathBuf>> {
    let rest = inside(path)?;
    Some(
        files::FILES
            .iter()
            .filter(|(name, _)| {
                rest.is_empty()
                    || *name == rest
                    || name
                        .strip_prefix(rest.as_str())
                        .is_some_and(|tail| tail.starts_with('/'))
            })
            .map(|(name, _)| Path::new(EMBEDDED).join(name))
            .collect(),
    )
}

/// The text of an embedded file; `None` when `path` names no embedded file.
pub(crate) fn embedded_text(path: &Path) -> Option<&'static str> {
    let rest = inside(path)?;
    files::FILES
        .iter()
        .find(|(name, _)| *name == rest)
        .map(|(_, text)| *text)
}

/// Whether `dir` is a project folder: it holds the project file, or both `vendors/` and
/// `vectors/`.
pub(crate) fn is_project_root(dir: &Path) -> bool {
    dir.join(FILE_NAME).is_file() || (dir.join("vendors").is_dir() && dir.join("vectors").is_dir())
}

/// The nearest project folder at or above `start`.
pub(crate) fn find_project_root(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .find(|dir| is_project_root(dir))
        .map(Path::to_path_buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_profiles_and_corpus_are_embedded() {
        let vendors = embedded_files(&embedded_vendors()).expect("embedded");
        assert!(vendors
            .iter()
            .any(|p| p == Path::new("<embedded>/vendors/mitsubishi-iqr.yaml")));
        let habin = Path::new("<embedded>/vectors/mitsubishi-iqr/habin.yaml");
        assert!(embedded_files(&embedded_vectors())
            .expect("embedded")
            .contains(&habin.to_path_buf()));
        let on_disk = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("vectors/mitsubishi-iqr/habin.yaml"),
        )
        .expect("habin.yaml");
        assert_eq!(embedded_text(habin), Some(on_disk.as_str()));
    }

    #[test]
    fn a_folder_selects_only_the_files_below_it() {
        let files = embedded_files(Path::new("<embedded>/vectors/mitsubishi-iqr")).expect("some");
        assert!(!files.is_empty());
        assert!(files
            .iter()
            .all(|f| f.starts_with("<embedded>/vectors/mitsubishi-iqr")));
        assert_eq!(
            embedded_files(Path::new("<embedded>/vectors/mitsubishi")),
            Some(Vec::new())
        );
        assert_eq!(embedded_files(Path::new("vectors")), None);
        assert_eq!(embedded_text(Path::new("<embedded>/vectors")), None);
    }

    #[test]
    fn the_project_is_found_upward() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        assert_eq!(
            find_project_root(&root.join("vectors/mitsubishi-iqr")).as_deref(),
            Some(root)
        );
        let empty = tempfile::tempdir().expect("temp dir");
        assert!(!is_project_root(empty.path()));
    }
}
