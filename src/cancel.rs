//! Cooperative cancellation of long runs.
//!
//! A [`Cancel`] token is handed to a run (in [`crate::analyze::AnalyzeOptions`]); whoever holds
//! a clone (a Ctrl-C handler, a Python binding, a test) may cancel it, and the run stops at its
//! next check (the Monte Carlo after its current chunk), returning what it has done, flagged as
//! partial. Each run has its own token, so cancelling one leaves later runs in the same process
//! alone.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A cancellation flag shared by clones (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token not cancelled.
    pub fn new() -> Self {
        Cancel::default()
    }

    /// Asks the runs holding this token (or a clone) to stop at their next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Has [`Cancel::cancel`] been called?
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::Cancel;

    #[test]
    fn clones_share_the_flag_and_fresh_tokens_do_not() {
        let a = Cancel::new();
        let b = a.clone();
        assert!(!b.is_cancelled());
        a.cancel();
        assert!(b.is_cancelled());
        assert!(!Cancel::new().is_cancelled());
    }
}
