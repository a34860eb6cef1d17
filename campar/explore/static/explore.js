// campar explore: the page. Everything it loads comes from the server that served it.
"use strict";

const $ = (id) => document.getElementById(id);
const SYMBOL = { omega: "ω", f0: "f0", mu_kn: "μkn", mu_cn: "μcn", zeta: "ζ" };
const MEANING = {
  omega: "cam speed (units of ωn)",
  f0: "preload (units of K1·h)",
  mu_kn: "contact stiffness ratio (dimensionless)",
  mu_cn: "contact damping ratio (dimensionless)",
  zeta: "damping ratio (dimensionless)",
};
const MARGIN = { left: 62, right: 12, top: 10, bottom: 46 };
const ZOOM_STEP = 1.25;
const MAP_SIZE = [760, 560]; // canvas pixels: one map
const SIDE_SIZE = [500, 420]; // each of two maps side by side

const state = {
  overlays: {},
  stores: [], store: 0, field: "label", layer: 0, compare: "one", box: null,
  mode: null, cell: null, line: null, views: [], ready: false, errors: [], zooms: [],
};
window.explore = state;

function axisTitle(name) {
  return `${SYMBOL[name] || name}: ${MEANING[name] || "dimensionless"}`;
}

async function api(route, params, method) {
  const url = `/api/${route}?` + new URLSearchParams(params || {});
  const response = await fetch(url, { method: method || "GET" });
  if (!response.ok) throw new Error((await response.text()).trim());
  return response.json();
}

// -- one map view ---------------------------------------------------------------------

