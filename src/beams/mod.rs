//! Beam elements: a two-node Timoshenko beam between frames of two bodies, co-rotational
//! (Crisfield 1990, CMAME 81:131; Battini & Pacoste 2002, CMAME 191:1755; Felippa & Haugen 2005,
//! CMAME 194:2285), written once over any [`Real`] so that dual numbers differentiate it like
//! every other part of the mechanics.
//!
//! **Nodes.** Node `a` sits at `point1` of `body1`, node `b` at `point2` of `body2` (points in
//! the reference configuration; either body may be ground). Each node's triad turns with its
//! body: `R_a = A₁ E₀`, with `E₀` the element's reference axes (`e₁` along the chord as drawn,
//! `e₂` from the `reference` direction, `e₃ = e₁ × e₂`). A free node of a meshed beam is a body
//! of its own, held by joints (its mass comes from the beams it joins).
//!
//! **Element frame.** The mean of the node triads, `R_m = R_a R(½ p(R_aᵀ R_b))`, turned by the
//! smallest rotation that puts its first axis on the current chord: `R_e`. `p` are the scaled
//! modified Rodrigues parameters of [`crate::rigid::rotation_parameters_of`], rational and
//! branch-free (exact over dual numbers at the identity). The frame is objective: a rigid
//! motion of both nodes moves it rigidly.
//!
//! **Deformation** ([`Element::deformations`]): six components whose stiffnesses are diagonal
//! (the natural modes of the Timoshenko element; Argyris's natural coordinates), with
//! `ψ = p(R_eᵀ R)` the local rotations of the two nodes (equal to the rotation vector up to
//! third order) and `φ = 12EI/(κGAL²)` per bending plane:
//!
//! ```text
//! e₀ = ℓ − L + ½ ∫₀ᴸ (v′² + w′²) dx     EA/L              (stretch, with the shallow-arch term)
//! e₁ = ψ_bx − ψ_ax                      GJ/L              (twist)
//! e₂ = ψ_az + ψ_bz                      3EI₃/(L(1+φ₃))    (antisymmetric bending about e₃)
//! e₃ = ψ_bz − ψ_az                      EI₃/L             (uniform bending about e₃)
//! e₄, e₅: likewise about e₂
//! ```
//!
//! The energy `½ Σ k_c e_c²` reproduces the closed-form Timoshenko stiffness of Przemieniecki
//! (1968) in the element frame: `[[4+φ, 2−φ], [2−φ, 4+φ]] EI/(L(1+φ))` over the two end
//! rotations is `3EI/(L(1+φ))(ψ_a+ψ_b)² + EI/L (ψ_b−ψ_a)²` over two. The shallow-arch term,
//! with `v` the Timoshenko deflection relative to the chord, makes the tangent's part in the
//! axial force `N` exactly the consistent geometric stiffness (Engesser type, as in ROSS):
//! the chord carries the string term `N/ℓ (I − e₁e₁ᵀ)`, and the local slopes integrate to
//! `(r(ψ_a² + ψ_b²) − 2t ψ_aψ_b) / (30L(1+φ)²)` with `r = (4+5φ+2.5φ²)L²`,
//! `t = (1+5φ+2.5φ²)L²`. No geometric stiffness is inserted: it comes from `N` at the solved
//! equilibrium through the exact second derivative of `e₀`.
//!
//! **Inertia** ([`Element::slice`]): the section at `ξ = x/L` is a rigid slice posed by the
//! element's own interpolation, at the chord point `x_a + ξ c` moved by the Timoshenko
//! deflection and turned by the interpolated section rotation (Przemieniecki's shape functions
//! for deflection and rotation, linear for twist). [`SLICES`] Gauss–Legendre slices carry the
//! mass `w ρA L` and the inertia `w L (ρJ, ρI₂, ρI₃)`: the integrands of the linearised kinetic
//! energy are polynomials of degree at most six, so the consistent translational and rotary
//! mass and the gyroscopic matrix (Nelson & McVaugh 1976; Nelson 1980) come out exactly, and the
//! centrifugal, Coriolis and spin-softening terms follow from the same kinematics (Le, Battini &
//! Hjiaj 2014, CMAME 269:538, without their hand-derived inertia terms).

