//! Linearisation about the dynamic equilibrium in minimal coordinates (Kim & Yoo 2007,
//! eqs. 15–22).
//!
//! With `R` a basis of the null space of `Φ_{q_R}` (coordinate partitioning,
//! `R = [−Φ_u⁻¹ Φ_v; I]` in dependent/independent order):
//!
//! ```text
//! M̂ = Rᵀ (∂r_R/∂q̈_R) R,   Ĉ = Rᵀ (∂r_R/∂q̇_R) R,   K̂ = Rᵀ ∂(r_R + Φ_{q_R}ᵀ λ)/∂q_R R
//! ```
//!
//! with `λ` held fixed in `K̂`: that term is the stiffness of the constraint forces, and leaving it
//! out gives wrong eigenvalues for any mechanism with loaded cut joints. `Ĉ` holds damping and
//! gyroscopic terms; `Ĉ` and `K̂` need not be symmetric. Written over any [`Real`] so the same
//! code gives the matrices' derivatives with respect to design variables.

use crate::linalg::{jacobian, pivot_columns, solve};
use crate::mechanics::dynamics::{Lifted, evaluate_rows, evaluate_with, mass_matrix, partials_for};
use crate::mechanics::ports::{UnbalanceLoad, Vectors};
use crate::real::{D1, Real, cst, lift1};
use nalgebra::DMatrix;

/// Why the linearisation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearizeError {
    #[error(
        "the constraint Jacobian is rank deficient at the equilibrium (redundant or locked cut joints)"
    )]
    RankDeficient,
    #[error(
        "the chosen independent coordinates do not parametrise the constraints here (Φ_u is singular)"
    )]
    BadIndependent,
}

/// Linearised equations of motion at an equilibrium.
#[derive(Debug, Clone)]
pub struct Linearization<T: Real> {
    /// Coordinate indices of `q_R` (free coordinates).
    pub free: Vec<usize>,
    /// Coordinate indices of the independent coordinates (one per degree of freedom).
    pub independent: Vec<usize>,
    /// `R`: `q_R` perturbation = `R z`, `n_R × n_dof`.
    pub basis: DMatrix<T>,
    /// `∂r_R/∂q̈_R`, `∂r_R/∂q̇_R`, `∂(r_R + Φ_Rᵀλ)/∂q_R` in all free coordinates.
    pub m_full: DMatrix<T>,
    pub c_full: DMatrix<T>,
    pub k_full: DMatrix<T>,
    /// `Φ_R`, constraint equations × free coordinates (`0 × n_R` without constraints).
    pub phi: DMatrix<T>,
    /// Reduced `M̂`, `Ĉ`, `K̂` (`n_dof × n_dof`).
    pub m: DMatrix<T>,
    pub c: DMatrix<T>,
    pub k: DMatrix<T>,
    /// `Rᵀ b` for each of the model's ports (see [`crate::mechanics::ports`]): its force
    /// vector in the independent coordinates; empty until [`Linearization::with_ports`].
    pub ports: Vec<Vec<T>>,
    /// Each of the model's unbalances' load, reduced to the independent coordinates likewise.
    pub unbalances: Vec<UnbalanceLoad<T>>,
}

impl<T: Real> Linearization<T> {
    /// The same linearisation with every number mapped by `f` (one direction of a
    /// [`crate::dual4::Dual4`] linearisation, say).
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Linearization<U> {
        Linearization {
            free: self.free.clone(),
            independent: self.independent.clone(),
            basis: self.basis.map(f),
            m_full: self.m_full.map(f),
            c_full: self.c_full.map(f),
            k_full: self.k_full.map(f),
            phi: self.phi.map(f),
            m: self.m.map(f),
            c: self.c.map(f),
            k: self.k.map(f),
            ports: self
                .ports
                .iter()
                .map(|b| b.iter().map(|&v| f(v)).collect())
                .collect(),
            unbalances: self.unbalances.iter().map(|u| u.map(f)).collect(),
        }
    }

