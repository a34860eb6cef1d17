// campar explore: bifurcation lines through the map — a row (along the first axis), a
// column (along the second) or a segment between two clicked cells — each one warm-started
// chain computed by the server as `campar line` computes one, and the branches through the
// clicked cell's cycle along a row or a column.
"use strict";

// A click in line mode: a row or a column at once; a segment at its second cell.
function lineClick(store, cell) {
  const along = $("line-along").value;
  if (along === "segment" && !(state.segmentStart && state.segmentStart.store === store)) {
    state.segmentStart = { store, cell };
    $("line-head").textContent = `segment from row ${cell.row}, column ${cell.col}: click its other end`;
    return false; // line mode stays on for the second click
  }
  const start = along === "segment" ? state.segmentStart.cell : null;
  state.segmentStart = null;
  drawLine(store, along, start || cell, start ? cell : null);
  return true;
}

function lineTitle(line) {
  const s = state.stores[line.store], x = s.x.name, y = s.y.name;
  if (line.along === "row") return `the row ${SYMBOL[y]} = ${fmt(line.a[y], 5)}`;
  if (line.along === "column") return `the column ${SYMBOL[x]} = ${fmt(line.a[x], 5)}`;
  return `the segment (${fmt(line.a[x], 4)}, ${fmt(line.a[y], 4)}) – (${fmt(line.b[x], 4)}, ${fmt(line.b[y], 4)})`;
}

async function drawLine(store, along, a, b) {
  const params = { store, along, row: a.row, col: a.col };
  if (b) Object.assign(params, { row2: b.row, col2: b.col });
  state.line = { store, along, row: a.row, col: a.col, a, b, data: null };
  $("branch-head").textContent = "";
  for (const v of activeViews()) v.paint();
  $("line-head").textContent = `computing ${lineTitle(state.line)} …`;
  let data;
  try {
    data = await api("line", params);
  } catch (error) {
    $("line-head").textContent = error.message;
    return;
  }
  state.line.data = data;
  state.line.branch = null;
  $("line-head").textContent = `${lineTitle(state.line)}: σn points y over ${SYMBOL[data.x] || data.x}, ` +
    `${data.points.length} points; label changes dashed (${data.changes.length})` +
    (data.kernel_note ? `; ${data.kernel_note}` : "");
  drawLinePlot();
}

// The line's mark on a map: dashed across the view for a row or a column, A to B for a segment.
function paintLine(view, ctx, r) {
  const line = state.line;
  if (!line || line.store !== view.storeIndex()) return;
  const s = state.stores[line.store];
  ctx.strokeStyle = "#e41a1c";
  ctx.setLineDash([6, 4]);
  ctx.beginPath();
  if (line.along === "row") {
    const [, py] = view.toPixel(0, line.a[s.y.name]);
    ctx.moveTo(r.x, py); ctx.lineTo(r.x + r.w, py);
  } else if (line.along === "column") {
    const [px] = view.toPixel(line.a[s.x.name], 0);
    ctx.moveTo(px, r.y); ctx.lineTo(px, r.y + r.h);
  } else {
    const [ax, ay] = view.toPixel(line.a[s.x.name], line.a[s.y.name]);
    const [bx, by] = view.toPixel(line.b[s.x.name], line.b[s.y.name]);
    ctx.moveTo(ax, ay); ctx.lineTo(bx, by);
  }
  ctx.stroke();
  ctx.setLineDash([]);
}

function drawLinePlot() {
  const line = state.line, data = line.data;
  const series = [{ points: data.points, dot: "#222", size: 2.5 }];
  const marks = data.changes.map((c) => ({ x: c.at }));
  if (line.branch) {
    const stable = [], unstable = [];
    for (const b of line.branch.branches) {
      for (const [x, y, ok] of b.points) (ok ? stable : unstable).push([x, y]);
    }
    series.push({ points: stable, dot: "#2c7be5", size: 2 }, { points: unstable, dot: "#f28e2b", size: 2 });
    series.push({ points: line.branch.special.map((p) => [p.value, p.y]), dot: "#e41a1c", size: 6 });
  }
  plot($("line-plot"), series, axisTitle(data.x), "σn: y (units of h)", "", marks);
}

// The branches through the clicked cell's cycle along the line's row or column (campar continue).
async function continueCell() {
  const c = state.cell, line = state.line;
  const on = line && c && c.store === line.store &&
    ((line.along === "row" && c.row === line.row) || (line.along === "column" && c.col === line.col));
  if (!c || !c.report || !line || !line.data || !on) {
    $("branch-head").textContent = "draw a row's or a column's line, then click a periodic cell on it";
    return;
  }
  $("branch-head").textContent = "continuing the cycle …";
  try {
    line.branch = await api("branch", { store: c.store, row: c.row, col: c.col, along: line.along });
  } catch (error) {
    $("branch-head").textContent = error.message;
    return;
  }
  const sp = line.branch.special.map((p) => `${p.type} at ${fmt(p.value, 4)}`).join(", ");
  const count = line.branch.branches.length;
  $("branch-head").textContent = `${count} branch${count === 1 ? "" : "es"}: stable blue, ` +
    `unstable orange; special points (red) ${sp || "none"}`;
  drawLinePlot();
}
