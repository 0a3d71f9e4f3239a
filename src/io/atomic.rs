//! Atomic writing: a temporary sibling file renamed over the target, stale temporaries of
//! killed writers removed, and reads and writes confined to an active [`OutputRoot`].

use super::root::active_root;
use super::OutputError;
#[cfg(doc)]
use super::OutputRoot;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Creates the parent directory of `path` (and its ancestors) if missing.
pub fn ensure_parent_dir(path: &Path) -> Result<(), OutputError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            fs::create_dir_all(dir).map_err(|e| OutputError::io("create directory", dir, e))
        }
        _ => Ok(()),
    }
}

/// Reads `path` whole, `Ok(None)` when it does not exist. While an [`OutputRoot`] is active
/// on this thread, `path` must lie under it and is read beneath its open directory (a
/// symlink leading out is refused), as writes are.
pub fn read_existing(path: &Path) -> Result<Option<Vec<u8>>, OutputError> {
    let read = match active_root() {
        Some(root) => {
            let rel = root.relative(path)?;
            root.dir.read(rel).map_err(|e| {
                if root.leads_outside(rel) {
                    std::io::Error::other("outside of the filesystem")
                } else {
                    e
                }
            })
        }
        None => fs::read(path),
    };
    match read {
        Ok(bytes) => Ok(Some(bytes)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) if e.to_string().contains("outside of the filesystem") => {
            Err(OutputError::Outside {
                path: path.to_path_buf(),
                root: active_root().map(|r| r.path.clone()).unwrap_or_default(),
            })
        }
        Err(e) => Err(OutputError::io("read", path, e)),
    }
}

/// A unique temporary sibling of `path` that keeps its extension:
/// `dir/.name.tmp-<pid>-<counter>.ext`.
pub fn temp_sibling(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let (prefix, ext) = temp_parts(path);
    path.with_file_name(format!("{prefix}{}-{n}{ext}", std::process::id()))
}

/// The parts of a temporary name around `<pid>-<counter>`: `.stem.tmp-` and `.ext` (or "").
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

/// Removes the temporary siblings of `target` left by writers that no longer run (a killed
/// process): names `.stem.tmp-<pid>-<n>.ext` whose pid is not ours and has no `/proc` entry.
/// Only on Linux, where a dead pid can be told from a live one; elsewhere they are ignored
/// (hidden names, never read).
pub(super) fn remove_stale_temps<I: Iterator<Item = String>>(
    names: impl FnOnce() -> I,
    target: &Path,
    mut remove: impl FnMut(&str),
) {
    if !cfg!(target_os = "linux") {
        return;
    }
    let (prefix, ext) = temp_parts(target);
    for name in names() {
        let Some(middle) = name
            .strip_prefix(&prefix)
            .and_then(|m| m.strip_suffix(&ext))
        else {
            continue;
        };
        let Some((pid, n)) = middle.split_once('-') else {
            continue;
        };
        let (Ok(pid), true) = (pid.parse::<u32>(), n.bytes().all(|b| b.is_ascii_digit())) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            remove(&name);
        }
    }
}

/// Renames the finished temporary file `tmp` over `path`; removes `tmp` if that fails.
pub fn commit_temp(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    fs::rename(tmp, path).map_err(|e| {
        let _ = fs::remove_file(tmp);
        OutputError::io("rename temporary file onto", path, e)
    })
}

/// Writes `bytes` to `path` atomically: parent directories are created, the bytes go to
/// a temporary file in the same directory, which is then renamed over the target
/// (replacing an existing file). No fsync is done: outputs favour speed over
/// durability across a power cut, but are never seen half-written. Temporary files of
/// the same target left by a killed writer are removed first.
///
/// While an [`OutputRoot`] is active on this thread ([`OutputRoot::within`]), `path` must lie
/// under it and the write goes through the root's open directory: a symlink leading out of
/// it, or a path outside it, is refused with [`OutputError::Outside`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    if let Some(root) = active_root() {
        return root.write_atomic(path, bytes);
    }
    ensure_parent_dir(path)?;
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        remove_stale_temps(
            || {
                fs::read_dir(dir)
                    .ok()
                    .into_iter()
                    .flatten()
                    .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            },
            path,
            |stale| {
                let _ = fs::remove_file(dir.join(stale));
            },
        );
    }
    let tmp = temp_sibling(path);
    let written = fs::File::create(&tmp).and_then(|mut f| f.write_all(bytes));
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(OutputError::io("write", &tmp, e));
    }
    commit_temp(&tmp, path)
}
