// Step "Your session and its report": a session (its .toml with its logs, its folder, or a zip) run as
// `motorlab characterize`, with per-unit progress, then the results table, the fleet check and the report.
import { $, download, el } from "../dom.js";
import { run as runRequest, isAbort } from "../api.js";
import { save } from "../store.js";
import { quantity, number } from "../format.js";
import { parameterWords, plain } from "../words.js";

let controller = null;

// New files chosen for the session: its finished results stay (a wrong file dropped on a finished session
// never erases them) until a run of the new files gives new ones.
export function addSessionFiles(t, files) {
  const list = [...files].map((f) => ({ name: f.name, path: f.webkitRelativePath || f.name, file: f }));
  const before = t.session || {};
  t.session = { files: list, body: before.body || null, ran: before.ran || null, status: "", error: "" };
  save();
}

const isSession = (files) => files.some((f) => /\.(toml|zip)$/i.test(f.name));

// The files the session description names (a quick look; the CLI reads it for real).
async function namedFiles(entry) {
  const text = await entry.file.text();
  const names = [];
  for (const line of text.split("\n")) {
    const m = /^\s*(files|truth|spindown)\s*=\s*(.*)$/.exec(line.replace(/#.*$/, ""));
    if (m) for (const q of m[2].matchAll(/"([^"]+)"|'([^']+)'/g)) names.push(q[1] || q[2]);
  }
  return names;
}

async function checkFiles(s, host) {
  const toml = s.files.find((f) => /\.toml$/i.test(f.name));
  if (!toml) {
    if (!s.files.some((f) => /\.zip$/i.test(f.name))) host.textContent = "Choose the session's .toml file too (or one .zip of the session's folder).";
    return;
  }
  const names = await namedFiles(toml);
  const chosen = new Set(s.files.map((f) => f.name));
  const missing = names.filter((n) => !chosen.has(n.split(/[\\/]/).pop()));
  host.textContent = missing.length
    ? `${toml.name} names ${missing.join(", ")}, not among the chosen files: choose ${missing.length > 1 ? "them" : "it"} too, or choose the session's folder.`
    : `${toml.name} names ${names.length} file${names.length === 1 ? "" : "s"}: all chosen.`;
}

async function runSession(ctx) {
  const t = ctx.state, s = t.session;
  if (!isSession(s.files)) {  // said at once, in words; the results before stay
    s.status = "failed";
    s.error = `${s.files.map((f) => f.name).join(", ")}: no session here. Choose the session's .toml file with its logs, or one .zip of its folder${s.body ? "; the results below are from the session run before, kept as they were" : ""}.`;
    save(); ctx.rerender();
    return;
  }
  const form = new FormData();
  for (const f of s.files) form.append("file", f.file, f.path);
  const previous = s.body ? { body: s.body, ran: s.ran } : null;
  s.status = "running"; s.error = ""; s.started = Date.now(); sessionStep = null;
  controller = new AbortController();
  ctx.rerender();
  const clock = setInterval(() => { const el2 = $(".session .run-status"); if (el2 && !el2.dataset.progress) el2.textContent = `running the analyses… ${Math.round((Date.now() - s.started) / 1000)} s`; }, 500);
  try {
    // The table comes first (onPartial), the report with its figures follows in the answer.
    const ran = s.files.map((f) => f.path);
    const onPartial = (part) => { s.body = { ...part, report_html: null }; s.ran = ran; save(); ctx.rerender(); };
    s.body = await runRequest("api/characterize", form, { signal: controller.signal, onProgress: progress, onPartial });
    s.ran = ran;
    s.status = "done";
    t.gains.unit = "";
  } catch (e) {
    s.status = isAbort(e) ? "stopped" : "failed";
    if (previous) Object.assign(s, previous);  // the finished results before are kept
    s.error = isAbort(e) ? "" : `${e.message}${previous ? ". The results below are from the session run before, kept as they were." : ""}`;
  } finally {
    clearInterval(clock); controller = null; save(); ctx.rerender();
  }
}

// The session's own steps (units done of total, the experiment running; then the report's sections) are
// shown; the steps inside one analysis (a fit's iterations) only until the first of them arrives.
let sessionStep = null;
function progress(p) {
  const own = p.unit === "unit" || p.unit === "section";
  if (!own && sessionStep) return;
  if (own) sessionStep = p;
  const bar = $(".session progress"), text = $(".session .run-status");
  if (bar && p.total) { bar.max = p.total; bar.value = p.done || 0; }
  const counted = p.total ? `${p.done || 0} of ${p.total} ${p.unit}${p.total === 1 ? "" : "s"} done` : "";
  if (text) { text.dataset.progress = "1"; text.textContent = plain(`${p.what || "working"}: ${counted}${p.detail ? ` (${p.detail})` : ""}`); }
}

// The report as embedded: its own page, fitted to the frame's width (a phone's 390 px): figures scaled
// down, wide tables scrolled within themselves, long words wrapped; the downloaded file is the report as written.
const FIT = `<meta name="viewport" content="width=device-width, initial-scale=1"><style>
html, body { max-width: 100%; overflow-x: hidden; } body { overflow-wrap: anywhere; margin: 8px; }
img, svg, figure, video, canvas { max-width: 100% !important; height: auto !important; }
table { display: block; max-width: 100%; overflow-x: auto; } pre { white-space: pre-wrap; }</style>`;

export function readable(html) {
  return /<head[^>]*>/i.test(html) ? html.replace(/<head[^>]*>/i, (m) => `${m}${FIT}`) : `${FIT}${html}`;
}

function resultsTable(r) {
  const names = [];
  for (const unit of Object.values(r.units)) for (const n of Object.keys(unit.parameters || {})) if (!names.includes(n)) names.push(n);
  const rows = Object.values(r.units).map((unit) => el("tr", {},
    el("th", { scope: "row", text: unit.label }), el("td", { "data-label": "status", text: unit.status === "ok" ? "ok" : plain(unit.status) }),
    names.map((n) => { const p = (unit.parameters || {})[n]; return el("td", { class: "num", "data-label": parameterWords(n).join(" "), text: p ? quantity(p.value, p.stderr, p.unit) : "not determined" }); })));
  return el("table", { class: "wide", id: "session-table" }, el("caption", { text: "Each unit's parameters" }),
    el("thead", {}, el("tr", {}, el("th", { text: "Unit" }), el("th", { text: "Status" }), names.map((n) => { const [w, s] = parameterWords(n); return el("th", { text: `${w} ${s}` }); }))),
    el("tbody", {}, rows));
}

function fleetTable(r) {
  const fleet = (r.fleet && r.fleet.parameters) || {};
  const rows = Object.entries(fleet).map(([n, f]) => {
    const flagged = Object.entries(f.z || {}).filter(([, z]) => Math.abs(z) > r.fleet.threshold).map(([u, z]) => `${u} (z = ${number(z, 3)})`);
    const [w, s] = parameterWords(n);
    return el("tr", {}, el("th", { scope: "row", text: `${w} ${s}` }), el("td", { "data-label": "units", text: String(f.n) }),
      el("td", { class: "num", "data-label": "mean", text: quantity(f.mean, null, f.unit) }), el("td", { class: "num", "data-label": "spread", text: quantity(f.std, null, f.unit) }),
      el("td", { "data-label": "unusual", text: flagged.join(", ") || "none" }));
  });
  return el("table", { class: "wide", id: "fleet-table" }, el("caption", { text: "Fleet check: which motor differs from the others?" }),
    el("thead", {}, el("tr", {}, ["Parameter", "Units", "Mean", "Spread", "Unusual units"].map((h) => el("th", { text: h })))), el("tbody", {}, rows));
}

export function render(host, ctx) {
  const t = ctx.state, s = t.session;
  host.append(el("h2", { text: ctx.task.title }), el("p", { class: "help", text: ctx.task.needs }));
  const pick = (input) => input.addEventListener("change", () => { if (input.files.length) { addSessionFiles(t, input.files); ctx.rerender(); } });
  const files = el("input", { type: "file", multiple: true, id: "session-files" });
  const folder = el("input", { type: "file", id: "session-folder", webkitdirectory: true });
  pick(files); pick(folder);
  const check = el("p", { class: "small", role: "status" });
  const running = s && s.status === "running" && controller;
  host.append(el("section", { class: "card session" },
    el("label", { class: "drop", for: "session-files" }, el("span", { text: "Choose the session file (.toml) with its logs, or one .zip of its folder" }), files),
    el("label", { class: "drop small", for: "session-folder" }, el("span", { text: "or choose the session's folder" }), folder),
    s ? el("p", { class: "small", text: `Chosen: ${s.files.map((f) => f.path).join(", ")}` }) : null, check,
    el("div", { class: "actions" },
      el("button", { type: "button", class: "primary", text: running ? "Running…" : "Run the session", disabled: !s || running, onclick: () => runSession(ctx) }),
      el("button", { type: "button", text: "Cancel", hidden: !running, onclick: () => controller && controller.abort() }),
      running ? el("progress", { "aria-label": "Progress of the session" }) : null,
      el("span", { class: "run-status", role: "status", text: s && s.status === "stopped" ? "cancelled" : "" })),
    s && s.error ? el("p", { class: "error", role: "alert", text: s.error }) : null));
  if (running && sessionStep) { const last = sessionStep; requestAnimationFrame(() => progress(last)); }  // kept across a re-render
  if (s && s.status !== "running" && (!s.body || (s.ran && s.files.map((f) => f.path).join("\n") !== s.ran.join("\n")))) checkFiles(s, check);
  if (s && s.body) {
    const r = s.body.results;
    const other = s.ran && s.files.map((f) => f.path).join("\n") !== s.ran.join("\n");
    const out = el("section", { class: "card", id: "session-result" },
      el("h3", { text: r.session && r.session.title ? r.session.title : "Results" }),
      other ? el("p", { class: "small", text: `These results are from ${s.ran.join(", ")}; run the session to replace them with the files chosen now.` }) : null,
      s.body.message ? el("p", { class: "error", text: `Some analyses failed: ${plain(s.body.message)}` }) : null,
      el("div", { class: "scroll" }, resultsTable(r)), el("div", { class: "scroll" }, fleetTable(r)),
      el("div", { class: "actions" },
        el("button", { type: "button", text: "Download results.json", onclick: () => download("results.json", JSON.stringify(r, null, 2), "application/json") }),
        el("button", { type: "button", text: "Download results.csv", onclick: () => download("results.csv", s.body.csv, "text/csv") }),
        s.body.report_html ? el("button", { type: "button", text: "Download the report", onclick: () => download("report.html", s.body.report_html, "text/html") }) : null),
      s.body.report_html
        ? el("details", { class: "report" }, el("summary", { text: "The printable report" }), el("iframe", { title: "The report", sandbox: "", srcdoc: readable(s.body.report_html) }))
        : el("p", { class: "small", role: "status", id: "report-status", text: running ? "The report with its figures is being drawn; it follows here." : "The report was not finished." }));
    host.append(out);
  }
  host.append(el("nav", { class: "next" }, el("a", { class: `button${s && s.body ? " primary" : ""}`, href: `#/${ctx.task.key}/gains`, text: "Gains for your code →" })));
}
