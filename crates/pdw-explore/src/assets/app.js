// pdw-sweep explore: the page. Vanilla JS, no build step; everything from the server's JSON API.
"use strict";

const $ = (id) => document.getElementById(id);
const M = { left: 74, top: 16, right: 16, bottom: 52 }; // basin plot margins (px)

const S = {
  file: 0, base: null, grid: null, job: null, slice: 0,
  walk: null, playing: true, t: 0, speed: 1, frames: 0, lastTs: null,
  clickT0: null, firstFrameMs: null, drag: null, poll: null, hover: null,
};
window.explorer = S; // for the browser test and the console

function showError(msg) {
  const e = $("error");
  e.textContent = msg; e.hidden = !msg;
}

async function api(path, body) {
  const opts = body === undefined ? {} : { method: "POST", body: JSON.stringify(body),
    headers: { "Content-Type": "application/json" } };
  let r;
  try { r = await fetch(path, opts); } catch (err) { throw new Error("the server does not answer: " + err); }
  let j;
  try { j = await r.json(); } catch (err) { throw new Error(`${path}: HTTP ${r.status}, not JSON`); }
  if (!r.ok) throw Object.assign(new Error(j.error || `HTTP ${r.status}`), { status: r.status });
  return j;
}

function fmt(v) {
  if (v === null || v === undefined || !isFinite(v)) return String(v);
  const a = Math.abs(v);
  return (a !== 0 && (a < 1e-3 || a >= 1e4)) ? v.toExponential(4) : v.toPrecision(5);
}

// ---------- the basin ----------

function plotRect() {
  const c = $("basin");
  return { L: M.left, T: M.top, W: c.width - M.left - M.right, H: c.height - M.top - M.bottom };
}

function range(a) { return [a.values[0], a.values[a.values.length - 1]]; }

function colourOf(g) {
  const m = new Map();
  for (const l of g.legend) {
    const h = l.colour;
    m.set(l.code, [parseInt(h.slice(1, 3), 16), parseInt(h.slice(3, 5), 16), parseInt(h.slice(5, 7), 16)]);
  }
  return m;
}

function drawBasin() {
  const g = S.grid, c = $("basin"), ctx = c.getContext("2d");
  ctx.clearRect(0, 0, c.width, c.height);
  if (!g) return;
  const { L, T, W, H } = plotRect();
  const nx = g.nx, ny = g.ny, off = S.slice * ny * nx;
  const img = new ImageData(nx, ny), col = colourOf(g);
  for (let i = 0; i < ny; i++) {
    for (let j = 0; j < nx; j++) {
      const rgb = col.get(g.outcome[off + i * nx + j]) || [255, 0, 255];
      const p = ((ny - 1 - i) * nx + j) * 4; // row 0 (y[0]) at the bottom
      img.data[p] = rgb[0]; img.data[p + 1] = rgb[1]; img.data[p + 2] = rgb[2]; img.data[p + 3] = 255;
    }
  }
  const tmp = document.createElement("canvas");
  tmp.width = nx; tmp.height = ny;
  tmp.getContext("2d").putImageData(img, 0, 0);
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(tmp, L, T, W, H);
  ctx.strokeStyle = "#333"; ctx.strokeRect(L, T, W, H);
  drawAxes(ctx, g, L, T, W, H);
  drawAttractors(ctx, g);
  if (S.drag && S.drag.moved) {
    const d = S.drag;
    ctx.strokeStyle = "#fff"; ctx.lineWidth = 2; ctx.setLineDash([5, 3]);
    ctx.strokeRect(Math.min(d.x0, d.x1), Math.min(d.y0, d.y1), Math.abs(d.x1 - d.x0), Math.abs(d.y1 - d.y0));
    ctx.setLineDash([]); ctx.lineWidth = 1;
  }
  if (S.walkCell) markCell(ctx, S.walkCell);
  Object.assign(c.dataset, { left: L, top: T, width: W, height: H });
}

function ticks(lo, hi, n) {
  const step = Math.pow(10, Math.floor(Math.log10((hi - lo) / n)));
  const err = (hi - lo) / n / step;
  const s = step * (err >= 5 ? 10 : err >= 2 ? 5 : err >= 1.5 ? 2 : 1);
  const out = [];
  for (let v = Math.ceil(lo / s) * s; v <= hi + 1e-12 * Math.abs(hi); v += s) out.push(v);
  return out;
}

