//! Whether a mode's roots are differentiable at a point, and if not why: one test for every
//! derivative the methods use.

use super::{C64, Mode, ModeClass};

/// Whether a mode's roots are differentiable functions of the system's parameters at a point,
/// and if not, why. Derivatives (first-order sensitivities, the Taylor methods' gradients and
/// Hessians) exist for a root exactly where it is simple; one test for all of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Smoothness {
    /// Both roots are simple: every quantity of the mode is differentiable.
    Simple,
    /// The mode's two roots coincide (it is changing between underdamped and overdamped): ω_d
    /// has a kink there; the pair's sum and product stay smooth.
    Coalescing,
    /// A root coincides with a root of another mode (0-based index), as two modes of a
    /// symmetric rotor at rest do: neither is differentiable by itself. Where the variables
    /// move the repeated root as one, each member is ([`crate::modal::cluster`]).
    Repeated { other: usize },
    /// A rigid-body mode (a zero root): no frequency or damping ratio to differentiate.
    Rigid,
}

impl std::fmt::Display for Smoothness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Smoothness::Simple => write!(f, "its roots are simple"),
            Smoothness::Coalescing => write!(
                f,
                "its two roots coincide (it is changing between underdamped and overdamped)"
            ),
            Smoothness::Repeated { other } => {
                write!(
                    f,
                    "a root of it is repeated in mode {} (a double root that the variables \
                     split, or only nearly repeated)",
                    other + 1
                )
            }
            Smoothness::Rigid => write!(f, "it is a rigid-body mode (a zero root)"),
        }
    }
}

/// Relative distance below which two roots count as one: `|λ − μ| ≤ SIMPLE_GAP · max(|λ|, |μ|)`.
/// The roots carry rounding of about `ε cond`; their derivatives grow like the inverse of
/// the gap, so that within a millionth they would carry more rounding than information.
pub const SIMPLE_GAP: f64 = 1e-6;

/// Each mode's [`Smoothness`] among all the roots of `modes`: scale-invariant (relative gaps
/// only), so that scaling every mass, damper and spring of a model leaves it unchanged.
pub fn smoothness(modes: &[Mode]) -> Vec<Smoothness> {
    let close = |a: C64, b: C64| (a - b).norm() <= SIMPLE_GAP * a.norm().max(b.norm());
    let roots = |m: &Mode| [m.root.lambda, m.partner.lambda];
    modes
        .iter()
        .enumerate()
        .map(|(i, md)| {
            if md.class == ModeClass::Rigid {
                return Smoothness::Rigid;
            }
            let repeated = modes.iter().enumerate().find(|(j, other)| {
                *j != i
                    && other.class != ModeClass::Rigid
                    && roots(md)
                        .iter()
                        .any(|&a| roots(other).iter().any(|&b| close(a, b)))
            });
            match repeated {
                Some((other, _)) => Smoothness::Repeated { other },
                None if close(md.root.lambda, md.partner.lambda) => Smoothness::Coalescing,
                None => Smoothness::Simple,
            }
        })
        .collect()
}
