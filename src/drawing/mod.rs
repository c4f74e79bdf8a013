//! Drawings of the mechanism and its modes (`modaltol draw`, the report): three orthographic
//! views in SVG ([`svg`]) and a page ([`html`]) with those views and an interactive 3-D view that
//! animates each mode over one period.
//!
//! The geometry is the [`Scene`] at the point's equilibrium, every vector of it (a point or a
//! direction) with the body that placed it ([`Anchor`]). A mode is drawn as its motion to first
//! order in its amplitude `a` (scaled so the largest displacement is a tenth of the
//! mechanism's size): each body's centre of mass moves by `Re(a d e^{iφ})` and the body turns by
//! `Re(a ω e^{iφ})` (the mode's [`PhysicalShape`], exact partial velocities), so a point `x` of
//! body `b` moves by `Re(a (d_b + ω_b × (x − c_b)) e^{iφ})` and a direction `u` turns by
//! `Re(a ω_b e^{iφ}) × u` (kept unit), a point inside a beam's curve by the curve's Hermite
//! combination of its nodes' motions: the pose at `q + a Re(v e^{iφ})` to `O(a²)`
//! ([`ModeMotion::frame`]), and a whirling mode whirls. This is what the page carries: the
//! equilibrium once, and per mode six complex numbers a body, from which its script poses every
//! frame itself, so the page grows with the bodies times the modes it animates, not with its
//! frames ([`html`] bounds it). The SVG overlays the mode's two extremes (φ = 0 and π, solid)
//! and the quarter periods (dashed) on the equilibrium (grey). The page draws with a canvas and
//! a few lines of its own script, no library and nothing fetched: it opens offline. Every view
//! group of the SVG carries its projection (`data-h`, `data-v`, `data-scale`, `data-ox`,
//! `data-oy`: a point `x` is drawn at `(ox + scale·h·x, oy − scale·v·x)`), and every mark its
//! name, so a drawing can be read back and checked against the model.

mod html;
mod svg;

pub use html::{MOTION_BUDGET, animated, html};
pub use svg::svg;

use crate::mechanics::System;
use crate::modal::C64;
use crate::model::{FieldError, Model};
use crate::scene::{Along, Anchor, P3, PhysicalShape, Scene, describe, hermite, physical_shapes};
use crate::sweep::Point;

/// What a drawing shows: the mechanism at a point's equilibrium and each mode's motion.
#[derive(Debug, Clone)]
pub struct Drawing {
    pub model: String,
    /// The operating speed (rad/s).
    pub speed: f64,
    pub scene: Scene,
    /// The body that placed each vector of `scene`, in the order of [`Scene::map`].
    pub anchors: Vec<Anchor>,
    /// The diagonal of the box around the mechanism (m).
    pub size: f64,
    pub modes: Vec<ModeMotion>,
    /// The ground axes the views are drawn in ([`Axes::of_gravity`]): up against gravity.
    pub axes: Axes,
}

/// The ground axes a drawing is seen along: `up` the axis (±x, ±y or ±z) nearest against
/// gravity (+y where there is none), `across` the first other axis of x, y, z drawn to the right
/// in the front view, and `toward` = `across × up` pointing at its viewer. The front view looks
/// along −`toward`, the top view down along −`up`, the side view along −`across` (third-angle
/// projection); in a y-up model they are the ground's x, y, z. A z-up model's front view is an
/// elevation too, not a plan.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Axes {
    pub across: P3,
    pub up: P3,
    pub toward: P3,
}

impl Axes {
    /// The axes of a model whose gravity is `g` (m/s², ground axes).
    pub fn of_gravity(g: P3) -> Axes {
        let unit = |k: usize, sign: f64| {
            let mut e = [0.0; 3];
            e[k] = sign;
            e
        };
        let k = (0..3)
            .max_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
            .unwrap_or(1);
        let up = if g[k] == 0.0 || !g[k].is_finite() {
            unit(1, 1.0)
        } else {
            unit(k, -g[k].signum())
        };
        let axis = up.iter().position(|&x| x != 0.0).unwrap_or(1);
        let across = unit(if axis == 0 { 1 } else { 0 }, 1.0);
        let toward = [
            across[1] * up[2] - across[2] * up[1],
            across[2] * up[0] - across[0] * up[2],
            across[0] * up[1] - across[1] * up[0],
        ];
        Axes { across, up, toward }
    }
}

