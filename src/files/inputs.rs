//! The run's inputs, by device and inode: no output of a run may replace or remove a file it
//! reads, whatever name, symbolic link or hard link leads to it.

use super::{FileError, invalid};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// A file, as the file system knows it: its device and inode (the same file through any
/// name, link or hard link).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Identity {
    pub(super) dev: u64,
    ino: u64,
}

impl Identity {
    /// The file `path` names, links followed; `None` where there is none.
    pub(super) fn of(path: &Path) -> Option<Identity> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::ResultDir;

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
}
