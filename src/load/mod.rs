//! Loading: YAML files -> the validated model (profiles, corpus, project file, known
//! differences).
//!
//! Every problem is collected with its file, line and key, and loading fails if there is any:
//! a corpus with a bad case is not run with that case left out, because a silently skipped
//! vector looks exactly like a passing one.

mod checks;
mod cross_vendor;
mod document;
mod error;
mod known;
mod libraries;
mod locate;
mod open_questions;
mod profiles;
mod project;
mod protocols;
mod shape;
mod source;
mod vectors;

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

pub use error::LoadErrors;
pub(crate) use error::{LoadError, LoadErrorKind};
pub use known::load_known;
pub(crate) use libraries::load_libraries;
pub(crate) use locate::LineIndex;
pub(crate) use open_questions::{load_open_questions, OPEN_QUESTIONS};
pub use profiles::load_profiles;
pub use project::{load_project, ENV_CONFIG, ENV_REQUIRE, ENV_SELF, FILE_NAME};
pub(crate) use project::{locate_project, valid_name};
pub(crate) use source::{
    embedded_files, embedded_text, embedded_vectors, embedded_vendors, find_project_root,
    is_project_root, EMBEDDED,
};
pub use vectors::load_corpus;
pub(crate) use vectors::CorpusBuilder;

/// The YAML files under a path: the file itself, or every `.yaml`/`.yml` below a folder, in a
/// stable order. Other files in a corpus folder (READMEs) are not vectors.
///
/// Symbolic links are followed, to folders as to files: a linked folder of vectors is part of the
/// corpus, never silently left out. A link that leads back to a folder it is in (a loop) and a
/// link to nothing are errors; a file reached twice through links is read once. A path under
/// `<embedded>` lists the files shipped in the binary.
pub(crate) fn yaml_files(path: &Path) -> Result<Vec<PathBuf>, LoadError> {
    if let Some(files) = embedded_files(path) {
        if files.is_empty() {
            return Err(LoadError {
                file: path.to_path_buf(),
                line: None,
                key: None,
                kind: LoadErrorKind::Io(
                    "no such folder among the files shipped in the binary".into(),
                )
                .into(),
            });
        }
        return Ok(files);
    }
    let error = |at: &Path, message: String| LoadError {
        file: at.to_path_buf(),
        line: None,
        key: None,
        kind: LoadErrorKind::Io(message).into(),
    };
    fn io_error(at: &Path) -> impl Fn(std::io::Error) -> LoadError + '_ {
        move |e| LoadError {
            file: at.to_path_buf(),
            line: None,
            key: None,
            kind: LoadErrorKind::Io(e.to_string()).into(),
        }
    }
    let meta = std::fs::metadata(path).map_err(io_error(path))?;
    if !meta.is_dir() {
        // A file, or something that is not one: `read_file` says which.
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let top = std::fs::canonicalize(path).map_err(io_error(path))?;
    // Each folder with the real paths of the folders it is in, to tell a loop from a link to a
    // folder elsewhere.
    let mut folders = vec![(path.to_path_buf(), vec![top])];
    while let Some((folder, above)) = folders.pop() {
        for entry in std::fs::read_dir(&folder).map_err(io_error(&folder))? {
            let entry = entry.map_err(io_error(&folder))?;
            let p = entry.path();
            let mut kind = entry.file_type().map_err(io_error(&p))?;
            if kind.is_symlink() {
                kind = std::fs::metadata(&p)
                    .map_err(|e| error(&p, format!("a symbolic link to nothing readable: {e}")))?
                    .file_type();
            }
            if kind.is_dir() {
                let real = std::fs::canonicalize(&p).map_err(io_error(&p))?;
                if above.contains(&real) {
                    return Err(error(
                        &p,
                        format!(
                            "a symbolic link loop: it leads back to {}, a folder it is in",
                            real.display()
                        ),
                    ));
                }
                let mut chain = above.clone();
                chain.push(real);
                folders.push((p, chain));
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("yaml" | "yml")) {
                let real = std::fs::canonicalize(&p).unwrap_or_else(|_| p.clone());
                if seen.insert(real) {
                    files.push(p);
                }
            }
        }
    }
    files.sort();
    Ok(files)
}

/// Per-file state while reading: where errors go and how their lines are found.
pub(crate) struct FileContext<'a> {
    pub file: PathBuf,
    pub index: LineIndex,
    pub errors: &'a mut Vec<LoadError>,
    /// The text holds what no parser may see (see [`LineIndex::read`]): nothing more is
    /// read.
    refused: bool,
    /// The document, built by the parse that indexed it, for [`parse_document`] to take.
    document: Option<serde_yaml::Value>,
}

