//! Working memory of the recorded program's passes, owned by the caller (faer's habit): a
//! sweep keeps one for all its points, a Monte Carlo or quadrature worker one for all its
//! samples, a sensitivity or Hessian call one for all its passes. A forward-mode buffer over
//! hyper-dual numbers is hundreds of kilobytes, and a sweep makes one [`Instance`] per speed:
//! allocating and clearing them per evaluation would cost more than some passes.
//!
//! [`Instance`]: super::Instance

use crate::real::Real;
use crate::tape::Forward;
use std::any::Any;
use std::cell::RefCell;

/// The working memory of the passes of [`super::Program`]s (see the module documentation):
/// lent to each [`super::Instance`] and each [`super::Recorded`]; one at a time uses each part
/// (a [`RefCell`]), so a workspace serves one thread.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The `f64` instances' scratch space.
    pub(super) work: RefCell<Work>,
    /// Forward-mode buffers over the scalars evaluated so far (one per type).
    buffers: RefCell<Vec<Box<dyn Any + Send>>>,
}

/// Scratch space of an [`super::Instance`]: values, one forward buffer per seeding (kept, as
/// switching a buffer's seeding clears it), values at three points, and values along
/// three directions.
#[derive(Debug, Default)]
pub(super) struct Work {
    pub(super) values: Vec<f64>,
    pub(super) jacobian: Forward<f64>,
    pub(super) linear: Forward<f64>,
    pub(super) varied: Vec<[f64; 3]>,
    pub(super) probe: Forward<f64>,
}

impl Workspace {
    /// Runs `f` with this workspace's forward-mode buffer over `S` (made at the first use).
    pub(super) fn with_buffer<S: Real, R>(&self, f: impl FnOnce(&mut Forward<S>) -> R) -> R {
        let mut work = {
            let mut b = self.buffers.borrow_mut();
            b.iter()
                .position(|x| x.is::<Forward<S>>())
                .and_then(|i| b.swap_remove(i).downcast::<Forward<S>>().ok())
                .unwrap_or_default()
        };
        let out = f(&mut work);
        self.buffers.borrow_mut().push(work);
        out
    }
}
