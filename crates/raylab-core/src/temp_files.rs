//! Temporary files raylab is writing, so an interrupted program can remove them.
//!
//! Images and scene files are written under a hidden temporary name beside the destination and
//! renamed into place ([`crate::film::write_atomically`]). A program stopped by Ctrl+C or
//! `kill` in between would leave that `.NAME.PID.tmp` behind: the command line's signal
//! handler calls [`remove_all`] before it exits.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

static WRITING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Keeps `path` on the list while it lives.
#[must_use = "the path is forgotten when the guard is dropped"]
pub struct Registered(PathBuf);

/// Puts `path` on the list of files to remove if the program is interrupted.
pub fn register(path: &Path) -> Registered {
    let mut list = WRITING.lock().unwrap_or_else(PoisonError::into_inner);
    list.push(path.to_path_buf());
    Registered(path.to_path_buf())
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut list = WRITING.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(i) = list.iter().position(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Removes every file on the list (for a signal handler, just before the program exits).
pub fn remove_all() {
    let list = WRITING.lock().unwrap_or_else(PoisonError::into_inner);
    for path in list.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// The files on the list now.
pub fn registered() -> Vec<PathBuf> {
    WRITING
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .clone()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_registered_file_is_removed_by_remove_all_and_forgotten_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join(".a.tmp"), dir.path().join(".b.tmp"));
        std::fs::write(&a, "a").unwrap();
        std::fs::write(&b, "b").unwrap();
        let guard_a = register(&a);
        {
            let _guard_b = register(&b);
            assert!(registered().contains(&b));
        }
        assert!(!registered().contains(&b), "forgotten when dropped");
        remove_all();
        assert!(!a.exists(), "removed");
        assert!(b.exists(), "no longer listed, so left alone");
        drop(guard_a);
        assert!(!registered().contains(&a));
    }
}
