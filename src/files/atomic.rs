//! Single files written atomically: staged beside the target and renamed into place, so that a
//! reader finds the old file or the new one, never a cut one; devices and pipes are written
//! directly, as they cannot be replaced.

use super::leftovers::{mark_in_use, remove_leftovers};
use super::{FileError, directory_of, fail, invalid, sync_parent, truncate, write_target};
use std::fs::File;
use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

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