use crate::real::{D1, M3, Real, V3, axial, cst, mul3, mul3_t, mulv};
use crate::rigid::{Pose, rotation_parameters, rotation_parameters_of};

/// The number of deformation components.
pub const COMPONENTS: usize = 6;

/// The Gauss–Legendre slices of one element: `(ξ, weight)` on `[0, 1]` (four points: exact for
/// polynomials of degree seven).
pub const SLICES: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// Section properties of an element (SI units), evaluated.
#[derive(Debug, Clone, Copy)]
pub struct Section<T> {
    /// Axial stiffness `EA` (N).
    pub ea: T,
    /// Torsional stiffness `GJ` (N·m²).
    pub gj: T,
    /// Bending stiffness about `e₂` and `e₃`, `[EI₂, EI₃]` (N·m²).
    pub ei: [T; 2],
    /// Shear parameter `φ = 12EI/(κGAL²)` of bending about `e₂` and `e₃` (zero:
    /// Euler–Bernoulli).
    pub phi: [T; 2],
    /// Mass per length `ρA` (kg/m).
    pub rho_a: T,
    /// Rotary inertia per length about `e₁`, `e₂`, `e₃`: `[ρJ, ρI₂, ρI₃]` (kg·m).
    pub rho_i: [T; 3],
}

impl<T: Real> Section<T> {
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Section<U> {
        Section {
            ea: f(self.ea),
            gj: f(self.gj),
            ei: self.ei.map(f),
            phi: self.phi.map(f),
            rho_a: f(self.rho_a),
            rho_i: self.rho_i.map(f),
        }
    }
}

/// An element's geometry in the reference configuration: its bodies, node points, reference
/// axes `E₀` (columns `e₁`, `e₂`, `e₃`) and length.
#[derive(Debug, Clone)]
pub struct Element<T> {
    pub body1: Option<usize>,
    pub point1: V3<T>,
    pub body2: Option<usize>,
    pub point2: V3<T>,
    pub axes: M3<T>,
    pub length: T,
    pub section: Section<T>,
    /// Stiffness-proportional material damping `β` (s), where given: the component forces
    /// are `k (e + β ė)` ([`Element::forces`]).
    pub beta: Option<T>,
}

/// The element at one configuration, in its own frame: the node `a`'s position, the chord
/// `c = x_b − x_a` and its length, the frame `R_e` and the nodes' local rotations.
#[derive(Debug, Clone, Copy)]
pub struct Local<T: Real> {
    pub xa: V3<T>,
    pub chord: V3<T>,
    pub length: T,
    pub frame: M3<T>,
    pub psi_a: V3<T>,
    pub psi_b: V3<T>,
}

impl<T: Real> Local<T> {
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Local<U> {
        Local {
            xa: self.xa.map(f),
            chord: self.chord.map(f),
            length: f(self.length),
            frame: self.frame.map(f),
            psi_a: self.psi_a.map(f),
            psi_b: self.psi_b.map(f),
        }
    }
}

/// `[v]×`.
fn skew<T: Real>(v: &V3<T>) -> M3<T> {
    let z = cst::<T>(0.0);
    M3::new(z, -v.z, v.y, v.z, z, -v.x, -v.y, v.x, z)
}

/// The smallest rotation taking the unit vector `u` to the unit vector `v` (`u·v > −1`):
/// `I + [k]× + [k]×² / (1 + u·v)`, `k = u × v`; rational, so exact over dual numbers.
fn aligning<T: Real>(u: &V3<T>, v: &V3<T>) -> M3<T> {
    let k = skew(&u.cross(v));
    M3::identity() + k + mul3(&k, &k) / (cst::<T>(1.0) + u.dot(v))
}

