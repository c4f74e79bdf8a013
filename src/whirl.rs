//! Whirl: whether a mode's orbits turn with the spin (forward) or against it (backward), as
//! rotordynamics labels the lines of a Campbell diagram (Friswell et al. 2010, §3.5 and §5.6;
//! ROSS's `whirl_direction`).
//!
//! The orbits are those of the **spinning parts' centres**: every body that spins in the steady
//! motion (its angular velocity `ω_b ≠ 0`) while its centre of mass stands still (a shaft's
//! node, a disk, a rotor; not a flyball, which the spin carries round), whatever joint or
//! element carries it. A mode's shape `v` moves such a body's centre by `d = J_v v` (ground
//! axes); across the spin axis `n = ω_b/|ω_b|`, with `e₁ ⊥ n` and `e₂ = n × e₁`, the orbit
//! `Re(u e^{iω_d t}) e₁ + Re(w e^{iω_d t}) e₂` (`u = d·e₁`, `w = d·e₂`) turns about `n` with the
//! sign of `Im(u w̄)`, and `κ = 2 Im(u w̄)/(|u|² + |w|²)` is the ratio of its minor to its major
//! axis with that sign (ROSS's `kappa`): `+1` a forward circle, `−1` a backward one, `0` a line.
//! The orbits read are the centres' translations, as rotordynamics reads a shaft's nodes; where
//! no centre translates, their tilts `r = J_ω v` across the axis (the axis' tip circles with
//! them), so a rigid rotor's conical mode, whose centre stands still, whirls as its tilt turns.
//!
//! A mode is **forward** where every orbit it moves (by more than 10⁻³ of its largest motion,
//! rotations counted at the model's size) turns forward, **backward** where every one turns
//! backward, **mixed** where both occur (ROSS's three labels); it has no whirl where no centre
//! moves across its axis (an axial or torsional mode), every orbit is a line (|κ| ≤ 10⁻⁶), or
//! nothing spins (at rest, a Campbell diagram's first speed).
//!
//! A **repeated root** (a double root at speed: an axisymmetric rotor whose bounce mode the
//! gyroscopic moments do not split) has no orbit of its own: any combination of its members'
//! shapes is a mode. The members are labelled by the combinations that turn most forward and
//! most backward, the extreme values of `Σ Im(u w̄) / Σ (|u|² + |w|²)` over the pair's shapes (a
//! 2 × 2 Hermitian pencil): a Jeffcott rotor's bounce pair at speed is one forward and one
//! backward circle at the same frequency, not two arbitrary ellipses.
//!
//! The orbit is the ground's only where the body's translations do not ride on its spin: a
//! body whose centre is moved by a coordinate of a joint that a spinning drive carries (a rotor
//! written in rotating coordinates) sees its orbit from the rotating frame, which turns it by
//! the spin; such a body is left out.

use crate::mechanics::System;
use crate::mechanics::dynamics::body_partials_for;
use crate::mechanics::ports::{least_aligned, rides_spin, steady_twist};
use crate::modal::C64;
use crate::real::{V3, lift1};

/// Below this share of a mode's largest motion (squared), a centre's orbit is not counted.
const MOVES: f64 = 1e-6;
/// An orbit whose `|κ|` is at most this is a line.
const LINE: f64 = 1e-6;
/// Roots this close (relative) are one repeated root.
const REPEATED: f64 = 1e-9;

/// A mode's whirl (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Whirl {
    Forward,
    Backward,
    Mixed,
}

impl Whirl {
    /// The word in tables: `forward`, `backward`, `mixed`.
    pub fn as_str(self) -> &'static str {
        match self {
            Whirl::Forward => "forward",
            Whirl::Backward => "backward",
            Whirl::Mixed => "mixed",
        }
    }

    /// The abbreviation of Campbell diagrams: `FW`, `BW`, `mixed`.
    pub fn short(self) -> &'static str {
        match self {
            Whirl::Forward => "FW",
            Whirl::Backward => "BW",
            Whirl::Mixed => "mixed",
        }
    }

    fn of_sign(x: f64) -> Option<Whirl> {
        if x > LINE {
            Some(Whirl::Forward)
        } else if x < -LINE {
            Some(Whirl::Backward)
        } else {
            None
        }
    }
}

/// A spinning centre: its body and the two directions across its spin axis.
struct Centre {
    body: usize,
    e1: V3<f64>,
    e2: V3<f64>,
}

