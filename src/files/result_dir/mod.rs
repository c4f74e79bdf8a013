//! Result directories replaced as a whole: staged beside the target (or inside it), committed
//! with their manifest last, and put in place in one atomic exchange where the system allows,
//! else renamed in one by one as a transaction. The two ways of putting a run in place are
//! submodules (`exchange`, `one_by_one`); this module decides between them.

mod exchange;
mod one_by_one;

use super::inputs::{Identity, Inputs};
use super::leftovers::{mark_in_use, remove_leftovers};
use super::manifest::{
    MANIFEST_FORMAT, Manifest, ManifestEntry, is_plain_name, listed, sha256_hex,
};
use super::{FileError, directory_of, fail, invalid, sync, sync_parent, truncate, write_target};
use exchange::exchange;
use one_by_one::{Rename, roll_back};
use std::fs::File;
use std::path::{Path, PathBuf};

/// Where a result directory is staged.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Staging {
    /// Beside the target, in its parent: the whole directory can be renamed or exchanged.
    Beside,
    /// Inside the target (a mount point, or a parent that is not writable): the files are
    /// renamed in one by one, each on the target's own file system.
    Inside,
}

/// The name of the staging directory inside a target.
const INSIDE: &str = "modaltol-staging";

/// A result directory being written: files go to a staging directory beside the target (or
/// inside it, see the module documentation); [`ResultDir::commit`] puts them in place.
/// Dropped without a commit, the staging directory is removed and the target is untouched.
pub struct ResultDir {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
    place: Staging,
    /// Holds the staging directory locked ([`mark_in_use`]).
    _lock: Option<File>,
    files: Vec<ManifestEntry>,
    inputs: Inputs,
}