function drawAxes(ctx, g, L, T, W, H) {
  const [x0, x1] = range(g.x), [y0, y1] = range(g.y);
  ctx.fillStyle = "#1f2933"; ctx.font = "12px DejaVu Sans, sans-serif";
  ctx.textAlign = "center"; ctx.textBaseline = "top";
  for (const v of ticks(x0, x1, 6)) {
    const px = L + (v - x0) / (x1 - x0) * W;
    ctx.fillRect(px, T + H, 1, 5); ctx.fillText(+v.toPrecision(6), px, T + H + 7);
  }
  ctx.textAlign = "right"; ctx.textBaseline = "middle";
  for (const v of ticks(y0, y1, 6)) {
    const py = T + H - (v - y0) / (y1 - y0) * H;
    ctx.fillRect(L - 5, py, 5, 1); ctx.fillText(+v.toPrecision(6), L - 7, py);
  }
  ctx.textAlign = "center"; ctx.textBaseline = "bottom";
  ctx.fillText(`${g.x.name} [${g.x.units}]`, L + W / 2, T + H + 44);
  ctx.save(); ctx.translate(14, T + H / 2); ctx.rotate(-Math.PI / 2);
  ctx.textBaseline = "top"; ctx.fillText(`${g.y.name} [${g.y.units}]`, 0, 0); ctx.restore();
}

function toPx(g, x, y) {
  const { L, T, W, H } = plotRect(), [x0, x1] = range(g.x), [y0, y1] = range(g.y);
  return [L + (x - x0) / (x1 - x0) * W, T + H - (y - y0) / (y1 - y0) * H];
}

function drawAttractors(ctx, g) {
  const ix = g.section_names.indexOf(g.x.name), iy = g.section_names.indexOf(g.y.name);
  const lines = [];
  for (const a of g.attractors) {
    for (const p of a.points) {
      const [px, py] = toPx(g, p[ix], p[iy]);
      ctx.beginPath(); ctx.arc(px, py, 5, 0, 2 * Math.PI);
      ctx.fillStyle = "#000"; ctx.fill(); ctx.strokeStyle = "#fff"; ctx.lineWidth = 2; ctx.stroke(); ctx.lineWidth = 1;
    }
    if (a.points.length) lines.push(`${a.name}: ${g.x.name} = ${fmt(a.points[0][ix])}, ${g.y.name} = ${fmt(a.points[0][iy])}` + (a.points.length > 1 ? ` (${a.points.length} points)` : ""));
  }
  $("gaitpoint").textContent = lines.join("\n") || "no attractor in this window";
}

function markCell(ctx, wc) {
  if (wc.job !== S.job || wc.slice !== S.slice) return;
  const g = S.grid, [px, py] = toPx(g, g.x.values[wc.col], g.y.values[wc.row]);
  ctx.strokeStyle = "#fff"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(px - 8, py); ctx.lineTo(px + 8, py); ctx.moveTo(px, py - 8); ctx.lineTo(px, py + 8); ctx.stroke();
  ctx.lineWidth = 1;
}

function drawLegend(g) {
  const used = new Set(g.outcome);
  $("legend").innerHTML = "";
  for (const l of g.legend) {
    if (!used.has(l.code)) continue;
    const n = g.outcome.reduce((s, v) => s + (v === l.code), 0);
    const el = document.createElement("span");
    el.innerHTML = `<span class="sw" style="background:${l.colour}"></span>${l.name} ${(100 * n / g.outcome.length).toFixed(1)} %`;
    $("legend").appendChild(el);
  }
}

function cellAt(ev) {
  const g = S.grid; if (!g) return null;
  const r = $("basin").getBoundingClientRect(), { L, T, W, H } = plotRect();
  const px = ev.clientX - r.left, py = ev.clientY - r.top;
  const col = Math.floor((px - L) / W * g.nx), row = Math.floor((T + H - py) / H * g.ny);
  if (col < 0 || row < 0 || col >= g.nx || row >= g.ny) return null;
  return { row, col, px, py };
}

function legendName(g, code) {
  const l = g.legend.find((l) => l.code === code);
  return l ? l.name : `code ${code}`;
}

function hover(ev) {
  if (S.drag) { const d = S.drag; const r = $("basin").getBoundingClientRect();
    d.x1 = ev.clientX - r.left; d.y1 = ev.clientY - r.top;
    d.moved = d.moved || Math.hypot(d.x1 - d.x0, d.y1 - d.y0) > 4; if (d.moved) drawBasin(); }
  const c = cellAt(ev), g = S.grid;
  if (!c) return;
  const k = S.slice * g.ny * g.nx + c.row * g.nx + c.col;
  const z = g.z ? `, ${g.z.name} = ${fmt(g.z.values[S.slice])} ${g.z.units}` : "";
  $("readout").textContent =
    `cell [row ${c.row}, col ${c.col}]  ${g.x.name} = ${fmt(g.x.values[c.col])} ${g.x.units}, ${g.y.name} = ${fmt(g.y.values[c.row])} ${g.y.units}${z}\n` +
    `outcome ${legendName(g, g.outcome[k])}, ${g.strides[k]} strides`;
}

