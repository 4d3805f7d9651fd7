//! Output folders that appear whole or not at all.
//!
//! A run writes into a hidden staging folder beside its target (`.NAME.pedomatch-tmp-PID` in the
//! same parent, so the final move is a rename on one file system) and swaps it into place only when
//! every file is written. A run that fails, is interrupted (Ctrl-C) or is killed leaves the previous
//! complete output, or nothing. Two runs into the same folder each stage their own files; the one
//! that finishes last wins, whole.
//!
//! The library never installs a signal handler: a program that wants Ctrl-C to leave no staging
//! folder behind calls [`interrupt`] from its own handler and exits (the `pedomatch` CLI does),
//! or, to go on afterwards, cancels its runs through a [`pedo_io::cancel::Cancel`] (the Python
//! bindings do): a cancelled run commits no folder and removes its staging folder.

use pedo_io::{IoError, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Marks a folder as a pedomatch output, which a later run may replace as a whole. A non-empty
/// folder without it is never replaced (it may hold the user's own files). Its first line is
/// [`MARKER_HEAD`]; the others list the files the output holds (relative, `/`-separated), so a
/// file saved into the folder afterwards (notes, an edited copy) stops it from being replaced.
const MARKER: &str = ".pedomatch-output";

/// The marker's first line.
const MARKER_HEAD: &str = "written by pedomatch";

/// Files a file manager leaves in a folder it shows (thumbnails, view settings): they are not the
/// user's work, so they never stop an output from being replaced.
const FILE_MANAGER_LITTER: [&str; 3] = [".DS_Store", "Thumbs.db", "desktop.ini"];

/// Staging folders of this process, removed by the interrupt handler.
static STAGING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Set by the interrupt handler: no file is written after it.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Stops every output of this process: no file is written and no folder committed from now on,
/// and the staging folders are removed. Meant for a Ctrl-C (SIGINT/SIGTERM) handler, which then
/// exits; it returns once the staging folders are gone (or after about 200 ms).
pub fn interrupt() {
    INTERRUPTED.store(true, Ordering::SeqCst);
    // Writers check the flag before each file; one that passed the check just before it
    // finishes within milliseconds, so the removal is repeated until nothing comes back.
    let dirs = STAGING.lock().map(|d| d.clone()).unwrap_or_default();
    for _ in 0..10 {
        for d in &dirs {
            let _ = std::fs::remove_dir_all(d);
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
        if dirs.iter().all(|d| !d.exists()) {
            break;
        }
    }
}

/// Whether [`interrupt`] was called.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

fn io_error(path: &Path, source: std::io::Error) -> IoError {
    IoError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn refused(path: &Path, msg: &str) -> IoError {
    IoError::Output {
        path: path.display().to_string(),
        msg: msg.to_string(),
    }
}

/// An output folder being written; see the module docs.
pub struct OutDir {
    /// The folder as the caller named it (errors name it).
    root: PathBuf,
    /// Where it is written: `root`, or the folder a symbolic link `root` points to.
    place: PathBuf,
    staging: PathBuf,
    committed: bool,
}

impl OutDir {
    /// Starts an output into `root`. Fails if `root` is a file, or a non-empty folder that is not
    /// a pedomatch output.
    pub fn create(root: &Path) -> Result<Self> {
        let place = through_links(root)?;
        let name = place
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| *n != "." && *n != "..")
            .ok_or_else(|| refused(root, "not a usable output folder name"))?;
        check_replaceable(&place)?;
        let parent = match place.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|e| io_error(&parent, e))?;
        sweep_stale(&parent, name);
        let staging = parent.join(format!(".{name}.pedomatch-tmp-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&staging);
        register(&staging);
        // The staging folder is an implementation detail: its failure is the output's.
        let unwritable = |e: std::io::Error| {
            let parent = parent.display();
            refused(root, &format!("cannot be written in {parent}: {e}"))
        };
        std::fs::create_dir(&staging).map_err(unwritable)?;
        std::fs::write(staging.join(MARKER), format!("{MARKER_HEAD}\n")).map_err(unwritable)?;
        Ok(Self {
            root: root.to_path_buf(),
            place,
            staging,
            committed: false,
        })
    }

    /// Writes `rel` (which may include sub-folders) into the staging folder.
    pub fn write(&self, rel: &str, contents: &[u8]) -> Result<()> {
        if interrupted() {
            return Err(refused(&self.root, "interrupted"));
        }
        let path = self.staging.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| io_error(&self.root.join(rel), e))?;
        }
        std::fs::write(&path, contents).map_err(|e| io_error(&self.root.join(rel), e))
    }

    /// Writes `rel` through a buffered writer that `fill` writes to, piece by piece, so that a
    /// large table never has to be held whole in memory.
    pub fn write_with(
        &self,
        rel: &str,
        fill: impl FnOnce(&mut (dyn std::io::Write + Send)) -> std::io::Result<()>,
    ) -> Result<()> {
        use std::io::Write;
        if interrupted() {
            return Err(refused(&self.root, "interrupted"));
        }
        let path = self.staging.join(rel);
        let failed = |e| io_error(&self.root.join(rel), e);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(failed)?;
        }
        let mut w = std::io::BufWriter::with_capacity(
            1 << 16,
            std::fs::File::create(&path).map_err(failed)?,
        );
        fill(&mut w).map_err(failed)?;
        w.flush().map_err(failed)
    }

    /// Creates `rel` (which may include sub-folders) in the staging folder and returns it
    /// behind a buffer, for a file written as its content is made (a streamed run's tables).
    /// [`OutDir::failed`] names the file in the writer's errors.
    pub fn create_file(&self, rel: &str) -> Result<std::io::BufWriter<std::fs::File>> {
        if interrupted() {
            return Err(refused(&self.root, "interrupted"));
        }
        let path = self.staging.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| self.failed(rel, e))?;
        }
        let file = std::fs::File::create(&path).map_err(|e| self.failed(rel, e))?;
        Ok(std::io::BufWriter::with_capacity(1 << 16, file))
    }

    /// The error of writing `rel`, named by its place in the output folder.
    pub fn failed(&self, rel: &str, e: std::io::Error) -> IoError {
        io_error(&self.root.join(rel), e)
    }

    /// The folder this output goes to.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Puts the complete folder in place of the previous one in one step.
    pub fn commit(mut self) -> Result<()> {
        if interrupted() {
            return Err(refused(&self.root, "interrupted"));
        }
        check_replaceable(&self.place)?;
        // The marker lists what this output holds (see MARKER).
        let files = files_under(&self.staging).map_err(|e| io_error(&self.root, e))?;
        let listing: String = std::iter::once(MARKER_HEAD)
            .chain(files.iter().map(String::as_str).filter(|f| *f != MARKER))
            .map(|line| format!("{line}\n"))
            .collect();
        std::fs::write(self.staging.join(MARKER), listing).map_err(|e| io_error(&self.root, e))?;
        swap_into_place(&self.staging, &self.place).map_err(|e| io_error(&self.root, e))?;
        // The staging path now holds the previous output (or nothing).
        let _ = std::fs::remove_dir_all(&self.staging);
        unregister(&self.staging);
        self.committed = true;
        Ok(())
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            unregister(&self.staging);
        }
    }
}