/// Each mode's whirl (`None`: none) at coordinates `q` of the system `sys`, for the modes'
/// roots `lambdas` (the reported ones, `Im λ ≥ 0`) and shapes over the free coordinates `free`.
pub fn whirls<V: AsRef<[C64]>>(
    sys: &System<f64>,
    q: &[f64],
    free: &[usize],
    lambdas: &[C64],
    shapes: &[V],
) -> Vec<Option<Whirl>> {
    let none = vec![None; shapes.len()];
    let driven: Vec<usize> = (0..sys.n).filter(|&c| sys.drive[c].is_some()).collect();
    if driven.iter().all(|&c| sys.drive[c] == Some(0.0)) {
        return none;
    }
    if sys.bodies.is_empty() {
        return none;
    }
    let coords: Vec<usize> = free.iter().chain(&driven).copied().collect();
    let j = body_partials_for(&sys.map(lift1), q, &coords);
    let nb = sys.bodies.len();
    let rate = |c: usize| sys.drive[c].unwrap_or(0.0);
    // The model's size, at which rotations count as motions.
    let cms: Vec<V3<f64>> = (0..nb)
        .map(|b| j.pose[b].apply(&sys.bodies[b].cm))
        .collect();
    // (The diagonal of the centres of mass' bounding box.)
    let (lo, hi) = (cms.iter()).fold((cms[0], cms[0]), |(lo, hi), c| (lo.inf(c), hi.sup(c)));
    let size = (hi - lo).norm().max(1e-3);
    let mut centres = Vec::new();
    for b in 0..nb {
        let (w, v) = steady_twist(sys, &j, &driven, rate, b);
        let spin = w.norm();
        if spin == 0.0 || v.norm() > 1e-9 * spin * size {
            continue;
        }
        // Translations riding on a spinning drive: the orbit is seen from the rotating frame.
        if rides_spin(sys, &j, (free, &driven), |d| rate(d) != 0.0, b) {
            continue;
        }
        let n = w / spin;
        let e1 = crate::rigid::perpendicular(&n, &least_aligned(&n));
        centres.push(Centre {
            body: b,
            e1,
            e2: n.cross(&e1),
        });
    }
    if centres.is_empty() {
        return none;
    }
    // Each body's partial velocities over the free coordinates, once for every mode.
    let rows: Vec<Vec<(V3<f64>, V3<f64>)>> = (0..nb)
        .map(|b| {
            free.iter()
                .map(|&c| (j.jv(sys, c, b), j.jw(sys, c, b)))
                .collect()
        })
        .collect();
    // Per mode: each centre's (u, w), and the mode's largest motion.
    let orbits: Vec<Orbits> = shapes
        .iter()
        .map(|v| {
            let v = v.as_ref();
            let moved = |b: usize| {
                let (mut d, mut r) = ([C64::new(0.0, 0.0); 3], [C64::new(0.0, 0.0); 3]);
                for ((jv, jw), &vi) in rows[b].iter().zip(v) {
                    for k in 0..3 {
                        d[k] += vi * jv[k];
                        r[k] += vi * jw[k];
                    }
                }
                (d, r)
            };
            let norm = |x: &[C64; 3]| x.iter().map(C64::norm_sqr).sum::<f64>();
            let motions: Vec<_> = (0..nb).map(moved).collect();
            let largest = (motions.iter())
                .map(|(d, r)| norm(d) + size * size * norm(r))
                .fold(0.0f64, f64::max);
            let across = |d: &[C64; 3], e: &V3<f64>| d[0] * e.x + d[1] * e.y + d[2] * e.z;
            // The centres' translations, else (where none moves) their tilts at the model's
            // size.
            let orbit = |x: &[C64; 3], c: &Centre, scale: f64| {
                (across(x, &c.e1) * scale, across(x, &c.e2) * scale)
            };
            Orbits {
                shifts: (centres.iter())
                    .map(|c| orbit(&motions[c.body].0, c, 1.0))
                    .collect(),
                tilts: (centres.iter())
                    .map(|c| orbit(&motions[c.body].1, c, size))
                    .collect(),
                largest,
            }
        })
        .collect();
    let mut out: Vec<Option<Whirl>> = orbits.iter().map(one).collect();
    // Repeated roots: the extreme combinations of each pair.
    for a in 0..lambdas.len() {
        for b in a + 1..lambdas.len() {
            let close = (lambdas[a] - lambdas[b]).norm() <= REPEATED * lambdas[a].norm();
            if close && lambdas[a].norm() > 0.0 {
                let [fa, fb] = pair(&orbits[a], &orbits[b]);
                out[a] = fa;
                out[b] = fb;
            }
        }
    }
    out
}