async function showFile(i) {
  S.file = i; S.job = null; S.slice = 0; S.sweep = null; S.design = null;
  $("refinebox").hidden = false; $("basinpanel").hidden = false; $("designbox").hidden = true;
  const kind = S.files && S.files[i] && S.files[i].kind;
  if (kind === "sweep") return showSweep(i);
  if (kind === "design") return showDesign(i);
  try {
    const g = await api(`/api/basin/${i}`);
    S.base = g; setGrid(g);
    $("model").textContent = `${g.model} walker, slope ${fmt(g.slope)} rad, ${g.nx}x${g.ny}${g.nz > 1 ? "x" + g.nz : ""} cells, ${g.max_strides} strides` +
      (g.shard ? `, shard ${g.shard.index} of ${g.shard.count}` : "") + (g.complete ? "" : " (incomplete)");
    buildSliders(g);
    $("slicebox").hidden = !g.z;
    if (g.z) { $("slice").max = g.nz - 1; $("slice").value = Math.floor(g.nz / 2); S.slice = Math.floor(g.nz / 2); sliceLabel(); drawBasin(); }
    $("back").disabled = true; $("save").disabled = true; $("winstatus").textContent = "showing the file";
    showError("");
  } catch (err) {
    S.grid = null; drawBasin();
    showError(`file ${i} cannot be shown: ${err.message}`);
  }
}

function setGrid(g) { S.grid = g; drawBasin(); drawLegend(g); }

function sliceLabel() {
  const g = S.grid; if (!g || !g.z) return;
  $("slicelabel").textContent = `${g.z.name} = ${fmt(g.z.values[S.slice])} ${g.z.units} (${S.slice + 1} of ${g.nz})`;
}

// ---------- refine ----------

function currentBox() {
  const g = S.grid; return { x: range(g.x), y: range(g.y) };
}

function resolution() {
  const v = $("res").value, { W, H } = plotRect();
  return v === "screen" ? [Math.round(W), Math.round(H)] : [+v, +v];
}

function sliderSet() {
  const set = {};
  for (const el of document.querySelectorAll("#sliders input")) {
    if (+el.value !== +el.dataset.file) set[el.dataset.name] = +el.value;
  }
  return set;
}

async function refine(box) {
  const [nx, ny] = resolution();
  const req = { file: S.file, box, nx, ny, slice: S.base.z ? S.slice : 0, set: sliderSet() };
  // Rapid requests (a slider's every step) may be answered out of order: only the latest one
  // sent is followed, and a followed job the server cancelled for a newer one is asked again.
  const seq = (S.refineSeq = (S.refineSeq || 0) + 1);
  S.refineBox = box; S.userCancel = false;
  try {
    const r = await api("/api/refine", req);
    if (seq !== S.refineSeq) return;
    S.job = r.job; S.refineT0 = performance.now();
    $("cancel").disabled = false; $("busy").textContent = "computing the window…";
    pollJob(r.job);
  } catch (err) { showError(err.message); }
}

function pollJob(id) {
  clearTimeout(S.poll);
  S.poll = setTimeout(async () => {
    let j;
    try { j = await api(`/api/job/${id}`); } catch (err) { showError(err.message); return; }
    if (id !== S.job) return;
    $("progress").value = j.total ? j.done / j.total : 0;
    $("winstatus").textContent = `window ${j.status}` + (j.phase ? `, ${j.phase}` : "") + (j.total ? ` (${j.done} of ${j.total} cells)` : "");
    if (j.status === "queued" || j.status === "running") { pollJob(id); return; }
    $("cancel").disabled = true; $("busy").textContent = "";
    if (j.status === "done") {
      S.refineMs = performance.now() - S.refineT0;
      $("winstatus").textContent = `window done: ${j.nx}x${j.ny} cells in ${(S.refineMs / 1000).toFixed(2)} s`;
      $("winstatus").dataset.status = "done";
      S.slice = 0; setGrid(j); $("back").disabled = false; $("save").disabled = false;
    } else if (j.status === "failed" || j.status === "evicted") showError(j.error);
    else if (j.status === "cancelled" && !S.userCancel) refine(S.refineBox);
  }, 60);
}

function buildSliders(g) {
  const box = $("sliders"); box.innerHTML = "";
  for (const p of g.params) {
    const span = p.value !== 0 ? Math.abs(p.value) * 0.5 : 0.1;
    const lab = document.createElement("label"); lab.textContent = p.name;
    const el = document.createElement("input");
    Object.assign(el, { type: "range", min: p.value - span, max: p.value + span, step: span / 100, value: p.value, id: `set-${p.name}` });
    el.dataset.name = p.name; el.dataset.file = p.value;
    const out = document.createElement("output"); out.textContent = fmt(p.value);
    el.addEventListener("input", () => { out.textContent = fmt(+el.value); });
    el.addEventListener("change", () => refine(currentBox()));
    box.append(lab, el, out);
  }
}

// ---------- sweep and continuation files ----------

