//! That a recording's file does not change while a run reads it: the SHA-256 a run records must
//! be of the bytes it parsed, so a file is stamped (size and modification time) before it is
//! read and checked after it is hashed and, streamed, after every window of frames.

use crate::{FrameSource, IoError, Recording, Result};
use std::path::{Path, PathBuf};

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
}
