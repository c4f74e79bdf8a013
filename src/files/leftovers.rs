//! What killed runs left: their staging files and directories (`.NAME.XXXXXX.partial`), which
//! a live run holds locked and the next run writing to the same place removes (rolling back a
//! result directory cut midway first).

use super::truncate;
use std::fs::File;
use std::path::Path;

/// Marks a staging file or directory as in use (an exclusive advisory lock, released when
/// the process ends however it ends), so that other runs' cleanup leaves it alone. Best
/// effort: where the file system has no locks, nothing is marked, and nothing unmarked is
/// ever removed by another run either.
pub(super) fn mark_in_use(f: &File) {
    let _ = f.try_lock();
}

/// Removes what killed runs left in `dir` for the target named `name`: staging files and
/// directories `.NAME.XXXXXX.partial` (`tempfile`'s six random characters) that no live run
/// holds locked. A staging directory is first handed to `roll_back` (a result directory's
/// staging directory, killed while its files were renamed in one by one, puts the earlier
/// run back in its target), so that the target holds the earlier run again.
pub(super) fn remove_leftovers(dir: &Path, name: &str, roll_back: Option<&dyn Fn(&Path)>) {
    let prefix = format!(".{}.", truncate(name, 60));
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let entry = e.file_name();
        let Some(middle) = entry
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|n| n.strip_suffix(".partial"))
        else {
            continue;
        };
        if middle.len() != 6 || !middle.chars().all(|c| c.is_ascii_alphanumeric()) {
            continue;
        }
        let path = e.path();
        let Ok(kind) = e.file_type() else { continue };
        let opened = if kind.is_dir() {
            File::open(&path)
        } else if kind.is_file() {
            std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(&path)
        } else {
            continue;
        };
        // Held by a live run (or a file system without locks): left alone.
        let Ok(f) = opened else { continue };
        if f.try_lock().is_err() {
            continue;
        }
        if let (true, Some(roll_back)) = (kind.is_dir(), roll_back) {
            roll_back(&path);
        }
        let _ = if kind.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
    }
}

#[cfg(test)]
mod tests {
    use crate::files::{AtomicFile, ResultDir, write_atomically};

    #[test]
    fn leftovers_of_killed_runs_are_removed_and_live_ones_kept() {
        let root = tempfile::tempdir().unwrap();
        let d = root.path();
        let dead_file = d.join(".x.csv.Ab3dE9.partial");
        let dead_dir = d.join(".results.Zz0aQ1.partial");
        let live_file = d.join(".x.csv.LiVe01.partial");
        let mine = d.join(".x.csv.partial"); // not a staging name
        std::fs::write(&dead_file, b"cut").unwrap();
        std::fs::create_dir(&dead_dir).unwrap();
        std::fs::write(dead_dir.join("tolerance.csv"), b"cut").unwrap();
        std::fs::write(&live_file, b"being written").unwrap();
        std::fs::write(&mine, b"keep").unwrap();
        let held = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&live_file)
            .unwrap();
        held.lock().unwrap();
        write_atomically(&d.join("x.csv"), b"new").unwrap();
        ResultDir::create(&d.join("results"))
            .unwrap()
            .commit(false)
            .unwrap();
        assert!(!dead_file.exists() && !dead_dir.exists());
        assert!(live_file.exists() && mine.exists());
        // A staging file of this process is held as long as it is being written.
        let f = AtomicFile::create(&d.join("y.csv")).unwrap();
        write_atomically(&d.join("y.csv"), b"other").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(d.join("y.csv")).unwrap(), b"");
    }
}