/// The largest semi-axis of a body's solid that is drawn, as a share of the mechanism's size
/// ([`Scene::size`]).
pub const SOLID_SHARE: f64 = 0.5;

/// The largest semi-axis of the ellipsoid with shape matrix `s` (m): the square root of its
/// largest eigenvalue.
pub fn largest_semi_axis(s: &[[f64; 3]; 3]) -> f64 {
    let m = nalgebra::Matrix3::from_fn(|i, j| s[i][j]);
    let largest = m.symmetric_eigenvalues().max();
    if largest > 0.0 { largest.sqrt() } else { 0.0 }
}

/// One mode's motion, to first order in its amplitude.
#[derive(Debug, Clone)]
pub struct ModeMotion {
    /// `mode k: ω_d = … rad/s, ζ = …` (or its status where it has no frequency).
    pub label: String,
    /// The mode oscillates (a damped frequency above zero): what the page animates first.
    pub oscillates: bool,
    /// The shape's scale `a`: the motion is that of the pose at `q + a Re(v e^{iφ})`.
    pub amplitude: f64,
    /// Per body: the displacement of its centre of mass (m) and its small rotation (rad,
    /// ground axes) at that amplitude, `a` times the mode's [`PhysicalShape`].
    pub motion: Vec<[[C64; 3]; 2]>,
}

