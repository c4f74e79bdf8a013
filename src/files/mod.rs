//! Files on disk are complete or absent: bounded reads, atomic single files, and result
//! directories replaced as a whole.
//!
//! * [`read_bounded`] reads at most a limit from anything (a regular file, a pipe, `/dev/zero`).
//! * [`AtomicFile`] writes beside the target (a temporary file in the same directory), syncs it
//!   and renames it into place: a reader finds the old file or the new one, never a cut one.
//! * [`ResultDir`] stages a whole result directory beside the target, writes `manifest.json`
//!   last (every file with its size and SHA-256), then exchanges the staged directory with the
//!   old one in one atomic `renameat2(RENAME_EXCHANGE)` (Linux) and removes the old one: killed
//!   at any moment, the target holds either the earlier complete run or the new one, and no file
//!   of an earlier run lingers beside a new one. When the target holds files that no earlier
//!   manifest lists (the user's own, or shard files), they are hard-linked into the staged
//!   directory before the exchange (the same files). Where that cannot be done (a special
//!   file, another file system inside the target) or the platform or file system cannot
//!   exchange, the files are renamed in one by one instead (each atomic), as one transaction:
//!   conflicts (a directory where a file goes, an input of the run) are looked for before
//!   anything moves, the earlier manifest goes first and the new one comes last, a rename
//!   that fails puts back everything moved before it, and a run killed midway is rolled back
//!   by the next one into the same place. Where the target is a mount point (a container's
//!   volume) or its parent is not writable, the run is staged inside the target, so that
//!   every rename stays on one file system.
//!
//! Common to both: a target that is a symbolic link is written through (the link stays, its
//! target gets the result, as a shell's `>` does); a single file onto a device or a pipe is
//! written to directly; files are created with the permissions the umask allows, as any other
//! program's; an output that is one of the run's inputs (the same file, by device and inode,
//! whatever links lead to it) is refused ([`Inputs`]); and what a killed run left (its staging
//! file or directory, `.NAME.XXXXXX.partial`, which a live run
//! holds locked) is removed by the next run writing to the same place.

use sha2::{Digest, Sha256};
use std::fs::File;
use std::io::{Read, Write};
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// Format tag of `manifest.json`.
pub const MANIFEST_FORMAT: &str = "modaltol-results-1";

/// An I/O failure, naming the path.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {what}")]
pub struct FileError {
    pub path: String,
    pub what: &'static str,
    #[source]
    pub source: std::io::Error,
}

fn fail(path: &Path, what: &'static str) -> impl FnOnce(std::io::Error) -> FileError {
    let path = path.display().to_string();
    // Errors of `tempfile` name its temporary path; the message names the target instead.
    move |e| FileError {
        path,
        what,
        source: without_temporary_path(e),
    }
}

/// `tempfile` appends its temporary path to an error (`… at path "/dir/.name.XXXX.partial"`);
/// the message names the target instead.
fn without_temporary_path(e: std::io::Error) -> std::io::Error {
    let text = e.to_string();
    match text.split_once(" at path ") {
        Some((head, _)) => std::io::Error::new(e.kind(), head.to_string()),
        None => e,
    }
}

fn invalid(path: &Path, what: &'static str, message: String) -> FileError {
    FileError {
        path: path.display().to_string(),
        what,
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, message),
    }
}

/// Reads a UTF-8 text of at most `max` bytes from `path`, whatever it is (a device or a pipe
/// has no size to check beforehand).
pub fn read_bounded(path: &Path, max: u64) -> Result<Vec<u8>, FileError> {
    let file = std::fs::File::open(path).map_err(fail(path, "cannot open"))?;
    let mut bytes = Vec::new();
    file.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(fail(path, "cannot read"))?;
    if bytes.len() as u64 > max {
        return Err(invalid(
            path,
            "too large",
            format!("more than {max} bytes (the limit for this kind of file)"),
        ));
    }
    Ok(bytes)
}

/// The path a write to `path` lands on: `path` with the symbolic links of its last component
/// followed (to a link's target, existing or not), as a shell's `>` writes through a link.
pub fn write_target(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    // Linux's own bound on a chain of links (ELOOP).
    for _ in 0..40 {
        match std::fs::read_link(&p) {
            Ok(link) => p = directory_of(&p).join(link),
            Err(_) => break,
        }
    }
    p
}

