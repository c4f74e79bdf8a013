//! modaltol: analytical tolerance analysis of the modal characteristics of multibody systems in
//! dynamic equilibrium.
//!
//! Data flows one way: [`model`] (file format, validation) → [`mechanics`] (kinematics,
//! equations of motion, constraints) → [`equilibrium`] → [`linearize`] → [`modal`] → [`sweep`]
//! → [`report`]. The mechanics is generic over the scalar type ([`real::Real`]) so automatic
//! differentiation gives exact derivatives everywhere; [`program`] traces that generic code once
//! per model ([`tape`]) so that the thousands of operating points of a sweep or a Monte Carlo run
//! evaluate a flat recorded program instead of nested dual numbers.
#![deny(clippy::float_cmp)]

pub mod analyze;
pub mod cancel;
pub mod compiled;
pub mod cuts;
pub mod dual4;
pub mod equilibrium;
pub mod files;
pub mod forces;
pub mod frf;
pub mod hessian;
pub mod joints;
pub mod linalg;
pub mod linearize;
pub mod mechanics;
pub mod modal;
pub mod model;
pub mod montecarlo;
pub mod output;
pub mod pair;
pub mod plots;
pub mod program;
pub mod propagate;
pub mod quadrature;
pub mod real;
pub mod report;
pub mod results;
pub mod rigid;
pub mod route;
pub mod sampling;
pub mod schur;
pub mod sensitivity;
pub mod settings;
pub mod shard;
pub mod study;
pub mod sweep;
pub mod tape;
pub mod taylor;
pub mod threads;
pub mod tolerance;
