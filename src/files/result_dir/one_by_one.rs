//! Putting a run in place by renaming its files in one by one, as one transaction: checked before
//! anything moves, undone when a rename fails ([`Moves`]), and rolled back by the next run when
//! the process was killed midway ([`roll_back`]).

use super::{Plan, ResultDir};
use crate::files::manifest::{Manifest, is_plain_name};
use crate::files::{FileError, fail, sync};
use std::path::{Path, PathBuf};

impl ResultDir {
    /// Renames the run's files in one by one as one transaction (see the module
    /// documentation): everything is checked before anything moves, and a failed rename puts
    /// back what moved before it.
    pub(super) fn install_one_by_one(
        &self,
        staging: &Path,
        manifest: &Manifest,
        plan: &Plan,
        rename: &mut Rename<'_>,
    ) -> Result<(), FileError> {
        let target = &self.target;
        let stale = &plan.stale;
        let backup = staging.join(".previous");
        std::fs::create_dir(&backup).map_err(fail(target, "cannot write results"))?;
        let mut moves = Moves::default();
        let result = (|| {
            // The earlier manifest first: while files change, the directory claims no run.
            let old_manifest = target.join("manifest.json");
            if old_manifest.exists() {
                moves.mv(rename, &old_manifest, &backup.join("manifest.json"))?;
            }
            for e in &manifest.files {
                let (from, to) = (staging.join(&e.file), target.join(&e.file));
                if std::fs::symlink_metadata(&to).is_ok() {
                    moves.mv(rename, &to, &backup.join(&e.file))?;
                }
                moves.mv(rename, &from, &to)?;
            }
            for f in stale {
                moves.mv(rename, &target.join(f), &backup.join(f))?;
            }
            moves.mv(rename, &staging.join("manifest.json"), &old_manifest)
        })();
        if let Err((path, e)) = result {
            moves.undo();
            return Err(FileError {
                path: path.display().to_string(),
                what: "cannot rename into place (the earlier result is left as it was)",
                source: e,
            });
        }
        sync(target);
        Ok(())
    }
}

/// One rename of a file: `rename(from, to)`.
pub(super) type Rename<'a> = dyn FnMut(&Path, &Path) -> std::io::Result<()> + 'a;

/// The renames of a transaction, to undo in reverse order.
#[derive(Default)]
struct Moves(Vec<(PathBuf, PathBuf)>);

impl Moves {
    fn mv(
        &mut self,
        rename: &mut Rename<'_>,
        from: &Path,
        to: &Path,
    ) -> Result<(), (PathBuf, std::io::Error)> {
        rename(from, to).map_err(|e| (to.to_path_buf(), e))?;
        self.0.push((from.to_path_buf(), to.to_path_buf()));
        Ok(())
    }

    /// Puts back every file moved (best effort: a rename back within one directory tree on one
    /// file system).
    fn undo(self) {
        for (from, to) in self.0.into_iter().rev() {
            let _ = std::fs::rename(&to, &from);
        }
    }
}

