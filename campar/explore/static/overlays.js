// campar explore: what the page draws over a map — typed edges, continued curves,
// hysteresis — each asked of the server once and kept.
"use strict";

// The typed edges of the cells in view (computed by the server, as campar plot does).
async function loadEdges() {
  if (!$("edges").checked) {
    state.edges = null;
    for (const v of activeViews()) v.paint();
    return;
  }
  const store = state.store, b = state.box;
  const have = state.edges;
  if (have && have.store === store && have.box[0] <= b[0] && have.box[1] >= b[1] &&
      have.box[2] <= b[2] && have.box[3] >= b[3]) return; // the view lies in the typed box
  $("status").textContent = "typing the edges …";
  try {
    const data = await api("edges", { store, x0: b[0], x1: b[1], y0: b[2], y1: b[3] });
    state.edges = { store, box: b.slice(), data };
    const counts = Object.entries(data.counts).map(([k, n]) => `${k} ${n}`).join(", ");
    $("status").textContent = `typed edges: ${counts || "none"}` +
      (data.multipliers ? "" : " (no multipliers stored: PD, SN, NS, jump cannot be told)");
  } catch (error) {
    showError(error.message);
  }
  for (const v of activeViews()) v.paint();
}

function resetBox() {
  const s = state.stores[state.store];
  setBox([s.x.edges[0], s.x.edges[1], s.y.edges[0], s.y.edges[1]]);
}

// -- overlays the store has: continued curves, hysteresis -------------------------------

async function loadOverlay(name) {
  const store = state.store, s = state.stores[store];
  const have = state.overlays[store] = state.overlays[store] || {};
  if ($(name).checked && !have[name]) {
    $("status").textContent = `reading the ${name} …`;
    try {
      const data = await api(name, { store });
      if (name === "hysteresis") {
        // cell centres from (row, column): the axes' cells are evenly spaced
        const xs = s.x.values, ys = s.y.values;
        data.centres = data.cells.map(([r, c]) => [xs[c], ys[r]]);
      }
      have[name] = data;
      $("status").textContent = name === "curves" ? `${data.curves.length} continued curves`
        : `${data.cells.length} cells with hysteresis`;
    } catch (error) {
      showError(error.message);
    }
  }
  for (const v of activeViews()) v.paint();
}
