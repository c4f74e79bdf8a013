//! Where a command writes: a file put in place whole, or stdout (refused when closed).

use crate::cli::*;
use anyhow::Result;
use modaltol::files::{AtomicFile, Inputs, ResultDir};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

pub(crate) fn write_csv(
    mut w: impl Write,
    header: &[impl AsRef<[u8]>],
    rows: &[Vec<String>],
) -> Result<()> {
    w.write_all(&modaltol::results::csv_bytes(header, rows))?;
    Ok(())
}

/// An output named that is one of the run's inputs: bad arguments, refused before anything
/// is computed or written.
pub(crate) fn refuse_input(inputs: &Inputs, output: &std::path::Path) -> Result<()> {
    inputs
        .refuse_output(output)
        .map_err(|e| InputError(format!("{e}: {}", e.source)).into())
}

/// `dir`, refusing (as an input error, before the run) an input it would replace or remove.
pub(crate) fn protect(dir: ResultDir, inputs: Inputs) -> Result<ResultDir> {
    dir.protect(inputs, modaltol::results::is_result_file)
        .map_err(|e| InputError(format!("{e}: {}", e.source)).into())
}

/// Where `analyze` writes: a shard's file, or the whole run's directory.
pub(crate) enum Destination {
    Shard(AtomicFile, PathBuf),
    Directory(ResultDir),
}

/// Where a command's table goes: a file written beside its target and renamed into place by
/// [`Sink::finish`] (a failed or killed run leaves the earlier file untouched), or stdout.
pub(crate) enum Sink {
    File(std::io::BufWriter<AtomicFile>),
    Stdout(std::io::BufWriter<std::io::StdoutLock<'static>>),
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::File(w) => w.write(buf),
            Sink::Stdout(w) => w.write(buf),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::File(w) => w.flush(),
            Sink::Stdout(w) => w.flush(),
        }
    }
}

impl Sink {
    /// The file `output` (refused where it is one of `inputs`), or stdout.
    pub(crate) fn to(output: &Option<PathBuf>, inputs: &Inputs) -> Result<Sink> {
        Ok(match output {
            Some(p) => {
                refuse_input(inputs, p)?;
                Sink::File(std::io::BufWriter::new(AtomicFile::create(p)?))
            }
            None if STDOUT_CLOSED.load(Ordering::SeqCst) => {
                return Err(Failed(
                    "stdout is closed: nothing could be written (give -o FILE)".into(),
                )
                .into());
            }
            None => Sink::Stdout(std::io::BufWriter::new(std::io::stdout().lock())),
        })
    }

    /// Flushes, and puts a file in place.
    pub(crate) fn finish(self) -> Result<()> {
        match self {
            Sink::File(w) => w.into_inner().map_err(|e| e.into_error())?.commit()?,
            Sink::Stdout(mut w) => w.flush()?,
        }
        Ok(())
    }
}

/// Was stdout closed when the process started (`modaltol … >&-`)? Rust's runtime opens
/// `/dev/null` in its place before `main`, and whatever is written there vanishes without a
/// word; so this is looked at before the runtime starts (an ELF initialiser), and a command
/// that would write to stdout refuses to run instead.
pub(crate) static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

#[cfg(target_os = "linux")]
#[used]
#[unsafe(link_section = ".init_array")]
pub(crate) static NOTE_A_CLOSED_STDOUT: extern "C" fn() = {
    extern "C" fn note() {
        // SAFETY: F_GETFD reads a descriptor's flags and nothing else; a closed one is EBADF.
        let closed = unsafe { libc::fcntl(1, libc::F_GETFD) } == -1;
        STDOUT_CLOSED.store(closed, Ordering::SeqCst);
    }
    note
};
