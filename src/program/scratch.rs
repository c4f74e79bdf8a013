//! Working memory of the recorded program's passes: forward-mode buffers and instances'
//! scratch spaces, kept per thread for the next pass (a sweep makes one instance per speed; a
//! buffer over hyper-dual numbers is hundreds of kilobytes).

use super::Instance;
use crate::real::Real;
use crate::tape::Forward;
use std::cell::RefCell;

thread_local! {
    /// Forward-mode scratch buffers of any scalar type, kept for the next pass on this thread
    /// (a buffer over hyper-dual numbers is hundreds of kilobytes).
    pub(super) static BUFFERS: RefCell<Vec<Box<dyn std::any::Any>>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with a forward-mode buffer over `S` from this thread's pool.
pub(super) fn with_buffer<S: Real, R>(f: impl FnOnce(&mut Forward<S>) -> R) -> R {
    let mut work = BUFFERS
        .with(|b| {
            let mut b = b.borrow_mut();
            let i = b.iter().position(|x| x.is::<Forward<S>>())?;
            b.swap_remove(i).downcast::<Forward<S>>().ok()
        })
        .unwrap_or_default();
    let out = f(&mut work);
    BUFFERS.with(|b| {
        let mut b = b.borrow_mut();
        if b.len() < 8 {
            b.push(work);
        }
    });
    out
}

/// Scratch space of an [`Instance`]: values, one forward buffer per seeding (kept, as switching
/// a buffer's seeding clears it), and values at three points.
#[derive(Debug, Default)]
pub(super) struct Work {
    pub(super) values: Vec<f64>,
    pub(super) jacobian: Forward<f64>,
    pub(super) linear: Forward<f64>,
    pub(super) varied: Vec<[f64; 3]>,
}

thread_local! {
    /// Scratch spaces of finished instances on this thread, reused by the next ones (a sweep
    /// makes one instance per speed).
    pub(super) static POOL: RefCell<Vec<Work>> = const { RefCell::new(Vec::new()) };
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        let work = std::mem::take(self.work.get_mut());
        POOL.with(|p| {
            let mut p = p.borrow_mut();
            if p.len() < 4 {
                p.push(work);
            }
        });
    }
}
