//! Which recording each folder name of a study folder belongs to, claimed before the folder is
//! written, so that runs of one study that do not share a process (`batch_row` calls on a Dask
//! cluster) never give two recordings one folder.
//!
//! A name's claim is a file `.pedomatch-names/NAME` holding the canonical path of its recording,
//! made in one step (a hard link of a complete file: no reader sees it half written), never
//! replaced. A folder's `summary.json` says the same once the run has written it; the claim
//! says it from before the run starts.

use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The folder of a study folder's claims.
pub(crate) const NAME_CLAIMS: &str = ".pedomatch-names";

fn claim_file(out: &Path, name: &str) -> PathBuf {
    out.join(NAME_CLAIMS).join(name)
}

/// The recording (as its path was recorded) that claimed folder `name` of study folder `out`.
pub(crate) fn claimant(out: &Path, name: &str) -> Option<String> {
    std::fs::read_to_string(claim_file(out, name))
        .ok()
        .filter(|s| !s.is_empty())
}

/// Claims folder `name` of study folder `out` for the recording at `path` (`file`: its
/// canonical path, when it resolves). `Ok(true)` when the name is now this recording's or
/// already was; `Ok(false)` when another recording holds it (`is_other` says whether a
/// recorded path is another file).
pub(crate) fn claim(
    out: &Path,
    name: &str,
    path: &Path,
    is_other: &dyn Fn(&str) -> bool,
) -> std::io::Result<bool> {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let dir = out.join(NAME_CLAIMS);
    std::fs::create_dir_all(&dir)?;
    let target = claim_file(out, name);
    let recorded = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let staged = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&staged, recorded.to_string_lossy().as_bytes())?;
    let linked = std::fs::hard_link(&staged, &target).or_else(|e| match e.kind() {
        // A file system without hard links: created empty where absent, then written (a
        // reader seeing it empty takes it for no claim, a narrow window).
        ErrorKind::Unsupported | ErrorKind::PermissionDenied => std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&target)
            .and_then(|mut f| {
                std::io::Write::write_all(&mut f, recorded.to_string_lossy().as_bytes())
            }),
        _ => Err(e),
    });
    let _ = std::fs::remove_file(&staged);
    match linked {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == ErrorKind::AlreadyExists => {
            Ok(claimant(out, name).is_none_or(|other| !is_other(&other)))
        }
        Err(e) => Err(e),
    }
}
