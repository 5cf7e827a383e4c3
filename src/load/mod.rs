//! Loading: YAML files -> the validated model (profiles, corpus, project file, known
//! differences).
//!
//! Every problem is collected with its file, line and key, and loading fails if there is any:
//! a corpus with a bad case is not run with that case left out, because a silently skipped
//! vector looks exactly like a passing one.

mod checks;
mod cross_vendor;
mod error;
mod known;
mod locate;
mod profiles;
mod project;
mod source;
mod vectors;

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

pub use error::{LoadError, LoadErrorKind, LoadErrors};
pub use known::load_known;
pub use locate::LineIndex;
pub use profiles::{load_profiles, parse_profile};
pub use project::{
    load_project, locate_project, requirements_enforced, valid_name, ENV_CONFIG, ENV_REQUIRE,
    ENV_SELF, FILE_NAME,
};
pub use source::{
    embedded_files, embedded_text, embedded_vectors, embedded_vendors, find_project_root,
    is_project_root, EMBEDDED,
};
pub use vectors::{load_corpus, CorpusBuilder};

/// The YAML files under a path: the file itself, or every `.yaml`/`.yml` below a folder, in a
/// stable order. Other files in a corpus folder (READMEs) are not vectors. A path under
/// `<embedded>` lists the files shipped in the binary.
pub fn yaml_files(path: &Path) -> Result<Vec<PathBuf>, LoadError> {
    let io_error = |e: std::io::Error| LoadError {
        file: path.to_path_buf(),
        line: None,
        key: None,
        kind: LoadErrorKind::Io(e.to_string()).into(),
    };
    if let Some(files) = embedded_files(path) {
        if files.is_empty() {
            return Err(io_error(std::io::ErrorKind::NotFound.into()));
        }
        return Ok(files);
    }
    let meta = std::fs::metadata(path).map_err(io_error)?;
    if meta.is_file() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files = Vec::new();
    let mut folders = vec![path.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).map_err(io_error)? {
            let entry = entry.map_err(io_error)?;
            let p = entry.path();
            if entry.file_type().map_err(io_error)?.is_dir() {
                folders.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("yaml" | "yml")) {
                files.push(p);
            }
        }
    }
    files.sort();
    Ok(files)
}

/// Per-file state while lowering: where errors go and how their lines are found.
pub(crate) struct FileContext<'a> {
    pub file: PathBuf,
    pub index: LineIndex,
    pub errors: &'a mut Vec<LoadError>,
}

impl<'a> FileContext<'a> {
    /// Starts lowering a file, reporting keys repeated within a mapping.
    pub fn new(file: &Path, text: &str, errors: &'a mut Vec<LoadError>) -> Self {
        let cx = FileContext {
            file: file.to_path_buf(),
            index: LineIndex::new(text),
            errors,
        };
        let repeated: Vec<(String, usize)> = cx.index.duplicates().to_vec();
        for (key, line) in repeated {
            cx.errors.push(LoadError {
                file: cx.file.clone(),
                line: Some(line),
                kind: LoadErrorKind::Invalid(
                    "duplicate key: it is already given above in the same mapping".into(),
                )
                .into(),
                key: Some(key),
            });
        }
        cx
    }

    pub fn error(&mut self, key: impl Into<String>, kind: LoadErrorKind) {
        let key = key.into();
        self.errors.push(LoadError {
            file: self.file.clone(),
            line: self.index.line(&key),
            key: Some(key),
            kind: kind.into(),
        });
    }

    pub fn location(&self, key: &str) -> crate::model::Location {
        crate::model::Location {
            file: self.file.clone(),
            line: self.index.line(key).unwrap_or(1),
        }
    }
}

/// Deserializes one YAML document, turning the deserializer's error into a [`LoadError`] with
/// the line and key path it reports.
pub(crate) fn parse_yaml<T: DeserializeOwned>(file: &Path, text: &str) -> Result<T, LoadError> {
    serde_yaml::from_str(text).map_err(|e| {
        let line = e.location().map(|l| l.line());
        let mut message = e.to_string();
        if let Some(l) = e.location() {
            let suffix = format!(" at line {} column {}", l.line(), l.column());
            if let Some(cut) = message.find(&suffix) {
                message.replace_range(cut..cut + suffix.len(), "");
            }
        }
        // The deserializer leads its message with the key path (`cases[0].flags: ...`).
        let (key, message) = match message.split_once(": ") {
            Some((path, rest)) if !path.is_empty() && !path.contains(' ') => {
                (Some(path.to_string()), rest.to_string())
            }
            _ => (None, message),
        };
        LoadError {
            file: file.to_path_buf(),
            line,
            key,
            kind: LoadErrorKind::Shape(message).into(),
        }
    })
}

/// The text of a file, or of a file shipped in the binary (a path under `<embedded>`).
pub(crate) fn read_file(path: &Path) -> Result<String, LoadError> {
    if let Some(text) = embedded_text(path) {
        return Ok(text.to_string());
    }
    std::fs::read_to_string(path).map_err(|e| LoadError {
        file: path.to_path_buf(),
        line: None,
        key: None,
        kind: LoadErrorKind::Io(e.to_string()).into(),
    })
}