async function showSweep(i) {
  try {
    const d = await api(`/api/sweep/${i}`);
    S.sweep = d; S.grid = null; S.base = null;
    $("refinebox").hidden = true; $("slicebox").hidden = true;
    $("model").textContent = `${d.model} walker, ${d.branches.length} branch(es) over ${d.parameter}`;
    $("readout").textContent = "click a branch point: its multipliers and its gait walking";
    drawSweep(); showError("");
  } catch (err) { S.sweep = null; drawSweep(); showError(`file ${i} cannot be shown: ${err.message}`); }
}

function sweepAxes(d) {
  let xl = Infinity, xh = -Infinity, yl = Infinity, yh = -Infinity;
  for (const b of d.branches) b.parameter.forEach((p, k) => {
    xl = Math.min(xl, p); xh = Math.max(xh, p); yl = Math.min(yl, b.section[k][0]); yh = Math.max(yh, b.section[k][0]);
  });
  const pad = (lo, hi) => { const m = 0.05 * ((hi - lo) || 1); return [lo - m, hi + m]; };
  return { x: { name: d.parameter, units: "", values: pad(xl, xh) }, y: { name: d.section_names[0], units: "", values: pad(yl, yh) } };
}

function drawSweep() {
  const c = $("basin"), ctx = c.getContext("2d"), d = S.sweep;
  ctx.clearRect(0, 0, c.width, c.height);
  $("legend").innerHTML = "";
  if (!d) return;
  const g = sweepAxes(d), { L, T, W, H } = plotRect();
  ctx.strokeStyle = "#333"; ctx.strokeRect(L, T, W, H);
  drawAxes(ctx, g, L, T, W, H);
  const shades = ["#2563eb", "#059669", "#d97706", "#7c3aed", "#dc2626"];
  d.branches.forEach((b, bi) => {
    const col = shades[bi % shades.length];
    b.parameter.forEach((p, k) => {
      const [px, py] = toPx(g, p, b.section[k][0]);
      ctx.beginPath(); ctx.arc(px, py, 3, 0, 2 * Math.PI);
      if (b.stable[k]) { ctx.fillStyle = col; ctx.fill(); } else { ctx.strokeStyle = col; ctx.stroke(); }
    });
    const el = document.createElement("span");
    el.innerHTML = `<span class="sw" style="background:${col}"></span>${b.name} (filled: stable)`;
    $("legend").appendChild(el);
  });
  if (S.sweepPick) {
    const b = d.branches[S.sweepPick.branch], [px, py] = toPx(g, b.parameter[S.sweepPick.point], b.section[S.sweepPick.point][0]);
    ctx.strokeStyle = "#111"; ctx.lineWidth = 2; ctx.beginPath(); ctx.arc(px, py, 7, 0, 2 * Math.PI); ctx.stroke(); ctx.lineWidth = 1;
  }
  Object.assign(c.dataset, { left: L, top: T, width: W, height: H });
}

function toPxAxes(g, x, y) {
  const { L, T, W, H } = plotRect(), [x0, x1] = range(g.x), [y0, y1] = range(g.y);
  return [L + (x - x0) / (x1 - x0) * W, T + H - (y - y0) / (y1 - y0) * H];
}

async function pickSweep(ev) {
  const d = S.sweep, g = sweepAxes(d), r = $("basin").getBoundingClientRect();
  const mx = ev.clientX - r.left, my = ev.clientY - r.top;
  let best = null;
  d.branches.forEach((b, bi) => b.parameter.forEach((p, k) => {
    const [px, py] = toPxAxes(g, p, b.section[k][0]), dist = Math.hypot(px - mx, py - my);
    if (!best || dist < best.dist) best = { dist, branch: bi, point: k };
  }));
  if (!best || best.dist > 20) return;
  S.clickT0 = performance.now(); S.firstFrameMs = null;
  try {
    const w = await api("/api/gait", { file: S.file, branch: best.branch, point: best.point });
    S.sweepPick = best; drawSweep();
    const mult = w.multipliers.map(([re, im]) => `${fmt(re)}${im ? (im > 0 ? " + " : " - ") + fmt(Math.abs(im)) + "i" : ""} (|λ| ${fmt(Math.hypot(re, im))})`);
    startWalk(w, `${w.branch} ${w.stable ? "stable" : "unstable"}`, `${w.parameter} = ${fmt(w.value)}`,
      `section: ${w.section_names.map((n, k) => `${n} = ${fmt(w.section[k])}`).join(", ")}\n` +
      `period ${fmt(w.period)} (${w.period_strides} stride(s)); multipliers: ${mult.join(", ")}`);
  } catch (err) { showError(err.message); }
}

// ---------- design files ----------

