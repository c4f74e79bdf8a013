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
//!
//! One submodule per piece: `read` (bounded reads), `inputs` (the files a run must not
//! replace), `atomic` (single files), `manifest` (what a result directory holds),
//! `result_dir` (whole directories, with their exchange and their one-by-one install as
//! submodules) and `leftovers` (what killed runs left). This module holds the error type and
//! the path helpers they share, and re-exports every public item.

mod atomic;
mod inputs;
mod leftovers;
mod manifest;
mod read;
mod result_dir;

pub use atomic::{AtomicFile, write_atomically};
pub use inputs::Inputs;
pub use manifest::{MANIFEST_FORMAT, Manifest, ManifestEntry, sha256_hex};
pub use read::read_bounded;
pub use result_dir::ResultDir;

use std::fs::File;
use std::path::{Path, PathBuf};

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

fn truncate(s: &str, max: usize) -> String {
    s.chars().take(max).collect()
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
}