/// The deflection shape functions of the end rotations (`N₂`, `N₄`) and the rotation shape
/// functions (`N_ψ2`, `N_ψ4`) of a Timoshenko element at `ξ`, end deflections zero
/// (Przemieniecki 1968; Friswell et al. 2010, §5.4.3).
fn shapes<T: Real>(xi: f64, phi: T, length: T) -> [T; 4] {
    let one = cst::<T>(1.0);
    let h = phi * cst::<T>(0.5);
    let d = one / (one + phi);
    let (x, x2, x3) = (cst::<T>(xi), cst::<T>(xi * xi), cst::<T>(xi * xi * xi));
    [
        length * d * (x3 - (cst::<T>(2.0) + h) * x2 + (one + h) * x),
        length * d * (x3 - (one - h) * x2 - h * x),
        d * (cst::<T>(3.0) * x2 - (cst::<T>(4.0) + phi) * x + one + phi),
        d * (cst::<T>(3.0) * x2 - (cst::<T>(2.0) - phi) * x),
    ]
}

/// The Timoshenko interpolation at one `ξ`: the section's deflection `d = (0, v, w)` and its
/// rotation parameters `θ = (twist, ψ_y, ψ_z)` relative to the element frame are linear in the
/// nodes' local rotations, with these shape values (constants of the slice).
#[derive(Debug, Clone, Copy)]
struct Interpolation<U: Real> {
    xi: U,
    /// [`shapes`] of bending about `e₃` and about `e₂`.
    about3: [U; 4],
    about2: [U; 4],
}

impl<U: Real> Interpolation<U> {
    /// `(d, θ)` from the nodes' rotations `a`, `b` (or from their variations). Bending about
    /// `e₃`: deflection `v` along `e₂` with slope `ψ_z`; about `e₂`: `w` along `e₃`, with
    /// `ψ_y = −w′` (the same shape functions over `(w, −ψ_y)`).
    fn at(&self, a: &V3<U>, b: &V3<U>) -> (V3<U>, V3<U>) {
        let [n2, n4, r2, r4] = self.about3;
        let (v, rz) = (n2 * a.z + n4 * b.z, r2 * a.z + r4 * b.z);
        let [n2, n4, r2, r4] = self.about2;
        let (w, ry) = (-(n2 * a.y + n4 * b.y), r2 * a.y + r4 * b.y);
        let twist = a.x + (b.x - a.x) * self.xi;
        (V3::new(cst(0.0), v, w), V3::new(twist, ry, rz))
    }
}

/// The first-order variation of a [`Local`] along a motion of its end bodies: `δx_a`, `δc`, the
/// frame's spin `δω` (`δR_e = [δω]× R_e`) and the nodes' `δψ_a`, `δψ_b`.
#[derive(Debug, Clone, Copy)]
pub struct LocalRate<T: Real> {
    pub xa: V3<T>,
    pub chord: V3<T>,
    pub spin: V3<T>,
    pub psi_a: V3<T>,
    pub psi_b: V3<T>,
}

impl<T: Real> LocalRate<T> {
    /// The variation that the dual parts of `at` carry.
    pub fn of(at: &Local<D1<T>>) -> Self {
        let eps = |v: &V3<D1<T>>| v.map(|c| c.eps);
        LocalRate {
            xa: eps(&at.xa),
            chord: eps(&at.chord),
            spin: axial(&mul3_t(&at.frame.map(|c| c.eps), &at.frame.map(|c| c.re))),
            psi_a: eps(&at.psi_a),
            psi_b: eps(&at.psi_b),
        }
    }
}

