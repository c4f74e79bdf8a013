//! Bounded reads: a model or shard file read whole, but never more than a limit, whatever the
//! path names (a regular file, a pipe, `/dev/zero`, which has no size to check beforehand).

use super::{FileError, fail, invalid};
use std::io::Read;
use std::path::Path;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::write_atomically;

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
