// gleaner dashboard: talks only to this server's /api/v1. Written for gleaner; no libraries.
"use strict";

// A farms server (`gleaner serve --farms`) marks the page: a farm picker, and the chosen
// farm's routes under /api/v1/farms/{farm} with that farm's token.
const FARMS = document.body.hasAttribute("data-farms");
// Missions per page of the missions panel.
const PAGE = 8;
// Smallest tap target on a phone, CSS px (the map's cells when "tap-size" is on).
const TAP_PX = 44;
// Smallest text on a phone, CSS px (the maps are enlarged until theirs is this big).
const TEXT_PX = 12;
const state = {
  project: null, field: null, preview: null, previewBody: null,
  selected: null, shown: null, colourBy: "s",
  // The missions panel: the page shown (`before` cursor, the cursors of the newer pages,
  // its missions, the `next` cursor), and the newest mission's id.
  page: { before: null, newer: [], missions: [], next: null },
  newest: null,
  farm: null, zoom: false,
};
// Farm tokens given to this page: farm -> {token, scope}.
const farmTokens = {};
const $ = (id) => document.getElementById(id);

// The API's base path: one project's, or the chosen farm's.
function apiBase() {
  return FARMS ? "/api/v1/farms/" + encodeURIComponent(state.farm || "") : "/api/v1";
}

// ---- helpers -------------------------------------------------------------------------

function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (v === null || v === undefined || v === false) continue;
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v === true ? "" : String(v));
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined) continue;
    e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return e;
}

function token() {
  if (FARMS) return state.farm && farmTokens[state.farm] ? farmTokens[state.farm].token : "";
  return $("token").value.trim();
}

function status(text, cls) {
  const s = $("status");
  s.textContent = text;
  s.className = cls || "muted";
}

async function call(method, path, body, { raw = false } = {}) {
  const headers = {};
  // Writes need the token; on a server bound beyond loopback so do previews: send it whenever
  // the page has one.
  if (token()) headers["Authorization"] = "Bearer " + token();
  let payload = body;
  if (body !== undefined && !(body instanceof FormData)) {
    headers["Content-Type"] = "application/json";
    payload = JSON.stringify(body);
  }
  const r = await fetch(apiBase() + path, { method, headers, body: payload });
  if (!r.ok) throw new Error(await failure(r));
  if (r.status === 204) return null;
  return raw ? r.text() : r.json();
}

// A refused request's reason, as the API words it.
async function failure(r) {
  let msg = r.status + " " + r.statusText;
  try {
    const e = await r.json();
    msg = e.reason + (e.field ? " (" + e.field + ")" : "");
  } catch (_) { /* not JSON */ }
  return msg;
}

const kJ = (j) => (j / 1000).toFixed(2);
const pct = (x) => (100 * x).toFixed(1) + "%";
const fmt = (x, d = 3) => (x === null || x === undefined ? "–" : Number(x).toFixed(d));

