//! Temporary files raylab is writing, so an interrupted program can remove them.
//!
//! Images and scene files are written to a temporary file beside the destination and renamed
//! into place ([`crate::transport::film::write_atomically`]). Its name is `.NAME.XXXXXX.tmp`, `XXXXXX`
//! random (made by the `tempfile` crate, which creates the file exclusively and never through
//! a symbolic link). A program stopped by a signal in between would leave it behind: the
//! command line's signal handler calls [`remove_all`] before it exits.
//!
//! A [`Registry`] is a list of such files; the program's own is [`GLOBAL`], which the free
//! functions use. A test that removes everything on a list makes a registry of its own, so it
//! never removes a file another test is writing.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

/// A list of files being written.
#[derive(Debug, Default)]
pub struct Registry {
    writing: Mutex<Vec<PathBuf>>,
}

/// The program's list: what [`crate::transport::film::write_atomically`] registers and the signal
/// handler removes.
pub static GLOBAL: Registry = Registry::new();

/// Keeps a path on its registry's list while it lives.
#[must_use = "the path is forgotten when the guard is dropped"]
pub struct Registered<'a> {
    registry: &'a Registry,
    path: PathBuf,
}

impl Registry {
    /// An empty list.
    pub const fn new() -> Self {
        Self {
            writing: Mutex::new(Vec::new()),
        }
    }

    fn list(&self) -> std::sync::MutexGuard<'_, Vec<PathBuf>> {
        self.writing.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Puts `path` on the list of files to remove if the program is interrupted.
    pub fn register(&self, path: &Path) -> Registered<'_> {
        self.list().push(path.to_path_buf());
        Registered {
            registry: self,
            path: path.to_path_buf(),
        }
    }

    /// Removes every file on the list (for a signal handler, just before the program exits).
    pub fn remove_all(&self) {
        for path in self.list().iter() {
            let _ = std::fs::remove_file(path);
        }
    }

    /// The files on the list now.
    pub fn registered(&self) -> Vec<PathBuf> {
        self.list().clone()
    }
}

impl Drop for Registered<'_> {
    fn drop(&mut self) {
        let mut list = self.registry.list();
        if let Some(i) = list.iter().position(|p| *p == self.path) {
            list.swap_remove(i);
        }
    }
}

/// Puts `path` on the program's list ([`GLOBAL`]).
pub fn register(path: &Path) -> Registered<'static> {
    GLOBAL.register(path)
}

/// Removes every file on the program's list ([`GLOBAL`]).
pub fn remove_all() {
    GLOBAL.remove_all();
}

/// The files on the program's list now.
pub fn registered() -> Vec<PathBuf> {
    GLOBAL.registered()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_registered_file_is_removed_by_remove_all_and_forgotten_when_dropped() {
        // A registry of its own: the program's list holds the files other tests are writing.
        let registry = Registry::new();
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join(".a.tmp"), dir.path().join(".b.tmp"));
        std::fs::write(&a, "a").unwrap();
        std::fs::write(&b, "b").unwrap();
        let guard_a = registry.register(&a);
        {
            let _guard_b = registry.register(&b);
            assert_eq!(registry.registered(), [a.clone(), b.clone()]);
        }
        assert_eq!(
            registry.registered(),
            std::slice::from_ref(&a),
            "b forgotten when dropped"
        );
        assert!(
            !GLOBAL.registered().contains(&a),
            "not on the program's list"
        );
        registry.remove_all();
        assert!(!a.exists(), "removed");
        assert!(b.exists(), "no longer listed, so left alone");
        drop(guard_a);
        assert!(registry.registered().is_empty());
    }
}