/// The directory `path` lies in (`.` for a bare name).
fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// A file, as the file system knows it: its device and inode (the same file through any
/// name, link or hard link).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Identity {
    dev: u64,
    ino: u64,
}

impl Identity {
    /// The file `path` names, links followed; `None` where there is none.
    fn of(path: &Path) -> Option<Identity> {
        std::fs::metadata(path).ok().map(|m| Identity::from(&m))
    }
}

impl From<&std::fs::Metadata> for Identity {
    fn from(m: &std::fs::Metadata) -> Self {
        Identity {
            dev: m.dev(),
            ino: m.ino(),
        }
    }
}

/// The input files of a run (a model, shard files), which no output of the run may replace or
/// remove: a run never destroys what it reads.
#[derive(Debug, Clone, Default)]
pub struct Inputs(Vec<(PathBuf, Identity)>);

impl Inputs {
    /// The files at `paths` (those that exist).
    pub fn new<P: AsRef<Path>>(paths: &[P]) -> Inputs {
        Inputs(
            paths
                .iter()
                .filter_map(|p| Identity::of(p.as_ref()).map(|id| (p.as_ref().to_path_buf(), id)))
                .collect(),
        )
    }

    /// The input that `path` (links followed) is, if it is one.
    fn find(&self, path: &Path) -> Option<&Path> {
        let id = Identity::of(path)?;
        self.0
            .iter()
            .find(|(_, i)| *i == id)
            .map(|(p, _)| p.as_path())
    }

    /// Refuses an output `path` that is one of the inputs (the same file by device and inode,
    /// through any symbolic or hard link).
    pub fn refuse_output(&self, path: &Path) -> Result<(), FileError> {
        match self.find(path) {
            Some(input) => Err(invalid(
                path,
                "cannot write",
                format!(
                    "it is the input {} (the same file); an output never replaces an input",
                    input.display()
                ),
            )),
            None => Ok(()),
        }
    }
}

/// Marks a staging file or directory as in use (an exclusive advisory lock, released when
/// the process ends however it ends), so that other runs' cleanup leaves it alone. Best
/// effort: where the file system has no locks, nothing is marked, and nothing unmarked is
/// ever removed by another run either.
fn mark_in_use(f: &File) {
    let _ = f.try_lock();
}

/// Removes what killed runs left in `dir` for the target named `name`: staging files and
/// directories `.NAME.XXXXXX.partial` (`tempfile`'s six random characters) that no live run
/// holds locked. A staging directory of a result directory `target` killed while its files
/// were renamed in one by one is first rolled back ([`roll_back`]), so that the target holds
/// the earlier run again.
fn remove_leftovers(dir: &Path, name: &str, target: Option<&Path>) {
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
        if let (true, Some(target)) = (kind.is_dir(), target) {
            roll_back(&path, target);
        }
        let _ = if kind.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
    }
}

