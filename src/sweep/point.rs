//! What one speed gives: the point, its branch and where Newton started, or why it failed.

use crate::equilibrium::{Equilibrium, EquilibriumError};
use crate::linearize::{Linearization, LinearizeError};
use crate::modal::{C64, ModalError, Mode, ModeClass};
use crate::model::FieldError;
use nalgebra::DVector;

/// Why a speed produced no result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointError {
    #[error("{0}")]
    Field(#[from] FieldError),
    #[error("equilibrium: {0}")]
    Equilibrium(#[from] EquilibriumError),
    #[error("linearisation: {0}")]
    Linearize(#[from] LinearizeError),
    #[error("modes: {0}")]
    Modal(#[from] ModalError),
    #[error("{0}")]
    Unbalance(String),
}

impl From<crate::mechanics::ports::PortError> for PointError {
    fn from(e: crate::mechanics::ports::PortError) -> Self {
        use crate::mechanics::ports::PortError;
        match e {
            PortError::Field(f) => PointError::Field(f),
            other => PointError::Unbalance(other.to_string()),
        }
    }
}

/// Everything computed at one speed.
#[derive(Debug, Clone)]
pub struct Point {
    pub speed: f64,
    pub equilibrium: Equilibrium,
    pub linear: Linearization<f64>,
    pub modes: Vec<Mode>,
    /// Shape of each mode in the free coordinates (`R x`), for tracking.
    pub shapes: Vec<DVector<C64>>,
    /// Remarks, e.g. a switch to the stable branch.
    pub note: Option<String>,
    /// The equilibrium continued from the previous speed was unstable and this point is on
    /// the stable branch found instead: the coordinates of that unstable equilibrium.
    pub switched_from: Option<Vec<f64>>,
    /// This point is on another branch than the previous speed's: the branch followed lost
    /// its stability and the sweep switched (see [`Sweep::step`](super::Sweep::step)).
    pub new_branch: bool,
    /// Which equilibrium this is and why it is the one reported.
    pub branch: Branch,
}

/// Where Newton started from.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Origin {
    /// The model's initial guess (the joints' `initial` values).
    InitialGuess,
    /// The solution at the previous speed of a sweep (extrapolated).
    Continued { speed: f64 },
    /// Coordinates the caller gave.
    Given,
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::InitialGuess => write!(f, "the model's initial guess"),
            Origin::Continued { speed } => write!(f, "the solution at {speed} rad/s"),
            Origin::Given => write!(f, "the coordinates given"),
        }
    }
}

/// Which equilibrium a point is on. Where a mechanism has several equilibria at a speed (a
/// pendulum past its bifurcation: hanging, and tilted either way), the one reported depends on
/// where Newton starts; this says which and why, in every output.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Branch {
    /// Where Newton started from.
    pub origin: Origin,
    pub kind: BranchKind,
}

/// Whether the equilibrium reached is the one reported.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum BranchKind {
    /// The equilibrium Newton reached is stable.
    Stable,
    /// The equilibrium Newton reached is unstable through its mode `mode` (0-based here,
    /// 1-based in JSON; among that equilibrium's modes, which are not reported) with the root
    /// `re + i·im`; the stable one found by stepping `amplitude` (rad or m at the largest coordinate) along that mode's
    /// shape (its real or imaginary part, `sign`) is reported instead.
    Switched {
        #[serde(serialize_with = "one_based")]
        mode: usize,
        re: f64,
        im: f64,
        imaginary_part: bool,
        sign: f64,
        amplitude: f64,
    },
    /// The equilibrium Newton reached is unstable through `mode` (0-based here, 1-based in
    /// JSON; among the point's modes) and reported as it is:
    /// `searched` says whether a stable one was looked for along the unstable modes (and none
    /// found) or not (switching off, [`Options::no_branch_switch`](super::Options::no_branch_switch),
    /// or `flutter_only`).
    Unstable {
        #[serde(serialize_with = "one_based")]
        mode: usize,
        re: f64,
        im: f64,
        searched: bool,
        /// The stiffness `K̂`'s symmetric part is positive definite: `K̂` is regular, so no
        /// equilibrium branches off this one, and the instability is flutter (circulatory
        /// forces or negative damping): there is no stable equilibrium nearby to look for.
        #[serde(skip_serializing_if = "std::ops::Not::not")]
        flutter_only: bool,
    },
}

/// Writes a 0-based mode index as the 1-based number every output shows.
fn one_based<S: serde::Serializer>(mode: &usize, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(*mode as u64 + 1)
}

impl Branch {
    /// `stable`, `switched` or `unstable`.
    pub fn as_str(&self) -> &'static str {
        match self.kind {
            BranchKind::Stable => "stable",
            BranchKind::Switched { .. } => "switched",
            BranchKind::Unstable { .. } => "unstable",
        }
    }
}

impl std::fmt::Display for Branch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let root = |mode: Option<usize>, re: f64, im: f64| {
            let how = if im == 0.0 {
                "a positive real root: static divergence"
            } else {
                "a complex pair with positive real part: flutter"
            };
            let which = mode.map_or("a mode".to_string(), |k| format!("mode {}", k + 1));
            format!("{which} has λ = {re:.6e} {im:+.6e}i, {how}")
        };
        match self.kind {
            BranchKind::Stable => {
                write!(f, "the equilibrium reached from {} is stable", self.origin)
            }
            BranchKind::Switched {
                mode: _,
                re,
                im,
                imaginary_part,
                sign,
                amplitude,
            } => write!(
                f,
                "the equilibrium reached from {} is unstable ({}); switched to the stable \
                 equilibrium found by stepping {amplitude} along {}{} of that mode's shape",
                self.origin,
                root(None, re, im),
                if sign < 0.0 { "minus " } else { "" },
                if imaginary_part {
                    "the imaginary part"
                } else {
                    "the real part"
                },
            ),
            BranchKind::Unstable {
                mode,
                re,
                im,
                searched,
                flutter_only,
            } => write!(
                f,
                "the equilibrium reached from {} is unstable ({}); {}",
                self.origin,
                root(Some(mode), re, im),
                if searched {
                    "no stable equilibrium was found along its unstable modes' shapes"
                } else if flutter_only {
                    "its stiffness is positive definite, so no other equilibrium branches off \
                     it: reported as reached"
                } else {
                    "reported as reached (no search for a stable branch)"
                }
            ),
        }
    }
}

impl Point {
    /// Is every mode stable?
    pub fn stable(&self) -> bool {
        self.modes.iter().all(|m| m.class != ModeClass::Unstable)
    }
}
