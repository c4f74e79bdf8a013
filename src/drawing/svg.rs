//! The three orthographic views as SVG (see the module documentation of [`super`]).

use super::{Axes, Drawing, ModeMotion, esc};
use crate::scene::{P3, Scene};
use std::fmt::Write;

/// A view: its name, and the ground directions drawn rightwards and upwards.
struct View {
    name: String,
    h: P3,
    v: P3,
}

/// The three views of a drawing seen along `axes` (third-angle projection): the front looking
/// along −`toward`, the top looking down along −`up`, the side looking along −`across`; in a
/// y-up model the front looks along −z, the top along −y, the side along −x.
fn views(axes: &Axes) -> [View; 3] {
    let neg = |a: P3| a.map(|x| -x);
    let name = |a: P3| {
        let k = a.iter().position(|&x| x != 0.0).unwrap_or(0);
        format!(
            "{}{}",
            if a[k] < 0.0 { "−" } else { "" },
            ["x", "y", "z"][k]
        )
    };
    let view = |what: &str, h: P3, v: P3| View {
        name: format!("{what} ({} →, {} ↑)", name(h), name(v)),
        h,
        v,
    };
    [
        view("front", axes.across, axes.up),
        view("top", axes.across, neg(axes.toward)),
        view("side", neg(axes.toward), axes.up),
    ]
}

/// The front view's names: gathered while the marks are drawn, one label per point (the names
/// of marks drawn at one point, as a node's joint, body and port, joined: the first two and how
/// many more), then written ([`Labels::write`]) each beside its point at the first of a few
/// places around it that lies inside the panel and overlaps no label written before, moving
/// outwards a line at a time; a name with no such place is left out (the marks carry every
/// name as `data-name`). Boxes from the font size: a glyph about 0.6 em wide.
struct Labels {
    /// Per point: where (px), and its names with their ranks and colours.
    points: Vec<((f64, f64), Vec<Named>)>,
    /// The box the labels must stay in: `[x0, y0, x1, y1]` (px).
    within: [f64; 4],
}

/// A name at a point, with its rank and colour.
type Named = (Rank, String, &'static str);

/// The names' font size (px), the SVG's.
const FONT: f64 = 10.0;

impl Labels {
    fn new(within: [f64; 4]) -> Labels {
        Labels {
            points: Vec::new(),
            within,
        }
    }

    /// Adds `name` (in `colour`, where it is the first at its point) to the mark at `at`.
    fn add(&mut self, at: (f64, f64), name: &str, rank: Rank, colour: &'static str) {
        let same = |p: &(f64, f64)| (p.0 - at.0).abs() < 1.0 && (p.1 - at.1).abs() < 1.0;
        let entry = (rank, name.to_string(), colour);
        match self.points.iter_mut().find(|(p, _)| same(p)) {
            Some((_, names)) => names.push(entry),
            None => self.points.push((at, vec![entry])),
        }
    }

    /// Writes the labels.
    fn write(self, s: &mut String) {
        let mut taken: Vec<[f64; 4]> = Vec::new();
        let [x0, y0, x1, y1] = self.within;
        for ((x, y), mut named) in self.points {
            // The names that say most first (a disk before the frames of its shaft's node),
            // each once.
            named.sort_by_key(|(rank, _, _)| *rank);
            let colour = named.first().map_or(INK, |n| n.2);
            let mut names: Vec<String> = Vec::new();
            for (_, name, _) in named {
                if !names.contains(&name) {
                    names.push(name);
                }
            }
            let text = match &names[..] {
                [a] => a.clone(),
                [a, b] => format!("{a}, {b}"),
                [a, b, rest @ ..] => format!("{a}, {b} +{}", rest.len()),
                [] => continue,
            };
            let w = 0.6 * FONT * text.chars().count() as f64;
            let fits = |b: &[f64; 4]| {
                b[0] >= x0
                    && b[2] <= x1
                    && b[1] >= y0
                    && b[3] <= y1
                    && (taken.iter())
                        .all(|o| b[2] <= o[0] || o[2] <= b[0] || b[3] <= o[1] || o[3] <= b[1])
            };
            // Baselines: right above, right below, left above, left below; then further out.
            let place = (0..8)
                .flat_map(|k| {
                    let step = k as f64 * (FONT + 2.0);
                    [
                        (x + 7.0, y - 7.0 - step),
                        (x + 7.0, y + 12.0 + step),
                        (x - 7.0 - w, y - 7.0 - step),
                        (x - 7.0 - w, y + 12.0 + step),
                    ]
                })
                .map(|(bx, by)| (bx, by, [bx, by - 0.8 * FONT, bx + w, by + 0.2 * FONT]))
                .find(|(_, _, b)| fits(b));
            if let Some((bx, by, b)) = place {
                taken.push(b);
                let _ = writeln!(
                    s,
                    r##"<text class="label" x="{bx}" y="{by}" fill="{colour}">{}</text>"##,
                    esc(&text)
                );
            }
        }
    }
}

/// Which of the names at one point a label gives first: a body with mass (a disk, a link),
/// a port, a joint, then a body without (a beam's node, a frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Rank {
    Solid,
    Port,
    Joint,
    Frame,
}

