//! The one atomic writer every output goes through: a file is written under a temporary name
//! beside its destination and renamed into place complete, alone or as part of a set that
//! appears together (DESIGN.md, Errors: never a partial output file); an interrupt removes
//! what a run had not finished.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use thiserror::Error;
/// A file that could not be written (the OS error is its source, not part of its message, so
/// an error chain names it once).
#[derive(Debug, Error)]
#[error("cannot write {}", path.display())]
pub struct WriteError {
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

/// A file written completely under a temporary name beside its destination, not yet renamed.
/// [`Staged::commit`] renames it into place; dropping it uncommitted removes the temporary
/// file, so every error path (and a panic) cleans up. [`commit_all`] makes a set of staged
/// files appear together, or not at all. Every temporary file is also listed in a process-wide
/// registry, so an interrupt ([`remove_temps`]) removes what the run had not finished.
#[must_use = "a staged file is removed unless committed"]
pub struct Staged {
    tmp: PathBuf,
    path: PathBuf,
    committed: bool,
}

/// Prefix of every temporary file the project writes: `.<name>.vastocean-tmp.<pid>.<n>`.
pub const TEMP_MARKER: &str = ".vastocean-tmp.";

/// Temporary files this process has open, and the lock a set commit holds while it renames
/// (an interrupt waits for it, so a set never appears half renamed).
static TEMPS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
static COMMITTING: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn lock<T>(m: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

fn register(tmp: &Path) {
    lock(&TEMPS).push(tmp.to_path_buf());
}

fn unregister(tmp: &Path) {
    lock(&TEMPS).retain(|t| t != tmp);
}

/// For an interrupt: removes the temporary files of writes under way (after any set being
/// renamed into place is finished) and returns how many there were. The process must exit next:
/// the commit lock stays held, so no later set can be committed.
pub fn remove_temps() -> usize {
    let commit = lock(&COMMITTING);
    let temps: Vec<PathBuf> = lock(&TEMPS).drain(..).collect();
    for t in &temps {
        let _ = fs::remove_file(t);
    }
    // Holding the commit lock until exit keeps a later set from being half-renamed.
    std::mem::forget(commit);
    temps.len()
}

fn temp_name(path: &Path) -> PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut name = std::ffi::OsString::from(".");
    name.push(path.file_name().unwrap_or_default());
    name.push(format!("{TEMP_MARKER}{}.{n}", std::process::id()));
    path.with_file_name(name)
}

/// Removes the temporary files that earlier runs writing `path` left behind when they were
/// killed (their process is gone); returns how many. Linux-only liveness check (/proc).
pub fn sweep_stale_temps(path: &Path) -> usize {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else {
        return 0;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(TEMP_MARKER);
    let prefix = prefix.to_string_lossy().into_owned();
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let pid = rest.split('.').next().and_then(|p| p.parse::<u32>().ok());
        let alive = pid.is_some_and(|p| Path::new(&format!("/proc/{p}")).exists());
        if !alive && fs::remove_file(e.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

impl Staged {
    /// Renames the temporary file to its destination.
    pub fn commit(self) -> Result<(), WriteError> {
        commit_all(vec![self])
    }

    /// Where the file goes when committed.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_file(&self.tmp);
        }
        unregister(&self.tmp);
    }
}

/// Renames every staged file into place, all or none: files already under the final names are
/// first moved aside, and if any rename fails the new files are removed and the old ones put
/// back, so a failure leaves the previous set untouched.
pub fn commit_all(files: Vec<Staged>) -> Result<(), WriteError> {
    let _commit = lock(&COMMITTING);
    let err = |path: &Path, source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    // Old files moved aside: (backup, final).
    let mut aside: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut done: Vec<usize> = Vec::new();
    let mut result = Ok(());
    for f in &files {
        if fs::symlink_metadata(&f.path).is_ok_and(|m| m.is_dir()) {
            result = Err(err(
                &f.path,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
            ));
            break;
        }
        if f.path.exists() {
            let backup = temp_name(&f.path);
            match fs::rename(&f.path, &backup) {
                Ok(()) => aside.push((backup, f.path.clone())),
                Err(e) => {
                    result = Err(err(&f.path, e));
                    break;
                }
            }
        }
    }
    if result.is_ok() {
        for (i, f) in files.iter().enumerate() {
            match fs::rename(&f.tmp, &f.path) {
                Ok(()) => done.push(i),
                Err(e) => {
                    result = Err(err(&f.path, e));
                    break;
                }
            }
        }
    }
    let mut files = files;
    if result.is_err() {
        for &i in &done {
            let _ = fs::remove_file(&files[i].path);
        }
        for (backup, path) in &aside {
            let _ = fs::rename(backup, path);
        }
    } else {
        for (backup, _) in &aside {
            let _ = fs::remove_file(backup);
        }
        for f in &mut files {
            f.committed = true;
        }
    }
    drop(files);
    result
}

/// Writes the contents of `path` to a unique temporary file in the same folder (created if
/// missing) and syncs it to disk; nothing appears under `path` until [`Staged::commit`].
pub fn stage(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<fs::File>) -> std::io::Result<()>,
) -> Result<Staged, WriteError> {
    let err = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    if path.file_name().is_none() {
        return Err(err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a file path",
        )));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(err)?;
    }
    let staged = Staged {
        tmp: temp_name(path),
        path: path.to_path_buf(),
        committed: false,
    };
    register(&staged.tmp);
    let file = fs::File::create(&staged.tmp).map_err(err)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        write(&mut w)?;
        w.flush()?;
        w.get_ref().sync_all()
    })();
    // On error `staged` drops here and removes the temporary file.
    result.map(|()| staged).map_err(err)
}

/// Writes `path` atomically: it appears complete, or not at all (DESIGN.md, Errors).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<fs::File>) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    stage(path, write)?.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_no_file() {
        let dir = std::env::temp_dir().join(format!("vastocean-atomic-{}", std::process::id()));
        let path = dir.join("x.json");
        let r = write_atomically(&path, |_| Err(std::io::Error::other("boom")));
        assert!(r.is_err());
        assert!(!path.exists());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0, "temp file removed");
        let _ = fs::remove_dir_all(dir);
    }
}