async function showDesign(i) {
  try {
    const d = await api(`/api/design/${i}`);
    S.design = d; S.grid = null; S.base = null; S.designSort = null; S.designPick = null;
    $("basinpanel").hidden = true; $("refinebox").hidden = true; $("designbox").hidden = false;
    const counts = new Map();
    for (const w of d.status_words) counts.set(w, (counts.get(w) || 0) + 1);
    $("model").textContent = `${d.model} walker, design search over ${d.free_names.join(", ")} (objective ${d.objective})`;
    $("designinfo").textContent = `${d.designs} designs: ${[...counts].map(([w, n]) => `${n} ${w}`).join(", ")}. ` +
      "Click a heading to sort (again: the other way), a row to walk that design's gait.";
    drawDesigns(); showError("");
  } catch (err) {
    S.design = null; $("basinpanel").hidden = true; $("refinebox").hidden = true;
    showError(`file ${i} cannot be shown: ${err.message}`);
  }
}

// The table's columns: the design's index, the free parameters, the status (its codes, shown
// in the words of the search picture's legend), then every measure and gait coordinate.
function designColumns(d) {
  const nf = d.free_names.length;
  return [
    { name: "design", units: "", values: d.status.map((_, k) => k) },
    ...d.columns.slice(0, nf),
    { name: "status", units: "", values: d.status, words: d.status_words },
    ...d.columns.slice(nf),
  ];
}

// Row order: by the sorted column's numbers (ascending or descending), NaN and empty cells
// last either way, ties in file order.
function designOrder(cols, sort) {
  const idx = cols[0].values.map((_, k) => k);
  if (!sort) return idx;
  const v = cols[sort.col].values, bad = (x) => x === null || x === undefined || !isFinite(x);
  return idx.sort((a, b) => (bad(v[a]) || bad(v[b]) ? bad(v[a]) - bad(v[b]) : sort.dir * (v[a] - v[b])));
}

function designHeading(c, k) {
  const th = document.createElement("th"), on = S.designSort && S.designSort.col === k;
  const up = on && S.designSort.dir > 0;
  th.append(c.name);
  if (c.units) { const u = document.createElement("span"); u.className = "units"; u.textContent = ` [${c.units}]`; th.append(u); }
  if (on) { const m = document.createElement("span"); m.className = "mark"; m.textContent = up ? " ▲" : " ▼"; th.append(m); }
  th.setAttribute("aria-sort", on ? (up ? "ascending" : "descending") : "none");
  th.dataset.col = k; th.title = "sort by " + c.name;
  th.addEventListener("click", () => {
    S.designSort = on ? { col: k, dir: -S.designSort.dir } : { col: k, dir: 1 };
    drawDesigns();
  });
  return th;
}

function drawDesigns() {
  const d = S.design, cols = designColumns(d), t = $("designs");
  t.replaceChildren();
  const head = t.createTHead().insertRow();
  cols.forEach((c, k) => head.appendChild(designHeading(c, k)));
  const body = t.createTBody();
  for (const i of designOrder(cols, S.designSort)) {
    const tr = body.insertRow();
    tr.dataset.design = i;
    if (d.reasons[i]) tr.title = d.reasons[i];
    if (S.designPick === i) tr.className = "picked";
    for (const c of cols) {
      const v = c.values[i];
      tr.insertCell().textContent = c.words ? c.words[i] : v === null || v === undefined ? "" : c.name === "design" ? String(v) : fmt(v);
    }
    tr.addEventListener("click", () => pickDesign(i));
  }
}

// A row clicked: the design's gait walked by the server (the model rebuilt with its values);
// a design without a gait gets the server's reason as a message instead of an animation.
async function pickDesign(i) {
  const d = S.design, seq = (S.designSeq = (S.designSeq || 0) + 1);
  S.clickT0 = performance.now(); S.firstFrameMs = null; S.designPick = i; drawDesigns();
  const labels = ["design", "parameters"], head = `${i}: ${d.status_words[i]}`;
  const params = d.free_names.map((n, k) => `${n} = ${fmt(d.columns[k].values[i])}`).join(", ");
  $("busy").textContent = "walking…";
  try {
    const w = await api("/api/design_walk", { file: S.file, design: i });
    if (seq !== S.designSeq) return;
    const period = d.columns.find((c) => c.name === "period");
    startWalk(w, head, params, `gait (the file's section state): ${w.section_names.map((n, k) => `${n} = ${fmt(w.section[k])}`).join(", ")}\n` +
      (period ? `period ${fmt(period.values[i])} ${period.units}; ` : "") + `${w.walk.steps_done} strides walked`, labels);
  } catch (err) {
    if (seq !== S.designSeq) return;
    if (err.status === 422) noWalk(head, params, err.message, labels); else showError(err.message);
  } finally { if (seq === S.designSeq) $("busy").textContent = ""; }
}

// ---------- the walk ----------

async function walkCell(c) {
  S.clickT0 = performance.now(); S.firstFrameMs = null;
  const req = { file: S.file, cell: [c.row, c.col], slice: S.job ? 0 : S.slice };
  if (S.job) req.job = S.job;
  $("busy").textContent = "walking…";
  try {
    const w = await api("/api/walk", req);
    S.walkCell = { row: c.row, col: c.col, job: S.job, slice: S.slice };
    const names = w.cell.names;
    startWalk(w, w.outcome, w.stored, `start: ${names.map((n, i) => `${n} = ${fmt(w.cell.state[i])}`).join(", ")}\n` +
      `the engine labels it ${w.outcome} after ${w.strides} strides (file: ${w.stored}, ${w.stored_strides}); ${w.walk.steps_done} steps walked`);
    drawBasin();
  } catch (err) { showError(err.message); }
  $("busy").textContent = "";
}