/// Undoes the one-by-one install ([`ResultDir::install_one_by_one`]) of a killed run staged at
/// `staging` into `target`, where it was cut before its manifest went in: the run's files
/// that reached the target are removed and the earlier ones (kept in `staging/.previous`) put
/// back. A staging directory without that backup never started an install, and one without
/// its manifest finished it: nothing to undo.
fn roll_back(staging: &Path, target: &Path) {
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

/// A file written beside its target and renamed into place by [`AtomicFile::commit`]; dropped
/// without a commit, it is removed and the target is untouched. A target that is no regular
/// file (a device such as `/dev/null`, a named pipe, `/dev/stdout`) is written directly
/// instead, as a shell's `>` does: it cannot be replaced, and replacing it would destroy it.
pub struct AtomicFile {
    target: PathBuf,
    file: Staged,
}

/// Where an [`AtomicFile`]'s bytes go.
enum Staged {
    /// A temporary file beside the target, renamed into place.
    Beside(tempfile::NamedTempFile),
    /// The target itself (a device or a pipe).
    Direct(File),
}

/// Is `path` something other than a regular file or a directory, through its links (a
/// device, a named pipe, a socket), or one of the process's open descriptors (`/dev/stdout`,
/// `/dev/fd/N`, `/proc/…`, whose links lead to a descriptor rather than a name)?
fn is_special(path: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(path) else {
        return false;
    };
    let descriptor = ["/dev/stdout", "/dev/stderr", "/dev/fd", "/proc"]
        .iter()
        .any(|d| path.starts_with(d));
    descriptor || (!meta.is_file() && !meta.is_dir())
}

impl AtomicFile {
    /// Starts writing `target` (through a symbolic link, to where it points). Fails now, before
    /// anything is computed, where the file cannot be written there: its directory is missing
    /// or not writable, or a directory stands at its name.
    pub fn create(target: &Path) -> Result<AtomicFile, FileError> {
        if is_special(target) {
            let f = std::fs::OpenOptions::new()
                .write(true)
                .open(target)
                .map_err(fail(target, "cannot open for writing"))?;
            return Ok(AtomicFile {
                target: target.to_path_buf(),
                file: Staged::Direct(f),
            });
        }
        let resolved = write_target(target);
        if resolved.is_dir() {
            return Err(invalid(target, "cannot write", "it is a directory".into()));
        }
        let dir = directory_of(&resolved);
        let name = resolved
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        remove_leftovers(dir, &name, None);
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{}.", truncate(&name, 60)))
            .suffix(".partial")
            .permissions(std::fs::Permissions::from_mode(0o666))
            .tempfile_in(dir)
            .map_err(fail(target, "cannot create the file"))?;
        mark_in_use(temp.as_file());
        Ok(AtomicFile {
            target: resolved,
            file: Staged::Beside(temp),
        })
    }

    /// Syncs and renames the file into place.
    pub fn commit(self) -> Result<(), FileError> {
        let target = self.target;
        match self.file {
            Staged::Direct(mut f) => f.flush().map_err(fail(&target, "cannot write")),
            Staged::Beside(temp) => {
                temp.as_file()
                    .sync_all()
                    .map_err(fail(&target, "cannot write"))?;
                temp.persist(&target)
                    .map_err(|e| fail(&target, "cannot rename into place")(e.error))?;
                sync_parent(&target);
                Ok(())
            }
        }
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.file {
            Staged::Beside(t) => t.write(buf),
            Staged::Direct(f) => f.write(buf),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.file {
            Staged::Beside(t) => t.flush(),
            Staged::Direct(f) => f.flush(),
        }
    }
}

/// Writes `bytes` to `target` atomically.
pub fn write_atomically(target: &Path, bytes: &[u8]) -> Result<(), FileError> {
    let mut f = AtomicFile::create(target)?;
    f.write_all(bytes).map_err(fail(target, "cannot write"))?;
    f.commit()
}

fn truncate(s: &str, max: usize) -> String {
    s.chars().take(max).collect()
}

/// SHA-256 of `bytes`, as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// One file of a result directory, as its manifest lists it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ManifestEntry {
    pub file: String,
    pub bytes: u64,
    pub sha256: String,
}

/// `manifest.json`: what belongs to one run, written last.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    pub format: String,
    /// The run stopped early (interrupted): the files are complete but hold a partial result.
    pub partial: bool,
    pub files: Vec<ManifestEntry>,
}

impl Manifest {
    /// Reads `dir/manifest.json`, if it is one.
    pub fn read(dir: &Path) -> Option<Manifest> {
        let bytes = read_bounded(&dir.join("manifest.json"), 1 << 20).ok()?;
        let m: Manifest = serde_json::from_slice(&bytes).ok()?;
        (m.format == MANIFEST_FORMAT).then_some(m)
    }

