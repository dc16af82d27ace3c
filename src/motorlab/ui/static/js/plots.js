// Interactive plots (Plotly, served by the app). Titles are headings above the plot, so the toolbar never
// covers them; text is 12 px; legends sit below the axes so a phone keeps the full width for the data.
import { el } from "./dom.js";
import { prettyUnit } from "./format.js";

const FONT = { size: 12, family: "system-ui, sans-serif" };
const CONFIG = { responsive: true, displaylogo: false, displayModeBar: true, modeBarButtonsToRemove: ["toImage", "sendDataToCloud"] };
const narrow = () => window.innerWidth < 600;

function base(height) {
  return { height, font: FONT, margin: { t: 28, r: 12, b: 44, l: 58 }, legend: { orientation: "h", y: -0.22, font: FONT },
    paper_bgcolor: "#fff", plot_bgcolor: "#fff" };
}

// Figures are drawn one per task of the page's main thread (each under 200 ms), so a view with several
// results never freezes: the page answers clicks and keys between two figures. A figure whose place is not
// in the page yet (the view being built) waits for it; one whose view was left is dropped.
const queue = [];
let pumping = false;

function pump() {
  const job = queue.shift();
  if (job) {
    if (job.div.isConnected) job.draw();
    else if (job.tries++ < 40) { queue.push(job); setTimeout(pump, 25); return; }
  }
  if (queue.length) setTimeout(pump, 0); else pumping = false;
}

function later(div, draw) {
  queue.push({ div, draw, tries: 0 });
  // the first figure waits for the page's next frame: the view it sits in is laid out in a task of its own
  if (!pumping) { pumping = true; requestAnimationFrame(() => setTimeout(pump, 0)); }
}

// Resolves once every figure asked for so far is drawn (tests, and a view that waits for its plots).
export const settled = () => new Promise((resolve) => { const wait = () => (pumping ? setTimeout(wait, 30) : resolve()); wait(); });

function figure(host, title, traces, layout, then) {
  const div = el("div", { class: "plot-area" });
  host.append(el("figure", { class: "plot" }, el("figcaption", { text: title }), div));
  draw(div, traces, layout, then);
  return div;
}

// Tick labels are left where Plotly puts them: its default check that none overflows the figure measures each
// label's box (a layout of the page each), up to half of a figure's drawing.
const axes = (layout) => Object.fromEntries(Object.entries(layout).map(([k, v]) =>
  [k, /^[xy]axis\d*$/.test(k) ? { ticklabeloverflow: "allow", ...v } : v]));

function draw(div, traces, layout, then) {
  later(div, () => { if (window.Plotly) { window.Plotly.react(div, traces, axes(layout), CONFIG); if (then) then(div); } });
}

// Two figures that zoom and pan along x together (a fit and its residuals, drawn as two tasks, not one).
function linked(a, b) {
  let busy = false;
  const follow = (from, to) => from.on("plotly_relayout", (ev) => {
    if (busy || !ev || !to.layout) return;
    const x = ev["xaxis.autorange"] ? { "xaxis.autorange": true }
      : "xaxis.range[0]" in ev ? { "xaxis.range": [ev["xaxis.range[0]"], ev["xaxis.range[1]"]] }
      : ev["xaxis.range"] ? { "xaxis.range": ev["xaxis.range"] } : null;
    if (!x) return;
    busy = true;
    Promise.resolve(window.Plotly.relayout(to, x)).finally(() => { busy = false; });
  });
  if (a.on && b.on) { follow(a, b); follow(b, a); }
}

// Plotly's first figure in a page costs several times the next ones (its styles, fonts and text measuring set
// up, and its code for points compiled at their first use): a figure of the same shape as a fit's (300 points,
// a line, a legend) is drawn out of sight once the page has started, then removed, so that cost is paid while
// the student chooses a file, not when the first result's figures are drawn.
export function warmUp() {
  if (!window.Plotly) return;
  const div = el("div", { "aria-hidden": "true", style: "position:absolute;left:-10000px;top:0;width:600px" });
  document.body.append(div);
  const x = Array.from({ length: 300 }, (_, k) => k / 100);
  draw(div, [{ x, y: x.map(Math.sin), mode: "markers", marker: { size: 4 }, name: "measured" },
    { x, y: x.map(Math.cos), mode: "lines", name: "model" }],
  { ...base(300), xaxis: { title: { text: "time in s" } }, yaxis: { title: { text: "speed" } } },
  () => setTimeout(() => { window.Plotly.purge(div); div.remove(); }, 0));
}

export function raw(host, item) {
  host.replaceChildren();
  if (!item.signals || !item.signals.length) return;
  const shown = item.signals.filter((s) => s.name !== "counts").slice(0, 4);
  const n = shown.length;
  const layout = { ...base(110 + 120 * n), grid: { rows: n, columns: 1, pattern: "independent" }, showlegend: false };
  const traces = shown.map((s, k) => ({ x: item.time, y: s.y, name: s.name, mode: "lines", xaxis: k ? `x${k + 1}` : "x", yaxis: k ? `y${k + 1}` : "y" }));
  shown.forEach((s, k) => {
    layout[`xaxis${k ? k + 1 : ""}`] = { matches: k ? "x" : undefined, title: { text: k === n - 1 ? "time in s" : "" } };
    layout[`yaxis${k ? k + 1 : ""}`] = { title: { text: `${s.name.replace(/_/g, " ")}${s.unit && s.unit !== "1" ? ` in ${prettyUnit(s.unit)}` : ""}`, font: FONT } };
  });
  figure(host, `${item.file}: the signals as read`, traces, layout);
}

