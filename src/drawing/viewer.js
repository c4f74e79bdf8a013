// The 3-D view of a drawing page (src/drawing/html.rs): the mechanism projected after a turn
// by yaw and pitch, a mode animated over its period. Reads the drawing from #data.
"use strict";
const D = JSON.parse(document.getElementById("data").textContent);
const canvas = document.getElementById("view"), ctx = canvas.getContext("2d");
const select = document.getElementById("mode"), button = document.getElementById("play");
const phaseText = document.getElementById("phase");
let yaw = 0.7, pitch = 0.45, zoom = 1, mode = Number(document.getElementById("view").dataset.start), playing = true, frame = 0;
const PERIOD = 2400;
const hash = /mode=(\d+)/.exec(location.hash);
if (hash) mode = Number(hash[1]) - 1;
if (mode >= D.modes.length) mode = -1;
select.value = String(mode);
function points(sc) {
  const out = [];
  for (const b of sc.bodies) { out.push(b.cm); for (const l of b.links) out.push(l); }
  for (const j of sc.joints) out.push(j.at);
  for (const l of sc.cuts.concat(sc.elements)) { out.push(l.ends[0]); out.push(l.ends[1]); }
  for (const p of sc.ports) out.push(p.at);
  return out;
}
const centre = [0, 1, 2].map(k => {
  const v = points(D.scene).map(p => p[k]);
  return v.length ? (Math.min(...v) + Math.max(...v)) / 2 : 0;
});
function project(p) {
  const x0 = p[0] - centre[0], y0 = p[1] - centre[1], z0 = p[2] - centre[2];
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const x = cy * x0 + sy * z0, z = -sy * x0 + cy * z0;
  const y = cp * y0 - sp * z;
  const s = 0.75 * Math.min(canvas.width, canvas.height) / D.size * zoom;
  return [canvas.width / 2 + s * x, canvas.height / 2 - s * y];
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
function label(a, text, colour) {
  const p = project(a);
  ctx.fillStyle = colour; ctx.font = "11px sans-serif"; ctx.fillText(text, p[0] + 7, p[1] - 7);
}
function drawScene(sc, faint) {
  const ink = faint ? "#c8c8c8" : "#333";
  for (const b of sc.bodies) for (const l of b.links) seg(b.cm, l, ink, faint ? 2 : 3);
  if (faint) return;
  const L = 0.06 * D.size;
  for (const e of sc.elements) seg(e.ends[0], e.ends[1], "#2ca02c", 1.5, [6, 3]);
  for (const c of sc.cuts) { seg(c.ends[0], c.ends[1], "#9467bd", 1.5, [2, 2]); dot(c.ends[0], 5, "white", "#9467bd"); }
  for (const j of sc.joints) {
    for (const a of j.axes) seg([j.at[0] - L * a[0], j.at[1] - L * a[1], j.at[2] - L * a[2]],
                                [j.at[0] + L * a[0], j.at[1] + L * a[1], j.at[2] + L * a[2]], "#d62728", 1.5);
    dot(j.at, j.driven ? 7 : 5, "white", "#333");
    label(j.at, j.name, "#a00");
  }
  const T = 0.05 * D.size, tints = ["#e377c2", "#17becf", "#bcbd22"];
  for (const b of sc.bodies) {
    for (let k = 0; k < 3; k++) {
      const a = b.axes[k];
      seg(b.cm, [b.cm[0] + T * a[0], b.cm[1] + T * a[1], b.cm[2] + T * a[2]], tints[k], 1);
    }
    dot(b.cm, 4, "#1f3b73"); label(b.cm, b.name, "#1f3b73");
  }
  for (const p of sc.ports) {
    seg(p.at, [p.at[0] + L * p.direction[0], p.at[1] + L * p.direction[1], p.at[2] + L * p.direction[2]], "#ff7f0e", 2.5);
    label(p.at, p.name, "#c60");
  }
}
function triad() {
  const o = [40, canvas.height - 40], names = ["x", "y", "z"], colours = ["#d62728", "#2ca02c", "#1f77b4"];
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  for (let k = 0; k < 3; k++) {
    const e = [0, 0, 0]; e[k] = 1;
    const x = cy * e[0] + sy * e[2], z = -sy * e[0] + cy * e[2], y = cp * e[1] - sp * z;
    ctx.strokeStyle = colours[k]; ctx.lineWidth = 2; ctx.beginPath();
    ctx.moveTo(o[0], o[1]); ctx.lineTo(o[0] + 25 * x, o[1] - 25 * y); ctx.stroke();
    ctx.fillStyle = colours[k]; ctx.fillText(names[k], o[0] + 30 * x - 3, o[1] - 30 * y + 4);
  }
}
function draw() {
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (mode >= 0) {
    const frames = D.modes[mode].frames;
    drawScene(D.scene, true);
    drawScene(frames[frame % frames.length], false);
    phaseText.textContent = "φ = " + Math.round(360 * frame / frames.length) + "°";
  } else {
    drawScene(D.scene, false);
    phaseText.textContent = "";
  }
  triad();
  canvas.dataset.frame = String(frame);
  canvas.dataset.mode = String(mode + 1);
}
// The animation runs on a timer (so a headless browser's virtual time advances it too).
setInterval(() => {
  if (playing && mode >= 0) {
    frame = (frame + 1) % D.modes[mode].frames.length;
    draw();
  }
}, PERIOD / 24);
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