class MapView {
  constructor(index, canvas, caption) {
    this.index = index;
    this.canvas = canvas;
    this.caption = caption;
    this.ctx = canvas.getContext("2d");
    this.image = null;
    this.imageBox = null;
    this.overlays = [];
    this.sequence = 0;
    this.drawn = 0;
    this.selection = null;
    this.listen();
  }
  get rect() {
    const c = this.canvas;
    return { x: MARGIN.left, y: MARGIN.top, w: c.width - MARGIN.left - MARGIN.right,
      h: c.height - MARGIN.top - MARGIN.bottom };
  }
  storeIndex() {
    return state.compare === "side" && this.index === 1 ? otherStore() : state.store;
  }
  toPixel(x, y) {
    const r = this.rect, b = state.box;
    return [r.x + (x - b[0]) / (b[1] - b[0]) * r.w, r.y + (b[3] - y) / (b[3] - b[2]) * r.h];
  }
  fromPixel(px, py) {
    const r = this.rect, b = state.box;
    return [b[0] + (px - r.x) / r.w * (b[1] - b[0]), b[3] - (py - r.y) / r.h * (b[3] - b[2])];
  }
  async draw() {
    const seq = ++this.sequence;
    const r = this.rect, box = state.box.slice();
    const params = { store: this.storeIndex(), field: state.field, layer: state.layer,
      x0: box[0], x1: box[1], y0: box[2], y1: box[3], w: Math.round(r.w), h: Math.round(r.h) };
    if (state.compare === "diff") params.diff = 1;
    let answer;
    try {
      answer = await api("map", params);
    } catch (error) {
      showError(error.message);
      return;
    }
    if (seq !== this.sequence) return; // a newer view was asked for meanwhile
    const image = new Image();
    image.src = answer.image;
    await image.decode();
    if (seq !== this.sequence) return;
    this.image = image;
    this.imageBox = box;
    this.answer = answer;
    this.overlays = await this.drawZooms(box, r);
    this.paint();
    this.drawn += 1;
    showLegend();
    showStatus(answer.status);
    state.ready = true;
  }
  async drawZooms(box, r) {
    const out = [];
    for (const zoom of state.zooms) {
      if (zoom.parent !== this.storeIndex() || zoom.store === undefined) continue;
      try {
        const a = await api("map", { store: zoom.store, field: state.field,
          x0: box[0], x1: box[1], y0: box[2], y1: box[3], w: Math.round(r.w), h: Math.round(r.h) });
        const im = new Image();
        im.src = a.image;
        await im.decode();
        out.push(im);
      } catch (error) { /* a zoom store not readable yet: drawn at the next refresh */ }
    }
    return out;
  }
  paint() {
    const ctx = this.ctx, r = this.rect, c = this.canvas;
    ctx.clearRect(0, 0, c.width, c.height);
    ctx.fillStyle = "#f4f4f4";
    ctx.fillRect(r.x, r.y, r.w, r.h);
    if (this.image) {
      // the last image, placed where its box lies in the current view (pan and zoom at once)
      const [ax, ay] = this.toPixel(this.imageBox[0], this.imageBox[3]);
      const [bx, by] = this.toPixel(this.imageBox[1], this.imageBox[2]);
      ctx.save();
      ctx.beginPath();
      ctx.rect(r.x, r.y, r.w, r.h);
      ctx.clip();
      ctx.imageSmoothingEnabled = false;
      ctx.drawImage(this.image, ax, ay, bx - ax, by - ay);
      for (const im of this.overlays) ctx.drawImage(im, ax, ay, bx - ax, by - ay);
      paintLine(this, ctx, r);
      if (state.edges && state.edges.store === this.storeIndex() && state.compare !== "diff") {
        const styles = state.edges.data.styles;
        ctx.lineWidth = 2;
        for (const [x0, y0, x1, y1, type] of state.edges.data.segments) {
          const [ax0, ay0] = this.toPixel(x0, y0), [ax1, ay1] = this.toPixel(x1, y1);
          ctx.strokeStyle = styles[type].colour;
          ctx.beginPath(); ctx.moveTo(ax0, ay0); ctx.lineTo(ax1, ay1); ctx.stroke();
        }
        ctx.lineWidth = 1;
      }
      const overlay = state.overlays[this.storeIndex()] || {};
      if (overlay.curves && $("curves").checked) {
        ctx.lineWidth = 2;
        for (const c of overlay.curves.curves) {
          ctx.strokeStyle = (overlay.curves.styles[c.type] || { colour: "#000" }).colour;
          ctx.beginPath();
          c.points.forEach(([x, y], i) => {
            if (x === null || y === null) return;
            const [px, py] = this.toPixel(x, y);
            i ? ctx.lineTo(px, py) : ctx.moveTo(px, py);
          });
          ctx.stroke();
        }
        ctx.lineWidth = 1;
      }
      if (overlay.hysteresis && $("hysteresis").checked) {
        const s = state.stores[this.storeIndex()];
        const dx = (s.x.edges[1] - s.x.edges[0]) / s.shape[1], dy = (s.y.edges[1] - s.y.edges[0]) / s.shape[0];
        ctx.strokeStyle = "#e41a1c";
        for (const [x, y] of overlay.hysteresis.centres) {
          const [ax, ay] = this.toPixel(x - dx / 2, y + dy / 2), [bx, by] = this.toPixel(x + dx / 2, y - dy / 2);
          ctx.strokeRect(ax + 0.5, ay + 0.5, Math.max(bx - ax - 1, 1), Math.max(by - ay - 1, 1));
        }
      }
      if (this.selection) {
        const s = this.selection;
        ctx.strokeStyle = "#2c7be5";
        ctx.strokeRect(Math.min(s[0], s[2]), Math.min(s[1], s[3]), Math.abs(s[2] - s[0]), Math.abs(s[3] - s[1]));
      }
      ctx.restore();
    }
    this.axes();
  }
  axes() {
    const ctx = this.ctx, r = this.rect, b = state.box, s = state.stores[this.storeIndex()];
    ctx.strokeStyle = "#333"; ctx.fillStyle = "#222"; ctx.font = "11px system-ui, sans-serif";
    ctx.strokeRect(r.x, r.y, r.w, r.h);
    ctx.textAlign = "center"; ctx.textBaseline = "top";
    for (const t of niceTicks(b[0], b[1], 8)) {
      const [px] = this.toPixel(t, b[2]);
      ctx.beginPath(); ctx.moveTo(px, r.y + r.h); ctx.lineTo(px, r.y + r.h + 4); ctx.stroke();
      ctx.fillText(String(t), px, r.y + r.h + 6);
    }
    ctx.fillText(axisTitle(s.x.name), r.x + r.w / 2, r.y + r.h + 24);
    ctx.textAlign = "right"; ctx.textBaseline = "middle";
    for (const t of niceTicks(b[2], b[3], 8)) {
      const [, py] = this.toPixel(b[0], t);
      ctx.beginPath(); ctx.moveTo(r.x - 4, py); ctx.lineTo(r.x, py); ctx.stroke();
      ctx.fillText(String(t), r.x - 6, py);
    }
    ctx.save();
    ctx.translate(12, r.y + r.h / 2); ctx.rotate(-Math.PI / 2);
    ctx.textAlign = "center";
    ctx.fillText(axisTitle(s.y.name), 0, 0);
    ctx.restore();
    this.caption.textContent = `${s.name} (${s.job}, ${s.shape[0]} × ${s.shape[1]} cells)` +
      (state.compare === "diff" ? ` − ${state.stores[otherStore()].name}` : "");
  }
  listen() {
    const c = this.canvas;
    let drag = null, hoverTimer = null;
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      const [x, y] = this.fromPixel(e.offsetX, e.offsetY);
      const f = e.deltaY < 0 ? 1 / ZOOM_STEP : ZOOM_STEP;
      const b = state.box;
      setBox([x - (x - b[0]) * f, x + (b[1] - x) * f, y - (y - b[2]) * f, y + (b[3] - y) * f]);
    }, { passive: false });
    c.addEventListener("mousedown", (e) => {
      drag = { x: e.offsetX, y: e.offsetY, box: state.box.slice(), moved: false };
    });
    c.addEventListener("mousemove", (e) => {
      if (drag) {
        const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
        if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
        if (drag.moved && state.mode === "zoom") {
          this.selection = [drag.x, drag.y, e.offsetX, e.offsetY];
          this.paint();
        } else if (drag.moved) {
          const r = this.rect, b = drag.box;
          const sx = dx / r.w * (b[1] - b[0]), sy = dy / r.h * (b[3] - b[2]);
          state.box = [b[0] - sx, b[1] - sx, b[2] + sy, b[3] + sy];
          for (const v of activeViews()) v.paint();
        }
        return;
      }
      clearTimeout(hoverTimer);
      hoverTimer = setTimeout(() => hover(this, e.offsetX, e.offsetY), 60);
    });
    c.addEventListener("mouseup", (e) => {
      const d = drag;
      drag = null;
      if (!d) return;
      if (d.moved && state.mode === "zoom") {
        const [x0, y0] = this.fromPixel(Math.min(d.x, e.offsetX), Math.max(d.y, e.offsetY));
        const [x1, y1] = this.fromPixel(Math.max(d.x, e.offsetX), Math.min(d.y, e.offsetY));
        this.selection = null;
        setMode(null);
        startZoom(this.storeIndex(), [x0, x1, y0, y1]);
      } else if (d.moved) {
        setBox(state.box);
      } else {
        click(this, e.offsetX, e.offsetY);
      }
    });
    c.addEventListener("mouseleave", () => { drag = null; });
    c.addEventListener("dblclick", () => resetBox());
  }
}

