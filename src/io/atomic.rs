//! Atomic writing: a temporary sibling file (random name, created exclusively, never through
//! a symlink, locked while written) renamed over the target, stale temporaries of dead writers
//! removed, and reads and writes confined to an active [`OutputRoot`].

use super::root::active_root;
use super::OutputError;
#[cfg(doc)]
use super::OutputRoot;
use std::fs;
use std::io::{self, Read as _, Write as _};
use std::path::Path;
use std::time::Duration;

/// Creates the parent directory of `path` (and its ancestors) if missing.
pub fn ensure_parent_dir(path: &Path) -> Result<(), OutputError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            fs::create_dir_all(dir).map_err(|e| OutputError::io("create directory", dir, e))
        }
        _ => Ok(()),
    }
}

/// Reads `path` whole, `Ok(None)` when it does not exist; refused when it is not a regular
/// file (a FIFO in its place is opened without blocking and refused, never waited on) or is
/// larger than `limit_bytes` (before reading; a file that grows meanwhile is read no further
/// than one byte past the limit). While an [`OutputRoot`] is active on this thread, `path`
/// must lie under it and is read beneath its open directory (a symlink leading out is
/// refused), as writes are.
pub fn read_existing(path: &Path, limit_bytes: u64) -> Result<Option<Vec<u8>>, OutputError> {
    let opened = match active_root() {
        Some(root) => {
            let rel = root.relative(path)?;
            let mut options = cap_std::fs::OpenOptions::new();
            options.read(true);
            #[cfg(unix)]
            cap_std::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
            root.dir
                .open_with(rel, &options)
                .map(|f| f.into_std())
                .map_err(|e| {
                    if root.leads_outside(rel) {
                        io::Error::other("outside of the filesystem")
                    } else {
                        e
                    }
                })
        }
        None => {
            let mut options = fs::OpenOptions::new();
            options.read(true);
            #[cfg(unix)]
            std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
            options.open(path)
        }
    };
    let file = match opened {
        Ok(file) => file,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) if e.to_string().contains("outside of the filesystem") => {
            return Err(OutputError::Outside {
                path: path.to_path_buf(),
                root: active_root().map(|r| r.path.clone()).unwrap_or_default(),
            })
        }
        Err(e) => return Err(OutputError::io("open", path, e)),
    };
    let meta = file
        .metadata()
        .map_err(|e| OutputError::io("inspect", path, e))?;
    let refused = |why: String| OutputError::io("read", path, io::Error::other(why));
    if !meta.is_file() {
        return Err(refused("not a regular file".into()));
    }
    let too_large = |size: u64| {
        refused(format!(
            "{} is larger than the {} it may hold",
            crate::budget::format_bytes(size as f64),
            crate::budget::format_bytes(limit_bytes as f64)
        ))
    };
    if meta.len() > limit_bytes {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    io::Read::take(file, limit_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| OutputError::io("read", path, e))?;
    if bytes.len() as u64 > limit_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(Some(bytes))
}

/// Age past which a temporary file whose lock is free is a dead writer's: a writer writes its
/// bytes in one go and renames the file at once (seconds at most), so an hour-old temporary
/// file is one no writer finishes.
const STALE_AGE: Duration = Duration::from_secs(3600);

/// A directory that whole files are written into: a path on the host's file system, or an
/// output root's open directory (see [`super::OutputRoot`]). Names are single components.
pub(super) trait Directory {
    /// The names of the entries.
    fn names(&self) -> Vec<String>;
    /// The age of `name` when it is a regular file (not a symlink, FIFO or directory).
    fn regular_file_age(&self, name: &Path) -> Option<Duration>;
    /// Opens `name` for reading and writing, created exclusively when `create_new`.
    fn open(&self, name: &Path, create_new: bool) -> io::Result<fs::File>;
    fn remove(&self, name: &Path) -> io::Result<()>;
    fn rename(&self, from: &Path, to: &Path) -> io::Result<()>;
}

/// Flags of every open of a temporary file: never through a symlink, never blocking (a FIFO
/// in its place must not hang the writer).
#[cfg(unix)]
const OPEN_FLAGS: i32 = libc::O_NOFOLLOW | libc::O_NONBLOCK;

impl Directory for Path {
    fn names(&self) -> Vec<String> {
        fs::read_dir(self)
            .into_iter()
            .flatten()
            .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect()
    }
    fn regular_file_age(&self, name: &Path) -> Option<Duration> {
        let meta = fs::symlink_metadata(self.join(name)).ok()?;
        meta.is_file()
            .then(|| meta.modified().ok()?.elapsed().ok())
            .flatten()
    }
    fn open(&self, name: &Path, create_new: bool) -> io::Result<fs::File> {
        let mut options = fs::OpenOptions::new();
        options.read(true).write(true).create_new(create_new);
        #[cfg(unix)]
        std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, OPEN_FLAGS);
        options.open(self.join(name))
    }
    fn remove(&self, name: &Path) -> io::Result<()> {
        fs::remove_file(self.join(name))
    }
    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        fs::rename(self.join(from), self.join(to))
    }
}

