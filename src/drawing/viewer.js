// The 3-D view of a drawing page (src/drawing/html.rs): the mechanism projected after a turn
// by yaw and pitch, a mode animated over its period. Reads the drawing from #data: the scene's
// vectors are indices into D.x; a mode's frame at phase φ moves every point x of body b by
// Re((d_b + ω_b × (x − c_b)) e^{iφ}) and turns every direction u by Re(ω_b e^{iφ}) × u (kept
// unit), and a point inside a beam's curve by the Hermite combination of its nodes' motions, as
// ModeMotion::frame does in src/drawing/mod.rs.
"use strict";
const D = JSON.parse(document.getElementById("data").textContent);
const canvas = document.getElementById("view"), ctx = canvas.getContext("2d");
const select = document.getElementById("mode"), button = document.getElementById("play");
const phaseText = document.getElementById("phase");
const FRAMES = 24, PERIOD = 2400;
let yaw = 0.7, pitch = 0.45, zoom = 1, mode = Number(canvas.dataset.start), playing = true, frame = 0;
const hash = /mode=(\d+)/.exec(location.hash);
if (hash) mode = D.modes.findIndex(m => m.number === Number(hash[1]));
if (mode >= D.modes.length) mode = -1;
select.value = String(mode);
const S = D.scene, X = D.x, A = D.anchor;
// The vectors at phase φ of mode m (the equilibrium where m is null), 3 numbers each.
function posed(m, phi) {
  if (!m) return X;
  const c = Math.cos(phi), s = Math.sin(phi), co = c, out = new Float64Array(X.length);
  for (let i = 0; i < A.length; i++) {
    const x = [X[3 * i], X[3 * i + 1], X[3 * i + 2]];
    let y = x;
    if (A[i] !== 0) {
      const b = Math.abs(A[i]) - 1, o = 6 * b, at = k => m.re[o + k] * c - m.im[o + k] * s;
      const w = [at(3), at(4), at(5)];
      const r = A[i] > 0 ? [0, 1, 2].map(k => x[k] - X[3 * S.bodies[b].cm + k]) : x;
      y = [0, 1, 2].map(k => x[k] + w[(k + 1) % 3] * r[(k + 2) % 3] - w[(k + 2) % 3] * r[(k + 1) % 3]);
      if (A[i] > 0) y = y.map((v, k) => v + at(k));
      else { const n = Math.hypot(y[0], y[1], y[2]); if (n > 0) y = y.map(v => v / n); }
    }
    out[3 * i] = y[0]; out[3 * i + 1] = y[1]; out[3 * i + 2] = y[2];
  }
  // A beam's curve inside the element: H1 δa + H2 L (ωa × ta) + H3 δb + H4 L (ωb × tb).
  for (const c of S.beams) {
    const n = c.points.length, a = c.points[0], b = c.points[n - 1];
    const turn = (k, t) => {
      const node = c.nodes[k];
      if (node === null) return [0, 0, 0];
      const at = j => m.re[6 * node + 3 + j] * co - m.im[6 * node + 3 + j] * s;
      const w = [at(0), at(1), at(2)], u = [X[3 * t], X[3 * t + 1], X[3 * t + 2]];
      return [w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]];
    };
    const ta = turn(0, c.tangents[0]), tb = turn(1, c.tangents[1]);
    for (let k = 1; k < n - 1; k++) {
      const x = k / (n - 1), x2 = x * x, x3 = x2 * x;
      const h = [1 - 3 * x2 + 2 * x3, x - 2 * x2 + x3, 3 * x2 - 2 * x3, x3 - x2];
      for (let j = 0; j < 3; j++) {
        const da = out[3 * a + j] - X[3 * a + j], db = out[3 * b + j] - X[3 * b + j];
        out[3 * c.points[k] + j] = X[3 * c.points[k] + j] + h[0] * da + h[1] * c.length * ta[j]
          + h[2] * db + h[3] * c.length * tb[j];
      }
    }
  }
  return out;
}
function pointIndices() {
  const out = [];
  for (const b of S.bodies) { out.push(b.cm); for (const l of b.links) out.push(l); }
  for (const j of S.joints) out.push(j.at);
  for (const l of S.cuts.concat(S.elements)) { out.push(l.ends[0]); out.push(l.ends[1]); }
  for (const p of S.ports) out.push(p.at);
  for (const c of S.beams) for (const p of c.points) out.push(p);
  return out;
}
const centre = [0, 1, 2].map(k => {
  const v = pointIndices().map(i => X[3 * i + k]);
  return v.length ? (Math.min(...v) + Math.max(...v)) / 2 : 0;
});
// Ground vectors in the view's axes: across, up (against gravity), toward the viewer.
function viewAxes(v) {
  const a = D.axes, d = u => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  return [d(a.across), d(a.up), d(a.toward)];
}
// A vector on the screen (px, y down), before the view's offset.
function turned(u) {
  const [x0, y0, z0] = viewAxes(u);
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const x = cy * x0 + sy * z0, z = -sy * x0 + cy * z0;
  const y = cp * y0 - sp * z;
  return [scale() * x, -scale() * y];
}
function scale() { return 0.75 * Math.min(canvas.width, canvas.height) / D.size * zoom; }
function project(p) {
  const [x, y] = turned([p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]]);
  return [canvas.width / 2 + x, canvas.height / 2 + y];
}
// A body's equivalent ellipsoid of inertia projected (as solids() in src/drawing/svg.rs):
// E = Σ S_kl u_k u_lᵀ over its turned axes u_k on the screen, semi-axes √eig(E).
function solid(b, v, faint) {
  const u = b.axes.map(i => turned(v(i)));
  let e00 = 0, e01 = 0, e11 = 0;
  for (let k = 0; k < 3; k++) for (let l = 0; l < 3; l++) {
    const w = b.solid[k][l];
    e00 += w * u[k][0] * u[l][0]; e01 += w * u[k][0] * u[l][1]; e11 += w * u[k][1] * u[l][1];
  }
  const mean = (e00 + e11) / 2, d = Math.hypot((e00 - e11) / 2, e01);
  const major = Math.sqrt(Math.max(mean + d, 0)), minor = Math.max(Math.sqrt(Math.max(mean - d, 0)), 1);
  if (!(major >= 1) || !isFinite(major)) return;
  const p = project(v(b.cm));
  ctx.beginPath(); ctx.ellipse(p[0], p[1], major, minor, Math.atan2(2 * e01, e00 - e11) / 2, 0, 2 * Math.PI);
  ctx.fillStyle = faint ? "rgba(187,187,187,0.15)" : "rgba(31,59,115,0.15)"; ctx.fill();
  ctx.strokeStyle = faint ? "rgba(187,187,187,0.5)" : "rgba(31,59,115,0.5)"; ctx.lineWidth = 1; ctx.stroke();
}
function seg(a, b, colour, width, dash) {
  const p = project(a), q = project(b);
  ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.setLineDash(dash || []);
  ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0], q[1]); ctx.stroke();
  ctx.setLineDash([]);
}
function dot(a, r, fill, stroke) {
  const p = project(a);
  ctx.beginPath(); ctx.arc(p[0], p[1], r, 0, 2 * Math.PI);
  ctx.fillStyle = fill; ctx.fill();
  if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = 1.5; ctx.stroke(); }
}
// Names: gathered per point while a scene is drawn (the names of marks at one point joined,
// those that say most first, as Rank in src/drawing/svg.rs: a body with mass, a port, a joint,
// a body without; each once; the first two and how many more), then written each at the first
// place beside its point that overlaps no name written before; a name with no such place is
// left out.
let names = [];
function label(a, text, colour, rank) {
  const p = project(a);
  const same = names.find(n => Math.abs(n.p[0] - p[0]) < 1 && Math.abs(n.p[1] - p[1]) < 1);
  if (same) same.marks.push({ text, colour, rank }); else names.push({ p, marks: [{ text, colour, rank }] });
}
function writeNames() {
  ctx.font = "11px sans-serif";
  const taken = [];
  for (const n of names) {
    n.marks.sort((a, b) => a.rank - b.rank);
    const texts = [...new Set(n.marks.map(m => m.text))];
    n.colour = n.marks[0].colour;
    const t = texts.length <= 2 ? texts.join(", ") : texts.slice(0, 2).join(", ") + " +" + (texts.length - 2);
    const w = ctx.measureText(t).width, [x, y] = n.p;
    for (let k = 0; k < 6; k++) {
      const step = 13 * k;
      const at = [[x + 7, y - 7 - step], [x + 7, y + 14 + step], [x - 7 - w, y - 7 - step], [x - 7 - w, y + 14 + step]]
        .find(([bx, by]) => taken.every(o => bx + w <= o[0] || o[2] <= bx || by + 3 <= o[1] || o[3] <= by - 11));
      if (at) {
        taken.push([at[0], at[1] - 11, at[0] + w, at[1] + 3]);
        ctx.fillStyle = n.colour; ctx.fillText(t, at[0], at[1]);
        break;
      }
    }
  }
  names = [];
}
function drawScene(P, faint) {
  const v = i => [P[3 * i], P[3 * i + 1], P[3 * i + 2]];
  const ink = faint ? "#c8c8c8" : "#333";
  // The solids first: each beam at its diameter, each body its ellipsoid.
  for (const c of S.beams) {
    if (!(c.radius > 0)) continue;
    ctx.strokeStyle = faint ? "rgba(187,187,187,0.3)" : "rgba(140,86,75,0.3)";
    ctx.lineWidth = 2 * c.radius * scale(); ctx.lineJoin = "round";
    ctx.beginPath();
    c.points.forEach((i, k) => { const p = project(v(i)); if (k) ctx.lineTo(p[0], p[1]); else ctx.moveTo(p[0], p[1]); });
    ctx.stroke();
  }
  for (const b of S.bodies) solid(b, v, faint);
  for (const b of S.bodies) for (const l of b.links) seg(v(b.cm), v(l), ink, faint ? 2 : 3);
  for (const c of S.beams) {
    for (let k = 1; k < c.points.length; k++) {
      seg(v(c.points[k - 1]), v(c.points[k]), faint ? "#c8c8c8" : "#8c564b", faint ? 2 : 4);
    }
  }
  if (faint) return;
  const L = 0.06 * D.size;
  const along = (p, a, t) => [p[0] + t * a[0], p[1] + t * a[1], p[2] + t * a[2]];
  for (const e of S.elements) seg(v(e.ends[0]), v(e.ends[1]), "#2ca02c", 1.5, [6, 3]);
  for (const c of S.cuts) { seg(v(c.ends[0]), v(c.ends[1]), "#9467bd", 1.5, [2, 2]); dot(v(c.ends[0]), 5, "white", "#9467bd"); }
  for (const j of S.joints) {
    const at = v(j.at);
    for (const a of j.axes) seg(along(at, v(a), -L), along(at, v(a), L), "#d62728", 1.5);
    dot(at, j.driven ? 7 : 5, "white", "#333");
    label(at, j.name, "#a00", 2);
  }
  const T = 0.05 * D.size, tints = ["#e377c2", "#17becf", "#bcbd22"];
  for (const b of S.bodies) {
    const cm = v(b.cm);
    for (let k = 0; k < 3; k++) seg(cm, along(cm, v(b.axes[k]), T), tints[k], 1);
    const massive = b.solid.some(row => row.some(x => x !== 0));
    dot(cm, 4, "#1f3b73"); label(cm, b.name, "#1f3b73", massive ? 0 : 3);
  }
  for (const p of S.ports) {
    const at = v(p.at);
    seg(at, along(at, v(p.direction), L), "#ff7f0e", 2.5);
    label(at, p.name, "#c60", 1);
  }
  writeNames();
}
function triad() {
  const o = [40, canvas.height - 40], names = ["x", "y", "z"], colours = ["#d62728", "#2ca02c", "#1f77b4"];
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  for (let k = 0; k < 3; k++) {
    const u = [0, 0, 0]; u[k] = 1;
    const e = viewAxes(u);
    const x = cy * e[0] + sy * e[2], z = -sy * e[0] + cy * e[2], y = cp * e[1] - sp * z;
    ctx.strokeStyle = colours[k]; ctx.lineWidth = 2; ctx.beginPath();
    ctx.moveTo(o[0], o[1]); ctx.lineTo(o[0] + 25 * x, o[1] - 25 * y); ctx.stroke();
    ctx.fillStyle = colours[k]; ctx.fillText(names[k], o[0] + 30 * x - 3, o[1] - 30 * y + 4);
  }
}
function draw() {
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (mode >= 0) {
    drawScene(X, true);
    drawScene(posed(D.modes[mode], 2 * Math.PI * frame / FRAMES), false);
    phaseText.textContent = "φ = " + Math.round(360 * frame / FRAMES) + "°";
  } else {
    drawScene(X, false);
    phaseText.textContent = "";
  }
  triad();
  canvas.dataset.frame = String(frame);
  canvas.dataset.mode = String(mode >= 0 ? D.modes[mode].number : 0);
}
// The animation runs on a timer (so a headless browser's virtual time advances it too).
setInterval(() => {
  if (playing && mode >= 0) {
    frame = (frame + 1) % FRAMES;
    draw();
  }
}, PERIOD / FRAMES);
select.addEventListener("change", () => { mode = Number(select.value); frame = 0; draw(); });
button.addEventListener("click", () => { playing = !playing; button.textContent = playing ? "pause" : "play"; });
let drag = null;
canvas.addEventListener("mousedown", e => { drag = [e.clientX, e.clientY]; });
window.addEventListener("mouseup", () => { drag = null; });
window.addEventListener("mousemove", e => {
  if (!drag) return;
  yaw += 0.01 * (e.clientX - drag[0]); pitch += 0.01 * (e.clientY - drag[1]);
  drag = [e.clientX, e.clientY]; draw();
});
canvas.addEventListener("wheel", e => { e.preventDefault(); zoom *= Math.exp(-0.001 * e.deltaY); draw(); }, { passive: false });
draw();
