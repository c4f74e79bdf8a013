//! Drawings of the mechanism and its modes (`modaltol draw`, the report): three orthographic
//! views in SVG ([`svg`]) and a page ([`html`]) with those views and an interactive 3-D view that
//! animates each mode over one period.
//!
//! The geometry is the [`Scene`] at the point's equilibrium; a mode is drawn as the mechanism
//! posed over its period by [`mode_frames`] (the exact kinematics at `q + a Re(v e^{iφ})`, `a`
//! scaled so the largest displacement is a tenth of the mechanism's size), so a whirling mode
//! whirls. The SVG overlays the mode's two extremes (φ = 0 and π, solid) and the quarter periods
//! (dashed) on the equilibrium (grey). The page draws with a canvas and a few lines of its own
//! script, no library and nothing fetched: it opens offline. Every view group of the SVG carries
//! its projection (`data-h`, `data-v`, `data-scale`, `data-ox`, `data-oy`: a point `x` is drawn
//! at `(ox + scale·h·x, oy − scale·v·x)`), and every mark its name, so a drawing can be read
//! back and checked against the model.

mod html;
mod svg;

pub use html::html;
pub use svg::svg;

use crate::mechanics::System;
use crate::model::{FieldError, Model};
use crate::scene::{Scene, describe, display_amplitude, mode_frames};
use crate::sweep::Point;

/// Phases drawn per period in the page's animation.
const FRAMES: usize = 24;

/// What a drawing shows: the mechanism at a point's equilibrium and each mode's motion.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Drawing {
    pub model: String,
    /// The operating speed (rad/s).
    pub speed: f64,
    pub scene: Scene,
    /// The diagonal of the box around the mechanism (m).
    pub size: f64,
    pub modes: Vec<ModeMotion>,
}

/// One mode over one period.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ModeMotion {
    /// `mode k: ω_d = … rad/s, ζ = …` (or its status where it has no frequency).
    pub label: String,
    /// The shape's scale in the frames: the mechanism is posed at `q + a Re(v e^{iφ})`.
    pub amplitude: f64,
    /// The mechanism at 24 phases over one period (frame 0: φ = 0).
    pub frames: Vec<Scene>,
}

impl Drawing {
    /// The drawing of `model` at the point `pt` solved with parameters `p`.
    pub fn new(model: &Model, p: &[f64], pt: &Point) -> Result<Drawing, FieldError> {
        let sys = System::new(model, p, pt.speed)?;
        let q = &pt.equilibrium.q;
        let scene = Scene::at(model, &sys, q);
        let size = scene.size();
        let free = &pt.linear.free;
        let modes = (pt.modes.iter().zip(&pt.shapes).enumerate())
            .map(|(k, (m, shape))| {
                let v: Vec<_> = shape.iter().copied().collect();
                let what = describe(model, &sys, q, free, &v);
                let label = if m.damped_frequency.is_finite() && m.damped_frequency > 0.0 {
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
                let amplitude = display_amplitude(model, &sys, q, free, &v, 0.1 * size);
                ModeMotion {
                    label,
                    amplitude,
                    frames: mode_frames(model, &sys, q, free, &v, amplitude, FRAMES),
                }
            })
            .collect();
        Ok(Drawing {
            model: model.name.clone(),
            speed: pt.speed,
            scene,
            size,
            modes,
        })
    }
}

/// Text for SVG and HTML: `&`, `<`, `>`, `"` escaped.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