/// Undoes the one-by-one install ([`ResultDir::install_one_by_one`]) of a killed run staged at
/// `staging` into `target`, where it was cut before its manifest went in: the run's files
/// that reached the target are removed and the earlier ones (kept in `staging/.previous`) put
/// back. A staging directory without that backup never started an install, and one without
/// its manifest finished it: nothing to undo.
pub(super) fn roll_back(staging: &Path, target: &Path) {
    let backup = staging.join(".previous");
    let Some(new) = Manifest::read(staging) else {
        return;
    };
    if !backup.is_dir() {
        return;
    }
    for e in &new.files {
        // Gone from the staging directory: it was renamed into the target.
        if is_plain_name(&e.file) && std::fs::symlink_metadata(staging.join(&e.file)).is_err() {
            let _ = std::fs::remove_file(target.join(&e.file));
        }
    }
    if let Ok(entries) = std::fs::read_dir(&backup) {
        for e in entries.flatten() {
            let _ = std::fs::rename(e.path(), target.join(e.file_name()));
        }
    }
    sync(target);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory's entries with their bytes, and the names beside it ([`snapshot`]).
    type Snapshot = (Vec<(String, Vec<u8>)>, Vec<String>);

    /// Every entry of `dir` with its bytes (directories as `/`), and what lies beside it.
    fn snapshot(dir: &Path) -> Snapshot {
        let mut inside: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let name = e.file_name().to_string_lossy().into_owned();
                let kind = e.file_type().unwrap();
                let bytes = if kind.is_dir() {
                    b"/".to_vec()
                } else if kind.is_file() {
                    std::fs::read(e.path()).unwrap()
                } else {
                    b"?".to_vec()
                };
                (name, bytes)
            })
            .collect();
        inside.sort();
        let mut beside: Vec<String> = std::fs::read_dir(dir.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        beside.sort();
        (inside, beside)
    }

    /// An earlier run in `target` with a file of the user's beside it and a socket (which
    /// cannot be linked, so that the next run is renamed in one by one), and the files of the
    /// next run.
    fn earlier_run_and_the_next(target: &Path) -> Vec<(&'static str, &'static [u8])> {
        let mut r = ResultDir::create(target).unwrap();
        for (name, bytes) in [
            ("a.csv", b"old a" as &[u8]),
            ("b.csv", b"old b"),
            ("gone.svg", b"old"),
        ] {
            r.write(name, bytes).unwrap();
        }
        r.commit(false).unwrap();
        std::fs::write(target.join("notes.txt"), b"mine").unwrap();
        std::os::unix::net::UnixListener::bind(target.join("socket")).unwrap();
        vec![
            ("a.csv", b"new a"),
            ("b.csv", b"new b"),
            ("c.csv", b"new c"),
        ]
    }

    /// An earlier run in `target` ([`earlier_run_and_the_next`]), and the next run staged,
    /// ready to commit, with the target's entries before it.
    fn next_run_staged(target: &Path) -> (ResultDir, Snapshot) {
        let next = earlier_run_and_the_next(target);
        let before = snapshot(target);
        let mut r = ResultDir::create(target).unwrap();
        for (name, bytes) in &next {
            r.write(name, bytes).unwrap();
        }
        (r, before)
    }

    #[test]
    fn a_directory_where_any_result_file_goes_is_refused_before_anything_moves() {
        let names = ["a.csv", "b.csv", "c.csv", "manifest.json"];
        for blocked in names {
            let root = tempfile::tempdir().unwrap();
            let target = root.path().join("results");
            let next = earlier_run_and_the_next(&target);
            let _ = std::fs::remove_file(target.join(blocked));
            std::fs::create_dir(target.join(blocked)).unwrap();
            let before = snapshot(&target);
            let mut r = ResultDir::create(&target).unwrap();
            for (name, bytes) in &next {
                r.write(name, bytes).unwrap();
            }
            let e = r.commit(false).unwrap_err();
            assert!(e.to_string().contains(blocked), "{blocked}: {e}");
            assert_eq!(snapshot(&target), before, "{blocked}: the target changed");
        }
    }

    #[test]
    fn a_rename_failing_at_any_step_leaves_the_earlier_run_whole() {
        let run = |fail_at: Option<usize>| {
            let root = tempfile::tempdir().unwrap();
            let target = root.path().join("results");
            let (r, before) = next_run_staged(&target);
            let mut calls = 0;
            let result = r.commit_with(false, &mut |a: &Path, b: &Path| {
                calls += 1;
                if Some(calls - 1) == fail_at {
                    return Err(std::io::Error::other("injected"));
                }
                std::fs::rename(a, b)
            });
            (result, calls, before, snapshot(&target), target, root)
        };
        let (ok, renames, _, _, target, _root) = run(None);
        ok.unwrap();
        Manifest::read(&target).unwrap().verify(&target).unwrap();
        assert_eq!(std::fs::read(target.join("notes.txt")).unwrap(), b"mine");
        assert!(!target.join("gone.svg").exists());
        assert!(renames >= 7, "{renames} renames");
        for k in 0..renames {
            let (result, _, before, after, target, _root) = run(Some(k));
            assert!(result.is_err(), "step {k}");
            assert_eq!(
                after, before,
                "a rename failing at step {k} changed the target"
            );
            Manifest::read(&target).unwrap().verify(&target).unwrap();
        }
    }

    #[test]
    fn a_run_killed_at_any_rename_is_rolled_back_by_the_next() {
        // A panic in the rename stands for a kill: nothing after it runs, nothing is undone,
        // the staging directory stays, its lock is released.
        let kill_at = |k: Option<usize>| {
            let root = tempfile::tempdir().unwrap();
            let target = root.path().join("results");
            let (r, before) = next_run_staged(&target);
            let mut calls = 0;
            let killed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                r.commit_with(false, &mut |a: &Path, b: &Path| {
                    calls += 1;
                    if Some(calls - 1) == k {
                        panic!("killed");
                    }
                    std::fs::rename(a, b)
                })
            }))
            .is_err();
            // The next run into the same place, before it writes anything.
            drop(ResultDir::create(&target).unwrap());
            (killed, calls, before, snapshot(&target), target, root)
        };
        let (killed, renames, ..) = kill_at(None);
        assert!(!killed);
        for k in 0..renames {
            let (killed, _, before, after, target, _root) = kill_at(Some(k));
            assert!(killed, "step {k}");
            assert_eq!(after.0, before.0, "killed at rename {k}: not rolled back");
            assert_eq!(after.1, before.1, "killed at rename {k}: leftovers beside");
            Manifest::read(&target).unwrap().verify(&target).unwrap();
        }
    }
}
