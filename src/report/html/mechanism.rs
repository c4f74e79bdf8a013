//! The report's section on the mechanism and its modes: the drawing at the middle of the
//! speeds analysed (`mechanism.svg`, and `mechanism.html` with every mode animated), the first
//! modes' shapes (`mode_K.svg`), and the modal assurance criterion across the speed range: how
//! the modes were tracked from speed to speed.

use super::esc;
use crate::analyze::Analysis;
use crate::drawing::Drawing;
use crate::modal::C64;
use crate::scene::mac;
use std::fmt::Write;

/// How many modes' shapes the report draws.
pub const MODES_DRAWN: usize = 3;

/// The section, for the drawing `d` (its files written beside the report).
pub fn mechanism_section(h: &mut String, a: &Analysis, d: &Drawing) {
    let _ = writeln!(
        h,
        "<h2>The mechanism and its modes</h2><p>At {} rad/s (the middle of the speeds analysed), nominal parameters: three orthographic views (m). <a href=\"mechanism.html\">Open the 3-D view</a>: turn it with the mouse and animate any mode over one period (it works offline).</p><figure><img src=\"mechanism.svg\" alt=\"the mechanism\"></figure>",
        d.speed
    );
    for (k, m) in d.modes.iter().take(MODES_DRAWN).enumerate() {
        let _ = writeln!(
            h,
            "<figure><img src=\"mode_{}.svg\" alt=\"mode {}\"><figcaption>{}: the equilibrium grey, the extremes of one period blue and red, the quarter periods dashed (amplitude scaled to a tenth of the mechanism's size).</figcaption></figure>",
            k + 1,
            k + 1,
            esc(&m.label)
        );
    }
    mac_tables(h, a);
}

/// The MAC between the modes at the lowest and the highest speed analysed, and per mode the
/// lowest MAC between consecutive speeds along the sweep (a mode tracked by its shape keeps a
/// MAC near 1; a low one marks a crossing or a veering).
fn mac_tables(h: &mut String, a: &Analysis) {
    let points: Vec<&crate::sweep::Point> = a.nominal.iter().flatten().collect();
    let (Some(lo), Some(hi)) = (points.first(), points.last()) else {
        return;
    };
    let shape = |p: &crate::sweep::Point, m: usize| -> Vec<C64> {
        p.shapes
            .get(m)
            .map_or_else(Vec::new, |s| s.iter().copied().collect())
    };
    let n = lo.shapes.len().min(hi.shapes.len());
    if n == 0 {
        return;
    }
    let _ = writeln!(
        h,
        "<h3>Modal assurance criterion</h3><p>MAC = |φ<sub>a</sub><sup>H</sup>φ<sub>b</sub>|² / (|φ<sub>a</sub>|²|φ<sub>b</sub>|²) of the shapes in the free coordinates: rows the modes at {} rad/s, columns at {} rad/s.</p><table><tr><th></th>{}</tr>",
        lo.speed,
        hi.speed,
        (1..=n)
            .map(|j| format!("<th>mode {j}</th>"))
            .collect::<String>()
    );
    for i in 0..n {
        let _ = write!(h, "<tr><th>mode {}</th>", i + 1);
        for j in 0..n {
            let v = mac(&shape(lo, i), &shape(hi, j));
            let shade = (255.0 - 120.0 * v.clamp(0.0, 1.0)).round() as u8;
            let _ = write!(
                h,
                "<td style=\"background:rgb({shade},{shade},255)\">{v:.3}</td>"
            );
        }
        let _ = writeln!(h, "</tr>");
    }
    let _ = writeln!(h, "</table>");
    let _ = writeln!(
        h,
        "<p>Tracking: per mode, the lowest MAC between its shapes at consecutive speeds, and where.</p><table><tr><th>mode</th><th>lowest MAC</th><th>between (rad/s)</th></tr>"
    );
    for m in 0..n {
        let worst = points
            .windows(2)
            .filter(|w| w[0].shapes.len() > m && w[1].shapes.len() > m)
            .map(|w| {
                (
                    mac(&shape(w[0], m), &shape(w[1], m)),
                    w[0].speed,
                    w[1].speed,
                )
            })
            .min_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((v, s0, s1)) = worst {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{v:.4}</td><td>{s0} – {s1}</td></tr>",
                m + 1
            );
        }
    }
    let _ = writeln!(h, "</table>");
}