impl ResultDir {
    /// Starts a result directory at `target` (through a symbolic link, to where it points),
    /// creating its parents. Fails now, before anything is computed, where the results cannot
    /// be written: a file stands at its name, or neither its parent nor the target itself
    /// takes a staging directory.
    pub fn create(target: &Path) -> Result<ResultDir, FileError> {
        let resolved = write_target(target);
        let parent = directory_of(&resolved).to_path_buf();
        std::fs::create_dir_all(&parent).map_err(fail(&parent, "cannot create the directory"))?;
        if resolved.exists() && !resolved.is_dir() {
            return Err(invalid(
                target,
                "cannot write results",
                "it exists and is not a directory".into(),
            ));
        }
        let name = resolved
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "results".into());
        let undo = |staging: &Path| roll_back(staging, &resolved);
        remove_leftovers(&parent, &name, Some(&undo));
        let exists = resolved.is_dir();
        if exists {
            remove_leftovers(&resolved, INSIDE, Some(&undo));
        }
        let stage = |dir: &Path, name: &str| {
            tempfile::Builder::new()
                .prefix(&format!(".{}.", truncate(name, 60)))
                .suffix(".partial")
                .tempdir_in(dir)
        };
        let (staging, place) = if exists && is_mount_point(&resolved, &parent) {
            (stage(&resolved, INSIDE), Staging::Inside)
        } else {
            match stage(&parent, &name) {
                Err(e) if exists && e.kind() != std::io::ErrorKind::NotFound => {
                    (stage(&resolved, INSIDE), Staging::Inside)
                }
                beside => (beside, Staging::Beside),
            }
        };
        let staging = staging.map_err(fail(target, "cannot create the results directory"))?;
        // Files renamed in one by one need a writable target: known now, not after the run.
        let one_by_one = place == Staging::Inside
            || (exists && !owned_by(&resolved, Manifest::read(&resolved).as_ref()));
        if one_by_one {
            use rustix::fs::{Access, access};
            access(&resolved, Access::WRITE_OK | Access::EXEC_OK)
                .map_err(|e| fail(target, "cannot write results")(e.into()))?;
        }
        let lock = File::open(staging.path()).ok();
        if let Some(f) = &lock {
            mark_in_use(f);
        }
        Ok(ResultDir {
            target: resolved,
            staging: Some(staging),
            place,
            _lock: lock,
            files: Vec::new(),
            inputs: Inputs::default(),
        })
    }

    /// The run's inputs, which the commit must not replace or remove ([`Inputs`]); the
    /// target itself must not be one. Refused now, before anything is computed: an input in
    /// the target that the run would replace (a name for which `writes` is true) or remove (a
    /// file of the earlier run). The commit checks again against the names actually written.
    pub fn protect(
        mut self,
        inputs: Inputs,
        writes: impl Fn(&str) -> bool,
    ) -> Result<ResultDir, FileError> {
        inputs.refuse_output(&self.target)?;
        let earlier = listed(Manifest::read(&self.target).as_ref());
        if let Ok(entries) = std::fs::read_dir(&self.target) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if writes(&name) || earlier.contains(&name) {
                    inputs.refuse_output(&e.path())?;
                }
            }
        }
        self.inputs = inputs;
        Ok(self)
    }

    fn staging(&self) -> &Path {
        self.staging.as_ref().expect("not committed").path()
    }

    /// Writes one file of the result (a plain name, no directories).
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<(), FileError> {
        let path = self.staging().join(name);
        std::fs::write(&path, bytes).map_err(fail(&self.target.join(name), "cannot write"))?;
        self.files.push(ManifestEntry {
            file: name.to_string(),
            bytes: bytes.len() as u64,
            sha256: sha256_hex(bytes),
        });
        Ok(())
    }

    /// Writes the manifest and puts the run in place of the target; returns where it went.
    /// A `partial` run never replaces a complete one: where the target holds a complete run,
    /// the partial one goes beside it (`TARGET.partial`, or `TARGET/partial` where the run is
    /// staged inside the target) and the complete one stays.
    pub fn commit(self, partial: bool) -> Result<PathBuf, FileError> {
        self.commit_with(partial, &mut |a, b| std::fs::rename(a, b))
    }

    /// [`ResultDir::commit`] with `rename` moving each file.
    fn commit_with(mut self, partial: bool, rename: &mut Rename<'_>) -> Result<PathBuf, FileError> {
        let manifest = Manifest {
            format: MANIFEST_FORMAT.into(),
            partial,
            files: std::mem::take(&mut self.files),
        };
        if partial && Manifest::read(&self.target).is_some_and(|m| !m.partial) {
            self.target = self.partial_place()?;
        }
        let staging = self.staging.take().expect("not committed").keep();
        let result = self.install(&staging, &manifest, rename);
        // Whatever happened, nothing of the staging directory stays behind.
        let _ = std::fs::remove_dir_all(&staging);
        result.map(|()| self.target.clone())
    }

    /// Where a partial run goes when the target holds a complete one: `TARGET.partial` beside
    /// it (on the same file system as the staging directory), or `TARGET/partial` where the run
    /// is staged inside the target.
    fn partial_place(&self) -> Result<PathBuf, FileError> {
        Ok(match self.place {
            Staging::Beside => {
                let mut name = self.target.file_name().unwrap_or_default().to_os_string();
                name.push(".partial");
                let place = self.target.with_file_name(name);
                if place.exists() && !place.is_dir() {
                    return Err(invalid(
                        &place,
                        "cannot write the partial result beside the complete one",
                        "a file stands at its name".into(),
                    ));
                }
                place
            }
            Staging::Inside => {
                let place = self.target.join("partial");
                std::fs::create_dir_all(&place)
                    .map_err(fail(&place, "cannot create the directory"))?;
                place
            }
        })
    }

    /// Puts the staged run in place; `rename` moves one file (a parameter so that tests can
    /// make any one of them fail).
    fn install(
        &self,
        staging: &Path,
        manifest: &Manifest,
        rename: &mut Rename<'_>,
    ) -> Result<(), FileError> {
        let text = serde_json::to_vec_pretty(manifest).expect("a manifest serialises");
        std::fs::write(staging.join("manifest.json"), &text)
            .map_err(fail(&self.target.join("manifest.json"), "cannot write"))?;
        for e in &manifest.files {
            sync(&staging.join(&e.file));
        }
        sync(&staging.join("manifest.json"));
        sync(staging);
        let target = &self.target;
        if self.place == Staging::Beside && !target.exists() {
            std::fs::rename(staging, target).map_err(fail(target, "cannot rename into place"))?;
            sync_parent(target);
            return Ok(());
        }
        let previous = Manifest::read(target);
        if self.place == Staging::Beside && owned_by(target, previous.as_ref()) {
            self.refuse_inputs_among(target, &listed(previous.as_ref()))?;
            if exchange(staging, target).is_ok() {
                // The old run is now at `staging`, removed by the caller.
                sync_parent(target);
                return Ok(());
            }
        }
        let plan = self.plan(manifest, previous.as_ref())?;
        if self.place == Staging::Beside && self.exchange_keeping(staging, &plan) {
            return Ok(());
        }
        self.install_one_by_one(staging, manifest, &plan, rename)
    }

    /// What replacing the target's content means: the run's files, the earlier run's files it
    /// does not write (removed), and the entries that stay (the user's own). Refuses, before
    /// anything moves, a directory where a result file goes and an input among the files
    /// replaced or removed.
    fn plan(&self, manifest: &Manifest, previous: Option<&Manifest>) -> Result<Plan, FileError> {
        let target = &self.target;
        let mut new: Vec<String> = manifest.files.iter().map(|e| e.file.clone()).collect();
        new.push("manifest.json".into());
        let is_file = |f: &String| {
            std::fs::symlink_metadata(target.join(f)).is_ok_and(|m| m.file_type().is_file())
        };
        // The earlier run's files this run does not write, removed (regular files only).
        let stale: Vec<String> = listed(previous)
            .into_iter()
            .filter(|f| !new.contains(f) && is_plain_name(f))
            .filter(is_file)
            .collect();
        for name in &new {
            if let Ok(m) = std::fs::symlink_metadata(target.join(name))
                && m.is_dir()
            {
                return Err(invalid(
                    &target.join(name),
                    "cannot write results",
                    "a directory stands where a result file goes; nothing was changed".into(),
                ));
            }
        }
        self.refuse_inputs_among(target, &new)?;
        self.refuse_inputs_among(target, &stale)?;
        let kept = std::fs::read_dir(target)
            .map(|entries| {
                entries
                    .flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| !new.contains(n) && !stale.contains(n))
                    .collect()
            })
            .unwrap_or_default();
        Ok(Plan { new, stale, kept })
    }

    /// Refuses to replace or remove `names` in `dir` where one of them is an input.
    fn refuse_inputs_among(&self, dir: &Path, names: &[String]) -> Result<(), FileError> {
        names
            .iter()
            .try_for_each(|n| self.inputs.refuse_output(&dir.join(n)))
    }
}

