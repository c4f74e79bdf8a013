//! Recorded programs: the generic mechanics traced once into a flat list of scalar operations,
//! then evaluated over any [`Real`].
//!
//! The mechanics is written once over [`Real`] and differentiated by nesting dual numbers: a
//! Jacobian of the equations of motion runs the tree kinematics once per coordinate over
//! `Dual<Dual2<f64>>`, most of whose parts are structurally zero, and repeats the same pose
//! products in every pass. Tracing that very code with [`Var`] (a scalar that records each
//! operation instead of only computing it) gives a straight-line program in which
//!
//! * operations on constants are folded (`x·0`, `x·1`, `x+0`, the zero parts of the duals),
//! * identical operations on identical operands are recorded once (hash-consing), so the pose
//!   products shared by all the dual passes appear once,
//! * operations that no output needs are dropped, and products used once by a sum are fused
//!   with it ([`Tape::finish`]).
//!
//! The program is then evaluated over `f64` for values, or over any dual number for exact
//! derivatives: no derivative is written by hand here either, the dual numbers differentiate the
//! recorded operations. A trace is only valid where the traced code does not branch on the
//! values: any comparison of a [`Var`] marks the trace as tainted, and [`record`] then returns
//! `None` so that the caller keeps to the direct route.
//!
//! This is operator-overloading tracing in the sense of Griewank & Walther, *Evaluating
//! Derivatives* (2nd ed., SIAM 2008), §3 and §5.
//!
//! [`Real`]: crate::real::Real

mod eval;
mod forward;
mod hyper;
mod native;
mod op;
mod packing;
mod passes;
mod pattern;
mod reverse;
mod seeding;
mod var;

pub use forward::{Forward, Rows};
pub use hyper::{Adjoint, Hyper};
pub use native::NativePass;
pub use op::{Fun, Op};
pub use pattern::Pattern;
pub use reverse::Reverse;
pub use seeding::{BLOCK, Seeding};
pub use var::{Term, Var};

/// A recorded straight-line program with inputs and outputs.
#[derive(Debug, Clone)]
pub struct Tape {
    ops: Vec<Op>,
    outputs: Vec<Var>,
    /// The first `n_static` operations depend on the static inputs only (see
    /// [`Tape::split`]).
    n_static: usize,
}

/// Traces `f` at the input values `x`: returns the raw trace (operations hash-consed and
/// folded with constants, none dropped or fused: [`Tape::finish`] makes the program of some of
/// its outputs), or `None` when `f` failed or the trace branched on a value (then it is not
/// valid away from `x`).
pub fn record(x: &[f64], f: impl FnOnce(&[Var]) -> Option<Vec<Var>>) -> Option<Tape> {
    var::record_with(x, true, f)
}

impl Tape {
    /// Number of recorded operations (inputs included).
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Is the program empty?
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }
}
