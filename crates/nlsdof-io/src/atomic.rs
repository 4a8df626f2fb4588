//! Atomic output files: content goes to a hidden temporary file next to the
//! target and is renamed over it only by [`AtomicFile::commit`]. Dropping an
//! uncommitted `AtomicFile` (error, panic) removes the temporary, and so does
//! a failed commit (flush or rename), so no partial output is ever visible
//! under the target name and no temporary is left behind.
//!
//! Targets that are not regular files are never replaced: a character
//! device (`/dev/null`, `/dev/full`, a terminal) is written through, so a
//! full device reports its error; a FIFO, socket or block device is refused;
//! a directory is refused up front. A symbolic link is followed: its target
//! is replaced, the link stays.
//!
//! With [`defer_commits`] (the CLI turns it on for every command that writes
//! files) a commit only flushes and syncs the temporary; the renames all
//! happen in [`commit_deferred`], once the command has succeeded, so a
//! command with several outputs writes all or nothing. Two outputs with the
//! same target in one run are refused.
//!
//! Every live temporary is remembered, and [`cleanup_all`] (called from the
//! Ctrl-C / SIGTERM / SIGHUP handler and on every error exit) removes them. A
//! whole output folder built as a hidden staging folder and renamed when
//! complete (`nlsdof demo`) is registered with [`register_partial_dir`] so
//! that the cleanup removes it too.

use crate::error::IoError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Temporaries not yet renamed (written, or committed but deferred).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Targets of this run's outputs (normalised), to refuse a second output
/// to the same file.
static TARGETS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static LIVE_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static DEFER: AtomicBool = AtomicBool::new(false);
/// Deferred renames: (temporary, target).
static PENDING: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

/// Removes every temporary file and staging folder still registered (for a
/// signal handler or an error exit). Deferred commits are dropped.
pub fn cleanup_all() {
    if let Ok(mut p) = PENDING.lock() {
        p.clear();
    }
    if let Ok(live) = LIVE.lock() {
        for p in live.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
    if let Ok(live) = LIVE_DIRS.lock() {
        for p in live.iter() {
            let _ = std::fs::remove_dir_all(p);
        }
    }
}

/// From now on [`AtomicFile::commit`] only finishes the temporary; the
/// renames happen in [`commit_deferred`] (all outputs of a run, or none).
pub fn defer_commits() {
    DEFER.store(true, Ordering::SeqCst);
}

/// Renames every deferred temporary over its target, in the order they
/// were committed. On a failure the remaining temporaries are removed and
/// the error is returned (the targets renamed before it stay).
pub fn commit_deferred() -> Result<(), IoError> {
    let pending = PENDING
        .lock()
        .map(|mut p| std::mem::take(&mut *p))
        .unwrap_or_default();
    let mut result = Ok(());
    for (tmp, target) in pending {
        if result.is_ok() {
            if let Err(source) = std::fs::rename(&tmp, &target) {
                result = Err(IoError::Write {
                    path: target.clone(),
                    source,
                });
                let _ = std::fs::remove_file(&tmp);
            }
        } else {
            let _ = std::fs::remove_file(&tmp);
        }
        forget(&tmp);
    }
    result
}

/// Remembers a staging folder (incomplete output) for [`cleanup_all`].
pub fn register_partial_dir(dir: &Path) {
    LIVE_DIRS.lock().map(|mut l| l.push(dir.to_path_buf())).ok();
}

/// Forgets a staging folder: it was renamed to its final name or removed.
pub fn unregister_partial_dir(dir: &Path) {
    LIVE_DIRS.lock().map(|mut l| l.retain(|p| p != dir)).ok();
}

fn forget(tmp: &Path) {
    LIVE.lock().map(|mut l| l.retain(|p| p != tmp)).ok();
}

fn write_error(path: &Path, kind: std::io::ErrorKind, message: String) -> IoError {
    IoError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::new(kind, message),
    }
}

/// Where an output to `target` really goes, and how.
enum Target {
    /// Regular file (existing or new): temporary + rename onto this path.
    Replace(PathBuf),
    /// Character device: written through.
    Device,
}

