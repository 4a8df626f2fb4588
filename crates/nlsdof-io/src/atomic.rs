//! Atomic output files: content goes to a hidden temporary file next to the
//! target and is renamed over it only by [`AtomicFile::commit`]. Dropping an
//! uncommitted `AtomicFile` (error, panic) removes the temporary, so no
//! partial output is ever visible under the target name.
//!
//! Every live temporary is remembered, and [`cleanup_all`] (called from the
//! Ctrl-C handler) removes them. A whole output folder built as a hidden
//! staging folder and renamed when complete (`nlsdof demo`) is registered
//! with [`register_partial_dir`] so that Ctrl-C removes it too.

use crate::error::IoError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static LIVE_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file and staging folder still registered (for a
/// Ctrl-C handler).
pub fn cleanup_all() {
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

/// Remembers a staging folder (incomplete output) for [`cleanup_all`].
pub fn register_partial_dir(dir: &Path) {
    LIVE_DIRS.lock().map(|mut l| l.push(dir.to_path_buf())).ok();
}

/// Forgets a staging folder: it was renamed to its final name or removed.
pub fn unregister_partial_dir(dir: &Path) {
    LIVE_DIRS.lock().map(|mut l| l.retain(|p| p != dir)).ok();
}

/// A file being written; invisible under its final name until committed.
pub struct AtomicFile {
    target: PathBuf,
    tmp: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    pub fn create(target: &Path) -> Result<Self, IoError> {
        let dir = target
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tmp = dir.join(format!(".{name}.{}.partial", std::process::id()));
        let f = File::create(&tmp).map_err(|source| IoError::Write {
            path: target.to_path_buf(),
            source,
        })?;
        LIVE.lock().map(|mut l| l.push(tmp.clone())).ok();
        Ok(Self {
            target: target.to_path_buf(),
            tmp,
            writer: Some(BufWriter::with_capacity(1 << 20, f)),
        })
    }

    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer.as_mut().expect("writer present until commit")
    }

    /// Flushes and renames the temporary over the target.
    pub fn commit(mut self) -> Result<(), IoError> {
        let w = self.writer.take().expect("writer present until commit");
        let f = w.into_inner().map_err(|e| IoError::Write {
            path: self.target.clone(),
            source: e.into_error(),
        })?;
        f.sync_all().ok();
        drop(f);
        std::fs::rename(&self.tmp, &self.target).map_err(|source| IoError::Write {
            path: self.target.clone(),
            source,
        })?;
        LIVE.lock().map(|mut l| l.retain(|p| p != &self.tmp)).ok();
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
        if self.writer.is_some() {
            self.writer = None;
            let _ = std::fs::remove_file(&self.tmp);
            LIVE.lock().map(|mut l| l.retain(|p| p != &self.tmp)).ok();
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