    /// Number by number, `f` of this linearisation's and `other`'s (two linearisations of one
    /// point, over different scalars: the parts of two directions joined into one number).
    pub fn zip<U: Real, V: Real>(
        &self,
        other: &Linearization<U>,
        f: impl Fn(T, U) -> V + Copy,
    ) -> Linearization<V> {
        let both = |a: &DMatrix<T>, b: &DMatrix<U>| a.zip_map(b, f);
        Linearization {
            free: self.free.clone(),
            independent: self.independent.clone(),
            basis: both(&self.basis, &other.basis),
            m_full: both(&self.m_full, &other.m_full),
            c_full: both(&self.c_full, &other.c_full),
            k_full: both(&self.k_full, &other.k_full),
            phi: both(&self.phi, &other.phi),
            m: both(&self.m, &other.m),
            c: both(&self.c, &other.c),
            k: both(&self.k, &other.k),
            ports: self
                .ports
                .iter()
                .zip(&other.ports)
                .map(|(a, b)| zip_vec(a, b, f))
                .collect(),
            unbalances: (self.unbalances.iter())
                .zip(&other.unbalances)
                .map(|(a, b)| UnbalanceLoad {
                    re: zip_vec(&a.re, &b.re, f),
                    im: zip_vec(&a.im, &b.im, f),
                    spin: f(a.spin, b.spin),
                })
                .collect(),
        }
    }

    /// Attaches the ports' vectors `b` and the unbalances' loads over the free coordinates,
    /// reduced to `Rᵀ b`.
    pub fn with_ports(mut self, full: Vectors<T>) -> Self {
        let reduce = |b: &[T]| -> Vec<T> {
            (0..self.basis.ncols())
                .map(|k| {
                    b.iter()
                        .enumerate()
                        .fold(cst::<T>(0.0), |s, (i, &v)| s + self.basis[(i, k)] * v)
                })
                .collect()
        };
        let ports = full.ports.iter().map(|b| reduce(b)).collect();
        let unbalances = (full.unbalances.iter())
            .map(|u| UnbalanceLoad {
                re: reduce(&u.re),
                im: reduce(&u.im),
                spin: u.spin,
            })
            .collect();
        self.ports = ports;
        self.unbalances = unbalances;
        self
    }
}

/// `f` of two vectors' numbers, pairwise.
fn zip_vec<T: Copy, U: Copy, V>(a: &[T], b: &[U], f: impl Fn(T, U) -> V) -> Vec<V> {
    a.iter().zip(b).map(|(&x, &y)| f(x, y)).collect()
}

/// Chooses independent coordinates: the user's, or by complete pivoting on `Φ_{q_R}` (the
/// best-conditioned dependent set). Returns coordinate indices.
pub fn choose_independent(
    phi_r: &DMatrix<f64>,
    free: &[usize],
    user: Option<&[usize]>,
) -> Result<Vec<usize>, LinearizeError> {
    if let Some(u) = user {
        return Ok(u.to_vec());
    }
    let dependent = pivot_columns(phi_r).ok_or(LinearizeError::RankDeficient)?;
    Ok((0..free.len())
        .filter(|k| !dependent.contains(k))
        .map(|k| free[k])
        .collect())
}

/// The steady motion a linearisation is taken about: the coordinates `q`, their rates `q̇`
/// (the driven coordinates' speeds; zero for the others) and the multipliers `λ`
/// (`q̈ = 0`).
#[derive(Debug, Clone, Copy)]
pub struct SteadyState<'a, T> {
    pub q: &'a [T],
    pub qd: &'a [T],
    pub lambda: &'a [T],
}

