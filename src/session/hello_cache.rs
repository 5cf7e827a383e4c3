//! The answers to `hello` a listing of the trials planned with, kept between processes.
//!
//! nextest lists the trials before every run, and what an external backend declines (marked
//! ignored in the listing, since nextest shows a trial that returns "ignored" as passed) is known
//! only from its handshake: starting every backend, an interpreter and a library each, cost most
//! of a listing. A cached answer stands for a backend while its command, working directory,
//! environment and the files its command names (the interpreter and the adapter script, by size
//! and modification time) are unchanged. A library upgraded under the same script is not seen
//! by that key, so a trial run alone (as nextest runs each) starts its backend and compares: an
//! answer that differs from the cached one fails the trial (the listing may have marked it by
//! the old answer) and replaces the cached one, so that the next listing is right.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::model::project::{ExternalSettings, Launch};

/// The cache file's contents: by backend name, the key it was recorded under and the answer.
#[derive(Default, Serialize, Deserialize)]
pub(crate) struct HelloCache {
    #[serde(skip)]
    path: PathBuf,
    #[serde(skip)]
    changed: bool,
    entries: BTreeMap<String, Entry>,
}

#[derive(Clone, PartialEq, Serialize, Deserialize)]
struct Entry {
    key: String,
    hello: String,
}

impl HelloCache {
    /// The cache at `path`; a missing or unreadable file is an empty cache (every backend is
    /// then started, as with no cache).
    pub(crate) fn load(path: &Path) -> HelloCache {
        let mut cache = std::fs::read(path)
            .ok()
            .and_then(|bytes| serde_json::from_slice::<HelloCache>(&bytes).ok())
            .unwrap_or_default();
        cache.path = path.to_path_buf();
        cache
    }

    /// The answer recorded for a backend with these settings, while its key holds.
    pub(crate) fn get(&self, settings: &ExternalSettings) -> Option<&[u8]> {
        let entry = self.entries.get(&settings.name)?;
        (entry.key == key(settings)).then_some(entry.hello.as_bytes())
    }

    /// Records a backend's answer; `Some(old)` when it replaces a different answer recorded
    /// under the same key.
    pub(crate) fn put(&mut self, settings: &ExternalSettings, hello: &[u8]) -> Option<String> {
        let entry = Entry {
            key: key(settings),
            hello: String::from_utf8_lossy(hello).into_owned(),
        };
        let before = self.entries.insert(settings.name.clone(), entry.clone());
        if before.as_ref() == Some(&entry) {
            return None;
        }
        self.changed = true;
        before.filter(|b| b.key == entry.key).map(|b| b.hello)
    }

    /// Writes the cache if anything changed, whole or not at all (a file of its own renamed
    /// into place: trials run side by side each write it).
    pub(crate) fn save(&self) -> std::io::Result<()> {
        if !self.changed {
            return Ok(());
        }
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let mut partial = self.path.clone().into_os_string();
        partial.push(format!(".{}", std::process::id()));
        let bytes = serde_json::to_vec_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(&partial, bytes)?;
        std::fs::rename(&partial, &self.path).inspect_err(|_| {
            let _ = std::fs::remove_file(&partial);
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

/// What a backend's answer depends on, as far as the harness can see it.
fn key(settings: &ExternalSettings) -> String {
    let words: Vec<String> = match &settings.launch {
        Launch::Exec(args) => args.clone(),
        Launch::Shell(line) => line
            .split_whitespace()
            .map(|w| w.trim_matches(['"', '\'']).to_string())
            .collect(),
    };
    let mut key = format!(
        "{}\n{:?}\n{:?}\n{:?} {}\n",
        settings.launch, settings.cwd, settings.env, settings.profile, settings.codec
    );
    for (i, word) in words.iter().enumerate() {
        if let Some(file) = named_file(settings, word, i == 0) {
            if let Ok(meta) = std::fs::metadata(&file) {
                let modified = meta
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos());
                key.push_str(&format!("{} {} {modified}\n", file.display(), meta.len()));
            }
        }
    }
    key
}

/// The file a word of a command may name: the program, found on PATH unless given as a path; any
/// other word as a path relative to the working directory (a word that names no file adds
/// nothing to the key); a variable of the backend's environment as its value.
fn named_file(settings: &ExternalSettings, word: &str, program: bool) -> Option<PathBuf> {
    let word = match word.strip_prefix('$') {
        Some(var) => settings.env.iter().find(|(k, _)| k == var)?.1.as_str(),
        None => word,
    };
    if program && !word.contains('/') {
        let path = std::env::var_os("PATH")?;
        return std::env::split_paths(&path)
            .map(|dir| dir.join(word))
            .find(|candidate| candidate.is_file());
    }
    let path = Path::new(word);
    Some(match &settings.cwd {
        Some(dir) if path.is_relative() => dir.join(path),
        _ => path.to_path_buf(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(dir: &Path) -> ExternalSettings {
        let mut s =
            ExternalSettings::new("lib", Launch::Exec(vec!["sh".into(), "adapter.sh".into()]));
        s.cwd = Some(dir.to_path_buf());
        s
    }

    #[test]
    fn an_answer_stands_while_the_files_its_command_names_are_unchanged() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("adapter.sh");
        std::fs::write(&script, "echo hello").expect("write");
        let path = dir.path().join("cache/hellos.json");
        let s = settings(dir.path());

        let mut cache = HelloCache::load(&path);
        assert_eq!(cache.get(&s), None);
        assert_eq!(cache.put(&s, b"{\"v\":1}"), None);
        cache.save().expect("save");
        let cache = HelloCache::load(&path);
        assert_eq!(cache.get(&s), Some(&b"{\"v\":1}"[..]));

        // A script of another size is another key.
        std::fs::write(&script, "echo hello again").expect("write");
        assert_eq!(HelloCache::load(&path).get(&s), None);
    }

    #[test]
    fn put_says_when_an_answer_under_the_same_key_changed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let s = settings(dir.path());
        let mut cache = HelloCache::load(&dir.path().join("hellos.json"));
        assert_eq!(cache.put(&s, b"a"), None);
        assert_eq!(cache.put(&s, b"a"), None);
        assert_eq!(cache.put(&s, b"b"), Some("a".to_string()));
    }

    #[test]
    fn a_damaged_cache_is_an_empty_one() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("hellos.json");
        std::fs::write(&path, "{not json").expect("write");
        assert_eq!(HelloCache::load(&path).get(&settings(dir.path())), None);
    }
}
