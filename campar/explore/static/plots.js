// campar explore: small plots drawn on a canvas (ticks, lines, points), no library.
"use strict";

function niceTicks(lo, hi, count) {
  const span = hi - lo;
  if (!(span > 0)) return [lo];
  const raw = span / count;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => span / s <= count) || raw;
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) ticks.push(+t.toPrecision(12));
  return ticks;
}

function clearPlot(canvas) {
  canvas.getContext("2d").clearRect(0, 0, canvas.width, canvas.height);
}

// A small scatter or line plot: series of {points: [[x, y]], line | dot: colour}.
function plot(canvas, series, xlabel, ylabel, title, marks) {
  const ctx = canvas.getContext("2d");
  const m = { left: 50, right: 8, top: title ? 16 : 6, bottom: 30 };
  const w = canvas.width - m.left - m.right, h = canvas.height - m.top - m.bottom;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const all = series.flatMap((s) => s.points).filter(([x, y]) => x !== null && y !== null);
  if (!all.length) return;
  let [x0, x1, y0, y1] = [Infinity, -Infinity, Infinity, -Infinity];
  for (const [x, y] of all) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
  if (x1 === x0) { x0 -= 0.5; x1 += 0.5; }
  if (y1 === y0) { y0 -= 0.5; y1 += 0.5; }
  const pad = 0.04 * (y1 - y0); y0 -= pad; y1 += pad;
  const X = (x) => m.left + (x - x0) / (x1 - x0) * w, Y = (y) => m.top + (y1 - y) / (y1 - y0) * h;
  ctx.font = "10px system-ui, sans-serif"; ctx.fillStyle = "#222"; ctx.strokeStyle = "#333";
  ctx.strokeRect(m.left, m.top, w, h);
  if (title) { ctx.textAlign = "left"; ctx.textBaseline = "top"; ctx.fillText(title, m.left, 2); }
  ctx.textAlign = "center"; ctx.textBaseline = "top";
  for (const t of niceTicks(x0, x1, 5)) ctx.fillText(String(t), X(t), m.top + h + 3);
  ctx.fillText(xlabel, m.left + w / 2, m.top + h + 16);
  ctx.textAlign = "right"; ctx.textBaseline = "middle";
  for (const t of niceTicks(y0, y1, 4)) ctx.fillText(String(t), m.left - 3, Y(t));
  ctx.save(); ctx.translate(10, m.top + h / 2); ctx.rotate(-Math.PI / 2);
  ctx.textAlign = "center"; ctx.fillText(ylabel, 0, 0); ctx.restore();
  for (const mark of marks || []) {
    ctx.strokeStyle = "#999"; ctx.setLineDash([3, 3]);
    ctx.beginPath(); ctx.moveTo(X(mark.x), m.top); ctx.lineTo(X(mark.x), m.top + h); ctx.stroke();
    ctx.setLineDash([]);
  }
  for (const s of series) {
    if (s.line) {
      ctx.strokeStyle = s.line; ctx.beginPath();
      s.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
      ctx.stroke();
    } else {
      ctx.fillStyle = s.dot;
      for (const [x, y] of s.points) ctx.fillRect(X(x) - s.size / 2, Y(y) - s.size / 2, s.size, s.size);
    }
  }
}