impl Directory for cap_std::fs::Dir {
    fn names(&self) -> Vec<String> {
        self.entries()
            .into_iter()
            .flatten()
            .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect()
    }
    fn regular_file_age(&self, name: &Path) -> Option<Duration> {
        let meta = self.symlink_metadata(name).ok()?;
        meta.is_file()
            .then(|| meta.modified().ok()?.into_std().elapsed().ok())
            .flatten()
    }
    fn open(&self, name: &Path, create_new: bool) -> io::Result<fs::File> {
        let mut options = cap_std::fs::OpenOptions::new();
        options.read(true).write(true).create_new(create_new);
        #[cfg(unix)]
        cap_std::fs::OpenOptionsExt::custom_flags(&mut options, OPEN_FLAGS);
        self.open_with(name, &options).map(|f| f.into_std())
    }
    fn remove(&self, name: &Path) -> io::Result<()> {
        self.remove_file(name)
    }
    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        cap_std::fs::Dir::rename(self, from, self, to)
    }
}

/// The parts of a temporary name of `target` around its random middle: `.stem.tmp-` and
/// `.ext` (or "").
fn temp_parts(path: &Path) -> (String, String) {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (format!(".{stem}.tmp-"), ext)
}

/// A temporary sibling name of `target` that keeps its extension and cannot be guessed:
/// `.stem.tmp-<16 random hex digits>.ext`.
pub(super) fn temp_name(target: &Path) -> String {
    let (prefix, ext) = temp_parts(target);
    format!("{prefix}{:016x}{ext}", rand::random::<u64>())
}

/// Removes the temporary siblings of `target` that their writers will never finish: hidden
/// names `.stem.tmp-<middle>.ext` of regular files older than [`STALE_AGE`] whose lock no
/// process holds. Every writer holds an exclusive lock on its temporary file until it is
/// renamed ([`write_whole`]); the lock is released when a process dies, on any host whose
/// file system passes locks on (local, NFS), and the age protects a live writer where locks
/// are local only (a shared file system mounted with local locks).
pub(super) fn remove_stale_temps(dir: &(impl Directory + ?Sized), target: &Path) {
    let (prefix, ext) = temp_parts(target);
    for name in dir.names() {
        let Some(middle) = name
            .strip_prefix(&prefix)
            .and_then(|m| m.strip_suffix(&ext))
        else {
            continue;
        };
        let plausible =
            !middle.is_empty() && middle.bytes().all(|b| b.is_ascii_hexdigit() || b == b'-');
        let old = || {
            dir.regular_file_age(Path::new(&name))
                .is_some_and(|a| a > STALE_AGE)
        };
        if !(plausible && old()) {
            continue;
        }
        let Ok(file) = dir.open(Path::new(&name), false) else {
            continue;
        };
        if file.try_lock().is_ok() {
            let _ = dir.remove(Path::new(&name));
        }
    }
}

/// Writes `bytes` whole to `name` in `dir`: first to a temporary sibling with a random name,
/// created exclusively (`O_CREAT | O_EXCL | O_NOFOLLOW`: an existing file or a symlink planted
/// under that name is never opened, so nothing outside is overwritten) and locked (without
/// waiting) while it is written, then renamed over `name`. Stale temporary files of `name` are removed first.
pub(super) fn write_whole(
    dir: &(impl Directory + ?Sized),
    name: &Path,
    bytes: &[u8],
) -> io::Result<()> {
    remove_stale_temps(dir, name);
    let tmp = temp_name(name);
    let tmp = Path::new(&tmp);
    let file = dir.open(tmp, true)?;
    // A brand-new file: nobody contends for its lock unless a stranger took it, and a file
    // system without locks (Lustre with noflock) leaves only the age rule; neither may block
    // or fail the write.
    let _ = file.try_lock();
    let written = (&file)
        .write_all(bytes)
        .and_then(|()| dir.rename(tmp, name));
    if written.is_err() {
        let _ = dir.remove(tmp);
    }
    written
}

/// Writes `bytes` to `path` atomically (`write_whole`): parent directories are created, the
/// bytes go to a temporary file in the same directory, which is then renamed over the target
/// (replacing an existing file, or a symlink, never written through). No fsync is done:
/// outputs favour speed over durability across a power cut, but are never seen half-written.
/// Stale temporary files of the same target are removed first (`remove_stale_temps`).
///
/// While an [`OutputRoot`] is active on this thread ([`OutputRoot::within`]), `path` must lie
/// under it and the write goes through the root's open directory: a symlink leading out of
/// it, or a path outside it, is refused with [`OutputError::Outside`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    if let Some(root) = active_root() {
        return root.write_atomic(path, bytes);
    }
    ensure_parent_dir(path)?;
    let name = path
        .file_name()
        .ok_or_else(|| OutputError::data(path, "no file name"))?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    write_whole(dir, Path::new(name), bytes).map_err(|e| OutputError::io("write", path, e))
}