/// A slice's first-order motion as a linear map of its element's variation ([`LocalRate`]),
/// the interpolation of [`Element::section`] differentiated by hand, its shape values being
/// constants of the slice:
///
/// ```text
/// δx = δx_a + ξ δc + δω × R_e d + R_e δd,        ω = δω + R_e T(θ) δθ,
/// T(θ) = ((1 − s) I + 2[σ]× + 2σσᵀ) / (1 + s)²,  σ = θ/4, s = σᵀσ
/// ```
///
/// with `T` the tangent of [`rotation_parameters`] (`axial(δP Pᵀ) = T δθ`; Schaub & Junkins,
/// *Analytical Mechanics of Space Systems*, §3.8). Tens of operations per variation, where the
/// slice's pose over dual numbers costs hundreds.
#[derive(Debug, Clone, Copy)]
pub struct SliceMap<T: Real> {
    shapes: Interpolation<T>,
    frame: M3<T>,
    /// `R_e d`.
    offset: V3<T>,
    /// `R_e T(θ)`.
    tangent: M3<T>,
    /// The slice's centre.
    pub centre: V3<T>,
}

impl<T: Real> SliceMap<T> {
    /// The slice's spin `ω` and its centre's velocity `δx` under the variation `d`.
    pub fn motion(&self, d: &LocalRate<T>) -> (V3<T>, V3<T>) {
        let (dd, dtheta) = self.shapes.at(&d.psi_a, &d.psi_b);
        let w = d.spin + mulv(&self.tangent, &dtheta);
        let x =
            d.xa + d.chord * self.shapes.xi + d.spin.cross(&self.offset) + mulv(&self.frame, &dd);
        (w, x)
    }
}

impl<T: Real> Element<T> {
    pub fn map<U: Real>(&self, f: impl Fn(T) -> U + Copy) -> Element<U> {
        Element {
            body1: self.body1,
            point1: self.point1.map(f),
            body2: self.body2,
            point2: self.point2.map(f),
            axes: self.axes.map(f),
            length: f(self.length),
            section: self.section.map(f),
            beta: self.beta.map(f),
        }
    }

    /// The stiffness of each deformation component (see the module documentation).
    pub fn stiffness(&self) -> [T; COMPONENTS] {
        let s = &self.section;
        let l = self.length;
        let three = cst::<T>(3.0);
        let one = cst::<T>(1.0);
        [
            s.ea / l,
            s.gj / l,
            three * s.ei[1] / (l * (one + s.phi[1])),
            s.ei[1] / l,
            three * s.ei[0] / (l * (one + s.phi[0])),
            s.ei[0] / l,
        ]
    }

    /// The component forces `k (e + β ė)` from the deformations `e` and, where the element is
    /// damped, their rates `ė`.
    pub fn forces(&self, e: &[T], rates: Option<&[T]>) -> [T; COMPONENTS] {
        let k = self.stiffness();
        std::array::from_fn(|c| match (self.beta, rates) {
            (Some(beta), Some(r)) => k[c] * (e[c] + beta * r[c]),
            _ => k[c] * e[c],
        })
    }

    /// The element at the poses of its two bodies, over any scalar `U` the element's numbers
    /// lift into (dual numbers in time or along a twist).
    pub fn local<U: Real>(
        &self,
        lift: impl Fn(T) -> U + Copy,
        x1: &Pose<U>,
        x2: &Pose<U>,
    ) -> Local<U> {
        let e0 = self.axes.map(lift);
        let xa = x1.apply(&self.point1.map(lift));
        let xb = x2.apply(&self.point2.map(lift));
        let (ra, rb) = (mul3(&x1.rot, &e0), mul3(&x2.rot, &e0));
        let half = rotation_parameters_of(&mul3(&ra.transpose(), &rb)) * cst::<U>(0.5);
        let mean = mul3(&ra, &rotation_parameters(&half));
        let chord = xb - xa;
        let length = chord.dot(&chord).sqrt();
        let e1 = chord / length;
        let frame = mul3(&aligning(&mean.column(0).into_owned(), &e1), &mean);
        Local {
            xa,
            chord,
            length,
            frame,
            psi_a: rotation_parameters_of(&mul3(&frame.transpose(), &ra)),
            psi_b: rotation_parameters_of(&mul3(&frame.transpose(), &rb)),
        }
    }

