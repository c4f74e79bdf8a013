//! The propagation methods as the tables name them.

/// Propagation methods, as named in the outputs. A yield is given by [`Method::FirstOrder`],
/// [`Method::Quadrature`] and [`Method::MonteCarlo`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    FirstOrder,
    SecondOrder,
    /// ω_d from the pair invariants (see [`crate::tolerance`]).
    Invariant,
    MonteCarlo,
    /// The whole pipeline integrated over the distribution ([`crate::quadrature`]).
    Quadrature,
    /// The answer to read: [`Method::Quadrature`] where it ran and gave a value; otherwise
    /// the automatic choice among the Taylor methods (for ω_d the invariant method within
    /// [`crate::tolerance::KINK_SIGMAS`] σ of a change of class, otherwise second order where
    /// it exists, else first order). The row's `basis` says which.
    Analytic,
}

impl Method {
    pub fn as_str(self) -> &'static str {
        match self {
            Method::FirstOrder => "first_order",
            Method::SecondOrder => "second_order",
            Method::Invariant => "invariant",
            Method::MonteCarlo => "monte_carlo",
            Method::Quadrature => "quadrature",
            Method::Analytic => "analytic",
        }
    }
}