/// Width and height of a view's panel (px).
const PANEL: f64 = 360.0;
/// Margin inside a panel (px).
const MARGIN: f64 = 30.0;
/// Height of the title above the panels (px).
const TITLE: f64 = 44.0;

fn dot(a: &P3, b: &P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Where a view draws: `(ox + s·h·x, oy − s·v·x)`.
struct Projection {
    s: f64,
    ox: f64,
    oy: f64,
    h: P3,
    v: P3,
    /// Where names may go: the panel less its title line and its axes mark, `[x0, y0, x1, y1]`.
    panel: [f64; 4],
}

impl Projection {
    fn at(&self, x: &P3) -> (f64, f64) {
        (
            self.ox + self.s * dot(&self.h, x),
            self.oy - self.s * dot(&self.v, x),
        )
    }
}

/// The colours of the layers: the mechanism, the mode's extremes, its quarter periods.
const INK: &str = "#333";
const BEAM: &str = "#8c564b";
const EXTREMES: [&str; 2] = ["#1f77b4", "#d62728"];
const QUARTERS: &str = "#9467bd";

/// The mechanism in three orthographic views, with mode `mode` (0-based) overlaid where given.
pub fn svg(d: &Drawing, mode: Option<usize>) -> String {
    let width = 3.0 * PANEL;
    let height = PANEL + TITLE;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="10" data-size="{}">"#,
        d.size
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let mode = mode.and_then(|k| d.modes.get(k));
    heading(&mut s, d, mode);
    // The mode at its quarter periods (φ = 0, π/2, π, 3π/2), to first order as the page
    // animates it.
    let quarters: Vec<Scene> = mode.map_or_else(Vec::new, |m| {
        (0..4)
            .map(|k| m.frame(d, std::f64::consts::FRAC_PI_2 * k as f64))
            .collect()
    });
    // One scale for the three views: the largest extent of any view fits its panel.
    let scenes: Vec<&Scene> = std::iter::once(&d.scene).chain(&quarters).collect();
    let views = views(&d.axes);
    let extent = views
        .iter()
        .flat_map(|view| {
            let span = |axis: &P3| {
                let (lo, hi) = range(&scenes, axis);
                hi - lo
            };
            [span(&view.h), span(&view.v)]
        })
        .fold(0.0f64, f64::max);
    let scale = (PANEL - 2.0 * MARGIN) / if extent > 0.0 { extent } else { d.size };
    for (k, view) in views.iter().enumerate() {
        let centre = |axis: &P3| {
            let (lo, hi) = range(&scenes, axis);
            if lo.is_finite() { (lo + hi) / 2.0 } else { 0.0 }
        };
        let x0 = k as f64 * PANEL;
        let pr = Projection {
            s: scale,
            ox: x0 + PANEL / 2.0 - scale * centre(&view.h),
            oy: TITLE + PANEL / 2.0 + scale * centre(&view.v),
            h: view.h,
            v: view.v,
            panel: [
                x0 + 6.0,
                TITLE + 20.0,
                x0 + PANEL - 6.0,
                TITLE + PANEL - 40.0,
            ],
        };
        let _ = writeln!(
            s,
            r#"<g class="view" data-view="{}" data-scale="{}" data-ox="{}" data-oy="{}" data-h="{},{},{}" data-v="{},{},{}">"#,
            k, pr.s, pr.ox, pr.oy, pr.h[0], pr.h[1], pr.h[2], pr.v[0], pr.v[1], pr.v[2]
        );
        let _ = writeln!(
            s,
            r##"<rect x="{}" y="{TITLE}" width="{}" height="{PANEL}" fill="none" stroke="#ccc"/>"##,
            x0 + 2.0,
            PANEL - 4.0
        );
        let _ = writeln!(
            s,
            r##"<text x="{}" y="{}" fill="#555">{}</text>"##,
            x0 + 8.0,
            TITLE + 14.0,
            esc(&view.name)
        );
        axes_mark(&mut s, &pr, x0);
        match &quarters[..] {
            [zero, quarter, half, three_quarters] => {
                scene(&mut s, &pr, &d.scene, Layer::Background, d.size);
                for q in [quarter, three_quarters] {
                    scene(&mut s, &pr, q, Layer::Quarter, d.size);
                }
                scene(&mut s, &pr, zero, Layer::Extreme(0), d.size);
                scene(&mut s, &pr, half, Layer::Extreme(1), d.size);
            }
            _ => scene(
                &mut s,
                &pr,
                &d.scene,
                Layer::Main { labels: k == 0 },
                d.size,
            ),
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(s, "</svg>");
    s
}

/// The drawing's title, and what its colours mean (with `mode`'s label where it is drawn).
fn heading(s: &mut String, d: &Drawing, mode: Option<&ModeMotion>) {
    let title = format!("{} at {} rad/s", d.model, d.speed);
    let _ = writeln!(
        s,
        r#"<text x="8" y="18" font-size="14" font-weight="bold">{}</text>"#,
        esc(&title)
    );
    let subtitle = match mode {
        Some(m) => format!(
            "{}: equilibrium grey, extremes blue (φ = 0) and red (φ = π), quarter periods dashed",
            m.label
        ),
        None => "bodies: centre of mass (dot), links, equivalent ellipsoid of inertia (shaded); joints: circles, axes red; cut joints: crossed; force elements: green; beams: brown; ports: orange; m".into(),
    };
    let _ = writeln!(
        s,
        r##"<text x="8" y="34" fill="#555">{}</text>"##,
        esc(&subtitle)
    );
}

/// The smallest and largest coordinate along `axis` of any point of `scenes` (`+∞, −∞` where
/// they have none).
fn range(scenes: &[&Scene], axis: &P3) -> (f64, f64) {
    let points = (scenes.iter().flat_map(|sc| sc.points())).map(|x| (dot(axis, &x), 0.0));
    // The solids reach beyond their centres (a beam's radius is drawn at its points too).
    let solids =
        (scenes.iter().flat_map(|sc| &sc.bodies)).map(|b| (dot(axis, &b.cm), b.reach(axis)));
    let beams = (scenes.iter().flat_map(|sc| &sc.beams))
        .flat_map(|c| c.points.iter().map(|x| (dot(axis, x), c.radius)));
    points
        .chain(solids)
        .chain(beams)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (v, r)| {
            (lo.min(v - r), hi.max(v + r))
        })
}

/// How a scene is drawn.
#[derive(Clone, Copy, PartialEq)]
enum Layer {
    /// The mechanism, every mark (labels in the first view).
    Main { labels: bool },
    /// The equilibrium under a mode: grey links only.
    Background,
    /// A mode's extreme (0: φ = 0, 1: φ = π): links and marks in its colour.
    Extreme(usize),
    /// A quarter period: dashed links.
    Quarter,
}

/// The ground axes' directions in a view's corner (a small triad).
fn axes_mark(s: &mut String, pr: &Projection, x0: f64) {
    let (cx, cy) = (x0 + PANEL - 40.0, TITLE + PANEL - 20.0);
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let mut e = [0.0; 3];
        e[k] = 1.0;
        let (dx, dy) = (dot(&pr.h, &e), -dot(&pr.v, &e));
        if dx.abs() + dy.abs() < 0.5 {
            // Along the line of sight: out of the page (⊙) where it points at the viewer,
            // `h × v`, else into it (⊗).
            let out = [
                pr.h[1] * pr.v[2] - pr.h[2] * pr.v[1],
                pr.h[2] * pr.v[0] - pr.h[0] * pr.v[2],
                pr.h[0] * pr.v[1] - pr.h[1] * pr.v[0],
            ];
            let mark = if dot(&out, &e) > 0.0 { "⊙" } else { "⊗" };
            let _ = writeln!(
                s,
                r##"<text x="{}" y="{}" fill="#888">{name} {mark}</text>"##,
                cx - 34.0,
                cy + 12.0
            );
            continue;
        }
        let _ = writeln!(
            s,
            r##"<line x1="{cx}" y1="{cy}" x2="{}" y2="{}" stroke="#888"/><text x="{}" y="{}" fill="#888">{name}</text>"##,
            cx + 14.0 * dx,
            cy + 14.0 * dy,
            cx + 18.0 * dx - 3.0,
            cy + 18.0 * dy + 3.0
        );
    }
}

fn line(s: &mut String, a: (f64, f64), b: (f64, f64), attrs: &str) {
    let _ = writeln!(
        s,
        r#"<line x1="{}" y1="{}" x2="{}" y2="{}" {attrs}/>"#,
        a.0, a.1, b.0, b.1
    );
}

fn scene(s: &mut String, pr: &Projection, sc: &Scene, layer: Layer, size: f64) {
    let (link, width, dash) = match layer {
        Layer::Main { .. } => (INK, 2.5, ""),
        Layer::Background => ("#bbb", 2.0, ""),
        Layer::Extreme(k) => (EXTREMES[k], 2.0, ""),
        Layer::Quarter => (QUARTERS, 1.2, r#" stroke-dasharray="4 3""#),
    };
    solids(s, pr, sc, layer);
    for b in &sc.bodies {
        let c = pr.at(&b.cm);
        for x in &b.links {
            line(
                s,
                c,
                pr.at(x),
                &format!(r#"stroke="{link}" stroke-width="{width}" stroke-linecap="round"{dash}"#),
            );
        }
    }
    // The beams' curves, in every layer: a mode bends them.
    let beam = match layer {
        Layer::Main { .. } => BEAM,
        _ => link,
    };
    for c in &sc.beams {
        let points: Vec<String> = (c.points.iter())
            .map(|x| {
                let (a, b) = pr.at(x);
                format!("{a},{b}")
            })
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline class="beam" data-name="{}" points="{}" fill="none" stroke="{beam}" stroke-width="{}" stroke-linecap="round"{dash}/>"#,
            esc(&c.name),
            points.join(" "),
            width + 1.0
        );
    }
    let Layer::Main { labels } = layer else {
        // A mode's layers: the links, and the centres of mass of the extremes.
        if let Layer::Extreme(_) = layer {
            for b in &sc.bodies {
                let (x, y) = pr.at(&b.cm);
                let _ = writeln!(s, r#"<circle cx="{x}" cy="{y}" r="3" fill="{link}"/>"#);
            }
        }
        return;
    };
    let axis_len = 0.06 * size * pr.s;
    elements(s, pr, sc);
    cuts(s, pr, sc);
    let mut names = labels.then(|| Labels::new(pr.panel));
    joints(s, pr, sc, axis_len, names.as_mut());
    bodies(s, pr, sc, names.as_mut());
    ports(s, pr, sc, axis_len, names.as_mut());
    if let Some(n) = names {
        n.write(s);
    }
}

/// The bodies and beams as solids, under everything else: each body's equivalent ellipsoid of
/// inertia projected (an ellipse; a disk seen edge-on is a flat one), each beam its curve at its
/// drawn diameter. Filled faintly in the mechanism's layers, outlined in a mode's extremes,
/// left out of its quarter periods.
fn solids(s: &mut String, pr: &Projection, sc: &Scene, layer: Layer) {
    let (fill, stroke) = match layer {
        Layer::Main { .. } => ("#1f3b73", "#1f3b73"),
        Layer::Background => ("#bbb", "#bbb"),
        Layer::Extreme(k) => ("none", EXTREMES[k]),
        Layer::Quarter => return,
    };
    let fill_opacity = if fill == "none" { 0.0 } else { 0.15 };
    for c in sc.beams.iter().filter(|c| c.radius > 0.0) {
        let points: Vec<String> = (c.points.iter())
            .map(|x| {
                let (a, b) = pr.at(x);
                format!("{a},{b}")
            })
            .collect();
        let (colour, opacity) = match layer {
            Layer::Main { .. } => (BEAM, 0.3),
            Layer::Background => ("#bbb", 0.3),
            _ => (stroke, 0.15),
        };
        let _ = writeln!(
            s,
            r#"<polyline class="beam-solid" data-name="{}" points="{}" fill="none" stroke="{colour}" stroke-opacity="{opacity}" stroke-width="{}" stroke-linejoin="round"/>"#,
            esc(&c.name),
            points.join(" "),
            2.0 * c.radius * pr.s
        );
    }
    for b in &sc.bodies {
        let Some([rx, ry, angle]) = projected_ellipse(pr, b) else {
            continue;
        };
        let (x, y) = pr.at(&b.cm);
        let _ = writeln!(
            s,
            r#"<ellipse class="solid" data-name="{}" cx="{x}" cy="{y}" rx="{rx}" ry="{ry}" transform="rotate({angle} {x} {y})" fill="{fill}" fill-opacity="{fill_opacity}" stroke="{stroke}" stroke-opacity="0.5"/>"#,
            esc(&b.name),
        );
    }
}

/// Body `b`'s solid seen in `pr`: the semi-axes (px) and the turn of the first from the
/// drawing's x axis (degrees, clockwise as SVG turns), `None` where it has none. The ellipsoid
/// `yᵀS⁻¹y ≤ 1` projects onto the ellipse `uᵀE⁻¹u ≤ 1` with `E = P S Pᵀ` (`P` the view's
/// 2×3 projection): its semi-axes are the square roots of `E`'s eigenvalues. A flat one (a disk
/// edge-on) is kept a pixel thick so that it shows.
fn projected_ellipse(pr: &Projection, b: &crate::scene::BodyMark) -> Option<[f64; 3]> {
    // The body's turned axes on the screen (y down).
    let u: Vec<[f64; 2]> = (b.axes.iter())
        .map(|a| [pr.s * dot(&pr.h, a), -pr.s * dot(&pr.v, a)])
        .collect();
    let mut e = [[0.0; 2]; 2];
    for k in 0..3 {
        for l in 0..3 {
            for (i, row) in e.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x += b.solid[k][l] * u[k][i] * u[l][j];
                }
            }
        }
    }
    let mean = 0.5 * (e[0][0] + e[1][1]);
    let d = (0.25 * (e[0][0] - e[1][1]).powi(2) + e[0][1].powi(2)).sqrt();
    let (major, minor) = ((mean + d).max(0.0).sqrt(), (mean - d).max(0.0).sqrt());
    let angle = 0.5 * (2.0 * e[0][1]).atan2(e[0][0] - e[1][1]);
    (major >= 1.0 && major.is_finite()).then(|| [major, minor.max(1.0), angle.to_degrees()])
}

/// The force elements: dashed green lines between their ends.
fn elements(s: &mut String, pr: &Projection, sc: &Scene) {
    for e in &sc.elements {
        let (a, b) = (pr.at(&e.ends[0]), pr.at(&e.ends[1]));
        let _ = writeln!(
            s,
            r##"<line class="element" data-name="{}" x1="{}" y1="{}" x2="{}" y2="{}" stroke="#2ca02c" stroke-width="1.5" stroke-dasharray="6 3"/>"##,
            esc(&e.name),
            a.0,
            a.1,
            b.0,
            b.1
        );
    }
}

/// The cut joints: a dotted line between their ends, crossed circles at the first.
fn cuts(s: &mut String, pr: &Projection, sc: &Scene) {
    for c in &sc.cuts {
        let (a, b) = (pr.at(&c.ends[0]), pr.at(&c.ends[1]));
        line(
            s,
            a,
            b,
            r##"stroke="#9467bd" stroke-width="1.5" stroke-dasharray="2 2""##,
        );
        let _ = writeln!(
            s,
            r##"<g class="cut" data-name="{}"><circle cx="{}" cy="{}" r="5" fill="white" stroke="#9467bd" stroke-width="1.5"/><path d="M{} {}l7 7m0 -7l-7 7" stroke="#9467bd"/></g>"##,
            esc(&c.name),
            a.0,
            a.1,
            a.0 - 3.5,
            a.1 - 3.5
        );
    }
}

/// The joints: circles with their axes (red), a ring around a driven one, named where
/// `labels`.
fn joints(
    s: &mut String,
    pr: &Projection,
    sc: &Scene,
    axis_len: f64,
    mut labels: Option<&mut Labels>,
) {
    for j in &sc.joints {
        let p = pr.at(&j.at);
        for a in &j.axes {
            let (dx, dy) = (dot(&pr.h, a) * axis_len, -dot(&pr.v, a) * axis_len);
            line(
                s,
                (p.0 - dx, p.1 - dy),
                (p.0 + dx, p.1 + dy),
                r##"stroke="#d62728" stroke-width="1.2""##,
            );
        }
        let ring = if j.driven {
            format!(
                r##"<circle cx="{}" cy="{}" r="8" fill="none" stroke="{INK}" stroke-width="1"/>"##,
                p.0, p.1
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            r##"<circle class="joint" data-name="{}" data-kind="{}" cx="{}" cy="{}" r="5" fill="white" stroke="{INK}" stroke-width="1.5"/>{ring}"##,
            esc(&j.name),
            j.kind,
            p.0,
            p.1
        );
        if let Some(l) = labels.as_deref_mut() {
            l.add(p, &j.name, Rank::Joint, "#a00");
        }
    }
}

/// The bodies' centres of mass, named where `labels`.
fn bodies(s: &mut String, pr: &Projection, sc: &Scene, mut labels: Option<&mut Labels>) {
    for b in &sc.bodies {
        let (x, y) = pr.at(&b.cm);
        let _ = writeln!(
            s,
            r##"<circle class="cm" data-name="{}" cx="{x}" cy="{y}" r="4" fill="#1f3b73"/>"##,
            esc(&b.name)
        );
        if let Some(l) = labels.as_deref_mut() {
            let rank = if b.solid == [[0.0; 3]; 3] {
                Rank::Frame
            } else {
                Rank::Solid
            };
            l.add((x, y), &b.name, rank, "#1f3b73");
        }
    }
}

/// The ports: orange arrows along their directions, named where `labels`.
fn ports(
    s: &mut String,
    pr: &Projection,
    sc: &Scene,
    axis_len: f64,
    mut labels: Option<&mut Labels>,
) {
    for p in &sc.ports {
        let a = pr.at(&p.at);
        let (dx, dy) = (
            dot(&pr.h, &p.direction) * axis_len,
            -dot(&pr.v, &p.direction) * axis_len,
        );
        let _ = writeln!(
            s,
            r##"<g class="port" data-name="{}"><line x1="{}" y1="{}" x2="{}" y2="{}" stroke="#ff7f0e" stroke-width="2"/><circle cx="{}" cy="{}" r="3" fill="#ff7f0e"/></g>"##,
            esc(&p.name),
            a.0,
            a.1,
            a.0 + dx,
            a.1 + dy,
            a.0,
            a.1
        );
        if let Some(l) = labels.as_deref_mut() {
            l.add(a, &p.name, Rank::Port, "#c60");
        }
    }
}