impl<'a> FileContext<'a> {
    /// Starts reading a file: first what no parser may see ([`LineIndex::read`]: a
    /// forbidden character, a second document, nesting past [`locate::MAX_DEPTH`]), before
    /// anything builds the document, since a pathological nesting holds the deserializer for
    /// minutes; then the keys repeated within a mapping.
    pub(crate) fn new(file: &Path, text: &str, errors: &'a mut Vec<LoadError>) -> Self {
        let (index, document) = match LineIndex::read(text) {
            Ok(read) => read,
            Err((line, message)) => {
                errors.push(LoadError {
                    file: file.to_path_buf(),
                    line: Some(line),
                    key: None,
                    kind: LoadErrorKind::Invalid(message).into(),
                });
                return FileContext {
                    file: file.to_path_buf(),
                    index: LineIndex::default(),
                    errors,
                    refused: true,
                    document: None,
                };
            }
        };
        let cx = FileContext {
            file: file.to_path_buf(),
            index,
            errors,
            refused: false,
            document,
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

    pub(crate) fn error(&mut self, key: impl Into<String>, kind: LoadErrorKind) {
        let key = key.into();
        self.errors.push(LoadError {
            file: self.file.clone(),
            line: self.index.line(&key),
            key: Some(key),
            kind: kind.into(),
        });
    }

    pub(crate) fn location(&self, key: &str) -> crate::model::Location {
        crate::model::Location {
            file: self.file.clone(),
            line: self.index.line(key).unwrap_or(1),
        }
    }
}

/// The schema of an on-disk type, generated once per process: a test process that runs one
/// trial reads a handful of files, and generating a schema costs more than checking one.
fn schema_once<T: schemars::JsonSchema + 'static>() -> std::sync::Arc<serde_json::Value> {
    use std::any::TypeId;
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    static SCHEMAS: OnceLock<Mutex<HashMap<TypeId, Arc<serde_json::Value>>>> = OnceLock::new();
    let mut schemas = match SCHEMAS.get_or_init(Default::default).lock() {
        Ok(s) => s,
        Err(poisoned) => poisoned.into_inner(),
    };
    schemas
        .entry(TypeId::of::<T>())
        .or_insert_with(|| Arc::new(crate::spec::schema_of::<T>()))
        .clone()
}

/// Reads a file of one document and builds what it describes: `build` gets the on-disk value
/// and the file's context to report problems to; every problem found, in the reading or the
/// building, is an error of the load.
pub(crate) fn load_document<T, R>(
    file: &Path,
    build: impl FnOnce(T, &mut FileContext<'_>) -> R,
) -> Result<R, LoadErrors>
where
    T: DeserializeOwned + schemars::JsonSchema + 'static,
{
    let text = read_file(file).map_err(|e| LoadErrors(vec![e]))?;
    let mut errors = Vec::new();
    let mut cx = FileContext::new(file, &text, &mut errors);
    let built = parse_document::<T>(&text, &mut cx).map(|spec| build(spec, &mut cx));
    match built {
        Some(built) if errors.is_empty() => Ok(built),
        _ => Err(LoadErrors(errors)),
    }
}

/// Reads one document as its on-disk type. A document the type refuses is checked for its
/// shape against the type's schema, which reports every unknown, missing or misplaced key at
/// once (see [`shape`]); when the shape is right, the deserializer's first error is the one
/// reported. A document that is not YAML at all goes straight to the deserializer, which says
/// where the syntax breaks. Problems go to the file's errors.
pub(crate) fn parse_document<T: DeserializeOwned + schemars::JsonSchema + 'static>(
    text: &str,
    cx: &mut FileContext<'_>,
) -> Option<T> {
    if cx.refused {
        return None;
    }
    let document = match cx.document.take() {
        Some(doc) => Ok(doc),
        None => serde_yaml::from_str::<serde_yaml::Value>(text),
    };
    if let Ok(doc) = document {
        // Whatever the walk of the schema reports, the type refuses too (its structs deny
        // unknown fields, and the schema is generated from them): a document it reads needs no
        // walk, which with the schema's making was a third of a start-up.
        if let Ok(value) = T::deserialize(&doc) {
            return Some(value);
        }
        if !shape::check(&doc, &schema_once::<T>(), cx) {
            return None;
        }
    }
    // Only a document the type refuses is parsed again, for the line the deserializer reports.
    deserialize(&cx.file.clone(), text)
        .map_err(|e| cx.errors.push(e))
        .ok()
}

/// Deserializes one YAML document already checked ([`LineIndex::read`]), turning the
/// deserializer's error into a [`LoadError`] with the line and key path it reports.
fn deserialize<T: DeserializeOwned>(file: &Path, text: &str) -> Result<T, LoadError> {
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

/// The text of a file (see [`read_regular`]), or of a file shipped in the binary (a path under
/// `<embedded>`).
pub(crate) fn read_file(path: &Path) -> Result<String, LoadError> {
    if let Some(text) = embedded_text(path) {
        return Ok(text.to_string());
    }
    let error = |line: Option<usize>, kind: LoadErrorKind| LoadError {
        file: path.to_path_buf(),
        line,
        key: None,
        kind: kind.into(),
    };
    let bytes = read_regular(path).map_err(|e| error(None, LoadErrorKind::Io(e.to_string())))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = bytes[..at].iter().filter(|b| **b == b'\n').count() + 1;
        error(
            Some(line),
            LoadErrorKind::Invalid(format!(
                "invalid UTF-8 (byte {:02X}H): a file must be UTF-8 text",
                bytes.get(at).copied().unwrap_or(0)
            )),
        )
    })?;
    Ok(text)
}