    /// The deformation components at `at` (see the module documentation), pushed onto `out`.
    pub fn deformations<U: Real>(
        &self,
        lift: impl Fn(T) -> U + Copy,
        at: &Local<U>,
        out: &mut Vec<U>,
    ) {
        let l = lift(self.length);
        let (a, b) = (&at.psi_a, &at.psi_b);
        let one = cst::<U>(1.0);
        // ∫ v′² dx over the local slopes of one bending plane, rotations `(p, q)`.
        let arch = |phi: U, p: U, q: U| {
            let phi2 = phi * phi * cst::<U>(2.5);
            let r = cst::<U>(4.0) + cst::<U>(5.0) * phi + phi2;
            let t = one + cst::<U>(5.0) * phi + phi2;
            l * (r * (p * p + q * q) - cst::<U>(2.0) * t * p * q)
                / (cst::<U>(30.0) * (one + phi) * (one + phi))
        };
        let [phi2, phi3] = self.section.phi.map(lift);
        let slopes = arch(phi3, a.z, b.z) + arch(phi2, a.y, b.y);
        out.extend([
            at.length - l + slopes * cst::<U>(0.5),
            b.x - a.x,
            a.z + b.z,
            b.z - a.z,
            a.y + b.y,
            b.y - a.y,
        ]);
    }

    /// The pose of the slice at `ξ` (maps the reference configuration to the current one, as
    /// a body's pose) at `at`: `R_e Q E₀ᵀ` with [`Element::section`]'s centre and `Q`.
    pub fn slice<U: Real>(&self, lift: impl Fn(T) -> U + Copy, at: &Local<U>, xi: f64) -> Pose<U> {
        let (centre, q) = self.section(lift, at, xi);
        Pose {
            rot: mul3_t(&mul3(&at.frame, &q), &self.axes.map(lift)),
            trans: centre,
        }
    }

    /// The slice at `ξ` at `at`: its centre, and its rotation `Q` relative to the element
    /// frame (the section's axes are `R_e Q`, the element's axes at the section as it turns).
    pub fn section<U: Real>(
        &self,
        lift: impl Fn(T) -> U + Copy,
        at: &Local<U>,
        xi: f64,
    ) -> (V3<U>, M3<U>) {
        let shapes = self.interpolation(lift, xi);
        let (d, theta) = shapes.at(&at.psi_a, &at.psi_b);
        let centre = at.xa + at.chord * cst::<U>(xi) + mulv(&at.frame, &d);
        (centre, rotation_parameters(&theta))
    }

    /// The Timoshenko interpolation at `ξ` (its shape values).
    fn interpolation<U: Real>(&self, lift: impl Fn(T) -> U + Copy, xi: f64) -> Interpolation<U> {
        let l = lift(self.length);
        let [phi2, phi3] = self.section.phi.map(lift);
        Interpolation {
            xi: cst(xi),
            about3: shapes(xi, phi3, l),
            about2: shapes(xi, phi2, l),
        }
    }

    /// The first-order motion of the slice at `ξ` as a linear map of the variation of `at`
    /// ([`SliceMap`]).
    pub fn slice_map<U: Real>(
        &self,
        lift: impl Fn(T) -> U + Copy,
        at: &Local<U>,
        xi: f64,
    ) -> SliceMap<U> {
        let shapes = self.interpolation(lift, xi);
        let (d, theta) = shapes.at(&at.psi_a, &at.psi_b);
        let offset = mulv(&at.frame, &d);
        let sigma = theta * cst::<U>(0.25);
        let s = sigma.dot(&sigma);
        let one = cst::<U>(1.0);
        let two = cst::<U>(2.0);
        let tangent =
            (M3::identity() * (one - s) + skew(&sigma) * two + sigma * sigma.transpose() * two)
                / ((one + s) * (one + s));
        SliceMap {
            shapes,
            frame: at.frame,
            offset,
            tangent: mul3(&at.frame, &tangent),
            centre: at.xa + at.chord * cst::<U>(xi) + offset,
        }
    }

