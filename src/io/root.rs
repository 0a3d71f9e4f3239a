//! The output root: a directory opened once, beneath which every write of a script goes.

use super::atomic::write_whole;
use super::OutputError;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// An output directory opened once. Writes through it are resolved beneath it by cap-std's
/// openat-style lookups (every component, symlinks included, is followed relative to the open
/// directory handle), so a symlink that leads out of it is refused at the moment of use: no
/// check-then-use race, even when a link is swapped while a script runs.
#[derive(Clone, Debug)]
pub struct OutputRoot {
    pub(super) dir: Arc<cap_std::fs::Dir>,
    pub(super) path: PathBuf,
}

impl OutputRoot {
    /// Creates `path` if missing and opens it as the root of every write made within it.
    pub fn open(path: &Path) -> Result<OutputRoot, OutputError> {
        fs::create_dir_all(path).map_err(|e| OutputError::io("create directory", path, e))?;
        let dir = cap_std::fs::Dir::open_ambient_dir(path, cap_std::ambient_authority())
            .map_err(|e| OutputError::io("open output directory", path, e))?;
        Ok(OutputRoot {
            dir: Arc::new(dir),
            path: path.to_path_buf(),
        })
    }

    /// The directory as given when opened.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Runs `f` with this root active on the current thread: every path a writer of this
    /// crate is given must then lie under [`OutputRoot::path`] and is written beneath the open
    /// directory (see [`write_atomic`]). The previous root is restored afterwards, also on panic.
    pub fn within<T>(&self, f: impl FnOnce() -> T) -> T {
        struct Restore(Option<OutputRoot>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let old = self.0.take();
                ACTIVE_ROOT.with(|r| *r.borrow_mut() = old);
            }
        }
        let old = ACTIVE_ROOT.with(|r| r.borrow_mut().replace(self.clone()));
        let _restore = Restore(old);
        f()
    }

    /// `path` relative to the root, or an error when it does not lie under it.
    pub(super) fn relative<'a>(&self, path: &'a Path) -> Result<&'a Path, OutputError> {
        path.strip_prefix(&self.path)
            .ok()
            .filter(|rel| {
                rel.components().all(|c| {
                    matches!(
                        c,
                        std::path::Component::Normal(_) | std::path::Component::CurDir
                    )
                })
            })
            .ok_or_else(|| OutputError::Outside {
                path: path.to_path_buf(),
                root: self.path.clone(),
            })
    }

    /// True when the longest existing prefix of `rel` resolves (symlinks followed) outside the
    /// root. Used only to word an error that cap-std already raised; the refusal itself does
    /// not depend on this check.
    pub(super) fn leads_outside(&self, rel: &Path) -> bool {
        let Ok(root) = fs::canonicalize(&self.path) else {
            return false;
        };
        rel.ancestors()
            .filter(|a| !a.as_os_str().is_empty())
            .find_map(|a| fs::canonicalize(self.path.join(a)).ok())
            .is_some_and(|real| !real.starts_with(&root))
    }

    /// Writes `bytes` to `path` (under the root) atomically, beneath the open directory.
    pub(super) fn write_atomic(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        let rel = self.relative(path)?;
        let escape = |e: std::io::Error, op: &'static str, at: &Path| {
            if e.to_string().contains("outside of the filesystem") || self.leads_outside(rel) {
                OutputError::Outside {
                    path: path.to_path_buf(),
                    root: self.path.clone(),
                }
            } else {
                OutputError::io(op, at, e)
            }
        };
        let name = rel
            .file_name()
            .ok_or_else(|| OutputError::data(path, "no file name"))?;
        let parent = rel.parent().filter(|p| !p.as_os_str().is_empty());
        let dir = match parent {
            Some(p) => {
                let full = self.path.join(p);
                self.dir
                    .create_dir_all(p)
                    .map_err(|e| escape(e, "create directory", &full))?;
                self.dir
                    .open_dir(p)
                    .map_err(|e| escape(e, "open directory", &full))?
            }
            None => self
                .dir
                .try_clone()
                .map_err(|e| escape(e, "open directory", &self.path))?,
        };
        write_whole(&dir, Path::new(name), bytes).map_err(|e| escape(e, "write", path))
    }
}

thread_local! {
    /// The output root active on this thread (see [`OutputRoot::within`]).
    static ACTIVE_ROOT: std::cell::RefCell<Option<OutputRoot>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with no output root active on the current thread (writes are then not confined),
/// the previous one restored afterwards, also on panic.
pub fn without_root<T>(f: impl FnOnce() -> T) -> T {
    struct Restore(Option<OutputRoot>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let old = self.0.take();
            ACTIVE_ROOT.with(|r| *r.borrow_mut() = old);
        }
    }
    let _restore = Restore(ACTIVE_ROOT.with(|r| r.borrow_mut().take()));
    f()
}

/// The output root active on this thread, if any.
pub fn active_root() -> Option<OutputRoot> {
    ACTIVE_ROOT.with(|r| r.borrow().clone())
}