/// Linearises at `at`. `l` is the system lifted to `Dual<T>`, `free` its free coordinates;
/// `independent` are coordinate indices from [`choose_independent`]. `stiffness`, when given,
/// is `∂(r_R + Φ_Rᵀλ)/∂q_R` already known (Newton's last Jacobian) and is not recomputed.
pub fn linearize<T: Real>(
    l: &Lifted<D1<T>>,
    free: &[usize],
    at: SteadyState<'_, T>,
    independent: &[usize],
    stiffness: Option<&DMatrix<T>>,
) -> Result<Linearization<T>, LinearizeError> {
    let SteadyState { q, qd, lambda } = at;
    let n = q.len();
    let nf = free.len();
    let lam: Vec<D1<T>> = lambda.iter().map(|&v| lift1(v)).collect();
    let lift = |v: &[T]| -> Vec<D1<T>> { v.iter().map(|&x| lift1(x)).collect() };
    let (q1, qd1, qdd1) = (lift(q), lift(qd), vec![lift1(cst::<T>(0.0)); n]);
    let xr: Vec<T> = free.iter().map(|&i| q[i]).collect();
    let rows = |qq: &[D1<T>], vv: &[D1<T>], aa: &[D1<T>]| -> Vec<D1<T>> {
        let g = evaluate_rows(l, qq, vv, aa, free).with_multipliers(&lam);
        free.iter().map(|&i| g[i]).collect()
    };
    let put = |base: &[D1<T>], x: &[D1<T>]| {
        let mut out = base.to_vec();
        for (k, &i) in free.iter().enumerate() {
            out[i] = x[k];
        }
        out
    };
    let k_full = match stiffness {
        Some(k) => k.clone(),
        None => jacobian(&xr, |x| rows(&put(&q1, x), &qd1, &qdd1)).1,
    };
    // M and C: the partial velocities depend on q only; compute them once, over T. M is
    // JᵀMJ from them directly (r is linear in q̈); C by dual passes in q̇.
    let jt = partials_for(&l.base, q, free);
    let m_full = mass_matrix(&l.base, &jt, free);
    let j = jt.map(lift1);
    let rows_v = |vv: &[D1<T>], aa: &[D1<T>]| -> Vec<D1<T>> {
        let g = evaluate_with(l, &j, &q1, vv, aa).with_multipliers(&lam);
        free.iter().map(|&i| g[i]).collect()
    };
    let vr: Vec<T> = free.iter().map(|&i| qd[i]).collect();
    let (_, c_full) = jacobian(&vr, |x| rows_v(&put(&qd1, x), &qdd1));
    let phi_r = DMatrix::from_fn(l.base.m, nf, |k, c| j.phi_q[(k, free[c])].re);
    reduce(free, independent, &phi_r, [m_full, c_full, k_full])
}

/// The reduced matrices from the full ones `[M, C, K]` (over the free coordinates `free`): `R`
/// from `Φ_R` (`m × n_R`) and the independent coordinates, then `M̂ = Rᵀ M R` and likewise
/// `Ĉ`, `K̂`.
pub fn reduce<T: Real>(
    free: &[usize],
    independent: &[usize],
    phi_r: &DMatrix<T>,
    [m_full, c_full, k_full]: [DMatrix<T>; 3],
) -> Result<Linearization<T>, LinearizeError> {
    let basis = null_basis(free, independent, phi_r)?;
    // Without constraints the basis is the identity: the matrices are their own reductions (two
    // dense products each were a tenth of a 160-segment chain's sensitivities, over duals).
    let reduce = |a: &DMatrix<T>| {
        if phi_r.nrows() == 0 {
            a.clone()
        } else {
            basis.tr_mul(&(a * &basis))
        }
    };
    Ok(Linearization {
        free: free.to_vec(),
        independent: independent.to_vec(),
        m: reduce(&m_full),
        c: reduce(&c_full),
        k: reduce(&k_full),
        basis,
        m_full,
        c_full,
        k_full,
        phi: phi_r.clone(),
        ports: Vec::new(),
        unbalances: Vec::new(),
    })
}

/// `R`, the basis of the null space of `Φ_R` (`m × n_R`, over the free coordinates `free`)
/// by coordinate partitioning: the identity on the `independent` coordinates, `−Φ_u⁻¹ Φ_v` on
/// the others; the identity without constraints.
pub fn null_basis<T: Real>(
    free: &[usize],
    independent: &[usize],
    phi_r: &DMatrix<T>,
) -> Result<DMatrix<T>, LinearizeError> {
    let nf = free.len();
    if phi_r.nrows() == 0 {
        return Ok(DMatrix::identity(nf, nf));
    }
    let ind: Vec<usize> = independent
        .iter()
        .map(|c| {
            free.iter()
                .position(|f| f == c)
                .expect("independent ⊂ free")
        })
        .collect();
    let dep: Vec<usize> = (0..nf).filter(|k| !ind.contains(k)).collect();
    let phi_u = DMatrix::from_fn(dep.len(), dep.len(), |r, c| phi_r[(r, dep[c])]);
    let phi_v = DMatrix::from_fn(dep.len(), ind.len(), |r, c| phi_r[(r, ind[c])]);
    let x = solve(&phi_u, &phi_v).ok_or(LinearizeError::BadIndependent)?;
    let mut r = DMatrix::from_element(nf, ind.len(), cst::<T>(0.0));
    for (c, &k) in ind.iter().enumerate() {
        r[(k, c)] = cst(1.0);
    }
    for (row, &k) in dep.iter().enumerate() {
        for c in 0..ind.len() {
            r[(k, c)] = -x[(row, c)];
        }
    }
    Ok(r)
}
