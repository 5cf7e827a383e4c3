//! Where a command's report goes, written the same safe way for every format: stdout; a
//! regular file, written whole or not at all (a temporary file beside it, renamed over it when
//! the report is complete, so an interrupted run never leaves half a report or a damaged
//! baseline); or a device or FIFO (`/dev/null`, `/dev/stdout`, a named pipe), written
//! directly, since renaming over one would replace it.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::CliError;

/// An open output: write to it, then [`Sink::finish`] it.
pub(super) enum Sink {
    Stdout(anstream::AutoStream<std::io::Stdout>),
    Direct {
        path: PathBuf,
        file: File,
    },
    Staged {
        path: PathBuf,
        temp: PathBuf,
        file: Option<File>,
    },
}

/// Refuses, before any work, an output that cannot be written: a folder, a file in a folder
/// that does not exist, or one the staged rename would wrongly replace (a link, a read-only
/// file).
pub(super) fn check(path: &Path) -> Result<(), CliError> {
    if path.is_dir() {
        return Err(CliError::input(format!(
            "{}: a folder, not a file to write",
            path.display()
        )));
    }
    refuse_link_or_read_only(path)?;
    if !path.exists() {
        let parent = parent(path);
        if !parent.is_dir() {
            return Err(CliError::input(format!(
                "{}: the folder {} does not exist",
                path.display(),
                parent.display()
            )));
        }
    }
    Ok(())
}

fn parent(path: &Path) -> PathBuf {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Refuses a target the staged rename would wrongly replace: a symbolic link to a file or to
/// nothing (the rename would put the output in the link's place, and writing through it would
/// reach a file elsewhere; a link to a device or FIFO, `/dev/stdout`, is written through), and
/// a read-only file (its mode and owner would be lost).
fn refuse_link_or_read_only(path: &Path) -> Result<(), CliError> {
    let refuse = |what: &str| Err(CliError::input(format!("{}: {what}", path.display())));
    let Ok(own) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if own.file_type().is_symlink() && !special(path) {
        return refuse(
            "a symbolic link: give the file it leads to, or another name (the output is never \
             written through a link)",
        );
    }
    if own.is_file() && own.permissions().readonly() {
        return refuse("read-only: make it writable, or give another file");
    }
    Ok(())
}

/// A new file beside the target to write the output into: created exclusively (never an
/// existing file, and never through a link planted at its name) under a name no other process
/// can predict, tried again under another name if one is taken.
fn stage(folder: &Path, name: &str) -> std::io::Result<(PathBuf, File)> {
    use std::hash::{BuildHasher, Hasher};
    let mut last = None;
    for attempt in 0..16u32 {
        // RandomState is seeded from the OS's randomness once per process; the hasher mixes the
        // clock and the attempt into it.
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u32(attempt);
        h.write_u128(
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos()),
        );
        let temp = folder.join(format!(
            ".{name}.{}.{:016x}.tmp",
            std::process::id(),
            h.finish()
        ));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
        {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::ErrorKind::AlreadyExists.into()))
}

/// Whether `path` is something other than a regular file, to be written in place.
fn special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Opens a device or FIFO for writing. A FIFO that no process reads would block the command
/// for ever: it is refused at once instead.
#[cfg(unix)]
fn open_in_place(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    use std::os::unix::io::AsRawFd;
    let fifo = std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo());
    if !fifo {
        return std::fs::OpenOptions::new().write(true).open(path);
    }
    let file = std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ENXIO) => std::io::Error::new(
                std::io::ErrorKind::BrokenPipe,
                "a FIFO (named pipe) that no process is reading",
            ),
            _ => e,
        })?;
    // A reader is there: writes may now wait for it, as to any pipe.
    // SAFETY: fcntl on a descriptor this function owns.
    unsafe {
        let flags = libc::fcntl(file.as_raw_fd(), libc::F_GETFL);
        libc::fcntl(file.as_raw_fd(), libc::F_SETFL, flags & !libc::O_NONBLOCK);
    }
    Ok(file)
}

#[cfg(not(unix))]
fn open_in_place(path: &Path) -> std::io::Result<File> {
    std::fs::OpenOptions::new().write(true).open(path)
}

impl Sink {
    /// `None` is stdout.
    pub(super) fn open(path: Option<&Path>) -> Result<Sink, CliError> {
        let Some(path) = path else {
            return Ok(Sink::Stdout(anstream::stdout()));
        };
        let failed = |e| CliError::write(Some(path), e);
        refuse_link_or_read_only(path)?;
        if special(path) {
            return Ok(Sink::Direct {
                path: path.to_path_buf(),
                file: open_in_place(path).map_err(failed)?,
            });
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (temp, file) = stage(&parent(path), &name).map_err(failed)?;
        Ok(Sink::Staged {
            path: path.to_path_buf(),
            temp,
            file: Some(file),
        })
    }

    /// Whether the output is a terminal's stdout (colours, the terminal's width).
    pub(super) fn is_stdout(&self) -> bool {
        matches!(self, Sink::Stdout(_))
    }

    /// Flushes, and syncs a staged file to disk, without putting it in place yet.
    fn sync(&mut self) -> Result<(), CliError> {
        let path = self.path().map(Path::to_path_buf);
        let failed = |e| CliError::write(path.as_deref(), e);
        self.flush().map_err(failed)?;
        if let Sink::Staged { file: Some(f), .. } = self {
            f.sync_all().map_err(failed)?;
        }
        Ok(())
    }

    /// Flushes, and puts a staged file in its place.
    pub(super) fn finish(mut self) -> Result<(), CliError> {
        let path = self.path().map(Path::to_path_buf);
        let failed = |e| CliError::write(path.as_deref(), e);
        self.flush().map_err(failed)?;
        if let Sink::Staged { path, temp, file } = &mut self {
            if let Some(f) = file.take() {
                f.sync_all().map_err(failed)?;
            }
            if let Err(e) = std::fs::rename(&*temp, &*path) {
                let _ = std::fs::remove_file(&*temp);
                return Err(failed(e));
            }
        }
        Ok(())
    }

    fn path(&self) -> Option<&Path> {
        match self {
            Sink::Stdout(_) => None,
            Sink::Direct { path, .. } | Sink::Staged { path, .. } => Some(path),
        }
    }

    /// A write error of this output, for the command's error.
    pub(super) fn error(&self, e: std::io::Error) -> CliError {
        CliError::write(self.path(), e)
    }
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::Stdout(out) => out.write(buf),
            Sink::Direct { file, .. } => file.write(buf),
            Sink::Staged { file, .. } => match file {
                Some(f) => f.write(buf),
                None => Err(std::io::ErrorKind::BrokenPipe.into()),
            },
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::Stdout(out) => out.flush(),
            Sink::Direct { file, .. } => file.flush(),
            Sink::Staged { file, .. } => file.as_mut().map_or(Ok(()), Write::flush),
        }
    }
}