/// The entries of a target that a run replaces, removes and keeps ([`ResultDir::plan`]).
struct Plan {
    /// The run's files and its manifest.
    new: Vec<String>,
    /// The earlier run's files this run does not write.
    stale: Vec<String>,
    /// Everything else in the target: the user's own entries.
    kept: Vec<String>,
}

impl Drop for ResultDir {
    fn drop(&mut self) {
        if let Some(s) = self.staging.take() {
            let _ = s.close();
        }
    }
}

/// Does the directory hold nothing but an earlier run (the regular files its manifest lists,
/// the manifest) or nothing at all? Only then may it be replaced as a whole.
fn owned_by(dir: &Path, manifest: Option<&Manifest>) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    let names = listed(manifest);
    for e in entries {
        let Ok(e) = e else { return false };
        let name = e.file_name().to_string_lossy().into_owned();
        if !names.contains(&name) || !e.file_type().is_ok_and(|t| t.is_file()) {
            return false;
        }
    }
    true
}

/// Is `dir` the root of a mount (a container's volume, a bind mount), so that nothing can be
/// renamed into it from its `parent`? Linux says so (`STATX_ATTR_MOUNT_ROOT`, 5.8); elsewhere,
/// or on older kernels, a device other than the parent's says so.
fn is_mount_point(dir: &Path, parent: &Path) -> bool {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{AtFlags, CWD, StatxAttributes, StatxFlags, statx};
        if let Ok(r) = statx(CWD, dir, AtFlags::empty(), StatxFlags::empty())
            && r.stx_attributes_mask.contains(StatxAttributes::MOUNT_ROOT)
        {
            return r.stx_attributes.contains(StatxAttributes::MOUNT_ROOT);
        }
    }
    Identity::of(dir).map(|i| i.dev) != Identity::of(parent).map(|i| i.dev)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_result_directory_replaces_the_earlier_run_whole() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("results");
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"old a").unwrap();
        r.write("stale.svg", b"old plot").unwrap();
        r.commit(false).unwrap();
        let m = Manifest::read(&target).unwrap();
        m.verify(&target).unwrap();
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"new a").unwrap();
        assert_eq!(r.commit(false).unwrap(), target);
        assert_eq!(std::fs::read(target.join("a.csv")).unwrap(), b"new a");
        assert!(!target.join("stale.svg").exists(), "a stale file stayed");
        let m = Manifest::read(&target).unwrap();
        assert!(!m.partial);
        m.verify(&target).unwrap();
        // Nothing of the staging directories is left beside the target.
        let left: Vec<_> = std::fs::read_dir(root.path()).unwrap().collect();
        assert_eq!(left.len(), 1);
    }

    #[test]
    fn a_partial_run_goes_beside_a_complete_one_and_replaces_a_partial_one() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("results");
        let beside = root.path().join("results.partial");
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"complete").unwrap();
        r.commit(false).unwrap();
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"partial").unwrap();
        assert_eq!(r.commit(true).unwrap(), beside);
        assert_eq!(std::fs::read(target.join("a.csv")).unwrap(), b"complete");
        assert_eq!(std::fs::read(beside.join("a.csv")).unwrap(), b"partial");
        assert!(Manifest::read(&beside).unwrap().partial);
        // Over a partial one, a partial run replaces it in place.
        let other = root.path().join("other");
        for (text, partial) in [(&b"first"[..], true), (&b"second"[..], true)] {
            let mut r = ResultDir::create(&other).unwrap();
            r.write("a.csv", text).unwrap();
            assert_eq!(r.commit(partial).unwrap(), other);
        }
        assert_eq!(std::fs::read(other.join("a.csv")).unwrap(), b"second");
    }

    #[test]
    fn foreign_files_in_the_target_are_kept() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("mine");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("notes.txt"), b"keep me").unwrap();
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"first").unwrap();
        r.write("b.csv", b"first").unwrap();
        r.commit(false).unwrap();
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"second").unwrap();
        r.commit(false).unwrap();
        assert_eq!(std::fs::read(target.join("notes.txt")).unwrap(), b"keep me");
        assert!(!target.join("b.csv").exists());
        Manifest::read(&target).unwrap().verify(&target).unwrap();
    }
}