    /// The mass and the principal inertia (about its centre, in the section's axes `e₁`, `e₂`,
    /// `e₃`) of the element: a slice of weight `w` carries `w` times each.
    pub fn section_inertia(&self) -> (T, V3<T>) {
        let s = &self.section;
        let l = self.length;
        (
            s.rho_a * l,
            V3::new(s.rho_i[0] * l, s.rho_i[1] * l, s.rho_i[2] * l),
        )
    }

    /// The mass and the inertia (about its centre, reference axes) of the slice of weight
    /// `w`.
    pub fn slice_inertia(&self, w: f64) -> (T, M3<T>) {
        let s = &self.section;
        let wl = self.length * cst::<T>(w);
        let e0 = &self.axes;
        let d = M3::from_diagonal(&V3::new(s.rho_i[0], s.rho_i[1], s.rho_i[2]));
        (s.rho_a * wl, mul3_t(&mul3(e0, &d), e0) * wl)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual;

    /// [`SliceMap::motion`] against the slice's pose over dual numbers (the second route), at a
    /// deformed, turned configuration with shear, along a variation that moves every part of
    /// [`Local`] (the frame by a rotation, so that `δR_e = [δω]× R_e`).
    #[test]
    fn slice_map_is_the_derivative_of_the_slice_pose() {
        let d = |re: f64, eps: f64| Dual::new(re, eps);
        let v =
            |a: [(f64, f64); 3]| V3::new(d(a[0].0, a[0].1), d(a[1].0, a[1].1), d(a[2].0, a[2].1));
        let element = Element {
            body1: None,
            point1: V3::zeros(),
            body2: None,
            point2: V3::new(0.4, 0.0, 0.0),
            axes: rotation_parameters(&V3::new(0.2, -0.1, 0.3)),
            length: 0.4,
            section: Section {
                ea: 1.0,
                gj: 1.0,
                ei: [1.0, 1.0],
                phi: [0.3, 0.7],
                rho_a: 1.0,
                rho_i: [1.0, 1.0, 1.0],
            },
            beta: None,
        };
        let at = Local {
            xa: v([(0.1, 0.3), (-0.2, 0.1), (0.05, -0.7)]),
            chord: v([(0.38, -0.2), (0.05, 0.4), (-0.1, 0.25)]),
            length: d(0.4, 0.0),
            frame: rotation_parameters(&v([(0.4, 0.9), (-0.6, 0.2), (1.1, -0.5)])),
            psi_a: v([(0.05, 0.3), (-0.08, 0.7), (0.12, -0.4)]),
            psi_b: v([(-0.1, 0.2), (0.07, -0.6), (0.03, 0.5)]),
        };
        let rate = LocalRate::of(&at);
        let here = at.map(|c| c.re);
        for &(xi, _) in &SLICES {
            let pose = element.slice(Dual::from_re, &at, xi);
            let rot = pose.rot.map(|c| c.re);
            let w = axial(&mul3_t(&pose.rot.map(|c| c.eps), &rot));
            let x = pose.trans.map(|c| c.eps);
            let map = element.slice_map(|c| c, &here, xi);
            let (mw, mx) = map.motion(&rate);
            assert!((mw - w).norm() < 1e-14 * w.norm(), "{mw} against {w}");
            assert!((mx - x).norm() < 1e-14 * x.norm(), "{mx} against {x}");
            assert!((map.centre - pose.trans.map(|c| c.re)).norm() < 1e-15);
        }
    }
}