/// `a × b` for complex `a` and real `b`.
fn cross(a: &[C64; 3], b: &P3) -> [C64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The first-order motion of the vector `x` placed by `anchor` in `scene`, where the bodies
/// move by `motion` (per body: displacement and rotation, complex).
fn moved(scene: &Scene, motion: &[[[C64; 3]; 2]], anchor: &Anchor, x: &P3) -> [C64; 3] {
    let zero = [C64::new(0.0, 0.0); 3];
    if let Some(along) = anchor.along {
        return moved_along(scene, motion, &along);
    }
    let Some(b) = anchor.body else {
        return zero;
    };
    let [d, w] = &motion[b];
    if anchor.direction {
        cross(w, x)
    } else {
        let c = scene.bodies[b].cm;
        let turned = cross(w, &[x[0] - c[0], x[1] - c[1], x[2] - c[2]]);
        [d[0] + turned[0], d[1] + turned[1], d[2] + turned[2]]
    }
}

/// The first-order motion of a point inside a beam's curve: the curve's Hermite combination
/// ([`crate::scene::CurveMark`]) of its nodes' motions and of its tangents' turns,
/// `H₁ δa + H₂ L (ωₐ × tₐ) + H₃ δb + H₄ L (ω_b × t_b)`.
fn moved_along(scene: &Scene, motion: &[[[C64; 3]; 2]], along: &Along) -> [C64; 3] {
    let c = &scene.beams[along.beam];
    let h = hermite(along.xi);
    let ends = [c.points[0], c.points[c.points.len() - 1]];
    let mut out = [C64::new(0.0, 0.0); 3];
    for k in 0..2 {
        let Some(b) = c.nodes[k] else { continue };
        let node = Anchor {
            body: Some(b),
            direction: false,
            along: None,
        };
        let at = moved(scene, motion, &node, &ends[k]);
        let turn = cross(&motion[b][1], &c.tangents[k]);
        for i in 0..3 {
            out[i] += at[i] * h[2 * k] + turn[i] * (h[2 * k + 1] * c.length);
        }
    }
    out
}

impl ModeMotion {
    /// The mechanism at phase `φ` (rad) of this mode, to first order: every point `x` moved by,
    /// and every direction `u` turned by, `Re(δ e^{iφ})` with `δ` its motion (see the module
    /// documentation), a direction then scaled back to unit length. Equal to the mechanism
    /// posed at `q + a Re(v e^{iφ})` to `O(a²)`; what the page's script draws.
    pub fn frame(&self, d: &Drawing, phase: f64) -> Scene {
        let turn = C64::from_polar(1.0, phase);
        let mut k = 0;
        d.scene.map(&mut |x: &P3| {
            let anchor = &d.anchors[k];
            k += 1;
            let m = moved(&d.scene, &self.motion, anchor, x);
            let y = [0, 1, 2].map(|c| x[c] + (m[c] * turn).re);
            if anchor.direction {
                let n = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
                if n > 0.0 { y.map(|c| c / n) } else { *x }
            } else {
                y
            }
        })
    }
}

/// The amplitude at which the motion `unit` (per body, per unit of the shape) moves a vector of
/// `scene` by at most `reach` (m): the largest displacement of a point, or of the tip of a
/// direction drawn a twentieth of the mechanism's size `size` long (so a turn about a link's
/// own line shows), along the shape's real and its imaginary part. Zero for a shape that moves
/// nothing.
fn amplitude(
    scene: &Scene,
    anchors: &[Anchor],
    unit: &[[[C64; 3]; 2]],
    size: f64,
    reach: f64,
) -> f64 {
    let mut k = 0;
    let mut most = 0.0f64;
    scene.map(&mut |x: &P3| {
        let anchor = &anchors[k];
        k += 1;
        let m = moved(scene, unit, anchor, x);
        let arm = if anchor.direction { 0.05 * size } else { 1.0 };
        let re = m.iter().map(|z| z.re * z.re).sum::<f64>().sqrt();
        let im = m.iter().map(|z| z.im * z.im).sum::<f64>().sqrt();
        most = most.max(arm * re.max(im));
    });
    if most > 0.0 && most.is_finite() {
        reach / most
    } else {
        0.0
    }
}

impl Drawing {
    /// The drawing of `model` at the point `pt` solved with parameters `p`.
    pub fn new(model: &Model, p: &[f64], pt: &Point) -> Result<Drawing, FieldError> {
        let sys = System::new(model, p, pt.speed)?;
        let q = &pt.equilibrium.q;
        let (mut scene, anchors) = Scene::anchored(model, &sys, q);
        let size = scene.size();
        // A solid larger than the mechanism would hide it: textbook inertias need not fit
        // the links drawn (Haug's governor's 1 kg collar has 0.15 kg·m², an ellipsoid of
        // 0.6 m radius on a 0.3 m mechanism). Those are drawn as their links alone.
        for b in &mut scene.bodies {
            if largest_semi_axis(&b.solid) > SOLID_SHARE * size {
                b.solid = [[0.0; 3]; 3];
            }
        }
        let free = &pt.linear.free;
        let shapes: Vec<Vec<C64>> = (pt.shapes.iter())
            .map(|s| s.iter().copied().collect())
            .collect();
        let physical = physical_shapes(&sys, q, free, &shapes);
        let lambdas: Vec<C64> = pt.modes.iter().map(|m| m.root.lambda).collect();
        let whirls = crate::whirl::whirls(&sys, q, free, &lambdas, &shapes);
        let modes = (pt.modes.iter().zip(&shapes).zip(&physical).enumerate())
            .map(|(k, ((m, v), shape))| {
                let what = describe(model, free, v, whirls[k]);
                let oscillates = m.damped_frequency.is_finite() && m.damped_frequency > 0.0;
                let label = if oscillates {
                    format!(
                        "mode {} ({what}): ω_d = {:.4} rad/s, ζ = {:.4}",
                        k + 1,
                        m.damped_frequency,
                        m.damping_ratio
                    )
                } else {
                    format!(
                        "mode {} ({what}): {} (λ = {:.4})",
                        k + 1,
                        m.class.as_str(),
                        m.root.lambda.re
                    )
                };
                let unit = body_motion(shape, 1.0);
                let a = amplitude(&scene, &anchors, &unit, size, 0.1 * size);
                ModeMotion {
                    label,
                    oscillates,
                    amplitude: a,
                    motion: body_motion(shape, a),
                }
            })
            .collect();
        let g = [sys.gravity.x, sys.gravity.y, sys.gravity.z];
        Ok(Drawing {
            axes: Axes::of_gravity(g),
            model: model.name.clone(),
            speed: pt.speed,
            scene,
            anchors,
            size,
            modes,
        })
    }
}

/// Per body: `a` times the displacement and the rotation of `shape`.
fn body_motion(shape: &PhysicalShape, a: f64) -> Vec<[[C64; 3]; 2]> {
    (shape.displacement.iter().zip(&shape.rotation))
        .map(|(d, w)| [d.map(|z| z * a), w.map(|z| z * a)])
        .collect()
}

/// Text for SVG and HTML: `&`, `<`, `>`, `"` escaped.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
