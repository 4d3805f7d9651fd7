//! That a recording's file does not change while a run reads it: the SHA-256 a run records is
//! of the bytes its parser read (`Hashing`, a reader between the file and the parser), a
//! streamed file's second pass is hashed too and must give the same digest, and a file is
//! stamped (size and modification time) before it is read and checked after every window of
//! frames, so that a change is caught as soon as it shows.

use crate::{FrameSource, IoError, Recording, Result};
use sha2::{Digest, Sha256};
use std::cell::RefCell;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// A reader that feeds every byte read through it to a SHA-256 its caller keeps (the reader
/// itself goes into a parser and is dropped there).
pub(crate) struct Hashing<R> {
    inner: R,
    sha: Rc<RefCell<Sha256>>,
}

impl<R: Read> Hashing<R> {
    /// `inner` hashed into `sha` as it is read.
    pub(crate) fn new(inner: R, sha: &Rc<RefCell<Sha256>>) -> Self {
        Self {
            inner,
            sha: Rc::clone(sha),
        }
    }
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.sha.borrow_mut().update(&buf[..n]);
        Ok(n)
    }
}

/// The lower-case hex SHA-256 of the file at `path`, read from its start to its end.
pub(crate) fn file_digest(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut sha = Sha256::new();
    std::io::copy(&mut file, &mut sha)?;
    Ok(hex(&sha.finalize()))
}

/// Lower-case hex of a digest.
pub(crate) fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The hex SHA-256 of `sha` after the rest of `file` (whatever the parser left unread: it
/// shares the parser's file offset) has been fed to it, so that it is the whole file's.
pub(crate) fn finish(
    sha: &Rc<RefCell<Sha256>>,
    file: Option<std::fs::File>,
) -> std::io::Result<String> {
    if let Some(mut rest) = file {
        std::io::copy(&mut rest, &mut Sink(Rc::clone(sha)))?;
    }
    Ok(hex(&sha.borrow().clone().finalize()))
}

/// A writer feeding a shared SHA-256.
struct Sink(Rc<RefCell<Sha256>>);

impl std::io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().update(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The error of a file whose second reading differs from its first.
pub(crate) fn changed(name: &str) -> IoError {
    IoError::Io {
        path: name.to_string(),
        source: std::io::Error::other(
            "changed while it was being read (a second reading of its bytes gives another SHA-256); run it again once nothing writes it",
        ),
    }
}

/// The error of a file whose second reading fails where its first, of the same file, did not:
/// it changed in between (cut, rewritten in place or removed while the reading went on).
pub(crate) fn changed_because(name: &str, second: &IoError) -> IoError {
    IoError::Io {
        path: name.to_string(),
        source: std::io::Error::other(format!(
            "changed while it was being read (its second reading fails where the first did not: {second}); run it again once nothing writes it"
        )),
    }
}

/// The size and modification time of a recording's file (of every file of a folder, in name
/// order), to tell that it changed while it was read; `None` if they cannot be read.
#[derive(Debug, Clone, PartialEq)]
pub struct FileStamp(Option<Vec<(PathBuf, u64, Option<std::time::SystemTime>)>>);

impl FileStamp {
    /// The stamp of the file (or folder of files) at `path` now.
    pub fn of(path: &Path) -> Self {
        let one = |p: PathBuf| {
            let m = std::fs::metadata(&p).ok()?;
            Some((p, m.len(), m.modified().ok()))
        };
        if path.is_dir() {
            let Ok(entries) = std::fs::read_dir(path) else {
                return Self(None);
            };
            let mut files: Vec<PathBuf> = entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            Self(files.into_iter().map(one).collect())
        } else {
            Self(one(path.to_path_buf()).map(|f| vec![f]))
        }
    }

    /// Fails if the file at `path` is no longer as stamped.
    ///
    /// # Errors
    /// [`IoError::Io`] naming `path`: it changed while it was being read.
    pub fn check(&self, path: &Path) -> Result<()> {
        if FileStamp::of(path) == *self {
            return Ok(());
        }
        Err(IoError::Io {
            path: path.display().to_string(),
            source: std::io::Error::other(
                "changed while it was being read (its size or modification time differ); run it again once nothing writes it",
            ),
        })
    }
}

/// The frames of a streamed run, each window checked against the stamp its file had before it
/// was read, so that the tables are of the bytes `summary.json`'s SHA-256 is of.
pub struct Unchanged<'a> {
    /// The frames read as the run goes.
    pub inner: &'a mut dyn FrameSource,
    /// The file they are read from.
    pub path: &'a Path,
    /// Its stamp before it was read.
    pub stamp: &'a FileStamp,
}

impl FrameSource for Unchanged<'_> {
    fn window(&mut self, recording: &Recording, w0: usize, w1: usize) -> Result<Recording> {
        let window = self.inner.window(recording, w0, w1)?;
        self.stamp.check(self.path)?;
        Ok(window)
    }

    fn finish(&mut self, recording: &Recording) -> Result<()> {
        self.inner.finish(recording)?;
        self.stamp.check(self.path)
    }
}