fn classify(target: &Path) -> Result<Target, IoError> {
    use std::io::ErrorKind as K;
    if target.as_os_str().is_empty() {
        return Err(write_error(
            target,
            K::InvalidInput,
            "empty file name".into(),
        ));
    }
    match std::fs::metadata(target) {
        Ok(meta) => {
            let ft = meta.file_type();
            if ft.is_dir() {
                return Err(write_error(
                    target,
                    K::InvalidInput,
                    "is a directory; give a file name".into(),
                ));
            }
            if ft.is_file() {
                // Follow a symbolic link: replace what it points to.
                let real = if std::fs::symlink_metadata(target)
                    .map(|m| m.file_type().is_symlink())
                    .unwrap_or(false)
                {
                    std::fs::canonicalize(target).unwrap_or_else(|_| target.to_path_buf())
                } else {
                    target.to_path_buf()
                };
                return Ok(Target::Replace(real));
            }
            #[cfg(unix)]
            {
                use std::os::unix::fs::FileTypeExt;
                if ft.is_char_device() {
                    return Ok(Target::Device);
                }
                let what = if ft.is_fifo() {
                    "a FIFO"
                } else if ft.is_socket() {
                    "a socket"
                } else if ft.is_block_device() {
                    "a block device"
                } else {
                    "not a regular file"
                };
                Err(write_error(
                    target,
                    K::InvalidInput,
                    format!("is {what}; refusing to write to it (give a regular file name)"),
                ))
            }
            #[cfg(not(unix))]
            Err(write_error(
                target,
                K::InvalidInput,
                "is not a regular file; refusing to write to it".into(),
            ))
        }
        Err(_) => {
            // A symbolic link that does not resolve: follow it by hand. A
            // loop is refused (renaming onto the link would replace it with
            // a regular file); a dangling link is written through, creating
            // its target, as a shell redirection does.
            if std::fs::symlink_metadata(target).is_ok_and(|m| m.file_type().is_symlink()) {
                let mut p = target.to_path_buf();
                for _ in 0..40 {
                    match std::fs::symlink_metadata(&p) {
                        Ok(m) if m.file_type().is_symlink() => {
                            let next = std::fs::read_link(&p).map_err(|e| {
                                write_error(target, e.kind(), format!("cannot read the link: {e}"))
                            })?;
                            p = match (next.is_absolute(), p.parent()) {
                                (false, Some(dir)) => dir.join(next),
                                _ => next,
                            };
                        }
                        Ok(_) => return classify(&p),
                        Err(_) => return classify(&p),
                    }
                }
                return Err(write_error(
                    target,
                    K::InvalidInput,
                    "is a symbolic link loop (it never reaches a file); give another output path"
                        .into(),
                ));
            }
            if target.to_string_lossy().ends_with('/') {
                return Err(write_error(
                    target,
                    K::InvalidInput,
                    "is a directory name; give a file name".into(),
                ));
            }
            Ok(Target::Replace(target.to_path_buf()))
        }
    }
}

/// `path` made absolute (the folder canonicalised when it exists), to
/// compare output targets.
fn normalised(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    };
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => std::fs::canonicalize(dir)
            .map(|d| d.join(name))
            .unwrap_or(abs),
        _ => abs,
    }
}

/// Registers `target` as an output of this run; refuses a second output to
/// the same file.
fn claim(shown: &Path, real: &Path) -> Result<PathBuf, IoError> {
    let key = normalised(real);
    let mut t = TARGETS.lock().unwrap_or_else(|e| e.into_inner());
    if t.contains(&key) {
        return Err(write_error(
            shown,
            std::io::ErrorKind::AlreadyExists,
            "the same file is given for two outputs; give each output its own name".into(),
        ));
    }
    t.push(key.clone());
    Ok(key)
}

fn release(key: &Path) {
    TARGETS.lock().map(|mut l| l.retain(|p| p != key)).ok();
}

/// Checks before any work that `targets` can be written: no directory, FIFO,
/// socket or block device, an existing folder, and no file named twice.
/// The label says which option each path came from.
pub fn check_targets(targets: &[(&str, &Path)]) -> Result<(), IoError> {
    let mut seen: Vec<(PathBuf, &str)> = Vec::new();
    for &(label, path) in targets {
        let real = match classify(path) {
            Ok(Target::Replace(p)) => p,
            Ok(Target::Device) => continue,
            Err(IoError::Write { source, .. }) => {
                return Err(write_error(
                    path,
                    source.kind(),
                    format!("{label}: {source}"),
                ))
            }
            Err(e) => return Err(e),
        };
        let dir = real
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        if !dir.is_dir() {
            return Err(write_error(
                path,
                std::io::ErrorKind::NotFound,
                format!("{label}: folder {} does not exist", dir.display()),
            ));
        }
        let key = normalised(&real);
        if let Some((_, other)) = seen.iter().find(|(k, _)| *k == key) {
            return Err(write_error(
                path,
                std::io::ErrorKind::AlreadyExists,
                format!("given for both {other} and {label}: one file for two outputs; give each output its own file"),
            ));
        }
        seen.push((key, label));
    }
    Ok(())
}

