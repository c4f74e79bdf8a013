//! Putting a run in place in one atomic exchange (`renameat2(RENAME_EXCHANGE)`, Linux), the
//! user's entries of the target kept by hard-linking them into the staged directory first.

use super::{Plan, ResultDir};
use crate::files::sync_parent;
use std::path::Path;

impl ResultDir {
    /// Puts the run in place in one atomic exchange while keeping the user's entries of the
    /// target: they are hard-linked into the staged directory first (the same files, not
    /// copies; directories made anew with their permissions), and whatever appeared in the
    /// target meanwhile is moved over after. False, with the staged directory as it was, where
    /// that cannot be done (another file system inside the target, a special file, a link the
    /// system refuses, no exchange).
    pub(super) fn exchange_keeping(&self, staging: &Path, plan: &Plan) -> bool {
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

#[cfg(target_os = "linux")]
pub(super) fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
pub(super) fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::Manifest;
    use std::fs::Permissions;
    use std::os::unix::fs::PermissionsExt;

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
}