// The other of the two stores given, to compare with (zoom stores come after them).
function otherStore() {
  return state.store === 0 ? 1 : 0;
}

function activeViews() {
  return state.compare === "side" ? state.views : [state.views[0]];
}

function setBox(box) {
  state.box = box;
  for (const v of activeViews()) v.draw();
  if ($("edges").checked) {
    clearTimeout(state.edgesTimer);
    state.edgesTimer = setTimeout(loadEdges, 400);
  }
}

// -- hover and click ------------------------------------------------------------------

function fmt(x, digits = 4) {
  return x === null || x === undefined ? "—" : Number(x).toFixed(digits);
}

async function hover(view, px, py) {
  const [x, y] = view.fromPixel(px, py);
  let cell;
  try {
    cell = await api("cell", { store: view.storeIndex(), layer: state.layer, x, y });
  } catch (error) {
    $("hover").textContent = error.message;
    return;
  }
  state.hovered = cell;
  $("hover").innerHTML = describeCell(cell, view.storeIndex());
}

function describeCell(cell, store) {
  if (cell.outside) return "outside the map";
  const s = state.stores[store];
  const where = `${SYMBOL[s.x.name] || s.x.name} = ${fmt(cell[s.x.name], 5)}, ` +
    `${SYMBOL[s.y.name] || s.y.name} = ${fmt(cell[s.y.name], 5)} (row ${cell.row}, column ${cell.col})`;
  if (cell.stored === "pending") return `<b>pending</b>: its tile is not committed yet<br>${where}`;
  if (cell.stored === "damaged") return `<b>damaged</b>, masked: ${cell.why}<br>${where}`;
  const mult = (cell.multipliers || []).map(([a, b]) => `|λ| = ${fmt(Math.hypot(a, b))}`).join(", ");
  return `<b id="hover-label">${cell.label}</b> ${cell.kind || ""}; status ${cell.status || "—"}<br>${where}<br>` +
    `duty cycle ${fmt(cell.dc)}, ε min ${fmt(cell.eps_min)}, ε max ${fmt(cell.eps_max)}, Pn max ${fmt(cell.pn_max)}<br>` +
    (cell.lyapunov !== undefined ? `Lyapunov exponent ${fmt(cell.lyapunov)}<br>` : "") +
    (mult ? `multipliers ${mult}<br>` : "") +
    (cell.attractors ? `attractors: ${cell.attractors.map((a) =>
      `${a.label} (${a.fraction === null ? "—" : (100 * a.fraction).toFixed(0) + " %"})`).join(", ")}<br>` : "") +
    `flags: ${(cell.flags || []).join(", ") || "none"}; ${cell.revolutions} revolutions, ${cell.steps} steps`;
}