/// Where an output named `root` is written: `root` itself, or, when `root` is a symbolic link
/// (followed through a chain of links), the folder it points to, which need not exist yet. The
/// link is kept and its target replaced: a user who links `results` to another disk wants the
/// results there, not a folder in place of the link.
fn through_links(root: &Path) -> Result<PathBuf> {
    let mut place = root.to_path_buf();
    // As the kernel's own bound on a chain of links.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&place) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&place).map_err(|e| io_error(root, e))?;
                place = match place.parent() {
                    Some(parent) => parent.join(target),
                    None => target,
                };
            }
            _ => return Ok(place),
        }
    }
    Err(refused(root, "a loop of symbolic links"))
}

fn register(staging: &Path) {
    if let Ok(mut dirs) = STAGING.lock() {
        dirs.push(staging.to_path_buf());
    }
}

fn unregister(staging: &Path) {
    if let Ok(mut dirs) = STAGING.lock() {
        dirs.retain(|d| d != staging);
    }
}

/// Whether `root` is a complete pedomatch output (a folder holding the marker).
pub fn is_output(root: &Path) -> bool {
    root.join(MARKER).is_file()
}

fn check_replaceable(root: &Path) -> Result<()> {
    match std::fs::read_dir(root) {
        // Write-protecting a finished output is how a user keeps it; the swap by rename in the
        // parent would otherwise replace it all the same.
        Ok(_) if is_write_protected(root) => Err(refused(
            root,
            "folder is write-protected (read-only); make it writable to replace it, or choose \
             another output folder",
        )),
        Ok(mut entries) => {
            if entries.next().is_none() {
                Ok(())
            } else if is_output(root) {
                check_only_outputs(root)
            } else {
                Err(refused(
                    root,
                    "folder exists and is not a pedomatch output; choose another output folder",
                ))
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(_) if root.exists() => Err(refused(
            root,
            "exists and is not a folder; choose another output folder",
        )),
        Err(e) => Err(io_error(root, e)),
    }
}

/// Refuses an earlier output that holds files it did not write (the user's notes, an edited
/// copy saved beside the tables): replacing the folder would delete them. A marker without a
/// listing (written before the listing existed) cannot tell, and is replaced as before.
fn check_only_outputs(root: &Path) -> Result<()> {
    let marker = std::fs::read_to_string(root.join(MARKER)).map_err(|e| io_error(root, e))?;
    let mut lines = marker.lines();
    let listed: std::collections::HashSet<&str> = lines.by_ref().skip(1).collect();
    if listed.is_empty() {
        return Ok(());
    }
    let foreign: Vec<String> = files_under(root)
        .map_err(|e| io_error(root, e))?
        .into_iter()
        .filter(|f| f != MARKER && !listed.contains(f.as_str()))
        .filter(|f| {
            let name = f.rsplit('/').next().unwrap_or(f);
            !FILE_MANAGER_LITTER.contains(&name) && !name.starts_with("._")
        })
        .collect();
    if foreign.is_empty() {
        return Ok(());
    }
    let shown: Vec<&str> = foreign.iter().take(3).map(String::as_str).collect();
    let more = match foreign.len() {
        n if n > 3 => format!(" and {} more", n - 3),
        _ => String::new(),
    };
    Err(refused(
        root,
        &format!(
            "this earlier pedomatch output now holds files it did not write ({}{more}), which \
             replacing it would delete; move them out, or choose another output folder",
            shown.join(", ")
        ),
    ))
}

/// Every file under `dir` (following no links), relative and `/`-separated, sorted.
fn files_under(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut out = Vec::new();
    for entry in walkdir::WalkDir::new(dir).min_depth(1) {
        let entry = entry.map_err(std::io::Error::from)?;
        if !entry.file_type().is_dir() {
            let rel = entry.path().strip_prefix(dir).unwrap_or(entry.path());
            let parts: Vec<_> = rel.iter().map(|p| p.to_string_lossy()).collect();
            out.push(parts.join("/"));
        }
    }
    out.sort();
    Ok(out)
}

/// Whether the folder's permissions grant nobody write access.
fn is_write_protected(root: &Path) -> bool {
    std::fs::metadata(root).is_ok_and(|m| m.permissions().readonly())
}

/// Removes staging folders for `name` left by runs that were killed (their process is gone).
fn sweep_stale(parent: &Path, name: &str) {
    let prefix = format!(".{name}.pedomatch-tmp-");
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !process_alive(pid) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

#[cfg(target_os = "linux")]
fn process_alive(pid: u32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
}

#[cfg(not(target_os = "linux"))]
fn process_alive(_pid: u32) -> bool {
    // Without a cheap liveness test, never remove another process's folder.
    true
}

/// Moves `staging` to `root`; if `root` exists, the two are exchanged, so `staging` then holds the
/// previous output. On Linux the exchange is one atomic `renameat2(RENAME_EXCHANGE)`: there is no
/// moment at which `root` is missing or mixed.
fn swap_into_place(staging: &Path, root: &Path) -> std::io::Result<()> {
    match std::fs::rename(staging, root) {
        Ok(()) => Ok(()),
        Err(_) if root.is_dir() => exchange(staging, root),
        Err(e) => Err(e),
    }
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let ca = CString::new(a.as_os_str().as_bytes())?;
    let cb = CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: both pointers are valid NUL-terminated paths that outlive the call; AT_FDCWD makes
    // relative paths resolve against the working directory, as `std::fs::rename` does.
    let rc = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    // Two renames: a kill between them leaves the previous output under the staging name.
    let old = a.with_extension("old");
    std::fs::rename(b, &old)?;
    std::fs::rename(a, b)?;
    std::fs::rename(&old, a)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("pedomatch-outdir-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[cfg(unix)]
    #[test]
    fn an_output_named_by_a_link_is_written_where_the_link_points_and_the_link_is_kept() {
        let d = tmp("link");
        let (disk, link) = (d.join("other-disk/results"), d.join("results"));
        std::fs::create_dir_all(disk.parent().unwrap()).unwrap();
        // A link to a folder that does not exist yet, then to the output it holds.
        std::os::unix::fs::symlink("other-disk/results", &link).unwrap();
        for round in ["first", "second"] {
            let out = OutDir::create(&link).unwrap();
            out.write("pairs.csv", round.as_bytes()).unwrap();
            out.commit().unwrap();
            let kept = std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink();
            assert!(kept, "{round}: the link was replaced by a folder");
            assert_eq!(
                std::fs::read_to_string(disk.join("pairs.csv")).unwrap(),
                round
            );
            assert_eq!(
                std::fs::read_to_string(link.join("pairs.csv")).unwrap(),
                round
            );
        }
        // Nothing was staged beside the link, on the wrong disk.
        let beside: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(beside.len(), 2, "{beside:?}");
        // A loop of links is an error, not a hang.
        let (a, b) = (d.join("a"), d.join("b"));
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        let e = OutDir::create(&a)
            .err()
            .expect("a loop of links")
            .to_string();
        assert!(e.contains("loop"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_committed_folder_replaces_the_previous_output_whole() {
        let base = tmp("replace");
        let root = base.join("out");
        let first = OutDir::create(&root).unwrap();
        first.write("a.csv", b"1").unwrap();
        first.write("figures/f.png", b"x").unwrap();
        first.commit().unwrap();
        assert_eq!(std::fs::read(root.join("a.csv")).unwrap(), b"1");

        let second = OutDir::create(&root).unwrap();
        second.write("b.csv", b"2").unwrap();
        // Until the commit, the first output is untouched.
        assert!(root.join("figures/f.png").is_file());
        second.commit().unwrap();
        assert!(
            !root.join("a.csv").exists(),
            "no file of the old output survives"
        );
        assert!(!root.join("figures").exists());
        assert_eq!(std::fs::read(root.join("b.csv")).unwrap(), b"2");
        let leftovers: Vec<_> = std::fs::read_dir(&base).unwrap().flatten().collect();
        assert_eq!(
            leftovers.len(),
            1,
            "staging folders are gone: {leftovers:?}"
        );
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn a_dropped_output_leaves_the_previous_one_and_no_staging() {
        let base = tmp("drop");
        let root = base.join("out");
        let first = OutDir::create(&root).unwrap();
        first.write("a.csv", b"1").unwrap();
        first.commit().unwrap();
        {
            let failed = OutDir::create(&root).unwrap();
            failed.write("a.csv", b"half").unwrap();
        }
        assert_eq!(std::fs::read(root.join("a.csv")).unwrap(), b"1");
        assert_eq!(std::fs::read_dir(&base).unwrap().count(), 1);
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn a_folder_of_other_files_is_never_replaced() {
        let base = tmp("foreign");
        let root = base.join("mine");
        std::fs::create_dir_all(&root).unwrap();
        std::fs::write(root.join("thesis.tex"), b"precious").unwrap();
        let err = OutDir::create(&root).err().expect("refused").to_string();
        assert!(err.contains("not a pedomatch output"), "{err}");
        assert_eq!(std::fs::read(root.join("thesis.tex")).unwrap(), b"precious");
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn an_output_holding_the_users_own_files_is_never_replaced() {
        let base = tmp("users-files");
        let root = base.join("out");
        let first = OutDir::create(&root).unwrap();
        first.write("a.csv", b"1").unwrap();
        first.write("figures/f.png", b"x").unwrap();
        first.commit().unwrap();
        // File-manager litter does not count; a re-run replaces the output.
        std::fs::write(root.join(".DS_Store"), b"").unwrap();
        std::fs::write(root.join("figures/Thumbs.db"), b"").unwrap();
        let second = OutDir::create(&root).unwrap();
        second.write("a.csv", b"2").unwrap();
        second.write("figures/f.png", b"y").unwrap();
        second.commit().unwrap();
        assert_eq!(std::fs::read(root.join("a.csv")).unwrap(), b"2");
        // Notes and an edited copy saved into it afterwards stop the next run, at its start.
        std::fs::write(root.join("notes.txt"), b"precious").unwrap();
        std::fs::write(root.join("figures/f_edited.png"), b"mine").unwrap();
        let err = OutDir::create(&root).err().expect("refused").to_string();
        assert!(
            err.contains("did not write (figures/f_edited.png, notes.txt)"),
            "{err}"
        );
        assert_eq!(std::fs::read(root.join("notes.txt")).unwrap(), b"precious");
        // ... and at its commit, if they were saved while the run was working.
        std::fs::remove_file(root.join("notes.txt")).unwrap();
        std::fs::remove_file(root.join("figures/f_edited.png")).unwrap();
        let third = OutDir::create(&root).unwrap();
        std::fs::write(root.join("notes.txt"), b"precious").unwrap();
        assert!(third.commit().is_err());
        assert_eq!(std::fs::read(root.join("notes.txt")).unwrap(), b"precious");
        assert_eq!(std::fs::read(root.join("a.csv")).unwrap(), b"2");
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn an_output_whose_marker_lists_no_files_is_replaced_as_before() {
        let base = tmp("legacy-marker");
        let root = base.join("out");
        std::fs::create_dir_all(&root).unwrap();
        std::fs::write(root.join(MARKER), b"written by pedomatch\n").unwrap();
        std::fs::write(root.join("a.csv"), b"1").unwrap();
        let out = OutDir::create(&root).unwrap();
        out.write("b.csv", b"2").unwrap();
        out.commit().unwrap();
        assert!(!root.join("a.csv").exists());
        let marker = std::fs::read_to_string(root.join(MARKER)).unwrap();
        assert_eq!(marker, "written by pedomatch\nb.csv\n");
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[cfg(unix)]
    fn set_mode(path: &Path, mode: u32) {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_write_protected_output_is_never_replaced() {
        let base = tmp("protected");
        let root = base.join("out");
        let first = OutDir::create(&root).unwrap();
        first.write("a.csv", b"1").unwrap();
        first.commit().unwrap();
        set_mode(&root, 0o555);
        let err = OutDir::create(&root).err().map(|e| e.to_string());
        set_mode(&root, 0o755);
        let err = err.expect("refused");
        assert!(err.contains("write-protected"), "{err}");
        assert_eq!(std::fs::read(root.join("a.csv")).unwrap(), b"1");
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn an_unwritable_place_is_named_by_the_output_not_its_staging_folder() {
        let base = tmp("unwritable");
        let parent = base.join("ro");
        std::fs::create_dir(&parent).unwrap();
        set_mode(&parent, 0o555);
        let bound = std::fs::create_dir(parent.join("probe")).is_err();
        let err = OutDir::create(&parent.join("res"))
            .err()
            .map(|e| e.to_string());
        set_mode(&parent, 0o755);
        if bound {
            let err = err.expect("refused");
            assert!(
                err.contains("ro/res") && err.contains("cannot be written in"),
                "{err}"
            );
            assert!(!err.contains("pedomatch-tmp"), "{err}");
        } // else: permissions do not bind this user (root)
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn stale_staging_of_a_dead_process_is_swept() {
        let base = tmp("stale");
        // PIDs above the kernel's pid_max (4194304 at most) never belong to a live process.
        let stale = base.join(".out.pedomatch-tmp-4294967");
        std::fs::create_dir_all(stale.join("figures")).unwrap();
        let out = OutDir::create(&base.join("out")).unwrap();
        assert!(!stale.exists());
        drop(out);
        std::fs::remove_dir_all(&base).unwrap();
    }
}