/// The bytes of a regular file. Anything else — a FIFO, a device, a socket, a folder — is
/// refused without being opened for long: reading a FIFO blocks until a writer comes, and a
/// device may never end.
pub(crate) fn read_regular(path: &Path) -> std::io::Result<Vec<u8>> {
    read_regular_limited(path, u64::MAX)
}

/// [`read_regular`] of a file at most `max` bytes long: a longer one (or one that grows while
/// read) is an error, never read into memory past `max`.
pub(crate) fn read_regular_limited(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    not_special(&std::fs::metadata(path)?)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Opening a FIFO that appeared since the check must not wait for a writer.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    not_special(&meta)?;
    let too_long = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("longer than {max} bytes"),
        )
    };
    if meta.len() > max {
        return Err(too_long());
    }
    let mut bytes = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(too_long());
    }
    Ok(bytes)
}

fn not_special(meta: &std::fs::Metadata) -> std::io::Result<()> {
    if meta.is_file() {
        return Ok(());
    }
    let kind = meta.file_type();
    let what = if kind.is_dir() {
        "a folder"
    } else {
        special_kind(&kind)
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("{what}, not a regular file"),
    ))
}

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a FIFO (named pipe)"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "not a file"
}

// Only tests parse a profile's text alone; the loader reaches it inside `profiles`.
#[cfg(test)]
#[cfg(test)]
pub(crate) use profiles::parse_profile;

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use serde::de::DeserializeOwned;

    use crate::spec::cross_vendor::CrossVendorFileSpec;
    use crate::spec::profile::ProfileSpec;
    use crate::spec::project::ProjectFileSpec;
    use crate::spec::vectors::VectorFileSpec;

    fn yaml_files(dir: &Path) -> Vec<PathBuf> {
        let mut out = Vec::new();
        for entry in std::fs::read_dir(dir).expect("a shipped folder") {
            let path = entry.expect("an entry").path();
            if path.is_dir() {
                out.extend(yaml_files(&path));
            } else if path.extension().is_some_and(|e| e == "yaml") {
                out.push(path);
            }
        }
        out
    }

    /// Why a shipped file would be parsed twice: the type refuses the document parsed once
    /// (a number where the schema asks for a string, say), so [`super::parse_document`] falls
    /// back to reading the text again.
    fn refused<T: DeserializeOwned>(path: &Path) -> Option<String> {
        let text = std::fs::read_to_string(path).expect("readable");
        let doc: serde_yaml::Value = serde_yaml::from_str(&text).expect("YAML");
        serde_yaml::from_value::<T>(doc)
            .err()
            .map(|e| format!("{}: {e}", path.display()))
    }

    /// Every shipped profile, vector file and the project file builds its type from the
    /// document parsed once: a listing reads each file one time.
    #[test]
    fn every_shipped_file_builds_from_the_document_parsed_once() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut refusals = Vec::new();
        let profiles = yaml_files(&root.join("vendors"));
        assert!(profiles.len() >= 10, "{profiles:?}");
        for path in &profiles {
            let protocol = path.parent().is_some_and(|d| d.ends_with("protocols"));
            refusals.extend(if protocol {
                refused::<crate::spec::protocol::ProtocolSpec>(path)
            } else {
                refused::<ProfileSpec>(path)
            });
        }
        let vectors = yaml_files(&root.join("vectors"));
        assert!(vectors.len() >= 20, "{vectors:?}");
        for path in &vectors {
            let cross_vendor = path.parent().is_some_and(|d| d.ends_with("cross-vendor"));
            let protocol = path.parent().is_some_and(|d| d.ends_with("protocols"));
            refusals.extend(if cross_vendor {
                refused::<CrossVendorFileSpec>(path)
            } else if protocol {
                refused::<crate::spec::protocol::ProtocolFileSpec>(path)
            } else {
                refused::<VectorFileSpec>(path)
            });
        }
        refusals.extend(refused::<ProjectFileSpec>(
            &root.join("plc-conformance.yaml"),
        ));
        assert!(refusals.is_empty(), "{}", refusals.join("\n"));
    }
}

#[cfg(test)]
mod white_box;
