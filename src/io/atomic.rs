//! Atomic file output: write to a temporary in the same directory, then rename.

use std::fs::{self, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use super::file_out::write_and_sync;

/// Why [`write_atomically`] failed. Every variant displays as one line naming the target path.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The target exists and is a directory.
    #[error("cannot write '{}': it is a directory", .path.display())]
    IsDirectory {
        /// The requested output path.
        path: PathBuf,
    },
    /// The target exists and is neither a regular file nor a directory (FIFO, socket, device…).
    #[error("cannot write '{}': it exists and is not a regular file", .path.display())]
    NotRegularFile {
        /// The requested output path.
        path: PathBuf,
    },
    /// The path has no file-name component (e.g. it ends in `..`).
    #[error("cannot write '{}': the path does not name a file", .path.display())]
    NoFileName {
        /// The requested output path.
        path: PathBuf,
    },
    /// The path's extension names no mesh format (see [`super::MeshFormat::from_path`]).
    #[error(
        "cannot write '{}': unknown output format; use a .msh, .inp or .vtu (tetrahedra) or \
         .obj, .ply or .stl (isosurface) extension",
        .path.display()
    )]
    UnknownFormat {
        /// The requested output path.
        path: PathBuf,
    },
    /// The directory the target would be created in does not exist (found by
    /// [`check_writable`]).
    #[error("cannot write '{}': directory '{}' does not exist", .path.display(), .dir.display())]
    MissingDirectory {
        /// The requested output path.
        path: PathBuf,
        /// Its parent directory.
        dir: PathBuf,
    },
    /// An I/O error while creating, writing, flushing or renaming the temporary file.
    #[error("cannot write '{}': {source}", .path.display())]
    Io {
        /// The requested output path.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
}

/// Distinguishes temporaries of concurrent calls within one process.
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporaries that exist right now (created and not yet renamed or removed), for
/// [`remove_pending_temporaries`]. Creating, renaming and removing a temporary happen while
/// this lock is held, so a signal handler that takes the lock sees every temporary on disk.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes every temporary of [`write_atomically`] and [`write_pending`] that exists now, and
/// keeps any new one from being created or renamed: the lock is never released. For a
/// SIGINT/SIGTERM handler that ends the process right after.
pub fn remove_pending_temporaries() {
    let guard = pending();
    for tmp in guard.iter() {
        let _ = fs::remove_file(tmp);
    }
    std::mem::forget(guard);
}

/// A complete file under its temporary name (see [`write_pending`]): [`PendingFile::commit`]
/// renames it onto its target; dropping it removes it.
#[derive(Debug)]
pub struct PendingFile {
    tmp: PathBuf,
    path: PathBuf,
}

impl PendingFile {
    /// Renames the temporary onto the target path.
    ///
    /// # Errors
    /// [`WriteError::Io`] if the rename fails (the temporary is then removed).
    pub fn commit(self) -> Result<(), WriteError> {
        let mut list = pending();
        let result = fs::rename(&self.tmp, &self.path);
        if result.is_err() {
            let _ = fs::remove_file(&self.tmp);
        }
        list.retain(|t| t != &self.tmp);
        drop(list);
        let path = self.path.clone();
        std::mem::forget(self);
        result.map_err(|source| WriteError::Io { path, source })
    }
}

impl Drop for PendingFile {
    fn drop(&mut self) {
        let mut list = pending();
        let _ = fs::remove_file(&self.tmp);
        list.retain(|t| t != &self.tmp);
    }
}

/// Writes a file atomically: `write` receives a buffered writer (1 MiB buffer) on a temporary
/// file `.{name}.tmp-{pid}-{n}` in the directory of `path`; after `write` returns `Ok`, the data
/// are flushed and synced and the temporary is renamed onto `path`, replacing an existing
/// regular file. Readers therefore see either the old file or the complete new one.
///
/// If `path` is a symbolic link, the link itself is replaced by the new file.
///
/// # Errors
/// Returns [`WriteError`] (whose `Display` is a single line naming `path`) and leaves neither
/// the temporary nor a partial `path` behind when
/// * `path` is an existing directory ([`WriteError::IsDirectory`]) or another non-regular file
///   such as a FIFO ([`WriteError::NotRegularFile`]); nothing is created in that case;
/// * `path` has no file name ([`WriteError::NoFileName`]);
/// * creating the temporary, the closure `write`, flushing, syncing or renaming fails
///   ([`WriteError::Io`]); an existing file at `path` is then left untouched.
pub fn write_atomically<F>(path: &Path, write: F) -> Result<(), WriteError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    write_pending(path, write)?.commit()
}

/// The first half of [`write_atomically`]: writes, flushes and syncs the temporary and returns
/// it without renaming it, so that several outputs can be completed before any replaces its
/// target (commit them in turn; drop them all when one fails).
///
/// # Errors
/// As [`write_atomically`], except that renaming cannot fail here.
pub fn write_pending<F>(path: &Path, write: F) -> Result<PendingFile, WriteError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let io_err = |source: io::Error| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    check_target(path)?;
    let name = path.file_name().ok_or_else(|| WriteError::NoFileName {
        path: path.to_path_buf(),
    })?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    let tmp = dir.join(tmp_name);

    let mut list = pending();
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(io_err)?;
    list.push(tmp.clone());
    drop(list);
    let pending_file = PendingFile {
        tmp,
        path: path.to_path_buf(),
    };
    // On an error, dropping `pending_file` removes the temporary.
    write_and_sync(file, write).map_err(io_err)?;
    Ok(pending_file)
}

/// Refuses an existing directory or other non-regular file as a target.
fn check_target(path: &Path) -> Result<(), WriteError> {
    match fs::metadata(path) {
        Ok(meta) if meta.is_dir() => Err(WriteError::IsDirectory {
            path: path.to_path_buf(),
        }),
        Ok(meta) if !meta.is_file() => Err(WriteError::NotRegularFile {
            path: path.to_path_buf(),
        }),
        Ok(_) => Ok(()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(WriteError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// Checks early (before any expensive work) that `path` can be a target of
/// [`write_atomically`]: it must not be an existing directory or other non-regular file, and
/// its directory must exist. Nothing is created.
///
/// # Errors
/// [`WriteError::IsDirectory`], [`WriteError::NotRegularFile`] or
/// [`WriteError::MissingDirectory`].
pub fn check_writable(path: &Path) -> Result<(), WriteError> {
    let path_buf = || path.to_path_buf();
    match fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err(WriteError::IsDirectory { path: path_buf() }),
        Ok(m) if !m.is_file() => return Err(WriteError::NotRegularFile { path: path_buf() }),
        _ => {}
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => Err(WriteError::MissingDirectory {
            path: path_buf(),
            dir: dir.to_path_buf(),
        }),
        _ => Ok(()),
    }
}

/// Whether `a` and `b` name the same file, whatever their spelling: the same device and inode
/// when both exist (hard links and symbolic links included), otherwise the same canonical
/// directory and file name (`out/../out/m.vtu` and `out/m.vtu`).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    match (canonical_target(a), canonical_target(b)) {
        (Some(ca), Some(cb)) => ca == cb,
        _ => a == b,
    }
}

/// `path` with its directory made canonical (the file itself need not exist).
fn canonical_target(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = fs::canonicalize(path) {
        return Some(p);
    }
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(fs::canonicalize(dir).ok()?.join(name))
}
