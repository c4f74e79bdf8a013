//! The drawing as a self-contained page: the three views (SVG) and a 3-D view on a canvas that
//! turns with the mouse and animates the mode chosen (see the module documentation of
//! [`super`]). The script is this file's own, a few dozen lines; nothing is fetched.

use super::{Drawing, esc, svg};

/// The page of drawing `d`, opening on mode `mode` (0-based; the equilibrium where `None`).
/// `#mode=K` in the address (1-based, 0: the equilibrium) chooses the mode as well.
pub fn html(d: &Drawing, mode: Option<usize>) -> String {
    let data = serde_json::to_string(d)
        .unwrap_or_else(|_| "null".into())
        .replace("</", "<\\/");
    let options: String = std::iter::once("<option value=\"-1\">equilibrium</option>".to_string())
        .chain(
            d.modes
                .iter()
                .enumerate()
                .map(|(k, m)| format!("<option value=\"{k}\">{}</option>", esc(&m.label))),
        )
        .collect();
    let start = mode.map_or(-1, |k| k as i64);
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
<p class="note">The mechanism at its equilibrium at {speed} rad/s (units: m). 3-D view: drag to turn, wheel to zoom; choose a mode to animate it over one period (amplitude scaled to a tenth of the mechanism's size; the equilibrium in grey). Orthographic views below.</p>
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