/// A file being written; invisible under its final name until committed.
pub struct AtomicFile {
    target: PathBuf,
    /// Temporary; `None` when writing through to a device.
    tmp: Option<PathBuf>,
    /// Where the temporary is renamed to (the target, or a link's target).
    dest: PathBuf,
    /// The claimed (normalised) target, released unless a deferred commit
    /// keeps it for the rest of the run.
    claim: Option<PathBuf>,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    pub fn create(target: &Path) -> Result<Self, IoError> {
        match classify(target)? {
            Target::Device => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(target)
                    .map_err(|source| IoError::Write {
                        path: target.to_path_buf(),
                        source,
                    })?;
                Ok(Self {
                    target: target.to_path_buf(),
                    tmp: None,
                    dest: target.to_path_buf(),
                    claim: None,
                    writer: Some(BufWriter::with_capacity(1 << 20, f)),
                })
            }
            Target::Replace(dest) => {
                let key = claim(target, &dest)?;
                let dir = dest
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .unwrap_or(Path::new("."));
                let name = dest
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let tmp = dir.join(format!(".{name}.{}.partial", std::process::id()));
                let f = File::create(&tmp).map_err(|source| {
                    release(&key);
                    IoError::Write {
                        path: target.to_path_buf(),
                        source,
                    }
                })?;
                LIVE.lock().map(|mut l| l.push(tmp.clone())).ok();
                Ok(Self {
                    target: target.to_path_buf(),
                    tmp: Some(tmp),
                    dest,
                    claim: Some(key),
                    writer: Some(BufWriter::with_capacity(1 << 20, f)),
                })
            }
        }
    }

    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer.as_mut().expect("writer present until commit")
    }

    /// Flushes and renames the temporary over the target (or, with
    /// [`defer_commits`], queues the rename). On failure the temporary is
    /// removed.
    pub fn commit(mut self) -> Result<(), IoError> {
        let result = self.finish();
        if result.is_err() {
            if let Some(tmp) = &self.tmp {
                let _ = std::fs::remove_file(tmp);
                forget(tmp);
            }
        }
        result
    }

    fn finish(&mut self) -> Result<(), IoError> {
        let w = self.writer.take().expect("writer present until commit");
        let err = |source| IoError::Write {
            path: self.target.clone(),
            source,
        };
        let f = w.into_inner().map_err(|e| err(e.into_error()))?;
        let Some(tmp) = &self.tmp else {
            // A device: flushed above; a sync error (e.g. EINVAL on a
            // terminal) is not a write error.
            return Ok(());
        };
        if let Err(e) = f.sync_all() {
            // ENOSPC, EIO, EDQUOT: the data may not be on disk.
            if matches!(e.raw_os_error(), Some(28) | Some(5) | Some(122)) {
                return Err(err(e));
            }
        }
        drop(f);
        if DEFER.load(Ordering::SeqCst) {
            PENDING
                .lock()
                .map(|mut p| p.push((tmp.clone(), self.dest.clone())))
                .ok();
            // The target stays claimed for the rest of the run.
            self.claim = None;
            return Ok(());
        }
        std::fs::rename(tmp, &self.dest).map_err(err)?;
        forget(tmp);
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer().flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(key) = self.claim.take() {
            release(&key);
        }
        if self.writer.is_some() {
            self.writer = None;
            if let Some(tmp) = &self.tmp {
                let _ = std::fs::remove_file(tmp);
                forget(tmp);
            }
        }
    }
}

/// Writes `bytes` to `target` atomically.
pub fn write_atomic(target: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let mut f = AtomicFile::create(target)?;
    f.write_all(bytes).map_err(|source| IoError::Write {
        path: target.to_path_buf(),
        source,
    })?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 30: an output path that is a symbolic link loop was replaced by
    /// a regular file. It is refused, and nothing is written; a dangling link
    /// is written through (its target created, the link kept).
    #[cfg(unix)]
    #[test]
    fn symlink_loops_are_refused_and_dangling_links_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let (l1, l2) = (dir.path().join("l1"), dir.path().join("l2"));
        std::os::unix::fs::symlink(&l2, &l1).unwrap();
        std::os::unix::fs::symlink(&l1, &l2).unwrap();
        let e = write_atomic(&l1, b"x").unwrap_err();
        assert!(e.to_string().contains("symbolic link loop"), "{e}");
        assert!(check_targets(&[("--out", &l1)]).is_err());
        assert!(std::fs::symlink_metadata(&l1)
            .unwrap()
            .file_type()
            .is_symlink());
        let dangling = dir.path().join("d");
        std::os::unix::fs::symlink("target.csv", &dangling).unwrap();
        write_atomic(&dangling, b"data").unwrap();
        assert!(std::fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            std::fs::read(dir.path().join("target.csv")).unwrap(),
            b"data"
        );
    }

    #[test]
    fn uncommitted_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.csv");
        {
            let mut f = AtomicFile::create(&target).unwrap();
            f.write_all(b"partial").unwrap();
        }
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_atomic(&target, b"whole").unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "whole");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}