// The x axis is the log's own time when each point's x is its time: spans left out can be shaded on it.
const againstLogTime = (p) => p.data && p.time && p.time.length === p.data.x.length
  && p.data.x.every((x, k) => x === null || p.time[k] === null || Math.abs(x - p.time[k]) < 1e-9);

// Data against the fitted model, residuals below (a figure of their own under it, x zoomed together: each
// figure is one task of the page, a fit's points and its residuals in one took up to twice as long).
// onSelect(points) gets the points picked with the box/lasso tool on either; `leftOut` (spans [start, end] of
// the log's time) are shaded on plots against that time.
export function panels(host, list, { onSelect, leftOut = [] } = {}) {
  host.replaceChildren();
  for (const p of list || []) {
    const traces = [];
    if (p.data) traces.push({ x: p.data.x, y: p.data.y, name: p.data.label || "measured", mode: "markers", marker: { size: 4 } });
    if (p.model) traces.push({ x: p.model.x, y: p.model.y, name: p.model.label || "model", mode: "lines" });
    for (const s of p.extra || []) if (s) traces.push({ x: s.x, y: s.y, name: s.label, mode: s.kind === "data" ? "markers" : "lines" });
    const layout = { ...base(narrow() ? 360 : 420), xaxis: { title: { text: p.x_label } }, yaxis: { title: { text: p.y_label } }, dragmode: "zoom" };
    const shaded = leftOut.length && againstLogTime(p);
    if (shaded) {
      layout.shapes = leftOut.map(([x0, x1]) => ({ type: "rect", xref: "x", yref: "paper", x0, x1, y0: 0, y1: 1,
        fillcolor: "#d33", opacity: 0.08, line: { width: 0 }, layer: "below" }));
      layout.annotations = leftOut.map(([x0, x1]) => ({ xref: "x", yref: "paper", x: (x0 + x1) / 2, y: 1, yanchor: "bottom",
        text: "left out", showarrow: false, font: { ...FONT, color: "#a33" } }));
    }
    // the measured points and their residuals share indices: a selection on either names the same rows
    const picked = (div) => {
      if (onSelect && div.on) div.on("plotly_selected", (ev) => onSelect(p, ev ? [...new Set(ev.points.filter((pt) => pt.curveNumber === 0).map((pt) => pt.pointIndex))] : []));
    };
    const main = figure(host, p.title, traces, layout, picked);
    if (p.same_x && p.data && p.model) {
      // measured − model at the measured points drawn (the worker's; a result kept from before, computed here)
      const res = p.residual || { x: p.data.x, y: p.data.y.map((y, k) => (y === null || p.model.y[k] === null ? null : y - p.model.y[k])) };
      const below = { ...base(narrow() ? 170 : 190), showlegend: false, dragmode: "zoom", xaxis: { title: { text: p.x_label } },
        yaxis: { title: { text: "measured − model" } }, margin: { t: 8, r: 12, b: 44, l: 58 } };
      if (shaded) below.shapes = layout.shapes.map((s) => ({ ...s }));  // its own: Plotly keeps and edits a figure's layout
      const div = el("div", { class: "plot-area residuals" });
      main.after(div);
      draw(div, [{ x: res.x, y: res.y, name: "residual", mode: "markers", marker: { size: 3, color: "#7f7f7f" } }], below,
        (d) => { picked(d); linked(main, d); });
    }
  }
}

// The simulated closed loop: reference and response against time, and the voltage, for a step and a profile.
export function response(host, curves, targetUnit) {
  host.replaceChildren();
  if (!curves) return;
  const unit = prettyUnit(curves.unit || targetUnit || "");
  for (const [title, c] of [["Step response (simulated)", curves.step], ["Following a motion profile (simulated)", curves.profile]]) {
    const traces = [
      { x: c.time, y: c.reference, name: "wanted", mode: "lines", line: { dash: "dash" } },
      { x: c.time, y: c.output, name: "simulated", mode: "lines" },
      { x: c.time, y: c.voltage, name: "voltage", mode: "lines", yaxis: "y2", line: { width: 1 } },
    ];
    const layout = { ...base(narrow() ? 300 : 340), xaxis: { title: { text: "time in s" } },
      yaxis: { title: { text: `${curves.loop === "velocity" ? "speed" : "position"} in ${unit}` } },
      // ticks of its own (round volts): an overlaying axis otherwise takes the left axis's grid (Plotly's "sync"),
      // 6.07, 7.67, 9.28, 10.89 V
      yaxis2: { title: { text: "voltage in V" }, overlaying: "y", side: "right", showgrid: false, tickmode: "auto" } };
    layout.margin.r = 50;
    figure(host, title, traces, layout);
  }
}