/// A mode's orbits `(u, w)` at the centres, their translations and tilts, and its largest
/// motion (squared).
struct Orbits {
    shifts: Vec<(C64, C64)>,
    tilts: Vec<(C64, C64)>,
    largest: f64,
}

impl Orbits {
    /// Do the centres translate (else only their tilts are read)?
    fn shift(&self) -> bool {
        self.shifts.iter().any(|o| moves(o, self.largest))
    }
}

/// The whirl of one mode.
fn one(o: &Orbits) -> Option<Whirl> {
    let (uw, largest) = (if o.shift() { &o.shifts } else { &o.tilts }, o.largest);
    let mut seen = (false, false);
    for (u, w) in uw.iter().filter(|o| moves(o, largest)) {
        let s = u.norm_sqr() + w.norm_sqr();
        match Whirl::of_sign(2.0 * (u * w.conj()).im / s) {
            Some(Whirl::Forward) => seen.0 = true,
            Some(_) => seen.1 = true,
            None => {}
        }
    }
    match seen {
        (true, false) => Some(Whirl::Forward),
        (false, true) => Some(Whirl::Backward),
        (true, true) => Some(Whirl::Mixed),
        (false, false) => None,
    }
}

/// Does the orbit `(u, w)` move, against a mode's largest motion (squared)?
fn moves((u, w): &(C64, C64), largest: f64) -> bool {
    let s = u.norm_sqr() + w.norm_sqr();
    s > MOVES * largest && s > 0.0
}

/// A repeated root's two members: the most forward and the most backward combination of
/// their shapes, `μ` the extreme values of `cᴴGc / cᴴSc` with `G = Σ (B − Bᴴ)/2i`,
/// `B_kj = u_j w̄_k`, and `S = Σ (ūu + w̄w)` over the centres both move.
fn pair(a: &Orbits, b: &Orbits) -> [Option<Whirl>; 2] {
    let largest = a.largest.max(b.largest);
    let (ua, ub) = if a.shift() || b.shift() {
        (&a.shifts, &b.shifts)
    } else {
        (&a.tilts, &b.tilts)
    };
    let (mut g, mut s) = ([[C64::new(0.0, 0.0); 2]; 2], [[C64::new(0.0, 0.0); 2]; 2]);
    for (x, y) in ua.iter().zip(ub) {
        let (u, w) = ([x.0, y.0], [x.1, y.1]);
        if u.iter().chain(&w).map(C64::norm_sqr).sum::<f64>() <= MOVES * largest {
            continue;
        }
        for k in 0..2 {
            for l in 0..2 {
                let bkl = u[l] * w[k].conj();
                let blk = u[k] * w[l].conj();
                g[k][l] += (bkl - blk.conj()) / C64::new(0.0, 2.0);
                s[k][l] += u[k].conj() * u[l] + w[k].conj() * w[l];
            }
        }
    }
    // det(G − μS) = 0: a μ² − b μ + c = 0, real roots for a definite S.
    let det = |m: [[C64; 2]; 2]| (m[0][0] * m[1][1] - m[0][1] * m[1][0]).re;
    let qa = det(s);
    if qa <= 0.0 {
        return [None, None];
    }
    let qb = (g[0][0] * s[1][1] + g[1][1] * s[0][0] - g[0][1] * s[1][0] - g[1][0] * s[0][1]).re;
    let qc = det(g);
    let root = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
    let (hi, lo) = ((qb + root) / (2.0 * qa), (qb - root) / (2.0 * qa));
    // κ = 2μ, as for one orbit.
    [Whirl::of_sign(2.0 * hi), Whirl::of_sign(2.0 * lo)]
}

/// [`whirls`] of every mode of the point `pt` of `model` solved with parameters `p`.
pub fn of_point(
    model: &crate::model::Model,
    p: &[f64],
    pt: &crate::sweep::Point,
) -> Result<Vec<Option<Whirl>>, crate::model::FieldError> {
    let sys = System::new(model, p, pt.speed)?;
    let lambdas: Vec<C64> = pt.modes.iter().map(|m| m.root.lambda).collect();
    let shapes: Vec<Vec<C64>> = (pt.shapes.iter())
        .map(|s| s.iter().copied().collect())
        .collect();
    Ok(whirls(
        &sys,
        &pt.equilibrium.q,
        &pt.linear.free,
        &lambdas,
        &shapes,
    ))
}
