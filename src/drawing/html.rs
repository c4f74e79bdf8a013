//! The drawing as a self-contained page: the three views (SVG) and a 3-D view on a canvas that
//! turns with the mouse and animates the mode chosen (see the module documentation of
//! [`super`]). The script is this file's own, a few dozen lines; nothing is fetched.
//!
//! The page's data (`#data`, JSON) is the equilibrium once and, per mode animated, the bodies'
//! motion: `size` (m); `axes` (`across`, `up`, `toward`: the ground axes the 3-D view turns
//! from, up against gravity); `scene`, the [`Scene`] with each vector replaced by its index `i`;
//! `x`, the vectors at the equilibrium (`x[3i..3i+3]`); `anchor`, per vector `b + 1` for a point
//! placed by body `b`, `−(b + 1)` for a direction turned by it, 0 for the ground's; `modes`, each
//! with its `number` (1-based), `label`, and `re`, `im`: per body its displacement (m) and
//! rotation (rad) at the drawn amplitude, six numbers a body. Points are rounded to a millionth
//! of the mechanism's size, motions to that or a millionth (m, rad), the finer: far below a
//! pixel.
//! The modes animated are the lowest that fit [`MOTION_BUDGET`] ([`animated`]), with the mode
//! asked for.

use super::{Drawing, esc, svg};
use crate::scene::Scene;
use serde::ser::{Serialize, SerializeSeq, Serializer};

/// The most numbers of motion the page carries (six real and six imaginary a body and mode):
/// at most about 3 MB of text (1.3 MB for a 150-body chain's), so that the modes keep the page
/// a few MB whatever the model's size (its equilibrium and views grow with the bodies alone).
/// About 150 bodies fit all their modes.
pub const MOTION_BUDGET: usize = 300_000;

/// The modes (0-based) that a page of a mechanism of `bodies` bodies with `modes` modes
/// animates: the lowest that fit [`MOTION_BUDGET`] (at least one), and `chosen` besides.
pub fn animated(bodies: usize, modes: usize, chosen: Option<usize>) -> Vec<usize> {
    let fit = (MOTION_BUDGET / (12 * bodies.max(1))).max(1).min(modes);
    let mut out: Vec<usize> = (0..fit).collect();
    if let Some(k) = chosen.filter(|&k| k >= fit && k < modes) {
        out.push(k);
    }
    out
}

/// Numbers written with `decimals` decimals (an integer where that is exact).
struct Rounded<'a> {
    values: &'a [f64],
    decimals: usize,
}

impl Serialize for Rounded<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.values.len()))?;
        for &x in self.values {
            let text = format!("{x:.*}", self.decimals);
            let text = match text.contains('.') {
                true => text.trim_end_matches('0').trim_end_matches('.'),
                false => &text,
            };
            match text.parse::<i64>() {
                Ok(n) => seq.serialize_element(&n)?,
                // Not finite: null.
                Err(_) => seq.serialize_element(&text.parse::<f64>().unwrap_or(f64::NAN))?,
            }
        }
        seq.end()
    }
}

#[derive(serde::Serialize)]
struct PageMode<'a> {
    number: usize,
    label: &'a str,
    re: Rounded<'a>,
    im: Rounded<'a>,
}

#[derive(serde::Serialize)]
struct Page<'a> {
    size: f64,
    /// The ground axes the view is turned from: `up` drawn up ([`super::Axes`]).
    axes: super::Axes,
    scene: Scene<usize>,
    x: Rounded<'a>,
    anchor: Vec<i64>,
    modes: Vec<PageMode<'a>>,
}

/// The decimals that resolve a millionth of `size` (m).
fn decimals(size: f64) -> usize {
    (6.0 - size.log10().floor()).clamp(0.0, 17.0) as usize
}