impl Drop for Sink {
    /// A staged file that was never finished (an error, an interruption) is removed: the
    /// file it would have replaced stays as it was.
    fn drop(&mut self) {
        if let Sink::Staged {
            temp,
            file: Some(_),
            ..
        } = self
        {
            let _ = std::fs::remove_file(&*temp);
        }
    }
}

/// Writes several files all or none: each is written whole and synced beside its target before
/// any replaces its target, so an error on one (a full disk, a missing folder) leaves every
/// file as it was.
pub(super) fn write_every<'a>(
    files: impl IntoIterator<Item = (&'a Path, &'a str)>,
) -> Result<(), CliError> {
    let mut staged = Vec::new();
    for (path, text) in files {
        let mut sink = Sink::open(Some(path))?;
        sink.write_all(text.as_bytes()).map_err(|e| sink.error(e))?;
        sink.sync()?;
        staged.push(sink);
    }
    staged.into_iter().try_for_each(Sink::finish)
}

/// Writes a whole report to `path`, or to stdout (`None`) followed by a newline.
pub(super) fn write(path: Option<&Path>, text: &str) -> Result<(), CliError> {
    let mut sink = Sink::open(path)?;
    let written = sink.write_all(text.as_bytes()).and_then(|()| {
        if path.is_none() {
            sink.write_all(b"\n")
        } else {
            Ok(())
        }
    });
    written.map_err(|e| sink.error(e))?;
    sink.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_or_none_is_written() {
        let dir = tempfile::tempdir().expect("temp dir");
        let first = dir.path().join("a.yaml");
        std::fs::write(&first, "before").expect("write");
        let unwritable = dir.path().join("missing-folder").join("b.yaml");
        let result = write_every([(first.as_path(), "after"), (unwritable.as_path(), "after")]);
        assert!(result.is_err());
        assert_eq!(std::fs::read_to_string(&first).expect("read"), "before");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(
            left,
            [std::ffi::OsString::from("a.yaml")],
            "no staged file left"
        );
        let second = dir.path().join("b.yaml");
        write_every([(first.as_path(), "after"), (second.as_path(), "new")]).expect("written");
        assert_eq!(std::fs::read_to_string(&first).expect("read"), "after");
        assert_eq!(std::fs::read_to_string(&second).expect("read"), "new");
    }

    /// A link planted where the output goes, to a file or to nothing, and a read-only file are
    /// refused, the file the link leads to untouched; a link to a device is written through.
    #[cfg(unix)]
    #[test]
    fn a_link_or_a_read_only_file_is_refused_and_nothing_is_written_through_it() {
        let dir = tempfile::tempdir().expect("temp dir");
        let decoy = dir.path().join("decoy");
        std::fs::write(&decoy, "keep").expect("write");
        let link = dir.path().join("out.txt");
        std::os::unix::fs::symlink(&decoy, &link).expect("link");
        let e = write(Some(&link), "report").expect_err("refused");
        assert!(e.to_string().contains("a symbolic link"), "{e}");
        let dangling = dir.path().join("gone.txt");
        std::os::unix::fs::symlink(dir.path().join("nothing"), &dangling).expect("link");
        assert!(write(Some(&dangling), "report").is_err());
        assert!(!dir.path().join("nothing").exists());
        let read_only = dir.path().join("ro.yaml");
        std::fs::write(&read_only, "before").expect("write");
        let mut mode = std::fs::metadata(&read_only).expect("meta").permissions();
        mode.set_readonly(true);
        std::fs::set_permissions(&read_only, mode).expect("chmod");
        let e = write(Some(&read_only), "after").expect_err("refused");
        assert!(e.to_string().contains("read-only"), "{e}");
        assert_eq!(std::fs::read_to_string(&read_only).expect("read"), "before");
        assert_eq!(std::fs::read_to_string(&decoy).expect("read"), "keep");
        let null = dir.path().join("null");
        std::os::unix::fs::symlink("/dev/null", &null).expect("link");
        write(Some(&null), "through").expect("written to the device");
        let left: Vec<_> = (std::fs::read_dir(dir.path()).expect("dir"))
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    /// Each staged file is new, under a name of its own: never one that exists.
    #[test]
    fn a_staged_file_is_created_new_under_a_name_of_its_own() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (a, _) = stage(dir.path(), "x").expect("staged");
        let (b, _) = stage(dir.path(), "x").expect("staged");
        assert_ne!(a, b);
        let name = a.file_name().expect("name").to_string_lossy().into_owned();
        assert!(name.starts_with(".x.") && name.ends_with(".tmp"), "{name}");
    }
}