    /// Does every listed file exist with its size and digest?
    pub fn verify(&self, dir: &Path) -> Result<(), String> {
        for e in &self.files {
            let bytes = std::fs::read(dir.join(&e.file)).map_err(|x| format!("{}: {x}", e.file))?;
            if bytes.len() as u64 != e.bytes || sha256_hex(&bytes) != e.sha256 {
                return Err(format!("{}: does not match the manifest", e.file));
            }
        }
        Ok(())
    }
}

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
        remove_leftovers(&parent, &name, Some(&resolved));
        let exists = resolved.is_dir();
        if exists {
            remove_leftovers(&resolved, INSIDE, Some(&resolved));
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

    /// Writes the manifest and puts the run in place of the target.
    pub fn commit(self, partial: bool) -> Result<(), FileError> {
        self.commit_with(partial, &mut |a, b| std::fs::rename(a, b))
    }

    /// [`ResultDir::commit`] with `rename` moving each file.
    fn commit_with(mut self, partial: bool, rename: &mut Rename<'_>) -> Result<(), FileError> {
        let manifest = Manifest {
            format: MANIFEST_FORMAT.into(),
            partial,
            files: std::mem::take(&mut self.files),
        };
        let staging = self.staging.take().expect("not committed").keep();
        let result = self.install(&staging, &manifest, rename);
        // Whatever happened, nothing of the staging directory stays behind.
        let _ = std::fs::remove_dir_all(&staging);
        result
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

    /// Puts the run in place in one atomic exchange while keeping the user's entries of the
    /// target: they are hard-linked into the staged directory first (the same files, not
    /// copies; directories made anew with their permissions), and whatever appeared in the
    /// target meanwhile is moved over after. False, with the staged directory as it was, where
    /// that cannot be done (another file system inside the target, a special file, a link the
    /// system refuses, no exchange).
    fn exchange_keeping(&self, staging: &Path, plan: &Plan) -> bool {
        let target = &self.target;
        let mut linked = Vec::new();
        let all = plan.kept.iter().all(|name| {
            let ok = link_tree(&target.join(name), &staging.join(name), 0).is_ok();
            linked.push(name);
            ok
        });
        if !all || exchange(staging, target).is_err() {
            for name in linked {
                let at = staging.join(name);
                let _ = std::fs::remove_dir_all(&at).or_else(|_| std::fs::remove_file(&at));
            }
            return false;
        }
        sync_parent(target);
        // The earlier content is now at `staging` (removed by the caller): entries created
        // there after the listing above are moved over, best effort.
        if let Ok(entries) = std::fs::read_dir(staging) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                let known = plan.kept.contains(&name)
                    || plan.new.contains(&name)
                    || plan.stale.contains(&name);
                if !known && std::fs::symlink_metadata(target.join(&name)).is_err() {
                    let _ = std::fs::rename(e.path(), target.join(&name));
                }
            }
        }
        true
    }

    /// Refuses to replace or remove `names` in `dir` where one of them is an input.
    fn refuse_inputs_among(&self, dir: &Path, names: &[String]) -> Result<(), FileError> {
        names
            .iter()
            .try_for_each(|n| self.inputs.refuse_output(&dir.join(n)))
    }

    /// Renames the run's files in one by one as one transaction (see the module
    /// documentation): everything is checked before anything moves, and a failed rename puts
    /// back what moved before it.
    fn install_one_by_one(
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

/// The entries of a target that a run replaces, removes and keeps ([`ResultDir::plan`]).
struct Plan {
    /// The run's files and its manifest.
    new: Vec<String>,
    /// The earlier run's files this run does not write.
    stale: Vec<String>,
    /// Everything else in the target: the user's own entries.
    kept: Vec<String>,
}

/// Makes `to` the same tree as `from` without copying a byte: regular files hard-linked,
/// symbolic links made anew, directories made with their permissions and filled alike. An
/// error for anything else (a device, a socket, a pipe), across file systems, or deeper than
/// 256 levels.
fn link_tree(from: &Path, to: &Path, depth: usize) -> std::io::Result<()> {
    let meta = std::fs::symlink_metadata(from)?;
    let kind = meta.file_type();
    if kind.is_symlink() {
        std::os::unix::fs::symlink(std::fs::read_link(from)?, to)
    } else if kind.is_file() {
        std::fs::hard_link(from, to)
    } else if kind.is_dir() && depth < 256 {
        std::fs::create_dir(to)?;
        for e in std::fs::read_dir(from)? {
            let e = e?;
            link_tree(&e.path(), &to.join(e.file_name()), depth + 1)?;
        }
        std::fs::set_permissions(to, meta.permissions())
    } else {
        Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
    }
}

/// One rename of a file: `rename(from, to)`.
type Rename<'a> = dyn FnMut(&Path, &Path) -> std::io::Result<()> + 'a;

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

/// The files a manifest lists and the manifest itself.
fn listed(manifest: Option<&Manifest>) -> Vec<String> {
    let mut names: Vec<String> = manifest
        .map(|m| m.files.iter().map(|f| f.file.clone()).collect())
        .unwrap_or_default();
    names.push("manifest.json".into());
    names
}

impl Drop for ResultDir {
    fn drop(&mut self) {
        if let Some(s) = self.staging.take() {
            let _ = s.close();
        }
    }
}

fn is_plain_name(name: &str) -> bool {
    !name.is_empty() && !name.contains(['/', '\\']) && name != "." && name != ".."
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

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Flushes a file or directory to disk (best effort: a crash of the machine, not only of the
/// process, should not leave a renamed but empty file).
fn sync(path: &Path) {
    if let Ok(f) = File::open(path) {
        let _ = f.sync_all();
    }
}

fn sync_parent(path: &Path) {
    sync(directory_of(path));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs::Permissions;

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
        r.commit(true).unwrap();
        assert_eq!(std::fs::read(target.join("a.csv")).unwrap(), b"new a");
        assert!(!target.join("stale.svg").exists(), "a stale file stayed");
        let m = Manifest::read(&target).unwrap();
        assert!(m.partial);
        m.verify(&target).unwrap();
        // Nothing of the staging directories is left beside the target.
        let left: Vec<_> = std::fs::read_dir(root.path()).unwrap().collect();
        assert_eq!(left.len(), 1);
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

    #[test]
    fn bounded_reads_stop_at_the_limit() {
        let e = read_bounded(Path::new("/dev/zero"), 1000).unwrap_err();
        assert!(e.to_string().starts_with("/dev/zero: too large"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("x");
        write_atomically(&f, b"12345").unwrap();
        assert_eq!(read_bounded(&f, 5).unwrap(), b"12345");
        assert!(read_bounded(&f, 4).is_err());
    }

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

    #[test]
    fn a_link_as_target_is_written_through() {
        let root = tempfile::tempdir().unwrap();
        let d = root.path();
        std::fs::create_dir(d.join("real")).unwrap();
        std::os::unix::fs::symlink("real", d.join("dir-link")).unwrap();
        std::os::unix::fs::symlink("dir-link", d.join("dir-link2")).unwrap();
        for (i, link) in ["dir-link", "dir-link2"].iter().enumerate() {
            let mut r = ResultDir::create(&d.join(link)).unwrap();
            r.write("a.csv", format!("run {i}").as_bytes()).unwrap();
            r.commit(false).unwrap();
            assert!(
                d.join(link)
                    .symlink_metadata()
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
            assert_eq!(
                std::fs::read(d.join("real/a.csv")).unwrap(),
                format!("run {i}").as_bytes()
            );
        }
        std::os::unix::fs::symlink("real/f.csv", d.join("file-link")).unwrap();
        for bytes in [b"first" as &[u8], b"second"] {
            // Dangling the first time: the file is made where the link points.
            write_atomically(&d.join("file-link"), bytes).unwrap();
            assert!(
                d.join("file-link")
                    .symlink_metadata()
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
            assert_eq!(std::fs::read(d.join("real/f.csv")).unwrap(), bytes);
        }
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_through_any_link() {
        let root = tempfile::tempdir().unwrap();
        let d = root.path();
        let model = d.join("m.toml");
        std::fs::write(&model, b"model").unwrap();
        std::fs::hard_link(&model, d.join("hard.toml")).unwrap();
        std::os::unix::fs::symlink("m.toml", d.join("soft.toml")).unwrap();
        std::os::unix::fs::symlink("soft.toml", d.join("soft2.toml")).unwrap();
        std::fs::write(d.join("other.toml"), b"model").unwrap();
        for input in ["m.toml", "hard.toml", "soft.toml", "soft2.toml"] {
            let inputs = Inputs::new(&[d.join(input)]);
            for output in ["m.toml", "hard.toml", "soft.toml", "soft2.toml"] {
                let e = inputs.refuse_output(&d.join(output)).unwrap_err();
                assert!(
                    e.source.to_string().contains("is the input"),
                    "{input} {output}: {e}"
                );
            }
            inputs.refuse_output(&d.join("other.toml")).unwrap();
            inputs.refuse_output(&d.join("new.csv")).unwrap();
        }
        // A result directory never replaces or removes an input, whatever its name there.
        let target = d.join("results");
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"1").unwrap();
        r.commit(false).unwrap();
        // Refused before the run: a file of the earlier run (removed as stale), a name the
        // run writes.
        let input = target.join("a.csv");
        let e = ResultDir::create(&target)
            .unwrap()
            .protect(Inputs::new(&[&input]), |_| false)
            .err()
            .unwrap();
        assert!(e.source.to_string().contains("is the input"), "{e}");
        std::fs::write(target.join("c.csv"), b"mine").unwrap();
        let mine = Inputs::new(&[target.join("c.csv")]);
        let e = ResultDir::create(&target)
            .unwrap()
            .protect(mine.clone(), |n| n == "c.csv")
            .err()
            .unwrap();
        assert!(e.source.to_string().contains("is the input"), "{e}");
        // Where the run's names were not foreseen, the commit refuses them still.
        let mut r = ResultDir::create(&target)
            .unwrap()
            .protect(mine, |_| false)
            .unwrap();
        r.write("c.csv", b"2").unwrap();
        let e = r.commit(false).unwrap_err();
        assert!(e.source.to_string().contains("is the input"), "{e}");
        assert_eq!(std::fs::read(&input).unwrap(), b"1");
        assert_eq!(std::fs::read(target.join("c.csv")).unwrap(), b"mine");
    }

    #[test]
    fn the_users_files_are_kept_through_one_atomic_exchange() {
        use std::os::unix::fs::MetadataExt;
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("results");
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"old a").unwrap();
        r.write("gone.svg", b"old").unwrap();
        r.commit(false).unwrap();
        std::fs::write(target.join("notes.txt"), b"mine").unwrap();
        std::fs::create_dir_all(target.join("sub/deeper")).unwrap();
        std::fs::write(target.join("sub/deeper/data.bin"), b"deep").unwrap();
        std::fs::set_permissions(target.join("sub"), Permissions::from_mode(0o750)).unwrap();
        std::os::unix::fs::symlink("notes.txt", target.join("link")).unwrap();
        // A user's file under a result's name, not listed by the earlier run: replaced.
        std::fs::write(target.join("b.csv"), b"user's b").unwrap();
        let inode = |p: &str| std::fs::metadata(target.join(p)).unwrap().ino();
        let (notes, deep) = (inode("notes.txt"), inode("sub/deeper/data.bin"));
        let mut r = ResultDir::create(&target).unwrap();
        r.write("a.csv", b"new a").unwrap();
        r.write("b.csv", b"new b").unwrap();
        r.commit_with(false, &mut |_: &Path, _: &Path| {
            panic!("renamed one by one instead of exchanged")
        })
        .unwrap();
        Manifest::read(&target).unwrap().verify(&target).unwrap();
        assert_eq!(std::fs::read(target.join("a.csv")).unwrap(), b"new a");
        assert_eq!(std::fs::read(target.join("b.csv")).unwrap(), b"new b");
        assert!(!target.join("gone.svg").exists());
        // The same files, not copies; the directory's permissions and the link kept.
        assert_eq!(inode("notes.txt"), notes);
        assert_eq!(inode("sub/deeper/data.bin"), deep);
        let mode = std::fs::metadata(target.join("sub")).unwrap().mode() & 0o777;
        assert_eq!(mode, 0o750);
        assert_eq!(
            std::fs::read_link(target.join("link")).unwrap(),
            Path::new("notes.txt")
        );
        let beside: Vec<_> = std::fs::read_dir(root.path()).unwrap().collect();
        assert_eq!(beside.len(), 1, "something was left beside the target");
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
