//! Shard files: one share of a Monte Carlo run split across batch jobs (`analyze --shard K/N`),
//! and their verification before `merge` combines them into exactly the result of one run.
//!
//! A shard keeps, per tolerance case, the maximal aligned blocks of chunk moments of its range
//! of chunks (see [`crate::montecarlo::TreeFold`]): a few per level, so a file's size does not
//! grow with the number of samples. Shard files travel between machines and are read back, so
//! `merge` trusts nothing in them:
//!
//! * a SHA-256 digest of the whole content (with the digest field empty) catches any edit or
//!   truncation;
//! * a [`Fingerprint`] of everything the numbers depend on (the whole validated model, the
//!   tolerance cases, the speeds, samples, seed, sampling and the quadrature's options), one
//!   SHA-256 per section, so a shard of another model or run is refused naming what differs
//!   (SHA-256 is stable; std's `DefaultHasher` may change between Rust releases);
//! * the blocks of shard `K` must be exactly the layout of shard `K`'s chunks, so a shard
//!   relabelled as another (even with a recomputed digest) is refused;
//! * every count and moment must be possible: `n + failed` equals the block's samples, every
//!   event count lies within them, `m2, m4 ≥ 0`, all numbers finite, the dimensions those of
//!   the model's outputs at the run's speeds.

mod check;
mod file;
mod fingerprint;
mod merge;

pub use check::Layout;
pub use file::{FORMAT, KeptFile, MAX_BYTES, ShardError, ShardFile, output_count};
pub use fingerprint::{Fingerprint, RunSettings};
pub use merge::{Gathered, cases_run, gather, merged_options, read_all, verify};
