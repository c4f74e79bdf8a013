//! Closed-form Timoshenko beam element matrices, the independent reference of the beam element
//! (Przemieniecki 1968; Friswell et al. 2010, §5.4; Nelson & McVaugh 1976; Nelson 1980): one
//! bending plane's stiffness, consistent translational and rotary mass, gyroscopic and
//! geometric stiffness, and the twelve-dof element of a straight beam built from two planes,
//! axial and torsion.

use nalgebra::DMatrix;

/// One bending plane: bending stiffness `EI` (N·m²), shear stiffness `κGA` (N; infinite for
/// Euler–Bernoulli), mass per length `ρA` and rotary inertia per length `ρI`.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub ei: f64,
    pub ga: f64,
    pub rho_a: f64,
    pub rho_i: f64,
}

impl Plane {
    /// `φ = 12EI/(κGAL²)`.
    pub fn phi(&self, l: f64) -> f64 {
        if self.ga.is_infinite() {
            0.0
        } else {
            12.0 * self.ei / (self.ga * l * l)
        }
    }
}

fn sym(a: [[f64; 4]; 4], f: f64) -> DMatrix<f64> {
    DMatrix::from_fn(4, 4, |i, j| f * a[i][j])
}

/// One plane's `[K, M, G]` over `(v₁, θ₁, v₂, θ₂)` with `θ = v′` (Euler–Bernoulli), the rotary
/// part of the mass only where `rotary`, and the gyroscopic matrix `G = 2 M_R` (`I_p = 2I`).
pub fn plane(s: Plane, l: f64, rotary: bool) -> [DMatrix<f64>; 3] {
    let p = s.phi(l);
    let k = sym(
        [
            [12.0, 6.0 * l, -12.0, 6.0 * l],
            [6.0 * l, (4.0 + p) * l * l, -6.0 * l, (2.0 - p) * l * l],
            [-12.0, -6.0 * l, 12.0, -6.0 * l],
            [6.0 * l, (2.0 - p) * l * l, -6.0 * l, (4.0 + p) * l * l],
        ],
        s.ei / (l.powi(3) * (1.0 + p)),
    );
    let (m1, m2, m3) = (
        312.0 + 588.0 * p + 280.0 * p * p,
        (44.0 + 77.0 * p + 35.0 * p * p) * l,
        108.0 + 252.0 * p + 140.0 * p * p,
    );
    let (m4, m5, m6) = (
        (26.0 + 63.0 * p + 35.0 * p * p) * l,
        (8.0 + 14.0 * p + 7.0 * p * p) * l * l,
        (6.0 + 14.0 * p + 7.0 * p * p) * l * l,
    );
    let translational = sym(
        [
            [m1, m2, m3, -m4],
            [m2, m5, m4, -m6],
            [m3, m4, m1, -m2],
            [-m4, -m6, -m2, m5],
        ],
        s.rho_a * l / (840.0 * (1.0 + p).powi(2)),
    );
    let (r2, r3, r4) = (
        (3.0 - 15.0 * p) * l,
        (4.0 + 5.0 * p + 10.0 * p * p) * l * l,
        (-1.0 - 5.0 * p + 5.0 * p * p) * l * l,
    );
    let rotary_mass = sym(
        [
            [36.0, r2, -36.0, r2],
            [r2, r3, -r2, r4],
            [-36.0, -r2, 36.0, -r2],
            [r2, r4, -r2, r3],
        ],
        s.rho_i / (30.0 * l * (1.0 + p).powi(2)),
    );
    let gyroscopic = &rotary_mass * 2.0;
    let mass = if rotary {
        translational + rotary_mass
    } else {
        translational
    };
    [k, mass, gyroscopic]
}

/// One plane's geometric stiffness under the axial tension `tension` (N), Engesser type
/// (Przemieniecki 1968, as ROSS's `Kaf`).
pub fn geometric(s: Plane, l: f64, tension: f64) -> DMatrix<f64> {
    let p = s.phi(l);
    let a = 36.0 + 60.0 * p + 30.0 * p * p;
    let r = (4.0 + 5.0 * p + 2.5 * p * p) * l * l;
    let t = (1.0 + 5.0 * p + 2.5 * p * p) * l * l;
    sym(
        [
            [a, 3.0 * l, -a, 3.0 * l],
            [3.0 * l, r, -3.0 * l, -t],
            [-a, -3.0 * l, a, -3.0 * l],
            [3.0 * l, -t, -3.0 * l, r],
        ],
        tension / (30.0 * l * (1.0 + p).powi(2)),
    )
}

/// A straight beam's section: axial and torsional stiffness and inertia, and its two bending
/// planes: about `e₂` (deflection `w` along `e₃`, rotation `θ₂ = −w′`) and about `e₃`
/// (deflection `v` along `e₂`, `θ₃ = v′`).
#[derive(Clone, Copy, Debug)]
pub struct Beam3 {
    pub ea: f64,
    pub gj: f64,
    pub rho_a: f64,
    pub rho_j: f64,
    pub about2: Plane,
    pub about3: Plane,
}