async function click(view, px, py) {
  const [x, y] = view.fromPixel(px, py);
  const store = view.storeIndex();
  const cell = await api("cell", { store, layer: state.layer, x, y }).catch((e) => ({ error: e.message }));
  if (cell.error || cell.outside) return;
  if (state.mode === "line") {
    if (lineClick(store, cell)) setMode(null);
    return;
  }
  computeCell(store, cell);
}

async function computeCell(store, cell) {
  const s = state.stores[store];
  $("cell-head").textContent = `computing ${SYMBOL[s.x.name]} = ${fmt(cell[s.x.name], 5)}, ` +
    `${SYMBOL[s.y.name]} = ${fmt(cell[s.y.name], 5)} …`;
  $("cell-label").textContent = "…";
  $("cell-label").className = "";
  $("cell-more").textContent = "";
  state.cell = { store, row: cell.row, col: cell.col, stored: cell.label, report: null };
  let report;
  try {
    report = await api("compute", { store, row: cell.row, col: cell.col, layer: state.layer });
  } catch (error) {
    $("cell-label").textContent = error.message;
    $("cell-label").className = "error";
    return;
  }
  state.cell.report = report;
  const p = report.parameters;
  $("cell-head").textContent = Object.entries(p).map(([k, v]) =>
    `${SYMBOL[k] || k}=${typeof v === "number" ? +v.toPrecision(6) : v}`).join(", ");
  $("cell-label").textContent = report.label;
  const mult = (report.multipliers || []).map(([a, b]) =>
    `${fmt(a, 6)}${b < 0 ? "−" : "+"}${fmt(Math.abs(b), 6)}j (|λ| ${fmt(Math.hypot(a, b), 6)})`).join(", ");
  $("cell-numbers").innerHTML = `${report.kind}; ${report.status}; stored label ${cell.label}<br>` +
    `duty cycle ${fmt(report.dc)}, ε min ${fmt(report.eps_min)}, ε max ${fmt(report.eps_max)}, ` +
    `Pn max ${fmt(report.pn_max)}<br>multipliers ${mult || "—"}<br>` +
    `${report.revolutions} revolutions, ${report.steps} steps, computed in ${report.seconds} s`;
  if (report.kernel_note) { // another kernel computed the store: said as text, never as markup
    const note = document.createElement("div");
    note.className = "error";
    note.textContent = report.kernel_note;
    $("cell-numbers").appendChild(note);
  }
  drawOrbit(report);
}