// Starts the animation and the time plots of a walk answer (`w.walk` as /api/walk gives it),
// with the texts of the outcome row (`labels`: the two headings) and of the info line.
function startWalk(w, outcome, stored, info, labels = ["outcome", "file label"]) {
  S.walk = w; S.t = w.walk.t[0]; S.playing = true; S.lastTs = null; S.awaitFirst = true;
  $("outcomelabel").textContent = labels[0]; $("storedlabel").textContent = labels[1];
  $("outcome").textContent = outcome; $("stored").textContent = stored; $("cellinfo").textContent = info;
  $("walkmsg").hidden = true;
  $("play").disabled = false; $("scrub").disabled = false; $("play").textContent = "pause";
  showError("");
}

// No walk to show: the animation stops, the canvases are cleared and `msg` says why.
function noWalk(outcome, stored, msg, labels) {
  S.walk = null; S.awaitFirst = false;
  $("outcomelabel").textContent = labels[0]; $("storedlabel").textContent = labels[1];
  $("outcome").textContent = outcome; $("stored").textContent = stored; $("cellinfo").textContent = "";
  $("walkmsg").textContent = msg; $("walkmsg").hidden = false;
  $("play").disabled = true; $("scrub").disabled = true;
  const c = $("walker"), ctx = c.getContext("2d");
  ctx.fillStyle = "#fbfbfd"; ctx.fillRect(0, 0, c.width, c.height);
  ctx.fillStyle = "#374151"; ctx.font = "14px DejaVu Sans, sans-serif"; ctx.fillText("nothing to walk: " + msg, 14, 28, c.width - 28);
  $("plots").getContext("2d").clearRect(0, 0, $("plots").width, $("plots").height);
}

function sampleAt(t) {
  const ts = S.walk.walk.t; let lo = 0, hi = ts.length - 1;
  while (hi - lo > 1) { const m = (lo + hi) >> 1; if (ts[m] <= t) lo = m; else hi = m; }
  return lo;
}

function world(x, y, gam) { // slope frame -> world (X forward, Y up)
  return [x * Math.cos(gam) + y * Math.sin(gam), -x * Math.sin(gam) + y * Math.cos(gam)];
}

// The walker's size: the farthest body point from the stance foot at the first sample.
function figureSize(w, P) {
  if (w.size === undefined) {
    let m = 0;
    for (let k = 1; k < P; k++) m = Math.max(m, Math.hypot(w.points[2 * k] - w.points[0], w.points[2 * k + 1] - w.points[1]));
    w.size = m > 0 ? m : 1;
  }
  return w.size;
}

function drawWalker(i) {
  const w = S.walk.walk, c = $("walker"), ctx = c.getContext("2d");
  ctx.fillStyle = "#fbfbfd"; ctx.fillRect(0, 0, c.width, c.height);
  const P = w.point_names.length;
  if (!P) { ctx.fillStyle = "#333"; ctx.fillText("the model gives no body points", 20, 30); return; }
  const gam = w.slope, pts = [];
  for (let k = 0; k < P; k++) pts.push(world(w.points[(i * P + k) * 2], w.points[(i * P + k) * 2 + 1], gam));
  const hipK = Math.max(0, w.point_names.indexOf("hip"));
  const scale = c.height * 0.62 / figureSize(w, P), cx = c.width / 2 - pts[hipK][0] * scale, cy = c.height * 0.82;
  const X = (p) => cx + p[0] * scale, Y = (p) => cy - p[1] * scale;
  // the slope: the line y = 0 of the slope frame
  const g0 = world(-50, 0, gam), g1 = world(50, 0, gam);
  ctx.strokeStyle = "#8b6f47"; ctx.lineWidth = 3;
  ctx.beginPath(); ctx.moveTo(X(g0), Y(g0)); ctx.lineTo(X(g1), Y(g1)); ctx.stroke();
  // strikes so far, marked on the ground where the swing foot landed
  ctx.fillStyle = "#dc2626";
  for (const e of w.events) {
    if (e.t > w.t[i]) break;
    const j = Math.min(sampleAt(e.t), w.t.length - 1);
    const foot = (k) => world(w.points[(j * P + k) * 2], w.points[(j * P + k) * 2 + 1], gam);
    const knee = /knee/.test(e.kind);
    if (knee && w.t[i] - e.t > 0.25 * timeScale(w)) continue; // a knee strike shows briefly
    const swingKnee = w.point_names.findIndex((n) => /swing/.test(n) && /knee/.test(n));
    const p = knee ? foot(Math.max(0, swingKnee)) : foot(P - 1);
    ctx.fillStyle = knee ? "#f59e0b" : "#dc2626";
    ctx.beginPath(); ctx.arc(X(p), Y(p), knee ? 6 : 4, 0, 2 * Math.PI); ctx.fill();
  }
  // legs: the body points in order, stance foot to swing foot
  ctx.strokeStyle = "#1f2933"; ctx.lineWidth = 4; ctx.lineCap = "round"; ctx.lineJoin = "round";
  ctx.beginPath(); ctx.moveTo(X(pts[0]), Y(pts[0]));
  for (let k = 1; k < P; k++) ctx.lineTo(X(pts[k]), Y(pts[k]));
  ctx.stroke();
  w.point_names.forEach((n, k) => {
    const r = n === "hip" ? 9 : /knee/.test(n) ? 4 : 3;
    ctx.beginPath(); ctx.arc(X(pts[k]), Y(pts[k]), r, 0, 2 * Math.PI);
    ctx.fillStyle = n === "hip" ? "#2563eb" : "#1f2933"; ctx.fill();
  });
  if (w.foot_radius > 0) { // round feet: arcs of the foot radius under each foot
    ctx.strokeStyle = "#6b7280"; ctx.lineWidth = 2;
    for (const k of [0, P - 1]) {
      const ctr = [pts[k][0] + w.foot_radius * Math.sin(gam), pts[k][1] + w.foot_radius * Math.cos(gam)];
      ctx.beginPath(); ctx.arc(X(ctr), Y(ctr), w.foot_radius * scale, 0.15 * Math.PI, 0.85 * Math.PI); ctx.stroke();
    }
  }
  ctx.lineWidth = 1; ctx.fillStyle = "#374151"; ctx.font = "12px DejaVu Sans, sans-serif";
  ctx.fillText(`t = ${w.t[i].toFixed(2)} ${w.units.time}`, 10, 18);
}