/// The twelve-dof element `[K, M, G, K_σ]` (`K_σ` per newton of tension), dofs
/// `(u, v, w, θ₁, θ₂, θ₃)` of node `a` then node `b` in the element's axes. `G` is the
/// gyroscopic matrix of a spin about `e₁`: `C = Ω G`.
pub fn element(b: &Beam3, l: f64) -> [DMatrix<f64>; 4] {
    let mut out = [0, 1, 2, 3].map(|_| DMatrix::zeros(12, 12));
    // Axial (0, 6) and torsion (3, 9).
    for (dofs, k, m) in [
        ([0, 6], b.ea / l, b.rho_a * l / 6.0),
        ([3, 9], b.gj / l, b.rho_j * l / 6.0),
    ] {
        for (i, &r) in dofs.iter().enumerate() {
            for (j, &c) in dofs.iter().enumerate() {
                out[0][(r, c)] += if i == j { k } else { -k };
                out[1][(r, c)] += if i == j { 2.0 * m } else { m };
            }
        }
    }
    // Bending about e₃ over (v, θ₃); about e₂ over (w, −θ₂).
    let v = ([1, 5, 7, 11], [1.0; 4]);
    let w = ([2, 4, 8, 10], [1.0, -1.0, 1.0, -1.0]);
    for (plane_, (dofs, sign)) in [(b.about3, v), (b.about2, w)] {
        let [k, m, _] = plane(plane_, l, true);
        let ks = geometric(plane_, l, 1.0);
        for i in 0..4 {
            for j in 0..4 {
                let (r, c, s) = (dofs[i], dofs[j], sign[i] * sign[j]);
                out[0][(r, c)] += s * k[(i, j)];
                out[1][(r, c)] += s * m[(i, j)];
                out[3][(r, c)] += s * ks[(i, j)];
            }
        }
    }
    // Gyroscopic: C[(v, θ₃), (w, −θ₂)] = Ω Ĝ₃ and the transpose negated (a disk of polar
    // moment I_p tilted by θ₂, θ₃: M₂ = I_p Ω θ̇₃, M₃ = −I_p Ω θ̇₂). Both planes' Ĝ are equal
    // for an axisymmetric section; the one about e₃ is used.
    let [_, _, g] = plane(b.about3, l, true);
    for i in 0..4 {
        for j in 0..4 {
            let (r, c, s) = (v.0[i], w.0[j], v.1[i] * w.1[j]);
            out[2][(r, c)] += s * g[(i, j)];
            out[2][(c, r)] -= s * g[(i, j)];
        }
    }
    out
}

/// The matrices of `n` elements in a row (`element`'s dofs, node by node), the first node's
/// dofs removed when `clamped`.
pub fn assemble(parts: &[DMatrix<f64>], n: usize, clamped: bool) -> Vec<DMatrix<f64>> {
    let size = 6 * (n + 1);
    parts
        .iter()
        .map(|part| {
            let mut whole = DMatrix::zeros(size, size);
            for e in 0..n {
                let mut block = whole.view_mut((6 * e, 6 * e), (12, 12));
                block += part;
            }
            if clamped {
                whole.view((6, 6), (size - 6, size - 6)).into_owned()
            } else {
                whole
            }
        })
        .collect()
}

/// The whirl frequencies `ω > 0` of `(K − ω²M + sΩωG) φ = 0` (`s = +1` forward, `−1`
/// backward), ascending: estimated by the eigenvalues of `[0 I; M⁻¹K M⁻¹(sΩG)]`, then each
/// refined by Newton's method on the eigenvalue of the symmetric `D(ω) = K − ω²M + sΩωG`
/// nearest zero (`μ' = φᵀD'(ω)φ`), which the companion form's spread of scales would leave
/// inaccurate for the low modes.
pub fn whirl([k, m, g]: &[DMatrix<f64>; 3], spin: f64) -> Vec<f64> {
    let n = k.nrows();
    let minv = m.clone().try_inverse().unwrap();
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    a.view_mut((0, n), (n, n))
        .copy_from(&DMatrix::identity(n, n));
    a.view_mut((n, 0), (n, n)).copy_from(&(&minv * k));
    a.view_mut((n, n), (n, n)).copy_from(&(&minv * g * spin));
    let refine = |mut w: f64| {
        for _ in 0..50 {
            let d = k - m * (w * w) + g * (spin * w);
            let eig = d.symmetric_eigen();
            let j = eig.eigenvalues.iamin();
            let phi = eig.eigenvectors.column(j);
            let slope = phi.dot(&((m * (-2.0 * w) + g * spin) * phi));
            let step = eig.eigenvalues[j] / slope;
            w -= step;
            if step.abs() <= 1e-15 * w.abs() {
                break;
            }
        }
        w
    };
    let mut w: Vec<f64> = a
        .complex_eigenvalues()
        .iter()
        .filter(|z| z.im.abs() <= 1e-6 * z.norm() && z.re > 0.0)
        .map(|z| refine(z.re))
        .collect();
    w.sort_by(f64::total_cmp);
    w
}
