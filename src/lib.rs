//! modaltol: analytical tolerance analysis of the modal characteristics of multibody systems in
//! dynamic equilibrium.
//!
//! # Data flow
//!
//! Data flows one way; a module imports only modules of the layers before its own (a folder
//! module with its submodules counts as one; `tests/architecture.rs` enforces the order):
//!
//! 1. Foundations: [`real`] (the scalar trait the mechanics is generic over), [`linalg`],
//!    [`schur`], [`rigid`], [`dual4`], [`jet`] (Taylor numbers part by part), [`implicit`] (the
//!    derivatives of an implicit solution), [`settings`], [`threads`], [`cancel`], [`files`].
//! 2. Element types: [`joints`], [`cuts`], [`forces`], [`beams`], and the [`requirements`] a design
//!    must meet (each kind one file plus one list, declared by [`kinds`]).
//! 3. [`model`]: the file format, validated once into a [`model::Model`].
//! 4. [`mechanics`]: kinematics, equations of motion and constraints over any [`real::Real`].
//! 5. [`linearize`]: M̂, Ĉ, K̂ in minimal coordinates (constraint stiffness included).
//! 6. [`equations`]: the one interface to the equations of an operating point over any scalar
//!    (residual, Newton's Jacobian, the rates, the linearisation), and the direct route.
//! 7. [`equilibrium`]: the dynamic equilibrium (Newton, balanced, certified).
//! 8. [`tape`], [`program`]: the same equations recorded once per model and replayed; the
//!    caller says how ([`program::Tier`]: one point, a sweep, a long run compiled to native
//!    code) and lends the working memory ([`program::Workspace`]): no hidden state.
//! 9. [`compiled`]: a model with its [`compiled::Route`] (recorded or direct) chosen once.
//! 10. [`pair`], [`modal`], [`output`], [`frf`]: damped modes, the pair maps, the outputs, |H|.
//! 11. [`sweep`]: a point (equilibrium, linearisation, modes) and the continuation over speeds;
//!     a point is the unit everything above consumes. [`whirl`]: each mode's whirl from the
//!     orbits of the spinning parts. [`scene`]: the mechanism placed at a configuration, and
//!     its modes as motions of the bodies and ports (for drawing).
//! 12. [`sensitivity`], [`hessian`]: exact first and second derivatives through the move of
//!     the equilibrium; [`nominal_sweep`]: the nominal sweep with, at each speed, its transfer
//!     function and sensitivities (the `sweep` command's table).
//! 13. [`tolerance`]: local models (values, gradients, Hessians) and the spread of a case;
//!     [`margins`]: the requirements' margins at a point. [`peaks`]: a transfer function's
//!     peaks along the speed and their speeds, located between the swept speeds, with their
//!     exact derivatives.
//! 14. [`sampling`]: the design-variable map and the sample sweep (samples and nodes).
//! 15. [`table`]: the rows of the result's tables (`tolerance.csv`, `probabilities.csv`,
//!     `yield.csv`, `sobol.csv`), each method's own fields in one enum, put in order once.
//! 16. [`propagate`]: the propagation layer: [`propagate::Study`], [`propagate::Run`], the
//!     [`propagate::Propagation`] trait and [`propagate::Tabulate`] (a method's value writes
//!     its own rows).
//! 17. The methods: [`taylor`] (first order, second order, invariant, the first-order yield),
//!     [`quadrature`], [`montecarlo`], and [`sobol`] (global sensitivity indices).
//! 18. [`analyze`], [`allocate`] (tolerance allocation to a yield target), [`request`], [`shard`]: the main job and its rows, the analysis request
//!     both front ends check the same way, and the job's split across runs.
//! 19. [`plots`], [`drawing`] (the mechanism and its modes), [`report`], [`results`]: what is
//!     written; the command line (`src/main.rs`
//!     and `src/cli/`, a crate of its own over this one: its arguments, the inputs they name,
//!     where the results go, signals, one file per subcommand) parses and writes, the Python
//!     package binds the same library.
//!
//! The mechanics is generic over the scalar type so automatic differentiation gives exact
//! derivatives everywhere; [`program`] traces that generic code once per model ([`tape`]) so
//! that the thousands of operating points of a sweep or a Monte Carlo run evaluate a flat
//! recorded program instead of nested dual numbers.
#![deny(clippy::float_cmp)]

pub mod allocate;
pub mod analyze;
pub mod beams;
pub mod cancel;
pub mod compiled;
pub mod cuts;
pub mod drawing;
pub mod dual4;
pub mod equations;
pub mod equilibrium;
pub mod files;
pub mod forces;
pub mod frf;
pub mod hessian;
pub mod implicit;
pub mod jet;
pub mod joints;
pub mod kinds;
pub mod linalg;
pub mod linearize;
pub mod margins;
pub mod mechanics;
pub mod modal;
pub mod model;
pub mod montecarlo;
pub mod nominal_sweep;
pub mod output;
pub mod pair;
pub mod peaks;
pub mod plots;
pub mod program;
pub mod propagate;
pub mod quadrature;
pub mod real;
pub mod report;
pub mod request;
pub mod requirements;
pub mod results;
pub mod rigid;
pub mod sampling;
pub mod scene;
pub mod schur;
pub mod sensitivity;
pub mod settings;
pub mod shard;
pub mod sobol;
pub mod sweep;
pub mod table;
pub mod tape;
pub mod taylor;
pub mod threads;
pub mod tolerance;
pub mod whirl;