fn folder_error(out: &Path, message: impl std::fmt::Display) -> IoError {
    IoError::OutputFolder {
        path: out.to_path_buf(),
        message: message.to_string(),
    }
}

/// Where an output folder named `out` really goes: `out` itself, or, when
/// `out` is a symbolic link, the folder it points to (so that the link is
/// kept and the folder behind it replaced, as writing through a link to a
/// file does). A link that does not resolve (a loop, or a missing target)
/// is refused before any work.
pub fn resolve_out_dir(out: &Path) -> Result<PathBuf, IoError> {
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return std::fs::canonicalize(out).map_err(|e| {
            folder_error(
                out,
                format!("is a symbolic link that does not resolve ({e}); give another folder"),
            )
        });
    }
    Ok(out.to_path_buf())
}

/// Whether `out` may become an output folder: absent, or an empty
/// folder, or any folder when `force`.
pub fn check_out_dir(out: &Path, force: bool) -> Result<(), IoError> {
    match std::fs::metadata(out) {
        Err(_) => Ok(()),
        Ok(m) if !m.is_dir() => Err(folder_error(out, "exists and is not a directory")),
        Ok(_) => {
            let non_empty = std::fs::read_dir(out)
                .map_err(|e| folder_error(out, e))?
                .next()
                .is_some();
            if non_empty && !force {
                Err(folder_error(
                    out,
                    "directory exists and is not empty (use --force to replace it)",
                ))
            } else {
                Ok(())
            }
        }
    }
}

/// A whole output folder built atomically: a hidden sibling of the target
/// (`.NAME.PID.partial`, with a `tables` subfolder), registered for the
/// Ctrl-C cleanup, renamed over the target by [`StagedDir::commit`] and
/// removed on drop unless committed.
pub struct StagedDir {
    dir: Option<PathBuf>,
}

impl StagedDir {
    /// Starts the folder that will become `out`.
    pub fn create(out: &Path) -> Result<Self, IoError> {
        let parent = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| folder_error(out, "not a folder name"))?;
        if !parent.is_dir() {
            return Err(folder_error(
                out,
                format!("parent folder {} does not exist", parent.display()),
            ));
        }
        let dir = parent.join(format!(".{name}.{}.partial", std::process::id()));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).ok();
        }
        register_partial_dir(&dir);
        std::fs::create_dir_all(dir.join("tables")).map_err(|source| IoError::Write {
            path: dir.clone(),
            source,
        })?;
        Ok(Self { dir: Some(dir) })
    }

    /// The folder to write into.
    pub fn path(&self) -> &Path {
        self.dir.as_deref().expect("present until commit")
    }

    /// Renames the finished folder to `out` (replacing an existing one).
    pub fn commit(mut self, out: &Path, force: bool) -> Result<(), IoError> {
        let dir = self.dir.take().expect("present until commit");
        let fail = |e: std::io::Error, dir: &Path| {
            std::fs::remove_dir_all(dir).ok();
            IoError::Write {
                path: out.to_path_buf(),
                source: e,
            }
        };
        if out.exists() {
            // checked at start: empty, or --force
            check_out_dir(out, force).inspect_err(|_| {
                std::fs::remove_dir_all(&dir).ok();
            })?;
            let old = dir.with_extension("old");
            std::fs::rename(out, &old).map_err(|e| fail(e, &dir))?;
            if let Err(e) = std::fs::rename(&dir, out) {
                std::fs::rename(&old, out).ok();
                return Err(fail(e, &dir));
            }
            std::fs::remove_dir_all(&old).ok();
        } else {
            std::fs::rename(&dir, out).map_err(|e| fail(e, &dir))?;
        }
        // Renamed (or removed on failure above, where a Ctrl-C cleanup of
        // the vanished path is harmless).
        unregister_partial_dir(&dir);
        Ok(())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if let Some(d) = self.dir.take() {
            std::fs::remove_dir_all(&d).ok();
            unregister_partial_dir(&d);
        }
    }
}
