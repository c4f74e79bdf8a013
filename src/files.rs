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
//!   manifest lists (the user's own, or shard files), or the platform or file system cannot
//!   exchange, the files are renamed in one by one instead (each atomic) and the earlier run's
//!   other files are removed; the manifest, written last, tells what belongs to the run.

use sha2::{Digest, Sha256};
use std::io::{Read, Write};
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

/// A file written beside its target and renamed into place by [`AtomicFile::commit`]; dropped
/// without a commit, it is removed and the target is untouched.
pub struct AtomicFile {
    target: PathBuf,
    temp: tempfile::NamedTempFile,
}

impl AtomicFile {
    pub fn create(target: &Path) -> Result<AtomicFile, FileError> {
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{}.", truncate(&name, 60)))
            .suffix(".partial")
            .tempfile_in(dir)
            .map_err(fail(target, "cannot create the file"))?;
        Ok(AtomicFile {
            target: target.to_path_buf(),
            temp,
        })
    }

    /// Syncs and renames the file into place.
    pub fn commit(self) -> Result<(), FileError> {
        let target = self.target;
        self.temp
            .as_file()
            .sync_all()
            .map_err(fail(&target, "cannot write"))?;
        self.temp
            .persist(&target)
            .map_err(|e| fail(&target, "cannot rename into place")(e.error))?;
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.temp.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.temp.flush()
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

/// A result directory being written: files go to a staging directory beside the target;
/// [`ResultDir::commit`] puts them in place (see the module documentation). Dropped without a
/// commit, the staging directory is removed and the target is untouched.
pub struct ResultDir {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
    files: Vec<ManifestEntry>,
}

impl ResultDir {
    pub fn create(target: &Path) -> Result<ResultDir, FileError> {
        let parent = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(fail(&parent, "cannot create the directory"))?;
        if target.exists() && !target.is_dir() {
            return Err(invalid(
                target,
                "cannot write results",
                "it exists and is not a directory".into(),
            ));
        }
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "results".into());
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{}.", truncate(&name, 60)))
            .suffix(".partial")
            .tempdir_in(&parent)
            .map_err(fail(target, "cannot create the results directory"))?;
        Ok(ResultDir {
            target: target.to_path_buf(),
            staging: Some(staging),
            files: Vec::new(),
        })
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
    pub fn commit(mut self, partial: bool) -> Result<(), FileError> {
        let manifest = Manifest {
            format: MANIFEST_FORMAT.into(),
            partial,
            files: std::mem::take(&mut self.files),
        };
        let staging = self.staging.take().expect("not committed").keep();
        let result = self.install(&staging, &manifest);
        // Whatever happened, nothing of the staging directory stays behind.
        let _ = std::fs::remove_dir_all(&staging);
        result
    }

    fn install(&self, staging: &Path, manifest: &Manifest) -> Result<(), FileError> {
        let text = serde_json::to_vec_pretty(manifest).expect("a manifest serialises");
        std::fs::write(staging.join("manifest.json"), &text)
            .map_err(fail(&self.target.join("manifest.json"), "cannot write"))?;
        for e in &manifest.files {
            sync(&staging.join(&e.file));
        }
        sync(&staging.join("manifest.json"));
        sync(staging);
        let target = &self.target;
        if !target.exists() {
            std::fs::rename(staging, target).map_err(fail(target, "cannot rename into place"))?;
            sync_parent(target);
            return Ok(());
        }
        let previous = Manifest::read(target);
        if owned_by(target, previous.as_ref()) && exchange(staging, target).is_ok() {
            // The old run is now at `staging`, removed by the caller.
            sync_parent(target);
            return Ok(());
        }
        // One by one: the data files, then the manifest; then the earlier run's leftovers.
        for e in &manifest.files {
            std::fs::rename(staging.join(&e.file), target.join(&e.file))
                .map_err(fail(&target.join(&e.file), "cannot rename into place"))?;
        }
        std::fs::rename(staging.join("manifest.json"), target.join("manifest.json")).map_err(
            fail(&target.join("manifest.json"), "cannot rename into place"),
        )?;
        if let Some(prev) = previous {
            for e in prev.files {
                if !manifest.files.iter().any(|n| n.file == e.file) && is_plain_name(&e.file) {
                    let _ = std::fs::remove_file(target.join(&e.file));
                }
            }
        }
        sync(target);
        Ok(())
    }
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

/// Does the directory hold nothing but an earlier run (the files its manifest lists, the
/// manifest) or nothing at all? Only then may it be replaced as a whole.
fn owned_by(dir: &Path, manifest: Option<&Manifest>) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    for e in entries {
        let Ok(e) = e else { return false };
        let name = e.file_name().to_string_lossy().into_owned();
        let listed = name == "manifest.json"
            || manifest.is_some_and(|m| m.files.iter().any(|f| f.file == name));
        if !listed {
            return false;
        }
    }
    true
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
    if let Ok(f) = std::fs::File::open(path) {
        let _ = f.sync_all();
    }
}

fn sync_parent(path: &Path) {
    if let Some(p) = path.parent() {
        sync(if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        });
    }
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
}