function series(w) {
  const n = w.t.length, d = w.state_names.length, out = [];
  const angles = [];
  for (let k = 0; k < d / 2; k++) angles.push({ name: w.state_names[k], v: Array.from({ length: n }, (_, i) => w.x[i * d + k]) });
  out.push({ title: "angles [rad]", lines: angles });
  if (w.energy) out.push({ title: `energy [${w.units.energy}]`, lines: [{ name: "E", v: w.energy }] });
  if (w.forces) {
    const lines = [{ name: "normal", v: w.forces.normal }];
    if (w.forces.knee_torque.some((v) => isFinite(v) && v !== 0)) lines.push({ name: "knee torque", v: w.forces.knee_torque });
    out.push({ title: `loads [${w.units.force}]`, lines });
  }
  return out;
}

const LINE_COLOURS = ["#2563eb", "#dc2626", "#059669", "#d97706", "#7c3aed", "#0891b2"];

function drawPlots(i) {
  const w = S.walk.walk, c = $("plots"), ctx = c.getContext("2d");
  ctx.clearRect(0, 0, c.width, c.height);
  const panels = series(w), h = c.height / panels.length, L = 60, R = c.width - 10;
  const t0 = w.t[0], t1 = w.t[w.t.length - 1] || 1;
  const tx = (t) => L + (t - t0) / ((t1 - t0) || 1) * (R - L);
  panels.forEach((p, k) => {
    const top = k * h + 16, bot = (k + 1) * h - 8;
    let lo = Infinity, hi = -Infinity;
    for (const l of p.lines) for (const v of l.v) if (isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (!(hi > lo)) { hi = lo + 1; lo -= 1; }
    const ty = (v) => bot - (v - lo) / (hi - lo) * (bot - top);
    ctx.strokeStyle = "#d1d5db"; ctx.strokeRect(L, top, R - L, bot - top);
    ctx.fillStyle = "#374151"; ctx.font = "11px DejaVu Sans, sans-serif";
    ctx.fillText(p.title, L, top - 4); ctx.fillText(fmt(hi), 4, top + 8); ctx.fillText(fmt(lo), 4, bot);
    ctx.strokeStyle = "#fca5a5";
    for (const e of w.events) { ctx.beginPath(); ctx.moveTo(tx(e.t), top); ctx.lineTo(tx(e.t), bot); ctx.stroke(); }
    p.lines.forEach((l, m) => {
      ctx.strokeStyle = LINE_COLOURS[m % LINE_COLOURS.length]; ctx.beginPath();
      let pen = false;
      for (let j = 0; j < l.v.length; j++) {
        if (!isFinite(l.v[j])) { pen = false; continue; }
        if (pen) ctx.lineTo(tx(w.t[j]), ty(l.v[j])); else ctx.moveTo(tx(w.t[j]), ty(l.v[j]));
        pen = true;
      }
      ctx.stroke(); ctx.fillStyle = ctx.strokeStyle; ctx.fillText(l.name, R - 90 - 70 * m, top - 4);
    });
    ctx.strokeStyle = "#111"; ctx.beginPath(); ctx.moveTo(tx(w.t[i]), top); ctx.lineTo(tx(w.t[i]), bot); ctx.stroke();
  });
}

function frame(ts) {
  requestAnimationFrame(frame);
  if (!S.walk) return;
  const w = S.walk.walk, tEnd = w.t[w.t.length - 1];
  if (S.playing && S.lastTs !== null) {
    S.t += (ts - S.lastTs) / 1000 * S.speed * timeScale(w);
    if (S.t > tEnd) S.t = w.t[0];
  }
  S.lastTs = ts;
  const i = sampleAt(S.t);
  drawWalker(i); drawPlots(i);
  if (S.playing) S.frames += 1;
  $("frame").textContent = S.frames;
  $("stepcount").textContent = w.step[i];
  $("scrub").value = Math.round(1000 * (S.t - w.t[0]) / ((tEnd - w.t[0]) || 1));
  if (S.awaitFirst) {
    S.awaitFirst = false;
    S.firstFrameMs = performance.now() - S.clickT0;
    $("latency").textContent = `click to first frame ${S.firstFrameMs.toFixed(0)} ms`;
  }
}

// Model time per second of animation: a step of the gait takes about a second at 1x.
function timeScale(w) {
  const steps = Math.max(1, w.steps_done);
  return (w.t[w.t.length - 1] - w.t[0]) / steps;
}

// ---------- wiring ----------

function wire() {
  const c = $("basin");
  c.addEventListener("mousemove", (ev) => { if (!S.sweep) hover(ev); });
  c.addEventListener("mousedown", (ev) => {
    const r = c.getBoundingClientRect();
    S.drag = { x0: ev.clientX - r.left, y0: ev.clientY - r.top, x1: ev.clientX - r.left, y1: ev.clientY - r.top, moved: false };
  });
  c.addEventListener("mouseup", (ev) => {
    const d = S.drag; S.drag = null;
    if (S.sweep) { pickSweep(ev); return; }
    if (!d || !S.grid) return;
    const r = c.getBoundingClientRect();
    d.x1 = ev.clientX - r.left; d.y1 = ev.clientY - r.top;
    if (Math.hypot(d.x1 - d.x0, d.y1 - d.y0) <= 4) { const cell = cellAt(ev); if (cell) walkCell(cell); return; }
    const g = S.grid, { L, T, W, H } = plotRect(), [x0, x1] = range(g.x), [y0, y1] = range(g.y);
    const X = (px) => x0 + (Math.min(Math.max(px, L), L + W) - L) / W * (x1 - x0);
    const Y = (py) => y0 + (T + H - Math.min(Math.max(py, T), T + H)) / H * (y1 - y0);
    const box = { x: [X(Math.min(d.x0, d.x1)), X(Math.max(d.x0, d.x1))], y: [Y(Math.max(d.y0, d.y1)), Y(Math.min(d.y0, d.y1))] };
    drawBasin();
    if (box.x[1] > box.x[0] && box.y[1] > box.y[0]) refine(box);
  });
  $("file").addEventListener("change", () => showFile(+$("file").value));
  $("slice").addEventListener("input", () => { S.slice = +$("slice").value; sliceLabel(); drawBasin(); });
  $("play").addEventListener("click", () => { S.playing = !S.playing; $("play").textContent = S.playing ? "pause" : "play"; });
  $("scrub").addEventListener("input", () => {
    if (!S.walk) return; const w = S.walk.walk; S.playing = false; $("play").textContent = "play";
    S.t = w.t[0] + (+$("scrub").value / 1000) * (w.t[w.t.length - 1] - w.t[0]);
  });
  $("speed").addEventListener("change", () => { S.speed = +$("speed").value; });
  $("cancel").addEventListener("click", async () => {
    S.userCancel = true;
    if (S.job !== null) { try { await api(`/api/job/${S.job}/cancel`, {}); } catch (err) { showError(err.message); } }
  });
  $("back").addEventListener("click", () => { S.job = null; setGrid(S.base); $("back").disabled = true; $("save").disabled = true; $("winstatus").textContent = "showing the file"; });
  $("save").addEventListener("click", async () => {
    try { const r = await api("/api/save", { job: S.job }); $("saved").textContent = `saved ${r.saved}`; $("saved").dataset.file = r.saved; }
    catch (err) { showError(err.message); }
  });
}

async function main() {
  wire();
  requestAnimationFrame(frame);
  let files;
  try { files = (await api("/api/files")).files; } catch (err) { showError(err.message); return; }
  S.files = files;
  for (const f of files) {
    const o = document.createElement("option");
    o.value = f.index; o.textContent = `${f.index}: ${f.name}` + (f.kind === "error" ? " (cannot be read)" : ` (${f.model})`);
    $("file").appendChild(o);
  }
  if (files.length) showFile(0); else showError("the server serves no file");
}

main();