// A sequential ramp (light yellow to dark blue-green) for cell values in [0, 1].
const RAMP = [[255, 247, 188], [199, 233, 180], [127, 205, 187], [65, 182, 196], [34, 94, 168], [12, 44, 132]];
function ramp(t) {
  t = Math.max(0, Math.min(1, t));
  const x = t * (RAMP.length - 1), i = Math.min(RAMP.length - 2, Math.floor(x)), f = x - i;
  const c = RAMP[i].map((v, k) => Math.round(v + f * (RAMP[i + 1][k] - v)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

// ---- the map ---------------------------------------------------------------------------

function cellValue(cell, key) {
  return cell.scores ? cell.scores[key] : null;
}

function colourCells() {
  const svg = $("map").querySelector("svg");
  if (!svg || !state.field) return;
  const key = state.colourBy;
  const bar = svg.querySelector("#colour-bar");
  if (bar) bar.style.display = key === "s" ? "" : "none";
  const values = state.field.cells.map((c) => cellValue(c, key)).filter((v) => v !== null);
  const lo = Math.min(...values), hi = Math.max(...values);
  svg.querySelectorAll("path.cell").forEach((p) => {
    if (key === "s") { p.style.fill = ""; return; }
    const v = cellValue(state.field.cells[+p.dataset.k], key);
    p.style.fill = v === null ? "#d9d9d9" : ramp(hi > lo ? (v - lo) / (hi - lo) : 0.5);
  });
  const legend = $("legend");
  legend.replaceChildren();
  if (key !== "s" && values.length) {
    const r = el("span", { class: "ramp" });
    r.style.background = `linear-gradient(to right, ${ramp(0)}, ${ramp(0.5)}, ${ramp(1)})`;
    legend.append(fmt(lo, 2), r, fmt(hi, 2));
  }
}

function showSvg(text, caption) {
  const doc = new DOMParser().parseFromString(text, "image/svg+xml");
  const svg = document.importNode(doc.documentElement, true);
  svg.removeAttribute("width");
  svg.removeAttribute("height");
  svg.setAttribute("role", "img");
  const map = $("map");
  map.replaceChildren(svg);
  const tip = $("tooltip");
  svg.querySelectorAll('path[id^="cell-"]').forEach((p) => {
    const k = +p.id.slice(5);
    const cell = state.field && state.field.cells[k];
    if (!cell) return;
    p.classList.add("cell");
    p.dataset.k = k;
    p.dataset.cell = cell.cell;
    if (cell.cell === state.selected) p.classList.add("selected");
    p.addEventListener("mousemove", (ev) => {
      const s = cell.scores;
      tip.textContent = cell.cell + (s ? `  S ${fmt(s.s)}  F ${fmt(s.f, 2)}  R ${fmt(s.r, 2)}  A ${fmt(s.a, 2)}  U ${fmt(s.u, 2)}` : "  not scored");
      tip.style.left = ev.clientX + 12 + "px";
      tip.style.top = ev.clientY + 12 + "px";
      tip.hidden = false;
    });
    p.addEventListener("mouseleave", () => { tip.hidden = true; });
    p.addEventListener("click", () => selectCell(cell.cell));
  });
  $("map-caption").textContent = caption || "";
  colourCells();
  drawBasemap(svg);
  fitMap($("map"), mapSizes());
}

// The main map: tap-size cells when asked (by default on a narrow screen), and then text
// at least TEXT_PX on a narrow screen; "Fit the map" shows the whole field in the box.
function mapSizes() {
  return { cells: state.zoom, text: state.zoom && narrow.matches };
}

// ---- phone sizes: maps enlarged (and scrolled in their box) so that cells are tap-sized --------

// An SVG text's size on the screen, CSS px: its font size times the scale it is drawn at.
function shownTextPx(t) {
  const m = t.getScreenCTM();
  const scale = m ? Math.hypot(m.a, m.b) : 1;
  return parseFloat(getComputedStyle(t).fontSize) * scale;
}

// Draws the SVG in `box` fitted to its width, then enlarged until its smallest cell is TAP_PX
// wide and high (`cells`) and its smallest text TEXT_PX high (`text`). An enlarged map
// scrolls inside its box (centred at first).
function fitMap(box, { cells, text: readable }) {
  const svg = box.querySelector("svg");
  if (!svg) return;
  svg.style.width = "";
  box.classList.remove("zoomed");
  const fitted = svg.getBoundingClientRect().width;
  if (!fitted) return;
  let factor = 1;
  if (cells) {
    let side = Infinity;
    svg.querySelectorAll("path.cell").forEach((p) => {
      const r = p.getBoundingClientRect();
      side = Math.min(side, r.width, r.height);
    });
    if (side > 0 && Number.isFinite(side)) factor = Math.max(factor, (TAP_PX + 1) / side);
  }
  if (readable) {
    let text = Infinity;
    svg.querySelectorAll("text, tspan").forEach((t) => { if (t.textContent.trim()) text = Math.min(text, shownTextPx(t)); });
    if (text > 0 && Number.isFinite(text)) factor = Math.max(factor, (TEXT_PX + 0.5) / text);
  }
  if (factor <= 1) return;
  box.classList.add("zoomed");
  svg.style.width = Math.ceil(fitted * factor) + "px";
  box.scrollLeft = (box.scrollWidth - box.clientWidth) / 2;
  box.scrollTop = (box.scrollHeight - box.clientHeight) / 2;
}

function setZoom(on) {
  state.zoom = on;
  const b = $("map-zoom");
  b.setAttribute("aria-pressed", String(on));
  b.textContent = on ? "Fit the map" : "Tap-size cells";
  fitMap($("map"), mapSizes());
}

async function loadMap(missionId) {
  const id = missionId || state.newest;
  const q = id ? "?mission=" + id : "";
  const text = await call("GET", "/map.svg" + q, undefined, { raw: true });
  state.shown = id;
  showSvg(text, state.shown ? "Mission " + state.shown : "No mission yet");
  renderMissions();
  if (!performance.getEntriesByName("map-ready").length) performance.mark("map-ready");
}

// Optional basemap: XYZ tiles under the cells, placed by fitting the SVG's (equirectangular)
// frame to two cells' known positions.
function drawBasemap(svg) {
  const url = state.project && state.project.basemap_url;
  if (!url || !state.field) return;
  const paths = [...svg.querySelectorAll("path.cell")];
  if (paths.length < 2) return;
  const pick = (p) => { const b = p.getBBox(); const c = state.field.cells[+p.dataset.k].centre_lon_lat; return { x: b.x + b.width / 2, y: b.y + b.height / 2, lon: c[0], lat: c[1] }; };
  const pts = paths.map(pick);
  let a = pts[0], b = pts[0];
  for (const p of pts) { if (Math.abs(p.lon - a.lon) > Math.abs(b.lon - a.lon)) b = p; }
  let c = pts[0];
  for (const p of pts) { if (Math.abs(p.lat - a.lat) > Math.abs(c.lat - a.lat)) c = p; }
  if (b.lon === a.lon || c.lat === a.lat) return;
  const sx = (b.x - a.x) / (b.lon - a.lon), sy = (c.y - a.y) / (c.lat - a.lat);
  const X = (lon) => a.x + (lon - a.lon) * sx, Y = (lat) => a.y + (lat - a.lat) * sy;
  const lons = pts.map((p) => p.lon), lats = pts.map((p) => p.lat);
  const [w, e, s, n] = [Math.min(...lons), Math.max(...lons), Math.min(...lats), Math.max(...lats)];
  const z = Math.max(1, Math.min(19, Math.floor(Math.log2(360 / Math.max(1e-6, (e - w) * 3)))));
  const tx = (lon) => Math.floor((lon + 180) / 360 * 2 ** z);
  const ty = (lat) => { const r = lat * Math.PI / 180; return Math.floor((1 - Math.log(Math.tan(r) + 1 / Math.cos(r)) / Math.PI) / 2 * 2 ** z); };
  const lonOf = (x) => x / 2 ** z * 360 - 180;
  const latOf = (y) => { const m = Math.PI - 2 * Math.PI * y / 2 ** z; return 180 / Math.PI * Math.atan(Math.sinh(m)); };
  const g = document.createElementNS("http://www.w3.org/2000/svg", "g");
  g.setAttribute("id", "basemap");
  g.setAttribute("opacity", "0.6");
  for (let x = tx(w) - 1; x <= tx(e) + 1; x++) {
    for (let y = ty(n) - 1; y <= ty(s) + 1; y++) {
      const img = document.createElementNS("http://www.w3.org/2000/svg", "image");
      const x0 = X(lonOf(x)), x1 = X(lonOf(x + 1)), y0 = Y(latOf(y)), y1 = Y(latOf(y + 1));
      img.setAttribute("href", url.replace("{z}", z).replace("{x}", x).replace("{y}", y));
      img.setAttribute("x", Math.min(x0, x1)); img.setAttribute("y", Math.min(y0, y1));
      img.setAttribute("width", Math.abs(x1 - x0)); img.setAttribute("height", Math.abs(y1 - y0));
      img.setAttribute("preserveAspectRatio", "none");
      g.append(img);
    }
  }
  const cells = svg.querySelector("#cells");
  if (cells) { cells.parentNode.insertBefore(g, cells); cells.setAttribute("fill-opacity", "0.75"); }
}

// ---- cell panel ----------------------------------------------------------------------------

function sparkline(series) {
  const W = 360, H = 80, P = 4;
  const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  svg.setAttribute("class", "spark");
  const t0 = series.t[0], t1 = series.t[series.t.length - 1];
  const v0 = Math.min(...series.values), v1 = Math.max(...series.values);
  const x = (t) => P + (t1 > t0 ? (t - t0) / (t1 - t0) : 0.5) * (W - 2 * P);
  const y = (v) => H - P - (v1 > v0 ? (v - v0) / (v1 - v0) : 0.5) * (H - 2 * P);
  const line = document.createElementNS("http://www.w3.org/2000/svg", "polyline");
  line.setAttribute("points", series.t.map((t, i) => x(t).toFixed(1) + "," + y(series.values[i]).toFixed(1)).join(" "));
  line.setAttribute("fill", "none");
  line.setAttribute("stroke", "#3b6ea5");
  line.setAttribute("stroke-width", "1.5");
  svg.append(line);
  return svg;
}

async function selectCell(id) {
  state.selected = id;
  document.querySelectorAll("path.cell").forEach((p) => p.classList.toggle("selected", p.dataset.cell === id));
  $("cell-hint").textContent = "Loading " + id + "…";
  try {
    const d = await call("GET", "/cells/" + encodeURIComponent(id) + "?days=60");
    renderCell(d);
  } catch (e) {
    $("cell-hint").textContent = e.message;
  }
}

function renderCell(d) {
  const c = d.cell, s = c.scores;
  $("cell-hint").textContent = "";
  const body = $("cell-body");
  body.replaceChildren();
  body.append(el("h3", {}, "Cell ", c.cell), el("p", { class: "muted" },
    `sensors ${c.sensors.join(", ")} · last collected ${c.last_collected || "never"}`));
  if (!s) {
    body.append(el("p", {}, "Not scored yet: run a scoring or plan a mission."));
  } else {
    const w = d.weights, k = d.contributions;
    const rows = [
      ["F freshness", s.freshness, w[0], k.freshness],
      ["A anomaly", s.anomaly, w[1], k.anomaly],
      ["U uncertainty", s.uncertainty, w[2], k.uncertainty],
      ["R redundancy", s.redundancy, w[3], k.redundancy],
    ];
    const max = Math.max(...rows.map((r) => Math.abs(r[3])), 1e-9);
    const t = el("table", { class: "terms" }, el("tr", {}, el("th", {}, "term"), el("th", {}, "value"), el("th", {}, "weight"), el("th", {}, "in S"), el("th", {}, "")));
    for (const [name, v, wt, contrib] of rows) {
      const bar = el("div", { class: "hbar" + (contrib < 0 ? " neg" : "") });
      bar.style.width = (100 * Math.abs(contrib) / max).toFixed(1) + "%";
      t.append(el("tr", {}, el("td", {}, name), el("td", {}, fmt(v)), el("td", {}, fmt(wt, 2)), el("td", {}, (contrib >= 0 ? "+" : "") + fmt(contrib)), el("td", { class: "bar-cell" }, bar)));
    }
    t.append(el("tr", {}, el("th", {}, "S"), el("th", {}, fmt(s.score)), el("th", {}), el("th", {}), el("th", {})));
    body.append(t, el("p", { id: "cell-why" },
      `Ranks #${d.rank} of ${d.scored} scored cells; its largest term is ${d.driver}` +
      (k.redundancy < -0.05 ? ", held down by redundancy with its neighbours." : ".")));
  }
  if (d.series.length) {
    const sel = el("select", {}, d.series.map((sr, i) => el("option", { value: i }, sr.sensor + " " + sr.modality)));
    const holder = el("div");
    const draw = () => {
      const sr = d.series[+sel.value];
      const last = sr.values[sr.values.length - 1];
      holder.replaceChildren(sparkline(sr), el("p", { class: "muted" },
        `${sr.values.length} readings to ${d.latest}; latest ${fmt(last)} (min ${fmt(Math.min(...sr.values))}, max ${fmt(Math.max(...sr.values))})`));
    };
    const vw = d.series.findIndex((sr) => sr.modality.startsWith("vw"));
    if (vw >= 0) sel.value = vw;
    sel.addEventListener("change", draw);
    body.append(el("label", {}, "Recent series (60 days)", sel), holder);
    draw();
  }
  estimatedSeries(c.cell, body);
}

// ---- a cell's estimated series with its 90% band ---------------------------------------------

const SVG_NS = "http://www.w3.org/2000/svg";
function svgEl(tag, attrs, text) {
  const e = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

// RFC 3339 without milliseconds (what the API takes).
const isoSeconds = (ms) => new Date(ms).toISOString().replace(/\.\d{3}Z$/, "Z");

// A unit as printed.
function prettyUnit(u) {
  if (!u) return "";
  return u === "m3/m3" ? "m³/m³" : u === "degC" ? "°C" : u;
}

// Round tick values over [lo, hi]: about `n` of them.
function niceTicks(lo, hi, n) {
  const span = hi - lo;
  if (!(span > 0)) return [lo];
  const raw = span / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(+v.toFixed(12));
  return out;
}

// One sensor's chart: the 90% interval as a band, the mean as a line, readings as dots,
// dated x axis and a y axis in the modality's unit.
function bandChart(sensor, times, mean, lo, hi, readings, quantity, unit, estimator) {
  // Text is 14 units high (app.css), at least 12 px where the chart is 310 px wide or more.
  const W = 360, H = 206, L = 58, R = 10, T = 26, B = 44;
  const svg = svgEl("svg", { viewBox: `0 0 ${W} ${H}`, class: "estimate", "data-sensor": sensor, role: "img" });
  const t0 = times[0], t1 = times[times.length - 1];
  const values = lo.concat(hi, readings.map((r) => r[1])).filter((v) => Number.isFinite(v));
  let v0 = Math.min(...values), v1 = Math.max(...values);
  if (!(v1 > v0)) { v0 -= 0.01; v1 += 0.01; }
  const pad = 0.05 * (v1 - v0);
  v0 -= pad; v1 += pad;
  const x = (t) => L + (t1 > t0 ? (t - t0) / (t1 - t0) : 0.5) * (W - L - R);
  const y = (v) => T + (1 - (v - v0) / (v1 - v0)) * (H - T - B);
  const f = (n) => n.toFixed(1);
  svg.append(svgEl("text", { x: L, y: 16 }, `${sensor} · ${quantity} · ${estimator}`));
  // Band: upper edge forwards, lower edge back.
  let d = times.map((t, i) => (i ? "L" : "M") + f(x(t)) + " " + f(y(hi[i]))).join("");
  for (let i = times.length - 1; i >= 0; i--) d += "L" + f(x(times[i])) + " " + f(y(lo[i]));
  svg.append(svgEl("path", { class: "band", d: d + "Z" }));
  svg.append(svgEl("polyline", { class: "mean", points: times.map((t, i) => f(x(t)) + "," + f(y(mean[i]))).join(" ") }));
  const dots = svgEl("g", { class: "readings" });
  for (const [t, v] of readings) dots.append(svgEl("circle", { class: "reading", cx: f(x(t)), cy: f(y(v)), r: 2 }));
  svg.append(dots);
  // Axes.
  const xa = svgEl("g", { class: "axis x-axis" });
  xa.append(svgEl("path", { d: `M${L} ${H - B}H${W - R}` }));
  const days = (t1 - t0) / 86400e3;
  const stepDays = days > 120 ? 30 : days > 45 ? 21 : days > 14 ? 7 : days > 4 ? 2 : 1;
  const first = Math.ceil(t0 / 86400e3 / stepDays) * stepDays;
  for (let k = first; k * 86400e3 <= t1; k += stepDays) {
    const t = k * 86400e3, px = x(t);
    xa.append(svgEl("line", { x1: f(px), y1: H - B, x2: f(px), y2: H - B + 3 }));
    xa.append(svgEl("text", { x: f(px), y: H - B + 17, "text-anchor": "middle" }, new Date(t).toISOString().slice(5, 10)));
  }
  xa.append(svgEl("text", { x: f((L + W - R) / 2), y: H - 5, "text-anchor": "middle" },
    `date (UTC), ${new Date(t0).toISOString().slice(0, 10)} to ${new Date(t1).toISOString().slice(0, 10)}`));
  svg.append(xa);
  const ya = svgEl("g", { class: "axis y-axis" });
  ya.append(svgEl("path", { d: `M${L} ${T}V${H - B}` }));
  const ticks = niceTicks(v0, v1, 4);
  const dec = Math.max(0, Math.min(6, -Math.floor(Math.log10((ticks[1] - ticks[0]) || 1))));
  for (const v of ticks) {
    ya.append(svgEl("line", { x1: L - 3, y1: f(y(v)), x2: L, y2: f(y(v)) }));
    ya.append(svgEl("text", { x: L - 5, y: f(y(v) + 5), "text-anchor": "end" }, v.toFixed(dec)));
  }
  const label = quantity.toUpperCase() + (unit ? ` (${unit})` : "");
  ya.append(svgEl("text", { x: 12, y: f((T + H - B) / 2), "text-anchor": "middle", transform: `rotate(-90 12 ${f((T + H - B) / 2)})` }, label));
  svg.append(ya);
  return svg;
}

async function estimatedSeries(cellId, body) {
  const latest = state.project && state.project.latest_reading;
  if (!latest) return;
  const range = el("select", { id: "estimate-range" },
    el("option", { value: "7" }, "last 7 days"), el("option", { value: "30" }, "last 30 days"),
    el("option", { value: "90" }, "last 90 days"));
  range.value = "30";
  const estimator = el("select", { id: "estimate-estimator" },
    el("option", { value: "changes" }, "kriging of changes"), el("option", { value: "dynamic" }, "dynamic field model"),
    el("option", { value: "levels" }, "kriging of levels"));
  const holder = el("div", { id: "estimate-chart" }, el("p", { class: "muted" }, "Estimating…"));
  body.append(el("h3", {}, "Estimated series"),
    el("div", { class: "estimate-controls" }, el("label", {}, "Range (6-hour steps)", range), el("label", {}, "Estimator", estimator)),
    holder,
    el("p", { class: "muted" }, "Line: estimated mean; band: 90% interval; dots: readings. ",
      el("a", { href: "#field-map-pane", class: "link", id: "estimate-field-map", onclick: (e) => { e.preventDefault(); showFieldMap(latest); } }, "Field map at the range's end")));
  const draw = async () => {
    const days = +range.value;
    const to = Date.parse(latest), from = to - days * 86400e3;
    holder.replaceChildren(el("p", { class: "muted" }, "Estimating…"));
    try {
      const q = `?from=${isoSeconds(from)}&to=${isoSeconds(to)}&every_hours=6&cell=${encodeURIComponent(cellId)}&estimator=${estimator.value}`;
      const [doc, detail] = await Promise.all([
        call("GET", "/reconstruct" + q),
        call("GET", "/cells/" + encodeURIComponent(cellId) + "?days=" + (days + 1)),
      ]);
      if (state.selected !== cellId) return;
      const times = doc.times.map((t) => Date.parse(t));
      const unit = prettyUnit(doc.unit);
      const quantity = doc.modality.split("@")[0];
      const charts = doc.sensors.map((s, j) => {
        const sr = detail.series.find((r) => r.sensor === s.sensor && r.modality === doc.modality);
        const readings = sr ? sr.t.map((t, i) => [t * 1000, sr.values[i]]).filter((r) => r[0] >= from && r[0] <= to) : [];
        return bandChart(s.sensor, times, doc.mean.map((r) => r[j]), doc.lo90.map((r) => r[j]), doc.hi90.map((r) => r[j]),
          readings, quantity, unit, doc.estimator);
      });
      holder.replaceChildren(...charts, el("p", { class: "muted", id: "estimate-facts" },
        `${doc.modality}: ${doc.times.length} estimates from ${doc.times[0]} to ${doc.times[doc.times.length - 1]}`));
    } catch (e) {
      holder.replaceChildren(el("p", { class: "error" }, e.message));
    }
  };
  range.addEventListener("change", draw);
  estimator.addEventListener("change", draw);
  await draw();
}

// ---- the estimated field map -------------------------------------------------------------------

async function fetchBlob(path) {
  const headers = {};
  if (token()) headers["Authorization"] = "Bearer " + token();
  const r = await fetch(apiBase() + path, { headers });
  if (!r.ok) throw new Error(await failure(r));
  return r.blob();
}

// Saves a blob as a file through a temporary link.
function saveBlob(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = el("a", { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

function fieldMapQuery() {
  const at = $("field-map-at").value.trim();
  return at ? "?at=" + encodeURIComponent(at) : "";
}

async function showFieldMap(at) {
  const pane = $("field-map-pane");
  pane.hidden = false;
  if (at !== undefined) $("field-map-at").value = at || "";
  const box = $("field-map");
  box.replaceChildren(el("p", { class: "muted" }, "Drawing the estimated field…"));
  try {
    const text = await (await fetchBlob("/reconstruct/map.svg" + fieldMapQuery())).text();
    const doc = new DOMParser().parseFromString(text, "image/svg+xml");
    const svg = document.importNode(doc.documentElement, true);
    svg.removeAttribute("width");
    svg.removeAttribute("height");
    svg.setAttribute("role", "img");
    svg.setAttribute("id", "field-map-svg-figure");
    box.replaceChildren(svg);
    fitMap(box, { cells: false, text: narrow.matches });
    pane.scrollIntoView({ block: "nearest" });
  } catch (e) {
    box.replaceChildren(el("p", { class: "error" }, e.message));
  }
}

async function downloadFieldMap(ext) {
  try {
    saveBlob(await fetchBlob("/reconstruct/map." + ext + fieldMapQuery()), "field-map." + ext);
  } catch (e) {
    status("Field map: " + e.message, "error");
  }
}

// ---- planning --------------------------------------------------------------------------------

function planBody(dryRun) {
  const f = new FormData($("plan-form"));
  const b = { dry_run: dryRun };
  for (const k of ["at", "history_until", "solver", "energy_preset"]) if (f.get(k)) b[k] = f.get(k);
  for (const k of ["time_limit_s"]) if (f.get(k) !== "") b[k] = Number(f.get(k));
  for (const k of ["seed", "iterations"]) if (f.get(k) !== "") b[k] = parseInt(f.get(k), 10);
  // A forecast wind (m/s, degrees clockwise from north it blows from); the project's when empty.
  if (f.get("wind_mps") !== "") {
    b.wind = { speed_mps: Number(f.get("wind_mps")), from_deg: Number(f.get("wind_from_deg") || 0) };
  }
  return b;
}

// The wind a route was planned in and the strongest it stands (m/s; directions in degrees).
function windView(w) {
  if (!w) return null;
  const stands = w.strongest_feasible_mps === undefined ? "" :
    w.strongest_capped ? " · stands any wind up to " + w.strongest_feasible_mps + " m/s" :
    " · stays within the battery up to " + w.strongest_feasible_mps.toFixed(1) + " m/s from there";
  const calm = w.over_budget_in_still_air
    ? " · over the battery in still air (hovering costs more without wind)" : "";
  return el("p", { id: "wind-summary" },
    w.forecast_mps > 0
      ? `Wind ${w.forecast_mps} m/s from ${w.from_deg}° (priced at ${w.planned_mps} m/s with the margin)${stands}${calm}`
      : `Still air${stands}`);
}

// ---- simulation ------------------------------------------------------------------------------

// The simulate request the form says: strategies, first mission, planner cap and the weather
// (a daily Weibull wind of the given mean, m/s, with its forecast error, m/s; still air else).
function simulateBody() {
  const f = new FormData($("simulate-form"));
  const b = {};
  const names = (f.get("strategies") || "").split(",").map((s) => s.trim()).filter(Boolean);
  if (names.length) b.strategies = names;
  if (f.get("start")) b.start = f.get("start");
  if (f.get("planner_iterations") !== "") b.planner_iterations = parseInt(f.get("planner_iterations"), 10);
  if (f.get("weather") === "weibull") {
    b.wind = "weibull:" + (f.get("wind_mean_mps") || "4");
    if (f.get("gust") !== "") b.gust = Number(f.get("gust"));
  }
  if (f.get("report")) b.report = true;
  return b;
}

// Object URLs of the report shown (its charts and Markdown), released when it is replaced.
let reportUrls = [];

// The campaign's report, when asked for: its charts (SVG, drawn as images: no script of
// theirs runs in the page) and the Markdown to download, as `gleaner simulate` writes them.
function reportView(report) {
  for (const u of reportUrls) URL.revokeObjectURL(u);
  reportUrls = [];
  if (!report) return null;
  const url = (text, type) => {
    const u = URL.createObjectURL(new Blob([text], { type }));
    reportUrls.push(u);
    return u;
  };
  const figures = report.figures.map((f) => el("figure", { "data-name": f.name },
    el("img", { src: url(f.svg, "image/svg+xml"), alt: f.name }),
    el("figcaption", {}, f.name)));
  return el("div", { id: "sim-report" },
    el("p", {}, el("a", { class: "link", id: "sim-report-md", href: url(report.markdown, "text/markdown"), download: "report.md" },
      "Report (Markdown)"), ` · ${report.figures.length} charts`),
    ...figures);
}

// The campaign's answer: per strategy the error after the flights and the energy; in wind,
// how the sorties flew (over budget, re-planned in the air, stops dropped).
function campaignView(doc) {
  const mean = (m) => (m && m.mean !== null && m.mean !== undefined ? m.mean : null);
  const rows = doc.strategies.map((x) => el("tr", { "data-strategy": x.strategy },
    el("td", {}, x.strategy + (doc.strategies.some((y) => y.budget !== x.budget) ? " ×" + x.budget : "")),
    el("td", {}, fmt(mean(x.metrics.rmse_kriged), 4)),
    el("td", {}, fmt(mean(x.metrics.energy_kj), 1)),
    el("td", {}, x.events_caught + " of " + x.events)));
  const parts = [
    el("p", {}, `${doc.missions} missions, ${(doc.first_mission || "–").slice(0, 10)} to ${(doc.last_mission || "–").slice(0, 10)}`),
    el("table", { id: "sim-strategies" },
      el("tr", {}, el("th", {}, "strategy"), el("th", {}, "RMSE after"), el("th", {}, "energy, kJ"), el("th", {}, "events caught"))),
  ];
  parts[1].append(...rows);
  if (doc.flights && doc.flights.length) {
    const t = el("table", { id: "sim-flights" },
      el("tr", {}, el("th", {}, "strategy"), el("th", {}, "mean forecast, m/s"), el("th", {}, "over budget"),
        el("th", {}, "re-planned"), el("th", {}, "stops dropped")));
    for (const f of doc.flights) {
      t.append(el("tr", { "data-strategy": f.strategy },
        el("td", {}, f.strategy),
        el("td", {}, fmt(f.mean_forecast_mps, 1)),
        el("td", { class: "over-budget" }, f.over_budget),
        el("td", { class: "replanned" }, f.replanned),
        el("td", { class: "dropped" }, f.cells_dropped)));
    }
    parts.push(el("p", { class: "muted" }, "Sorties in the simulated wind:"), t);
  }
  const report = reportView(doc.report);
  if (report) parts.push(report);
  return el("div", {}, ...parts);
}

async function simulate(ev) {
  ev.preventDefault();
  const body = simulateBody();
  status("Simulating…");
  $("simulate").disabled = true;
  $("simulate-result").replaceChildren(el("p", { class: "muted" }, "Simulating…"));
  try {
    const doc = await call("POST", "/simulate", body);
    $("simulate-result").replaceChildren(campaignView(doc));
    status("Simulation done.", "ok");
  } catch (e) {
    $("simulate-result").replaceChildren(el("p", { class: "error" }, e.message));
    status("Simulation failed.", "error");
  } finally {
    $("simulate").disabled = false;
  }
}

function energyView(m) {
  const e = m.energy;
  const scale = Math.max(e.budget_j, e.total_j);
  const bar = el("div", { class: "bar", title: "E_t, E_h, E_c, E_r against the usable budget" });
  for (const [cls, v] of [["et", e.travel_j], ["eh", e.hover_j], ["ec", e.comm_j], ["er", e.return_j]]) {
    const s = el("span", { class: cls });
    s.style.width = (100 * v / scale).toFixed(2) + "%";
    bar.append(s);
  }
  const key = (cls, label, v) => el("span", {}, el("i", { class: "" }, ""), label + " " + kJ(v) + " kJ");
  const keys = el("div", { class: "keys" });
  for (const [cls, label, v] of [["et", "E_t travel", e.travel_j], ["eh", "E_h hover", e.hover_j], ["ec", "E_c radio", e.comm_j], ["er", "E_r return", e.return_j]]) {
    const k = key(cls, label, v);
    k.firstChild.style.background = getComputedStyle(document.documentElement).getPropertyValue("--" + cls);
    keys.append(k);
  }
  return el("div", {},
    el("p", {}, el("strong", {}, m.stops.length + " cells"), ` · total S ${fmt(m.total_score, 2)} · planner ${m.planner} · t = ${m.planned_at}`),
    bar, keys,
    el("p", {}, "Energy ", el("strong", { id: "energy-total", "data-joules": e.total_j }, kJ(e.total_j) + " kJ"),
      ` of ${kJ(e.budget_j)} kJ usable (${pct(e.utilisation)}) · ${(e.distance_m / 1000).toFixed(2)} km · ${(e.flight_time_s / 60).toFixed(1)} min`),
    windView(m.wind),
    el("p", { class: "muted" }, "Route: base → " + m.stops.map((s) => s.cell).join(" → ") + " → base"));
}

async function preview(ev) {
  ev.preventDefault();
  const body = planBody(true);
  status("Planning (dry run)…");
  $("preview").disabled = true;
  // Whatever was previewed before is not what the form says now: nothing to save until this
  // preview succeeds.
  state.preview = null;
  state.previewBody = null;
  $("save").disabled = true;
  try {
    const m = await call("POST", "/plan", body);
    state.preview = m;
    state.previewBody = body;
    const svg = await call("POST", "/map.svg", m, { raw: true });
    showSvg(svg, "Preview (not saved)");
    $("plan-result").replaceChildren(el("p", { class: "muted" }, "Preview — not saved yet:"), energyView(m));
    $("save").disabled = false;
    status("Route planned: check it, then save.", "ok");
  } catch (e) {
    $("plan-result").replaceChildren(el("p", { class: "error" }, e.message));
    status("Planning failed.", "error");
  } finally {
    $("preview").disabled = false;
  }
}

async function save() {
  if (!state.previewBody) return;
  $("save").disabled = true;
  status("Saving the mission…");
  try {
    const m = await call("POST", "/plan", { ...state.previewBody, dry_run: false });
    $("plan-result").replaceChildren(el("p", { class: "ok", id: "saved" }, "Saved as mission " + m.mission_id + "."), energyView(m));
    state.page = { before: null, newer: [], missions: [], next: null };
    await refresh();
    await loadMap(m.mission_id);
    if (state.selected) await selectCell(state.selected);
    status("Mission " + m.mission_id + " saved.", "ok");
  } catch (e) {
    $("plan-result").append(el("p", { class: "error" }, e.message));
    $("save").disabled = false;
    status("Saving failed.", "error");
  }
}

// ---- missions: pages, cancel, delete, downloads -------------------------------------------------

// What a mission's status is called on the page.
const STATUS = { planned: "planned", flown: "recorded", cancelled: "cancelled" };

// Loads the page of missions below `state.page.before` (newest first).
async function loadPage() {
  const before = state.page.before;
  const p = await call("GET", `/missions/page?limit=${PAGE}` + (before ? `&before=${before}` : ""));
  state.page.missions = p.missions;
  state.page.next = p.next;
  if (before === null) state.newest = p.missions.length ? p.missions[0].mission_id : null;
}

function missionsError(text) {
  const e = $("missions-error");
  e.textContent = text || "";
  e.hidden = !text;
}

async function turnPage(older) {
  const pg = state.page;
  const before = pg.before;
  if (older) {
    if (pg.next === null) return;
    pg.newer.push(pg.before);
    pg.before = pg.next;
  } else {
    if (!pg.newer.length) return;
    pg.before = pg.newer.pop();
  }
  try {
    await loadPage();
    missionsError("");
  } catch (e) {
    // Stay where we were.
    if (older) pg.before = pg.newer.pop(); else { pg.newer.push(pg.before); pg.before = before; }
    missionsError("Cannot load the missions: " + e.message);
  }
  renderMissions();
}

// Asks on the page (not a browser dialog) whether to go on; resolves true or false. A new
// question answers the previous one "no".
let pendingConfirm = null;
function confirmOnPage(text, yes) {
  if (pendingConfirm) pendingConfirm(false);
  const box = $("missions-confirm");
  $("missions-confirm-text").textContent = text;
  $("confirm-yes").textContent = yes;
  box.hidden = false;
  return new Promise((resolve) => {
    pendingConfirm = (answer) => {
      pendingConfirm = null;
      box.hidden = true;
      resolve(answer);
    };
    $("confirm-yes").focus();
  });
}

// Cancels (`cancel`) or deletes a mission after asking, then shows the page again.
async function changeMission(id, cancel) {
  const question = cancel
    ? `Cancel mission #${id}? It stays in the history as cancelled and can no longer be recorded or exported.`
    : `Delete mission #${id}? Its plan and stops are removed for good.`;
  if (!(await confirmOnPage(question, cancel ? "Yes, cancel it" : "Yes, delete it"))) return;
  status((cancel ? "Cancelling" : "Deleting") + " mission " + id + "…");
  try {
    if (cancel) await call("POST", `/missions/${id}/cancel`, {});
    else await call("DELETE", `/missions/${id}`);
    missionsError("");
    status(`Mission ${id} ${cancel ? "cancelled" : "deleted"}.`, "ok");
  } catch (e) {
    missionsError(`${cancel ? "Cancelling" : "Deleting"} mission #${id} failed: ${e.message}`);
    status("Mission " + id + " unchanged.", "error");
    return;
  }
  try {
    await refresh();
    // A page emptied by the delete: show the newer one.
    while (!state.page.missions.length && state.page.newer.length) {
      state.page.before = state.page.newer.pop();
      await loadPage();
    }
    if (state.shown === id) await loadMap(null); else renderMissions();
  } catch (e) {
    missionsError("Cannot load the missions: " + e.message);
  }
}

function missionRow(m) {
  const id = m.mission_id;
  const actions = [];
  if (m.status === "planned") {
    actions.push(el("button", { type: "button", class: "secondary cancel", title: "Cancel mission " + id, onclick: () => changeMission(id, true) }, "Cancel"));
  }
  if (m.status !== "flown") {
    actions.push(el("button", { type: "button", class: "secondary delete", title: "Delete mission " + id, onclick: () => changeMission(id, false) }, "Delete"));
  }
  return el("li", { class: "mission" + (id === state.shown ? " current" : ""), "data-mission": id, "data-status": m.status },
    el("button", { type: "button", class: "show", title: "Show mission " + id + " on the map", onclick: () => loadMap(id) },
      el("strong", {}, "#" + id), " ", m.kind, " ",
      el("span", { class: "status " + m.status }, STATUS[m.status] || m.status),
      el("span", { class: "facts" }, `${m.planned_at.slice(0, 10)} · ${m.stops.length} cells · ${pct(m.energy.utilisation)}`)),
    el("span", { class: "actions" }, actions));
}

function renderMissions() {
  const pg = state.page;
  const box = $("missions");
  if (!pg.missions.length) {
    box.replaceChildren(el("p", { class: "muted" }, "No missions yet."));
  } else {
    box.replaceChildren(el("ul", { class: "mission-list" }, pg.missions.map(missionRow)));
  }
  const total = state.project ? state.project.missions : pg.missions.length;
  $("missions-range").textContent = pg.missions.length
    ? `#${pg.missions[0].mission_id} to #${pg.missions[pg.missions.length - 1].mission_id} · ${total} in all`
    : "";
  $("missions-newer").disabled = !pg.newer.length;
  $("missions-older").disabled = pg.next === null;

  const dl = $("downloads");
  dl.replaceChildren();
  const shown = pg.missions.find((m) => m.mission_id === state.shown);
  if (state.shown && shown && shown.status === "cancelled") {
    dl.append(el("span", { class: "muted" }, `Mission ${state.shown} is cancelled: no flight files.`));
  } else if (state.shown) {
    const files = [["mission.plan", ".plan"], ["mission.kmz", "DJI .kmz"], ["mission.waypoints", "WPL"], ["mission.geojson", "GeoJSON"], ["mission.svg", "SVG"], ["mission.png", "PNG"]];
    dl.append(el("span", { class: "muted" }, "Mission " + state.shown + ":"));
    for (const [name, label] of files) {
      const path = `/missions/${state.shown}/files/${name}`, file = `mission-${state.shown}.${name.slice(8)}`;
      // A farm's files need its token: fetched, then saved.
      const onclick = FARMS ? async (e) => {
        e.preventDefault();
        try { saveBlob(await fetchBlob(path), file); } catch (err) { status("Download: " + err.message, "error"); }
      } : null;
      dl.append(el("a", { href: apiBase() + path, download: file, id: "dl-" + name.slice(8), onclick }, label));
    }
  }
  const target = $("upload-target");
  const keep = target.value;
  const recordable = pg.missions.filter((m) => m.status !== "cancelled");
  target.replaceChildren(el("option", { value: "" }, "no mission: ingest readings"),
    ...recordable.map((m) => el("option", { value: m.mission_id }, `mission #${m.mission_id} (${STATUS[m.status] || m.status})`)));
  if (keep && recordable.some((m) => String(m.mission_id) === keep)) target.value = keep;
}

// ---- uploads -----------------------------------------------------------------------------------

async function upload(files) {
  if (!files.length) return;
  const target = $("upload-target").value;
  const form = new FormData();
  for (const f of files) form.append("files", f, f.name);
  const out = $("upload-result");
  out.replaceChildren(el("p", { class: "muted" }, `Uploading ${files.length} file(s)…`));
  try {
    let text;
    if (target) {
      if ($("upload-at").value) form.append("at", $("upload-at").value);
      const r = await call("POST", `/missions/${target}/record`, form);
      text = `Mission #${r.mission} recorded at ${r.at}: ${r.cells.length} cells, ${r.sensors_collected} sensors, ${r.readings_inserted} new readings.`;
    } else {
      const r = await call("POST", "/ingest", form);
      text = `Ingested ${r.files} file(s): ${r.readings} readings (${r.inserted} new, ${r.unchanged} already stored).`;
    }
    out.replaceChildren(el("p", { class: "ok" }, text));
    await refresh();
    await loadMap(state.shown);
  } catch (e) {
    out.replaceChildren(el("p", { class: "error" }, "Nothing was stored: " + e.message));
  }
}

function wireUpload() {
  const drop = $("drop");
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    upload([...e.dataTransfer.files]);
  });
  $("upload-files").addEventListener("change", (e) => upload([...e.target.files]));
}

// ---- start ---------------------------------------------------------------------------------------

async function refresh() {
  const [project, field] = await Promise.all([call("GET", "/project"), call("GET", "/field"), loadPage()]);
  state.project = project;
  state.field = field;
  // A farm is named by its farm name (its project's own name after it, when different).
  $("project-name").textContent = "· " + (FARMS ? state.farm + (project.name !== state.farm ? ` (${project.name})` : "") : project.name);
  const scope = FARMS && farmTokens[state.farm] ? ` · ${farmTokens[state.farm].scope} token` : "";
  $("project-facts").textContent = `${field.cells.length} cells of ${project.cell_size_m} m · ${project.sensors} sensors · ` +
    `${project.readings.toLocaleString("en")} readings to ${project.latest_reading || "–"} · ${project.missions} missions · energy preset ${project.energy_preset}` +
    (project.writable ? "" : " · read-only server") + scope;
}

// ---- farms (a farms server): the picker ------------------------------------------------------

const FARM_TOKENS_KEY = "gleaner-farm-tokens";

// Which farm a token opens, as the server says (GET /api/v1/farms names the token's own farm
// and scope, never another).
async function addFarmToken(tok) {
  const r = await fetch("/api/v1/farms", { headers: { Authorization: "Bearer " + tok } });
  if (!r.ok) throw new Error(await failure(r));
  const farms = await r.json();
  for (const f of farms) farmTokens[f.farm] = { token: tok, scope: f.scope };
  sessionStorage.setItem(FARM_TOKENS_KEY, JSON.stringify(Object.values(farmTokens).map((f) => f.token)));
  renderFarms();
  return farms.map((f) => f.farm);
}

function renderFarms() {
  const sel = $("farm");
  const names = Object.keys(farmTokens).sort();
  sel.replaceChildren(...(names.length
    ? names.map((n) => el("option", { value: n }, `${n} (${farmTokens[n].scope})`))
    : [el("option", { value: "" }, "no farm token yet")]));
  sel.value = state.farm || "";
}

// Shows `farm`: its project, map and missions, from the first page.
async function openFarm(farm) {
  state.farm = farm;
  sessionStorage.setItem("gleaner-farm", farm);
  renderFarms();
  Object.assign(state, { project: null, field: null, preview: null, previewBody: null, selected: null, shown: null, newest: null });
  state.page = { before: null, newer: [], missions: [], next: null };
  $("save").disabled = true;
  $("plan-result").replaceChildren();
  $("upload-result").replaceChildren();
  $("cell-body").replaceChildren();
  $("cell-hint").textContent = "Click a cell on the map.";
  $("field-map-pane").hidden = true;
  missionsError("");
  $("map").replaceChildren(el("p", { class: "muted" }, "Loading " + farm + "…"));
  await load();
}

async function startFarms() {
  $("farm-picker").hidden = false;
  $("token-label").hidden = true;
  const given = [];
  for (const [k, v] of new URLSearchParams(location.hash.slice(1))) if (k === "token" && v) given.push(v);
  if (given.length) history.replaceState(null, "", location.pathname + location.search);
  let stored = [];
  try { stored = JSON.parse(sessionStorage.getItem(FARM_TOKENS_KEY) || "[]"); } catch (_) { /* none */ }
  for (const tok of [...new Set([...stored, ...given])]) {
    try { await addFarmToken(tok); } catch (e) { status("A farm token was refused: " + e.message, "error"); }
  }
  $("farm").addEventListener("change", (e) => { if (e.target.value) openFarm(e.target.value); });
  $("farm-token-form").addEventListener("submit", async (e) => {
    e.preventDefault();
    const tok = $("farm-token").value.trim();
    if (!tok) return;
    try {
      const farms = await addFarmToken(tok);
      $("farm-token").value = "";
      if (farms.length) await openFarm(farms[0]);
    } catch (err) {
      status("The farm token was refused: " + err.message, "error");
    }
  });
  const names = Object.keys(farmTokens).sort();
  if (!names.length) {
    $("map").replaceChildren(el("p", { class: "muted" }, "Add a farm token (above) to open its farm."));
    status("No farm open: add a farm token.");
    return;
  }
  const last = sessionStorage.getItem("gleaner-farm");
  await openFarm(names.includes(last) ? last : names[0]);
}

// Loads the project (or farm) and draws its map.
async function load() {
  try {
    await refresh();
    const f = $("plan-form");
    f.elements.time_limit_s.placeholder = state.project.time_limit_s;
    f.elements.seed.placeholder = state.project.seed;
    await loadMap(null);
    status("Ready.");
  } catch (e) {
    status("Cannot load the " + (FARMS ? "farm" : "project") + ": " + e.message, "error");
  }
}

// Narrow screens (the one-column layout): tap-size cells by default, maps' text enlarged.
const narrow = matchMedia("(max-width: 60rem)");

async function start() {
  $("colour-by").addEventListener("change", (e) => { state.colourBy = e.target.value; colourCells(); });
  $("plan-form").addEventListener("submit", preview);
  $("simulate-form").addEventListener("submit", simulate);
  $("save").addEventListener("click", save);
  $("field-map-button").addEventListener("click", () => showFieldMap());
  $("field-map-redraw").addEventListener("click", () => showFieldMap());
  $("field-map-png").addEventListener("click", () => downloadFieldMap("png"));
  $("field-map-svg").addEventListener("click", () => downloadFieldMap("svg"));
  $("missions-older").addEventListener("click", () => turnPage(true));
  $("missions-newer").addEventListener("click", () => turnPage(false));
  $("confirm-yes").addEventListener("click", () => pendingConfirm && pendingConfirm(true));
  $("confirm-no").addEventListener("click", () => pendingConfirm && pendingConfirm(false));
  $("map-zoom").addEventListener("click", () => setZoom(!state.zoom));
  state.zoom = narrow.matches;
  setZoom(state.zoom);
  narrow.addEventListener("change", (e) => setZoom(e.matches));
  wireUpload();
  if (FARMS) {
    await startFarms();
    return;
  }
  const m = /token=([^&]+)/.exec(location.hash);
  if (m) {
    sessionStorage.setItem("gleaner-token", decodeURIComponent(m[1]));
    history.replaceState(null, "", location.pathname + location.search);
  }
  $("token").value = sessionStorage.getItem("gleaner-token") || "";
  $("token").addEventListener("change", () => sessionStorage.setItem("gleaner-token", token()));
  await load();
}

start();