function drawOrbit(report) {
  const t = report.trace;
  for (const id of ["phase", "eps", "pn", "yc"]) clearPlot($(id));
  if (!t) return;
  const sections = report.sections.map(([y, v]) => [y, v]);
  const det = (t.events.detachment || []).map((e) => [e[1], e[2]]);
  plot($("phase"), [
    { points: t.y.map((y, i) => [y, t.v[i]]), line: "#2c7be5" },
    { points: sections, dot: "#e41a1c", size: 4 },
    { points: det, dot: "#ff7f00", size: 3 },
  ], "y (units of h)", "ẏ (units of h·ωn)", "phase portrait: σn (red), detachments (orange)");
  const series = (name, colour) => [{ points: t.t.map((x, i) => [x, t[name][i]]), line: colour }];
  plot($("eps"), series("eps", "#4daf4a"), "t (units of 1/ωn)", "ε (h)");
  plot($("pn"), series("pn", "#984ea3"), "t (units of 1/ωn)", "Pn (K1·h)");
  plot($("yc"), series("yc", "#a65628"), "t (units of 1/ωn)", "yc (h)");
}

async function cellAction(route, extra, describe) {
  const c = state.cell;
  if (!c) return;
  $("cell-more").textContent = `computing ${route} …`;
  try {
    const data = await api(route, { store: c.store, row: c.row, col: c.col, ...extra });
    c[route] = data;
    $("cell-more").textContent = describe(data);
  } catch (error) {
    $("cell-more").textContent = error.message;
  }
}

function describeAttractors(data) {
  return `${data.attractors.length} attractors from ${data.starts} starts:\n` + data.attractors.map((a) =>
    `${a.label}  ${(100 * a.fraction).toFixed(1)} % of starts, duty cycle ${fmt(a.dc)}`).join("\n");
}

function describeCycle(o) {
  const mult = o.multipliers.map(([a, b]) => `|λ| ${fmt(Math.hypot(a, b), 6)}`).join(", ");
  return `${o.label} cycle, ${o.stable ? "stable" : "unstable"}; multipliers ${mult}\n` +
    `σn: ${o.sections.map(([y, v]) => `(${fmt(y, 6)}, ${fmt(v, 6)})`).join(" ")}`;
}

// -- a zoom that computes --------------------------------------------------------------

async function startZoom(parent, box) {
  try {
    const zoom = await api("zoom", { store: parent, x0: box[0], x1: box[1], y0: box[2], y1: box[3],
      points: $("zoom-points").value }, "POST");
    await loadStores();
    state.zooms.push({ parent, store: zoom.store });
    $("status").textContent = `zoom: ${zoom.name} running`;
    watchStores();
  } catch (error) {
    showError(error.message);
  }
}

// -- legend, status, export --------------------------------------------------------------

function showLegend() {
  const legend = $("legend");
  legend.innerHTML = "";
  for (const view of activeViews()) {
    if (view.answer) legendOf(legend, view);
  }
}

function legendOf(legend, view) {
  const answer = view.answer;
  const title = document.createElement("b");
  const store = state.stores[view.storeIndex()];
  const f = store.fields.find((x) => x.name === state.field);
  title.textContent = (state.compare === "side" ? `${store.name}: ` : "") + (f ? f.title : state.field);
  title.style.display = "block";
  legend.appendChild(title);
  if (answer.range) {
    const row = document.createElement("div");
    row.innerHTML = `<span class="swatch" style="width:120px;background:linear-gradient(90deg,#440154,#3b528b,#21918c,#5ec962,#fde725)"></span>`;
    legend.appendChild(row);
    const text = document.createElement("div");
    text.textContent = `${answer.range[0].toPrecision(4)} … ${answer.range[1].toPrecision(4)}`;
    legend.appendChild(text);
  }
  for (const e of answer.legend || []) {
    const row = document.createElement("div");
    row.className = "entry";
    row.dataset.label = e.label;
    const swatch = `<span class="swatch${e.hatch ? " hatch" : ""}" style="background-color:${e.colour || "#fff"}"></span>`;
    const members = e.members && e.members.length ? ` (${e.members.join(", ")})` : "";
    row.innerHTML = `${swatch}<span>${e.label}${members}</span><span style="margin-left:auto">${e.count}</span>`;
    legend.appendChild(row);
  }
}