/// The page of drawing `d`, opening on mode `mode` (0-based; the equilibrium where `None`).
/// `#mode=K` in the address (1-based, 0: the equilibrium) chooses the mode as well.
pub fn html(d: &Drawing, mode: Option<usize>) -> String {
    let shown = animated(d.scene.bodies.len(), d.modes.len(), mode);
    let mut x = Vec::new();
    let parts = mode_parts(d, &shown);
    let page = page(d, &shown, &parts, &mut x);
    let data = serde_json::to_string(&page)
        .unwrap_or_else(|_| "null".into())
        .replace("</", "<\\/");
    let options: String =
        std::iter::once("<option value=\"-1\">equilibrium</option>".to_string())
            .chain(shown.iter().enumerate().map(|(i, &k)| {
                format!("<option value=\"{i}\">{}</option>", esc(&d.modes[k].label))
            }))
            .collect();
    // The mode asked for, else the first that oscillates: the page opens moving.
    let start = mode
        .and_then(|k| shown.iter().position(|&s| s == k))
        .or_else(|| shown.iter().position(|&k| d.modes[k].oscillates))
        .map_or(-1, |i| i as i64);
    let lowest = animated(d.scene.bodies.len(), d.modes.len(), None).len();
    let which = if lowest < d.modes.len() {
        let also = match shown.get(lowest) {
            Some(k) => format!(" and mode {}", k + 1),
            None => String::new(),
        };
        format!(
            " This page animates modes 1 to {lowest} of {}{also}, to stay a few MB: <code>modaltol draw --mode K</code> adds mode K.",
            d.modes.len()
        )
    } else {
        String::new()
    };
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 16px; color: #222; }}
#view {{ border: 1px solid #ccc; cursor: grab; display: block; }}
.bar {{ margin: 8px 0; }}
.note {{ color: #555; font-size: 13px; }}
</style></head>
<body>
<h1 style="font-size:20px">{title}</h1>
<p class="note">The mechanism at its equilibrium at {speed} rad/s (units: m). 3-D view: drag to turn, wheel to zoom; choose a mode to animate it over one period (to first order in its amplitude, scaled to a tenth of the mechanism's size; the equilibrium in grey).{which} Orthographic views below.</p>
<div class="bar"><label>Show <select id="mode">{options}</select></label>
<button id="play">pause</button> <span id="phase" class="note"></span></div>
<canvas id="view" width="900" height="560" data-frame="0" data-start="{start}"></canvas>
<h2 style="font-size:16px">Orthographic views</h2>
{svg}
<script id="data" type="application/json">{data}</script>
<script>
{script}</script>
</body></html>
"#,
        title = esc(&format!("{} at {} rad/s", d.model, d.speed)),
        speed = d.speed,
        svg = svg(d, None),
        script = include_str!("viewer.js"),
    )
}

/// The real and imaginary parts of each `shown` mode's motion, flattened as the page reads them.
fn mode_parts(d: &Drawing, shown: &[usize]) -> Vec<[Vec<f64>; 2]> {
    (shown.iter())
        .map(|&k| {
            let flat = |part: fn(&crate::modal::C64) -> f64| {
                (d.modes[k].motion.iter())
                    .flat_map(|[dx, w]| dx.iter().chain(w).map(part))
                    .collect()
            };
            [flat(|z| z.re), flat(|z| z.im)]
        })
        .collect()
}

/// The page's data: the scene with its points numbered into `x` (three coordinates each), each
/// point's anchor (`b + 1` for a point of body `b`, `−(b + 1)` for a direction, 0 on the
/// ground) and the `shown` modes with their motions' `parts` ([`mode_parts`]).
fn page<'a>(
    d: &'a Drawing,
    shown: &[usize],
    parts: &'a [[Vec<f64>; 2]],
    x: &'a mut Vec<f64>,
) -> Page<'a> {
    let scene = d.scene.map(&mut |v| {
        x.extend_from_slice(v);
        x.len() / 3 - 1
    });
    let anchor = (d.anchors.iter())
        .map(|a| {
            a.body.map_or(0, |b| {
                if a.direction {
                    -(b as i64 + 1)
                } else {
                    b as i64 + 1
                }
            })
        })
        .collect();
    let length = decimals(d.size);
    Page {
        size: d.size,
        axes: d.axes,
        scene,
        x: Rounded {
            values: x,
            decimals: length,
        },
        anchor,
        modes: (shown.iter().zip(parts))
            .map(|(&k, [re, im])| PageMode {
                number: k + 1,
                label: &d.modes[k].label,
                re: Rounded {
                    values: re,
                    decimals: length.max(6),
                },
                im: Rounded {
                    values: im,
                    decimals: length.max(6),
                },
            })
            .collect(),
    }
}
