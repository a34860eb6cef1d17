// campar explore: the exports — the map as PNG or SVG, a cell's numbers as JSON.
"use strict";

function download(name, blob) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
}

function exportPng() {
  state.views[0].canvas.toBlob((blob) => download(`${state.stores[state.store].job}-${state.field}.png`, blob));
}

function exportSvg() {
  const v = state.views[0], r = v.rect, c = v.canvas;
  const [ax, ay] = v.toPixel(v.imageBox[0], v.imageBox[3]);
  const [bx, by] = v.toPixel(v.imageBox[1], v.imageBox[2]);
  const s = state.stores[v.storeIndex()], b = state.box;
  const esc = (t) => String(t).replace(/&/g, "&amp;").replace(/</g, "&lt;");
  const parts = [`<svg xmlns="http://www.w3.org/2000/svg" width="${c.width}" height="${c.height}" font-family="sans-serif" font-size="11">`,
    `<clipPath id="plot"><rect x="${r.x}" y="${r.y}" width="${r.w}" height="${r.h}"/></clipPath>`,
    `<image clip-path="url(#plot)" x="${ax}" y="${ay}" width="${bx - ax}" height="${by - ay}" preserveAspectRatio="none" style="image-rendering:pixelated" href="${v.answer.image}"/>`,
    `<rect x="${r.x}" y="${r.y}" width="${r.w}" height="${r.h}" fill="none" stroke="#333"/>`];
  for (const t of niceTicks(b[0], b[1], 8)) {
    const [px] = v.toPixel(t, b[2]);
    parts.push(`<line x1="${px}" x2="${px}" y1="${r.y + r.h}" y2="${r.y + r.h + 4}" stroke="#333"/>`,
      `<text x="${px}" y="${r.y + r.h + 16}" text-anchor="middle">${t}</text>`);
  }
  for (const t of niceTicks(b[2], b[3], 8)) {
    const [, py] = v.toPixel(b[0], t);
    parts.push(`<line x1="${r.x - 4}" x2="${r.x}" y1="${py}" y2="${py}" stroke="#333"/>`,
      `<text x="${r.x - 6}" y="${py + 4}" text-anchor="end">${t}</text>`);
  }
  parts.push(`<text x="${r.x + r.w / 2}" y="${r.y + r.h + 34}" text-anchor="middle">${esc(axisTitle(s.x.name))}</text>`,
    `<text transform="translate(14 ${r.y + r.h / 2}) rotate(-90)" text-anchor="middle">${esc(axisTitle(s.y.name))}</text>`, "</svg>");
  download(`${s.job}-${state.field}.svg`, new Blob([parts.join("\n")], { type: "image/svg+xml" }));
}

function exportJson() {
  const c = state.cell;
  if (!c || !c.report) return;
  download(`cell-${c.row}-${c.col}.json`, new Blob([JSON.stringify(c, null, 1)], { type: "application/json" }));
}