function showStatus(status) {
  const damaged = Object.keys(status.damaged).length;
  let text = `tiles ${status.verified}/${status.tiles} verified`;
  if (damaged) text += `, ${damaged} damaged (masked: ${Object.entries(status.damaged)[0].join(": ")})`;
  if (!status.scanned) text += ", verifying …";
  if (status.problem) text += `; ${status.problem}`;
  $("status").textContent = text;
  $("status").className = damaged || status.problem ? "error" : "";
  if (status.verified < status.tiles) watchStores(); // tiles to come, or masked ones to look at
}

function showError(message) {
  state.errors.push(message);
  $("status").textContent = message;
  $("status").className = "error";
}

// -- set-up -----------------------------------------------------------------------------

function setMode(mode) {
  state.mode = state.mode === mode ? null : mode;
  if (state.mode !== "line") state.segmentStart = null;
  $("line-mode").classList.toggle("active", state.mode === "line");
  $("zoom-mode").classList.toggle("active", state.mode === "zoom");
}

async function loadStores() {
  state.stores = await api("stores");
  const select = $("store");
  const chosen = select.value;
  select.innerHTML = "";
  state.stores.forEach((s, i) => select.add(new Option(`${s.name} (${s.job})`, i)));
  select.value = chosen || "0";
}

function fillFields() {
  const s = state.stores[state.store];
  const select = $("field");
  select.innerHTML = "";
  for (const f of s.fields) select.add(new Option(f.title, f.name));
  if (!s.fields.some((f) => f.name === state.field)) state.field = s.fields[0].name;
  select.value = state.field;
  const layers = $("layer");
  layers.innerHTML = "";
  s.layers.forEach((name, i) => layers.add(new Option(name, i)));
  $("layer-box").style.display = s.layers.length > 1 ? "" : "none";
  $("compare-box").style.display = state.stores.length > 1 ? "" : "none";
  $("curves-box").style.display = s.curves ? "" : "none";
  $("hysteresis-box").style.display = s.layers.length > 1 ? "" : "none";
}

let watching = null;
function watchStores() {
  if (watching) return;
  watching = setInterval(async () => {
    let stores;
    try { stores = await api("stores"); } catch (error) { return; }
    // a masked (damaged) tile keeps the page watching: a run may repair it
    const busy = stores.some((s) => !s.status.scanned || s.status.verified < s.status.tiles);
    const changed = JSON.stringify(stores.map((s) => s.status)) !== JSON.stringify(state.stores.map((s) => s.status));
    state.stores = stores;
    if (changed) for (const v of activeViews()) v.draw();
    if (!busy) { clearInterval(watching); watching = null; }
  }, 250); // twice as often as the server looks at a store a run writes (a zoom: more)
}

async function main() {
  state.views = [new MapView(0, $("map0"), $("caption0")), new MapView(1, $("map1"), $("caption1"))];
  await loadStores();
  fillFields();
  $("store").onchange = () => { state.store = +$("store").value; fillFields(); resetBox(); };
  $("field").onchange = () => { state.field = $("field").value; setBox(state.box); };
  $("layer").onchange = () => { state.layer = +$("layer").value; setBox(state.box); };
  $("compare").onchange = () => {
    state.compare = $("compare").value;
    const side = state.compare === "side";
    $("second-map").style.display = side ? "block" : "none";
    for (const v of state.views) {
      v.canvas.width = side ? SIDE_SIZE[0] : MAP_SIZE[0];
      v.canvas.height = side ? SIDE_SIZE[1] : MAP_SIZE[1];
    }
    setBox(state.box);
  };
  $("edges").onchange = loadEdges;
  $("branch").onclick = continueCell;
  $("curves").onchange = () => loadOverlay("curves");
  $("hysteresis").onchange = () => loadOverlay("hysteresis");
  $("line-mode").onclick = () => setMode("line");
  $("zoom-mode").onclick = () => setMode("zoom");
  $("reset").onclick = resetBox;
  $("export-png").onclick = exportPng;
  $("export-svg").onclick = exportSvg;
  $("export-json").onclick = exportJson;
  $("attractors").onclick = () => cellAction("attractors", { k: $("starts").value }, describeAttractors);
  $("cycle").onclick = () => cellAction("cycle", { n: $("cycle-n").value }, describeCycle);
  resetBox();
  watchStores();
}

main().catch((error) => showError(error.message));
